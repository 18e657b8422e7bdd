/*
 * hproject.h - point projection onto a host surface with continuation and
 * periodic parameters, for following boundary curves through a surface's
 * parameter space (trimming loops, error grids).
 *
 * Unlike the decoder's K9 (cm_patch_project, which starts from a grid and
 * clamps to the rectangle), this starts from a given guess and, in a
 * direction where the surface closes on itself, lets the parameter run
 * past the seam (it evaluates at the wrapped value), so a loop crossing a
 * seam stays continuous.
 */
#ifndef HPROJECT_H
#define HPROJECT_H

#include "geom/hnurbs.h"

typedef struct hsurf_param {
    const hsurf *s;
    double u0, u1, v0, v1; /* domain */
    int closed_u, closed_v; /* 1: the parameter wraps with period u1-u0 (v1-v0) */
} hsurf_param;

/** Domain and closedness (tolerance `tol` in model units) of s. */
hsurf_param hsurf_param_of(const hsurf *s, double tol);

/** Point, S_u, S_v at (u,v), wrapping periodic parameters and clamping the others. */
CM_NODISCARD cm_err hsurf_param_eval(const hsurf_param *sp, double u, double v, cm_vec3 d[3], cm_status *st);

/**
 * Levenberg-Marquardt from (u,v) towards the closest point to P (at most
 * 60 steps).  Periodic parameters are not wrapped in the result (they stay
 * near the start), the others are clamped to the domain.
 */
CM_NODISCARD cm_err hsurf_project_from(const hsurf_param *sp, cm_vec3 P, double *u, double *v, double *dist,
                                       cm_status *st);

/** Global projection: best of an n x n grid (n >= 2), then hsurf_project_from. */
CM_NODISCARD cm_err hsurf_project_grid(const hsurf_param *sp, cm_vec3 P, int n, double *u, double *v, double *dist,
                                       cm_status *st);

#endif /* HPROJECT_H */
