/* cm_lm.c - Levenberg-Marquardt on |S(u,v) - P|^2 (see cm_lm.h). */
#include "cm/cm_lm.h"

#include <stddef.h>

#include "cm/cm_lsq.h"

double cm_lm_bound_apply(double x, cm_lm_bound b, double lo, double hi)
{
    switch (b) {
    case CM_LM_CLAMP:
        return x < lo ? lo : (x > hi ? hi : x);
    case CM_LM_CLAMP_LOW:
        if (!(x > lo))
            return lo;
        return x > hi ? hi : x;
    case CM_LM_FREE:
        break;
    }
    return x;
}

void cm_lm2_start(cm_lm2 *lm, const cm_lm2_opts *opts, const cm_lm2_box *box, cm_vec3 P, double u, double v,
                  const cm_vec3 d[3])
{
    lm->opts = opts;
    lm->box = box;
    lm->P = P;
    lm->u = u;
    lm->v = v;
    lm->d[0] = d[0];
    lm->d[1] = d[1];
    lm->d[2] = d[2];
    lm->f = cm_norm2(cm_sub(d[0], P));
    lm->un = u;
    lm->vn = v;
    lm->mu = opts->mu0;
    lm->step = 0.0;
    lm->steps = 0;
    lm->done = 0;
}

int cm_lm2_next(cm_lm2 *lm)
{
    const cm_lm2_box *b = lm->box;
    if (lm->done || lm->steps >= lm->opts->max_steps)
        return 0;
    const cm_vec3 *d = lm->d;
    cm_vec3 r = cm_sub(d[0], lm->P);
    double J[4] = {cm_dot(d[1], d[1]), cm_dot(d[1], d[2]), 0.0, cm_dot(d[2], d[2])};
    J[2] = J[1];
    double g[2] = {-cm_dot(d[1], r), -cm_dot(d[2], r)};
    double tr = J[0] + J[3];
    double A[4] = {J[0] + lm->mu * tr, J[1], J[2], J[3] + lm->mu * tr}, x[2];
    /* both partials vanish (no descent direction), or the damped system is singular */
    if (!(tr > 0.0) || cm_solve2(A, g, 0.0, x, NULL) != CM_OK) {
        lm->done = 1;
        return 0;
    }
    lm->un = cm_lm_bound_apply(lm->u + x[0], b->bound_u, b->u0, b->u1);
    lm->vn = cm_lm_bound_apply(lm->v + x[1], b->bound_v, b->v0, b->v1);
    lm->step = fabs(lm->un - lm->u) / (b->u1 - b->u0) + fabs(lm->vn - lm->v) / (b->v1 - b->v0);
    return 1;
}

void cm_lm2_take(cm_lm2 *lm, const cm_vec3 d[3])
{
    const cm_lm2_opts *o = lm->opts;
    double fn = cm_norm2(cm_sub(d[0], lm->P));
    if (o->accept_equal ? fn <= lm->f : fn < lm->f) {
        lm->u = lm->un;
        lm->v = lm->vn;
        lm->f = fn;
        lm->d[0] = d[0];
        lm->d[1] = d[1];
        lm->d[2] = d[2];
        lm->mu = lm->mu / o->mu_factor > o->mu_min ? lm->mu / o->mu_factor : o->mu_min;
    } else {
        lm->mu *= o->mu_factor;
        if (lm->mu > o->mu_max)
            lm->done = 1;
    }
    if (lm->step < o->step_min)
        lm->done = 1;
    lm->steps++;
}
