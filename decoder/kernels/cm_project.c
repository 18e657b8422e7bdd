/* cm_project.c - patch evaluation and point projection (spec K9). */
#include "cm/cm_project.h"

#include <stddef.h>

#include "cm/cm_lm.h"
#include "cm/cm_patchfit.h"

#define CURVE_SAMPLES 33 /* K9: initial guess from 33 uniform samples */
#define CURVE_ITERS 30
#define GRID 17          /* K9: 17x17 initial grid */
#define STEP_REL 1e-12   /* stop when a step is below 1e-12 of the domain */

/* K9's Levenberg-Marquardt schedule (cm_lm.h); cm_psurf_project_from's differs in accept_equal,
   mu_max, step_min and max_steps */
static const cm_lm2_opts patch_lm = {
    .max_steps = 50,
    .mu0 = 1e-3,
    .mu_factor = 10.0,
    .mu_min = 1e-12,
    .mu_max = 1e6,
    .step_min = STEP_REL,
    .accept_equal = 0,
};

cm_patch cm_patch_of_surf(const cm_surf *s)
{
    cm_patch p;
    p.kind = CM_PATCH_NURBS;
    p.nurbs = s;
    p.greg = NULL;
    p.egreg = NULL;
    p.corr = NULL;
    p.fit = 0;
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
    p.egreg = NULL;
    p.corr = NULL;
    p.fit = 0;
    p.u0 = 0.0;
    p.u1 = 1.0;
    p.v0 = 0.0;
    p.v1 = 1.0;
    return p;
}

cm_patch cm_patch_of_egreg(const cm_egreg *g)
{
    cm_patch p = cm_patch_of_gregory(NULL);
    p.kind = CM_PATCH_EGREG;
    p.egreg = g;
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
        cm_fit_add(s->corr, s->fit, u, v, &d[0], &d[1], &d[2]);
        return CM_OK;
    case CM_PATCH_EGREG: {
        cm_err e = cm_egreg_eval(s->egreg, u, v, &d[0], &d[1], &d[2], st);
        if (e == CM_OK)
            cm_fit_add(s->corr, s->fit, u, v, &d[0], &d[1], &d[2]);
        return e;
    }
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
    cm_lm2_box box = {s->u0, s->u1, s->v0, s->v1, CM_LM_CLAMP_LOW, CM_LM_CLAMP_LOW};
    cm_lm2 lm;
    cm_lm2_start(&lm, &patch_lm, &box, P, u, v, d);
    while (cm_lm2_next(&lm)) {
        if ((e = cm_patch_eval(s, lm.un, lm.vn, d, st)) != CM_OK)
            return e;
        cm_lm2_take(&lm, d);
    }
    if (u_out)
        *u_out = lm.u;
    if (v_out)
        *v_out = lm.v;
    if (dist_out)
        *dist_out = sqrt(lm.f);
    return CM_OK;
}
