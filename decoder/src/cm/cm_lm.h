/*
 * cm_lm.h - the Levenberg-Marquardt (damped Gauss-Newton) driver of the
 * closest-point searches on a surface: minimise f(u,v) = |S(u,v) - P|^2
 * over the two parameters.  Used by cm_psurf_project_from (cm_param.c) and
 * cm_patch_project (cm_project.c); what differs between them is a
 * parameter here (cm_lm2_opts, cm_lm2_box), nothing else.
 *
 * The driver does not evaluate the surface: it proposes a point, the caller
 * evaluates S, S_u, S_v there and hands them back (no callback: an indirect
 * call would hide its stack from check-stack; evaluation errors stay with
 * the caller):
 *
 *     cm_lm2 lm;
 *     cm_lm2_start(&lm, &opts, &box, P, u, v, d);     d: S, S_u, S_v at (u,v)
 *     while (cm_lm2_next(&lm)) {
 *         if ((e = eval(lm.un, lm.vn, d)) != CM_OK)
 *             return e;
 *         cm_lm2_take(&lm, d);
 *     }
 *     the result: lm.u, lm.v and lm.f (the squared distance)
 *
 * One step: with r = S - P and the normal matrix J = [S_u.S_u S_u.S_v;
 * S_u.S_v S_v.S_v], solve (J + mu tr(J) I) x = -(S_u.r, S_v.r) by Cramer's
 * rule, bound (u,v) + x to the box, evaluate there.  A step that lowers f
 * (or leaves it equal, with accept_equal) is taken and mu shrinks by
 * mu_factor down to mu_min; any other raises mu by mu_factor, and past
 * mu_max the search ends.  It also ends after max_steps proposals, after a
 * step shorter than step_min (|du| and |dv| relative to the box, taken or
 * not), or when J has no descent direction (tr J == 0, or singular).  The
 * point returned is never worse than the start.
 *
 * Contract: no allocation, recursion or I/O; bounded iterations; a fixed
 * sequence of + - * / (bit-identical everywhere).
 */
#ifndef CM_LM_H
#define CM_LM_H

#include "cm/cm_vec.h"

/** How a proposed parameter is kept in its interval [lo, hi]. */
typedef enum cm_lm_bound {
    CM_LM_FREE = 0,     /* not at all (a periodic parameter, left unwrapped) */
    CM_LM_CLAMP = 1,    /* x < lo ? lo : x > hi ? hi : x (a NaN stays NaN) */
    CM_LM_CLAMP_LOW = 2 /* !(x > lo) ? lo : x > hi ? hi : x (a NaN, and lo of either sign, become lo) */
} cm_lm_bound;

/** The damping schedule and the stopping rules. */
typedef struct cm_lm2_opts {
    int max_steps;    /* proposals evaluated, at most */
    double mu0;       /* damping at the start, relative to tr J */
    double mu_factor; /* mu / mu_factor after a step taken, mu * mu_factor after one refused */
    double mu_min;    /* the floor of mu */
    double mu_max;    /* a refusal raising mu above this ends the search */
    double step_min;  /* a step with |du|/(u1-u0) + |dv|/(v1-v0) below this ends the search */
    int accept_equal; /* 1: a step leaving f equal is taken (f_new <= f); 0: only a decrease */
} cm_lm2_opts;

/** The parameter rectangle: bounds of the proposals and the scale of the step measure. */
typedef struct cm_lm2_box {
    double u0, u1, v0, v1;
    cm_lm_bound bound_u, bound_v;
} cm_lm2_box;

/** State of one search; read u, v, f (the best point so far) and un, vn (the proposal). */
typedef struct cm_lm2 {
    const cm_lm2_opts *opts;
    const cm_lm2_box *box;
    cm_vec3 P;
    double u, v, f; /* best point and |S(u,v) - P|^2 */
    cm_vec3 d[3];   /* S, S_u, S_v at (u,v) */
    double un, vn;  /* the proposal to evaluate */
    double mu, step;
    int steps, done;
} cm_lm2;

/** Start at (u,v) (used as given, not bounded) where d holds S, S_u, S_v; opts and box must outlive lm. */
void cm_lm2_start(cm_lm2 *lm, const cm_lm2_opts *opts, const cm_lm2_box *box, cm_vec3 P, double u, double v,
                  const cm_vec3 d[3]);

/** The next proposal in lm->un, lm->vn: 1, or 0 when the search has ended. */
int cm_lm2_next(cm_lm2 *lm);

/** S, S_u, S_v at the proposal: the step is taken or refused, the damping adapted. */
void cm_lm2_take(cm_lm2 *lm, const cm_vec3 d[3]);

/** x kept in [lo, hi] as `b` says. */
double cm_lm_bound_apply(double x, cm_lm_bound b, double lo, double hi);

#endif /* CM_LM_H */
