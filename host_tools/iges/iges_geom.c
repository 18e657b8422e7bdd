/* iges_geom.c - IGES curve and surface entities as exact NURBS (see iges_geom.h). */
#include "iges_geom.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define MAX_NEST 32 /* composite/transform nesting: deeper means a cycle in the file */

static void mark_used(iges_file *f, const iges_entity *e)
{
    f->ents[e - f->ents].used = 1;
}

/* ---- sanity of coordinates ---- */

int iges_coords_sane(const cm_vec3 *p, long n, double *worst)
{
    for (long i = 0; i < n; i++) {
        const double c[3] = {p[i].x, p[i].y, p[i].z};
        for (int k = 0; k < 3; k++)
            if (!(fabs(c[k]) <= IGES_MAX_COORD_MM)) {
                if (worst)
                    *worst = c[k];
                return 0;
            }
    }
    return 1;
}

/* " (its transformation DE 5)" when e has one, for messages about geometry sent far away */
static const char *xform_note(const iges_entity *e, char *buf, size_t cap)
{
    if (e->xform != 0)
        snprintf(buf, cap, " (its transformation: DE %d)", e->xform < 0 ? -e->xform : e->xform);
    else
        snprintf(buf, cap, " (the transformations of the entities placing it)");
    return buf;
}

/* ---- transformations ---- */

int iges_entity_xform(iges_file *f, const iges_entity *e, haffine *out)
{
    *out = haffine_identity();
    int de = e->xform;
    for (int depth = 0; de != 0; depth++) {
        if (depth >= MAX_NEST) {
            iges_entity_error(f, e, "transformation chain longer than %d (a cycle?)", MAX_NEST);
            return -1;
        }
        const iges_entity *t = iges_by_de(f, de < 0 ? -de : de);
        if (!t || t->type != 124) {
            iges_entity_error(f, e, "transformation pointer %d does not name a 124 entity", de);
            return -1;
        }
        if (t->bad || t->nparams < 12) {
            iges_entity_error(f, e, "transformation DE %d is malformed", t->de);
            return -1;
        }
        haffine m;
        for (int r = 0; r < 3; r++) {
            for (int c = 0; c < 3; c++)
                m.R[r][c] = iges_num_or(t, r * 4 + c, r == c ? 1.0 : 0.0);
        }
        m.t = cm_v3(iges_num_or(t, 3, 0), iges_num_or(t, 7, 0), iges_num_or(t, 11, 0));
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                if (!isfinite(m.R[r][c])) {
                    iges_entity_error(f, e, "transformation DE %d has a non-finite entry", t->de);
                    return -1;
                }
        mark_used(f, t);
        /* this matrix acts first, then the one it points to */
        *out = haffine_compose(&m, out);
        de = t->xform;
    }
    return 0;
}

/* map of entity e's definition space to millimetre model space */
static int entity_map(iges_file *f, const iges_entity *e, const haffine *parent, haffine *out)
{
    haffine own;
    if (iges_entity_xform(f, e, &own))
        return -1;
    *out = haffine_compose(parent, &own);
    return 0;
}

/* ---- curves ---- */

static cm_err curve_rec(iges_file *f, int de, const haffine *parent, hcurve_list *out, int depth, cm_status *st);

/* map a finished piece of entity e into model space and append it; geometry sent beyond
 * IGES_MAX_COORD_MM (or to infinity) by the transformations is refused, naming e */
static cm_err push_mapped(iges_file *f, const iges_entity *e_src, hcurve *c, const haffine *m, hcurve_list *out,
                          cm_status *st)
{
    hcurve_transform(c, m);
    double worst = 0;
    if (!iges_coords_sane(c->ctrl, c->n, &worst)) {
        char note[96];
        hcurve_free(c);
        return iges_entity_error(f, e_src, "in model space its control points reach %g mm, beyond +-%g mm%s",
                                 worst, IGES_MAX_COORD_MM, xform_note(e_src, note, sizeof note)),
               cm_fail(st, CM_E_RANGE, "curve coordinates");
    }
    cm_err e = hcurve_list_push(out, c, st);
    if (e != CM_OK)
        hcurve_free(c);
    return e;
}

static cm_err arc_100(iges_file *f, const iges_entity *e, const haffine *m, hcurve_list *out, cm_status *st)
{
    double v[7];
    for (int i = 0; i < 7; i++)
        if (iges_num(f, e, i, &v[i]))
            return cm_fail(st, CM_E_IGES, "arc");
    cm_vec3 c = cm_v3(v[1], v[2], v[0]);
    double dx0 = v[3] - v[1], dy0 = v[4] - v[2], dx1 = v[5] - v[1], dy1 = v[6] - v[2];
    double r = hypot(dx0, dy0);
    if (!(r > 0.0))
        return iges_entity_error(f, e, "zero radius"), cm_fail(st, CM_E_IGES, "arc");
    double a0 = atan2(dy0, dx0), a1 = atan2(dy1, dx1);
    if (hypot(v[5] - v[3], v[6] - v[4]) <= 1e-12 * r) {
        a1 = a0 + 2 * M_PI; /* start == end: a full circle */
    } else {
        while (a1 <= a0)
            a1 += 2 * M_PI;
    }
    hcurve h = {0};
    cm_err err = hcurve_ellipse_arc(c, cm_v3(1, 0, 0), cm_v3(0, 1, 0), r, r, a0, a1, &h, st);
    if (err != CM_OK)
        return err; /* curve_rec names the entity (or reports out of memory as such) */
    return push_mapped(f, e, &h, m, out, st);
}

/* conic gradient at (x,y) for A x^2 + B xy + C y^2 + D x + E y + F */
static void conic_grad(const double *k, double x, double y, double *gx, double *gy)
{
    *gx = 2 * k[0] * x + k[1] * y + k[3];
    *gy = k[1] * x + 2 * k[2] * y + k[4];
}

static cm_err conic_104(iges_file *f, const iges_entity *e, const haffine *m, hcurve_list *out, cm_status *st)
{
    double k[6], zt, x1, y1, x2, y2;
    for (int i = 0; i < 6; i++)
        if (iges_num(f, e, i, &k[i]))
            return cm_fail(st, CM_E_IGES, "conic");
    if (iges_num(f, e, 6, &zt) || iges_num(f, e, 7, &x1) || iges_num(f, e, 8, &y1) || iges_num(f, e, 9, &x2) ||
        iges_num(f, e, 10, &y2))
        return cm_fail(st, CM_E_IGES, "conic");
    double disc = k[1] * k[1] - 4 * k[0] * k[2];
    hcurve h = {0};
    cm_err err;
    if (disc < 0) {
        /* ellipse: centre and principal axes */
        double det = 4 * k[0] * k[2] - k[1] * k[1];
        double cx = (k[1] * k[4] - 2 * k[2] * k[3]) / det, cy = (k[1] * k[3] - 2 * k[0] * k[4]) / det;
        double fc = k[0] * cx * cx + k[1] * cx * cy + k[2] * cy * cy + k[3] * cx + k[4] * cy + k[5];
        double th = 0.5 * atan2(k[1], k[0] - k[2]);
        double ct = cos(th), s = sin(th);
        double l1 = k[0] * ct * ct + k[1] * ct * s + k[2] * s * s; /* along (ct, s) */
        double l2 = k[0] * s * s - k[1] * ct * s + k[2] * ct * ct; /* along (-s, ct) */
        if (!(-fc / l1 > 0) || !(-fc / l2 > 0))
            return iges_entity_error(f, e, "conic coefficients do not describe a real ellipse"),
                   cm_fail(st, CM_E_IGES, "conic");
        double a = sqrt(-fc / l1), b = sqrt(-fc / l2);
        cm_vec3 X = cm_v3(ct, s, 0), Y = cm_v3(-s, ct, 0);
        double p0x = x1 - cx, p0y = y1 - cy, p1x = x2 - cx, p1y = y2 - cy;
        double t0 = atan2((p0x * -s + p0y * ct) / b, (p0x * ct + p0y * s) / a);
        double t1 = atan2((p1x * -s + p1y * ct) / b, (p1x * ct + p1y * s) / a);
        if (hypot(x2 - x1, y2 - y1) <= 1e-12 * (a + b))
            t1 = t0 + 2 * M_PI;
        else
            while (t1 <= t0)
                t1 += 2 * M_PI;
        err = hcurve_ellipse_arc(cm_v3(cx, cy, zt), X, Y, a, b, t0, t1, &h, st);
    } else {
        /* parabola or hyperbola arc: one rational quadratic span from the end tangents */
        double g0x, g0y, g1x, g1y;
        conic_grad(k, x1, y1, &g0x, &g0y);
        conic_grad(k, x2, y2, &g1x, &g1y);
        /* tangent lines: g0 . (p - P0) = 0 and g1 . (p - P2) = 0 */
        double det = g0x * g1y - g0y * g1x;
        if (fabs(det) <= 1e-14 * hypot(g0x, g0y) * hypot(g1x, g1y))
            return iges_entity_error(f, e, "conic arc end tangents are parallel"), cm_fail(st, CM_E_IGES, "conic");
        double c0 = g0x * x1 + g0y * y1, c1 = g1x * x2 + g1y * y2;
        double px = (c0 * g1y - g0y * c1) / det, py = (g0x * c1 - c0 * g1x) / det;
        /* shoulder point: the conic on the line from the chord midpoint M to P1 gives the weight */
        double mx = 0.5 * (x1 + x2), my = 0.5 * (y1 + y2), dx = px - mx, dy = py - my;
        double qa = k[0] * dx * dx + k[1] * dx * dy + k[2] * dy * dy;
        double qb = 2 * k[0] * mx * dx + k[1] * (mx * dy + my * dx) + 2 * k[2] * my * dy + k[3] * dx + k[4] * dy;
        double qc = k[0] * mx * mx + k[1] * mx * my + k[2] * my * my + k[3] * mx + k[4] * my + k[5];
        double sh = -1;
        if (fabs(qa) > 1e-300) {
            double dsc = qb * qb - 4 * qa * qc;
            if (dsc >= 0) {
                double r1 = (-qb - sqrt(dsc)) / (2 * qa), r2 = (-qb + sqrt(dsc)) / (2 * qa);
                sh = (r1 > 0 && r1 < 1) ? r1 : r2;
            }
        } else if (fabs(qb) > 1e-300) {
            sh = -qc / qb;
        }
        if (!(sh > 0 && sh < 1))
            return iges_entity_error(f, e, "conic arc has no shoulder point between its ends"),
                   cm_fail(st, CM_E_IGES, "conic");
        double w1 = sh / (1 - sh);
        err = hcurve_conic_span(cm_v3(x1, y1, zt), cm_v3(px, py, zt), cm_v3(x2, y2, zt), w1, &h, st);
    }
    if (err != CM_OK)
        return err; /* curve_rec names the entity (or reports out of memory as such) */
    return push_mapped(f, e, &h, m, out, st);
}

static cm_err copious_106(iges_file *f, const iges_entity *e, const haffine *m, hcurve_list *out, cm_status *st)
{
    int ip, n;
    if (iges_int(f, e, 0, &ip) || iges_int(f, e, 1, &n))
        return cm_fail(st, CM_E_IGES, "copious");
    if (!((e->form >= 1 && e->form <= 3) || (e->form >= 11 && e->form <= 13) || e->form == 63))
        return iges_entity_error(f, e, "copious data form %d is not a curve", e->form), cm_fail(st, CM_E_IGES, "copious");
    int stride = ip == 1 ? 2 : ip == 2 ? 3 : ip == 3 ? 6 : 0;
    int base = ip == 1 ? 3 : 2;
    if (stride == 0 || n < 2 || n > 10000000 || base + (long)n * stride > e->nparams)
        return iges_entity_error(f, e, "copious data: %d points of kind %d do not fit its %d parameters", n, ip,
                                 e->nparams),
               cm_fail(st, CM_E_IGES, "copious");
    int closed = e->form == 63;
    cm_vec3 *p = malloc((size_t)(n + 1) * sizeof *p);
    if (!p)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    double zt = ip == 1 ? iges_num_or(e, 2, 0.0) : 0.0;
    int k = 0;
    for (int i = 0; i < n; i++) {
        const int o = base + i * stride;
        cm_vec3 q = cm_v3(iges_num_or(e, o, (double)NAN), iges_num_or(e, o + 1, (double)NAN), ip == 1 ? zt : iges_num_or(e, o + 2, (double)NAN));
        if (!cm_finite3(q)) {
            free(p);
            return iges_entity_error(f, e, "copious data point %d is not numeric", i + 1),
                   cm_fail(st, CM_E_IGES, "copious");
        }
        if (k > 0 && cm_dist(q, p[k - 1]) == 0.0)
            continue; /* repeated point: no zero-length span */
        p[k++] = q;
    }
    if (closed && k > 2 && cm_dist(p[0], p[k - 1]) > 0.0)
        p[k++] = p[0];
    if (k < 2) {
        free(p);
        return iges_entity_error(f, e, "copious data has fewer than 2 distinct points"),
               cm_fail(st, CM_E_IGES, "copious");
    }
    hcurve h = {0};
    cm_err err = hcurve_polyline(p, k, &h, st);
    free(p);
    if (err != CM_OK)
        return err; /* curve_rec names the entity */
    return push_mapped(f, e, &h, m, out, st);
}

static cm_err line_110(iges_file *f, const iges_entity *e, const haffine *m, hcurve_list *out, cm_status *st)
{
    double v[6];
    for (int i = 0; i < 6; i++)
        if (iges_num(f, e, i, &v[i]))
            return cm_fail(st, CM_E_IGES, "line");
    cm_vec3 a = cm_v3(v[0], v[1], v[2]), b = cm_v3(v[3], v[4], v[5]);
    if (cm_dist(a, b) == 0.0)
        return iges_entity_error(f, e, "zero-length line"), cm_fail(st, CM_E_IGES, "line");
    hcurve h = {0};
    cm_err err = hcurve_line(a, b, &h, st);
    if (err != CM_OK)
        return err; /* curve_rec names the entity */
    return push_mapped(f, e, &h, m, out, st);
}

static cm_err spline_112(iges_file *f, const iges_entity *e, const haffine *m, hcurve_list *out, cm_status *st)
{
    int ctype, h, ndim, n;
    if (iges_int(f, e, 0, &ctype) || iges_int(f, e, 1, &h) || iges_int(f, e, 2, &ndim) || iges_int(f, e, 3, &n))
        return cm_fail(st, CM_E_IGES, "spline");
    if (n < 1 || n > 1000000 || 4 + (n + 1) + 12L * n > e->nparams)
        return iges_entity_error(f, e, "%d segments do not fit its %d parameters", n, e->nparams),
               cm_fail(st, CM_E_IGES, "spline");
    double *T = malloc((size_t)(n + 1) * sizeof *T);
    cm_vec3 *coef = malloc((size_t)n * 4 * sizeof *coef);
    if (!T || !coef) {
        free(T);
        free(coef);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    for (int i = 0; i <= n; i++)
        T[i] = iges_num_or(e, 4 + i, (double)NAN);
    int base = 4 + n + 1, ok = 1;
    for (int i = 0; i < n; i++) {
        for (int c = 0; c < 4; c++) {
            const int o = base + i * 12;
            coef[i * 4 + c] = cm_v3(iges_num_or(e, o + c, (double)NAN), iges_num_or(e, o + 4 + c, (double)NAN),
                                    ndim == 2 ? iges_num_or(e, o + 8 + c, 0.0) : iges_num_or(e, o + 8 + c, (double)NAN));
            if (!cm_finite3(coef[i * 4 + c]))
                ok = 0;
        }
        if (!(T[i + 1] > T[i]))
            ok = 0;
    }
    hcurve hc = {0};
    cm_err err = ok ? hcurve_from_cubic_segments(T, coef, n, &hc, st) : CM_E_IGES;
    free(T);
    free(coef);
    if (err == CM_E_NOMEM)
        return err;
    if (err != CM_OK)
        return iges_entity_error(f, e, "malformed breakpoints or coefficients"), cm_fail(st, CM_E_IGES, "spline");
    return push_mapped(f, e, &hc, m, out, st);
}

/* 1 if all weights are equal: then the curve/surface is polynomial */
static int weights_equal(const double *w, long n)
{
    for (long i = 1; i < n; i++)
        if (w[i] != w[0])
            return 0;
    return 1;
}

static cm_err bspline_126(iges_file *f, const iges_entity *e, const haffine *m, hcurve_list *out, cm_status *st)
{
    int K, M;
    if (iges_int(f, e, 0, &K) || iges_int(f, e, 1, &M))
        return cm_fail(st, CM_E_IGES, "126");
    /* range-checked before any arithmetic: K = 2147483647 must not overflow K + 1 */
    if (M < 1 || M > CM_MAX_DEGREE || K < M || K > 999999)
        return iges_entity_error(f, e, "degree %d with upper index %d is not a valid curve (degree 1..%d, "
                                       "index degree..999999)", M, K, CM_MAX_DEGREE),
               cm_fail(st, CM_E_IGES, "126");
    int n = K + 1, p = M;
    int nk = n + p + 1;
    int o_knots = 6, o_w = o_knots + nk, o_p = o_w + n, o_v = o_p + 3 * n;
    if (o_v + 2 > e->nparams)
        return iges_entity_error(f, e, "%d control points of degree %d need %d parameters, it has %d", n, p, o_v + 2,
                                 e->nparams),
               cm_fail(st, CM_E_IGES, "126");
    hcurve h = {0};
    cm_err err = hcurve_alloc(&h, p, n, 1, st);
    if (err != CM_OK)
        return err;
    /* every number must be there (a missing one is NaN here, caught by cm_curve_check below) */
    for (int i = 0; i < nk; i++)
        h.knots[i] = iges_num_or(e, o_knots + i, (double)NAN);
    for (int i = 0; i < n; i++) {
        h.w[i] = iges_num_or(e, o_w + i, (double)NAN);
        h.ctrl[i] = cm_v3(iges_num_or(e, o_p + 3 * i, (double)NAN), iges_num_or(e, o_p + 3 * i + 1, (double)NAN),
                          iges_num_or(e, o_p + 3 * i + 2, (double)NAN));
    }
    double v0 = iges_num_or(e, o_v, (double)NAN), v1 = iges_num_or(e, o_v + 1, (double)NAN);
    if (weights_equal(h.w, n)) {
        free(h.w);
        h.w = NULL;
    }
    cm_curve view = hcurve_view(&h);
    cm_status cst;
    cm_status_init(&cst);
    if (cm_curve_check(&view, &cst) != CM_OK) {
        hcurve_free(&h);
        return iges_entity_error(f, e, "invalid B-spline curve: %s", cm_strerror(cst.code)),
               cm_fail(st, CM_E_IGES, "126");
    }
    /* the curve may be used on a sub-range of its knot domain */
    double t0, t1;
    hcurve_domain(&h, &t0, &t1);
    double tol = 1e-9 * (t1 - t0);
    if (isfinite(v0) && isfinite(v1) && v0 < v1 && (v0 > t0 + tol || v1 < t1 - tol)) {
        double a = v0 > t0 ? v0 : t0, b = v1 < t1 ? v1 : t1;
        hcurve sub = {0};
        err = hcurve_subrange(&h, a, b, &sub, st);
        hcurve_free(&h);
        if (err == CM_E_NOMEM)
            return err;
        if (err != CM_OK)
            return iges_entity_error(f, e, "cannot restrict to [%g, %g]", v0, v1), err;
        h = sub;
    }
    return push_mapped(f, e, &h, m, out, st);
}

static cm_err composite_102(iges_file *f, const iges_entity *e, const haffine *m, hcurve_list *out, int depth,
                            cm_status *st)
{
    int n;
    if (iges_int(f, e, 0, &n))
        return cm_fail(st, CM_E_IGES, "102");
    if (n < 1 || n > e->nparams - 1) /* not n + 1 > nparams: n may be 2147483647 */
        return iges_entity_error(f, e, "composite of %d curves has %d parameters", n, e->nparams),
               cm_fail(st, CM_E_IGES, "102");
    for (int i = 0; i < n; i++) {
        int de;
        if (iges_ptr(f, e, 1 + i, 0, &de))
            return cm_fail(st, CM_E_IGES, "102");
        const iges_entity *c = iges_by_de(f, de);
        if (c->type == 116)
            continue; /* a point constituent adds no geometry (IGES allows it) */
        cm_err err = curve_rec(f, de, m, out, depth + 1, st);
        if (err != CM_OK)
            return err;
    }
    return CM_OK;
}

static cm_err curve_rec(iges_file *f, int de, const haffine *parent, hcurve_list *out, int depth, cm_status *st)
{
    const iges_entity *e = iges_by_de(f, de);
    if (!e) /* callers pass pointers iges_ptr checked: not reached from a file */
        return iges_error(f, 0, "DE %d is not an entity of this file", de), cm_fail(st, CM_E_IGES, "curve");
    if (depth > MAX_NEST)
        return iges_entity_error(f, e, "curves nested deeper than %d (a cycle?)", MAX_NEST),
               cm_fail(st, CM_E_IGES, "curve");
    if (e->bad)
        return iges_entity_error(f, e, "its parameter data could not be read"), cm_fail(st, CM_E_IGES, "curve");
    haffine m;
    if (entity_map(f, e, parent, &m))
        return cm_fail(st, CM_E_IGES, "curve");
    cm_err err;
    switch (e->type) {
    case 100: err = arc_100(f, e, &m, out, st); break;
    case 102: err = composite_102(f, e, &m, out, depth, st); break;
    case 104: err = conic_104(f, e, &m, out, st); break;
    case 106: err = copious_106(f, e, &m, out, st); break;
    case 110: err = line_110(f, e, &m, out, st); break;
    case 112: err = spline_112(f, e, &m, out, st); break;
    case 126: err = bspline_126(f, e, &m, out, st); break;
    case 142: {
        int cptr;
        if (iges_ptr(f, e, 3, 1, &cptr))
            return cm_fail(st, CM_E_IGES, "142");
        if (cptr == 0)
            return iges_entity_error(f, e, "curve on surface without a model-space curve (only a parameter-space "
                                            "curve) is not supported"),
                   cm_fail(st, CM_E_UNSUPPORTED, "142");
        err = curve_rec(f, cptr, &m, out, depth + 1, st);
        break;
    }
    default:
        return iges_entity_error(f, e, "entity type %d is not a supported curve", e->type),
               cm_fail(st, CM_E_UNSUPPORTED, "curve");
    }
    if (err == CM_OK)
        mark_used(f, e);
    else if (err == CM_E_NOMEM)
        iges_nomem(f, e->pd_line, "building entity %d, DE %d", e->type, e->de); /* not the entity's fault */
    else if (f->err[0] == 0) /* a construction refused the numbers: still say which entity */
        iges_entity_error(f, e, "cannot build the curve: %s", cm_strerror(err));
    return err;
}

/*
 * Curve pieces entity `de` flattens into (composites through every level), saturating just past
 * IGES_MAX_CURVE_PIECES; memoised per entity so a DAG is counted in time linear in its size.
 * Malformed or cyclic structures count as 1 here: curve_rec reports them.
 */
static int count_pieces(iges_file *f, int de, int depth)
{
    const iges_entity *e = iges_by_de(f, de < 0 ? -de : de);
    if (!e || depth > MAX_NEST || e->bad)
        return 1;
    int *memo = &f->curve_pieces[e - f->ents];
    if (*memo > 0)
        return *memo;
    long long n = 1;
    if (e->type == 102) {
        n = 0;
        int m = iges_count_or0(e, 0);
        for (int i = 1; i <= m && i < e->nparams && n <= IGES_MAX_CURVE_PIECES; i++) {
            int mde = iges_int_or(e, i, 0);
            const iges_entity *c = iges_by_de(f, mde < 0 ? -mde : mde);
            if (c && c->type != 116)
                n += count_pieces(f, mde, depth + 1);
        }
    } else if (e->type == 142) {
        int c = iges_int_or(e, 3, 0);
        if (c != 0)
            n = count_pieces(f, c, depth + 1);
    }
    if (n < 1)
        n = 1;
    if (n > IGES_MAX_CURVE_PIECES)
        n = IGES_MAX_CURVE_PIECES + 1;
    *memo = (int)n;
    return *memo;
}

int iges_curve_pieces(iges_file *f, int de)
{
    if (!f->curve_pieces) {
        f->curve_pieces = calloc((size_t)(f->nents > 0 ? f->nents : 1), sizeof *f->curve_pieces);
        if (!f->curve_pieces)
            return -1;
    }
    return count_pieces(f, de, 0);
}

cm_err iges_curve(iges_file *f, int de, const haffine *parent, hcurve_list *out, cm_status *st)
{
    const iges_entity *e = iges_by_de(f, de);
    if (e) {
        int n = iges_curve_pieces(f, de);
        if (n < 0)
            return iges_nomem(f, e->pd_line, "counting the pieces of curve DE %d", de),
                   cm_fail(st, CM_E_NOMEM, "out of memory");
        if (n > IGES_MAX_CURVE_PIECES) {
            /* name the composite that explodes (a 142 only points to it) */
            const iges_entity *c = e;
            for (int k = 0; k < MAX_NEST && c->type == 142; k++) {
                const iges_entity *m = iges_by_de(f, iges_int_or(c, 3, 0));
                if (!m)
                    break;
                c = m;
            }
            char what[64] = "";
            if (c != e)
                snprintf(what, sizeof what, ", through its curve DE %d", c->de);
            return iges_entity_error(f, e,
                                     "expands to more than %d curve pieces (limit %d per curve)%s: composite "
                                     "curves that list composites many times over",
                                     IGES_MAX_CURVE_PIECES, IGES_MAX_CURVE_PIECES, what),
                   cm_fail(st, CM_E_LIMIT, "curve pieces");
        }
        if (f->pieces_made + n > IGES_MAX_MODEL_PIECES) {
            f->over_budget = 1;
            return iges_entity_error(f, e,
                                     "the model's curves expand to more than %lld pieces (limit %lld per model)",
                                     IGES_MAX_MODEL_PIECES, IGES_MAX_MODEL_PIECES),
                   cm_fail(st, CM_E_LIMIT, "model curve pieces");
        }
    }
    int before = out->n;
    cm_err err = curve_rec(f, de, parent, out, 0, st);
    f->pieces_made += out->n - before;
    return err;
}

/* ---- joining curve pieces (a composite generatrix or directrix) ---- */

/*
 * One curve through the pieces in order: every piece raised to the highest
 * degree, made rational if any is, clamped, mapped to [k, k+1], and joined
 * C0 (interior knots of multiplicity p at the joints).  A rational piece's
 * weights are scaled so its first weight equals the previous piece's last
 * (scaling all weights of a curve does not change it), so the shared
 * control point has one weight.
 */
static cm_err join_pieces(const hcurve_list *l, hcurve *out, cm_status *st)
{
    if (l->n == 1)
        return hcurve_copy(&l->c[0], out, st);
    int p = 1, rational = 0, total = 1;
    for (int i = 0; i < l->n; i++) {
        if (l->c[i].p > p)
            p = l->c[i].p;
        rational |= l->c[i].w != NULL;
    }
    hcurve *pc = calloc((size_t)l->n, sizeof *pc);
    if (!pc)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    cm_err e = CM_OK;
    for (int i = 0; i < l->n && e == CM_OK; i++) {
        hcurve tmp = {0};
        e = hcurve_clamp(&l->c[i], &tmp, st);
        if (e == CM_OK)
            e = hcurve_elevate(&tmp, p, &pc[i], st);
        hcurve_free(&tmp);
        if (e == CM_OK) {
            hcurve_reparam(&pc[i], (double)i, (double)(i + 1));
            total += pc[i].n - 1;
        }
    }
    if (e == CM_OK)
        e = hcurve_alloc(out, p, total, rational, st);
    if (e == CM_OK) {
        int k = 0, kk = 0;
        double wscale = 1.0;
        for (int i = 0; i < l->n; i++) {
            const hcurve *c = &pc[i];
            if (rational) {
                double w0 = c->w ? c->w[0] : 1.0;
                wscale = i == 0 ? 1.0 / w0 : out->w[k - 1] / w0;
            }
            for (int j = (i == 0 ? 0 : 1); j < c->n; j++) {
                out->ctrl[k] = c->ctrl[j];
                if (rational)
                    out->w[k] = (c->w ? c->w[j] : 1.0) * wscale;
                k++;
            }
            if (i > 0) /* the shared point: mean of the two ends (they agree up to the file's gap) */
                out->ctrl[k - c->n] = cm_scale(cm_add(out->ctrl[k - c->n], c->ctrl[0]), 0.5);
            /* knots: p+1 at the start (first piece), p at each joint, then the piece's interior ones */
            if (i > 0)
                for (int j = 0; j < p; j++)
                    out->knots[kk++] = (double)i;
            for (int j = (i == 0 ? 0 : p + 1); j < c->n; j++)
                out->knots[kk++] = c->knots[j];
        }
        for (int j = 0; j <= p; j++)
            out->knots[kk++] = (double)l->n;
    }
    for (int i = 0; i < l->n; i++)
        hcurve_free(&pc[i]);
    free(pc);
    if (e != CM_OK)
        hcurve_free(out);
    return e;
}

static cm_err single_curve(iges_file *f, int de, const haffine *m, hcurve *out, cm_status *st)
{
    hcurve_list l = {0};
    cm_err e = iges_curve(f, de, m, &l, st);
    if (e == CM_OK && l.n == 0)
        e = iges_entity_error(f, iges_by_de(f, de), "the curve has no geometry (only points)");
    if (e == CM_OK)
        e = join_pieces(&l, out, st);
    hcurve_list_free(&l);
    return e;
}

/* ---- points and directions of the analytic surfaces ---- */

static int point_116(iges_file *f, const iges_entity *host, int i, const haffine *m, cm_vec3 *out)
{
    int de;
    if (iges_ptr(f, host, i, 0, &de))
        return -1;
    const iges_entity *e = iges_by_de(f, de);
    haffine mm;
    if (e->type != 116 || e->bad || entity_map(f, e, m, &mm)) {
        iges_entity_error(f, host, "parameter %d must point to a point (116)", i + 1);
        return -1;
    }
    cm_vec3 p = cm_v3(iges_num_or(e, 0, (double)NAN), iges_num_or(e, 1, (double)NAN), iges_num_or(e, 2, (double)NAN));
    if (!cm_finite3(p)) {
        iges_entity_error(f, e, "point coordinates are not numeric");
        return -1;
    }
    mark_used(f, e);
    *out = haffine_apply(&mm, p);
    return 0;
}

/* unit direction of a 123 entity (0 pointer allowed when optional: *out untouched, returns 1) */
static int dir_123(iges_file *f, const iges_entity *host, int i, const haffine *m, int optional, cm_vec3 *out)
{
    int de;
    if (iges_ptr(f, host, i, optional, &de))
        return -1;
    if (de == 0)
        return 1;
    const iges_entity *e = iges_by_de(f, de);
    haffine mm;
    if (e->type != 123 || e->bad || entity_map(f, e, m, &mm)) {
        iges_entity_error(f, host, "parameter %d must point to a direction (123)", i + 1);
        return -1;
    }
    cm_vec3 d = haffine_apply_dir(&mm, cm_v3(iges_num_or(e, 0, (double)NAN), iges_num_or(e, 1, (double)NAN), iges_num_or(e, 2, (double)NAN)));
    if (!cm_finite3(d) || !(cm_norm(d) > 0)) {
        iges_entity_error(f, e, "direction is zero or not numeric");
        return -1;
    }
    mark_used(f, e);
    *out = cm_unit(d);
    return 0;
}

/* uniform scale of an affine map (lengths such as radii scale by it) */
static double map_scale(const haffine *m)
{
    const double(*R)[3] = m->R;
    double det = R[0][0] * (R[1][1] * R[2][2] - R[1][2] * R[2][1]) - R[0][1] * (R[1][0] * R[2][2] - R[1][2] * R[2][0]) +
                 R[0][2] * (R[1][0] * R[2][1] - R[1][1] * R[2][0]);
    return cbrt(fabs(det));
}

static cm_err plane_patch(iges_file *f, const iges_entity *e, cm_vec3 P, cm_vec3 N, const cm_vec3 *ref,
                          const hbox *extent, hsurf *out, cm_status *st)
{
    if (!extent || extent->empty)
        return iges_entity_error(f, e, "plane used without a bounded face: cannot size it"),
               cm_fail(st, CM_E_IGES, "plane");
    cm_vec3 X, Y;
    hbox_frame(N, ref, &X, &Y);
    double x0, x1, y0, y1;
    hbox_axis_range(extent, P, X, &x0, &x1);
    hbox_axis_range(extent, P, Y, &y0, &y1);
    return hsurf_plane(P, X, Y, x0, x1, y0, y1, out, st);
}

int iges_is_surface(int type)
{
    switch (type) {
    case 108: case 118: case 120: case 122: case 128: case 190: case 192: case 194: case 196: case 198:
        return 1;
    default:
        return 0;
    }
}

static cm_err bspline_128(iges_file *f, const iges_entity *e, const haffine *m, hsurf *out, cm_status *st)
{
    int K1, K2, M1, M2;
    if (iges_int(f, e, 0, &K1) || iges_int(f, e, 1, &K2) || iges_int(f, e, 2, &M1) || iges_int(f, e, 3, &M2))
        return cm_fail(st, CM_E_IGES, "128");
    /* range-checked before any arithmetic: K1 = 2147483647 must not overflow K1 + 1 */
    if (M1 < 1 || M2 < 1 || M1 > CM_MAX_DEGREE || M2 > CM_MAX_DEGREE || K1 < M1 || K2 < M2 || K1 > 99999 ||
        K2 > 99999 || (long)(K1 + 1) * (K2 + 1) > 10000000)
        return iges_entity_error(f, e,
                                 "degrees %d x %d with upper indices %d x %d is not a valid surface (degrees 1..%d, "
                                 "at most 100000 points per direction, 10^7 in all)",
                                 M1, M2, K1, K2, CM_MAX_DEGREE),
               cm_fail(st, CM_E_IGES, "128");
    int nu = K1 + 1, nv = K2 + 1;
    int nku = nu + M1 + 1, nkv = nv + M2 + 1;
    long o_u = 9, o_v = o_u + nku, o_w = o_v + nkv, o_p = o_w + (long)nu * nv, o_d = o_p + 3L * nu * nv;
    if (o_d + 4 > e->nparams)
        return iges_entity_error(f, e, "%d x %d control points need %ld parameters, it has %d", nu, nv, o_d + 4,
                                 e->nparams),
               cm_fail(st, CM_E_IGES, "128");
    hsurf s = {0};
    cm_err err = hsurf_alloc(&s, M1, M2, nu, nv, 1, st);
    if (err != CM_OK)
        return err;
    for (int i = 0; i < nku; i++)
        s.U[i] = iges_num_or(e, (int)o_u + i, (double)NAN);
    for (int i = 0; i < nkv; i++)
        s.V[i] = iges_num_or(e, (int)o_v + i, (double)NAN);
    /* the file lists the net with the u index running fastest */
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            long k = (long)j * nu + i;
            long idx = (long)i * nv + j;
            s.w[idx] = iges_num_or(e, (int)(o_w + k), (double)NAN);
            s.ctrl[idx] = cm_v3(iges_num_or(e, (int)(o_p + 3 * k), (double)NAN), iges_num_or(e, (int)(o_p + 3 * k + 1), (double)NAN),
                                iges_num_or(e, (int)(o_p + 3 * k + 2), (double)NAN));
        }
    if (weights_equal(s.w, (long)nu * nv)) {
        free(s.w);
        s.w = NULL;
    }
    cm_surf view = hsurf_view(&s);
    cm_status cst;
    cm_status_init(&cst);
    if (cm_surf_check(&view, &cst) != CM_OK) {
        hsurf_free(&s);
        return iges_entity_error(f, e, "invalid B-spline surface: %s", cm_strerror(cst.code)),
               cm_fail(st, CM_E_IGES, "128");
    }
    /* the declared parameter range may be smaller than the knot domain */
    double u0, u1, v0, v1;
    hsurf_domain(&s, &u0, &u1, &v0, &v1);
    double du0 = iges_num_or(e, (int)o_d, u0), du1 = iges_num_or(e, (int)o_d + 1, u1);
    double dv0 = iges_num_or(e, (int)o_d + 2, v0), dv1 = iges_num_or(e, (int)o_d + 3, v1);
    double tu = 1e-9 * (u1 - u0), tv = 1e-9 * (v1 - v0);
    if (du0 < du1 && dv0 < dv1 && (du0 > u0 + tu || du1 < u1 - tu || dv0 > v0 + tv || dv1 < v1 - tv)) {
        hsurf sub = {0};
        err = hsurf_subrange(&s, fmax(du0, u0), fmin(du1, u1), fmax(dv0, v0), fmin(dv1, v1), &sub, st);
        hsurf_free(&s);
        if (err == CM_E_NOMEM)
            return err;
        if (err != CM_OK)
            return iges_entity_error(f, e, "cannot restrict to its declared parameter range"), err;
        s = sub;
    }
    hsurf_transform(&s, m);
    *out = s;
    return CM_OK;
}

static cm_err surface_rec(iges_file *f, int de, const haffine *parent, const hbox *extent, hsurf *out, cm_status *st)
{
    const iges_entity *e = iges_by_de(f, de);
    if (!e) /* callers pass pointers iges_ptr checked: not reached from a file */
        return iges_error(f, 0, "DE %d is not an entity of this file", de), cm_fail(st, CM_E_IGES, "surface");
    if (e->bad)
        return iges_entity_error(f, e, "its parameter data could not be read"), cm_fail(st, CM_E_IGES, "surface");
    haffine m;
    if (entity_map(f, e, parent, &m))
        return cm_fail(st, CM_E_IGES, "surface");
    double sc = map_scale(&m);
    cm_err err = CM_OK;
    switch (e->type) {
    case 128:
        err = bspline_128(f, e, &m, out, st);
        break;
    case 108: {
        double a, b, c, d;
        if (iges_num(f, e, 0, &a) || iges_num(f, e, 1, &b) || iges_num(f, e, 2, &c) || iges_num(f, e, 3, &d))
            return cm_fail(st, CM_E_IGES, "108");
        cm_vec3 n = cm_v3(a, b, c);
        if (!(cm_norm(n) > 0))
            return iges_entity_error(f, e, "plane normal is zero"), cm_fail(st, CM_E_IGES, "108");
        cm_vec3 P = haffine_apply(&m, cm_scale(n, d / cm_norm2(n)));
        err = plane_patch(f, e, P, cm_unit(haffine_apply_dir(&m, n)), NULL, extent, out, st);
        break;
    }
    case 190: {
        cm_vec3 P, N, ref;
        int r;
        if (point_116(f, e, 0, &m, &P) || dir_123(f, e, 1, &m, 0, &N) || (r = dir_123(f, e, 2, &m, 1, &ref)) < 0)
            return cm_fail(st, CM_E_IGES, "190");
        err = plane_patch(f, e, P, N, r == 0 ? &ref : NULL, extent, out, st);
        break;
    }
    case 192:
    case 194: {
        cm_vec3 P, Z, ref, X, Y;
        double rad, semi = 0.0;
        int r, ref_i = e->type == 192 ? 3 : 4;
        if (point_116(f, e, 0, &m, &P) || dir_123(f, e, 1, &m, 0, &Z) || iges_num(f, e, 2, &rad) ||
            (e->type == 194 && iges_num(f, e, 3, &semi)) || (r = dir_123(f, e, ref_i, &m, 1, &ref)) < 0)
            return cm_fail(st, CM_E_IGES, "cylinder/cone");
        if (!(rad >= 0) || (e->type == 192 && !(rad > 0)) || !(fabs(semi) < 90.0))
            return iges_entity_error(f, e, "radius %g / semi-angle %g out of range", rad, semi),
                   cm_fail(st, CM_E_IGES, "cylinder/cone");
        if (!extent || extent->empty)
            return iges_entity_error(f, e, "unbounded surface used without a bounded face"),
                   cm_fail(st, CM_E_IGES, "cylinder/cone");
        hbox_frame(Z, r == 0 ? &ref : NULL, &X, &Y);
        double v0, v1;
        hbox_axis_range(extent, P, Z, &v0, &v1);
        if (e->type == 192) {
            err = hsurf_cylinder(P, X, Y, Z, rad * sc, 0, 2 * M_PI, v0, v1, out, st);
        } else {
            double ta = tan(semi * M_PI / 180.0), apex = ta != 0 ? -rad * sc / ta : -HUGE_VAL;
            if (ta > 0 && v0 < apex)
                v0 = apex;
            if (ta < 0 && v1 > apex)
                v1 = apex;
            err = hsurf_cone(P, X, Y, Z, rad * sc, semi * M_PI / 180.0, 0, 2 * M_PI, v0, v1, out, st);
        }
        break;
    }
    case 196:
    case 198: {
        cm_vec3 P, Z = cm_v3(0, 0, 1), ref, X, Y;
        double r1, r2 = 0;
        int r, zi = e->type == 196 ? 2 : 1;
        if (point_116(f, e, 0, &m, &P) || (e->type == 196 ? iges_num(f, e, 1, &r1) : 0) ||
            (e->type == 198 && (iges_num(f, e, 2, &r1) || iges_num(f, e, 3, &r2))) ||
            dir_123(f, e, zi, &m, e->type == 196, &Z) < 0 || (r = dir_123(f, e, e->type == 196 ? 3 : 4, &m, 1, &ref)) < 0)
            return cm_fail(st, CM_E_IGES, "sphere/torus");
        if (!(r1 > 0) || (e->type == 198 && !(r2 > 0)))
            return iges_entity_error(f, e, "non-positive radius"), cm_fail(st, CM_E_IGES, "sphere/torus");
        hbox_frame(Z, r == 0 ? &ref : NULL, &X, &Y);
        if (e->type == 196)
            err = hsurf_sphere(P, X, Y, Z, r1 * sc, 0, 2 * M_PI, -M_PI / 2, M_PI / 2, out, st);
        else
            err = hsurf_torus(P, X, Y, Z, r1 * sc, r2 * sc, 0, 2 * M_PI, -M_PI, M_PI, out, st);
        break;
    }
    case 118: {
        int d1, d2, dirflg = iges_int_or(e, 2, 0);
        if (iges_ptr(f, e, 0, 0, &d1) || iges_ptr(f, e, 1, 0, &d2))
            return cm_fail(st, CM_E_IGES, "118");
        hcurve a = {0}, b = {0};
        err = single_curve(f, d1, &m, &a, st);
        if (err == CM_OK)
            err = single_curve(f, d2, &m, &b, st);
        if (err == CM_OK) {
            if (dirflg == 1)
                hcurve_reverse(&b);
            if (e->form == 0)
                iges_warn(f, e->pd_line, "ruled surface DE %d: form 0 (equal arc length) built as form 1 (equal "
                                         "parameter); exact only for uniformly parametrised rails", e->de);
            err = hsurf_ruled(&a, &b, out, st);
        }
        hcurve_free(&a);
        hcurve_free(&b);
        break;
    }
    case 120: {
        int dl, dc;
        double sa, ta;
        if (iges_ptr(f, e, 0, 0, &dl) || iges_ptr(f, e, 1, 0, &dc) || iges_num(f, e, 2, &sa) || iges_num(f, e, 3, &ta))
            return cm_fail(st, CM_E_IGES, "120");
        const iges_entity *axis = iges_by_de(f, dl);
        haffine am;
        if (axis->type != 110 || axis->bad || entity_map(f, axis, &m, &am))
            return iges_entity_error(f, e, "axis must be a line (110)"), cm_fail(st, CM_E_IGES, "120");
        cm_vec3 A = haffine_apply(&am, cm_v3(iges_num_or(axis, 0, (double)NAN), iges_num_or(axis, 1, (double)NAN),
                                             iges_num_or(axis, 2, (double)NAN)));
        cm_vec3 B = haffine_apply(&am, cm_v3(iges_num_or(axis, 3, (double)NAN), iges_num_or(axis, 4, (double)NAN),
                                             iges_num_or(axis, 5, (double)NAN)));
        if (!cm_finite3(A) || !cm_finite3(B) || !(cm_dist(A, B) > 0))
            return iges_entity_error(f, e, "axis line is degenerate"), cm_fail(st, CM_E_IGES, "120");
        if (!(ta > sa) || ta - sa > 2 * M_PI * (1 + 1e-9))
            return iges_entity_error(f, e, "rotation angles [%g, %g] are not an increasing range of at most 2 pi",
                                     sa, ta),
                   cm_fail(st, CM_E_IGES, "120");
        if (ta - sa > 2 * M_PI)
            ta = sa + 2 * M_PI;
        mark_used(f, axis);
        hcurve g = {0};
        err = single_curve(f, dc, &m, &g, st);
        /*
         * The generatrix turns about the axis by the right-hand rule in the entity's own frame.
         * Axis and generatrix arrive here already mapped to model space; when the entity's
         * transformation mirrors (determinant < 0, a 124 of form 1, as OCCT writes mirrored parts)
         * the mapped rotation turns the other way, so the axis is reversed (OCCT revolves in the
         * local frame and moves the result: the same surface).
         */
        double det = m.R[0][0] * (m.R[1][1] * m.R[2][2] - m.R[1][2] * m.R[2][1]) -
                     m.R[0][1] * (m.R[1][0] * m.R[2][2] - m.R[1][2] * m.R[2][0]) +
                     m.R[0][2] * (m.R[1][0] * m.R[2][1] - m.R[1][1] * m.R[2][0]);
        cm_vec3 dir = det < 0 ? cm_sub(A, B) : cm_sub(B, A);
        if (err == CM_OK)
            err = hsurf_revolve(&g, A, dir, sa, ta, out, st);
        hcurve_free(&g);
        break;
    }
    case 122: {
        int dc;
        double l[3];
        if (iges_ptr(f, e, 0, 0, &dc) || iges_num(f, e, 1, &l[0]) || iges_num(f, e, 2, &l[1]) || iges_num(f, e, 3, &l[2]))
            return cm_fail(st, CM_E_IGES, "122");
        hcurve c = {0};
        err = single_curve(f, dc, &m, &c, st);
        if (err == CM_OK) {
            cm_vec3 d0[1];
            double t0, t1;
            hcurve_domain(&c, &t0, &t1);
            cm_curve v = hcurve_view(&c);
            err = cm_curve_eval(&v, t0, 0, d0, st);
            if (err == CM_OK)
                err = hsurf_extrude(&c, cm_sub(haffine_apply(&m, cm_v3(l[0], l[1], l[2])), d0[0]), out, st);
        }
        hcurve_free(&c);
        break;
    }
    default:
        return iges_entity_error(f, e, "entity type %d is not a supported surface", e->type),
               cm_fail(st, CM_E_UNSUPPORTED, "surface");
    }
    if (err == CM_OK) {
        double worst = 0;
        if (!iges_coords_sane(out->ctrl, (long)out->nu * out->nv, &worst)) {
            char note[96];
            hsurf_free(out);
            return iges_entity_error(f, e, "in model space its control points reach %g mm, beyond +-%g mm%s", worst,
                                     IGES_MAX_COORD_MM, xform_note(e, note, sizeof note)),
                   cm_fail(st, CM_E_RANGE, "surface coordinates");
        }
        mark_used(f, e);
    } else if (err == CM_E_NOMEM) {
        iges_nomem(f, e->pd_line, "building entity %d, DE %d", e->type, e->de); /* not the entity's fault */
    } else if (f->err[0] == 0) {
        iges_entity_error(f, e, "cannot build the surface: %s", cm_strerror(err));
    }
    return err;
}

cm_err iges_surface(iges_file *f, int de, const haffine *parent, const hbox *extent, hsurf *out, cm_status *st)
{
    return surface_rec(f, de, parent, extent, out, st);
}
