/*
 * cm_corner.h - what the Gregory construction reads of the curve mesh: each
 * face's reference normal, its corner normals (spec 5.3), the K7 cubic of
 * every outer-loop edge and the edge basis normals (spec 5.4, with the
 * symmetric rule across G1 edges).  Decoder code, used as-is by the encoder.
 */
#ifndef CM_CORNER_H
#define CM_CORNER_H

#include "cm/cm_format.h"
#include "cm/cm_gregface.h"

/* entries of each of cm_corner_ws's two caches (a power of two): faces and edges are looked up by
   their index modulo this, and a model's faces meet their neighbours a few faces apart */
#define CM_CORNER_CACHE 64

typedef struct cm_corner_ws {
    cm_vec3 samples[CM_MAX_FACE_SAMPLES];  /* the face's boundary samples */
    cm_vec3 scratch[CM_MAX_FACE_SAMPLES];  /* a partner face's */
    cm_vec3 geo[CM_GREG_MAX_INPUT];
    int has_geo[CM_GREG_MAX_INPUT];
    int32_t vert[CM_GREG_MAX_INPUT];
    /* while cache_model is set (cm_corner_cache_begin), what a face's rebuild computes of the curve
       mesh alone is kept for the next faces: a face's n_F and bbox (every GREGORY face asks for its
       G1 partners' too) and an edge's K7 cubic (asked by both its faces).  The same numbers, not
       computed again; the encoder, whose trials change the model between rebuilds, leaves it off */
    const cm_model *cache_model;
    struct {
        int32_t face; /* -1: empty */
        double bbox;
        cm_vec3 n;
    } normal_cache[CM_CORNER_CACHE];
    struct {
        int32_t edge; /* -1: empty */
        cm_cubic c;
    } cubic_cache[CM_CORNER_CACHE];
} cm_corner_ws;

/** Keep face normals and edge cubics of m in ws from now on (m must not change until
 *  cm_corner_cache_end); NULL m is cm_corner_cache_end. */
void cm_corner_cache_begin(cm_corner_ws *ws, const cm_model *m);
/** Compute everything again (the model may change). */
void cm_corner_cache_end(cm_corner_ws *ws);

/**
 * Reference normal n_F of face f (Newell normal of its outer-loop samples, K11)
 * and bbox_F, the diagonal of the box of all its boundary samples (spec §1).
 * @param samples  CM_MAX_FACE_SAMPLES scratch points
 */
CM_NODISCARD cm_err cm_face_normal(const cm_model *m, uint32_t f, cm_vec3 *samples, double *bbox, cm_vec3 *n,
                                   cm_status *st);

/**
 * Unit tangent of use U at its start (at_end 0) or end, in the use's direction: the curve's end
 * derivative, or where that is <= eps long (a doubled control point) the chord to the point at
 * 1e-3 from that end.  0 if it is still degenerate.
 */
int cm_use_tangent(const cm_model *m, const cm_use *U, int at_end, double eps, cm_vec3 *t);

/**
 * The input of cm_greg_build() for face f's outer loop: n sides with their
 * cubics in the face's direction, basis normals, corner normals, n_F and
 * EPS_LEN (1e-12 of the face's bbox).  A flat corner with no G1 edge takes
 * the record's hint (format 4.13, spec 15.3) where it has one, else n_F.
 * Each side also names its edge and curve (for cm_egreg_build).  `exact` 1
 * (GREGORY-EXACT): no K7 cubics (left zero), and corner and partner normals
 * as the loops orient them, never turned to n_F (see geo_normal).
 * @return CM_E_UNSUPPORTED for fewer than 3 sides, CM_E_LIMIT above
 *         CM_MAX_SIDES, errors of K7
 */
CM_NODISCARD cm_err cm_greg_input_build(const cm_model *m, uint32_t f, int exact, cm_greg_input *in, cm_corner_ws *ws,
                                        cm_status *st);

#endif /* CM_CORNER_H */
