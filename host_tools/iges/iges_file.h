/*
 * iges_file.h - the IGES 5.3 file layer: sections, Global parameters,
 * Directory entries and Parameter Data, tokenised but not interpreted.
 *
 * Fixed-format ASCII only (the form every exporter in the corpus writes);
 * the compressed ASCII form ('C' in column 73) and binary files are refused
 * with a clear message.  Tolerant of what real exporters do: CRLF or CR line
 * ends, lines shorter than 80 columns, a missing Terminate section, wrong
 * counts in it (warnings, not errors, when the data itself is complete).
 * Everything malformed that makes the data unusable is an error that names
 * the file line.
 *
 * Geometry lives elsewhere (iges_geom.c turns entities into NURBS, and
 * iges_brep.c into faces); this layer only answers "what does entity DE 57
 * say".
 */
#ifndef IGES_FILE_H
#define IGES_FILE_H

#include <stddef.h>

#include "cm/cm_error.h"

typedef enum iges_pkind {
    IGES_P_EMPTY = 0, /* defaulted parameter: two delimiters in a row */
    IGES_P_NUM = 1,   /* integer, real or pointer */
    IGES_P_STR = 2    /* Hollerith string */
} iges_pkind;

typedef struct iges_param {
    iges_pkind kind;
    double num;      /* IGES_P_NUM */
    const char *str; /* IGES_P_STR: NUL-terminated copy (may hold any bytes) */
    int len;         /* string length in bytes */
} iges_param;

typedef struct iges_entity {
    int type, form;
    int de;              /* sequence number of its first Directory line (odd) */
    int line;            /* file line of that Directory line (1-based) */
    int pd_line;         /* file line of its first Parameter line */
    int pd_seq, pd_count; /* Parameter section sequence number and line count */
    int structure, font, level, view;
    int xform;           /* DE of a 124 transformation, or 0 */
    int label_assoc;
    int blank, subord, use, hier; /* status number digits (pairs) */
    int weight, color;   /* color: > 0 a colour number, < 0 minus the DE of a 314 */
    char label[9];
    int subscript;
    int nparams;         /* parameters after the entity type number */
    iges_param *params;
    int bad;             /* parameters could not be read (an error was warned) */
    int used;            /* translated into the model (set by the geometry layers) */
} iges_entity;

typedef struct iges_global {
    char pdelim, rdelim;
    char *sender_id, *file_name, *system_id, *preprocessor;
    char *receiver_id;
    double model_scale;  /* model space units per real-world unit (param 13) */
    int units_flag;      /* param 14 */
    char *units_name;
    char *date;          /* file generation date, raw */
    double resolution;   /* minimum user-intended resolution, in file units */
    double max_coord;
    char *author, *organization;
    int version, drafting;
    char *model_date;
} iges_global;

typedef struct iges_warning {
    int line;            /* file line, 0 if none */
    char *msg;
} iges_warning;

typedef struct iges_file {
    char *path;
    iges_global g;
    double to_mm;        /* multiply file coordinates by this to get millimetres */
    iges_entity *ents;
    int nents;
    int *de_map;         /* (de-1)/2 -> index in ents, -1 if none */
    int de_map_n;
    int nlines_s, nlines_g, nlines_d, nlines_p;
    iges_warning *warn;
    int nwarn, capwarn;
    char err[512];       /* message of the error that stopped iges_read, "" otherwise */
    int err_line;
    /* import budgets (iges_geom.c): what the entity graph may expand to */
    int *curve_pieces;   /* per entity index: curve pieces it flattens into (memo; 0 = not counted yet) */
    long long pieces_made; /* curve pieces built so far for the whole model */
    int over_budget;     /* a model-wide import budget was exceeded: the import stops (f->err says which) */
} iges_file;

/**
 * Read an IGES file.  On error returns non-CM_OK (CM_E_IGES for malformed
 * content, CM_E_IO for I/O) with f->err = "line N: ..." and f->err_line;
 * f is left freeable.  Warnings (skipped or suspicious content) go to
 * f->warn.
 */
CM_NODISCARD cm_err iges_read(const char *path, iges_file *f, cm_status *st);

/** The same from memory (used by the fuzzer); `data` need not be NUL-terminated. */
CM_NODISCARD cm_err iges_parse(const char *data, size_t len, iges_file *f, cm_status *st);

void iges_free(iges_file *f);

/** The entity whose Directory entry starts at sequence number `de`, or NULL. */
const iges_entity *iges_by_de(const iges_file *f, int de);

/** Record a file-level error "line N: ..." into f->err unless one is there; returns CM_E_IGES. */
cm_err iges_error(iges_file *f, int line, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/**
 * An allocation failed: record "line N: out of memory (...)" into f->err unless one is there
 * and return CM_E_NOMEM (never CM_E_IGES: the input is not to blame).  `line` 0 if none.
 */
cm_err iges_nomem(iges_file *f, int line, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/** Add a warning (printf-style); `line` 0 if none. */
void iges_warn(iges_file *f, int line, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/*
 * Typed parameter access for entity e, parameter index i (0-based, after
 * the type number).  On a missing, empty or wrongly typed parameter the
 * getters with a default return it; the strict ones record an error in f
 * ("line N: entity 126 (DE 57) parameter 5: expected a number") and return
 * non-zero.
 */
double iges_num_or(const iges_entity *e, int i, double dflt);
int iges_int_or(const iges_entity *e, int i, int dflt);
/**
 * A count read from parameter i for a loop over the parameters that follow it: the integer there,
 * clamped to [0, e->nparams] (missing, negative, fractional or absurd values give 0 or the clamp),
 * so `for (k = 0; k < count; k++)` never runs past the parameters nor overflows an index.
 */
int iges_count_or0(const iges_entity *e, int i);
/** v as an int when it is an integer in [lo, hi], else dflt (no undefined conversion). */
int iges_to_int(double v, int lo, int hi, int dflt);
int iges_num(iges_file *f, const iges_entity *e, int i, double *out);
int iges_int(iges_file *f, const iges_entity *e, int i, int *out);
/** A pointer parameter: a DE number that must name an entity (0 allowed if allow_null). */
int iges_ptr(iges_file *f, const iges_entity *e, int i, int allow_null, int *de_out);

/** Record an error about entity e (printf-style) into f->err unless one is there; returns CM_E_IGES. */
cm_err iges_entity_error(iges_file *f, const iges_entity *e, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/** Human name of an entity type ("rational B-spline curve"), "unknown" if not known. */
const char *iges_type_name(int type);

#endif /* IGES_FILE_H */
