/*
 * cm_param.h - following a face's boundary through its surface's
 * parameter space: the (u,v) polygon of each loop, shared by the
 * workstation's import (trimmed faces) and the terminal's tessellation of
 * kept surfaces, so both see the same domain.
 *
 * A loop is a closed sequence of 3D points on (or within a gap of) the
 * surface.  Each point is projected by continuation from the previous one
 * (Levenberg-Marquardt from the last (u,v)), so a loop crossing the seam of
 * a closed surface stays continuous: the parameter may leave [u0,u1] by a
 * period ("unwrapped"), the surface is evaluated at the wrapped value.
 * Poles (a collapsed side: a sphere's pole, a cone's apex) leave a point's
 * free parameter undefined; a run of pole points is redrawn along the pole
 * line from the free parameter before it to the one after it (the shorter
 * way round), which is the polygon the face really has in (u,v), and the
 * pole point appears twice (arrival and departure).  A loop that winds
 * around a closed direction (a band of a full cylinder) is reported with
 * its winding so the caller can close it with cm_join_winding().
 *
 * Contract: no allocation, recursion or I/O; bounded iterations; only
 * + - * / sqrt (bit-identical everywhere); workspace from the caller.
 */
#ifndef CM_PARAM_H
#define CM_PARAM_H

#include "cm/cm_bspline.h"
#include "cm/cm_error.h"
#include "cm/cm_vec.h"
#include "cm_limits.h"

typedef struct cm_psurf {
    cm_surf s;
    double u0, u1, v0, v1;   /* domain */
    int closed_u, closed_v;  /* the surface meets itself across u0/u1 (v0/v1) */
} cm_psurf;

/** Domain and closedness of s: closed when S(u0,v) == S(u1,v) within tol at 9 values of v. */
CM_NODISCARD cm_err cm_psurf_init(cm_psurf *ps, const cm_surf *s, double tol, cm_status *st);

/** S, S_u, S_v at (u,v): periodic parameters wrapped, others clamped. */
CM_NODISCARD cm_err cm_psurf_eval(const cm_psurf *ps, double u, double v, cm_vec3 d[3], cm_status *st);

/**
 * Closest point by Levenberg-Marquardt from (u,v) (cm_lm.h: mu from 1e-3, x0.1 on a step that does not
 * raise the distance, down to 1e-12, x10 on any other, up to 1e8; at most 60 steps; stop when
 * |du|+|dv| < 1e-14 of the domain).  Periodic parameters stay unwrapped, the others are clamped.
 */
CM_NODISCARD cm_err cm_psurf_project_from(const cm_psurf *ps, cm_vec3 P, double *u, double *v, double *dist,
                                          cm_status *st);

/** Best of an n x n grid (2 <= n <= 64), then cm_psurf_project_from. */
CM_NODISCARD cm_err cm_psurf_project_grid(const cm_psurf *ps, cm_vec3 P, int n, double *u, double *v, double *dist,
                                          cm_status *st);

/** The n x n grid of cm_psurf_project_grid (2 <= n <= 64): g[i * n + j] = S(u_i, v_j). */
CM_NODISCARD cm_err cm_psurf_grid_points(const cm_psurf *ps, int n, cm_vec3 *g, cm_status *st);

/** cm_psurf_project_grid over a grid cm_psurf_grid_points made: the same answer, without evaluating
 *  the grid again (a caller projecting many points onto one surface keeps it). */
CM_NODISCARD cm_err cm_psurf_project_grid_pts(const cm_psurf *ps, cm_vec3 P, int n, const cm_vec3 *g, double *u,
                                              double *v, double *dist, cm_status *st);

/** Workspace of cm_loop_uv. */
/* cm_loop_uv's global searches use two grids, COARSE^2 and FINE^2 points; with
   CM_PARAM_GRID_CACHE the surface's points on them are evaluated once per loop instead of once per
   search (a hostile or garbled loop may need 32 + n/8 searches of 1681 evaluations each) */
#ifndef CM_PARAM_GRID_CACHE
#  define CM_PARAM_GRID_CACHE 1
#endif
#define CM_PARAM_GRID_COARSE 17 /* the first point's search, then the fine grid if it lands badly */
#define CM_PARAM_GRID_FINE 41
#define CM_PARAM_GRID_POINTS                                                                                \
    (CM_PARAM_GRID_CACHE ? CM_PARAM_GRID_COARSE * CM_PARAM_GRID_COARSE + CM_PARAM_GRID_FINE * CM_PARAM_GRID_FINE : 1)

typedef struct cm_param_ws {
    cm_vec2 uv[CM_MAX_TESS_POINTS + 1];
    unsigned char pole[CM_MAX_TESS_POINTS + 1];
    cm_vec3 grid[CM_PARAM_GRID_POINTS];  /* the coarse grid's points, then the fine grid's */
    unsigned char grid_have[2];          /* which of the two hold this loop's surface */
    int net_start;                       /* format 4.8 (set by the caller): a loop's first point starts
                                            from the surface's control net, the grids only where that
                                            lands badly, and the continuation's searches stop at a step
                                            of 1e-10 of the domain instead of 1e-14 */
} cm_param_ws;

/**
 * The (u,v) polygon of one loop of n points.
 * @param accept   a continuation step landing farther than this from its point is retried by a global search
 * @param[out] uv  the polygon (pole points doubled: at most 2n points); cap its capacity
 * @param[out] src for each polygon point, the index of the loop point it came from
 * @param[out] wind_u, wind_v  net turns around closed directions (0 for an ordinary loop)
 * @param[in,out] max_gap      raised to the largest point-to-surface distance seen
 * @return CM_E_LIMIT if n > CM_MAX_TESS_POINTS, CM_E_NOSPACE if cap is too small
 */
CM_NODISCARD cm_err cm_loop_uv(const cm_psurf *ps, const cm_vec3 *pts, int n, double accept, cm_vec2 *uv, int *src,
                               int cap, int *nout, int *wind_u, int *wind_v, double *max_gap, cm_param_ws *ws,
                               cm_status *st);

/**
 * One polygon for a face bounded by loops winding around a closed surface
 * direction: `lo` winds the lower band edge, `hi` (may be NULL) the upper;
 * with only `lo`, the band is closed by the domain edge at `cap_coord`.
 * Works in coordinates where x is the winding direction (swap u,v before
 * and after for a v-winding face).  The lower loop must run +x, the upper
 * -x.  Output: lo, the seam up, hi (unwrapped to descend by one period),
 * the seam down: a simple polygon (counter-clockwise).
 * Layout of the output: lo[0..nlo), lo[0] + one period, then either hi[(hi_start + i) % nhi]
 * for i = 0..nhi (unwrapped) or two cap points.
 * @param[out] hi_start  where the upper loop was entered (may be NULL)
 * @return CM_E_NOSPACE if cap < nlo + nhi + 3
 */
CM_NODISCARD cm_err cm_join_winding(const cm_vec2 *lo, int nlo, const cm_vec2 *hi, int nhi, double period,
                                    double cap_coord, cm_vec2 *out, int cap, int *nout, int *hi_start, cm_status *st);

/**
 * Which side of a lone loop winding round a closed surface the face lies on (spec §1: the material
 * on the left of the loop, seen with the face normal towards the viewer): 1 the side of the high
 * parameter (the band between the loop and the domain's v1, or u1), 0 the low side.  `dir` is the
 * loop's winding (+1 running +u for along_u, +v otherwise), `flip` the face's (normal = -(Su x Sv)).
 * Walking +u, Su x Sv on the left is +v; walking +v it is -u; a flipped face mirrors both.
 */
static inline int cm_winding_cap_high(int dir, int flip, int along_u)
{
    return (dir > 0) ^ (flip != 0) ^ (along_u == 0);
}

/**
 * Each loop is projected on its own, from wherever its first point's search lands, so on a closed
 * surface a hole can come out a period away from the outer polygon (a cylinder face running
 * [-pi, 0] with its hole found at [3.7, 4.7]): outside it, the hole would be lost.  Move every
 * loop after the first (uv[loop_start[l]] .. uv[loop_start[l + 1]]) by whole periods of the
 * closed directions so its mean lies nearest the middle of the first loop's box.
 */
void cm_loops_align(const cm_psurf *ps, cm_vec2 *uv, const int *loop_start, int nloops);

#endif /* CM_PARAM_H */
