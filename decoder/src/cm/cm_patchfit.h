/*
 * cm_patchfit.h - the interior correction of a Gregory patch (method
 * GREGORY-FIT, docs/METHODS.md).
 *
 * Why: a Gregory patch interpolates a face's boundary and its neighbours'
 * tangent planes, but the interior is only what the blending makes of them.
 * On real models many faces come back at 1.0-1.2 % of their size against a
 * tolerance of 1 % (fillets of revolution, saddles), and at a tolerance of
 * 0.1 % most curved faces do.  The encoder knows the true surface: it fits a
 * small correction and sends it, a few bytes against the hundreds a kept
 * surface costs.
 *
 * The correction of one patch over [0,1]^2 is
 *
 *   D(u,v) = sum_{i,j < m} c_ij B_{i+2}(u) B_{j+2}(v),   B_k = Bernstein of degree m+3,
 *
 * m = 1..CM_FIT_MAX_M coefficients per direction.  B_k with 2 <= k <= d-2
 * vanishes with its first derivative at 0 and 1, so D and its first partials
 * are zero on all four sides of the patch: the boundary stays the curve mesh's,
 * the cross derivatives stay those G1 was built from, and the patches of one
 * face still meet as before.  Adding D changes nothing else.
 *
 * Contract: pure functions; no heap, no VLA, no recursion; + - * / only in
 * a fixed order (spec §2 rules 3-4).
 */
#ifndef CM_PATCHFIT_H
#define CM_PATCHFIT_H

#include <stdint.h>

#include "cm/cm_vec.h"

#define CM_FIT_MAX_M 5                                /* coefficients per direction */
#define CM_FIT_MAX_COEF (CM_FIT_MAX_M * CM_FIT_MAX_M) /* per patch */
#define CM_FIT_MAX_EXP 40                             /* a step at most 2^40 model grid steps */
#define CM_FIT_MAX_INT (1 << 24)                      /* |quantised coordinate| beyond is refused */

/**
 * The m basis functions B_{i+2} of degree m+3 at t, and their derivatives
 * (db may be NULL).  m outside 1..CM_FIT_MAX_M gives zeros.
 */
void cm_fit_basis(int m, double t, double b[CM_FIT_MAX_M], double db[CM_FIT_MAX_M]);

/**
 * Add the correction c[i*m + j] (m per direction) at (u,v) to S and, where
 * not NULL, to the partials Su, Sv.  m == 0 adds nothing.
 */
void cm_fit_add(const cm_vec3 *c, int m, double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv);

/**
 * A record's quantised coordinate in millimetres: qi * 2^exp * grid, grid the model's grid step
 * (cm_model.q, a power of two) and exp the record's.  Exact (power-of-two scalings).
 */
double cm_fit_dequantise(int32_t qi, double grid, int exp);

/**
 * A fitted net's interior correction (NFILL, G1FIT; format 4.2): the same D with m per direction,
 * over the net's parameters, added to a clamped bicubic net of nu x nv points (row-major in u,
 * knots U and V): point (i,j), 2 <= i <= nu-3 and 2 <= j <= nv-3, moves by D(xi_i, eta_j) at its
 * Greville abscissae.  Rows and columns 0, 1, n-2 and n-1 stay: the border, and the cross
 * derivatives along it that G1 with the neighbours was built from, are the net's own.  The
 * surface stays one B-spline net, evaluated and tessellated as before.
 */
void cm_fit_net_add(cm_vec3 *ctrl, int nu, int nv, const double *U, const double *V, const cm_vec3 *c, int m);

#endif /* CM_PATCHFIT_H */
