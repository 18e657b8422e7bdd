/*
 * cm_lsq.h - linear solvers and least squares (spec K6, K8).
 *
 * All systems here are symmetric positive definite by construction, so
 * Cholesky without pivoting is used; a pivot below 1e-13 of the largest
 * diagonal entry is reported as CM_E_SINGULAR (the "documented
 * conditioning limit").  Storage is caller-owned; sizes are checked
 * against fixedcfg limits.
 */
#ifndef CM_LSQ_H
#define CM_LSQ_H

#include "cm/cm_error.h"
#include "cm/cm_vec.h"
#include "cm_limits.h"

/** Relative pivot threshold of both Cholesky variants (spec K8b). */
#define CM_CHOL_PIVOT_REL 1e-13

/**
 * K8a: solve the 2x2 system A x = b by Cramer's rule, A row-major.
 * @return CM_E_SINGULAR if |det| <= det_min (x untouched)
 */
CM_NODISCARD cm_err cm_solve2(const double A[4], const double b[2], double det_min, double x[2], cm_status *st);

/** K8a: 3x3 by Cramer's rule, A row-major; CM_E_SINGULAR if |det| <= det_min. */
CM_NODISCARD cm_err cm_solve3(const double A[9], const double b[3], double det_min, double x[3], cm_status *st);

/**
 * K8b: dense Cholesky A = L L^T in place (lower triangle of A, row-major
 * with leading dimension lda; the upper triangle is not read).
 * @return CM_E_LIMIT if n > CM_MAX_DENSE, CM_E_SINGULAR on a small pivot
 */
CM_NODISCARD cm_err cm_chol_dense(double *A, int n, int lda, cm_status *st);

/** Solve L L^T x = b for three right-hand sides at once (b overwritten by x). */
void cm_chol_dense_solve3(const double *L, int n, int lda, cm_vec3 *b);

/** Index of M[i][j] (j <= i, i-j <= w) in banded lower storage of half bandwidth w. */
#define CM_BAND_IDX(i, j, w) ((long)(i) * ((w) + 1) + ((i) - (j)))

/**
 * K8c: banded Cholesky in place.  Storage: row i holds M[i][i-k] at
 * CM_BAND_IDX(i, i-k, w), k = 0..w (n*(w+1) doubles).
 * @return CM_E_LIMIT if n > CM_MAX_LSQ_UNKNOWNS or w > CM_MAX_LSQ_BAND,
 *         CM_E_SINGULAR on a small pivot
 */
CM_NODISCARD cm_err cm_chol_band(double *A, int n, int w, cm_status *st);

/** Solve with a banded factor for three right-hand sides (b overwritten by x). */
void cm_chol_band_solve3(const double *L, int n, int w, cm_vec3 *b);

/** Workspace of cm_fit_curve: the normal equations of at most CM_MAX_DENSE unknowns. */
typedef struct cm_fit_curve_ws {
    double M[CM_MAX_DENSE * CM_MAX_DENSE];
    cm_vec3 rhs[CM_MAX_DENSE];
} cm_fit_curve_ws;

/**
 * K6: least-squares B-spline curve of degree p with a given knot vector
 * (NURBS Book eq. 9.63-9.67): minimise sum w_k |C(t_k) - Q_k|^2 +
 * lambda |D P|^2, D the second differences of the control polygon and
 * lambda = 1e-6 trace(N^T W N)/#unknowns (keeps the system SPD when a span
 * holds no data).  End points are fixed when `P_first` / `P_last` are
 * non-NULL, free otherwise.
 * @param Q, t, omega  m data points, parameters in the knot domain,
 *                     weights (omega NULL = all 1)
 * @param[out] P    n_ctrl control points (fixed ends copied in)
 * @param[out] rms  sqrt(mean |C(t_k) - Q_k|^2), unweighted; may be NULL
 * @return CM_E_LIMIT if n_ctrl > CM_MAX_DENSE or p > CM_MAX_DEGREE,
 *         CM_E_RANGE if m < 1 or n_ctrl < p+1, CM_E_SINGULAR
 */
CM_NODISCARD cm_err cm_fit_curve(const cm_vec3 *Q, const double *t, const double *omega, int m, int p, int n_ctrl,
                                 const double *knots, const cm_vec3 *P_first, const cm_vec3 *P_last, cm_vec3 *P,
                                 double *rms, cm_fit_curve_ws *ws, cm_status *st);

#endif /* CM_LSQ_H */
