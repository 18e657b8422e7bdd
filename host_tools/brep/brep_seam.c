/* brep_seam.c - a band bounded by two loops winding round a closed surface, cut open along a
   parameter line of its surface (brep_seam.h). */
#include "brep/brep_seam.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SEAM_SAMPLES 48 /* per curve of the far loop: where it crosses the cut's line */
#define SEAM_BISECT 52  /* halvings of the crossing's bracket (a curve parameter to 2^-52 of its step) */

/* d wrapped into (-period/2, period/2] */
static double wrap(double d, double period)
{
    d = fmod(d, period);
    if (d > 0.5 * period)
        d -= period;
    else if (d <= -0.5 * period)
        d += period;
    return d;
}

/* the parameters of P on the face's surface: x along the winding direction, y across it */
static int surf_xy(const face_domain *fd, int along_u, cm_vec3 P, double *x, double *y)
{
    double u, v, d;
    if (face_domain_project_global(fd, P, &u, &v, &d) != CM_OK || !isfinite(u) || !isfinite(v))
        return 0;
    *x = along_u ? u : v;
    *y = along_u ? v : u;
    return 1;
}

static cm_vec3 curve_at(const hcurve *c, double t)
{
    cm_curve cv = hcurve_view(c);
    cm_vec3 d[1] = {{0, 0, 0}};
    if (cm_curve_eval(&cv, t, 0, d, NULL) != CM_OK) /* (a checked curve: cannot happen) */
        return cm_v3((double)NAN, (double)NAN, (double)NAN);
    return d[0];
}

/* the loop's curves as copies, in order, reversed whole when rev (the loop then runs backwards) */
static cm_err copy_loop(const brep_model *m, const brep_loop *l, int rev, hcurve *out, cm_status *st)
{
    for (int i = 0; i < l->n; i++) {
        hcurve *c = &out[i];
        cm_err e = hcurve_copy(&m->segs[l->first + (rev ? l->n - 1 - i : i)], c, st);
        if (e != CM_OK)
            return e;
        if (rev)
            hcurve_reverse(c);
    }
    return CM_OK;
}

/* where the curves c[0..n) cross the line x = x0 (mod period) nearest to y0: curve *ci at *ti, its
   other parameter *yi; 0 if they never cross it */
static int find_crossing(const face_domain *fd, int along_u, double period, const hcurve *c, int n, double x0,
                         double y0, int *ci, double *ti, double *yi)
{
    int found = 0;
    double best = HUGE_VAL;
    for (int i = 0; i < n; i++) {
        double t0, t1, x, y, gp = 0.0, tp = 0.0;
        hcurve_domain(&c[i], &t0, &t1);
        int have = 0;
        for (int j = 0; j <= SEAM_SAMPLES; j++) {
            double t = t0 + (t1 - t0) * j / SEAM_SAMPLES;
            if (!surf_xy(fd, along_u, curve_at(&c[i], t), &x, &y)) {
                have = 0;
                continue;
            }
            double g = wrap(x - x0, period);
            /* a change of sign that is not the wrap's jump half a period away */
            if (have && ((gp < 0.0 && g >= 0.0) || (gp > 0.0 && g <= 0.0)) && fabs(g - gp) < 0.25 * period) {
                double a = tp, b = t, ga = gp;
                for (int k = 0; k < SEAM_BISECT; k++) {
                    double mid = 0.5 * (a + b), xm, ym;
                    if (!surf_xy(fd, along_u, curve_at(&c[i], mid), &xm, &ym))
                        break;
                    double gm = wrap(xm - x0, period);
                    if ((ga < 0.0) == (gm < 0.0)) {
                        a = mid;
                        ga = gm;
                    } else {
                        b = mid;
                    }
                }
                double tc = 0.5 * (a + b), xc, yc;
                if (surf_xy(fd, along_u, curve_at(&c[i], tc), &xc, &yc) && fabs(yc - y0) < best) {
                    best = fabs(yc - y0);
                    *ci = i;
                    *ti = tc;
                    *yi = yc;
                    found = 1;
                }
            }
            gp = g;
            tp = t;
            have = 1;
        }
    }
    return found;
}

static void free_curves(hcurve *c, int n)
{
    for (int i = 0; c && i < n; i++)
        hcurve_free(&c[i]);
}

/* a cap's pole: the end y of the other parameter, at the edge of the domain's polygon, where the
   surface shrinks to one point (a cone's apex, a dome's top); 0 if there is none */
static int find_pole(const brep_model *m, const brep_face *F, const face_domain *fd, double accept, double *yp)
{
    int along_u = fd->wind_along_u;
    double lo = along_u ? fd->ps.v0 : fd->ps.u0, hi = along_u ? fd->ps.v1 : fd->ps.u1;
    double pmin = along_u ? fd->vmin : fd->umin, pmax = along_u ? fd->vmax : fd->umax;
    double x0 = along_u ? fd->ps.u0 : fd->ps.v0, period = along_u ? fd->ps.u1 - fd->ps.u0 : fd->ps.v1 - fd->ps.v0;
    cm_surf view = hsurf_view(&m->surfs[F->surf]);
    for (int end = 0; end < 2; end++) {
        double y = end ? hi : lo, near = end ? pmax : pmin;
        if (!(fabs(near - y) <= 1e-6 * (hi - lo)))
            continue; /* the polygon does not reach this end */
        cm_vec3 P[3];
        int same = 1;
        for (int k = 0; k < 3 && same; k++) {
            cm_vec3 S[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
            double x = x0 + period * k / 3.0;
            if (cm_surf_eval(&view, along_u ? x : y, along_u ? y : x, 0, S, NULL) != CM_OK)
                return 0;
            P[k] = S[0][0];
            same = k == 0 || cm_dist(P[k], P[0]) <= accept;
        }
        if (same) {
            *yp = y;
            return 1;
        }
    }
    return 0;
}

/* the new outer loop's curves into out (room for na + nb + 3): the near loop from its start PA, the
   cut up to PB, the far loop from PB round to PB (a cap has none: PB is its pole), the cut back
   down; their count in *n, or 0 where the cut cannot be made */
static cm_err build_cut_loop(const brep_model *m, const brep_face *F, const face_domain *fd, double accept,
                             hcurve *out, int *n, cm_status *st)
{
    *n = 0;
    int along_u = fd->wind_along_u;
    double period = along_u ? fd->ps.u1 - fd->ps.u0 : fd->ps.v1 - fd->ps.v0;
    const brep_loop *la = &m->loops[F->first_loop + fd->wind_loop[0]];
    const brep_loop *lb = fd->wind_loop[1] >= 0 ? &m->loops[F->first_loop + fd->wind_loop[1]] : NULL;
    int na = la->n, nb = lb ? lb->n : 0;
    hcurve *a = calloc((size_t)na, sizeof *a), *b = calloc((size_t)nb + 1, sizeof *b);
    cm_err e = a && b ? CM_OK : cm_fail(st, CM_E_NOMEM, "out of memory");
    if (e == CM_OK)
        e = copy_loop(m, la, 0, a, st);
    /* each loop once round (the face domain counted its turns); the far loop runs the other way
       round (an outer loop and its hole), as the file may not have it */
    int ta = fd->wind_turns[0], tb = lb ? fd->wind_turns[1] : -ta;
    if (e == CM_OK && lb)
        e = copy_loop(m, lb, 0, b, st);
    int ok = e == CM_OK && abs(ta) == 1 && abs(tb) == 1;
    if (ok && lb && (ta > 0) == (tb > 0)) {
        free_curves(b, nb);
        memset(b, 0, (size_t)nb * sizeof *b);
        e = copy_loop(m, lb, 1, b, st);
        ok = e == CM_OK;
    }
    /* PA: the near loop's start; PB: where the far loop crosses PA's parameter line */
    double t0, t1, xa = 0, ya = 0, yb = 0, tc = 0;
    int ci = -1;
    cm_vec3 PA = cm_v3(0, 0, 0);
    if (ok) {
        hcurve_domain(&a[0], &t0, &t1);
        PA = curve_at(&a[0], t0);
    }
    ok = ok && surf_xy(fd, along_u, PA, &xa, &ya) &&
         (lb ? find_crossing(fd, along_u, period, b, nb, xa, ya, &ci, &tc, &yb) : find_pole(m, F, fd, accept, &yb));
    hcurve iso = {0}, cut = {0}, back = {0}, head = {0}, tail = {0};
    if (ok && e == CM_OK) {
        /* the cut: the surface's line at xa from ya to yb (wrapped into the surface's domain) */
        double lo = along_u ? fd->ps.u0 : fd->ps.v0, x = lo + wrap(xa - lo, period);
        x = x < lo ? x + period : x;
        const hsurf *S = &m->surfs[F->surf];
        e = along_u ? hsurf_iso_u(S, x, &iso, st) : hsurf_iso_v(S, x, &iso, st);
        if (e == CM_OK) { /* (a loop on the domain's edge projects a rounding beyond it) */
            double d0, d1;
            hcurve_domain(&iso, &d0, &d1);
            double room = 1e-9 * (d1 - d0);
            ya = ya < d0 && ya > d0 - room ? d0 : (ya > d1 && ya < d1 + room ? d1 : ya);
            yb = yb < d0 && yb > d0 - room ? d0 : (yb > d1 && yb < d1 + room ? d1 : yb);
        }
        if (e == CM_OK && ya != yb) {
            e = hcurve_subrange(&iso, ya < yb ? ya : yb, ya < yb ? yb : ya, &cut, st);
            if (e == CM_OK && ya > yb)
                hcurve_reverse(&cut);
        } else {
            ok = 0;
        }
        if (e == CM_E_ARG) { /* (a range outside the iso-curve's domain: no cut) */
            e = CM_OK;
            ok = 0;
        }
    }
    cm_vec3 PB = cm_v3(0, 0, 0);
    if (ok && e == CM_OK) {
        double c0, c1;
        hcurve_domain(&cut, &c0, &c1);
        PB = lb ? curve_at(&b[ci], tc) : curve_at(&cut, c1);
    }
    if (ok && e == CM_OK) {
        double c0, c1;
        hcurve_domain(&cut, &c0, &c1);
        ok = cm_dist(curve_at(&cut, c0), PA) <= accept && cm_dist(curve_at(&cut, c1), PB) <= accept &&
             cm_dist(PA, PB) > accept;
    }
    if (ok && e == CM_OK) {
        e = hcurve_copy(&cut, &back, st);
        if (e == CM_OK)
            hcurve_reverse(&back);
    }
    /* the far loop split at PB (unless PB is one of its curve's ends) */
    int split = 0;
    if (ok && e == CM_OK && lb) {
        double b0, b1;
        hcurve_domain(&b[ci], &b0, &b1);
        if (cm_dist(curve_at(&b[ci], b0), PB) <= accept) {
            tc = b0;
        } else if (cm_dist(curve_at(&b[ci], b1), PB) <= accept) {
            ci = (ci + 1) % nb;
            tc = b0;
        } else {
            e = hcurve_subrange(&b[ci], b0, tc, &head, st);
            if (e == CM_OK)
                e = hcurve_subrange(&b[ci], tc, b1, &tail, st);
            split = 1;
            if (e == CM_E_ARG) {
                e = CM_OK;
                ok = 0;
            }
        }
    }
    if (ok && e == CM_OK) {
        int k = 0;
        for (int i = 0; i < na; i++) {
            out[k++] = a[i];
            memset(&a[i], 0, sizeof a[i]);
        }
        out[k++] = cut;
        memset(&cut, 0, sizeof cut);
        /* from PB: the tail of the split curve (or the curve starting there), round, then its head
           (the neighbour sharing the far loop keeps its vertex where the file's curve started: a
           circle restarted at PB as one curve would be cut there again by the curve mesh) */
        if (split) {
            out[k++] = tail;
            memset(&tail, 0, sizeof tail);
        }
        for (int j = split ? 1 : 0; j < nb; j++) {
            int i = (ci + j) % nb;
            out[k++] = b[i];
            memset(&b[i], 0, sizeof b[i]);
        }
        if (split) {
            out[k++] = head;
            memset(&head, 0, sizeof head);
        }
        out[k++] = back;
        memset(&back, 0, sizeof back);
        *n = k;
    }
    free_curves(a, na);
    free_curves(b, nb);
    free(a);
    free(b);
    hcurve_free(&iso);
    hcurve_free(&cut);
    hcurve_free(&back);
    hcurve_free(&head);
    hcurve_free(&tail);
    return e;
}

cm_err brep_cut_seam(brep_model *m, int f, face_domain *fd, double tol, int *cut, cm_status *st)
{
    *cut = 0;
    brep_face *F = &m->faces[f];
    /* (a band with other holes too is left alone: no method rebuilds a hole on a curved surface,
       and the cut could cross one) */
    if (!fd->uv || !fd->joined_seam || fd->wind_loop[0] < 0 || F->no_cut || F->nloops != (fd->wind_loop[1] < 0 ? 1 : 2))
        return CM_OK;
    const brep_loop *la = &m->loops[F->first_loop + fd->wind_loop[0]];
    int room = la->n + (fd->wind_loop[1] >= 0 ? m->loops[F->first_loop + fd->wind_loop[1]].n : 0) + 3;
    hcurve *c = calloc((size_t)room, sizeof *c);
    if (!c)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    /* as the face domain accepts a boundary point: a small fraction of the face, not below tol */
    hbox fb = hbox_empty();
    for (int l = 0; l < F->nloops; l++)
        for (int s = 0; s < m->loops[F->first_loop + l].n; s++)
            hbox_add_curve(&fb, &m->segs[m->loops[F->first_loop + l].first + s]);
    double accept = fmax(1e-4 * (fb.empty ? 1.0 : cm_dist(fb.lo, fb.hi)), 10.0 * tol);
    int n = 0;
    cm_status lst; /* (a curve the cut cannot be made of is no error: the face stays as it is) */
    cm_status_init(&lst);
    cm_err e = build_cut_loop(m, F, fd, accept, c, &n, &lst);
    if (e != CM_OK || n == 0) {
        free_curves(c, room);
        free(c);
        return e == CM_E_NOMEM ? cm_fail(st, CM_E_NOMEM, "out of memory") : CM_OK;
    }
    /* the new loops: the cut one, then the face's other holes (the same curves) */
    int old_loop = F->first_loop, old_n = F->nloops, first_seg = m->nsegs, first_loop = m->nloops;
    int cap = fd->wind_loop[1] < 0;
    for (int i = 0; i < n && e == CM_OK; i++)
        e = brep_add_seg(m, &c[i], st);
    free_curves(c, room);
    free(c);
    if (e == CM_OK)
        e = brep_add_loop(m, first_seg, n, st);
    for (int l = 0; l < old_n && e == CM_OK; l++)
        if (l != fd->wind_loop[0] && l != fd->wind_loop[1])
            e = brep_add_loop(m, m->loops[old_loop + l].first, m->loops[old_loop + l].n, st);
    if (e != CM_OK)
        return e;
    F = &m->faces[f];
    F->first_loop = first_loop;
    F->nloops = m->nloops - first_loop;
    F->cut_from_loop = old_loop;
    F->cut_from_nloops = old_n;
    face_domain_free(fd);
    cm_status fst;
    cm_status_init(&fst);
    e = face_domain_build(m, f, tol, fd, &fst);
    /* (a cap's loop still winds in (u,v): its two cuts meet at the pole, which the polygon joins) */
    if (e == CM_OK && (cap || !fd->joined_seam) && fd->nloops == F->nloops) {
        *cut = 1;
        return CM_OK;
    }
    if (fst.code == CM_E_NOMEM)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    /* the cut face has no domain: back to the face as it was */
    F->no_cut = 1;
    return brep_uncut_seam(m, f, fd, tol, st);
}



cm_err brep_uncut_seam(brep_model *m, int f, face_domain *fd, double tol, cm_status *st)
{
    brep_face *F = &m->faces[f];
    if (F->cut_from_nloops <= 0)
        return CM_OK;
    F->first_loop = F->cut_from_loop;
    F->nloops = F->cut_from_nloops;
    F->cut_from_nloops = 0;
    F->no_cut = 1;
    face_domain_free(fd);
    cm_status lst;
    cm_status_init(&lst);
    if (face_domain_build(m, f, tol, fd, &lst) != CM_OK && lst.code == CM_E_NOMEM)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    return CM_OK;
}
