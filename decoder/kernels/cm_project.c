/* cm_project.c - patch evaluation and point projection (spec K9). */
#include "cm/cm_project.h"

#include <stddef.h>

#include "cm/cm_lsq.h"


#define CURVE_SAMPLES 33 /* K9: initial guess from 33 uniform samples */
#define CURVE_ITERS 30
#define GRID 17          /* K9: 17x17 initial grid */
#define LM_ITERS 50
#define STEP_REL 1e-12   /* stop when a step is below 1e-12 of the domain */

cm_patch cm_patch_of_surf(const cm_surf *s)
{
    cm_patch p;
    p.kind = CM_PATCH_NURBS;
    p.nurbs = s;
    p.greg = NULL;
    p.u0 = s->U[s->p];
    p.u1 = s->U[s->nu];
    p.v0 = s->V[s->q];
    p.v1 = s->V[s->nv];
    return p;
}

cm_patch cm_patch_of_gregory(const cm_gregory *g)
{
    cm_patch p;
    p.kind = CM_PATCH_GREGORY;
    p.nurbs = NULL;
    p.greg = g;
    p.u0 = 0.0;
    p.u1 = 1.0;
    p.v0 = 0.0;
    p.v1 = 1.0;
    return p;
}

static double clampd(double x, double lo, double hi)
{
    if (!(x > lo))
        return lo;
    return x > hi ? hi : x;
}

cm_err cm_patch_eval(const cm_patch *s, double u, double v, cm_vec3 d[3], cm_status *st)
{
    u = clampd(u, s->u0, s->u1);
    v = clampd(v, s->v0, s->v1);
    switch (s->kind) {
    case CM_PATCH_NURBS: {
        cm_vec3 S[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
        cm_err e = cm_surf_eval(s->nurbs, u, v, 1, S, st);
        if (e != CM_OK)
            return e;
        d[0] = S[0][0];
        d[1] = S[1][0];
        d[2] = S[0][1];
        return CM_OK;
    }
    case CM_PATCH_GREGORY:
        cm_greg_eval(s->greg, u, v, &d[0], &d[1], &d[2]);
        return CM_OK;
    }
    return cm_fail(st, CM_E_ARG, __func__);
}

cm_err cm_curve_project(const cm_curve *c, double t0, double t1, cm_vec3 P, double *t_out, double *dist_out,
                        cm_status *st)
{
    cm_vec3 d[3];
    cm_err e;
    double best_t = t0, best_f = 0.0;
    for (int i = 0; i < CURVE_SAMPLES; i++) {
        double ti = t0 + (t1 - t0) * (double)i / (double)(CURVE_SAMPLES - 1);
        if ((e = cm_curve_eval(c, ti, 0, d, st)) != CM_OK)
            return e;
        double f = cm_norm2(cm_sub(d[0], P));
        if (i == 0 || f < best_f) {
            best_f = f;
            best_t = ti;
        }
    }
    /* Newton iterates are taken as long as they do not increase the distance
     * by more than rounding: near the minimum |C-P|^2 is flat to O(dt^2), so
     * a strict "decreases" test would stop at the first plateau of rounding
     * noise and leave t off by ~1e-9 of the interval. */
    double t = best_t;
    double tol = STEP_REL * fabs(t1 - t0);
    for (int it = 0; it < CURVE_ITERS; it++) {
        if ((e = cm_curve_eval(c, t, 2, d, st)) != CM_OK)
            return e;
        cm_vec3 r = cm_sub(d[0], P);
        double f = cm_norm2(r);
        if (f <= best_f * (1.0 + 1e-12)) {
            best_f = f;
            best_t = t;
        }
        double g = cm_dot(r, d[1]);
        double gp = cm_dot(d[1], d[1]) + cm_dot(r, d[2]);
        if (!(gp > 0.0))
            break; /* not a minimum direction: keep the best so far */
        double tn = clampd(t - g / gp, t0, t1);
        double step = fabs(tn - t);
        t = tn;
        if (step < tol) {
            if ((e = cm_curve_eval(c, t, 0, d, st)) != CM_OK)
                return e;
            f = cm_norm2(cm_sub(d[0], P));
            if (f <= best_f * (1.0 + 1e-12)) {
                best_f = f;
                best_t = t;
            }
            break;
        }
    }
    if (t_out)
        *t_out = best_t;
    if (dist_out)
        *dist_out = sqrt(best_f);
    return CM_OK;
}

cm_err cm_patch_project(const cm_patch *s, cm_vec3 P, double *u_out, double *v_out, double *dist_out,
                        cm_status *st)
{
    cm_vec3 d[3];
    cm_err e;
    double du = s->u1 - s->u0, dv = s->v1 - s->v0;
    double u = s->u0, v = s->v0, f = 0.0;
    for (int i = 0; i < GRID; i++) {
        for (int j = 0; j < GRID; j++) {
            double ui = s->u0 + du * (double)i / (double)(GRID - 1);
            double vj = s->v0 + dv * (double)j / (double)(GRID - 1);
            if ((e = cm_patch_eval(s, ui, vj, d, st)) != CM_OK)
                return e;
            double fi = cm_norm2(cm_sub(d[0], P));
            if ((i == 0 && j == 0) || fi < f) {
                f = fi;
                u = ui;
                v = vj;
            }
        }
    }
    if ((e = cm_patch_eval(s, u, v, d, st)) != CM_OK)
        return e;
    double mu = 1e-3;
    for (int it = 0; it < LM_ITERS; it++) {
        cm_vec3 r = cm_sub(d[0], P);
        double J[4] = {cm_dot(d[1], d[1]), cm_dot(d[1], d[2]), 0.0, cm_dot(d[2], d[2])};
        J[2] = J[1];
        double g[2] = {-cm_dot(d[1], r), -cm_dot(d[2], r)};
        double tr = J[0] + J[3];
        if (!(tr > 0.0))
            break; /* both partials vanish: no descent direction */
        double A[4] = {J[0] + mu * tr, J[1], J[2], J[3] + mu * tr};
        double x[2];
        if (cm_solve2(A, g, 0.0, x, NULL) != CM_OK)
            break;
        double un = clampd(u + x[0], s->u0, s->u1);
        double vn = clampd(v + x[1], s->v0, s->v1);
        double step = fabs(un - u) / du + fabs(vn - v) / dv;
        cm_vec3 dn[3];
        if ((e = cm_patch_eval(s, un, vn, dn, st)) != CM_OK)
            return e;
        double fn = cm_norm2(cm_sub(dn[0], P));
        if (fn < f) {
            u = un;
            v = vn;
            f = fn;
            d[0] = dn[0];
            d[1] = dn[1];
            d[2] = dn[2];
            mu = mu / 10.0 > 1e-12 ? mu / 10.0 : 1e-12;
        } else {
            mu *= 10.0;
            if (mu > 1e6)
                break;
        }
        if (step < STEP_REL)
            break;
    }
    if (u_out)
        *u_out = u;
    if (v_out)
        *v_out = v;
    if (dist_out)
        *dist_out = sqrt(f);
    return CM_OK;
}
