/* cm_param.c - loops through a surface's parameter space (see cm_param.h). */
#include "cm/cm_param.h"

#include <stddef.h>
#include <string.h>

#include "cm/cm_limits_info.h"
#include "cm/cm_lm.h"

/* turns of a loop round a closed direction beyond which it is no loop of a face (a real one makes 0 or 1) */
#define CM_PARAM_MAX_WINDING 1e6

#define CM_PARAM_MAX_TIES 16   /* chords over a pole considered per loop */
#define CM_PARAM_POLE_PROBES 8 /* evaluations round a side to tell a pole */

/* the Levenberg-Marquardt schedule of cm_psurf_project_from (cm_lm.h); cm_patch_project's differs in
   accept_equal, mu_max, step_min and max_steps */
static const cm_lm2_opts project_lm = {
    .max_steps = 60,
    .mu0 = 1e-3,
    .mu_factor = 10.0,
    .mu_min = 1e-12,
    .mu_max = 1e8,
    .step_min = 1e-14,
    .accept_equal = 1,
};

static double wrap(double x, double a, double b, int periodic)
{
    if (periodic) {
        double p = b - a;
        x -= p * floor((x - a) / p);
        return x > b ? b : x; /* rounding at the seam */
    }
    return x < a ? a : (x > b ? b : x);
}

cm_err cm_psurf_eval(const cm_psurf *ps, double u, double v, cm_vec3 d[3], cm_status *st)
{
    cm_vec3 S[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
    cm_err e = cm_surf_eval(&ps->s, wrap(u, ps->u0, ps->u1, ps->closed_u), wrap(v, ps->v0, ps->v1, ps->closed_v), 1,
                            S, st);
    if (e != CM_OK)
        return e;
    d[0] = S[0][0];
    d[1] = S[1][0];
    d[2] = S[0][1];
    return CM_OK;
}

cm_err cm_psurf_init(cm_psurf *ps, const cm_surf *s, double tol, cm_status *st)
{
    ps->s = *s;
    ps->u0 = s->U[s->p];
    ps->u1 = s->U[s->nu];
    ps->v0 = s->V[s->q];
    ps->v1 = s->V[s->nv];
    ps->closed_u = ps->closed_v = 0;
    int cu = 1, cv = 1;
    for (int k = 0; k <= 8; k++) {
        cm_vec3 a[3], b[3];
        double t = (double)k / 8.0;
        cm_err e;
        if ((e = cm_psurf_eval(ps, ps->u0, ps->v0 + (ps->v1 - ps->v0) * t, a, st)) != CM_OK ||
            (e = cm_psurf_eval(ps, ps->u1, ps->v0 + (ps->v1 - ps->v0) * t, b, st)) != CM_OK)
            return e;
        if (cm_dist(a[0], b[0]) > tol)
            cu = 0;
        if ((e = cm_psurf_eval(ps, ps->u0 + (ps->u1 - ps->u0) * t, ps->v0, a, st)) != CM_OK ||
            (e = cm_psurf_eval(ps, ps->u0 + (ps->u1 - ps->u0) * t, ps->v1, b, st)) != CM_OK)
            return e;
        if (cm_dist(a[0], b[0]) > tol)
            cv = 0;
    }
    ps->closed_u = cu;
    ps->closed_v = cv;
    return CM_OK;
}

/* format 4.8's loop walks end at a step of this much of the domain, not project_lm's 1e-14.  A loop
   point lies up to a quarter of its face's tolerance off a kept surface (format 4.1), where the
   search converges only linearly: its last steps took about half of a walk's 13 evaluations a point
   (occt__hammer), for digits far below any tolerance */
#define WALK_STEP_MIN_48 1e-10

/* (dend, when not NULL: S, Su, Sv at the (u,v) returned, the search's last point taken: the bits of
   cm_psurf_eval there) */
static cm_err project_with(const cm_psurf *ps, cm_vec3 P, const cm_lm2_opts *opts, double *u, double *v,
                           double *dist, cm_vec3 dend[3], cm_status *st)
{
    /* periodic parameters stay unwrapped, the others are clamped (the start too) */
    cm_lm2_box box = {ps->u0, ps->u1, ps->v0, ps->v1, ps->closed_u ? CM_LM_FREE : CM_LM_CLAMP,
                      ps->closed_v ? CM_LM_FREE : CM_LM_CLAMP};
    double uu = cm_lm_bound_apply(*u, box.bound_u, box.u0, box.u1);
    double vv = cm_lm_bound_apply(*v, box.bound_v, box.v0, box.v1);
    cm_vec3 d[3];
    cm_err e = cm_psurf_eval(ps, uu, vv, d, st);
    if (e != CM_OK)
        return e;
    cm_lm2 lm;
    cm_lm2_start(&lm, opts, &box, P, uu, vv, d);
    while (cm_lm2_next(&lm)) {
        if ((e = cm_psurf_eval(ps, lm.un, lm.vn, d, st)) != CM_OK)
            return e;
        cm_lm2_take(&lm, d);
    }
    *u = lm.u;
    *v = lm.v;
    if (dist)
        *dist = sqrt(lm.f);
    if (dend)
        for (int i = 0; i < 3; i++)
            dend[i] = lm.d[i];
    return CM_OK;
}

cm_err cm_psurf_project_from(const cm_psurf *ps, cm_vec3 P, double *u, double *v, double *dist, cm_status *st)
{
    return project_with(ps, P, &project_lm, u, v, dist, NULL, st);
}

/* the (u,v) of the control point nearest P (the first of equals), at its Greville abscissae: where
   a B-spline's net lies close to its surface, a start close to P's own (u,v) */
static void net_nearest(const cm_psurf *ps, cm_vec3 P, double *u, double *v)
{
    const cm_surf *s = &ps->s;
    long n = (long)s->nu * (long)s->nv, best = 0;
    double bf = cm_norm2(cm_sub(s->ctrl[0], P));
    for (long i = 1; i < n; i++) {
        double f = cm_norm2(cm_sub(s->ctrl[i], P));
        if (f < bf) {
            bf = f;
            best = i;
        }
    }
    int iu = (int)(best / s->nv), iv = (int)(best % s->nv);
    double gu = 0.0, gv = 0.0;
    for (int k = 1; k <= s->p; k++)
        gu += s->U[iu + k];
    for (int k = 1; k <= s->q; k++)
        gv += s->V[iv + k];
    *u = gu / (double)s->p;
    *v = gv / (double)s->q;
}

/* parameter i of n grid values over [a, b] */
static double grid_at(double a, double b, int i, int n) { return a + (b - a) * (double)i / (double)(n - 1); }

/* the grid point nearest P (first of equals, row by row), from the surface's points g (NULL: evaluated
   here), then refined by cm_psurf_project_from */
static cm_err grid_search(const cm_psurf *ps, cm_vec3 P, int n, const cm_vec3 *g, double *u, double *v,
                          double *dist, cm_status *st)
{
    double bu = ps->u0, bv = ps->v0, bf = -1.0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double ui = grid_at(ps->u0, ps->u1, i, n), vj = grid_at(ps->v0, ps->v1, j, n);
            cm_vec3 d[3];
            if (g)
                d[0] = g[i * n + j];
            else {
                cm_err e = cm_psurf_eval(ps, ui, vj, d, st);
                if (e != CM_OK)
                    return e;
            }
            double fi = cm_norm2(cm_sub(d[0], P));
            if (bf < 0 || fi < bf) {
                bf = fi;
                bu = ui;
                bv = vj;
            }
        }
    *u = bu;
    *v = bv;
    return cm_psurf_project_from(ps, P, u, v, dist, st);
}

cm_err cm_psurf_project_grid(const cm_psurf *ps, cm_vec3 P, int n, double *u, double *v, double *dist, cm_status *st)
{
    if (n < 2 || n > 64)
        return cm_fail(st, CM_E_ARG, __func__);
    return grid_search(ps, P, n, NULL, u, v, dist, st);
}

cm_err cm_psurf_grid_points(const cm_psurf *ps, int n, cm_vec3 *g, cm_status *st)
{
    if (n < 2 || n > 64)
        return cm_fail(st, CM_E_ARG, __func__);
    /* the parameters cm_psurf_eval would pass on; the points are its d[0], bit for bit, at a tenth
       of the cost (a loop whose points lie off its surface builds the fine grid: 14 % of cgma's
       decode when every grid point was a full evaluation with derivatives) */
    double gu[64], gv[64];
    for (int i = 0; i < n; i++) {
        gu[i] = wrap(grid_at(ps->u0, ps->u1, i, n), ps->u0, ps->u1, ps->closed_u);
        gv[i] = wrap(grid_at(ps->v0, ps->v1, i, n), ps->v0, ps->v1, ps->closed_v);
    }
    return cm_surf_eval_grid(&ps->s, gu, n, gv, n, g, st);
}

cm_err cm_psurf_project_grid_pts(const cm_psurf *ps, cm_vec3 P, int n, const cm_vec3 *g, double *u, double *v,
                                 double *dist, cm_status *st)
{
    if (n < 2 || n > 64 || !g)
        return cm_fail(st, CM_E_ARG, __func__);
    return grid_search(ps, P, n, g, u, v, dist, st);
}

/*
 * cm_psurf_project_grid with the grid's surface points kept in ws for the rest of the loop: the same
 * evaluations in the same order, so the same answer (and the same error, at the same grid point,
 * when one fails).  Other grid sizes, or a build without the cache, search as before.
 */
static cm_err project_grid_cached(const cm_psurf *ps, cm_vec3 P, int n, cm_param_ws *ws, double *u, double *v,
                                  double *dist, cm_status *st)
{
    int which = n == CM_PARAM_GRID_COARSE ? 0 : (n == CM_PARAM_GRID_FINE ? 1 : -1);
    if (!CM_PARAM_GRID_CACHE || which < 0)
        return cm_psurf_project_grid(ps, P, n, u, v, dist, st);
    cm_vec3 *g = ws->grid + (which ? CM_PARAM_GRID_COARSE * CM_PARAM_GRID_COARSE : 0);
    if (!ws->grid_have[which]) {
        cm_err e = cm_psurf_grid_points(ps, n, g, st);
        if (e != CM_OK)
            return e;
        ws->grid_have[which] = 1;
    }
    return grid_search(ps, P, n, g, u, v, dist, st);
}

cm_err cm_loop_uv(const cm_psurf *ps, const cm_vec3 *pts, int n, double accept, cm_vec2 *uv_out, int *src, int cap,
                  int *nout, int *wind_u, int *wind_v, double *max_gap, cm_param_ws *ws, cm_status *st)
{
    if (n > CM_MAX_TESS_POINTS)
        return cm_fail_limit(st, CM_LIMIT_MAX_TESS_POINTS, (uint64_t)n, CM_MAX_TESS_POINTS, __func__);
    if (n < 1)
        return cm_fail(st, CM_E_ARG, __func__);
    double pu = ps->u1 - ps->u0, pv = ps->v1 - ps->v0;
    ws->grid_have[0] = ws->grid_have[1] = 0; /* a new loop: perhaps a new surface at the same address */
    cm_lm2_opts walk_opts = project_lm;
    if (ws->net_start)
        walk_opts.step_min = WALK_STEP_MIN_48;
    const cm_lm2_opts *walk = &walk_opts;
    cm_vec2 *uv = ws->uv;
    unsigned char *pole = ws->pole;
    double u = 0, v = 0;
    cm_err e;
    /* 1. project by continuation; index n is the loop's start once more (for the winding).  The
       first point's grid search can land on a wrong local minimum (a helical strip's neighbouring
       turn, one pitch away, where a 41-point grid aliases the turns); the walk then finds its way
       by a global search a few points on, and the loop comes back to its start from the right side.
       When the start was far worse than that return, the loop is walked once more from there. */
    double gap = 0.0;
    for (int pass = 0; pass < 2; pass++) {
        /* global searches (a grid of 41 x 41 evaluations each) are for the few points where the walk
           loses its way; a loop that needs them everywhere (a hostile or garbled surface) gets a
           bounded number, so a face costs O(n) projections whatever the file holds */
        int global_left = 32 + n / 8;
        double dist_start = 0.0, dist_end = 0.0;
        gap = 0.0;
        for (int k = 0; k <= n; k++) {
            cm_vec3 P = pts[k < n ? k : 0];
            double uu = u, vv = v, dist;
            /* the surface's point and partials where the search ended (at_u, at_v), which the pole
               test below needs at (uu, vv): evaluated again only where a grid or a period moved it */
            cm_vec3 dd[3];
            double at_u = 0.0, at_v = 0.0;
            int have_dd = 0;
            if (k == 0 && pass == 0) {
                /* the first point: (format 4.8) from the control net; a coarse grid (289 evaluations)
                   where that lands badly, a fine one (1681) only if the coarse grid does too.  The
                   net's start lands within `accept` on 487 of the 514 kept loops of the 36 corpus
                   models (occt__hammer: on the grid's point on 8 of 9, the ninth at a clamped
                   side's minimum 1.079 mm off instead of 1.060, accept 2.57) */
                int landed = 0;
                if (ws->net_start) {
                    net_nearest(ps, P, &uu, &vv);
                    if ((e = project_with(ps, P, walk, &uu, &vv, &dist, dd, st)) != CM_OK)
                        return e;
                    landed = dist <= accept;
                    have_dd = 1;
                    at_u = uu;
                    at_v = vv;
                }
                if (!landed) {
                    if ((e = project_grid_cached(ps, P, CM_PARAM_GRID_COARSE, ws, &uu, &vv, &dist, st)) != CM_OK)
                        return e;
                    if (dist > accept &&
                        (e = project_grid_cached(ps, P, CM_PARAM_GRID_FINE, ws, &uu, &vv, &dist, st)) != CM_OK)
                        return e;
                }
            } else {
                /* (the second pass starts from where the first came back to the start) */
                if ((e = project_with(ps, P, walk, &uu, &vv, &dist, dd, st)) != CM_OK)
                    return e;
                have_dd = 1;
                at_u = uu;
                at_v = vv;
                if (dist > accept && global_left > 0) {
                    global_left--;
                    /* lost the way (a jump): search globally, keep the periodic copy nearest to us */
                    double gu, gv, gd;
                    if ((e = project_grid_cached(ps, P, CM_PARAM_GRID_FINE, ws, &gu, &gv, &gd, st)) != CM_OK)
                        return e;
                    if (gd < dist) {
                        if (ps->closed_u)
                            gu += pu * floor((u - gu) / pu + 0.5);
                        if (ps->closed_v)
                            gv += pv * floor((v - gv) / pv + 0.5);
                        uu = gu;
                        vv = gv;
                        dist = gd;
                    }
                }
            }
            if (k > 0) {
                /* consecutive samples are far closer than half a period: take the periodic copy nearest
                   to the previous point (a Newton walk may have gone round the long way) */
                if (ps->closed_u)
                    uu += pu * floor((u - uu) / pu + 0.5);
                if (ps->closed_v)
                    vv += pv * floor((v - vv) / pv + 0.5);
            }
            /* (the same bits of (u,v), the same point: a copy a period away may round otherwise) */
            if (!(have_dd && memcmp(&uu, &at_u, sizeof uu) == 0 && memcmp(&vv, &at_v, sizeof vv) == 0) &&
                (e = cm_psurf_eval(ps, uu, vv, dd, st)) != CM_OK)
                return e;
            /* a pole: the iso-line through the point in one direction is shorter than `accept`
             * (exporters leave a generatrix end a little off the axis) */
            double lu = cm_norm(dd[1]) * pu, lv = cm_norm(dd[2]) * pv;
            pole[k] = (unsigned char)(lu <= accept && lu < lv ? 1 : (lv <= accept && lv < lu ? 2 : 0));
            if (k < n && dist > gap)
                gap = dist;
            if (k == 0)
                dist_start = dist;
            if (k == n)
                dist_end = dist;
            u = uu;
            v = vv;
            uv[k] = cm_v2(u, v);
        }
        if (!(dist_start > accept && dist_end < 0.5 * dist_start))
            break;
        /* the second pass starts from the return, its periodic copy in the domain */
        if (ps->closed_u)
            u -= pu * floor((u - ps->u0) / pu);
        if (ps->closed_v)
            v -= pv * floor((v - ps->v0) / pv);
    }
    if (max_gap && gap > *max_gap)
        *max_gap = gap;
    /* 1b. a chord passing over a pole (a meridian of a sphere through its pole: its ends half a period
       apart round the axis) can be drawn either way round, and the nearest copy is a rounding tie.  A
       loop through a pole does not enclose it (drawn round it, its (u,v) polygon would take in the far
       half of the pole's neighbourhood, outside the face: triangles folded over the chord), so such
       ties are turned, latest first, until the loop winds no more (or none is left) */
    if (ps->closed_u || ps->closed_v) {
        int tie_k[CM_PARAM_MAX_TIES], tie_dir[CM_PARAM_MAX_TIES], ntie = 0;
        for (int dir = 0; dir < 2; dir++) {
            /* dir 0: v closed, poles at u = u0, u1; dir 1: u closed, poles at v = v0, v1 */
            if (dir == 0 ? !ps->closed_v : !ps->closed_u)
                continue;
            double period = dir == 0 ? pv : pu;
            for (int side = 0; side < 2; side++) {
                double fixed = dir == 0 ? (side ? ps->u1 : ps->u0) : (side ? ps->v1 : ps->v0);
                cm_vec3 q = cm_v3(0, 0, 0), axis = cm_v3(0, 0, 0), t_prev = cm_v3(0, 0, 0), t_first = cm_v3(0, 0, 0);
                double spread = 0.0;
                for (int j = 0; j <= CM_PARAM_POLE_PROBES; j++) {
                    double w = (dir == 0 ? ps->v0 : ps->u0) + period * (double)j / (double)CM_PARAM_POLE_PROBES;
                    cm_vec3 d[3];
                    if ((e = cm_psurf_eval(ps, dir == 0 ? fixed : w, dir == 0 ? w : fixed, d, st)) != CM_OK)
                        return e;
                    cm_vec3 t = dir == 0 ? d[1] : d[2]; /* the tangent leaving the pole */
                    if (j == 0) {
                        q = d[0];
                        t_first = t;
                    } else {
                        double g = cm_dist(d[0], q);
                        spread = g > spread ? g : spread;
                        axis = cm_add(axis, cm_cross(t_prev, j == CM_PARAM_POLE_PROBES ? t_first : t));
                    }
                    t_prev = t;
                }
                double la = cm_norm(axis);
                if (spread > accept || !(la > 0))
                    continue; /* not a pole */
                axis = cm_scale(axis, 1.0 / la);
                for (int k = 1; k <= n && ntie < CM_PARAM_MAX_TIES; k++) {
                    double dk = dir == 0 ? uv[k].y - uv[k - 1].y : uv[k].x - uv[k - 1].x;
                    if (pole[k] || pole[k - 1] || fabs(dk) < 0.25 * period)
                        continue;
                    /* the chord's ends seen from the pole, across its axis */
                    cm_vec3 a = cm_sub(pts[k - 1], q), b = cm_sub(pts[k < n ? k : 0], q);
                    a = cm_sub(a, cm_scale(axis, cm_dot(a, axis)));
                    b = cm_sub(b, cm_scale(axis, cm_dot(b, axis)));
                    double lc = cm_dist(a, b);
                    if (!(cm_dot(a, b) < 0) || !(lc > 0))
                        continue;
                    int known = 0; /* a sphere's two poles share the axis */
                    for (int t = 0; t < ntie; t++)
                        known |= tie_k[t] == k && tie_dir[t] == dir;
                    if (!known && fabs(cm_dot(cm_cross(a, b), axis)) <= accept * lc) {
                        tie_k[ntie] = k;
                        tie_dir[ntie++] = dir;
                    }
                }
            }
        }
        for (int dir = 0; dir < 2 && ntie > 0; dir++) {
            double period = dir == 0 ? pv : pu;
            for (int t = ntie - 1; t >= 0; t--) {
                double turns = dir == 0 ? (uv[n].y - uv[0].y) / period : (uv[n].x - uv[0].x) / period;
                int w = (int)floor(turns + 0.5);
                if (w == 0)
                    break;
                int k = tie_k[t];
                double dk = dir == 0 ? uv[k].y - uv[k - 1].y : uv[k].x - uv[k - 1].x;
                if (tie_dir[t] != dir || (dk > 0) != (w > 0))
                    continue;
                double adj = w > 0 ? -period : period;
                for (int j = k; j <= n; j++) {
                    if (dir == 0)
                        uv[j].y += adj;
                    else
                        uv[j].x += adj;
                }
            }
        }
    }
    /* 2. redraw pole runs along the pole line; shift what follows to stay continuous */
    double shift_u = 0, shift_v = 0;
    int last = -1; /* last non-pole point */
    int tie = -1, tie_u = 0; /* the last exit from a pole turning half a period (either way as short) */
    for (int i = 0; i <= n; i++) {
        uv[i].x += shift_u;
        uv[i].y += shift_v;
        if (pole[i]) {
            if (last >= 0) {
                if (pole[i] == 1)
                    uv[i].x = uv[last].x;
                else
                    uv[i].y = uv[last].y;
            }
            continue;
        }
        if (last >= 0 && i > last + 1) {
            /* leaving a pole run: turn the shorter way to this point's free parameter */
            int free_u = pole[i - 1] == 1;
            double delta = free_u ? uv[i].x - uv[last].x : uv[i].y - uv[last].y, period = free_u ? pu : pv;
            int closed = free_u ? ps->closed_u : ps->closed_v;
            double adj = closed ? -period * floor(delta / period + 0.5) : 0.0;
            if (closed && fabs(fabs(delta + adj) - 0.5 * period) <= 1e-6 * period) {
                tie = i;
                tie_u = free_u;
            }
            if (free_u) {
                shift_u += adj;
                uv[i].x += adj;
            } else {
                shift_v += adj;
                uv[i].y += adj;
            }
        }
        last = i;
    }
    /*
     * 2b. a loop through a pole never needs to wind round the pole's free direction: the pole closes
     * it.  Where an exit turned exactly half a period (a half cone or hemisphere, as CATIA splits
     * them), either turn is as short, and the one that makes the loop wind one turn is the wrong one:
     * the other is taken.
     */
    if (tie >= 0) {
        double period = tie_u ? pu : pv;
        double turns = floor(((tie_u ? uv[n].x - uv[0].x : uv[n].y - uv[0].y)) / period + 0.5);
        if (fabs(turns) == 1.0)
            for (int i = tie; i <= n; i++) {
                if (tie_u)
                    uv[i].x -= turns * period;
                else
                    uv[i].y -= turns * period;
            }
    }
    /* a loop that starts (so ends) at a pole closes along the pole line: arriving a period (or less)
       away from where it left is no turn round the surface */
    int start_pole_u = pole[0] == 1 && pole[n] == 1 && fabs(uv[n].x - uv[0].x) <= pu * (1 + 1e-9);
    int start_pole_v = pole[0] == 2 && pole[n] == 2 && fabs(uv[n].y - uv[0].y) <= pv * (1 + 1e-9);
    /* 3. emit: the last point of a pole run appears twice, with the arrival and the departure parameter */
    int k = 0;
    for (int i = 0; i < n; i++) {
        int run_end = pole[i] && (i + 1 == n || !pole[i + 1]);
        if (k + 1 + run_end > cap)
            return cm_fail_nospace(st, (uint64_t)(k + 1 + run_end), (uint64_t)cap, __func__);
        uv_out[k] = uv[i];
        src[k++] = i;
        if (run_end) {
            cm_vec2 dep = uv[i];
            if (pole[i] == 1)
                dep.x = uv[i + 1].x;
            else
                dep.y = uv[i + 1].y;
            uv_out[k] = dep;
            src[k++] = i;
        }
    }
    *nout = k;
    /* the turns round each closed direction, as an int only when it is one: a hostile surface's
       projection can run off by 7e10 periods (fuzz-decode-crc, a float-to-int overflow under UBSan) */
    double wu = ps->closed_u && !start_pole_u ? floor((uv[n].x - uv[0].x) / pu + 0.5) : 0.0;
    double wv = ps->closed_v && !start_pole_v ? floor((uv[n].y - uv[0].y) / pv + 0.5) : 0.0;
    if (!(fabs(wu) <= CM_PARAM_MAX_WINDING) || !(fabs(wv) <= CM_PARAM_MAX_WINDING))
        return cm_fail(st, CM_E_RANGE, "a loop that winds round a closed surface beyond any count");
    *wind_u = (int)wu;
    *wind_v = (int)wv;
    return CM_OK;
}

cm_err cm_join_winding(const cm_vec2 *lo, int nlo, const cm_vec2 *hi, int nhi, double period, double cap_coord,
                       cm_vec2 *out, int cap, int *nout, int *hi_start, cm_status *st)
{
    int need = nlo + 1 + (hi ? nhi + 1 : 2);
    if (need > cap)
        return cm_fail_nospace(st, (uint64_t)need, (uint64_t)cap, __func__);
    int k = 0;
    for (int i = 0; i < nlo; i++)
        out[k++] = lo[i];
    out[k++] = cm_v2(lo[0].x + period, lo[0].y);
    if (hi) {
        /* start the upper loop where it is nearest (mod period) to lo[0] + period */
        int best = 0;
        double bd = -1;
        for (int i = 0; i < nhi; i++) {
            double du = hi[i].x - (lo[0].x + period);
            du -= period * floor(du / period + 0.5);
            if (bd < 0 || fabs(du) < bd) {
                bd = fabs(du);
                best = i;
            }
        }
        if (hi_start)
            *hi_start = best;
        double shift = (lo[0].x + period) - hi[best].x;
        shift = period * floor(shift / period + 0.5);
        double prev = hi[best].x + shift;
        for (int i = 0; i <= nhi; i++) {
            cm_vec2 q = hi[(best + i) % nhi];
            double x = q.x + shift;
            x += period * floor((prev - x) / period + 0.5);
            out[k++] = cm_v2(x, q.y);
            prev = x;
        }
    } else {
        out[k++] = cm_v2(lo[0].x + period, cap_coord);
        out[k++] = cm_v2(lo[0].x, cap_coord);
    }
    *nout = k;
    return CM_OK;
}

void cm_loops_align(const cm_psurf *ps, cm_vec2 *uv, const int *loop_start, int nloops)
{
    if (nloops < 2 || (!ps->closed_u && !ps->closed_v) || loop_start[1] <= loop_start[0])
        return;
    double pu = ps->u1 - ps->u0, pv = ps->v1 - ps->v0;
    double lo_u = HUGE_VAL, hi_u = -HUGE_VAL, lo_v = HUGE_VAL, hi_v = -HUGE_VAL;
    for (int i = loop_start[0]; i < loop_start[1]; i++) {
        lo_u = uv[i].x < lo_u ? uv[i].x : lo_u;
        hi_u = uv[i].x > hi_u ? uv[i].x : hi_u;
        lo_v = uv[i].y < lo_v ? uv[i].y : lo_v;
        hi_v = uv[i].y > hi_v ? uv[i].y : hi_v;
    }
    double cu = 0.5 * (lo_u + hi_u), cv = 0.5 * (lo_v + hi_v);
    for (int l = 1; l < nloops; l++) {
        int n = loop_start[l + 1] - loop_start[l];
        if (n <= 0)
            continue;
        double mu = 0, mv = 0;
        for (int i = loop_start[l]; i < loop_start[l + 1]; i++) {
            mu += uv[i].x / n;
            mv += uv[i].y / n;
        }
        double ku = ps->closed_u && pu > 0 ? floor((cu - mu) / pu + 0.5) : 0.0;
        double kv = ps->closed_v && pv > 0 ? floor((cv - mv) / pv + 0.5) : 0.0;
        if (!(fabs(ku) <= CM_PARAM_MAX_WINDING) || !(fabs(kv) <= CM_PARAM_MAX_WINDING) || (ku == 0 && kv == 0))
            continue;
        for (int i = loop_start[l]; i < loop_start[l + 1]; i++) {
            uv[i].x += ku * pu;
            uv[i].y += kv * pv;
        }
    }
}
