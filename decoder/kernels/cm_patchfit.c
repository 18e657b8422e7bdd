/* cm_patchfit.c - the interior correction of a Gregory patch (see cm_patchfit.h). */
#include "cm/cm_patchfit.h"

#include <stddef.h>

/* Bernstein B^d_k(t) = C(d,k) t^k (1-t)^(d-k) by repeated products (no pow: spec §2 rule 3), for
   0 <= k <= d <= CM_FIT_MAX_M + 3: t^k from t's powers tp[] (tp[i] = tp[i-1] t from 1.0), then (1-t)
   d-k times, then the binomial, an exact integer.  The bits of forming C(d,k) as c (d-k+i) / i and
   t^k in the loop each call (every step of both is exact or the same product; test_patchfit holds it
   to that), at a third of the cost: every GREGORY-FIT point's evaluation calls this 3 m times per
   direction */
static double bernstein_pow(int d, int k, const double *tp, double s)
{
    static const double binom[CM_FIT_MAX_M + 4][CM_FIT_MAX_M + 4] = {
        {1}, {1, 1}, {1, 2, 1}, {1, 3, 3, 1}, {1, 4, 6, 4, 1}, {1, 5, 10, 10, 5, 1}, {1, 6, 15, 20, 15, 6, 1},
        {1, 7, 21, 35, 35, 21, 7, 1}, {1, 8, 28, 56, 70, 56, 28, 8, 1}};
    if (k < 0 || k > d)
        return 0.0;
    double r = tp[k];
    for (int i = 0; i < d - k; i++)
        r *= s;
    return binom[d][k] * r;
}

_Static_assert(CM_FIT_MAX_M + 3 <= 8, "bernstein_pow's binomial table stops at degree 8");

void cm_fit_basis(int m, double t, double b[CM_FIT_MAX_M], double db[CM_FIT_MAX_M])
{
    for (int i = 0; i < CM_FIT_MAX_M; i++) {
        b[i] = 0.0;
        if (db)
            db[i] = 0.0;
    }
    if (m < 1 || m > CM_FIT_MAX_M)
        return;
    int d = m + 3;
    double tp[CM_FIT_MAX_M + 4], s = 1.0 - t;
    tp[0] = 1.0;
    for (int i = 1; i <= d; i++)
        tp[i] = tp[i - 1] * t;
    for (int i = 0; i < m; i++) {
        b[i] = bernstein_pow(d, i + 2, tp, s);
        if (db) /* (B^d_k)' = d (B^(d-1)_(k-1) - B^(d-1)_k) */
            db[i] = (double)d * (bernstein_pow(d - 1, i + 1, tp, s) - bernstein_pow(d - 1, i + 2, tp, s));
    }
}

void cm_fit_add(const cm_vec3 *c, int m, double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv)
{
    if (m < 1 || m > CM_FIT_MAX_M)
        return;
    double bu[CM_FIT_MAX_M], dbu[CM_FIT_MAX_M], bv[CM_FIT_MAX_M], dbv[CM_FIT_MAX_M];
    cm_fit_basis(m, u, bu, dbu);
    cm_fit_basis(m, v, bv, dbv);
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++) {
            cm_vec3 cij = c[i * m + j];
            *S = cm_axpy(*S, bu[i] * bv[j], cij);
            if (Su)
                *Su = cm_axpy(*Su, dbu[i] * bv[j], cij);
            if (Sv)
                *Sv = cm_axpy(*Sv, bu[i] * dbv[j], cij);
        }
}

double cm_fit_dequantise(int32_t qi, double grid, int exp)
{
    double step = grid; /* doubled exp times: exact, and no libm call in the decoder */
    for (int i = 0; i < exp && i < CM_FIT_MAX_EXP; i++)
        step *= 2.0;
    return (double)qi * step;
}

/* Greville abscissa of a cubic's control point i: the mean of knots i+1..i+3 */
static double greville3(const double *K, int i)
{
    return (K[i + 1] + K[i + 2] + K[i + 3]) / 3.0;
}

void cm_fit_net_add(cm_vec3 *ctrl, int nu, int nv, const double *U, const double *V, const cm_vec3 *c, int m)
{
    for (int i = 2; i <= nu - 3; i++)
        for (int j = 2; j <= nv - 3; j++) {
            cm_vec3 D = cm_v3(0.0, 0.0, 0.0);
            cm_fit_add(c, m, greville3(U, i), greville3(V, j), &D, NULL, NULL);
            ctrl[i * nv + j] = cm_add(ctrl[i * nv + j], D);
        }
}
