/*
 * cm_method.h - a face method as one module (docs/METHODS.md).
 *
 * A face's surface is deleted by the encoder and rebuilt by the terminal
 * by one of a family of methods.  Each method is one file in
 * decoder/methods/ holding one cm_method row (what the method is) and the
 * functions behind the operations below: how its record is read and
 * written in the FACE section, what its loops must look like, and how its
 * surface is rebuilt from the curve mesh.  The reader (cm_decode.c), the
 * rebuild (cm_rebuild.c), the tessellation (through the representation
 * the rebuild returns, cm_rebuilt.repr), the encoder's candidate list and
 * its reports all go through this table; nothing else names a method
 * (tests/tools/check_method_modules.sh).  Adding a method is one file, one
 * row in cm_method_table, one case per operation in cm_methods.c and its
 * tests.
 */
#ifndef CM_METHOD_H
#define CM_METHOD_H

#include <stdint.h>

#include "cm/cm_arith.h"
#include "cm/cm_format.h"
#include "cm/cm_rebuild.h"
#include "cm/cm_sections.h"

/** Why a record or a face's loops were refused: the rule or field, and for a limit its id and need. */
typedef struct cm_method_fault {
    const char *what;
    unsigned limit;   /* CM_E_LIMIT only: the limit's id (cm_limits_info.h) */
    uint64_t need;    /* CM_E_LIMIT only: what the face needs */
} cm_method_fault;

typedef struct cm_method {
    const char *name;     /* "plane": reports, --report, cmz eval */
    const char *counted;  /* the word after its count in summaries: "plane", "kept" */
    uint8_t id;           /* CM_METHOD_*: the number on the wire */
    uint8_t since_major;  /* the first format version that carries it: major ... */
    uint8_t since_minor;  /* ... and minor */
    uint8_t kept_surface; /* its surface travels in SURF (one per such face, in face order) */
    uint8_t has_record;   /* fields follow the method number in the FACE section */
    uint8_t layouts;      /* layouts its record chooses from (0: none): reports print the face's */
    const char *too_new;  /* the error when a file older than since_major carries it */
} cm_method;

/*
 * What a method does, dispatched by cm_methods.c to the method's module: one switch per operation,
 * no function pointers, so that the stack gate sees every call the decoder makes.
 */

/** A G1FIT edge's twist (format 4.2): the sine of the angle by which the surface's normal at each of
    the edge's inner samples is turned about the edge from the carried one, in 1/4096 */
#define CM_TWIST_N 9        /* inner samples of an edge: CM_FMT_SEG_PER_EDGE - 1 */
#define CM_TWIST_ONE 4096   /* the sine's unit */
#define CM_TWIST_MAX 4095   /* |quantised sine| at most this (the cosine stays positive) */

/** GREGORY-FIT's correction as the writer sends it: coefficient = q * 2^exp * the model's grid step
    (and, from format 4.2, a net's: m = 0 none; G1FIT's twists along its edges). */
typedef struct cm_fit_q {
    int m;                 /* coefficients per direction, 1..CM_FIT_MAX_M (a net's: 0 = none) */
    int patches;           /* patches, 1..CM_MAX_GREG */
    int exp;               /* 0..CM_FIT_MAX_EXP */
    const int32_t (*q)[3]; /* patch k's coefficient (i,j): q[(k m + i) m + j] */
    int ntwist;            /* G1FIT: uses of the outer loop with a twist (0: none; else all of them) */
    const int16_t (*twist)[CM_TWIST_N]; /* per use, its samples' quantised sines (all 0: untwisted) */
    unsigned hint_mask;    /* GREGORY family (format 4.13): the hinted corners (cm_face_hint_mask) ... */
    const int16_t (*hint)[2]; /* ... each one's normal, octahedral (cm_hint_encode), in corner order */
} cm_fit_q;

/** Spec 15.3: unit normal n as octahedral coordinates in units of 1/CM_FMT_HINT_ONE (the writer's). */
void cm_hint_encode(cm_vec3 n, int16_t q[2]);
/** ... and back, a unit normal (the reader's; the same bits on every machine). */
cm_vec3 cm_hint_decode(int32_t qx, int32_t qy);
/** Face F's hints (mask, one octahedral pair each in corner order) into m's control-point pool after
    its correction, as the reader puts them (the writer's trials too): CM_E_LIMIT when the pool has
    no room (nothing placed). */
CM_NODISCARD cm_err cm_gregory_place_hints(cm_model *m, cm_face *F, unsigned mask, const int16_t (*q)[2]);

/**
 * FACE section: the record's fields after the method number, into F (nothing for a method without
 * a record); data the record carries beyond F's fields (GREGORY-FIT's correction) goes to the
 * model's pools.  CM_E_TRUNCATED when the coder overran, CM_E_LIMIT with why->limit and why->need
 * when a pool is full; anything else names the field in why->what.
 */
CM_NODISCARD cm_err cm_method_read_record(const cm_method *M, cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m,
                                          cm_face *F, cm_method_fault *why);
/** The same fields written (the workstation's writer); fit: GREGORY-FIT's correction (else NULL). */
void cm_method_write_record(const cm_method *M, cm_ac_enc *ac, cm_face_ctx *ctx, const cm_face *F,
                            const cm_fit_q *fit);
/** After the face's loops are read: do they fit the method? */
CM_NODISCARD cm_err cm_method_check_loops(const cm_method *M, const cm_model *m, const cm_face *F,
                                          cm_method_fault *why);
/** Does the rebuild use the midpoint (t = 1/2) of the outer loop's edges? */
int cm_method_needs_midpoints(const cm_method *M, const cm_face *F);
/**
 * Rebuild face f's surface into out (out->bbox, and the samples ws->samples[0..n) with the outer
 * loop first, n_outer of them, are filled by the caller; spec §2 rule 1).  `check`: compare what was
 * rebuilt with the record's checksum where the record has one.
 */
CM_NODISCARD cm_err cm_method_rebuild(const cm_method *M, const cm_model *m, uint32_t f, int check, int n,
                                      int n_outer, cm_rebuilt *out, cm_rebuild_ws *ws, cm_status *st);
/** Raise need[] (indexed by limit id) by what face F's rebuild needs beyond its loops. */
void cm_method_needs(const cm_method *M, const cm_model *m, const cm_face *F, uint32_t *need);

/**
 * Every method this version knows, in the encoder's order of trial (spec §14): the first whose
 * rebuild passes the verification wins; the last (KEEP) always applies.
 */
extern const cm_method *const cm_method_table[CM_METHOD_COUNT];

/** The method every face can fall back to: its own surface kept (the last row of the table). */
#define CM_METHOD_FALLBACK CM_METHOD_KEEP

/** The method numbered `id` on the wire, or NULL if this version does not know it. */
const cm_method *cm_method_of(unsigned id);

/** Its name, "?" for an unknown number (reports only). */
const char *cm_method_name(unsigned id);

extern const cm_method cm_method_keep, cm_method_plane, cm_method_gregory, cm_method_gregory_exact,
    cm_method_gregory_fit, cm_method_nfill, cm_method_g1fit;

#endif /* CM_METHOD_H */
