/*
 * cm_gregory.h - the bicubic Gregory patch (spec §6.1; Chiyokura & Kimura
 * 1983) with exact first derivatives.
 *
 *   S(u,v) = sum_i sum_j B_i(u) B_j(v) P_ij(u,v)
 *   P_11 = (u P110 + v P111)/(u+v)          P_12 = (u P120 + (1-v) P121)/(u+1-v)
 *   P_21 = ((1-u) P210 + v P211)/(1-u+v)    P_22 = ((1-u) P220 + (1-v) P221)/(2-u-v)
 *
 * The 16+4 points: P[i][j] (i along u, j along v; P[1..2][1..2] unused) and
 * I[i-1][j-1][0] = P_ij0 (used on the v-boundaries v=0, v=1),
 * I[i-1][j-1][1] = P_ij1 (used on the u-boundaries u=0, u=1).
 */
#ifndef CM_GREGORY_H
#define CM_GREGORY_H

#include "cm/cm_vec.h"

typedef struct cm_gregory {
    cm_vec3 P[4][4];
    cm_vec3 I[2][2][2];
} cm_gregory;

/**
 * Evaluate a Gregory patch at (u,v), clamped to [0,1]^2.
 * At a corner where an interior blend is 0/0 the pair's mean is used
 * (its Bernstein weight is 0 there) and its derivative term is 0; the
 * derivatives elsewhere include the rational blending terms exactly
 * (unlike embree's "approximative" derivative).
 * @param[out] S, Su, Sv  point and first partials; Su/Sv may be NULL
 */
void cm_greg_eval(const cm_gregory *g, double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv);

/**
 * One interior blend X = (a*A + b*B)/(a+b) with a, b affine in (u,v) and the
 * gradients a_u, a_v, b_u, b_v.  Writes X and its partials.  If a+b is
 * exactly 0 (a patch corner) X is the mean of A and B and the partials are
 * 0: the weight of X and its derivative vanish there, so the value is
 * immaterial and the limit of the product is 0.  (Also the compatibility-
 * corrected twists of the exact-boundary patch, cm_egreg.h.)
 */
void cm_greg_blend(cm_vec3 A, cm_vec3 B, double a, double b, double a_u, double a_v, double b_u, double b_v,
                   cm_vec3 *X, cm_vec3 *X_u, cm_vec3 *X_v);

#endif /* CM_GREGORY_H */
