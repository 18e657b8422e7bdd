/*
 * step_file.h - the ISO 10303-21 ("STEP Part 21") file layer: HEADER and
 * DATA sections, entity instances `#n = ...;` (simple and complex), their
 * parameters as typed trees, not interpreted.
 *
 * One pass over the text builds three flat arrays: the instances, the
 * partial records of each (a complex instance `#n=(A(..) B(..));` has
 * several, a simple one exactly one) and every parameter value, nested
 * lists and typed values (`LENGTH_MEASURE(2.5)`) laid out in preorder with
 * their subtree sizes, so walking a list is a loop, never a recursion, and
 * nothing is allocated per value.  Look-up by instance number is a binary
 * search over a sorted index (forward references cost nothing special).
 *
 * Tolerant of what real exporters write: comments anywhere, any spacing and
 * line ends, lower-case keywords, several DATA sections, Part 21 edition 3
 * DATA('name',(...)) headers, a missing END-ISO-10303-21.  An instance that
 * cannot be read is skipped with a warning naming its line and number (the
 * rest of the file still loads); the file is refused, with an error naming
 * the line, only when it is not Part 21 at all or nothing of it can be read.
 *
 * Geometry lives elsewhere (step_brep.c turns instances into faces).
 */
#ifndef STEP_FILE_H
#define STEP_FILE_H

#include <stddef.h>

#include "cm/cm_error.h"

typedef enum step_kind {
    STEP_MISSING = 0, /* asked past the end of a list (never stored) */
    STEP_UNSET,       /* $ */
    STEP_DERIVED,     /* * */
    STEP_INT,
    STEP_REAL,
    STEP_STR,         /* '...' (raw, escapes as written; step_str decodes) */
    STEP_BINARY,      /* "..." */
    STEP_ENUM,        /* .NAME. */
    STEP_REF,         /* #n */
    STEP_LIST,        /* ( ... ) */
    STEP_TYPED        /* NAME( value ): one child */
} step_kind;

typedef struct step_val {
    unsigned char kind;
    int size;   /* values in this subtree, itself included (>= 1) */
    int n;      /* LIST: items; TYPED: 1 */
    int ref;    /* REF: the instance number */
    double num; /* INT, REAL */
    int text;   /* STR, BINARY, ENUM, TYPED: offset of the name/contents in step_file.text */
    int len;    /* its length in bytes */
} step_val;

typedef struct step_part {
    int name, name_len; /* entity type name (offset into text) */
    int params;         /* index of its parameter LIST in vals */
} step_part;

typedef struct step_entity {
    int id;             /* #id; 0 for HEADER entities */
    int line;           /* file line where the instance starts */
    int first_part, nparts;
    int used;           /* turned into the model (set by step_brep.c, for `cmz info`) */
} step_entity;

typedef struct step_warning {
    int line;
    char *msg;
} step_warning;

typedef struct step_file {
    char *path;
    char *text;         /* the whole file, NUL-terminated */
    size_t len;
    step_entity *ents;  /* DATA instances in file order */
    int nents, capents;
    step_entity *hdr;   /* HEADER entities (FILE_DESCRIPTION, FILE_NAME, FILE_SCHEMA) */
    int nhdr, caphdr;
    step_part *parts;
    int nparts, capparts;
    step_val *vals;
    int nvals, capvals;
    int *by_id;         /* indices into ents sorted by id, each id once (the first instance of a name) */
    int nents_indexed;
    int nlines;
    char schema[160];   /* FILE_SCHEMA's first name, "" if none */
    char system[160];   /* FILE_NAME's originating system, "" if none */
    step_warning *warn;
    int nwarn, capwarn;
    int warnings_dropped; /* past the first 10000 warnings: counted, not kept */
    int bad_instances;  /* instances skipped because they could not be read (warned) */
    char err[512];      /* the error that stopped step_read, "" otherwise */
    int err_line;
} step_file;

/** 1 if the data looks like a Part 21 file (after blanks, a BOM and comments: "ISO-10303-21;"). */
int step_sniff(const char *data, size_t len);

/**
 * Read a STEP file.  CM_E_STEP with f->err "line N: ..." when the text is not
 * Part 21 or holds no readable instance, CM_E_IO when it cannot be read,
 * CM_E_NOMEM; f is always freeable.  Warnings go to f->warn.
 */
CM_NODISCARD cm_err step_read(const char *path, step_file *f, cm_status *st);
/** The same from memory (`data` need not be NUL-terminated; it is copied); f->path is left NULL. */
CM_NODISCARD cm_err step_parse(const char *data, size_t len, step_file *f, cm_status *st);
void step_free(step_file *f);

/** Record a warning (printf-style). */
void step_warn(step_file *f, int line, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/** Record the error unless one is there (printf-style); returns CM_E_STEP. */
cm_err step_error(step_file *f, int line, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/** The instance #id, or NULL. */
const step_entity *step_by_id(const step_file *f, int id);

/** 1 if the instance is (or, for a complex one, has a part) of this type (case-insensitive). */
int step_is(const step_file *f, const step_entity *e, const char *type);
/** The parameter list of its part of this type (NULL type: its first part); NULL if none. */
const step_val *step_params(const step_file *f, const step_entity *e, const char *type);
/** Its (first part's) type name into buf (truncated), for messages; returns buf. */
const char *step_type(const step_file *f, const step_entity *e, char *buf, size_t cap);

/** Item i of a LIST (a TYPED value's inner value for i == 0); NULL when out of range or not a list. */
const step_val *step_item(const step_val *list, int i);
/** The value under TYPED wrappers (LENGTH_MEASURE(2.5) -> 2.5). */
const step_val *step_untyped(const step_val *v);
/** 1 if v is an enumeration of this name (without dots), or a TYPED value of this type name. */
int step_val_is(const step_file *f, const step_val *v, const char *name);
/** A number (INT or REAL, under TYPED wrappers) into *out; 0 on success, -1 otherwise. */
int step_num(const step_val *v, double *out);
/** A reference's instance, NULL if v is no reference or names nothing. */
const step_entity *step_ref(const step_file *f, const step_val *v);
/** A string's decoded text into buf (the '' quote and \X\hh escapes); "" for a non-string. */
const char *step_str(const step_file *f, const step_val *v, char *buf, size_t cap);

#endif /* STEP_FILE_H */
