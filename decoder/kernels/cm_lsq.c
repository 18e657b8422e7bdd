/* cm_lsq.c - Cramer, dense and banded Cholesky, least-squares curves (spec K6, K8). */
#include "cm/cm_lsq.h"

#include <stddef.h>

#include "cm/cm_bspline.h"
#include "cm/cm_limits_info.h"

cm_err cm_solve2(const double A[4], const double b[2], double det_min, double x[2], cm_status *st)
{
    double det = A[0] * A[3] - A[1] * A[2];
    if (!(fabs(det) > det_min))
        return cm_fail(st, CM_E_SINGULAR, __func__);
    x[0] = (b[0] * A[3] - A[1] * b[1]) / det;
    x[1] = (A[0] * b[1] - b[0] * A[2]) / det;
    return CM_OK;
}

static double det3(const double A[9])
{
    return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
           A[2] * (A[3] * A[7] - A[4] * A[6]);
}

cm_err cm_solve3(const double A[9], const double b[3], double det_min, double x[3], cm_status *st)
{
    double det = det3(A);
    if (!(fabs(det) > det_min))
        return cm_fail(st, CM_E_SINGULAR, __func__);
    for (int c = 0; c < 3; c++) {
        double M[9];
        for (int i = 0; i < 9; i++)
            M[i] = A[i];
        for (int r = 0; r < 3; r++)
            M[r * 3 + c] = b[r];
        x[c] = det3(M) / det;
    }
    return CM_OK;
}

cm_err cm_chol_dense(double *A, int n, int lda, cm_status *st)
{
    if (n > CM_MAX_DENSE)
        return cm_fail_limit(st, CM_LIMIT_MAX_FIT_CTRL, (uint64_t)n, CM_MAX_DENSE, __func__);
    if (n < 1 || lda < n)
        return cm_fail(st, CM_E_ARG, __func__);
    double dmax = 0.0;
    for (int i = 0; i < n; i++)
        if (fabs(A[(long)i * lda + i]) > dmax)
            dmax = fabs(A[(long)i * lda + i]);
    double tiny = CM_CHOL_PIVOT_REL * dmax;
    for (int j = 0; j < n; j++) {
        double d = A[(long)j * lda + j];
        for (int k = 0; k < j; k++)
            d -= A[(long)j * lda + k] * A[(long)j * lda + k];
        if (!(d > tiny))
            return cm_fail(st, CM_E_SINGULAR, __func__);
        double ljj = sqrt(d);
        A[(long)j * lda + j] = ljj;
        for (int i = j + 1; i < n; i++) {
            double s = A[(long)i * lda + j];
            for (int k = 0; k < j; k++)
                s -= A[(long)i * lda + k] * A[(long)j * lda + k];
            A[(long)i * lda + j] = s / ljj;
        }
    }
    return CM_OK;
}

void cm_chol_dense_solve3(const double *L, int n, int lda, cm_vec3 *b)
{
    for (int i = 0; i < n; i++) {
        cm_vec3 s = b[i];
        for (int k = 0; k < i; k++)
            s = cm_axpy(s, -L[(long)i * lda + k], b[k]);
        b[i] = cm_scale(s, 1.0 / L[(long)i * lda + i]);
    }
    for (int i = n - 1; i >= 0; i--) {
        cm_vec3 s = b[i];
        for (int k = i + 1; k < n; k++)
            s = cm_axpy(s, -L[(long)k * lda + i], b[k]);
        b[i] = cm_scale(s, 1.0 / L[(long)i * lda + i]);
    }
}

cm_err cm_chol_band(double *A, int n, int w, cm_status *st)
{
    if (n > CM_MAX_LSQ_UNKNOWNS)
        return cm_fail_limit(st, CM_LIMIT_MAX_LSQ_UNKNOWNS, (uint64_t)n, CM_MAX_LSQ_UNKNOWNS, __func__);
    if (w > CM_MAX_LSQ_BAND)
        return cm_fail_limit(st, CM_LIMIT_MAX_LSQ_BAND, (uint64_t)w, CM_MAX_LSQ_BAND, __func__);
    if (n < 1 || w < 0)
        return cm_fail(st, CM_E_ARG, __func__);
    double dmax = 0.0;
    for (int i = 0; i < n; i++)
        if (fabs(A[CM_BAND_IDX(i, i, w)]) > dmax)
            dmax = fabs(A[CM_BAND_IDX(i, i, w)]);
    double tiny = CM_CHOL_PIVOT_REL * dmax;
    for (int i = 0; i < n; i++) {
        int j0 = i - w > 0 ? i - w : 0;
        for (int j = j0; j <= i; j++) {
            double s = A[CM_BAND_IDX(i, j, w)];
            /* L[i][k] and L[j][k] are both inside the band for k >= i-w */
            for (int k = j0; k < j; k++)
                s -= A[CM_BAND_IDX(i, k, w)] * A[CM_BAND_IDX(j, k, w)];
            if (j == i) {
                if (!(s > tiny))
                    return cm_fail(st, CM_E_SINGULAR, __func__);
                A[CM_BAND_IDX(i, i, w)] = sqrt(s);
            } else {
                A[CM_BAND_IDX(i, j, w)] = s / A[CM_BAND_IDX(j, j, w)];
            }
        }
    }
    return CM_OK;
}

void cm_chol_band_solve3(const double *L, int n, int w, cm_vec3 *b)
{
    for (int i = 0; i < n; i++) {
        cm_vec3 s = b[i];
        int k0 = i - w > 0 ? i - w : 0;
        for (int k = k0; k < i; k++)
            s = cm_axpy(s, -L[CM_BAND_IDX(i, k, w)], b[k]);
        b[i] = cm_scale(s, 1.0 / L[CM_BAND_IDX(i, i, w)]);
    }
    for (int i = n - 1; i >= 0; i--) {
        cm_vec3 s = b[i];
        int k1 = i + w < n - 1 ? i + w : n - 1;
        for (int k = i + 1; k <= k1; k++)
            s = cm_axpy(s, -L[CM_BAND_IDX(k, i, w)], b[k]);
        b[i] = cm_scale(s, 1.0 / L[CM_BAND_IDX(i, i, w)]);
    }
}

/* Assemble and solve the normal equations of cm_fit_curve for the unknown
 * control points first..first+nu-1 (fixed ends already stored in P). */
static cm_err fit_solve(const cm_vec3 *Q, const double *t, const double *omega, int m, int p, int n_ctrl,
                        const double *knots, int first, int nu, cm_vec3 *P, cm_fit_curve_ws *ws, cm_status *st)
{
    int last = first + nu - 1;
    cm_err e;
    for (long i = 0; i < (long)nu * nu; i++)
        ws->M[i] = 0.0;
    for (int i = 0; i < nu; i++)
        ws->rhs[i] = cm_v3(0, 0, 0);

    /* data part: N^T W N and N^T W R, R = Q minus the fixed ends' share */
    for (int k = 0; k < m; k++) {
        double N[CM_MAX_ORDER];
        int span = cm_bspl_find_span(n_ctrl, p, knots, t[k]);
        if ((e = cm_bspl_basis(span, t[k], p, knots, N, st)) != CM_OK)
            return e;
        double wk = omega ? omega[k] : 1.0;
        cm_vec3 R = Q[k];
        for (int a = 0; a <= p; a++) {
            int ia = span - p + a;
            if (ia < first || ia > last)
                R = cm_axpy(R, -N[a], P[ia]);
        }
        for (int a = 0; a <= p; a++) {
            int ra = span - p + a - first;
            if (ra < 0 || ra >= nu)
                continue;
            ws->rhs[ra] = cm_axpy(ws->rhs[ra], wk * N[a], R);
            for (int b = 0; b <= p; b++) {
                int rb = span - p + b - first;
                if (rb >= 0 && rb < nu)
                    ws->M[(long)ra * nu + rb] += wk * N[a] * N[b];
            }
        }
    }
    double trace = 0.0;
    for (int i = 0; i < nu; i++)
        trace += ws->M[(long)i * nu + i];
    double lambda = 1e-6 * trace / (double)nu;

    /* fairing: lambda * sum_r |P_{r-1} - 2P_r + P_{r+1}|^2 over the full polygon */
    static const double coef[3] = {1.0, -2.0, 1.0};
    for (int r = 1; r + 1 < n_ctrl; r++) {
        for (int a = 0; a < 3; a++) {
            int ra = r - 1 + a - first;
            if (ra < 0 || ra >= nu)
                continue;
            for (int b = 0; b < 3; b++) {
                int ib = r - 1 + b, rb = ib - first;
                if (rb >= 0 && rb < nu)
                    ws->M[(long)ra * nu + rb] += lambda * coef[a] * coef[b];
                else /* fixed end: its term moves to the right-hand side */
                    ws->rhs[ra] = cm_axpy(ws->rhs[ra], -lambda * coef[a] * coef[b], P[ib]);
            }
        }
    }
    if ((e = cm_chol_dense(ws->M, nu, nu, st)) != CM_OK)
        return e;
    cm_chol_dense_solve3(ws->M, nu, nu, ws->rhs);
    for (int i = 0; i < nu; i++)
        P[first + i] = ws->rhs[i];
    return CM_OK;
}

cm_err cm_fit_curve(const cm_vec3 *Q, const double *t, const double *omega, int m, int p, int n_ctrl,
                    const double *knots, const cm_vec3 *P_first, const cm_vec3 *P_last, cm_vec3 *P, double *rms,
                    cm_fit_curve_ws *ws, cm_status *st)
{
    if (p > CM_MAX_DEGREE)
        return cm_fail_limit(st, CM_LIMIT_MAX_DEGREE, (uint64_t)p, CM_MAX_DEGREE, __func__);
    if (n_ctrl > CM_MAX_DENSE)
        return cm_fail_limit(st, CM_LIMIT_MAX_FIT_CTRL, (uint64_t)n_ctrl, CM_MAX_DENSE, __func__);
    if (p < 1 || n_ctrl < p + 1 || m < 1)
        return cm_fail(st, CM_E_RANGE, __func__);

    int first = P_first ? 1 : 0;
    int nu = (P_last ? n_ctrl - 1 : n_ctrl) - first; /* unknown control points */
    if (P_first)
        P[0] = *P_first;
    if (P_last)
        P[n_ctrl - 1] = *P_last;
    cm_err e;
    if (nu > 0 && (e = fit_solve(Q, t, omega, m, p, n_ctrl, knots, first, nu, P, ws, st)) != CM_OK)
        return e;
    if (rms) {
        cm_curve c = {p, n_ctrl, knots, P, NULL};
        double sum = 0.0;
        for (int k = 0; k < m; k++) {
            cm_vec3 d[1];
            if ((e = cm_curve_eval(&c, t[k], 0, d, st)) != CM_OK)
                return e;
            sum += cm_norm2(cm_sub(d[0], Q[k]));
        }
        *rms = sqrt(sum / (double)m);
    }
    return CM_OK;
}
