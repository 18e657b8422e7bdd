/* cm_cubic_convert.c - cubic edge conversion (spec K7). */
#include "cm/cm_cubic_convert.h"

#include <math.h>
#include <stddef.h>

#include "cm/cm_lsq.h"
#include "cm/cm_project.h"

/* Case 1 of K7: one polynomial span of degree <= 3 (weights absent or all equal). */
static int single_poly_span(const cm_curve *c)
{
    int p = c->p;
    if (p > 3 || c->n_ctrl != p + 1)
        return 0;
    for (int i = 1; i <= p; i++)
        if (c->knots[i] != c->knots[0] || c->knots[p + 1 + i] != c->knots[p + 1])
            return 0;
    if (c->w)
        for (int i = 1; i < c->n_ctrl; i++)
            if (c->w[i] != c->w[0])
                return 0;
    return 1;
}

static cm_cubic exact_cubic(const cm_curve *c, double t0, double t1)
{
    const cm_vec3 *P = c->ctrl;
    cm_cubic cu;
    if (c->p == 1)
        cu = cm_cubic_from_line(P[0], P[1]);
    else if (c->p == 2)
        cu = cm_cubic_from_quad(P[0], P[1], P[2]);
    else {
        cm_cubic t = {{P[0], P[1], P[2], P[3]}};
        cu = t;
    }
    double a = c->knots[c->p], b = c->knots[c->p + 1];
    if (t0 == a && t1 == b)
        return cu;
    /* the sub-range [t0,t1]: cut at s1, then the left part at s0/s1 */
    double s0 = (t0 - a) / (b - a), s1 = (t1 - a) / (b - a);
    cm_cubic left, right;
    if (s1 < 1.0) {
        cm_cubic_split(&cu, s1, &left, &right);
        cu = left;
    }
    if (s0 > 0.0) {
        cm_cubic_split(&cu, s0 / s1, &left, &right);
        cu = right;
    }
    return cu;
}

/* Unit tangent from the curve derivative, or from the first distinct sample when the derivative vanishes. */
static cm_vec3 end_tangent(cm_vec3 deriv, const cm_vec3 *Q, int from_end, double eps)
{
    int ok;
    cm_vec3 t = cm_unit_or(deriv, eps, cm_v3(0, 0, 0), &ok);
    if (ok)
        return t;
    for (int k = 1; k < CM_K7_SAMPLES; k++) {
        cm_vec3 d = from_end ? cm_sub(Q[CM_K7_SAMPLES - 1], Q[CM_K7_SAMPLES - 1 - k]) : cm_sub(Q[k], Q[0]);
        t = cm_unit_or(d, eps, cm_v3(0, 0, 0), &ok);
        if (ok)
            return t;
    }
    return t;
}

/* K7's measure of a cubic (K9): the largest distance of the samples Q from it */
static cm_err samples_dist(const cm_cubic *cu, const cm_vec3 Q[CM_K7_SAMPLES], double *delta, cm_status *st)
{
    cm_curve view = cm_cubic_as_curve(cu);
    double dmax = 0.0;
    for (int k = 0; k < CM_K7_SAMPLES; k++) {
        double dist;
        cm_err e = cm_curve_project(&view, 0.0, 1.0, Q[k], NULL, &dist, st);
        if (e != CM_OK)
            return e;
        if (dist > dmax)
            dmax = dist;
    }
    *delta = dmax;
    return CM_OK;
}

cm_err cm_cubic_convert(const cm_curve *c, double t0, double t1, cm_cubic *out, double *delta, int *exact,
                        cm_status *st)
{
    cm_err e;
    if (!(t0 < t1))
        return cm_fail(st, CM_E_ARG, __func__);
    if (single_poly_span(c)) {
        *out = exact_cubic(c, t0, t1);
        if (delta)
            *delta = 0.0;
        if (exact)
            *exact = 1;
        return CM_OK;
    }
    if (exact)
        *exact = 0;

    cm_vec3 Q[CM_K7_SAMPLES];
    double s[CM_K7_SAMPLES];
    cm_vec3 d0[2], d1[2];
    for (int k = 0; k < CM_K7_SAMPLES; k++) {
        cm_vec3 d[1];
        double t = t0 + (t1 - t0) * (double)k / (double)(CM_K7_SAMPLES - 1);
        if ((e = cm_curve_eval(c, t, 0, d, st)) != CM_OK)
            return e;
        Q[k] = d[0];
    }
    if ((e = cm_curve_eval(c, t0, 1, d0, st)) != CM_OK || (e = cm_curve_eval(c, t1, 1, d1, st)) != CM_OK)
        return e;
    /* chord-length parameters */
    double len = 0.0;
    s[0] = 0.0;
    for (int k = 1; k < CM_K7_SAMPLES; k++) {
        len += cm_dist(Q[k], Q[k - 1]);
        s[k] = len;
    }
    if (!(len > 0.0))
        return cm_fail(st, CM_E_DEGENERATE, __func__);
    for (int k = 1; k < CM_K7_SAMPLES; k++)
        s[k] /= len;
    s[CM_K7_SAMPLES - 1] = 1.0;

    double eps = 1e-12 * len;
    cm_vec3 C0 = Q[0], C3 = Q[CM_K7_SAMPLES - 1];
    cm_vec3 T0 = end_tangent(d0[1], Q, 0, eps * fabs(1.0 / (t1 - t0)));
    cm_vec3 T3 = end_tangent(d1[1], Q, 1, eps * fabs(1.0 / (t1 - t0)));
    double fallback = cm_dist(C3, C0) / 3.0;
    double alpha = fallback, beta = fallback;
    cm_cubic cu;

    for (int iter = 0; iter < CM_K7_ITERS; iter++) {
        /* 2x2 normal equations in the handle lengths alpha, beta */
        double M[4] = {0, 0, 0, 0}, r[2] = {0, 0};
        for (int k = 0; k < CM_K7_SAMPLES; k++) {
            double B[4];
            cm_bernstein3(s[k], B, NULL);
            cm_vec3 a = cm_scale(T0, B[1]);
            cm_vec3 b = cm_scale(T3, -B[2]);
            cm_vec3 ek = cm_sub(cm_sub(Q[k], cm_scale(C0, B[0] + B[1])), cm_scale(C3, B[2] + B[3]));
            M[0] += cm_dot(a, a);
            M[1] += cm_dot(a, b);
            M[3] += cm_dot(b, b);
            r[0] += cm_dot(a, ek);
            r[1] += cm_dot(b, ek);
        }
        M[2] = M[1];
        double trace = M[0] + M[3];
        double x[2];
        if (cm_solve2(M, r, 1e-14 * trace * trace, x, NULL) == CM_OK && x[0] > 0.0 && x[1] > 0.0) {
            alpha = x[0];
            beta = x[1];
        } else {
            alpha = beta = fallback;
        }
        cu.c[0] = C0;
        cu.c[1] = cm_axpy(C0, alpha, T0);
        cu.c[2] = cm_axpy(C3, -beta, T3);
        cu.c[3] = C3;
        if (iter == CM_K7_ITERS - 1)
            break;
        /* Hoschek parameter correction: 2 Newton steps on |B(s)-Q_k|^2 per interior sample */
        for (int k = 1; k < CM_K7_SAMPLES - 1; k++) {
            for (int n = 0; n < 2; n++) {
                cm_vec3 d[3];
                cm_cubic_eval(&cu, s[k], d);
                cm_vec3 diff = cm_sub(d[0], Q[k]);
                double f1 = cm_dot(diff, d[1]);
                double f2 = cm_dot(d[1], d[1]) + cm_dot(diff, d[2]);
                if (!(f2 > 0.0))
                    break;
                double sn = s[k] - f1 / f2;
                s[k] = sn < 0.0 ? 0.0 : (sn > 1.0 ? 1.0 : sn);
            }
        }
    }
    *out = cu;
    return delta ? samples_dist(&cu, Q, delta, st) : CM_OK;
}

/*
 * Format 4.14: the cubic of a one-span conic in closed form.  Its standard-form weight is
 * w = w1 / sqrt(w0 w2) and its middle point (P0 + 2 w P1 + P2) / (2 + 2 w); the cubic with the same
 * ends and end tangents whose middle point is that one has handles a (P1 - P0) and a (P1 - P2) with
 * a = 4 w / (3 (1 + w)) (a parabola, w = 1: its exact degree elevation; a circular arc of angle
 * theta: the classic 4/3 tan(theta/4) r).  K7's least squares with parameter correction cost about
 * 70 000 instructions an edge, a fifth of the terminal's decode of a model of many small GREGORY
 * faces bounded by arcs (tail_section_asm: 855 arcs); this is a few dozen.  The price: a 90 degree
 * arc's radial error 2.7e-4 R where K7's fit reaches 2.0e-4 R (spec T4 asks 2.5e-4 R of K7, which
 * files before 4.14 keep); the encoder still takes a side only within a quarter of the face's
 * tolerance, which over the 34 corpus models left every face's method as it was (and let 4 more
 * faces of ec_soapbox be GREGORY).
 */
int cm_cubic_from_conic(const cm_curve *c, cm_cubic *out)
{
    if (c->p != 2 || c->n_ctrl != 3 || !c->w)
        return 0;
    double w = c->w[1] / sqrt(c->w[0] * c->w[2]), a = 4.0 * w / (3.0 * (1.0 + w));
    if (!(a > 0.0 && a < 4.0 / 3.0)) /* a weight not positive, or not finite */
        return 0;
    const cm_vec3 *P = c->ctrl;
    out->c[0] = P[0];
    out->c[1] = cm_axpy(P[0], a, cm_sub(P[1], P[0]));
    out->c[2] = cm_axpy(P[2], a, cm_sub(P[1], P[2]));
    out->c[3] = P[2];
    return 1;
}

cm_err cm_edge_cubic(const cm_curve *c, int conic, cm_cubic *out, cm_status *st)
{
    /* (an edge's curve runs over [0,1]: the conic's one span is all of it) */
    if (!conic || !cm_cubic_from_conic(c, out) || c->knots[2] != 0.0 || c->knots[3] != 1.0)
        return cm_cubic_convert(c, 0.0, 1.0, out, NULL, NULL, st);
    return CM_OK;
}

cm_err cm_edge_cubic_delta(const cm_curve *c, const cm_cubic *cu, double *delta, cm_status *st)
{
    cm_vec3 Q[CM_K7_SAMPLES];
    for (int k = 0; k < CM_K7_SAMPLES; k++) {
        cm_err e = cm_curve_eval(c, (double)k / (double)(CM_K7_SAMPLES - 1), 0, &Q[k], st);
        if (e != CM_OK)
            return e;
    }
    return samples_dist(cu, Q, delta, st);
}
