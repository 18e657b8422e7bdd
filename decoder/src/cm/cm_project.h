/*
 * cm_project.h - point projection onto curves and surface patches
 * (spec K9), and the patch evaluator shared by every surface kind.
 *
 * A cm_patch is a view of one parametric patch (a NURBS surface or a
 * Gregory patch) with the parameter rectangle to search.  Composite
 * surfaces (several patches) are projected patch by patch by the caller,
 * keeping the minimum distance.
 */
#ifndef CM_PROJECT_H
#define CM_PROJECT_H

#include "cm/cm_bspline.h"
#include "cm/cm_egreg.h"
#include "cm/cm_error.h"
#include "cm/cm_gregory.h"
#include "cm/cm_vec.h"

typedef enum cm_patch_kind {
    CM_PATCH_NURBS = 0,  /* cm_surf */
    CM_PATCH_GREGORY = 1, /* cm_gregory on [0,1]^2 */
    CM_PATCH_EGREG = 2    /* cm_egreg (exact boundaries) on [0,1]^2 */
} cm_patch_kind;

typedef struct cm_patch {
    cm_patch_kind kind;
    const cm_surf *nurbs;     /* kind == CM_PATCH_NURBS */
    const cm_gregory *greg;   /* kind == CM_PATCH_GREGORY */
    const cm_egreg *egreg;    /* kind == CM_PATCH_EGREG */
    double u0, u1, v0, v1;    /* parameter rectangle */
    const cm_vec3 *corr;      /* GREGORY and EGREG: an interior correction added (cm_patchfit.h) ... */
    int fit;                  /* ... of fit x fit coefficients (0: none) */
} cm_patch;

/** View of a NURBS surface over its whole domain. */
cm_patch cm_patch_of_surf(const cm_surf *s);

/** View of a Gregory patch over [0,1]^2. */
cm_patch cm_patch_of_gregory(const cm_gregory *g);

/** View of an exact-boundary Gregory patch over [0,1]^2. */
cm_patch cm_patch_of_egreg(const cm_egreg *g);

/**
 * Point and first partials of a patch at (u,v) (clamped to the rectangle).
 * @param[out] d  d[0] = S, d[1] = S_u, d[2] = S_v
 */
CM_NODISCARD cm_err cm_patch_eval(const cm_patch *s, double u, double v, cm_vec3 d[3], cm_status *st);

/**
 * K9 curve projection: closest point of c on [t0,t1] to P.  Start from the
 * best of 33 uniform samples, then at most 30 Newton steps on
 * f(t) = (C(t)-P).C'(t) with t clamped; stops when a step moves t by less
 * than 1e-12 of the interval.  The best point seen is returned, so the
 * result is never worse than the initial sample.
 * @param[out] t, dist  parameter and distance |C(t)-P| (either may be NULL)
 */
CM_NODISCARD cm_err cm_curve_project(const cm_curve *c, double t0, double t1, cm_vec3 P, double *t, double *dist,
                                     cm_status *st);

/**
 * K9 surface projection: best point of a 17x17 parameter grid, then
 * Levenberg-Marquardt on |S(u,v)-P|^2 (cm_lm.h: mu from 1e-3, x0.1 on a
 * step that lowers the distance, down to 1e-12, x10 on any other, up to
 * 1e6; at most 50 steps; stop when |du|+|dv| < 1e-12 of the rectangle;
 * proposals clamped to it).  Plain Newton fails at
 * collapsed patch corners, LM does not (spec K9).
 * @param[out] u, v, dist  parameters and distance (any may be NULL)
 */
CM_NODISCARD cm_err cm_patch_project(const cm_patch *s, cm_vec3 P, double *u, double *v, double *dist, cm_status *st);

#endif /* CM_PROJECT_H */
