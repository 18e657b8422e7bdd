/*
 * cm_bezier.h - Bézier tools (spec K4): cubic evaluation and split, line
 * and quadratic to cubic, general split and degree elevation.
 *
 * Contract: no allocation, no recursion, no I/O; results depend only on the
 * inputs through a fixed sequence of + - * / (bit-identical everywhere).
 */
#ifndef CM_BEZIER_H
#define CM_BEZIER_H

#include "cm/cm_bspline.h"
#include "cm/cm_error.h"
#include "cm/cm_vec.h"

/** A cubic Bézier C0..C3 (spec §1 "cubic edge"). */
typedef struct cm_cubic {
    cm_vec3 c[4];
} cm_cubic;

/** Cubic Bernstein polynomials B0..B3 at t and their first derivatives (either output may be NULL). */
void cm_bernstein3(double t, double B[4], double dB[4]);

/**
 * Point and derivatives of a cubic at t (t is not clamped).
 * @param[out] d  d[0] = C(t), d[1] = C'(t), d[2] = C''(t)
 */
void cm_cubic_eval(const cm_cubic *c, double t, cm_vec3 d[3]);

/** de Casteljau split at t: `a` covers [0,t], `b` covers [t,1]; both may alias nothing in `c`. */
void cm_cubic_split(const cm_cubic *c, double t, cm_cubic *a, cm_cubic *b);

/** The same cubic run backwards. */
cm_cubic cm_cubic_reverse(const cm_cubic *c);

/** Line P->Q as a cubic (P, P+(Q-P)/3, P+2(Q-P)/3, Q). */
cm_cubic cm_cubic_from_line(cm_vec3 P, cm_vec3 Q);

/** Quadratic Q0,Q1,Q2 elevated exactly to a cubic. */
cm_cubic cm_cubic_from_quad(cm_vec3 Q0, cm_vec3 Q1, cm_vec3 Q2);

/**
 * A cubic as a cm_curve view (degree 3, knots [0,0,0,0,1,1,1,1]) so the
 * generic curve kernels (K9 projection) apply.  The view points into `c`.
 */
cm_curve cm_cubic_as_curve(const cm_cubic *c);

/**
 * General de Casteljau split of a degree-p Bézier (p+1 points) at t.
 * @param[out] left, right  p+1 points each
 */
CM_NODISCARD cm_err cm_bez_split(const cm_vec3 *P, int p, double t, cm_vec3 *left, cm_vec3 *right, cm_status *st);

/** Binomial coefficient C(n,k), 0 unless 0 <= k <= n; exact in binary64 for n <= 2*CM_HARD_MAX_DEGREE. */
double cm_binomial(int n, int k);

/**
 * Degree elevation of a degree-p Bézier by t (NURBS Book eq. 5.36):
 * Q_i = sum_j C(p,j) C(t,i-j) / C(p+t,i) P_j; the end points are copied
 * (Q_0 = P_0, Q_p+t = P_p, bit for bit).
 * @param[out] Q  p+t+1 points
 * @return CM_E_LIMIT if p+t > CM_MAX_DEGREE
 */
CM_NODISCARD cm_err cm_bez_elevate(const cm_vec3 *P, int p, int t, cm_vec3 *Q, cm_status *st);

/** cm_bez_elevate on homogeneous points (a rational Bézier: every channel, w too, as above). */
CM_NODISCARD cm_err cm_bez_elevate_h(const cm_hpt *P, int p, int t, cm_hpt *Q, cm_status *st);

#endif /* CM_BEZIER_H */
