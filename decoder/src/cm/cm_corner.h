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

typedef struct cm_corner_ws {
    cm_vec3 samples[CM_MAX_FACE_SAMPLES];  /* the face's boundary samples */
    cm_vec3 scratch[CM_MAX_FACE_SAMPLES];  /* a partner face's */
    cm_vec3 geo[CM_GREG_MAX_INPUT];
    int has_geo[CM_GREG_MAX_INPUT];
    int32_t vert[CM_GREG_MAX_INPUT];
} cm_corner_ws;

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
 * EPS_LEN (1e-12 of the face's bbox).  Hints (spec 15.3) are not part of
 * this format version: a flat corner with no G1 partner takes n_F.
 * Each side also names its edge and curve (for cm_egreg_build).  `exact` 1
 * (GREGORY-EXACT): no K7 cubics (left zero), and corner and partner normals
 * as the loops orient them, never turned to n_F (see geo_normal).
 * @return CM_E_UNSUPPORTED for fewer than 3 sides, CM_E_LIMIT above
 *         CM_MAX_SIDES, errors of K7
 */
CM_NODISCARD cm_err cm_greg_input_build(const cm_model *m, uint32_t f, int exact, cm_greg_input *in, cm_corner_ws *ws,
                                        cm_status *st);

#endif /* CM_CORNER_H */
