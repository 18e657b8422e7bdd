/* face_domain.c - a face's loops in parameter space, orientation, inside test, sampling. */
#include "face_domain.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_geom.h"

/* ---- polygon storage ---- */

static int push_pt(face_domain *fd, cm_vec2 uv, cm_vec3 p)
{
    if (fd->npts == fd->cap) {
        int cap = fd->cap ? 2 * fd->cap : 256;
        cm_vec2 *a = realloc(fd->uv, (size_t)cap * sizeof *a);
        if (!a)
            return -1;
        fd->uv = a;
        cm_vec3 *b = realloc(fd->xyz, (size_t)cap * sizeof *b);
        if (!b)
            return -1;
        fd->xyz = b;
        fd->cap = cap;
    }
    fd->uv[fd->npts] = uv;
    fd->xyz[fd->npts] = p;
    fd->npts++;
    return 0;
}

void face_domain_free(face_domain *fd)
{
    free(fd->uv);
    free(fd->xyz);
    free(fd->loops);
    if (fd->grid)
        free(fd->grid->pts);
    free(fd->grid);
    memset(fd, 0, sizeof *fd);
}

cm_err face_domain_project_global(const face_domain *fd, cm_vec3 S, double *u, double *v, double *d)
{
    fd_grid *G = fd->grid;
    if (G && G->state == 0) {
        G->pts = malloc((size_t)FD_GRID_N * FD_GRID_N * sizeof *G->pts);
        G->state = G->pts && cm_psurf_grid_points(&fd->ps, FD_GRID_N, G->pts, NULL) == CM_OK ? 1 : -1;
    }
    if (G && G->state == 1)
        return cm_psurf_project_grid_pts(&fd->ps, S, FD_GRID_N, G->pts, u, v, d, NULL);
    return cm_psurf_project_grid(&fd->ps, S, FD_GRID_N, u, v, d, NULL);
}

static double signed_area(const cm_vec2 *p, int n)
{
    double a = 0;
    for (int i = 0, j = n - 1; i < n; j = i++)
        a += cm_cross2(p[j], p[i]);
    return 0.5 * a;
}

/* samples per boundary segment: enough to follow its image in (u,v) */
static int seg_samples(const hcurve *c)
{
    int spans = c->n - c->p;
    int n = 6 * (spans > 0 ? spans : 1) * (c->p > 1 ? c->p : 2);
    return n < 12 ? 12 : (n > 240 ? 240 : n);
}

static void reverse_range(face_domain *fd, int first, int n)
{
    for (int i = 0; i < n / 2; i++) {
        cm_vec2 t = fd->uv[first + i];
        fd->uv[first + i] = fd->uv[first + n - 1 - i];
        fd->uv[first + n - 1 - i] = t;
        cm_vec3 q = fd->xyz[first + i];
        fd->xyz[first + i] = fd->xyz[first + n - 1 - i];
        fd->xyz[first + n - 1 - i] = q;
    }
}

/* reverse loop `l` of the model in place: segment order and each segment's direction */
static void reverse_model_loop(brep_model *m, const brep_loop *l)
{
    for (int i = 0; i < l->n / 2; i++) {
        hcurve t = m->segs[l->first + i];
        m->segs[l->first + i] = m->segs[l->first + l->n - 1 - i];
        m->segs[l->first + l->n - 1 - i] = t;
    }
    for (int i = 0; i < l->n; i++)
        hcurve_reverse(&m->segs[l->first + i]);
}

/*
 * The (u,v) polygon of one model loop: samples of its curves followed
 * through the surface by the shared kernel (cm_loop_uv: continuation,
 * seams, poles), written into fd with the 3D point each came from.
 */
static cm_param_ws param_ws; /* large: static, one face at a time */

static cm_err project_loop(const brep_model *m, const brep_loop *l, face_domain *fd, double accept, int *wu, int *wv,
                           cm_status *st)
{
    int n = 0;
    for (int s = 0; s < l->n; s++)
        n += seg_samples(&m->segs[l->first + s]);
    cm_vec3 *pts = malloc((size_t)n * sizeof *pts);
    cm_vec2 *uv = malloc((size_t)(2 * n) * sizeof *uv);
    int *src = malloc((size_t)(2 * n) * sizeof *src);
    cm_err e = (!pts || !uv || !src) ? cm_fail(st, CM_E_NOMEM, "out of memory") : CM_OK;
    int k = 0;
    for (int s = 0; s < l->n && e == CM_OK; s++) {
        const hcurve *c = &m->segs[l->first + s];
        cm_curve cv = hcurve_view(c);
        double t0, t1;
        hcurve_domain(c, &t0, &t1);
        int ns = seg_samples(c);
        for (int j = 0; j < ns && e == CM_OK; j++) {
            cm_vec3 d[1];
            e = cm_curve_eval(&cv, t0 + (t1 - t0) * j / ns, 0, d, st);
            pts[k++] = d[0];
        }
    }
    int nout = 0;
    if (e == CM_OK)
        e = cm_loop_uv(&fd->ps, pts, n, accept, uv, src, 2 * n, &nout, wu, wv, &fd->max_gap, &param_ws, st);
    for (int i = 0; i < nout && e == CM_OK; i++)
        if (push_pt(fd, uv[i], pts[src[i]]))
            e = cm_fail(st, CM_E_NOMEM, "out of memory");
    free(pts);
    free(uv);
    free(src);
    return e;
}

cm_err face_domain_build(brep_model *m, int face, double tol, face_domain *fd, cm_status *st)
{
    memset(fd, 0, sizeof *fd);
    brep_face *f = &m->faces[face];
    fd->face = face;
    fd->wind_loop[0] = fd->wind_loop[1] = -1;
    cm_surf view = hsurf_view(&m->surfs[f->surf]);
    if (cm_psurf_init(&fd->ps, &view, tol, st) != CM_OK)
        return cm_fail(st, CM_E_DEGENERATE, "face_domain: surface");
    fd->loops = calloc((size_t)f->nloops + 1, sizeof *fd->loops);
    fd->grid = calloc(1, sizeof *fd->grid);
    int *wu = calloc((size_t)f->nloops, sizeof(int)), *wv = calloc((size_t)f->nloops, sizeof(int));
    if (!fd->loops || !fd->grid || !wu || !wv) {
        free(wu);
        free(wv);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    /* accept a continuation step if it lands within a small fraction of the face's size */
    hbox fb = hbox_empty();
    for (int l = 0; l < f->nloops; l++) {
        const brep_loop *lp = &m->loops[f->first_loop + l];
        for (int s = 0; s < lp->n; s++)
            hbox_add(&fb, m->segs[lp->first + s].ctrl[0]);
    }
    double fdiag = fb.empty ? 1.0 : cm_dist(fb.lo, fb.hi);
    double accept = fmax(1e-4 * fdiag, 10 * tol);
    cm_err e = CM_OK;
    for (int l = 0; l < f->nloops && e == CM_OK; l++) {
        fd_loop *L = &fd->loops[l];
        L->first = fd->npts;
        e = project_loop(m, &m->loops[f->first_loop + l], fd, accept, &wu[l], &wv[l], st);
        L->n = fd->npts - L->first;
        L->winds = wu[l] != 0 || wv[l] != 0;
        L->area = L->winds ? 0.0 : signed_area(fd->uv + L->first, L->n);
    }
    fd->nloops = f->nloops;
    double desired = f->flip ? -1.0 : 1.0; /* sign of the outer loop's (u,v) area */

    /* the outer loop: the ordinary loop of largest |area| (the file's first, normally) */
    int outer = -1, nwind = 0;
    for (int l = 0; l < fd->nloops; l++) {
        if (fd->loops[l].winds)
            nwind++;
        else if (outer < 0 || fabs(fd->loops[l].area) > fabs(fd->loops[outer].area))
            outer = l;
    }
    if (e == CM_OK && nwind > 0) {
        /* winding loops: join them (or one with the domain edge) into the outer polygon */
        int a = -1, b = -1;
        for (int l = 0; l < fd->nloops; l++)
            if (fd->loops[l].winds) {
                if (a < 0)
                    a = l;
                else if (b < 0)
                    b = l;
            }
        int along_u = wu[a] != 0;
        double period = along_u ? fd->ps.u1 - fd->ps.u0 : fd->ps.v1 - fd->ps.v0;
        if (nwind > 2 || (b >= 0 && (along_u ? wu[b] == 0 : wv[b] == 0))) {
            e = cm_fail(st, CM_E_UNSUPPORTED, "face_domain: more than two loops wind around the surface");
        } else {
            /* work with x = winding coordinate, y = the other */
            cm_vec2 *pa = malloc((size_t)fd->loops[a].n * sizeof *pa);
            cm_vec2 *pb = b >= 0 ? malloc((size_t)fd->loops[b].n * sizeof *pb) : NULL;
            if (!pa || (b >= 0 && !pb)) {
                free(pa);
                free(pb);
                e = cm_fail(st, CM_E_NOMEM, "out of memory");
            } else {
                int na = fd->loops[a].n, nb = b >= 0 ? fd->loops[b].n : 0;
                double ya = 0, yb = 0;
                for (int i = 0; i < na; i++) {
                    cm_vec2 q = fd->uv[fd->loops[a].first + i];
                    pa[i] = along_u ? q : cm_v2(q.y, q.x);
                    ya += pa[i].y / na;
                }
                for (int i = 0; i < nb; i++) {
                    cm_vec2 q = fd->uv[fd->loops[b].first + i];
                    pb[i] = along_u ? q : cm_v2(q.y, q.x);
                    yb += pb[i].y / nb;
                }
                int dira = along_u ? wu[a] : wv[a];
                /* the file's own direction decides which side a lone winding loop bounds */
                const cm_vec2 *lo = pa, *hi = pb;
                int nlo = na, nhi = nb, lo_dir = dira;
                if (b >= 0 && yb < ya) {
                    lo = pb;
                    hi = pa;
                    nlo = nb;
                    nhi = na;
                    lo_dir = along_u ? wu[b] : wv[b];
                }
                /* make the lower loop run +x (and so the upper -x) */
                cm_vec2 *rl = NULL, *rh = NULL;
                int bad = 0;
                if (b >= 0 || lo_dir < 0) {
                    /* copies so they can be reversed */
                    rl = malloc((size_t)nlo * sizeof *rl);
                    rh = b >= 0 ? malloc((size_t)nhi * sizeof *rh) : NULL;
                    if (!rl || (b >= 0 && !rh))
                        bad = 1;
                    else {
                        int lo_sign = 1;
                        for (int i = 0; i < nlo; i++)
                            rl[i] = lo[i];
                        if (b >= 0) {
                            double dx = 0;
                            for (int i = 1; i < nlo; i++)
                                dx += rl[i].x - rl[i - 1].x;
                            lo_sign = dx >= 0 ? 1 : -1;
                        } else {
                            lo_sign = lo_dir > 0 ? 1 : -1;
                        }
                        if (lo_sign < 0)
                            for (int i = 0; i < nlo / 2; i++) {
                                cm_vec2 t = rl[i];
                                rl[i] = rl[nlo - 1 - i];
                                rl[nlo - 1 - i] = t;
                            }
                        for (int i = 0; i < nhi; i++)
                            rh[i] = hi[i];
                        if (b >= 0) {
                            double dx = 0;
                            for (int i = 1; i < nhi; i++)
                                dx += rh[i].x - rh[i - 1].x;
                            if (dx > 0)
                                for (int i = 0; i < nhi / 2; i++) {
                                    cm_vec2 t = rh[i];
                                    rh[i] = rh[nhi - 1 - i];
                                    rh[nhi - 1 - i] = t;
                                }
                        }
                    }
                }
                cm_vec2 *poly = NULL;
                int np = 0;
                if (!bad) {
                    double vcap = (along_u ? fd->ps.v1 : fd->ps.u1);
                    if (b < 0 && !cm_winding_cap_high(lo_dir, f->flip, along_u))
                        vcap = along_u ? fd->ps.v0 : fd->ps.u0;
                    poly = malloc((size_t)(nlo + nhi + 3) * sizeof *poly);
                    bad = !poly || cm_join_winding(rl ? rl : lo, nlo, b >= 0 ? rh : NULL, nhi, period, vcap, poly,
                                                   nlo + nhi + 3, &np, NULL, NULL) != CM_OK;
                }
                free(rl);
                free(rh);
                free(pa);
                free(pb);
                if (bad) {
                    e = cm_fail(st, CM_E_NOMEM, "out of memory");
                } else {
                    /* replace the winding loops by the joined polygon as loop 0 */
                    fd_loop J;
                    J.first = fd->npts;
                    J.winds = 0;
                    for (int i = 0; i < np && e == CM_OK; i++) {
                        cm_vec2 q = along_u ? poly[i] : cm_v2(poly[i].y, poly[i].x);
                        if (push_pt(fd, q, cm_v3(nan(""), nan(""), nan(""))))
                            e = cm_fail(st, CM_E_NOMEM, "out of memory");
                    }
                    free(poly);
                    J.n = np;
                    J.area = signed_area(fd->uv + J.first, J.n);
                    if (J.area * desired < 0) {
                        reverse_range(fd, J.first, J.n);
                        J.area = -J.area;
                    }
                    int k = 1;
                    fd_loop *nl = calloc((size_t)fd->nloops + 1, sizeof *nl);
                    if (!nl) {
                        e = cm_fail(st, CM_E_NOMEM, "out of memory");
                    } else {
                        nl[0] = J;
                        for (int l = 0; l < fd->nloops; l++)
                            if (!fd->loops[l].winds)
                                nl[k++] = fd->loops[l];
                        free(fd->loops);
                        fd->loops = nl;
                        fd->nloops = k;
                        fd->joined_seam = 1;
                        fd->wind_loop[0] = a;
                        fd->wind_loop[1] = b;
                        fd->wind_along_u = along_u;
                        fd->wind_turns[0] = dira;
                        fd->wind_turns[1] = b >= 0 ? (along_u ? wu[b] : wv[b]) : 0;
                        outer = -1; /* loop 0 is already the outer region */
                    }
                }
            }
        }
    } else if (e == CM_OK && outer > 0) {
        /* the outer loop is not the first: move it first in the model and here */
        brep_loop tmp = m->loops[f->first_loop + outer];
        memmove(&m->loops[f->first_loop + 1], &m->loops[f->first_loop], (size_t)outer * sizeof tmp);
        m->loops[f->first_loop] = tmp;
        fd_loop t2 = fd->loops[outer];
        memmove(&fd->loops[1], &fd->loops[0], (size_t)outer * sizeof t2);
        fd->loops[0] = t2;
        fd->reordered = 1;
        outer = 0;
    }
    if (e == CM_OK) {
        /* orientation (spec §1): outer counter-clockwise about the face normal, holes clockwise */
        for (int l = 0; l < fd->nloops; l++) {
            fd_loop *L = &fd->loops[l];
            double want = l == 0 ? desired : -desired;
            if (L->area * want < 0) {
                reverse_range(fd, L->first, L->n);
                L->area = -L->area;
                fd->reversed = 1;
                if (!fd->joined_seam)
                    reverse_model_loop(m, &m->loops[f->first_loop + l]);
            }
        }
        /* holes on the outer polygon's periodic copy (as the terminal does: cm_tessellate.c); the
           loops need not be stored one after the other (a joined outer polygon comes last) */
        for (int l = 1; l < fd->nloops && e == CM_OK; l++) {
            int n0 = fd->loops[0].n, nl = fd->loops[l].n;
            cm_vec2 *tmp = malloc((size_t)(n0 + nl) * sizeof *tmp);
            if (!tmp) {
                e = cm_fail(st, CM_E_NOMEM, "out of memory");
                break;
            }
            memcpy(tmp, fd->uv + fd->loops[0].first, (size_t)n0 * sizeof *tmp);
            memcpy(tmp + n0, fd->uv + fd->loops[l].first, (size_t)nl * sizeof *tmp);
            int starts[3] = {0, n0, n0 + nl};
            cm_loops_align(&fd->ps, tmp, starts, 2);
            memcpy(fd->uv + fd->loops[l].first, tmp + n0, (size_t)nl * sizeof *tmp);
            free(tmp);
        }
        fd->umin = fd->vmin = HUGE_VAL;
        fd->umax = fd->vmax = -HUGE_VAL;
        for (int i = 0; i < fd->loops[0].n; i++) {
            cm_vec2 q = fd->uv[fd->loops[0].first + i];
            fd->umin = fmin(fd->umin, q.x);
            fd->umax = fmax(fd->umax, q.x);
            fd->vmin = fmin(fd->vmin, q.y);
            fd->vmax = fmax(fd->vmax, q.y);
        }
    }
    free(wu);
    free(wv);
    return e;
}

int face_domain_inside(const face_domain *fd, cm_vec2 uv)
{
    if (fd->nloops == 0 || !cm_point_in_polygon(fd->uv + fd->loops[0].first, fd->loops[0].n, uv))
        return 0;
    for (int l = 1; l < fd->nloops; l++)
        if (cm_point_in_polygon(fd->uv + fd->loops[l].first, fd->loops[l].n, uv))
            return 0;
    return 1;
}

double face_domain_edge_dist(const face_domain *fd, cm_vec2 p)
{
    double best = HUGE_VAL;
    for (int l = 0; l < fd->nloops; l++) {
        const cm_vec2 *q = fd->uv + fd->loops[l].first;
        int n = fd->loops[l].n;
        for (int i = 0, j = n - 1; i < n; j = i++) {
            cm_vec2 a = q[j], d = cm_sub2(q[i], a), w = cm_sub2(p, a);
            double dd = cm_dot2(d, d), t = dd > 0 ? cm_dot2(w, d) / dd : 0;
            t = t < 0 ? 0 : t > 1 ? 1 : t;
            cm_vec2 r = cm_sub2(w, cm_v2(t * d.x, t * d.y));
            double dist = sqrt(cm_dot2(r, r));
            if (dist < best)
                best = dist;
        }
    }
    return best;
}

cm_err face_domain_eval(const brep_model *m, const face_domain *fd, double u, double v, cm_vec3 *P, cm_vec3 *N,
                        cm_status *st)
{
    cm_vec3 d[3];
    cm_err e = cm_psurf_eval(&fd->ps, u, v, d, st);
    if (e != CM_OK)
        return e;
    *P = d[0];
    if (N) {
        cm_vec3 n = cm_cross(d[1], d[2]);
        double l = cm_norm(n);
        *N = l > 0 ? cm_scale(n, (m->faces[fd->face].flip ? -1.0 : 1.0) / l) : cm_v3(0, 0, 0);
    }
    return CM_OK;
}

static double lcg(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (double)(*s >> 8) / 16777216.0;
}

int face_domain_sample(const face_domain *fd, int n, uint32_t seed, cm_vec2 *out)
{
    if (fd->nloops == 0 || n <= 0)
        return 0;
    double w = fd->umax - fd->umin, h = fd->vmax - fd->vmin;
    if (!(w > 0) || !(h > 0))
        return 0;
    /* jittered grids, finer (and closer to the boundary) until enough points are inside;
     * then every k-th candidate, so the points spread over the whole face */
    enum { GMAX = 256 };
    static const double margins[4] = {0.02, 0.005, 0.001, 0.0};
    cm_vec2 *cand = malloc((size_t)GMAX * GMAX * sizeof *cand);
    if (!cand)
        return 0;
    int got = 0;
    for (int mi = 0; mi < 4 && got == 0; mi++) {
        double margin = margins[mi] * fmin(w, h);
        for (int g = (int)ceil(2 * sqrt((double)n)); g <= GMAX; g *= 2) {
            uint32_t s = seed;
            int nc = 0;
            for (int i = 0; i < g; i++)
                for (int j = 0; j < g; j++) {
                    cm_vec2 q = cm_v2(fd->umin + w * (i + lcg(&s)) / g, fd->vmin + h * (j + lcg(&s)) / g);
                    if (face_domain_inside(fd, q) && (margin == 0 || face_domain_edge_dist(fd, q) >= margin))
                        cand[nc++] = q;
                }
            if (nc >= n || (g * 2 > GMAX && nc > 0)) {
                int k = nc > n ? n : nc;
                for (int i = 0; i < k; i++)
                    out[i] = cand[(long)i * nc / k];
                got = k;
                break;
            }
        }
    }
    free(cand);
    if (got == 0) {
        /* a sliver: step inward from the middle of each outer edge */
        const cm_vec2 *q = fd->uv + fd->loops[0].first;
        int m = fd->loops[0].n;
        double sgn = fd->loops[0].area >= 0 ? 1.0 : -1.0;
        for (int i = 0; i < m && got < n; i++) {
            cm_vec2 a = q[i], b = q[(i + 1) % m], d = cm_sub2(b, a);
            double len = sqrt(cm_dot2(d, d));
            if (!(len > 0))
                continue;
            cm_vec2 in = cm_v2(-d.y * sgn / len, d.x * sgn / len); /* left of a counter-clockwise edge */
            for (double eps = 1e-2; eps >= 1e-6; eps /= 10) {
                double step = eps * fmin(w, h);
                cm_vec2 c = cm_v2(0.5 * (a.x + b.x) + step * in.x, 0.5 * (a.y + b.y) + step * in.y);
                if (face_domain_inside(fd, c)) {
                    out[got++] = c;
                    break;
                }
            }
        }
    }
    return got;
}
