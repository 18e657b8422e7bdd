/*
 * encode.h - the workstation encoder: a loaded model (IGES -> curve mesh)
 * to .cmz bytes (docs/FORMAT.md, docs/METHODS.md).
 *
 * Order of work (spec §14), one file each:
 *   1. every part consistently oriented (shared edges run both ways) and
 *      the edges quantised first (spec §2 rule 5): clamped on [0,1], ends
 *      exactly on the quantised vertices (tx_build.c);
 *   2. the file written with every face kept and decoded with the
 *      terminal's code, so that the methods are tried on exactly the
 *      transmitted edges: per face the first method of the table whose
 *      rebuild passes the check against the source surface (spec §12),
 *      then the G1 fix-point (§13) (choose_methods.c, enc_plane.c,
 *      enc_gregory.c, enc_keep.c);
 *   3. the terminal's tessellation of every face: the needs, and closed
 *      parts turned outwards by the volume they enclose (needs.c); a part
 *      turned is encoded again from 1;
 *   4. the final file written (write_sections.c), decoded once more, its
 *      needs compared with the target profile's limits (encode.c).
 * A face that cannot be sent is settled between passes (encode.c:
 * encode_model).  All work storage is allocated per call: two encodes may
 * run side by side.
 */
#ifndef ENCODE_H
#define ENCODE_H

#include <stddef.h>
#include <stdint.h>

#include "cm/cm_format.h"
#include "cm/cm_limits_info.h"
#include "model_load.h"

struct enc_parts;

typedef struct encode_opts {
    double rel_tol;    /* rebuild tolerance, fraction of a face's bounding box (spec §1: 0.01) */
    double quant_rel;  /* coordinate grid step, fraction of the model diagonal (rounded down to 2^k mm) */
    double tess_rel;   /* recommended chordal tolerance, fraction of the model diagonal */
    const cm_limit_info *target; /* limits of the profile the file must load on (NULL: none) */
    const char *target_name;
    double abs_tol;              /* > 0: a face's tolerance in mm (with rel_tol too when rel_set) */
    int rel_set;                 /* rel_tol was asked for (with abs_tol the smaller one applies) */
    double model_tol_rel;        /* unless rel_tol or abs_tol was asked for: a face's tolerance is
                                    also at most this fraction of the model's diagonal (default 1e-3;
                                    0: rel_tol alone) */
    int gregory;                 /* try GREGORY (spec §6) on non-planar faces (default 1) */
    int gregory_exact;           /* then GREGORY-EXACT (with gregory; default 1) */
    int gregory_fit;             /* then GREGORY-FIT (with gregory_exact; default 1) */
    int g1fit;                   /* then G1FIT (spec §9 over the face's edges; default 1) */
    int nfill;                   /* then NFILL (spec §8; default 1) */
    int turning_basis;           /* exact patches turn their cross basis with edges that turn more than
                                    a right angle (format 2.6, cm_egreg.h; default 1; 0: format 2.5's
                                    linear basis throughout) */
    int predicted;               /* code curves and knots predicted (format 3, cm_predict.h; default 1;
                                    0: format 2's coding, for terminals of format 2) */
    int compact_header;          /* with predicted: format 4's compact header (cm_fmt_compact_pack; default 1;
                                    0: format 3's fixed one, for terminals of format 3) */
    int compact_minor;           /* its minor: 2 (default) lets NFILL and G1FIT nets carry an interior
                                    correction (format 4.2); 1 codes the origin on a coarse step and the
                                    rebuild tolerance from the default (format 4.1); 0: format 4.0 */
    int budget_steps;            /* with predicted: curves as the fewest cubic points and on steps of their
                                    own from the tolerance budget, the vertices on one (tx_coarsen.c;
                                    default 1; 0: every point on the grid, as in the source) */
    int instances;               /* a model loaded with its placed copies folded out (MODEL_LOAD_FOLD) sends
                                    each copy as a transform (format 4.3; default 1: see encode_places) */
    int strict;                  /* a face that cannot be sent fails the model (default: left out, warned) */
    int measure_mesh;            /* measure each face's triangles against its source (face_report.mesh_dev;
                                    default 0: it costs a second tessellation and many projections) */
    model_progress progress;     /* called per face in the long stages (NULL: none) */
    void *progress_ctx;
    int jobs;                    /* processes for the per-face work (enc_workers.c; 1: this one alone):
                                    the same bytes whatever the count; more than 1 forks the caller,
                                    so a threaded caller keeps it at 1 */
    int jobs_die_after;          /* tests only: each worker dies after taking this many faces, its last
                                    unanswered (0: never), to show that the encoder takes them over */
    const char *steps;           /* a file naming parts one per line: the terminal's assembly steps in
                                    that order (parts.c; NULL: file order) */
    void (*test_parts)(struct enc_parts *p); /* tests only: rewrites the parts before they are written
                                    (a broken writer's records; NULL: none) */
} encode_opts;

void encode_opts_default(encode_opts *o);

/** Whether o writes placed copies (format 4.3 on, instances on): a caller loads the model with
    MODEL_LOAD_FOLD then, and encode_model refuses a folded model otherwise. */
int encode_places(const encode_opts *o);

/** Whether a decoded copy's transform m (cm_placement.m) is x as format 4.3 sends it: the linear part
    exactly, the translation within half a grid step q (the grid origin's rounding too). */
int encode_placement_is(const double m[12], const haffine *x, double q, const double origin[3]);

/** Leave out what a reader of format major.minor (at most) cannot read: the coding, methods and the
    turning basis newer than it, so that the file is written as that version or older. */
void encode_opts_for_format(encode_opts *o, int major, int minor);

/** A face's rebuild tolerance in mm (spec §1 tol_F): rel_tol x bbox_F, or abs_tol, or the smaller. */
double encode_face_tol(double rel_tol, int rel_set, double abs_tol, double bbox);

/** The options as they apply to a model of diagonal `diag` (mm): with neither --tol nor --tol-abs,
    abs_tol = model_tol_rel x diag and the smaller of it and rel_tol x bbox_F applies (issue 14.6). */
void encode_opts_for_model(encode_opts *o, double diag);

typedef struct face_report {
    int method;        /* CM_METHOD_* */
    int layout, corner; /* GREGORY: layout 0/1/2 and layout 2's vertex; -1 otherwise */
    double rebuild_avg;/* mean distance over the §12 points (mm) */
    double greg_ratio; /* best §12 ratio any GREGORY candidate reached (0: none tried) */
    double g1_cos;     /* worst |nF.nG| on the face's G1 edges, final surfaces (§13; 1: none) */
    const char *why;   /* KEEP: why GREGORY did not apply or failed (NULL: not tried) */
    double bbox;       /* face bounding-box diagonal (mm) */
    double plane_dev;  /* largest boundary distance from the face's plane (mm) */
    double rebuild_max;/* largest distance of the original surface to the sent one (§12 grid, mm) */
    double ratio;      /* rebuild_max / bbox */
    int surf_ctrl;     /* control points sent for a kept surface */
    int fit_m;         /* GREGORY-FIT: coefficients per direction of its correction (else 0) */
    double mesh_dev;   /* the face as the terminal shows it against its source, both ways (mm; -1: not
                          measured; encode_opts.measure_mesh) */
} face_report;

typedef struct encode_result {
    uint8_t *bytes;    /* malloc'd file */
    size_t len;
    uint32_t need[CM_LIMIT_COUNT];
    uint32_t faces_by_method[CM_METHOD_COUNT]; /* faces sent by each method, indexed by its number */
    int edges_line, edges_curve;
    int faces_flipped; /* faces turned to make every part consistently oriented */
    int faces_left_out; /* faces the encoder left out (model_leave_out_face: warned, in lm->left_out) */
    uint32_t placements, placed_faces; /* format 4.3: copies of parts sent as transforms, and their faces */
    double q;          /* grid step (mm) */
    int edges_refit, surfs_refit; /* edges and kept surfaces re-approximated to fit the target profile */
    int edges_reapproximated;     /* curves sent as fewer cubic points within their budget (budget steps) */
    int edges_arcs;               /* curves sent as arcs through their middle points (format 4.4) */
    int surfs_reapproximated;     /* kept surfaces likewise */
    int nets_whole;               /* kept nets sent whole: re-approximated, they folded their triangles */
    double tess_asked, tess_used; /* recommended chordal tolerance (mm): asked (--tess), written (coarser
                                     when a target profile's tessellation limits needed it, issue 14.5) */
    size_t section_bytes[6];
    face_report *faces; /* one per face (malloc'd) */
    char refusal[512]; /* non-empty: the target profile cannot load the file (why) */
    int parts, parts_stepped; /* format 4.11: parts sent (0: none), of them in the order of opts.steps */
} encode_result;

/* The model's parts in the order of the terminal's assembly steps (parts.c, format 4.11): what the
   CAD system made one (an outermost instance or occurrence, a solid or shell, an IGES associativity
   group), loose faces joined by their edges, each placed copy one; in file order, or those `steps`
   (a file: names or "#N", one per line) names first.  face_part[f] (the cmesh's faces) and
   place_part[k] (lm->brep.placements) are 1..nparts. */
struct enc_parts {
    int nparts, stepped; /* parts; of them ordered by steps */
    int held;            /* faces and copies the CAD system put in a part (not loose) */
    int *face_part, *place_part;
};
typedef struct enc_parts enc_parts;

/** Number the parts; CM_E_ARG / CM_E_IO with why (whylen bytes) saying what is wrong with steps. */
CM_NODISCARD cm_err enc_parts_build(const loaded_model *lm, const char *steps, enc_parts *p, char *why,
                                    size_t whylen, cm_status *st);
void enc_parts_free(enc_parts *p);

/** The names part (1..nparts) answers to in a steps file (0 to 2 of them, into names); its faces in *nfaces. */
int enc_part_names(const loaded_model *lm, const enc_parts *p, int part, char names[2][80], int *nfaces);

void encode_result_free(encode_result *r);

/**
 * Encode lm.  The model's faces may be re-oriented in place, and a face that cannot be sent is
 * left out of lm (warned; see encode.c: encode_model).  On success
 * r->bytes holds the file; if opts->target is set and a need exceeds it,
 * returns CM_E_LIMIT with r->refusal explaining (the bytes are still
 * produced, so a caller may report sizes).
 */
CM_NODISCARD cm_err encode_model(loaded_model *lm, const encode_opts *opts, encode_result *r, cm_status *st);

#endif /* ENCODE_H */
