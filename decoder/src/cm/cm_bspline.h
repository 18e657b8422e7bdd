/*
 * cm_bspline.h - B-spline and NURBS curves and surfaces (spec K1-K3, K5).
 *
 * Conventions (The NURBS Book, 2nd ed.):
 *   p, q      degree in u, v (order = degree + 1)
 *   n_ctrl    number of control points (the book's n+1)
 *   knots     the full vector, n_ctrl + p + 1 values, in memory
 *   ctrl      control points; for surfaces row-major in u:
 *             ctrl[i*nv + j] is P_ij, i along u (0..nu-1), j along v
 *   w         weights, same layout as ctrl; NULL means non-rational
 * The parameter domain is [knots[p], knots[n_ctrl]]; the knot vector need
 * not be clamped.  Curves and surfaces are *views*: they point at storage
 * owned by the caller (model pools, workspaces), nothing is copied.
 *
 * Contract of every function here: no allocation, no recursion, no I/O;
 * stack below CM_STACK_FN_MAX; evaluation is a fixed sequence of + - * /
 * (bit-identical across architectures with -ffp-contract=off).  Degrees
 * above CM_MAX_DEGREE are refused with CM_E_LIMIT, never asserted.
 */
#ifndef CM_BSPLINE_H
#define CM_BSPLINE_H

#include "cm/cm_error.h"
#include "cm/cm_vec.h"
#include "cm_limits.h"

typedef struct cm_curve {
    int p;              /* degree, 1..CM_MAX_DEGREE */
    int n_ctrl;         /* control points, >= p+1 */
    const double *knots; /* n_ctrl + p + 1 values */
    const cm_vec3 *ctrl; /* n_ctrl points */
    const double *w;    /* n_ctrl weights > 0, or NULL */
} cm_curve;

/** A point in homogeneous form (w*P, w): what the rational algorithms interpolate. */
typedef struct cm_hpt {
    double x, y, z, w;
} cm_hpt;

typedef struct cm_surf {
    int p, q;           /* degrees in u and v */
    int nu, nv;         /* control points per direction */
    const double *U;    /* nu + p + 1 knots */
    const double *V;    /* nv + q + 1 knots */
    const cm_vec3 *ctrl; /* nu*nv points, row-major in u */
    const double *w;    /* nu*nv weights > 0, or NULL */
} cm_surf;

/**
 * Validate a knot vector for degree `p` and `n_ctrl` control points:
 * finite, non-decreasing, no multiplicity above p+1, non-empty domain.
 * @return CM_OK, CM_E_KNOTS, CM_E_NONFINITE, CM_E_RANGE (p < 1 or
 *         n_ctrl < p+1), CM_E_LIMIT (p > CM_MAX_DEGREE).
 */
CM_NODISCARD cm_err cm_knots_check(int p, int n_ctrl, const double *knots, cm_status *st);

/**
 * Validate a curve: degree, count against CM_MAX_EDGE_CTRL, knots, finite
 * control points, weights finite and > 0.
 */
CM_NODISCARD cm_err cm_curve_check(const cm_curve *c, cm_status *st);

/** Validate a surface: degrees, counts (CM_MAX_SURF_CTRL_DIR, CM_MAX_SURF_CTRL), knots, points, weights. */
CM_NODISCARD cm_err cm_surf_check(const cm_surf *s, cm_status *st);

/**
 * K1 FindSpan (A2.1): the span index i in [p, n_ctrl-1] with
 * knots[i] <= u < knots[i+1]; u is clamped to the domain and u at the
 * domain end maps to the last non-empty span.  Requires a checked knot
 * vector; terminates in at most 64 halvings whatever the input.
 */
int cm_bspl_find_span(int n_ctrl, int p, const double *knots, double u);

/**
 * K1 BasisFuns (A2.2): the p+1 non-zero basis functions at u in `span`.
 * @param[out] N  p+1 values, N[r] = N_{span-p+r,p}(u)
 */
CM_NODISCARD cm_err cm_bspl_basis(int span, double u, int p, const double *knots, double *N, cm_status *st);

/**
 * K1 DersBasisFuns (A2.3): basis functions and derivatives up to `nd`.
 * @param[out] ders  ders[k][r] = k-th derivative of N_{span-p+r,p}(u),
 *                   k = 0..nd (nd <= CM_MAX_DERS), r = 0..p
 */
CM_NODISCARD cm_err cm_bspl_ders_basis(int span, double u, int p, int nd, const double *knots,
                                       double ders[CM_MAX_DERS + 1][CM_MAX_ORDER], cm_status *st);

/**
 * K2 curve point and derivatives (A3.2 / A4.2 for rational curves).
 * @param[out] d  d[k] = k-th derivative at u, k = 0..nd (nd <= CM_MAX_DERS)
 */
CM_NODISCARD cm_err cm_curve_eval(const cm_curve *c, double u, int nd, cm_vec3 *d, cm_status *st);

/**
 * K2 surface point and partial derivatives (A3.6 / A4.4).
 * @param[out] S  S[k][l] = d^(k+l) S / du^k dv^l for k+l <= nd (nd <= CM_MAX_DERS);
 *                other entries are set to zero
 */
CM_NODISCARD cm_err cm_surf_eval(const cm_surf *s, double u, double v, int nd,
                                 cm_vec3 S[CM_MAX_DERS + 1][CM_MAX_DERS + 1], cm_status *st);

/**
 * K2 surface points on a grid: g[i * nv + j] = S(u[i], v[j]), the bits of cm_surf_eval's S[0][0]
 * (the same sums in the same order: each row's basis computed once, the u sums shared by the grid
 * points of one v span).  For grid searches, which need points only.
 */
CM_NODISCARD cm_err cm_surf_eval_grid(const cm_surf *s, const double *u, int nu, const double *v, int nv,
                                      cm_vec3 *g, cm_status *st);

/**
 * K3 knot insertion (A5.1, Boehm), in homogeneous space for rational
 * curves: insert u `r` times.  The result describes the same curve.
 * @param[out] knots_out  n_ctrl + r + p + 1 values
 * @param[out] ctrl_out   n_ctrl + r points
 * @param[out] w_out      n_ctrl + r weights (ignored when c->w is NULL)
 * @param cap             capacity of ctrl_out/w_out in points
 * @return CM_E_ARG if u lies outside the domain or the multiplicity would
 *         exceed p; CM_E_NOSPACE if cap < n_ctrl + r; CM_E_LIMIT if the
 *         result exceeds CM_MAX_EDGE_CTRL.
 */
CM_NODISCARD cm_err cm_curve_insert_knot(const cm_curve *c, double u, int r, double *knots_out,
                                         cm_vec3 *ctrl_out, double *w_out, int cap, cm_status *st);

/**
 * K3 the affine steps of knot insertion (A5.1) on homogeneous points, for
 * cm_curve_insert_knot and the workstation's unbounded curves: u, to be
 * inserted r times (r >= 1), lies in span k (knots[k] <= u < knots[k+1])
 * with multiplicity s (r + s <= p).  R[0..p-s] holds the old points
 * P[k-p .. k-s] (overwritten); the new points Q[k-p+1 .. k-s+r-1] are
 * written to out[0 .. p-s+r-2].  The points before and after them are the
 * old ones (Q[i] = P[i] for i <= k-p, Q[i+r] = P[i] for i >= k-s).
 */
void cm_knot_insert_steps(const double *knots, int p, int k, int s, int r, double u, cm_hpt *R, cm_hpt *out);

/**
 * K5 clamped uniform knot vector of degree p for n_ctrl control points:
 * p+1 zeros, interior knots k/(n_ctrl-p), p+1 ones.
 * @param[out] knots  n_ctrl + p + 1 values
 */
CM_NODISCARD cm_err cm_knots_uniform(int n_ctrl, int p, double *knots, cm_status *st);

/** K5 Greville abscissae xi_i = (knots[i+1] + ... + knots[i+p]) / p, i = 0..n_ctrl-1. */
CM_NODISCARD cm_err cm_greville(int n_ctrl, int p, const double *knots, double *xi, cm_status *st);

#endif /* CM_BSPLINE_H */
