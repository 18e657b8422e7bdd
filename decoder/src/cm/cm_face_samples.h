/*
 * cm_face_samples.h - the fixed boundary samples of a face (spec 8.1: ten
 * per edge use) that every method's rebuild and its error measure start
 * from, and the face size (bbox_F) taken from them.  Below the methods and
 * the corner analysis, which both use them.
 */
#ifndef CM_FACE_SAMPLES_H
#define CM_FACE_SAMPLES_H

#include "cm/cm_error.h"
#include "cm/cm_format.h"
#include "cm/cm_vec.h"

/**
 * Boundary samples of face f (all loops, loop order, use direction):
 * points at t = s/10, s = 0..9 of every edge use.
 * @param[out] n_outer  samples of the outer loop (the first ones)
 * @return CM_E_LIMIT if the face has more uses than CM_MAX_FACE_EDGES
 */
CM_NODISCARD cm_err cm_face_samples(const cm_model *m, uint32_t f, cm_vec3 *out, int cap, int *n, int *n_outer,
                                    cm_status *st);

/** Diagonal of the axis-aligned box of n > 0 points (spec §1 bbox_F of a face's samples). */
double cm_points_diag(const cm_vec3 *p, int n);

#endif /* CM_FACE_SAMPLES_H */
