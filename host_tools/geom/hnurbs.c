/*
 * hnurbs.c - owned NURBS curves and surfaces and the exact constructions of
 * hnurbs.h (The NURBS Book notation: A5.1 knot insertion, A5.4 knot
 * refinement, eq. 5.36 Bezier degree elevation, A7.1-style circular arcs,
 * A8.1-style surfaces of revolution).
 *
 * Host code: allocates, uses sin/cos, has no size limit on control point
 * counts (the shared kernel's cm_curve_insert_knot stops at
 * CM_MAX_EDGE_CTRL, so the curves are held here, in homogeneous
 * coordinates, and the kernel's per-span steps do the arithmetic: knot
 * insertion by cm_knot_insert_steps, degree elevation by cm_bez_elevate_h;
 * knot refinement, A5.4, is only here).  Degrees stay within CM_MAX_DEGREE
 * because the shared evaluators refuse anything higher.
 *
 * Conventions of every builder: inputs are validated first (CM_E_ARG,
 * CM_E_KNOTS, CM_E_DEGENERATE, ...); the result is built in a temporary and
 * moved into `out` at the end, after `out`'s previous contents are freed, so
 * `out` may even alias an input.  On error `out` is left empty.  Allocation
 * failure is CM_E_NOMEM.
 */
#include "geom/hnurbs.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_bezier.h"
#include "cm/cm_limits_info.h"

#define HN_PI 3.14159265358979323846
#define HN_2PI (2.0 * HN_PI)
#define HN_HALF_PI (0.5 * HN_PI)
/* control point counts stay far below INT_MAX, so n + p + 1, n + r etc. cannot overflow */
#define HN_MAX_COUNT (INT_MAX / 4)

/* ---- allocation (with the tests' fault injection) ---- */

static _Thread_local int fail_countdown = -1;

void hnurbs_fail_alloc_after(int n) { fail_countdown = n < 0 ? -1 : n; }

int hnurbs_fail_alloc_pending(void) { return fail_countdown >= 0; }

/* Zeroed array of `count` elements, or NULL (exhausted, overflow, or the injected failure). */
static void *hn_calloc(size_t count, size_t size)
{
    if (fail_countdown == 0) {
        fail_countdown = -1;
        return NULL;
    }
    if (fail_countdown > 0)
        fail_countdown--;
    if (count == 0)
        count = 1; /* calloc(0) may return NULL, which would look like a failure */
    return calloc(count, size);
}

/* ---- storage ---- */

static cm_err check_degree(int p, cm_status *st, const char *where)
{
    if (p < 1)
        return cm_fail(st, CM_E_ARG, where);
    if (p > CM_MAX_DEGREE)
        return cm_fail_limit(st, CM_LIMIT_MAX_DEGREE, (uint64_t)p, CM_MAX_DEGREE, where);
    return CM_OK;
}

cm_err hcurve_alloc(hcurve *c, int p, int n, int rational, cm_status *st)
{
    if (!c)
        return cm_fail(st, CM_E_ARG, __func__);
    hcurve_free(c);
    cm_err e = check_degree(p, st, __func__);
    if (e != CM_OK)
        return e;
    if (n < p + 1 || n > HN_MAX_COUNT)
        return cm_fail(st, CM_E_ARG, __func__);
    c->knots = hn_calloc((size_t)(n + p + 1), sizeof *c->knots);
    c->ctrl = hn_calloc((size_t)n, sizeof *c->ctrl);
    if (rational)
        c->w = hn_calloc((size_t)n, sizeof *c->w);
    if (!c->knots || !c->ctrl || (rational && !c->w)) {
        hcurve_free(c);
        return cm_fail(st, CM_E_NOMEM, __func__);
    }
    for (int i = 0; rational && i < n; i++)
        c->w[i] = 1.0;
    c->p = p;
    c->n = n;
    return CM_OK;
}

cm_err hsurf_alloc(hsurf *s, int p, int q, int nu, int nv, int rational, cm_status *st)
{
    if (!s)
        return cm_fail(st, CM_E_ARG, __func__);
    hsurf_free(s);
    cm_err e = check_degree(p, st, __func__);
    if (e == CM_OK)
        e = check_degree(q, st, __func__);
    if (e != CM_OK)
        return e;
    if (nu < p + 1 || nv < q + 1 || nu > HN_MAX_COUNT || nv > HN_MAX_COUNT)
        return cm_fail(st, CM_E_ARG, __func__);
    size_t total = (size_t)nu * (size_t)nv; /* fits: both below INT_MAX/4, size_t is 64-bit on hosts */
    s->U = hn_calloc((size_t)(nu + p + 1), sizeof *s->U);
    s->V = hn_calloc((size_t)(nv + q + 1), sizeof *s->V);
    s->ctrl = hn_calloc(total, sizeof *s->ctrl);
    if (rational)
        s->w = hn_calloc(total, sizeof *s->w);
    if (!s->U || !s->V || !s->ctrl || (rational && !s->w)) {
        hsurf_free(s);
        return cm_fail(st, CM_E_NOMEM, __func__);
    }
    for (size_t i = 0; rational && i < total; i++)
        s->w[i] = 1.0;
    s->p = p;
    s->q = q;
    s->nu = nu;
    s->nv = nv;
    return CM_OK;
}

void hcurve_free(hcurve *c)
{
    if (!c)
        return;
    free(c->knots);
    free(c->ctrl);
    free(c->w);
    memset(c, 0, sizeof *c);
}

void hsurf_free(hsurf *s)
{
    if (!s)
        return;
    free(s->U);
    free(s->V);
    free(s->ctrl);
    free(s->w);
    memset(s, 0, sizeof *s);
}

/* The arrays exist and the counts are consistent (enough to copy or walk the curve). */
static int curve_shaped(const hcurve *c)
{
    return c && c->knots && c->ctrl && c->p >= 1 && c->n >= c->p + 1 && c->n <= HN_MAX_COUNT;
}

static int surf_shaped(const hsurf *s)
{
    return s && s->U && s->V && s->ctrl && s->p >= 1 && s->q >= 1 && s->nu >= s->p + 1 && s->nv >= s->q + 1 &&
           s->nu <= HN_MAX_COUNT && s->nv <= HN_MAX_COUNT;
}

/* Finite control points and finite positive weights (the kernels' rules). */
static cm_err check_points(const cm_vec3 *P, const double *w, size_t n, cm_status *st, const char *where)
{
    for (size_t i = 0; i < n; i++) {
        if (!cm_finite3(P[i]) || (w && !isfinite(w[i])))
            return cm_fail(st, CM_E_NONFINITE, where);
        if (w && !(w[i] > 0.0))
            return cm_fail(st, CM_E_RANGE, where);
    }
    return CM_OK;
}

/* Everything the algorithms below rely on: shape, degree, knot vector, points and weights. */
static cm_err check_curve(const hcurve *c, cm_status *st, const char *where)
{
    if (!curve_shaped(c))
        return cm_fail(st, CM_E_ARG, where);
    cm_err e = check_degree(c->p, st, where);
    if (e == CM_OK)
        e = cm_knots_check(c->p, c->n, c->knots, st);
    if (e == CM_OK)
        e = check_points(c->ctrl, c->w, (size_t)c->n, st, where);
    return e;
}

static cm_err check_surf(const hsurf *s, cm_status *st, const char *where)
{
    if (!surf_shaped(s))
        return cm_fail(st, CM_E_ARG, where);
    cm_err e = check_degree(s->p, st, where);
    if (e == CM_OK)
        e = check_degree(s->q, st, where);
    if (e == CM_OK)
        e = cm_knots_check(s->p, s->nu, s->U, st);
    if (e == CM_OK)
        e = cm_knots_check(s->q, s->nv, s->V, st);
    if (e == CM_OK)
        e = check_points(s->ctrl, s->w, (size_t)s->nu * (size_t)s->nv, st, where);
    return e;
}

/* Move a finished temporary into `out` (freeing what `out` held), or drop both on error. */
static cm_err curve_finish(hcurve *tmp, hcurve *out, cm_err e)
{
    hcurve_free(out);
    if (e == CM_OK)
        *out = *tmp;
    else
        hcurve_free(tmp);
    return e;
}

static cm_err surf_finish(hsurf *tmp, hsurf *out, cm_err e)
{
    hsurf_free(out);
    if (e == CM_OK)
        *out = *tmp;
    else
        hsurf_free(tmp);
    return e;
}

cm_err hcurve_copy(const hcurve *c, hcurve *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    if (!curve_shaped(c))
        return curve_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    hcurve t = {0};
    cm_err e = hcurve_alloc(&t, c->p, c->n, c->w != NULL, st);
    if (e == CM_OK) {
        memcpy(t.knots, c->knots, (size_t)(c->n + c->p + 1) * sizeof *t.knots);
        memcpy(t.ctrl, c->ctrl, (size_t)c->n * sizeof *t.ctrl);
        if (c->w)
            memcpy(t.w, c->w, (size_t)c->n * sizeof *t.w);
    }
    return curve_finish(&t, out, e);
}

cm_err hsurf_copy(const hsurf *s, hsurf *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    if (!surf_shaped(s))
        return surf_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    hsurf t = {0};
    cm_err e = hsurf_alloc(&t, s->p, s->q, s->nu, s->nv, s->w != NULL, st);
    if (e == CM_OK) {
        size_t total = (size_t)s->nu * (size_t)s->nv;
        memcpy(t.U, s->U, (size_t)(s->nu + s->p + 1) * sizeof *t.U);
        memcpy(t.V, s->V, (size_t)(s->nv + s->q + 1) * sizeof *t.V);
        memcpy(t.ctrl, s->ctrl, total * sizeof *t.ctrl);
        if (s->w)
            memcpy(t.w, s->w, total * sizeof *t.w);
    }
    return surf_finish(&t, out, e);
}

cm_curve hcurve_view(const hcurve *c)
{
    cm_curve v = {c->p, c->n, c->knots, c->ctrl, c->w};
    return v;
}

cm_surf hsurf_view(const hsurf *s)
{
    cm_surf v = {s->p, s->q, s->nu, s->nv, s->U, s->V, s->ctrl, s->w};
    return v;
}

void hcurve_domain(const hcurve *c, double *t0, double *t1)
{
    int ok = curve_shaped(c);
    *t0 = ok ? c->knots[c->p] : 0.0;
    *t1 = ok ? c->knots[c->n] : 0.0;
}

void hsurf_domain(const hsurf *s, double *u0, double *u1, double *v0, double *v1)
{
    int ok = surf_shaped(s);
    *u0 = ok ? s->U[s->p] : 0.0;
    *u1 = ok ? s->U[s->nu] : 0.0;
    *v0 = ok ? s->V[s->q] : 0.0;
    *v1 = ok ? s->V[s->nv] : 0.0;
}

/* ---- knot vector maps shared by reparam, reverse and the working curves ---- */

/*
 * Map knots affinely from [t0,t1] onto [a,b].  The domain ends land exactly
 * on a and b; rounded interior knots are kept inside [a,b] (and knots
 * outside the domain outside it), so the vector stays non-decreasing.
 */
static void map_knots(double *U, int m, double t0, double t1, double a, double b)
{
    double s = (b - a) / (t1 - t0);
    for (int i = 0; i < m; i++) {
        double u = U[i], v;
        if (u == t0)
            v = a;
        else if (u == t1)
            v = b;
        else {
            v = a + (u - t0) * s;
            if (u < t0)
                v = fmin(v, a);
            else if (u > t1)
                v = fmax(v, b);
            else
                v = fmin(fmax(v, a), b);
        }
        U[i] = v;
    }
}

/* u -> t0 + t1 - u with the same care as map_knots: ends exact, regions kept apart. */
static double mirror_knot(double u, double t0, double t1)
{
    if (u == t0)
        return t1;
    if (u == t1)
        return t0;
    double v = (t0 + t1) - u;
    if (u < t0)
        return fmax(v, t1);
    if (u > t1)
        return fmin(v, t0);
    return fmin(fmax(v, t0), t1);
}

/* ---- homogeneous working curves: insertion, refinement, elevation ---- */

/* A curve in homogeneous form (w*P, w); polynomial curves carry w = 1. */
typedef struct hwork {
    int p, n;
    double *U;  /* n + p + 1 */
    cm_hpt *P;  /* n */
} hwork;

static void hw_free(hwork *h)
{
    free(h->U);
    free(h->P);
    memset(h, 0, sizeof *h);
}

static cm_err hw_alloc(hwork *h, int p, int n, cm_status *st, const char *where)
{
    memset(h, 0, sizeof *h);
    if (n > HN_MAX_COUNT)
        return cm_fail(st, CM_E_ARG, where);
    h->U = hn_calloc((size_t)(n + p + 1), sizeof *h->U);
    h->P = hn_calloc((size_t)n, sizeof *h->P);
    if (!h->U || !h->P) {
        hw_free(h);
        return cm_fail(st, CM_E_NOMEM, where);
    }
    h->p = p;
    h->n = n;
    return CM_OK;
}

/* (1-alpha) a + alpha b, the affine step of knot refinement */
static cm_hpt h4_lerp(cm_hpt a, cm_hpt b, double alpha)
{
    double beta = 1.0 - alpha;
    cm_hpt r = {beta * a.x + alpha * b.x, beta * a.y + alpha * b.y, beta * a.z + alpha * b.z,
                beta * a.w + alpha * b.w};
    return r;
}

static cm_err hw_from_curve(const hcurve *c, hwork *h, cm_status *st, const char *where)
{
    cm_err e = hw_alloc(h, c->p, c->n, st, where);
    if (e != CM_OK)
        return e;
    memcpy(h->U, c->knots, (size_t)(c->n + c->p + 1) * sizeof *h->U);
    for (int i = 0; i < c->n; i++) {
        double w = c->w ? c->w[i] : 1.0;
        cm_hpt q = {c->ctrl[i].x * w, c->ctrl[i].y * w, c->ctrl[i].z * w, w};
        h->P[i] = q;
    }
    return CM_OK;
}

/*
 * Back to Euclidean form.  A curve that was polynomial keeps its x,y,z as
 * they are (its w channel is 1 up to the rounding of the affine steps and
 * carries no information); `rational` asks for a weight array anyway.
 */
static cm_err hw_to_curve(const hwork *h, int src_rational, int rational, hcurve *out, cm_status *st)
{
    cm_err e = hcurve_alloc(out, h->p, h->n, rational, st);
    if (e != CM_OK)
        return e;
    memcpy(out->knots, h->U, (size_t)(h->n + h->p + 1) * sizeof *h->U);
    for (int i = 0; i < h->n; i++) {
        cm_hpt q = h->P[i];
        if (src_rational) {
            out->ctrl[i] = cm_v3(q.x / q.w, q.y / q.w, q.z / q.w);
            if (rational)
                out->w[i] = q.w;
        } else {
            out->ctrl[i] = cm_v3(q.x, q.y, q.z);
        }
    }
    return CM_OK;
}

/* Index k of the span with U[k] <= u < U[k+1] (u in [U[p], U[n])) and the multiplicity s of u. */
static int hw_span(const hwork *h, double u, int *s)
{
    int k = cm_bspl_find_span(h->n, h->p, h->U, u);
    int m = 0;
    for (int i = k; i >= 0 && h->U[i] == u; i--)
        m++;
    *s = m;
    return k;
}

/* A5.1: insert u (U[p] <= u < U[n]) r times, r + multiplicity <= p (the kernel's steps, any count). */
static cm_err hw_insert(hwork *h, double u, int r, cm_status *st, const char *where)
{
    if (r <= 0)
        return CM_OK;
    int p = h->p, n = h->n, s;
    int k = hw_span(h, u, &s);
    const double *U = h->U;
    const cm_hpt *P = h->P;
    hwork q;
    cm_err e = hw_alloc(&q, p, n + r, st, where);
    if (e != CM_OK)
        return e;
    for (int i = 0; i <= k; i++)
        q.U[i] = U[i];
    for (int i = 1; i <= r; i++)
        q.U[k + i] = u;
    for (int i = k + 1; i <= n + p; i++)
        q.U[i + r] = U[i];
    for (int i = 0; i <= k - p; i++)
        q.P[i] = P[i];
    for (int i = k - s; i < n; i++)
        q.P[i + r] = P[i];
    cm_hpt R[CM_MAX_ORDER];
    for (int i = 0; i <= p - s; i++)
        R[i] = P[k - p + i];
    cm_knot_insert_steps(U, p, k, s, r, u, R, q.P + (k - p + 1));
    hw_free(h);
    *h = q;
    return CM_OK;
}

/*
 * Cut the curve at u (U[p] <= u < U[n]) and keep the part after it as a
 * curve clamped at u: insert u up to multiplicity p, then the control
 * point at u is P[b-p] (b = last index of u) and everything before it
 * only shapes the discarded part.
 */
static cm_err hw_cut_left(hwork *h, double u, cm_status *st, const char *where)
{
    int s;
    hw_span(h, u, &s);
    cm_err e = hw_insert(h, u, h->p - s, st, where);
    if (e != CM_OK)
        return e;
    int p = h->p, b = hw_span(h, u, &s), drop = b - p;
    int nk = h->n + p + 1;
    for (int i = 0; i <= p; i++)
        h->U[i] = u;
    memmove(h->U + p + 1, h->U + b + 1, (size_t)(nk - b - 1) * sizeof *h->U);
    memmove(h->P, h->P + drop, (size_t)(h->n - drop) * sizeof *h->P);
    h->n -= drop;
    return CM_OK;
}

/* Run the curve backwards with knots u -> -u: exact (negation does not round), undone by itself. */
static void hw_mirror(hwork *h)
{
    int m = h->n + h->p + 1;
    for (int i = 0, j = m - 1; i < j; i++, j--) {
        double t = h->U[i];
        h->U[i] = h->U[j];
        h->U[j] = t;
    }
    for (int i = 0; i < m; i++)
        h->U[i] = -h->U[i];
    for (int i = 0, j = h->n - 1; i < j; i++, j--) {
        cm_hpt t = h->P[i];
        h->P[i] = h->P[j];
        h->P[j] = t;
    }
}

/* The piece [t0, t1] of the domain as a clamped curve: cut at t0, then (mirrored) at t1. */
static cm_err hw_restrict(hwork *h, double t0, double t1, cm_status *st, const char *where)
{
    cm_err e = hw_cut_left(h, t0, st, where);
    if (e != CM_OK)
        return e;
    hw_mirror(h);
    e = hw_cut_left(h, -t1, st, where);
    hw_mirror(h);
    return e;
}

/*
 * A5.4: insert the non-decreasing knots X[0..nx-1], all strictly inside the
 * domain of a clamped curve, in one pass.
 */
static cm_err hw_refine(hwork *h, const double *X, int nx, cm_status *st, const char *where)
{
    if (nx <= 0)
        return CM_OK;
    int p = h->p, nl = h->n - 1, m = h->n + p, r = nx - 1;
    const double *U = h->U;
    const cm_hpt *P = h->P;
    hwork q;
    if (h->n > HN_MAX_COUNT - nx)
        return cm_fail(st, CM_E_ARG, where);
    cm_err e = hw_alloc(&q, p, h->n + nx, st, where);
    if (e != CM_OK)
        return e;
    double *Ub = q.U;
    cm_hpt *Q = q.P;
    int a = cm_bspl_find_span(h->n, p, U, X[0]);
    int b = cm_bspl_find_span(h->n, p, U, X[r]) + 1;
    for (int j = 0; j <= a - p; j++)
        Q[j] = P[j];
    for (int j = b - 1; j <= nl; j++)
        Q[j + r + 1] = P[j];
    for (int j = 0; j <= a; j++)
        Ub[j] = U[j];
    for (int j = b + p; j <= m; j++)
        Ub[j + r + 1] = U[j];
    int i = b + p - 1, k = b + p + r;
    for (int j = r; j >= 0; j--) {
        while (X[j] <= U[i] && i > a) {
            Q[k - p - 1] = P[i - p - 1];
            Ub[k] = U[i];
            k--;
            i--;
        }
        Q[k - p - 1] = Q[k - p];
        for (int l = 1; l <= p; l++) {
            int ind = k - p + l;
            double alpha = Ub[k + l] - X[j];
            if (alpha == 0.0) {
                Q[ind - 1] = Q[ind];
            } else {
                alpha /= Ub[k + l] - U[i - p + l];
                Q[ind - 1] = h4_lerp(Q[ind], Q[ind - 1], alpha);
            }
        }
        Ub[k] = X[j];
        k--;
    }
    hw_free(h);
    *h = q;
    return CM_OK;
}

/*
 * Raise a clamped curve to degree new_p: refine every interior knot to
 * multiplicity p (Bezier decomposition), elevate each segment (eq. 5.36,
 * the kernel's cm_bez_elevate_h: end points copied exactly), reassemble
 * with multiplicity new_p at the breakpoints (new_p + 1 where the input had
 * a full-multiplicity knot, so a discontinuity stays one).  Shared end points
 * of neighbouring segments are bit-identical, so nothing is averaged.
 */
static cm_err hw_elevate(hwork *h, int new_p, cm_status *st, const char *where)
{
    int p = h->p, t = new_p - p;
    if (t <= 0)
        return CM_OK;
    /* 1. Bezier decomposition */
    int ninner = h->n - p - 1; /* interior knots of a clamped vector: U[p+1 .. n-1] */
    double *X = hn_calloc((size_t)(ninner > 0 ? ninner : 1) * (size_t)p, sizeof *X);
    if (!X)
        return cm_fail(st, CM_E_NOMEM, where);
    int nx = 0;
    for (int i = p + 1; i < h->n;) {
        int s = 1;
        while (i + s < h->n && h->U[i + s] == h->U[i])
            s++;
        for (int k = s; k < p; k++)
            X[nx++] = h->U[i];
        i += s;
    }
    cm_err e = hw_refine(h, X, nx, st, where);
    free(X);
    if (e != CM_OK)
        return e;
    /* 2. count the output: new_p points per segment, +1 for the first and per unshared start */
    long nout = 0;
    int prev = -1;
    for (int k = p; k < h->n; k++) {
        if (!(h->U[k] < h->U[k + 1]))
            continue;
        nout += (prev < 0 || k - p != prev) ? new_p + 1 : new_p;
        prev = k;
    }
    if (nout > HN_MAX_COUNT)
        return cm_fail(st, CM_E_ARG, where);
    hwork q;
    if ((e = hw_alloc(&q, new_p, (int)nout, st, where)) != CM_OK)
        return e;
    /* 3. elevate and reassemble */
    cm_hpt E[CM_MAX_ORDER];
    int np = 0, nk = 0;
    prev = -1;
    for (int k = p; k < h->n; k++) {
        if (!(h->U[k] < h->U[k + 1]))
            continue;
        int shared = prev >= 0 && k - p == prev;
        if ((e = cm_bez_elevate_h(h->P + (k - p), p, t, E, st)) != CM_OK) {
            hw_free(&q);
            return e;
        }
        int mult = prev < 0 ? new_p + 1 : shared ? new_p : new_p + 1;
        for (int j = 0; j < mult; j++)
            q.U[nk++] = h->U[k];
        for (int j = shared ? 1 : 0; j <= new_p; j++)
            q.P[np++] = E[j];
        prev = k;
    }
    for (int j = 0; j <= new_p; j++)
        q.U[nk++] = h->U[h->n];
    hw_free(h);
    *h = q;
    return CM_OK;
}

/* Clamp at both ends of the domain and map the domain onto [0,1]. */
static cm_err hw_normalise(hwork *h, cm_status *st, const char *where)
{
    double t0 = h->U[h->p], t1 = h->U[h->n];
    cm_err e = hw_restrict(h, t0, t1, st, where);
    if (e == CM_OK)
        map_knots(h->U, h->n + h->p + 1, t0, t1, 0.0, 1.0);
    return e;
}

/*
 * The knots each of two clamped vectors on the same domain lacks for their
 * union (each value with the larger multiplicity): Xa for a, Xb for b.
 */
static cm_err knot_union(const hwork *a, const hwork *b, double **Xa, int *na, double **Xb, int *nb,
                         cm_status *st, const char *where)
{
    *Xa = hn_calloc((size_t)(b->n + 1), sizeof **Xa);
    *Xb = hn_calloc((size_t)(a->n + 1), sizeof **Xb);
    *na = *nb = 0;
    if (!*Xa || !*Xb) {
        free(*Xa);
        free(*Xb);
        *Xa = *Xb = NULL;
        return cm_fail(st, CM_E_NOMEM, where);
    }
    /* interior knots only: a->U[pa+1 .. na-1], b->U[pb+1 .. nb-1] */
    int i = a->p + 1, j = b->p + 1;
    while (i < a->n || j < b->n) {
        double u = i < a->n ? a->U[i] : HUGE_VAL;
        if (j < b->n && b->U[j] < u)
            u = b->U[j];
        int ma = 0, mb = 0;
        while (i < a->n && a->U[i] == u)
            i++, ma++;
        while (j < b->n && b->U[j] == u)
            j++, mb++;
        for (int k = ma; k < mb; k++)
            (*Xa)[(*na)++] = u;
        for (int k = mb; k < ma; k++)
            (*Xb)[(*nb)++] = u;
    }
    return CM_OK;
}

/* ---- curve constructions ---- */

static int finite_vecs(const cm_vec3 *v, int n)
{
    for (int i = 0; i < n; i++)
        if (!cm_finite3(v[i]))
            return 0;
    return 1;
}

cm_err hcurve_line(cm_vec3 a, cm_vec3 b, hcurve *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    if (!cm_finite3(a) || !cm_finite3(b))
        return curve_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    if (!(cm_dist(a, b) > 0.0))
        return curve_finish(NULL, out, cm_fail(st, CM_E_DEGENERATE, __func__));
    hcurve t = {0};
    cm_err e = hcurve_alloc(&t, 1, 2, 0, st);
    if (e == CM_OK) {
        t.knots[0] = t.knots[1] = 0.0;
        t.knots[2] = t.knots[3] = 1.0;
        t.ctrl[0] = a;
        t.ctrl[1] = b;
    }
    return curve_finish(&t, out, e);
}

cm_err hcurve_polyline(const cm_vec3 *pts, int n, hcurve *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    if (!pts || n < 2 || n > HN_MAX_COUNT || !finite_vecs(pts, n))
        return curve_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    hcurve t = {0};
    cm_err e = hcurve_alloc(&t, 1, n, 0, st);
    if (e == CM_OK) {
        t.knots[0] = 0.0;
        for (int i = 0; i < n; i++)
            t.knots[i + 1] = (double)i;
        t.knots[n + 1] = (double)(n - 1);
        memcpy(t.ctrl, pts, (size_t)n * sizeof *pts);
    }
    return curve_finish(&t, out, e);
}

/* |t1 - t0| may exceed 2 pi by rounding when the caller wrote t0 + 2 pi: a few ulps of slack. */
static double angle_slack(double t0, double t1)
{
    return 8.0 * DBL_EPSILON * fmax(HN_2PI, fmax(fabs(t0), fabs(t1)));
}

static int angle_range_ok(double t0, double t1)
{
    return isfinite(t0) && isfinite(t1) && t0 < t1 && t1 - t0 <= HN_2PI + angle_slack(t0, t1);
}

/*
 * The unit circle arc (cos t, sin t, 0), t in [t0, t1], as ceil(sweep / 90
 * degrees) rational quadratic spans of equal angle.  Knots t0 (triple),
 * t0 + k h (double), t1 (triple); the control point at each knot is the
 * circle point at that very knot value, so the parameter equals the angle at
 * the knots.  Each span's middle point is the tangent intersection
 * (cos m, sin m) / cos(d/2) with weight cos(d/2), computed from the span's
 * own end angles, so every span is an exact circle even where t1 is not
 * exactly t0 + n h.  A full circle ends on its first point bit for bit.
 */
static cm_err unit_arc(double t0, double t1, hcurve *arc, cm_status *st, const char *where)
{
    double sweep = t1 - t0;
    /* a sweep a rounding error above 90 degrees (t1 = t0 + pi/2 computed) still makes one span */
    int ns = (int)ceil(sweep / HN_HALF_PI - 1e-9);
    if (ns < 1)
        ns = 1;
    int full = fabs(sweep - HN_2PI) <= angle_slack(t0, t1);
    cm_err e = hcurve_alloc(arc, 2, 2 * ns + 1, 1, st);
    if (e != CM_OK)
        return cm_fail(st, e, where);
    double h = sweep / ns;
    for (int i = 0; i < 3; i++) {
        arc->knots[i] = t0;
        arc->knots[2 * ns + 1 + i] = t1;
    }
    for (int k = 1; k < ns; k++)
        arc->knots[2 * k + 1] = arc->knots[2 * k + 2] = t0 + k * h;
    /* the angle of breakpoint k is knots[2k + 2] (k < ns) and t1 for k = ns */
    for (int k = 0; k <= ns; k++) {
        double a = k < ns ? arc->knots[2 * k + 2] : t1;
        arc->ctrl[2 * k] = cm_v3(cos(a), sin(a), 0.0);
        arc->w[2 * k] = 1.0;
    }
    for (int k = 0; k < ns; k++) {
        double a = arc->knots[2 * k + 2], b = k + 1 < ns ? arc->knots[2 * k + 4] : t1;
        double m = 0.5 * (a + b), wm = cos(0.5 * (b - a));
        arc->ctrl[2 * k + 1] = cm_v3(cos(m) / wm, sin(m) / wm, 0.0);
        arc->w[2 * k + 1] = wm;
    }
    if (full)
        arc->ctrl[2 * ns] = arc->ctrl[0];
    return CM_OK;
}

/* X and Y span a plane (not zero, not parallel). */
static int plane_frame_ok(cm_vec3 X, cm_vec3 Y)
{
    return cm_norm(cm_cross(X, Y)) > 0.0;
}

cm_err hcurve_ellipse_arc(cm_vec3 c, cm_vec3 X, cm_vec3 Y, double a, double b, double t0, double t1, hcurve *out,
                          cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    if (!cm_finite3(c) || !cm_finite3(X) || !cm_finite3(Y) || !isfinite(a) || !isfinite(b) || !(a > 0.0) ||
        !(b > 0.0) || !angle_range_ok(t0, t1))
        return curve_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    if (!plane_frame_ok(X, Y))
        return curve_finish(NULL, out, cm_fail(st, CM_E_DEGENERATE, __func__));
    hcurve t = {0};
    cm_err e = unit_arc(t0, t1, &t, st, __func__);
    /* an affine image of the unit circle arc: the ellipse, exactly */
    for (int i = 0; e == CM_OK && i < t.n; i++) {
        cm_vec3 u = t.ctrl[i];
        t.ctrl[i] = cm_add(c, cm_add(cm_scale(X, a * u.x), cm_scale(Y, b * u.y)));
    }
    return curve_finish(&t, out, e);
}

cm_err hcurve_conic_span(cm_vec3 P0, cm_vec3 P1, cm_vec3 P2, double w1, hcurve *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    if (!cm_finite3(P0) || !cm_finite3(P1) || !cm_finite3(P2) || !isfinite(w1) || !(w1 > 0.0))
        return curve_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    if (!(cm_dist(P0, P2) > 0.0))
        return curve_finish(NULL, out, cm_fail(st, CM_E_DEGENERATE, __func__));
    /* w1 == 1 is a parabola: polynomial, which the kernels (K7) treat exactly as such */
    hcurve t = {0};
    cm_err e = hcurve_alloc(&t, 2, 3, w1 != 1.0, st);
    if (e == CM_OK) {
        for (int i = 0; i < 3; i++) {
            t.knots[i] = 0.0;
            t.knots[3 + i] = 1.0;
        }
        t.ctrl[0] = P0;
        t.ctrl[1] = P1;
        t.ctrl[2] = P2;
        if (t.w)
            t.w[1] = w1;
    }
    return curve_finish(&t, out, e);
}

cm_err hcurve_from_cubic_segments(const double *T, const cm_vec3 *coef, int nseg, hcurve *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    if (!T || !coef || nseg < 1 || nseg > (HN_MAX_COUNT - 1) / 3)
        return curve_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    for (int i = 0; i <= nseg; i++)
        if (!isfinite(T[i]) || (i > 0 && !(T[i] > T[i - 1])))
            return curve_finish(NULL, out, cm_fail(st, CM_E_KNOTS, __func__));
    if (!finite_vecs(coef, 4 * nseg))
        return curve_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    hcurve t = {0};
    cm_err e = hcurve_alloc(&t, 3, 3 * nseg + 1, 0, st);
    if (e != CM_OK)
        return curve_finish(&t, out, e);
    for (int i = 0; i < 4; i++) {
        t.knots[i] = T[0];
        t.knots[3 * nseg + 1 + i] = T[nseg];
    }
    for (int i = 1; i < nseg; i++)
        t.knots[3 * i + 1] = t.knots[3 * i + 2] = t.knots[3 * i + 3] = T[i];
    /*
     * Power basis to Bezier on [T[i], T[i+1]] with s = h x, x in [0,1]:
     * b0 = A, b1 = A + hB/3, b2 = A + 2hB/3 + h^2 C/3, b3 = A + hB + h^2 C + h^3 D.
     * Segment i starts at its own A_i (IGES defines the curve there by
     * segment i), so a gap left by the previous segment's end is closed at
     * the breakpoint; the last segment's end is its polynomial value.
     */
    for (int i = 0; i < nseg; i++) {
        double h = T[i + 1] - T[i];
        cm_vec3 A = coef[4 * i], B = cm_scale(coef[4 * i + 1], h), C = cm_scale(coef[4 * i + 2], h * h),
                D = cm_scale(coef[4 * i + 3], h * h * h);
        t.ctrl[3 * i] = A;
        t.ctrl[3 * i + 1] = cm_add(A, cm_scale(B, 1.0 / 3.0));
        t.ctrl[3 * i + 2] = cm_add(cm_add(A, cm_scale(B, 2.0 / 3.0)), cm_scale(C, 1.0 / 3.0));
        if (i == nseg - 1)
            t.ctrl[3 * i + 3] = cm_add(cm_add(A, B), cm_add(C, D));
    }
    return curve_finish(&t, out, CM_OK);
}

cm_vec3 haffine_apply(const haffine *m, cm_vec3 x)
{
    return cm_add(haffine_apply_dir(m, x), m->t);
}

cm_vec3 haffine_apply_dir(const haffine *m, cm_vec3 x)
{
    return cm_v3(m->R[0][0] * x.x + m->R[0][1] * x.y + m->R[0][2] * x.z,
                 m->R[1][0] * x.x + m->R[1][1] * x.y + m->R[1][2] * x.z,
                 m->R[2][0] * x.x + m->R[2][1] * x.y + m->R[2][2] * x.z);
}

int haffine_invert(const haffine *m, haffine *out)
{
    const double(*R)[3] = m->R;
    double c[3][3] = {{R[1][1] * R[2][2] - R[1][2] * R[2][1], R[0][2] * R[2][1] - R[0][1] * R[2][2],
                       R[0][1] * R[1][2] - R[0][2] * R[1][1]},
                      {R[1][2] * R[2][0] - R[1][0] * R[2][2], R[0][0] * R[2][2] - R[0][2] * R[2][0],
                       R[0][2] * R[1][0] - R[0][0] * R[1][2]},
                      {R[1][0] * R[2][1] - R[1][1] * R[2][0], R[0][1] * R[2][0] - R[0][0] * R[2][1],
                       R[0][0] * R[1][1] - R[0][1] * R[1][0]}};
    double det = R[0][0] * c[0][0] + R[0][1] * c[1][0] + R[0][2] * c[2][0];
    if (!(fabs(det) > 1e-12))
        return 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            out->R[i][j] = c[i][j] / det;
    out->t = cm_scale(haffine_apply_dir(out, m->t), -1.0);
    return 1;
}

void haffine_rows(const haffine *m, double rows[12])
{
    const double t[3] = {m->t.x, m->t.y, m->t.z};
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++)
            rows[4 * i + j] = m->R[i][j];
        rows[4 * i + 3] = t[i];
    }
}

haffine haffine_identity(void)
{
    haffine m;
    memset(&m, 0, sizeof m);
    m.R[0][0] = m.R[1][1] = m.R[2][2] = 1.0;
    return m;
}

haffine haffine_compose(const haffine *a, const haffine *b)
{
    haffine r;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            r.R[i][j] = a->R[i][0] * b->R[0][j] + a->R[i][1] * b->R[1][j] + a->R[i][2] * b->R[2][j];
    r.t = haffine_apply(a, b->t);
    return r;
}

void hcurve_transform(hcurve *c, const haffine *m)
{
    if (!curve_shaped(c) || !m)
        return;
    /* rational curves too: the rational basis sums to one, so affine maps commute with it */
    for (int i = 0; i < c->n; i++)
        c->ctrl[i] = haffine_apply(m, c->ctrl[i]);
}

void hcurve_reverse(hcurve *c)
{
    if (!curve_shaped(c))
        return;
    int m = c->n + c->p + 1;
    double t0 = c->knots[c->p], t1 = c->knots[c->n];
    for (int i = 0, j = m - 1; i < j; i++, j--) {
        double t = c->knots[i];
        c->knots[i] = c->knots[j];
        c->knots[j] = t;
    }
    for (int i = 0; i < m; i++)
        c->knots[i] = mirror_knot(c->knots[i], t0, t1);
    for (int i = 0, j = c->n - 1; i < j; i++, j--) {
        cm_vec3 t = c->ctrl[i];
        c->ctrl[i] = c->ctrl[j];
        c->ctrl[j] = t;
        if (c->w) {
            double wt = c->w[i];
            c->w[i] = c->w[j];
            c->w[j] = wt;
        }
    }
}

void hcurve_reparam(hcurve *c, double a, double b)
{
    /* a void function: an invalid range (a >= b, not finite) leaves the curve as it is */
    if (!curve_shaped(c) || !isfinite(a) || !isfinite(b) || !(a < b))
        return;
    map_knots(c->knots, c->n + c->p + 1, c->knots[c->p], c->knots[c->n], a, b);
}

cm_err hcurve_subrange(const hcurve *c, double t0, double t1, hcurve *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    cm_err e = check_curve(c, st, __func__);
    if (e != CM_OK)
        return curve_finish(NULL, out, e);
    double d0 = c->knots[c->p], d1 = c->knots[c->n];
    if (!isfinite(t0) || !isfinite(t1) || !(t0 < t1) || t0 < d0 || t1 > d1)
        return curve_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    hwork h;
    hcurve t = {0};
    e = hw_from_curve(c, &h, st, __func__);
    if (e == CM_OK)
        e = hw_restrict(&h, t0, t1, st, __func__);
    if (e == CM_OK)
        e = hw_to_curve(&h, c->w != NULL, c->w != NULL, &t, st);
    hw_free(&h);
    return curve_finish(&t, out, e);
}

cm_err hcurve_clamp(const hcurve *c, hcurve *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    cm_err e = check_curve(c, st, __func__);
    if (e != CM_OK)
        return curve_finish(NULL, out, e);
    return hcurve_subrange(c, c->knots[c->p], c->knots[c->n], out, st);
}

cm_err hcurve_elevate(const hcurve *c, int new_p, hcurve *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    cm_err e = check_curve(c, st, __func__);
    if (e != CM_OK)
        return curve_finish(NULL, out, e);
    if (new_p < c->p)
        return curve_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    if (new_p > CM_MAX_DEGREE)
        return curve_finish(NULL, out,
                            cm_fail_limit(st, CM_LIMIT_MAX_DEGREE, (uint64_t)new_p, CM_MAX_DEGREE, __func__));
    if (new_p == c->p) /* nothing to raise: an exact copy, clamped or not as it came */
        return hcurve_copy(c, out, st);
    /* the result is clamped on the same domain (the Bezier decomposition needs it) */
    hwork h;
    hcurve t = {0};
    e = hw_from_curve(c, &h, st, __func__);
    if (e == CM_OK)
        e = hw_restrict(&h, c->knots[c->p], c->knots[c->n], st, __func__);
    if (e == CM_OK)
        e = hw_elevate(&h, new_p, st, __func__);
    if (e == CM_OK)
        e = hw_to_curve(&h, c->w != NULL, c->w != NULL, &t, st);
    hw_free(&h);
    return curve_finish(&t, out, e);
}

cm_err hcurve_make_compatible(hcurve *a, hcurve *b, cm_status *st)
{
    cm_err e = check_curve(a, st, __func__);
    if (e == CM_OK)
        e = check_curve(b, st, __func__);
    if (e != CM_OK)
        return e;
    if (a == b)
        return cm_fail(st, CM_E_ARG, __func__);
    hwork ha = {0}, hb = {0};
    hcurve na = {0}, nb = {0};
    double *Xa = NULL, *Xb = NULL;
    int nxa = 0, nxb = 0, P = a->p > b->p ? a->p : b->p, rational = a->w != NULL || b->w != NULL;
    e = hw_from_curve(a, &ha, st, __func__);
    if (e == CM_OK)
        e = hw_from_curve(b, &hb, st, __func__);
    if (e == CM_OK)
        e = hw_normalise(&ha, st, __func__);
    if (e == CM_OK)
        e = hw_normalise(&hb, st, __func__);
    if (e == CM_OK)
        e = hw_elevate(&ha, P, st, __func__);
    if (e == CM_OK)
        e = hw_elevate(&hb, P, st, __func__);
    if (e == CM_OK)
        e = knot_union(&ha, &hb, &Xa, &nxa, &Xb, &nxb, st, __func__);
    if (e == CM_OK)
        e = hw_refine(&ha, Xa, nxa, st, __func__);
    if (e == CM_OK)
        e = hw_refine(&hb, Xb, nxb, st, __func__);
    if (e == CM_OK)
        e = hw_to_curve(&ha, a->w != NULL, rational, &na, st);
    if (e == CM_OK)
        e = hw_to_curve(&hb, b->w != NULL, rational, &nb, st);
    free(Xa);
    free(Xb);
    hw_free(&ha);
    hw_free(&hb);
    if (e != CM_OK) { /* the inputs stay as they were */
        hcurve_free(&na);
        hcurve_free(&nb);
        return e;
    }
    hcurve_free(a);
    hcurve_free(b);
    *a = na;
    *b = nb;
    return CM_OK;
}

/* ---- surface constructions ---- */

static cm_err surf_from_rows(hsurf *t, int p, int nu, const double *U, double v0, double v1, int rational,
                             cm_status *st)
{
    cm_err e = hsurf_alloc(t, p, 1, nu, 2, rational, st);
    if (e != CM_OK)
        return e;
    memcpy(t->U, U, (size_t)(nu + p + 1) * sizeof *U);
    t->V[0] = t->V[1] = v0;
    t->V[2] = t->V[3] = v1;
    return CM_OK;
}

cm_err hsurf_plane(cm_vec3 o, cm_vec3 X, cm_vec3 Y, double u0, double u1, double v0, double v1, hsurf *out,
                   cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    if (!cm_finite3(o) || !cm_finite3(X) || !cm_finite3(Y) || !isfinite(u0) || !isfinite(u1) || !isfinite(v0) ||
        !isfinite(v1) || !(u0 < u1) || !(v0 < v1))
        return surf_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    if (!plane_frame_ok(X, Y))
        return surf_finish(NULL, out, cm_fail(st, CM_E_DEGENERATE, __func__));
    hsurf t = {0};
    const double U[4] = {u0, u0, u1, u1};
    cm_err e = surf_from_rows(&t, 1, 2, U, v0, v1, 0, st);
    /* bilinear interpolation of an affine map is the map itself */
    for (int i = 0; e == CM_OK && i < 2; i++)
        for (int j = 0; j < 2; j++)
            t.ctrl[i * 2 + j] = cm_add(o, cm_add(cm_scale(X, i ? u1 : u0), cm_scale(Y, j ? v1 : v0)));
    return surf_finish(&t, out, e);
}

cm_err hsurf_ruled(const hcurve *a, const hcurve *b, hsurf *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    hcurve ca = {0}, cb = {0};
    hsurf t = {0};
    cm_err e = check_curve(a, st, __func__);
    if (e == CM_OK)
        e = check_curve(b, st, __func__);
    if (e == CM_OK)
        e = hcurve_copy(a, &ca, st);
    if (e == CM_OK)
        e = hcurve_copy(b, &cb, st);
    if (e == CM_OK)
        e = hcurve_make_compatible(&ca, &cb, st);
    if (e == CM_OK)
        e = surf_from_rows(&t, ca.p, ca.n, ca.knots, 0.0, 1.0, ca.w != NULL, st);
    /*
     * Row v=0 is a, row v=1 is b, each with its own weights: every ruling
     * S(u, .) is the straight segment a(u)-b(u); with rational rails whose
     * weight functions differ, v is not proportional to length along it.
     */
    for (int i = 0; e == CM_OK && i < ca.n; i++) {
        t.ctrl[2 * i] = ca.ctrl[i];
        t.ctrl[2 * i + 1] = cb.ctrl[i];
        if (t.w) {
            t.w[2 * i] = ca.w[i];
            t.w[2 * i + 1] = cb.w[i];
        }
    }
    hcurve_free(&ca);
    hcurve_free(&cb);
    return surf_finish(&t, out, e);
}

cm_err hsurf_revolve(const hcurve *g, cm_vec3 axis_pt, cm_vec3 axis_dir, double a0, double a1, hsurf *out,
                     cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    cm_err e = check_curve(g, st, __func__);
    if (e != CM_OK)
        return surf_finish(NULL, out, e);
    if (!cm_finite3(axis_pt) || !cm_finite3(axis_dir) || !angle_range_ok(a0, a1))
        return surf_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    if (!(cm_norm(axis_dir) > 0.0))
        return surf_finish(NULL, out, cm_fail(st, CM_E_DEGENERATE, __func__));
    cm_vec3 Z = cm_unit(axis_dir);
    hcurve arc = {0};
    hsurf t = {0};
    e = unit_arc(a0, a1, &arc, st, __func__);
    if (e == CM_OK)
        e = hsurf_alloc(&t, g->p, 2, g->n, arc.n, 1, st);
    if (e == CM_OK) {
        memcpy(t.U, g->knots, (size_t)(g->n + g->p + 1) * sizeof *t.U);
        memcpy(t.V, arc.knots, (size_t)(arc.n + 3) * sizeof *t.V);
    }
    /*
     * Control point i turns on its own circle: radial vector R from the axis
     * (not normalised, so a point on the axis needs no special case) and
     * T = Z x R of the same length.  The arc point of angle a is
     * P + (cos a - 1) R + sin a T, which is P itself bit for bit at angle 0.
     */
    for (int i = 0; e == CM_OK && i < g->n; i++) {
        cm_vec3 P = g->ctrl[i], d = cm_sub(P, axis_pt);
        cm_vec3 R = cm_sub(d, cm_scale(Z, cm_dot(d, Z))), T = cm_cross(Z, R);
        double wi = g->w ? g->w[i] : 1.0;
        for (int j = 0; j < arc.n; j++) {
            long idx = (long)i * arc.n + j;
            t.ctrl[idx] = cm_add(P, cm_add(cm_scale(R, arc.ctrl[j].x - 1.0), cm_scale(T, arc.ctrl[j].y)));
            t.w[idx] = wi * arc.w[j];
        }
    }
    hcurve_free(&arc);
    return surf_finish(&t, out, e);
}

cm_err hsurf_extrude(const hcurve *c, cm_vec3 d, hsurf *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    cm_err e = check_curve(c, st, __func__);
    if (e != CM_OK)
        return surf_finish(NULL, out, e);
    if (!cm_finite3(d))
        return surf_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    if (!(cm_norm(d) > 0.0))
        return surf_finish(NULL, out, cm_fail(st, CM_E_DEGENERATE, __func__));
    hsurf t = {0};
    e = surf_from_rows(&t, c->p, c->n, c->knots, 0.0, 1.0, c->w != NULL, st);
    for (int i = 0; e == CM_OK && i < c->n; i++) {
        t.ctrl[2 * i] = c->ctrl[i];
        t.ctrl[2 * i + 1] = cm_add(c->ctrl[i], d);
        if (t.w)
            t.w[2 * i] = t.w[2 * i + 1] = c->w[i];
    }
    return surf_finish(&t, out, e);
}

/*
 * o + rho(v) (cos u X + sin u Y) + z(v) Z for a profile curve
 * v -> (rho, z) = (prof.x, prof.y): the tensor product of the unit arc in u
 * with the profile, weights multiplied.  Exact because the rational arc
 * and the profile each reproduce their own coordinate functions.
 */
static cm_err frame_surface(cm_vec3 o, cm_vec3 X, cm_vec3 Y, cm_vec3 Z, double u0, double u1, const hcurve *prof,
                            hsurf *out, cm_status *st, const char *where)
{
    hcurve arc = {0};
    hsurf t = {0};
    cm_err e = unit_arc(u0, u1, &arc, st, where);
    if (e == CM_OK)
        e = hsurf_alloc(&t, 2, prof->p, arc.n, prof->n, 1, st);
    if (e == CM_OK) {
        memcpy(t.U, arc.knots, (size_t)(arc.n + 3) * sizeof *t.U);
        memcpy(t.V, prof->knots, (size_t)(prof->n + prof->p + 1) * sizeof *t.V);
        for (int i = 0; i < arc.n; i++) {
            cm_vec3 C = cm_add(cm_scale(X, arc.ctrl[i].x), cm_scale(Y, arc.ctrl[i].y));
            for (int j = 0; j < prof->n; j++) {
                long idx = (long)i * prof->n + j;
                t.ctrl[idx] = cm_add(o, cm_add(cm_scale(C, prof->ctrl[j].x), cm_scale(Z, prof->ctrl[j].y)));
                t.w[idx] = arc.w[i] * (prof->w ? prof->w[j] : 1.0);
            }
        }
    }
    hcurve_free(&arc);
    return surf_finish(&t, out, e);
}

static int frame_ok(cm_vec3 o, cm_vec3 X, cm_vec3 Y, cm_vec3 Z)
{
    return cm_finite3(o) && cm_finite3(X) && cm_finite3(Y) && cm_finite3(Z);
}

/* The straight profile (rho0, v0) -> (rho1, v1) with parameter v on [v0, v1]. */
static cm_err line_profile(double rho0, double rho1, double v0, double v1, hcurve *prof, cm_status *st)
{
    cm_err e = hcurve_alloc(prof, 1, 2, 0, st);
    if (e == CM_OK) {
        prof->knots[0] = prof->knots[1] = v0;
        prof->knots[2] = prof->knots[3] = v1;
        prof->ctrl[0] = cm_v3(rho0, v0, 0.0);
        prof->ctrl[1] = cm_v3(rho1, v1, 0.0);
    }
    return e;
}

cm_err hsurf_cylinder(cm_vec3 o, cm_vec3 X, cm_vec3 Y, cm_vec3 Z, double r, double u0, double u1, double v0,
                      double v1, hsurf *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    if (!frame_ok(o, X, Y, Z) || !isfinite(r) || !(r > 0.0) || !angle_range_ok(u0, u1) || !isfinite(v0) ||
        !isfinite(v1) || !(v0 < v1))
        return surf_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    hcurve prof = {0};
    cm_err e = line_profile(r, r, v0, v1, &prof, st);
    if (e == CM_OK)
        e = frame_surface(o, X, Y, Z, u0, u1, &prof, out, st, __func__);
    else
        hsurf_free(out);
    hcurve_free(&prof);
    return e;
}

cm_err hsurf_cone(cm_vec3 o, cm_vec3 X, cm_vec3 Y, cm_vec3 Z, double r, double semi_angle, double u0, double u1,
                  double v0, double v1, hsurf *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    if (!frame_ok(o, X, Y, Z) || !isfinite(r) || !(r >= 0.0) || !isfinite(semi_angle) ||
        !(fabs(semi_angle) < HN_HALF_PI) || !angle_range_ok(u0, u1) || !isfinite(v0) || !isfinite(v1) || !(v0 < v1))
        return surf_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    double ta = tan(semi_angle);
    hcurve prof = {0};
    cm_err e = line_profile(r + v0 * ta, r + v1 * ta, v0, v1, &prof, st);
    if (e == CM_OK)
        e = frame_surface(o, X, Y, Z, u0, u1, &prof, out, st, __func__);
    else
        hsurf_free(out);
    hcurve_free(&prof);
    return e;
}

/* (rho0 + s cos v, s sin v) for v in [v0, v1]: a scaled, shifted unit arc (the meridian). */
static cm_err arc_profile(double rho0, double s, double v0, double v1, hcurve *prof, cm_status *st,
                          const char *where)
{
    cm_err e = unit_arc(v0, v1, prof, st, where);
    for (int j = 0; e == CM_OK && j < prof->n; j++)
        prof->ctrl[j] = cm_v3(rho0 + s * prof->ctrl[j].x, s * prof->ctrl[j].y, 0.0);
    return e;
}

cm_err hsurf_sphere(cm_vec3 o, cm_vec3 X, cm_vec3 Y, cm_vec3 Z, double r, double u0, double u1, double v0, double v1,
                    hsurf *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    /* v is a latitude: [-pi/2, pi/2], with the same few ulps of slack as any angle */
    double sl = angle_slack(v0, v1);
    if (!frame_ok(o, X, Y, Z) || !isfinite(r) || !(r > 0.0) || !angle_range_ok(u0, u1) || !angle_range_ok(v0, v1) ||
        v0 < -HN_HALF_PI - sl || v1 > HN_HALF_PI + sl)
        return surf_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    hcurve prof = {0};
    cm_err e = arc_profile(0.0, r, v0, v1, &prof, st, __func__);
    if (e == CM_OK)
        e = frame_surface(o, X, Y, Z, u0, u1, &prof, out, st, __func__);
    else
        hsurf_free(out);
    hcurve_free(&prof);
    return e;
}

cm_err hsurf_torus(cm_vec3 o, cm_vec3 X, cm_vec3 Y, cm_vec3 Z, double R, double r, double u0, double u1, double v0,
                   double v1, hsurf *out, cm_status *st)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, __func__);
    if (!frame_ok(o, X, Y, Z) || !isfinite(R) || !isfinite(r) || !(R > 0.0) || !(r > 0.0) ||
        !angle_range_ok(u0, u1) || !angle_range_ok(v0, v1))
        return surf_finish(NULL, out, cm_fail(st, CM_E_ARG, __func__));
    hcurve prof = {0};
    cm_err e = arc_profile(R, r, v0, v1, &prof, st, __func__);
    if (e == CM_OK)
        e = frame_surface(o, X, Y, Z, u0, u1, &prof, out, st, __func__);
    else
        hsurf_free(out);
    hcurve_free(&prof);
    return e;
}

void hsurf_transform(hsurf *s, const haffine *m)
{
    if (!surf_shaped(s) || !m)
        return;
    size_t total = (size_t)s->nu * (size_t)s->nv;
    for (size_t i = 0; i < total; i++)
        s->ctrl[i] = haffine_apply(m, s->ctrl[i]);
}

/*
 * The iso-curve at parameter t of direction `fix_u` (1: u fixed, curve in v):
 * contract the fixed direction with its basis functions in homogeneous
 * space; the other direction keeps its degree and knots.
 */
static cm_err iso_curve(const hsurf *s, int fix_u, double t, hcurve *out, cm_status *st, const char *where)
{
    if (!out)
        return cm_fail(st, CM_E_ARG, where);
    cm_err e = check_surf(s, st, where);
    if (e != CM_OK)
        return curve_finish(NULL, out, e);
    int pf = fix_u ? s->p : s->q, nf = fix_u ? s->nu : s->nv;
    int pc = fix_u ? s->q : s->p, nc = fix_u ? s->nv : s->nu;
    const double *Kf = fix_u ? s->U : s->V, *Kc = fix_u ? s->V : s->U;
    if (!isfinite(t) || t < Kf[pf] || t > Kf[nf])
        return curve_finish(NULL, out, cm_fail(st, CM_E_ARG, where));
    double N[CM_MAX_ORDER];
    int span = cm_bspl_find_span(nf, pf, Kf, t);
    hcurve c = {0};
    e = cm_bspl_basis(span, t, pf, Kf, N, st);
    if (e == CM_OK)
        e = hcurve_alloc(&c, pc, nc, s->w != NULL, st);
    if (e == CM_OK)
        memcpy(c.knots, Kc, (size_t)(nc + pc + 1) * sizeof *Kc);
    for (int j = 0; e == CM_OK && j < nc; j++) {
        cm_vec3 acc = cm_v3(0, 0, 0);
        double wacc = 0.0;
        for (int r = 0; r <= pf; r++) {
            int i = span - pf + r;
            long idx = fix_u ? (long)i * s->nv + j : (long)j * s->nv + i;
            double wi = s->w ? s->w[idx] : 1.0;
            acc = cm_axpy(acc, N[r] * wi, s->ctrl[idx]);
            wacc += N[r] * wi;
        }
        c.ctrl[j] = s->w ? cm_scale(acc, 1.0 / wacc) : acc;
        if (c.w)
            c.w[j] = wacc;
    }
    return curve_finish(&c, out, e);
}

cm_err hsurf_iso_u(const hsurf *s, double u, hcurve *out, cm_status *st)
{
    return iso_curve(s, 1, u, out, st, __func__);
}

cm_err hsurf_iso_v(const hsurf *s, double v, hcurve *out, cm_status *st)
{
    return iso_curve(s, 0, v, out, st, __func__);
}

/* S(lo, x) == S(hi, x) within tol at 9 values x of the other direction (u_dir: lo/hi are u). */
static int surf_closed(const hsurf *s, int u_dir, double tol)
{
    if (check_surf(s, NULL, __func__) != CM_OK || !(tol >= 0.0))
        return 0;
    cm_surf v = hsurf_view(s);
    double u0, u1, v0, v1;
    hsurf_domain(s, &u0, &u1, &v0, &v1);
    for (int k = 0; k <= 8; k++) {
        double x = u_dir ? v0 + (v1 - v0) * k / 8.0 : u0 + (u1 - u0) * k / 8.0;
        cm_vec3 A[CM_MAX_DERS + 1][CM_MAX_DERS + 1], B[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
        if (cm_surf_eval(&v, u_dir ? u0 : x, u_dir ? x : v0, 0, A, NULL) != CM_OK ||
            cm_surf_eval(&v, u_dir ? u1 : x, u_dir ? x : v1, 0, B, NULL) != CM_OK)
            return 0;
        if (!(cm_dist(A[0][0], B[0][0]) <= tol))
            return 0;
    }
    return 1;
}

int hsurf_closed_u(const hsurf *s, double tol) { return surf_closed(s, 1, tol); }

int hsurf_closed_v(const hsurf *s, double tol) { return surf_closed(s, 0, tol); }

/* the part [u0,u1] x [v0,v1] of a surface, exactly, column by column then row by row */
cm_err hsurf_subrange(const hsurf *s, double u0, double u1, double v0, double v1, hsurf *out, cm_status *st)
{
    hsurf a = {0};
    cm_err e = CM_OK;
    /* u direction: each column j is a curve in u */
    for (int pass = 0; pass < 2 && e == CM_OK; pass++) {
        const hsurf *src = pass == 0 ? s : &a;
        int along_u = pass == 0;
        int ncurves = along_u ? src->nv : src->nu, nctrl = along_u ? src->nu : src->nv;
        double lo = along_u ? u0 : v0, hi = along_u ? u1 : v1;
        hsurf res = {0};
        for (int c = 0; c < ncurves && e == CM_OK; c++) {
            hcurve col = {0}, sub = {0};
            e = hcurve_alloc(&col, along_u ? src->p : src->q, nctrl, src->w != NULL, st);
            if (e != CM_OK)
                break;
            memcpy(col.knots, along_u ? src->U : src->V, (size_t)(nctrl + col.p + 1) * sizeof(double));
            for (int i = 0; i < nctrl; i++) {
                long idx = along_u ? (long)i * src->nv + c : (long)c * src->nv + i;
                col.ctrl[i] = src->ctrl[idx];
                if (src->w)
                    col.w[i] = src->w[idx];
            }
            e = hcurve_subrange(&col, lo, hi, &sub, st);
            if (e == CM_OK && c == 0)
                e = along_u ? hsurf_alloc(&res, src->p, src->q, sub.n, src->nv, src->w != NULL, st)
                            : hsurf_alloc(&res, src->p, src->q, src->nu, sub.n, src->w != NULL, st);
            if (e == CM_OK) {
                if (c == 0) {
                    memcpy(along_u ? res.U : res.V, sub.knots, (size_t)(sub.n + sub.p + 1) * sizeof(double));
                    memcpy(along_u ? res.V : res.U, along_u ? src->V : src->U,
                           (size_t)(along_u ? src->nv + src->q + 1 : src->nu + src->p + 1) * sizeof(double));
                }
                for (int i = 0; i < sub.n; i++) {
                    long idx = along_u ? (long)i * res.nv + c : (long)c * res.nv + i;
                    res.ctrl[idx] = sub.ctrl[i];
                    if (res.w)
                        res.w[idx] = sub.w ? sub.w[i] : 1.0;
                }
            }
            hcurve_free(&col);
            hcurve_free(&sub);
        }
        if (pass == 0) {
            a = res;
        } else {
            hsurf_free(&a);
            if (e == CM_OK)
                *out = res;
            else
                hsurf_free(&res);
        }
    }
    if (e != CM_OK)
        hsurf_free(&a);
    return e;
}

/* ---- lists ---- */

void hcurve_list_free(hcurve_list *l)
{
    for (int i = 0; i < l->n; i++)
        hcurve_free(&l->c[i]);
    free(l->c);
    memset(l, 0, sizeof *l);
}

cm_err hcurve_list_push(hcurve_list *l, hcurve *c, cm_status *st)
{
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 8;
        hcurve *q = realloc(l->c, (size_t)cap * sizeof *q);
        if (!q)
            return cm_fail(st, CM_E_NOMEM, "out of memory");
        l->c = q;
        l->cap = cap;
    }
    l->c[l->n++] = *c;
    memset(c, 0, sizeof *c);
    return CM_OK;
}
