/*
 * cm_sections.h - the coding contexts of each .cmz section (docs/FORMAT.md:
 * "each field named below has its own model").  One struct per section,
 * started by one function, used by the writer (host_tools/encode) and the
 * reader (cm_decode.c) alike: the two cannot disagree on which adaptive
 * model codes which field, and a new field is added in one place.
 */
#ifndef CM_SECTIONS_H
#define CM_SECTIONS_H

#include "cm/cm_arith.h"

/* VERT: count, then grid coordinates as deltas */
typedef struct cm_vert_ctx {
    cm_ac_int count, coord[3];
    cm_ac_int step; /* format 3: the exponent of the vertices' step */
    cm_ac_prob repeat[3]; /* format 4: the coordinate is one of the axis's recent values ... */
    cm_ac_int slot[3];    /* ... this one (cm_vcache) */
} cm_vert_ctx;

/* EDGE: count; per edge its vertex references, G1 bit, kind, and a curve's degree, size, knots,
   control points and weights */
typedef struct cm_edge_ctx {
    cm_ac_int count, back, degree, ncoef, knot, coord[3], weight;
    cm_ac_prob is_new, g1, kind, rational, uniform;
    cm_ac_prob linear, knot_zero; /* format 3: the curve's predictor, a repeated knot */
    cm_ac_int knot_delta;         /* format 3: a knot gap less the last gap that was not zero */
    cm_ac_int step;               /* format 3: the exponent of the curve's own step */
    cm_ac_prob arc;               /* format 4.4: a curve sent as an arc (its middle point) */
    cm_ac_int arc_step, arc_coord[3]; /* ... the point's step and its offset from the chord's midpoint */
} cm_edge_ctx;

/* SURF: count; per kept surface its degrees, sizes, knots, net and weights */
typedef struct cm_surf_ctx {
    cm_ac_int count, degree, ncoef, knot, coord[3], weight;
    cm_ac_prob rational, uniform;
    cm_ac_prob quadratic;         /* format 3: the net's predictor (cm_pred_net) */
    cm_ac_int step;               /* format 3: the exponent of the net's own step */
    cm_ac_prob knot_zero;         /* format 3, as for edges */
    cm_ac_int knot_delta;
    cm_ac_prob ruled, closed;     /* format 4.4: the surface ruled between two arcs (full circles) */
    cm_ac_prob along_v;           /* ... the arcs along v */
    cm_ac_int ruled_step, ruled_coord[3]; /* ... their points' step and coordinates */
} cm_surf_ctx;

/* FACE: count; per face its method, its record (GREGORY: layout, corner, checksum), orientation,
   loops and edge uses */
typedef struct cm_face_ctx {
    cm_ac_int count, method, loops, uses, back, layout, corner;
    cm_ac_prob flip, is_new, rev_new, rev_old;
    cm_ac_int cand;     /* format 4.5: a use's place among the edges at its vertex (cm_use_adj.h) */
    cm_ac_prob rev_closed; /* ... and the direction of a closed edge's use */
    cm_ac_int fit_m, fit_patches, fit_exp, fit_coef; /* GREGORY-FIT's correction (and the nets') */
    cm_ac_prob twist_on, twist_use;                  /* G1FIT's twists (format 4.2): any, per use */
    cm_ac_int twist_n, twist;                        /* ... their count, and each sample's change */
    cm_ac_int place_n, place_first, place_count;     /* format 4.3: the placed copies ... */
    cm_ac_int place_entry, place_shift;              /* ... their linear parts' entries, translations */
    cm_ac_prob hint_any;                             /* format 4.13: GREGORY-family corner hints: any, */
    cm_ac_int hint_mask, hint_oct;                   /* ... their corners, their normals */
    int net_fit; /* format 4.2 on: NFILL and G1FIT records end with a correction's field (not a
                    coder context: set by the reader and the writer from the version) */
    int placements; /* format 4.3 on: the section ends with the placed copies (likewise) */
    int hints;      /* format 4.13 on: GREGORY-family records end with their corner hints (likewise) */
} cm_face_ctx;

/* COLR: palette size, then a palette index per face */
typedef struct cm_colr_ctx {
    cm_ac_int count, index;
    cm_ac_int nparts, part;     /* format 4.11: the parts */
    cm_ac_int name_bytes, name_len, name_back; /* format 4.12: their names' bytes sent in all, each new
                                                  name's length, an earlier part's name again */
    cm_ac_prob name_again;
    cm_ac_prob part_same, part_next;
} cm_colr_ctx;

void cm_vert_ctx_init(cm_vert_ctx *c);
void cm_edge_ctx_init(cm_edge_ctx *c);
void cm_surf_ctx_init(cm_surf_ctx *c);
void cm_face_ctx_init(cm_face_ctx *c);
void cm_colr_ctx_init(cm_colr_ctx *c);

#endif /* CM_SECTIONS_H */
