/* cm_tessellate.c - faces of a decoded model as triangles (see cm_tessellate.h). */
#include "cm/cm_tessellate.h"

#include <stddef.h>

#include "cm/cm_const.h"
#include "cm/cm_limits_info.h"
#include "cm/cm_method.h"

#define MAX_DOUBLINGS 12

/*
 * The work the tessellation does on one face is bounded by what the file's header declares, not
 * only by this build's limits (which on the workstation are large enough for any model, so one
 * damaged face could otherwise take minutes: a triangulation of 65536 points, sixteen times over).
 * The encoder measured the needs with this code at the file's tolerance: MAX_TESS_POINTS is the
 * most points any face used, MAX_EDGE_SAMPLES the most samples of any edge.  A face of a valid file
 * never reaches twice that (room for a newer decoder that refines a little more), so its output is
 * the same with or without the bound; a damaged face stops there.  A finer tolerance than the
 * file's (r times finer) scales the bound by 4 r^2: the points grow about as r, but refinement
 * doubles them in steps (a Gregory face of as1_pe_203 goes from 500 to 5420 points at r = 3); a
 * need of 0 (not declared: a model the encoder builds in memory) leaves the build's limit; a file
 * always declares them (cm_decode.c).
 */
static int declared_cap(uint32_t need, int slack, int limit, const cm_model *m, double tol)
{
    if (need == 0)
        return limit;
    double r = tol > 0 && m->tess_tol > tol ? m->tess_tol / tol : 1.0;
    double scale = r > 1.0 ? 4.0 * r * r : 1.0;
    double cap = (2.0 * (double)need + (double)slack) * scale;
    return cap < (double)limit ? (int)cap : limit;
}

int cm_tess_point_cap(const cm_model *m, double tol)
{
    return declared_cap(m->need_tess_points, 256, CM_MAX_TESS_POINTS, m, tol);
}

int cm_tess_edge_sample_cap(const cm_model *m, double tol)
{
    return declared_cap(m->need_edge_samples, 16, CM_MAX_EDGE_SAMPLES, m, tol);
}

/* The per-face caps bound one face; this one bounds the model.  Without it a header whose
   tolerance was set to 1e-300 mm (the needs left as they were) drives every face to its cap: a
   160-face model then decodes to 194 576 triangles in 0.9 s where the file declares 11 012 */
int cm_tess_triangle_cap(const cm_model *m, double tol)
{
    return declared_cap(m->need_tris, 1024, CM_MAX_TRIS, m, tol);
}

/* a face needs more points than `cap` (its budget, ws->point_cap, or an array's size): beyond this
   build's limit, or (a smaller budget) beyond what the header declares, which a valid file never is */
static cm_err over_budget(int cap, uint64_t need, cm_status *st, const char *where)
{
    if (cap >= CM_MAX_TESS_POINTS)
        return cm_fail_limit(st, CM_LIMIT_MAX_TESS_POINTS, need, CM_MAX_TESS_POINTS, where);
    if (st && st->code == CM_OK) {
        st->need = need;
        st->have = (uint64_t)cap;
    }
    return cm_fail(st, CM_E_RANGE, "tessellation: the face needs more points than the header declares "
                                   "(MAX_TESS_POINTS)");
}

cm_err cm_edge_params(const cm_model *m, uint32_t e, double tol, double *ts, cm_vec3 *pts, int cap, int *n_out,
                      cm_status *st)
{
    const cm_edge *E = &m->edges[e];
    int maxn = cap - 1 < CM_MAX_EDGE_SAMPLES - 1 ? cap - 1 : CM_MAX_EDGE_SAMPLES - 1;
    int declared = cm_tess_edge_sample_cap(m, tol) - 1;
    if (maxn > declared)
        maxn = declared;
    if (maxn < 1)
        return cm_fail_nospace(st, 2, (uint64_t)cap, __func__);
    /* an edge of an N-split GREGORY face needs its midpoint (t = 1/2) as a sample: both faces of the
       edge then sample it at an even count (spec 6.4: the sub-patches meet the edge there) */
    int even = m->edge_split[e] != 0 && maxn >= 2;
    cm_curve c;
    cm_model_edge_curve(m, e, &c);
    if (E->kind == CM_EDGE_LINE) {
        int nl = even ? 2 : 1;
        for (int i = 0; i <= nl; i++) {
            ts[i] = (double)i / (double)nl;
            cm_err err;
            if (pts && (err = cm_curve_eval(&c, ts[i], 0, &pts[i], st)) != CM_OK)
                return err;
        }
        *n_out = nl;
        return CM_OK;
    }
    /* start from one segment per knot span (at least 2), double until every chord fits */
    int spans = 1;
    for (int i = c.p + 1; i < c.n_ctrl; i++)
        if (c.knots[i] > c.knots[i - 1] && c.knots[i] < 1.0)
            spans++;
    int n = spans < 2 ? 2 : spans;
    if (n > maxn)
        n = maxn;
    int have = -1; /* the count whose points pts holds */
    for (int round = 0; round < MAX_DOUBLINGS; round++) {
        double worst = 0.0;
        cm_vec3 prev = cm_v3(0, 0, 0);
        for (int i = 0; i <= n; i++) {
            cm_vec3 d[1];
            cm_err err = cm_curve_eval(&c, (double)i / (double)n, 0, d, st);
            if (err != CM_OK)
                return err;
            if (pts)
                pts[i] = d[0];
            if (i > 0) {
                cm_vec3 mid[1];
                if ((err = cm_curve_eval(&c, ((double)i - 0.5) / (double)n, 0, mid, st)) != CM_OK)
                    return err;
                double dev = cm_dist(mid[0], cm_scale(cm_add(prev, d[0]), 0.5));
                if (dev > worst)
                    worst = dev;
            }
            prev = d[0];
        }
        have = n;
        if (worst <= tol || n >= maxn)
            break;
        n = 2 * n > maxn ? maxn : 2 * n;
    }
    if (even && n % 2 != 0)
        n = n + 1 <= maxn ? n + 1 : n - 1;
    for (int i = 0; i <= n; i++)
        ts[i] = (double)i / (double)n;
    ts[n] = 1.0;
    for (int i = 0; pts && have != n && i <= n; i++) {
        cm_err err = cm_curve_eval(&c, ts[i], 0, &pts[i], st);
        if (err != CM_OK)
            return err;
    }
    *n_out = n;
    return CM_OK;
}

static double poly_area(const cm_vec2 *p, int n)
{
    double a = 0;
    for (int i = 0, j = n - 1; i < n; j = i++)
        a += cm_cross2(p[j], p[i]);
    return 0.5 * a;
}

static void reverse_pts(cm_vec2 *p, int *src, int n)
{
    for (int i = 0; i < n / 2; i++) {
        cm_vec2 t = p[i];
        p[i] = p[n - 1 - i];
        p[n - 1 - i] = t;
        int s = src[i];
        src[i] = src[n - 1 - i];
        src[n - 1 - i] = s;
    }
}

/* the boundary points of every loop of face f, in use direction, into ws->bpts (patchwise: the face
 * is tessellated patch by patch, each holding itself to the budget).
 * Not inlined: gcc 12 then reports a (false) maybe-uninitialized in the caller. */
__attribute__((noinline)) static cm_err sample_boundary(const cm_model *m, const cm_face *F, double tol, int patchwise,
                                                        cm_tess_ws *ws, int *nb, cm_tess_info *info, cm_status *st)
{
    int k = 0;
    for (uint32_t l = 0; l < F->nloops; l++) {
        const cm_loop *L = &m->loops[F->loop0 + l];
        ws->loop_bstart[l] = k;
        for (uint32_t u = 0; u < L->nuse; u++) {
            const cm_use *U = &m->uses[L->use0 + u];
            int n;
            cm_err e = cm_edge_params(m, U->edge, tol, ws->ts, ws->epts, CM_MAX_EDGE_SAMPLES, &n, st);
            if (e != CM_OK)
                return e;
            if (n + 1 > info->max_edge_samples)
                info->max_edge_samples = n + 1;
            /* bpts holds CM_MAX_TESS_POINTS; a PLANE or KEEP face triangulates all of them at once,
               a GREGORY face a part per patch (tess_patch holds each patch to the budget) */
            int cap = patchwise ? CM_MAX_TESS_POINTS : ws->point_cap;
            if (k + n > cap)
                return over_budget(cap, (uint64_t)(k + n), st, __func__);
            if (l == 0 && u < CM_MAX_LOOP_EDGES) {
                ws->use_first[u] = k;
                ws->use_n[u] = n;
            }
            /* the use's start up to (not including) its end: the next use supplies that point */
            for (int i = 0; i < n; i++)
                ws->bpts[k++] = ws->epts[U->rev ? n - i : i];
        }
    }
    ws->loop_bstart[F->nloops] = k;
    *nb = k;
    return CM_OK;
}

/* a kept face's loops in (u,v), winding loops joined along the seam; fills uv/src/loop_start */
static cm_err keep_domain(const cm_psurf *ps, const cm_face *F, double accept, cm_tess_ws *ws, int *npts,
                          int *nloops_out, cm_tess_info *info, cm_status *st)
{
    int k = 0, nwind = 0, a = -1, b = -1;
    *npts = 0;
    *nloops_out = 0;
    for (uint32_t l = 0; l < F->nloops; l++) {
        int first = ws->loop_bstart[l], count = ws->loop_bstart[l + 1] - first, nout;
        ws->loop_start[l] = k;
        cm_err e = cm_loop_uv(ps, ws->bpts + first, count, accept, ws->uv + k, ws->src + k, ws->point_cap - k,
                              &nout, &ws->wind_u[l], &ws->wind_v[l], &info->max_gap, &ws->pw, st);
        if (e != CM_OK)
            return e;
        for (int i = 0; i < nout; i++)
            ws->src[k + i] += first;
        k += nout;
        if (ws->wind_u[l] || ws->wind_v[l]) {
            nwind++;
            if (a < 0)
                a = (int)l;
            else
                b = (int)l;
        }
    }
    ws->loop_start[F->nloops] = k;
    *npts = k;
    *nloops_out = (int)F->nloops;
    if (nwind == 0) {
        cm_loops_align(ps, ws->uv, ws->loop_start, (int)F->nloops);
        return CM_OK;
    }
    int along_u = ws->wind_u[a] != 0;
    if (nwind > 2 || (b >= 0 && (along_u ? ws->wind_u[b] == 0 : ws->wind_v[b] == 0)))
        return cm_fail(st, CM_E_UNSUPPORTED, "loops winding around the surface in two directions");
    /* x = the winding direction (coordinates swapped for a v-winding face); the lower loop must
     * run +x and the upper -x, so the band between them comes out counter-clockwise */
    double period = along_u ? ps->u1 - ps->u0 : ps->v1 - ps->v0;
    double mean[2] = {0, 0};
    for (int w = 0; w < 2; w++) {
        int l = w ? b : a;
        if (l < 0)
            continue;
        for (int i = ws->loop_start[l]; i < ws->loop_start[l + 1]; i++)
            mean[w] += along_u ? ws->uv[i].y : ws->uv[i].x;
        mean[w] /= (double)(ws->loop_start[l + 1] - ws->loop_start[l]);
    }
    int lo = a, hi = b;
    if (b >= 0 && mean[1] < mean[0]) {
        lo = b;
        hi = a;
    }
    int nlo = ws->loop_start[lo + 1] - ws->loop_start[lo];
    int nhi = hi >= 0 ? ws->loop_start[hi + 1] - ws->loop_start[hi] : 0;
    /* copies of the two loops, swapped to (x, y), in the triangulator's free point array */
    cm_vec2 *plo = ws->tri.p, *phi = ws->tri.p + nlo;
    int *slo = ws->ssrc, *shi = ws->ssrc + nlo;
    for (int i = 0; i < nlo + nhi; i++) {
        int from = i < nlo ? ws->loop_start[lo] + i : ws->loop_start[hi] + (i - nlo);
        cm_vec2 q = ws->uv[from];
        plo[i] = along_u ? q : cm_v2(q.y, q.x);
        slo[i] = ws->src[from];
    }
    int w_lo = along_u ? ws->wind_u[lo] : ws->wind_v[lo];
    double cap_coord = along_u ? ps->v1 : ps->u1;
    if (w_lo < 0)
        reverse_pts(plo, slo, nlo);
    if (hi >= 0 && (along_u ? ws->wind_u[hi] : ws->wind_v[hi]) > 0)
        reverse_pts(phi, shi, nhi);
    if (hi < 0 && !cm_winding_cap_high(w_lo, F->flip, along_u)) /* the band below a lone loop */
        cap_coord = along_u ? ps->v0 : ps->u0;
    int nj, hi_start = 0;
    cm_err e = cm_join_winding(plo, nlo, hi >= 0 ? phi : NULL, nhi, period, cap_coord, ws->tmp, ws->point_cap,
                               &nj, &hi_start, st);
    if (e != CM_OK)
        return e;
    /* sources of the joined polygon: lo, lo[0] again, hi from hi_start (unwrapped), or the cap (none) */
    for (int i = 0; i < nj; i++) {
        int s = -1;
        if (i < nlo)
            s = slo[i];
        else if (i == nlo)
            s = slo[0];
        else if (hi >= 0)
            s = shi[(hi_start + (i - nlo - 1)) % nhi];
        ws->src2[i] = s;
        if (!along_u)
            ws->tmp[i] = cm_v2(ws->tmp[i].y, ws->tmp[i].x);
    }
    /* the other loops (holes) follow the joined polygon */
    int out = nj, nl = 1;
    for (uint32_t l = 0; l < F->nloops; l++) {
        if ((int)l == a || (int)l == b)
            continue;
        int len = ws->loop_start[l + 1] - ws->loop_start[l];
        if (out + len > ws->point_cap)
            return over_budget(ws->point_cap, (uint64_t)(out + len), st, __func__);
        for (int i = 0; i < len; i++) {
            ws->tmp[out + i] = ws->uv[ws->loop_start[l] + i];
            ws->src2[out + i] = ws->src[ws->loop_start[l] + i];
        }
        ws->loop_start[nl++] = out;
        out += len;
    }
    ws->loop_start[0] = 0;
    ws->loop_start[nl] = out;
    for (int i = 0; i < out; i++) {
        ws->uv[i] = ws->tmp[i];
        ws->src[i] = ws->src2[i];
    }
    cm_loops_align(ps, ws->uv, ws->loop_start, nl);
    *npts = out;
    *nloops_out = nl;
    return CM_OK;
}

/*
 * The region in ws->tmp (scaled (u,v), about millimetres), triangulated.  A face whose boundary
 * runs back close along itself - a sliver of the region far narrower than the tolerance, as where
 * a spring's coil is ground flat - can cross itself by rounding in (u,v).  Then, in turn: triangles
 * folded over by at most a quarter of the tolerance are allowed (cm_triangulate_folds); the
 * boundary points are snapped to a grid of a quarter of the tolerance, then of the tolerance,
 * which makes such runs coincide (a slit, which the triangulator removes).  The 3D points stay
 * the edges' own, so the mesh stays closed; the fold is below the tolerance.
 */
/* format 4.7 on, boundaries of this many points go to the triangulator's Delaunay path first: a
   GREGORY patch's sides of a few hundred samples, ear-clipped into fans, cost a fifth of
   hex_nut_jam_am's decode in Lawson flips (cm_triangulate_cdt) */
#define TESS_CDT_FIRST_47 64
static cm_err triangulate(cm_tess_ws *ws, int npts, int nloops, double min_dist, double tol, int *ntris,
                          cm_status *st)
{
    /* format 4.7 on, the boundary alone, then the interior points as the refinement adds its own
       (cm_triangulate_more: no Lawson pass over the whole region after them) */
    int all = npts;
    if (ws->refine_47)
        npts = ws->loop_start[nloops];
    cm_status first;
    cm_status_init(&first);
    int cdt_first = ws->refine_47 ? TESS_CDT_FIRST_47 : 0;
    cm_err e = cm_triangulate_cdt(ws->tmp, npts, ws->loop_start, nloops, min_dist, 0.0, cdt_first, ws->tris,
                                  CM_MAX_TESS_TRIS, ntris, NULL, &ws->tri, &first);
    ws->folded = e == CM_E_DEGENERATE;
    for (int k = 0; e == CM_E_DEGENERATE && k < 3 && tol > 0; k++) {
        if (k > 0) {
            double grid = k == 1 ? 0.25 * tol : tol;
            for (int i = 0; i < ws->loop_start[nloops]; i++)
                ws->tmp[i] = cm_v2(grid * floor(ws->tmp[i].x / grid + 0.5), grid * floor(ws->tmp[i].y / grid + 0.5));
        }
        cm_status again;
        cm_status_init(&again);
        e = cm_triangulate_cdt(ws->tmp, npts, ws->loop_start, nloops, min_dist, 0.25 * tol, cdt_first, ws->tris,
                               CM_MAX_TESS_TRIS, ntris, NULL, &ws->tri, &again);
    }
    if (e != CM_OK && st && st->code == CM_OK) {
        /* report the first attempt's failure: it names the original geometry (and return its code:
           a status and a return that disagree broke the fuzz contract, issue 10) */
        *st = first;
        return first.code != CM_OK ? first.code : e;
    }
    if (e == CM_OK && all > npts)
        e = cm_triangulate_more(ws->tmp, all, min_dist, ws->tris, CM_MAX_TESS_TRIS, ntris, &ws->tri, st);
    return e;
}

/* rounds of refinement of a curved face's triangulation (each at most doubles the points locally;
 * it stops when a round adds none).  Four left triangles 0.99 mm off a B-spline face of occ22470
 * at a 0.117 mm tolerance (Open CASCADE measured); sixteen bring every corpus face within it at the
 * file's tolerance, but not at a finer one: asitus__IAD_v3's 337 mm six-sided G1FIT faces at a
 * tenth of it (0.027 mm) still added 800 points in the sixteenth round and left triangles 0.73 mm
 * off the surface; they settle in 24 to 26.  The rounds only bound a face that never settles (a
 * damaged one), whose points the header's needs bound anyway (declared_cap). */
#define TESS_REFINE_ROUNDS 64

/* what a face's (u,v) means: the plane's frame, a kept NURBS, or one patch of a GREGORY-family face */
enum { CHART_FRAME, CHART_NURBS, CHART_GREGORY };
typedef struct chart {
    int kind;
    const cm_psurf *ps;     /* KEEP */
    const cm_frame *frame;  /* PLANE */
    const cm_greg_surface *gs; /* GREGORY family: the patches ... */
    int patch;              /* ... and which */
    double sign;            /* the face normal is sign * (Su x Sv) */
    int off_surface;        /* NURBS rebuilt to a tolerance (NFILL, G1FIT; a kept net from 4.1): the loop's points lie up to it off
                               the surface, so the refinement measures from the surface's own points */
    cm_egreg_memo *memo;    /* GREGORY family: the patch's side evaluations (reset for each patch) */
} chart;

/* point and first partials at (u,v) */
static cm_err chart_eval(const chart *c, double u, double v, cm_vec3 d[3], cm_status *st)
{
    if (c->kind == CHART_NURBS)
        return cm_psurf_eval(c->ps, u, v, d, st);
    if (c->kind == CHART_GREGORY) {
        cm_err e = cm_greg_surface_eval_memo(c->gs, c->patch, u, v, &d[0], &d[1], &d[2], c->memo);
        if (e != CM_OK)
            return cm_fail(st, e, "Gregory patch");
        return cm_finite3(d[0]) ? CM_OK : cm_fail(st, CM_E_NONFINITE, "Gregory patch");
    }
    d[0] = cm_frame_world(c->frame, cm_v3(u, v, 0));
    d[1] = c->frame->ex;
    d[2] = c->frame->ey;
    return CM_OK;
}

/* the unit normal sign * (Su x Sv) / |Su x Sv| of an evaluation d, turned to the face; 0 where it
   degenerates (a pole, a collapsed Gregory side) */
static int unit_normal(const chart *c, const cm_vec3 d[3], cm_vec3 *N)
{
    cm_vec3 n = cm_cross(d[1], d[2]);
    double l = cm_norm(n);
    if (!(l > CM_EPS_CROSS_REL * cm_norm(d[1]) * cm_norm(d[2]) && l > 0))
        return 0;
    *N = cm_scale(n, c->sign / l);
    return 1;
}

/*
 * The unit normal of point i from its evaluation d (the refinement's), as emit_region writes it:
 * chart_normal at the same (u,v) evaluates the same bits again, one surface evaluation per vertex.
 * Where the normal degenerates (a pole) none is kept, and chart_normal borrows one from nearby.
 */
static void keep_normal(const chart *c, cm_tess_ws *ws, int i, const cm_vec3 d[3])
{
    ws->has_nrm[i] = (unsigned char)unit_normal(c, d, &ws->nrm[i]);
}

/*
 * 3D position of triangulation point i: a boundary point is its curve's own point, except, for the
 * refinement's flatness tests (`test`) on a surface the loop is not on (off_surface), the surface's
 * point at its (u,v): there the loop is up to the rebuild tolerance off the surface, and measured
 * from it the triangles along the loop would never pass (C1G0B0O: 36 NFILL faces doubled the
 * model's triangles).  The emitted mesh always takes the curve's point (watertight).
 */
static cm_err point_xyz(const chart *c, cm_tess_ws *ws, int i, int test, cm_status *st)
{
    if (ws->src[i] >= 0 && !(test && c->off_surface)) {
        ws->xyz[i] = ws->bpts[ws->src[i]];
        if (test) {
            /* format 4.7 on, its normal (s_shaped needs it; emit_region would evaluate it anyway,
               and where that fails borrow one: so none is kept then, and the face goes on) */
            cm_vec3 d[3];
            ws->has_nrm[i] = 0;
            if (ws->refine_47 && chart_eval(c, ws->uv[i].x, ws->uv[i].y, d, NULL) == CM_OK)
                keep_normal(c, ws, i, d);
        }
        return CM_OK;
    }
    cm_vec3 d[3];
    cm_err e = chart_eval(c, ws->uv[i].x, ws->uv[i].y, d, st);
    ws->xyz[i] = d[0];
    if (test)
        keep_normal(c, ws, i, d);
    return e;
}

/* how far the flat mesh's point `flat` is from the surface's S(uv), along the surface normal: the
 * parametrisation's own distortion (a rational arc's parameter midpoint is not its angular
 * midpoint) moves S(uv) along the surface, which is no error; d gets S(uv) and its partials */
static cm_err deviation(const chart *c, cm_vec2 uv, cm_vec3 flat, double *dev, cm_vec3 d[3], cm_status *st)
{
    cm_err e = chart_eval(c, uv.x, uv.y, d, st);
    if (e != CM_OK)
        return e;
    cm_vec3 n = cm_cross(d[1], d[2]), off = cm_sub(d[0], flat);
    double ln = cm_norm(n);
    *dev = ln > CM_EPS_CROSS_REL * cm_norm(d[1]) * cm_norm(d[2]) && ln > 0 ? fabs(cm_dot(off, n)) / ln : cm_norm(off);
    return CM_OK;
}

/*
 * A piece of the flat mesh (a triangle or an inner side) tested at `n` points: uv[k] in (u,v),
 * flat[k] on the flat mesh.  The point farthest from the surface, if farther than tol, is added to
 * the triangulation (one point per piece, so a round at most doubles the points locally).
 */
static cm_err refine_worst(const chart *c, cm_tess_ws *ws, const cm_vec2 *uv, const cm_vec3 *flat, int n, double tol,
                           double su, double sv, int *npts, cm_status *st)
{
    double worst = tol;
    int at = -1;
    cm_vec3 at_d[3];
    for (int k = 0; k < n; k++) {
        double dev;
        cm_vec3 d[3];
        cm_err e = deviation(c, uv[k], flat[k], &dev, d, st);
        if (e != CM_OK)
            return e;
        if (dev > worst) {
            worst = dev;
            at = k;
            at_d[0] = d[0];
            at_d[1] = d[1];
            at_d[2] = d[2];
        }
    }
    if (at < 0 || *npts >= ws->point_cap)
        return CM_OK;
    int k = (*npts)++;
    ws->uv[k] = uv[at];
    ws->tmp[k] = cm_v2(uv[at].x * su, uv[at].y * sv);
    ws->src[k] = -1;
    ws->xyz[k] = at_d[0];
    keep_normal(c, ws, k, at_d);
    return CM_OK;
}

/* i -> j (i < j) is a segment of a boundary loop (consecutive points of one loop) */
static int boundary_side(const int *loop_start, int nloops, int nbnd, int i, int j)
{
    if (i >= nbnd || j >= nbnd)
        return 0;
    for (int l = 0; l < nloops; l++) {
        int a = loop_start[l], b = loop_start[l + 1];
        if (i >= a && i < b)
            return j < b && (j == i + 1 || (i == a && j == b - 1));
    }
    return 0;
}

/* unit normal at (u,v), turned to the face; a degenerate point (a pole, a collapsed Gregory side)
 * borrows the normal a little towards `toward` */
static cm_vec3 chart_normal(const chart *c, double u, double v, cm_vec2 toward)
{
    if (c->kind == CHART_FRAME)
        return c->frame->ez;
    for (int k = 0; k < 4; k++) {
        double s = k == 0 ? 0.0 : (k == 1 ? 1e-6 : (k == 2 ? 1e-4 : 1e-2));
        cm_vec3 d[3], N;
        if (chart_eval(c, u + s * (toward.x - u), v + s * (toward.y - v), d, NULL) != CM_OK)
            break;
        if (unit_normal(c, d, &N))
            return N;
    }
    return cm_v3(0, 0, c->sign);
}

/* a triangle of the flat mesh tested inside: at its centre, and (before format 4.7) halfway from it
   to each corner.  Those three found nothing the centre and the sides' tests would not: over the
   corpus at the bench's deflections the deviation measured by Open CASCADE is the same with and
   without them, the triangles within 1 % (issue 15) */
static cm_err test_triangle(const chart *c, cm_tess_ws *ws, const int *tc, double tol, double su, double sv,
                            int *npts, cm_status *st)
{
    cm_vec2 tuv[4];
    cm_vec3 txyz[4];
    int nq = ws->refine_47 ? 1 : 4;
    for (int q = 0; q < nq; q++) {
        double w[3] = {1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0};
        if (q > 0)
            for (int k = 0; k < 3; k++)
                w[k] = k == q - 1 ? 2.0 / 3.0 : 1.0 / 6.0;
        tuv[q] = cm_v2(w[0] * ws->uv[tc[0]].x + w[1] * ws->uv[tc[1]].x + w[2] * ws->uv[tc[2]].x,
                       w[0] * ws->uv[tc[0]].y + w[1] * ws->uv[tc[1]].y + w[2] * ws->uv[tc[2]].y);
        txyz[q] = cm_add(cm_add(cm_scale(ws->xyz[tc[0]], w[0]), cm_scale(ws->xyz[tc[1]], w[1])),
                         cm_scale(ws->xyz[tc[2]], w[2]));
    }
    return refine_worst(c, ws, tuv, txyz, nq, tol, su, sv, npts, st);
}

/*
 * Is the surface along the side i -> j shaped like an S, by the normals at its ends
 * (cm_chord_s_part)?  Where the S part of the cubic with the ends' slopes is at most a quarter of
 * the tolerance, the quarter points cannot fail when the midpoint passes (3/4 of its error plus
 * that quarter), and are not tested: two of a side's three surface evaluations, most of the
 * refinement's (issue 15).  Without both normals (a boundary point whose evaluation failed, a
 * pole) they are tested.
 */
static int s_shaped(const cm_tess_ws *ws, int i, int j, double tol)
{
    if (!ws->has_nrm[i] || !ws->has_nrm[j])
        return 1;
    return !(cm_chord_s_part(ws->xyz[i], ws->nrm[i], ws->xyz[j], ws->nrm[j]) <= 0.25 * tol);
}

/*
 * Format 4.8: is a piece of the flat mesh within a quarter of the tolerance by the normals at its
 * corners alone?  A side's sag is predicted by the cubic through its ends with the ends' slopes:
 * its C part at the middle (cm_chord_c_part) plus its S part (cm_chord_s_part).  A triangle's at
 * its centre by the quadratic triangle whose sides sag that much: 4/9 of the sum of its sides'
 * (the centre's weight of a side's middle control point is 2/9, and that point lies twice the
 * side's sag off).  Such a piece passes without a test.  Over the 36 corpus models at the bench's
 * deflections, the pieces it passes measured at most 0.86 of the tolerance when tested anyway (19
 * above a half), so none would have failed and each mesh is the one testing them makes; half to
 * 86 % of the sides' tests and a fifth to four fifths of the triangles' are spared (a cylinder's or
 * a fillet's sides along its lines predict 0).  What it cannot see is a bump that leaves no trace in its corners' normals (a
 * side rising and falling back between equal normals); the pieces it judges are those the interior
 * grid and the rounds before made, whose corners sample the surface as densely as the boundary's
 * sampling (GREGORY) or its curvature (a kept surface) asks, so such a bump is narrower than a cell,
 * where the tests at one to three points before 4.8 miss as much.  A corner without a normal (a
 * pole, a failed evaluation): tested.
 */
static double side_sag(const cm_tess_ws *ws, int i, int j)
{
    return cm_chord_c_part(ws->xyz[i], ws->nrm[i], ws->xyz[j], ws->nrm[j]) +
           cm_chord_s_part(ws->xyz[i], ws->nrm[i], ws->xyz[j], ws->nrm[j]);
}

static int side_flat(const cm_tess_ws *ws, int i, int j, double tol)
{
    return ws->has_nrm[i] && ws->has_nrm[j] && side_sag(ws, i, j) <= 0.25 * tol;
}

static int triangle_flat(const cm_tess_ws *ws, const int *tc, double tol)
{
    if (!ws->has_nrm[tc[0]] || !ws->has_nrm[tc[1]] || !ws->has_nrm[tc[2]])
        return 0;
    double sag = side_sag(ws, tc[0], tc[1]) + side_sag(ws, tc[1], tc[2]) + side_sag(ws, tc[2], tc[0]);
    return 4.0 / 9.0 * sag <= 0.25 * tol;
}

/* an inner side i -> j tested at its midpoint and quarter points (the surface's error along a long
   side need not peak in the middle; format 4.7 on, the quarter points only where the side may be
   S-shaped: s_shaped) */
static cm_err test_side(const chart *c, cm_tess_ws *ws, int i, int j, double tol, double su, double sv, int *npts,
                        cm_status *st)
{
    cm_vec2 suv[3];
    cm_vec3 sxyz[3];
    int nq = !ws->refine_47 || s_shaped(ws, i, j, tol) ? 3 : 1;
    for (int q = 0; q < nq; q++) {
        double s = q == 0 ? 0.5 : (q == 1 ? 0.25 : 0.75);
        suv[q] = cm_v2((1 - s) * ws->uv[i].x + s * ws->uv[j].x, (1 - s) * ws->uv[i].y + s * ws->uv[j].y);
        sxyz[q] = cm_add(cm_scale(ws->xyz[i], 1 - s), cm_scale(ws->xyz[j], s));
    }
    return refine_worst(c, ws, suv, sxyz, nq, tol, su, sv, npts, st);
}

/*
 * What passed the deviation test in the last round.  The test of a triangle (its corners in the
 * triangulator's order) or of an inner side (i < j) depends on nothing but its corners, which never
 * move; the triangulation is rebuilt each round, but far from the points just added it comes out
 * the same, and such pieces used to be tested again, round after round (27-35 surface evaluations
 * per output vertex, issue 15).  A piece found in the last round's table is passed again without
 * a test, so the output is the same as testing it.  Open addressing in a table sized to the round
 * (at most CM_TESS_PASS_SLOTS), filled to half at most: a piece that finds no room is tested again
 * next round, which costs only time.
 */
typedef struct pass_table {
    uint64_t *key; /* 0: empty */
    uint32_t mask; /* slots - 1 */
    uint32_t n, room;
} pass_table;

static uint64_t tri_key(const int *tc)
{
    return (UINT64_C(1) << 63) | ((uint64_t)tc[0] << 42) | ((uint64_t)tc[1] << 21) | (uint64_t)tc[2];
}

static uint64_t side_key(int i, int j) { return (UINT64_C(1) << 62) | ((uint64_t)i << 21) | (uint64_t)j; }

static uint32_t pass_slot(uint64_t k, uint32_t mask)
{
    k ^= k >> 31;
    k *= UINT64_C(0x9e3779b97f4a7c15);
    k ^= k >> 29;
    return (uint32_t)k & mask;
}

/* an empty table of at least 4 `pieces` slots (fewer when the build, or ws->pass_slots, has fewer) */
static void pass_begin(pass_table *t, const cm_tess_ws *ws, uint64_t *key, int pieces)
{
    uint32_t cap = ws->pass_slots > 0 && ws->pass_slots < CM_TESS_PASS_SLOTS ? ws->pass_slots : CM_TESS_PASS_SLOTS;
    uint32_t slots = 1;
    while (slots < cap && slots < 4u * (uint32_t)pieces)
        slots *= 2;
    for (uint32_t s = 0; s < slots; s++)
        key[s] = 0;
    t->key = key;
    t->mask = slots - 1;
    t->n = 0;
    t->room = slots / 2;
}

static int pass_has(const pass_table *t, uint64_t k)
{
    for (uint32_t s = pass_slot(k, t->mask), probes = 0; probes <= t->mask; s = (s + 1) & t->mask, probes++) {
        if (t->key[s] == k)
            return 1;
        if (t->key[s] == 0)
            return 0;
    }
    return 0;
}

static void pass_add(pass_table *t, uint64_t k)
{
    if (t->n >= t->room)
        return;
    uint32_t s = pass_slot(k, t->mask);
    while (t->key[s] != 0 && t->key[s] != k)
        s = (s + 1) & t->mask;
    if (t->key[s] == 0)
        t->n++;
    t->key[s] = k;
}

/* a piece that passed last round passes again untested (1), counted in ws->skipped */
static int pass_again(const pass_table *last, pass_table *now, cm_tess_ws *ws, uint64_t key)
{
    if (!last->key || !pass_has(last, key))
        return 0;
    pass_add(now, key);
    ws->skipped++;
    return 1;
}

/*
 * Refinement of curved charts: an interior grid follows curvature sampled at a few points, which
 * misses peaks (a rational arc's parameter speed varies along it), and triangles reaching from the
 * boundary to the grid can be wider than a cell.  Each triangle is tested at its centre and halfway
 * from there to each corner, each inner side at its midpoint and quarter points (a long side's
 * error need not peak in its middle: a hull's bilge turns faster at one end); a triangle or side
 * with a point farther than tol from the surface gets its farthest point, and the region is
 * triangulated again; a few rounds bring every such point within tol.  Format 4.7 on, a triangle
 * is tested at its centre only, a side at its quarter points only where it may be S-shaped
 * (s_shaped), and the points a round adds go into the last round's triangulation
 * (cm_triangulate_more) instead of a new one: a third to a half of a decode's instructions.
 */
static cm_err refine_region(const chart *c, cm_tess_ws *ws, int *npts_io, int *ntris_io, int nloops,
                            double min_dist, double tol, double su, double sv, int *nsurface, cm_status *st)
{
    int npts = *npts_io, ntris = *ntris_io, nxyz = 0, nbnd = ws->loop_start[nloops];
    cm_err e = CM_OK;
    pass_table last = {NULL, 0, 0, 0}, now;
    for (int round = 0; c->kind != CHART_FRAME && round < TESS_REFINE_ROUNDS; round++) {
        for (; nxyz < npts; nxyz++)
            if ((e = point_xyz(c, ws, nxyz, 1, st)) != CM_OK)
                return e;
        pass_begin(&now, ws, ws->passed[round & 1], ntris + ntris / 2 * 3);
        int before = npts;
        for (int t = 0; t < ntris && npts < ws->point_cap; t++) {
            const int *tc = ws->tris[t];
            uint64_t key = tri_key(tc);
            int passed = pass_again(&last, &now, ws, key);
            if (!passed && ws->refine_48 && !ws->test_every_piece && triangle_flat(ws, tc, tol)) {
                pass_add(&now, key);
                ws->predicted++;
                passed = 1;
            }
            if (!passed) {
                int tested = npts;
                ws->tested++;
                if ((e = test_triangle(c, ws, tc, tol, su, sv, &npts, st)) != CM_OK)
                    return e;
                if (npts == tested && npts < ws->point_cap)
                    pass_add(&now, key);
            }
            for (int k = 0; k < 3 && npts < ws->point_cap; k++) {
                int i = tc[k], j = tc[(k + 1) % 3];
                if (j < i) /* each inner side once, from the triangle that has it as i -> j, i < j */
                    continue;
                if (boundary_side(ws->loop_start, nloops, nbnd, i, j))
                    continue;
                uint64_t skey = side_key(i, j);
                if (pass_again(&last, &now, ws, skey))
                    continue;
                if (ws->refine_48 && !ws->test_every_piece && side_flat(ws, i, j, tol)) {
                    pass_add(&now, skey);
                    ws->predicted++;
                    continue;
                }
                int tested = npts;
                ws->tested++;
                if ((e = test_side(c, ws, i, j, tol, su, sv, &npts, st)) != CM_OK)
                    return e;
                if (npts == tested && npts < ws->point_cap)
                    pass_add(&now, skey);
            }
        }
        /* the points just added carry their surface point (refine_worst): not evaluated again */
        nxyz = npts;
        if (npts == before)
            break;
        last = now;
        min_dist *= 0.5;
        /* format 4.7 on: the points just added go into the last round's triangulation, except in a
           region whose boundary crosses itself by rounding (the fold fallback, ws->folded): that is
           triangulated afresh each round as before 4.7, since its folded triangles are what the
           encoder looks for in a re-approximated net (needs.c: occt__bug22869_Spring's coil, whose
           net a quarter off the surface then stays 0.12 mm off the model without a fold) */
        if (ws->refine_47 && !ws->folded)
            e = cm_triangulate_more(ws->tmp, npts, min_dist, ws->tris, CM_MAX_TESS_TRIS, &ntris, &ws->tri, st);
        else
            e = triangulate(ws, npts, nloops, min_dist, tol, &ntris, st);
        if (e != CM_OK)
            return e;
    }
    *npts_io = npts;
    *ntris_io = ntris;
    *nsurface = nxyz; /* points [0, nxyz) off the boundary have their surface point in ws->xyz */
    return CM_OK;
}

/*
 * Append the triangulated region to the mesh (vertices and indices, no face record): positions of
 * the used points, boundary vertices the curves' own points.  A triangle with two corners at one
 * point of the output (a pole, a collapsed Gregory side, corners closer than float resolution) has
 * no area: it is dropped.  Its two other sides are then the same segment both ways, so its
 * neighbours meet directly and the mesh stays closed.  Triangles are counter-clockwise in (u,v),
 * around Su x Sv; `turn` reverses them.
 */
static cm_err emit_region(const chart *c, cm_tess_ws *ws, int npts, int nsurface, int ntris, cm_vec2 centre,
                          int turn, cm_mesh *mesh, int *emitted, cm_status *st)
{
    cm_err e;
    for (int i = 0; i < npts; i++)
        ws->vmap[i] = UINT32_MAX;
    for (int t = 0; t < ntris; t++)
        for (int k = 0; k < 3; k++)
            ws->vmap[ws->tris[t][k]] = 0;
    /* a boundary point takes its curve's point; an interior one the refinement evaluated keeps it
       (point_xyz would evaluate the same (u,v) again: the same bits) */
    for (int i = 0; i < npts; i++)
        if (ws->vmap[i] != UINT32_MAX && (i >= nsurface || ws->src[i] >= 0) &&
            (e = point_xyz(c, ws, i, 0, st)) != CM_OK)
            return e;
    int kept_tris = 0;
    for (int t = 0; t < ntris; t++) {
        const int *tc = ws->tris[t];
        int flat = 0;
        for (int k = 0; k < 3; k++) {
            cm_vec3 a = ws->xyz[tc[k]], b = ws->xyz[tc[(k + 1) % 3]];
            flat |= (float)a.x == (float)b.x && (float)a.y == (float)b.y && (float)a.z == (float)b.z;
        }
        if (flat)
            continue;
        for (int k = 0; k < 3; k++)
            ws->tris[kept_tris][k] = tc[k];
        kept_tris++;
    }
    ntris = kept_tris;
    for (int i = 0; i < npts; i++)
        ws->vmap[i] = UINT32_MAX;
    uint32_t nv = 0;
    for (int t = 0; t < ntris; t++)
        for (int k = 0; k < 3; k++)
            if (ws->vmap[ws->tris[t][k]] == UINT32_MAX)
                ws->vmap[ws->tris[t][k]] = nv++;
    if (nv > mesh->cap_verts - mesh->nverts)
        return cm_fail_limit(st, CM_LIMIT_MAX_TRIS, (uint64_t)mesh->nverts + nv, mesh->cap_verts, __func__);
    if ((uint64_t)ntris * 3 > (uint64_t)(mesh->cap_index - mesh->nindex))
        return cm_fail_limit(st, CM_LIMIT_MAX_TRIS, ((uint64_t)mesh->nindex + 3u * (uint64_t)ntris) / 3,
                             mesh->cap_index / 3, __func__);
    cm_err room = cm_mesh_make_room(mesh, nv, 3u * (uint32_t)ntris, st); /* a streaming mesh's window */
    if (room != CM_OK)
        return room;
    uint32_t base = mesh->nverts;
    for (int i = 0; i < npts; i++) {
        if (ws->vmap[i] == UINT32_MAX)
            continue;
        cm_vec3 P = ws->xyz[i];
        cm_vec3 N = i < nsurface && ws->has_nrm[i] ? ws->nrm[i] : chart_normal(c, ws->uv[i].x, ws->uv[i].y, centre);
        uint32_t k = base + ws->vmap[i];
        float *p = cm_mesh_wpos(mesh, k), *n = cm_mesh_wnrm(mesh, k);
        p[0] = (float)P.x;
        p[1] = (float)P.y;
        p[2] = (float)P.z;
        n[0] = (float)N.x;
        n[1] = (float)N.y;
        n[2] = (float)N.z;
    }
    for (int t = 0; t < ntris; t++) {
        uint32_t *ix = cm_mesh_widx(mesh, mesh->nindex + 3 * (uint32_t)t);
        ix[0] = base + ws->vmap[ws->tris[t][0]];
        ix[1] = base + ws->vmap[ws->tris[t][turn ? 2 : 1]];
        ix[2] = base + ws->vmap[ws->tris[t][turn ? 1 : 2]];
    }
    mesh->nverts += nv;
    mesh->nindex += 3u * (uint32_t)ntris;
    *emitted = ntris;
    return CM_OK;
}

/* open a face record for the vertices and indices appended from here on */
static cm_err begin_face(const cm_model *m, uint32_t f, cm_mesh *mesh, cm_mesh_face **mf, cm_status *st)
{
    const cm_face *F = &m->faces[f];
    if (mesh->nfaces >= mesh->cap_faces)
        return cm_fail_limit(st, CM_LIMIT_MAX_FACES, (uint64_t)mesh->nfaces + 1, mesh->cap_faces, __func__);
    *mf = &mesh->faces[mesh->nfaces];
    (*mf)->first_vert = mesh->nverts;
    (*mf)->first_index = mesh->nindex;
    (*mf)->nverts = (*mf)->nindex = 0;
    (*mf)->has_color = F->color != 0;
    (*mf)->rgb = F->color ? m->palette[F->color] : 0;
    (*mf)->source_face = f;
    return CM_OK;
}

static void end_face(cm_mesh *mesh, cm_mesh_face *mf)
{
    mf->nverts = mesh->nverts - mf->first_vert;
    mf->nindex = mesh->nindex - mf->first_index;
    mesh->nfaces++;
}

/* ---- GREGORY faces: patch by patch, the curve mesh's samples on the outside ---- */

/* points of a cubic (an N-split's internal curve) at s = i/n with every chord within tol */
static int cubic_segments(const cm_cubic *c, double tol, int maxn)
{
    int n = 2;
    for (int round = 0; round < MAX_DOUBLINGS; round++) {
        double worst = 0.0;
        cm_vec3 d[3], prev;
        cm_cubic_eval(c, 0.0, d);
        prev = d[0];
        for (int i = 1; i <= n; i++) {
            cm_cubic_eval(c, (double)i / (double)n, d);
            cm_vec3 q = d[0];
            cm_cubic_eval(c, ((double)i - 0.5) / (double)n, d);
            double dev = cm_dist(d[0], cm_scale(cm_add(prev, q), 0.5));
            worst = dev > worst ? dev : worst;
            prev = q;
        }
        if (worst <= tol || n >= maxn)
            break;
        n = 2 * n > maxn ? maxn : 2 * n;
    }
    return n;
}

/* append boundary point (u,v) whose 3D point is bpts[src] */
static cm_err add_bnd(cm_tess_ws *ws, int *k, double u, double v, int src, cm_status *st)
{
    if (*k >= ws->point_cap)
        return over_budget(ws->point_cap, (uint64_t)*k + 1, st, __func__);
    ws->uv[*k] = cm_v2(u, v);
    ws->src[*k] = src;
    (*k)++;
    return CM_OK;
}

/* points of outer-loop use `u` from its sample a up to (not including) b, at side parameter
 * s = (i - a) / (b - a) mapped by (u0 + du s, v0 + dv s) */
static cm_err add_use(cm_tess_ws *ws, int *k, int use, int a, int b, double u0, double v0, double du, double dv,
                      cm_status *st)
{
    cm_err e = CM_OK;
    for (int i = a; i < b && e == CM_OK; i++) {
        double s = (double)(i - a) / (double)(b - a);
        e = add_bnd(ws, k, u0 + du * s, v0 + dv * s, ws->use_first[use] + i, st);
    }
    return e;
}

/*
 * Format 4.10: a patch's speeds along u and v, as the plane of triangulation scales them, from its
 * boundary: the mean of the lengths of its two sides along u (v = 0 and v = 1) and of its two along
 * v, measured on the boundary's points (the curve mesh's samples, already there).  Before, the mean
 * of |Su| and |Sv| at 5 x 5 interior points: 25 evaluations of the patch with derivatives before
 * its first triangle, a third of the Gregory evaluations of a model of small faces
 * (Tightening_screw: 2306 of 7443) for a scale that only shapes the triangles.  Over the 34 corpus
 * models at the bench's deflections the same triangle counts (but occ22470's 3118 -> 3114) and Open
 * CASCADE's deviation the same, the terminal's instructions -18 % to 0 % (Shelt_channel_5 287.6 ->
 * 237.0 M, ovt__asmo 162.2 -> 143.4 M; none saved without a GREGORY face).
 * A side collapsed to a point (layout 2) counts 0: half the other.
 */
static void patch_scale(const cm_tess_ws *ws, int npts, double *su, double *sv)
{
    double len[4] = {0, 0, 0, 0};
    for (int i = 0; i < npts; i++) {
        int j = i + 1 < npts ? i + 1 : 0;
        cm_vec2 a = ws->uv[i], b = ws->uv[j];
        /* the boundary runs v = 0, u = 1, v = 1 (backwards), u = 0: a segment on one of them */
        int side = a.y == 0.0 && b.y == 0.0 ? 0 : a.x == 1.0 && b.x == 1.0 ? 1 : a.y == 1.0 && b.y == 1.0 ? 2
                 : a.x == 0.0 && b.x == 0.0 ? 3 : -1;
        if (side >= 0 && ws->src[i] >= 0 && ws->src[j] >= 0)
            len[side] += cm_dist(ws->bpts[ws->src[i]], ws->bpts[ws->src[j]]);
    }
    *su = 0.5 * (len[0] + len[2]);
    *sv = 0.5 * (len[1] + len[3]);
}

/* one Gregory patch whose boundary polygon is in ws->uv/src [0, npts): triangulate, refine, emit */
static cm_err tess_patch(const cm_greg_surface *gs, int patch, cm_tess_ws *ws, int npts, int side_n[4], double tol, cm_mesh *mesh,
                         cm_tess_info *info, cm_status *st)
{
    chart c = {CHART_GREGORY, NULL, NULL, gs, patch, 1.0, 0, &ws->egreg_memo};
    cm_egreg_memo_reset(c.memo);
    cm_err e;
    ws->loop_start[0] = 0;
    ws->loop_start[1] = npts;
    /* scale (u,v) by the patch's speeds, so triangles are well shaped in 3D */
    double su = 0, sv = 0;
    if (ws->refine_410)
        patch_scale(ws, npts, &su, &sv);
    else
        for (int i = 0; i < 5; i++)
            for (int j = 0; j < 5; j++) {
                cm_vec3 d[3];
                if ((e = chart_eval(&c, (i + 0.5) / 5.0, (j + 0.5) / 5.0, d, st)) != CM_OK)
                    return e;
                su += cm_norm(d[1]) / 25.0;
                sv += cm_norm(d[2]) / 25.0;
            }
    if (!(su > 0) || !(sv > 0))
        su = sv = 1.0;
    /* interior grid as fine as the boundary's sampling (refinement adds where the surface curves).
       (A grid no finer than the patch's curvature asks, estimated from its first derivatives on
       the 5 x 5 samples, saved 12 % of hex_nut_jam_am's decode but let the mesh stray further:
       Open CASCADE measured OCC8842_cylinder_CATIA 0.066 -> 0.127 mm, xnurbs_fillet-complex
       0.67 -> 1.03 mm at a 0.62 mm deflection: the tests at a triangle's centre and a side's
       middle miss more between them on the larger triangles.  Not taken.) */
    int nu = side_n[0] > side_n[2] ? side_n[0] : side_n[2], nv = side_n[1] > side_n[3] ? side_n[1] : side_n[3];
    double room = (double)(CM_MAX_TESS_POINTS - npts) * 0.5;
    if ((double)nu * (double)nv > room && room >= 1) {
        double shrink = sqrt(room / ((double)nu * (double)nv));
        nu = (int)ceil((double)nu * shrink);
        nv = (int)ceil((double)nv * shrink);
    }
    /* a grid that does not fit the face's budget at all (never so for a valid file) is shrunk the
       same way, to half the room the budget leaves */
    room = (double)(ws->point_cap - npts) * 0.5;
    if ((double)nu * (double)nv > 2.0 * room && room >= 1) {
        double shrink = sqrt(room / ((double)nu * (double)nv));
        nu = (int)ceil((double)nu * shrink);
        nv = (int)ceil((double)nv * shrink);
    }
    int interior = 0;
    if (nu > 1 || nv > 1)
        for (int i = 0; i < nu && npts < ws->point_cap; i++)
            for (int j = 0; j < nv && npts < ws->point_cap; j++) {
                ws->uv[npts] = cm_v2((i + 0.5) / nu, (j + 0.5) / nv);
                ws->src[npts++] = -1;
                interior++;
            }
    for (int i = 0; i < npts; i++)
        ws->tmp[i] = cm_v2(ws->uv[i].x * su, ws->uv[i].y * sv);
    double cu = su / nu, cv = sv / nv;
    double min_dist = interior > 0 ? 0.25 * (cu < cv ? cu : cv) : 0.0;
    int ntris = 0, emitted = 0;
    if ((e = triangulate(ws, npts, 1, min_dist, tol, &ntris, st)) != CM_OK)
        return e;
    int nsurface = 0;
    if ((e = refine_region(&c, ws, &npts, &ntris, 1, min_dist, tol, su, sv, &nsurface, st)) != CM_OK)
        return e;
    if ((e = emit_region(&c, ws, npts, nsurface, ntris, cm_v2(0.5, 0.5), 0, mesh, &emitted, st)) != CM_OK)
        return e;
    info->points = npts > info->points ? npts : info->points;
    info->triangles += emitted;
    return CM_OK;
}

static cm_err tess_gregory(const cm_model *m, uint32_t f, const cm_greg_surface *gs, double tol, int nb,
                           cm_mesh *mesh, cm_tess_ws *ws, cm_tess_info *info, cm_status *st)
{
    const cm_loop *L = &m->loops[m->faces[f].loop0];
    int n = (int)L->nuse, k = 0, sn[4];
    cm_err e = CM_OK;
    if (m->faces[f].nloops != 1)
        return cm_fail(st, CM_E_UNSUPPORTED, "Gregory patches on a face with holes");
    if (gs->layout == CM_GREG_LAYOUT_JOINED && gs->exact) {
        /* one patch, layout 0's places; side m is the uses from corner m to corner m+1, the i-th on
           [s0, s1] of the side's parameter (cm_gregface.h) */
        static const double u0[4] = {0, 1, 1, 0}, v0[4] = {0, 0, 1, 1}, du[4] = {1, 0, -1, 0}, dv[4] = {0, 1, 0, -1};
        int c[CM_GREG_JOINED_CORNERS], nc = 0;
        for (int i = 0; i < n && nc < CM_GREG_JOINED_CORNERS; i++)
            if ((gs->j >> i) & 1)
                c[nc++] = i;
        if (nc != CM_GREG_JOINED_CORNERS)
            return cm_fail(st, CM_E_FORMAT, "joined Gregory patch without its four corners");
        for (int side = 0; side < 4 && e == CM_OK; side++) {
            const cm_egreg_side *sd = &gs->e[0].side[side];
            int count = (side + 1 < 4 ? c[side + 1] : c[0] + n) - c[side];
            if (count != (sd->kind == CM_EGREG_SIDE_CHAIN ? sd->npiece : 1))
                return cm_fail(st, CM_E_FORMAT, "joined Gregory side does not match its loop");
            sn[side] = 0;
            for (int i = 0; i < count && e == CM_OK; i++) {
                int use = (c[side] + i) % n;
                double a = count > 1 ? sd->piece[i].s0 : 0.0, b = count > 1 ? sd->piece[i].s1 : 1.0;
                sn[side] += ws->use_n[use];
                e = add_use(ws, &k, use, 0, ws->use_n[use], u0[side] + du[side] * a, v0[side] + dv[side] * a,
                            du[side] * (b - a), dv[side] * (b - a), st);
            }
        }
        return e != CM_OK ? e : tess_patch(gs, 0, ws, k, sn, tol, mesh, info, st);
    }
    if (gs->layout != CM_GREG_LAYOUT_SPLIT) {
        /* one patch: sides 0, 1, 2 along v=0, u=1, v=1 (backwards); layout 0's side 3 along u=0,
           layout 2's collapsed into V_j (its corners (0,1) and (0,0) are both V_j) */
        int j = gs->layout == CM_GREG_LAYOUT_DEGEN ? gs->j : 0;
        static const double u0[4] = {0, 1, 1, 0}, v0[4] = {0, 0, 1, 1}, du[4] = {1, 0, -1, 0}, dv[4] = {0, 1, 0, -1};
        int sides = gs->layout == CM_GREG_LAYOUT_DEGEN ? 3 : 4;
        for (int s = 0; s < sides && e == CM_OK; s++) {
            int use = (j + s) % n;
            sn[s] = ws->use_n[use];
            e = add_use(ws, &k, use, 0, ws->use_n[use], u0[s], v0[s], du[s], dv[s], st);
        }
        if (sides == 3) {
            sn[3] = 1;
            if (e == CM_OK)
                e = add_bnd(ws, &k, 0.0, 1.0, ws->use_first[j], st);
        }
        return e != CM_OK ? e : tess_patch(gs, 0, ws, k, sn, tol, mesh, info, st);
    }
    /* N-split: internal curve I_i sampled once (s = q/m, q = 1..m-1, after the face's edge samples in
       bpts), its start M_i being edge i's own sample at t = 1/2 and its end the centre, one point */
    int next = nb, ifirst[CM_MAX_SIDES], im[CM_MAX_SIDES], centre = next++;
    if (next > CM_MAX_TESS_POINTS)
        return cm_fail_limit(st, CM_LIMIT_MAX_TESS_POINTS, (uint64_t)next, CM_MAX_TESS_POINTS, __func__);
    ws->bpts[centre] = gs->centre;
    for (int i = 0; i < n; i++) {
        if (ws->use_n[i] % 2 != 0)
            return cm_fail(st, CM_E_FORMAT, "N-split edge without its midpoint sample");
        im[i] = cubic_segments(&gs->inner[i], tol, CM_MAX_EDGE_SAMPLES - 1);
        ifirst[i] = next;
        if (next + im[i] > CM_MAX_TESS_POINTS)
            return cm_fail_limit(st, CM_LIMIT_MAX_TESS_POINTS, (uint64_t)(next + im[i]), CM_MAX_TESS_POINTS, __func__);
        for (int q = 1; q < im[i]; q++) {
            cm_vec3 d[3];
            cm_cubic_eval(&gs->inner[i], (double)q / (double)im[i], d);
            ws->bpts[next++] = d[0];
        }
    }
    /* patch i around V_i: (0,0) V_i, (1,0) M_i, (1,1) C, (0,1) M_i-1 */
    for (int i = 0; i < n && e == CM_OK; i++) {
        int p = (i + n - 1) % n, ni = ws->use_n[i], np = ws->use_n[p];
        k = 0;
        e = add_use(ws, &k, i, 0, ni / 2, 0, 0, 1, 0, st);                        /* V_i -> M_i */
        if (e == CM_OK)
            e = add_bnd(ws, &k, 1.0, 0.0, ws->use_first[i] + ni / 2, st);        /* M_i */
        for (int q = 1; q < im[i] && e == CM_OK; q++)                            /* I_i up */
            e = add_bnd(ws, &k, 1.0, (double)q / (double)im[i], ifirst[i] + q - 1, st);
        if (e == CM_OK)
            e = add_bnd(ws, &k, 1.0, 1.0, centre, st);                           /* C */
        for (int q = im[p] - 1; q >= 1 && e == CM_OK; q--)                       /* I_p back */
            e = add_bnd(ws, &k, (double)q / (double)im[p], 1.0, ifirst[p] + q - 1, st);
        if (e == CM_OK)                                                          /* M_p -> V_i */
            e = add_use(ws, &k, p, np / 2, np, 0, 1, 0, -1, st);
        sn[0] = ni / 2;
        sn[1] = im[i];
        sn[2] = im[p];
        sn[3] = np - np / 2;
        if (e == CM_OK)
            e = tess_patch(gs, i, ws, k, sn, tol, mesh, info, st);
    }
    return e;
}

/* format 4.9: the most a kept face's plane of triangulation squeezes a curved direction whose grid
   cells are longer than the other's (a ruled direction, degree 1, is squeezed without limit) */
#define TESS_SQUEEZE_MAX_49 4.0

/*
 * Format 4.9: the plane a kept face is triangulated in.  Before, (u,v) scaled by the surface's mean
 * speeds (about millimetres), whatever its curvature grid: on a face curved one way and straight or
 * nearly so the other (a cylinder, a fillet, a hull's strake) the Delaunay triangulation joined the
 * loop's points straight across the curved direction, and the refinement split those triangles at
 * their centres, scattering points over the face (as1_pe_203's twelve half cylinders of 127 mm:
 * 312 triangles each, 3744 of the model's 6928; Open CASCADE meshes the whole model in 3848).  Now
 * the direction whose grid cells are longer is squeezed until its cells are as wide as the other's
 * are high, so that the triangles run along the flatter direction, each across about one cell of
 * the curved one, where the curvature grid put them:
 * - a surface of degree 1 in exactly one direction (a rational (1, 2) cylinder, cone, surface of
 *   revolution or extrusion of a line) is straight along it within each knot span: its grid gets at
 *   least a column per span, and the squeeze has no limit (no bump can hide along a ruling);
 * - otherwise by at most TESS_SQUEEZE_MAX_49: a direction the 5 x 5 curvature samples call flat may
 *   still bend between them, and triangles four cells long are tested as before.
 * Over the corpus at the bench's deflections: as1_pe_203 6928 -> 3592 triangles, occ22470 4196 ->
 * 3118, ship_kvlcc2 2676 -> 2042, Open CASCADE's deviation of each mesh the same or smaller.  A
 * bilinear net (degree 1 both ways) is twisted: the general rule.  The refinement still tests what
 * this makes.
 */
static void kept_plane(const cm_surf *s, double umin, double umax, double vmin, double vmax, int *nu, int *nv,
                       double *su, double *sv)
{
    if (!(umax > umin) || !(vmax > vmin) || *nu < 1 || *nv < 1)
        return;
    double limit = TESS_SQUEEZE_MAX_49;
    if ((s->p == 1) != (s->q == 1)) {
        int along_u = s->p == 1;
        const double *K = along_u ? s->U : s->V;
        int nk = along_u ? s->nu + 2 : s->nv + 2; /* n + p + 1 knots, p = 1 */
        double lo = along_u ? umin : vmin, hi = along_u ? umax : vmax;
        int spans = 1; /* the interior knots inside the loop's range each start a span */
        for (int i = 1; i < nk && spans < CM_MAX_TESS_POINTS / 4; i++)
            if (K[i] > K[i - 1] && K[i - 1] > lo && K[i - 1] < hi)
                spans++;
        if (along_u && spans > *nu) /* (more than the curvature grid's only where a ruling kinks) */
            *nu = spans;
        if (!along_u && spans > *nv)
            *nv = spans;
        limit = 1e300;
    }
    double cu = (umax - umin) * *su / (double)*nu, cv = (vmax - vmin) * *sv / (double)*nv; /* cells, mm */
    if (!(cu > 0.0) || !(cv > 0.0))
        return;
    double r = cu / cv;
    if (r > 1.0)
        *su /= r < limit ? r : limit;
    else if (r < 1.0)
        *sv *= r > 1.0 / limit ? r : 1.0 / limit;
}

static cm_err tessellate_face(const cm_model *m, uint32_t f, double tol, cm_mesh *mesh, cm_tess_ws *ws,
                              cm_tess_info *info, cm_status *st)
{
    const cm_face *F = &m->faces[f];
    ws->point_cap = cm_tess_point_cap(m, tol);
    if (F->nloops > CM_MAX_LOOPS)
        return cm_fail_limit(st, CM_LIMIT_MAX_LOOPS, F->nloops, CM_MAX_LOOPS, __func__);
    cm_rebuilt rb;
    cm_err e = cm_rebuild_face(m, f, &rb, &ws->rb, st);
    if (e != CM_OK)
        return e;
    int nb;
    if ((e = sample_boundary(m, F, tol, rb.repr == CM_REPR_PATCHES, ws, &nb, info, st)) != CM_OK)
        return e;
    cm_mesh_face *mf = NULL;
    if ((e = begin_face(m, f, mesh, &mf, st)) != CM_OK)
        return e;
    if (rb.repr == CM_REPR_PATCHES) {
        if ((e = tess_gregory(m, f, rb.greg, tol, nb, mesh, ws, info, st)) != CM_OK)
            return e;
        end_face(mesh, mf);
        return CM_OK;
    }
    int npts = 0, nloops = (int)F->nloops;
    cm_psurf ps;
    int keep = rb.repr == CM_REPR_NURBS;
    const cm_method *M = cm_method_of(F->method);
    /* a loop off its surface: NFILL's and G1FIT's (rebuilt to a tolerance), and from format 4.1 a
       kept face's, whose net may be re-approximated: tested against the curve's own points, the
       refinement crowded points where the loop runs off the surface (asitus__IAD_v3: 78 to 228
       triangles folded at a quarter of the recommended tolerance) */
    int off_surface = keep && M && (!M->kept_surface || m->kept_off_edges);
    chart c = {keep ? CHART_NURBS : CHART_FRAME, &ps, &rb.frame, NULL, 0, rb.sign, off_surface, NULL};
    if (keep) {
        if ((e = cm_psurf_init(&ps, &rb.surf, 1e-9 * rb.bbox, st)) != CM_OK)
            return e;
        int kn = 0, kl = 0;
        if ((e = keep_domain(&ps, F, 1e-3 * rb.bbox, ws, &kn, &kl, info, st)) != CM_OK)
            return e;
        npts = kn;
        nloops = kl;
    } else {
        /* PLANE: the frame's (x, y); ez is the face normal (spec 5A) */
        for (int l = 0; l <= nloops; l++)
            ws->loop_start[l] = ws->loop_bstart[l];
        for (int i = 0; i < nb; i++) {
            cm_vec3 q = cm_frame_local(&rb.frame, ws->bpts[i]);
            ws->uv[i] = cm_v2(q.x, q.y);
            ws->src[i] = i;
        }
        npts = nb;
    }
    /* the triangulator wants the outer loop counter-clockwise and holes clockwise in its plane */
    for (int l = 0; l < nloops; l++) {
        int first = ws->loop_start[l], n = ws->loop_start[l + 1] - first;
        double area = poly_area(ws->uv + first, n);
        if ((l == 0) != (area > 0))
            reverse_pts(ws->uv + first, ws->src + first, n);
    }
    int interior = 0, grid_nu = 1, grid_nv = 1;
    /* the plane of triangulation: (u,v) scaled by the surface's mean speeds, so triangles are well
     * shaped in 3D even where u is an angle and v a length */
    double umin = ws->uv[0].x, umax = umin, vmin = ws->uv[0].y, vmax = vmin;
    for (int i = 0; i < ws->loop_start[1]; i++) {
        umin = ws->uv[i].x < umin ? ws->uv[i].x : umin;
        umax = ws->uv[i].x > umax ? ws->uv[i].x : umax;
        vmin = ws->uv[i].y < vmin ? ws->uv[i].y : vmin;
        vmax = ws->uv[i].y > vmax ? ws->uv[i].y : vmax;
    }
    double su = 1.0, sv = 1.0;
    if (keep && umax > umin && vmax > vmin) {
        /* speeds and curvatures on a 5 x 5 grid over the domain */
        double kuu = 0, kvv = 0, msu = 0, msv = 0;
        for (int i = 0; i < 5; i++)
            for (int j = 0; j < 5; j++) {
                double u = umin + (umax - umin) * (i + 0.5) / 5.0, v = vmin + (vmax - vmin) * (j + 0.5) / 5.0;
                cm_vec3 S[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
                double uw = u, vw = v;
                if (ps.closed_u)
                    uw -= (ps.u1 - ps.u0) * floor((u - ps.u0) / (ps.u1 - ps.u0));
                if (ps.closed_v)
                    vw -= (ps.v1 - ps.v0) * floor((v - ps.v0) / (ps.v1 - ps.v0));
                if ((e = cm_surf_eval(&ps.s, uw, vw, 2, S, st)) != CM_OK)
                    return e;
                msu += cm_norm(S[1][0]) / 25.0;
                msv += cm_norm(S[0][1]) / 25.0;
                double a = cm_norm(S[2][0]), b = cm_norm(S[0][2]);
                kuu = a > kuu ? a : kuu;
                kvv = b > kvv ? b : kvv;
            }
        if (msu > 0 && msv > 0) {
            su = msu;
            sv = msv;
        }
        /* interior grid: chordal error of a span h with second derivative k is k h^2 / 8 */
        double du = kuu > 0 ? sqrt(8.0 * tol / kuu) : umax - umin;
        double dv = kvv > 0 ? sqrt(8.0 * tol / kvv) : vmax - vmin;
        double nu_f = (umax - umin) / du, nv_f = (vmax - vmin) / dv;
        /* NaN or infinity (a hostile surface's curvature) counts as one cell, and no direction may
           ask for more cells than a face has points */
        if (!(nu_f >= 1))
            nu_f = 1;
        if (!(nv_f >= 1))
            nv_f = 1;
        if (nu_f > (double)CM_MAX_TESS_POINTS)
            nu_f = (double)CM_MAX_TESS_POINTS;
        if (nv_f > (double)CM_MAX_TESS_POINTS)
            nv_f = (double)CM_MAX_TESS_POINTS;
        double room = (double)(CM_MAX_TESS_POINTS - npts) * 0.5;
        if (nu_f * nv_f > room && room >= 1) {
            double shrink = sqrt(room / (nu_f * nv_f));
            nu_f *= shrink;
            nv_f *= shrink;
        }
        /* a grid that does not fit the face's budget at all (never so for a valid file) is shrunk
           the same way, to half the room the budget leaves */
        room = (double)(ws->point_cap - npts) * 0.5;
        if (ceil(nu_f) * ceil(nv_f) > 2.0 * room && room >= 1) {
            double shrink = sqrt(room / (nu_f * nv_f));
            nu_f *= shrink;
            nv_f *= shrink;
        }
        int nu_i = (int)ceil(nu_f), nv_i = (int)ceil(nv_f);
        if (ws->refine_49)
            kept_plane(&ps.s, umin, umax, vmin, vmax, &nu_i, &nv_i, &su, &sv);
        grid_nu = nu_i;
        grid_nv = nv_i;
        if (nu_i > 1 || nv_i > 1)
            for (int i = 0; i < nu_i && npts < ws->point_cap; i++)
                for (int j = 0; j < nv_i && npts < ws->point_cap; j++) {
                    ws->uv[npts] = cm_v2(umin + (umax - umin) * (i + 0.5) / nu_i, vmin + (vmax - vmin) * (j + 0.5) / nv_i);
                    ws->src[npts++] = -1;
                    interior++;
                }
    }
    for (int i = 0; i < npts; i++)
        ws->tmp[i] = cm_v2(ws->uv[i].x * su, ws->uv[i].y * sv);
    /* interior points too close to the boundary or each other: a quarter of a grid cell's shorter
       side (cells are long and thin on a cylinder: their area would drop every other point) */
    double min_dist = 0.0;
    if (interior > 0) {
        double cu = (umax - umin) * su / grid_nu, cv = (vmax - vmin) * sv / grid_nv;
        min_dist = 0.25 * (cu < cv ? cu : cv);
    }
    int ntris = 0;
    if ((e = triangulate(ws, npts, nloops, min_dist, tol, &ntris, st)) != CM_OK)
        return e;
    int nsurface = 0;
    if ((e = refine_region(&c, ws, &npts, &ntris, nloops, min_dist, tol, su, sv, &nsurface, st)) != CM_OK)
        return e;
    info->points = npts;
    /* a flipped kept face turns its triangles */
    int emitted = 0;
    if ((e = emit_region(&c, ws, npts, nsurface, ntris, cm_v2(0.5 * (umin + umax), 0.5 * (vmin + vmax)), rb.sign < 0,
                         mesh, &emitted, st)) != CM_OK)
        return e;
    info->triangles = emitted;
    end_face(mesh, mf);
    return CM_OK;
}

cm_err cm_tessellate_face(const cm_model *m, uint32_t f, double tol, cm_mesh *mesh, cm_tess_ws *ws,
                          cm_tess_info *info, cm_status *st)
{
    cm_tess_info local;
    if (!info)
        info = &local;
    info->points = info->triangles = info->max_edge_samples = 0;
    info->max_gap = 0;
    ws->tested = ws->skipped = ws->predicted = 0;
    ws->refine_47 = m->refine_47;
    ws->refine_48 = m->refine_48;
    ws->refine_49 = m->refine_49;
    ws->refine_410 = m->refine_410;
    ws->pw.net_start = m->refine_48;
    int open = st != NULL && st->code == CM_OK;
    cm_err e = tessellate_face(m, f, tol, mesh, ws, info, st);
    info->tested = ws->tested;
    info->skipped = ws->skipped;
    info->predicted = ws->predicted;
    /* whatever failed (the rebuild, a kernel, the mesh's room) failed for this face: the status
       names it and, as its place in the input, the face's record */
    if (e != CM_OK && open)
        cm_status_at_face(st, f, m->faces[f].rec_off);
    return e;
}
