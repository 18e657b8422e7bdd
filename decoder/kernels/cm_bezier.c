/* cm_bezier.c - Bézier tools (spec K4). */
#include "cm/cm_bezier.h"

#include <stddef.h>

#include "cm/cm_limits_info.h"

/* knots of a single cubic Bézier span; shared by every cm_cubic_as_curve view */
static const double cubic_knots[8] = {0, 0, 0, 0, 1, 1, 1, 1};

void cm_bernstein3(double t, double B[4], double dB[4])
{
    double s = 1.0 - t;
    if (B) {
        B[0] = s * s * s;
        B[1] = 3.0 * t * s * s;
        B[2] = 3.0 * t * t * s;
        B[3] = t * t * t;
    }
    if (dB) {
        dB[0] = -3.0 * s * s;
        dB[1] = 3.0 * s * s - 6.0 * t * s;
        dB[2] = 6.0 * t * s - 3.0 * t * t;
        dB[3] = 3.0 * t * t;
    }
}

void cm_cubic_eval(const cm_cubic *c, double t, cm_vec3 d[3])
{
    double B[4], dB[4];
    cm_bernstein3(t, B, dB);
    double s = 1.0 - t;
    /* second derivative: 6 * sum of second differences with linear Bernstein weights */
    double d2[3] = {6.0 * s, 6.0 * t, 0.0};
    cm_vec3 a0 = cm_add(cm_sub(c->c[2], cm_scale(c->c[1], 2.0)), c->c[0]);
    cm_vec3 a1 = cm_add(cm_sub(c->c[3], cm_scale(c->c[2], 2.0)), c->c[1]);
    cm_vec3 p = cm_v3(0, 0, 0), dp = cm_v3(0, 0, 0);
    for (int i = 0; i < 4; i++) {
        p = cm_axpy(p, B[i], c->c[i]);
        dp = cm_axpy(dp, dB[i], c->c[i]);
    }
    d[0] = p;
    d[1] = dp;
    d[2] = cm_add(cm_scale(a0, d2[0]), cm_scale(a1, d2[1]));
}

void cm_cubic_split(const cm_cubic *c, double t, cm_cubic *a, cm_cubic *b)
{
    cm_vec3 p01 = cm_lerp(c->c[0], c->c[1], t);
    cm_vec3 p12 = cm_lerp(c->c[1], c->c[2], t);
    cm_vec3 p23 = cm_lerp(c->c[2], c->c[3], t);
    cm_vec3 p012 = cm_lerp(p01, p12, t);
    cm_vec3 p123 = cm_lerp(p12, p23, t);
    cm_vec3 m = cm_lerp(p012, p123, t);
    cm_cubic l = {{c->c[0], p01, p012, m}};
    cm_cubic r = {{m, p123, p23, c->c[3]}};
    *a = l;
    *b = r;
}

cm_cubic cm_cubic_reverse(const cm_cubic *c)
{
    cm_cubic r = {{c->c[3], c->c[2], c->c[1], c->c[0]}};
    return r;
}

cm_cubic cm_cubic_from_line(cm_vec3 P, cm_vec3 Q)
{
    cm_vec3 d = cm_sub(Q, P);
    cm_cubic r = {{P, cm_axpy(P, 1.0 / 3.0, d), cm_axpy(P, 2.0 / 3.0, d), Q}};
    return r;
}

cm_cubic cm_cubic_from_quad(cm_vec3 Q0, cm_vec3 Q1, cm_vec3 Q2)
{
    cm_cubic r = {{Q0, cm_axpy(Q0, 2.0 / 3.0, cm_sub(Q1, Q0)), cm_axpy(Q2, 2.0 / 3.0, cm_sub(Q1, Q2)), Q2}};
    return r;
}

cm_curve cm_cubic_as_curve(const cm_cubic *c)
{
    cm_curve v;
    v.p = 3;
    v.n_ctrl = 4;
    v.knots = cubic_knots;
    v.ctrl = c->c;
    v.w = NULL;
    return v;
}

cm_err cm_bez_split(const cm_vec3 *P, int p, double t, cm_vec3 *left, cm_vec3 *right, cm_status *st)
{
    if (p > CM_MAX_DEGREE)
        return cm_fail_limit(st, CM_LIMIT_MAX_DEGREE, (uint64_t)p, CM_MAX_DEGREE, __func__);
    if (p < 1)
        return cm_fail(st, CM_E_RANGE, __func__);
    cm_vec3 tmp[CM_MAX_ORDER];
    for (int i = 0; i <= p; i++)
        tmp[i] = P[i];
    left[0] = tmp[0];
    right[p] = tmp[p];
    for (int k = 1; k <= p; k++) {
        for (int i = 0; i <= p - k; i++)
            tmp[i] = cm_lerp(tmp[i], tmp[i + 1], t);
        left[k] = tmp[0];
        right[p - k] = tmp[p - k];
    }
    return CM_OK;
}

double cm_binomial(int n, int k)
{
    if (k < 0 || k > n)
        return 0.0;
    double r = 1.0;
    for (int i = 1; i <= k; i++)
        r = r * (double)(n - k + i) / (double)i;
    return r;
}

static cm_err elevate_args(int p, int t, cm_status *st, const char *where)
{
    if (p < 1 || t < 0)
        return cm_fail(st, CM_E_RANGE, where);
    if (p + t > CM_MAX_DEGREE)
        return cm_fail_limit(st, CM_LIMIT_MAX_DEGREE, (uint64_t)(p + t), CM_MAX_DEGREE, where);
    return CM_OK;
}

cm_err cm_bez_elevate_h(const cm_hpt *P, int p, int t, cm_hpt *Q, cm_status *st)
{
    cm_err e = elevate_args(p, t, st, __func__);
    if (e != CM_OK)
        return e;
    for (int i = 0; i <= p + t; i++) {
        int j0 = i - t > 0 ? i - t : 0;
        int j1 = i < p ? i : p;
        double denom = cm_binomial(p + t, i);
        cm_hpt acc = {0, 0, 0, 0};
        for (int j = j0; j <= j1; j++) {
            double c = cm_binomial(p, j) * cm_binomial(t, i - j) / denom;
            acc.x = acc.x + c * P[j].x;
            acc.y = acc.y + c * P[j].y;
            acc.z = acc.z + c * P[j].z;
            acc.w = acc.w + c * P[j].w;
        }
        Q[i] = acc;
    }
    Q[0] = P[0];
    Q[p + t] = P[p];
    return CM_OK;
}

cm_err cm_bez_elevate(const cm_vec3 *P, int p, int t, cm_vec3 *Q, cm_status *st)
{
    cm_err e = elevate_args(p, t, st, __func__);
    if (e != CM_OK)
        return e;
    cm_hpt H[CM_MAX_ORDER], E[CM_MAX_ORDER];
    for (int i = 0; i <= p; i++)
        H[i] = (cm_hpt){P[i].x, P[i].y, P[i].z, 1.0};
    if ((e = cm_bez_elevate_h(H, p, t, E, st)) != CM_OK)
        return e;
    for (int i = 0; i <= p + t; i++)
        Q[i] = cm_v3(E[i].x, E[i].y, E[i].z);
    return CM_OK;
}
