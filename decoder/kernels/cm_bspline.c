/*
 * cm_bspline.c - B-spline basis, NURBS curve/surface evaluation, knot
 * insertion (spec K1-K3, K5; The NURBS Book A2.1-A2.3, A3.2, A3.6, A4.2,
 * A4.4, A5.1).  See cm_bspline.h for conventions and the contract.
 */
#include "cm/cm_bspline.h"

#include <stddef.h>

#include "cm/cm_limits_info.h"

/* binomial coefficients up to CM_MAX_DERS (the rational quotient rule) */
static const double binom[CM_MAX_DERS + 1][CM_MAX_DERS + 1] = {{1, 0, 0}, {1, 1, 0}, {1, 2, 1}};
_Static_assert(CM_MAX_DERS == 2, "binom[] table is written for CM_MAX_DERS == 2");

static cm_err check_degree(int p, cm_status *st, const char *where)
{
    if (p > CM_MAX_DEGREE)
        return cm_fail_limit(st, CM_LIMIT_MAX_DEGREE, (uint64_t)p, CM_MAX_DEGREE, where);
    if (p < 1)
        return cm_fail(st, CM_E_RANGE, where);
    return CM_OK;
}

cm_err cm_knots_check(int p, int n_ctrl, const double *knots, cm_status *st)
{
    cm_err e = check_degree(p, st, __func__);
    if (e != CM_OK)
        return e;
    if (n_ctrl < p + 1)
        return cm_fail(st, CM_E_RANGE, __func__);
    int m = n_ctrl + p + 1; /* number of knots */
    int mult = 1;
    for (int i = 0; i < m; i++) {
        if (!isfinite(knots[i]))
            return cm_fail(st, CM_E_NONFINITE, __func__);
        if (i > 0) {
            if (knots[i] < knots[i - 1])
                return cm_fail(st, CM_E_KNOTS, __func__);
            mult = (knots[i] == knots[i - 1]) ? mult + 1 : 1;
            if (mult > p + 1)
                return cm_fail(st, CM_E_KNOTS, __func__);
        }
    }
    if (!(knots[p] < knots[n_ctrl]))
        return cm_fail(st, CM_E_KNOTS, __func__); /* empty parameter domain */
    return CM_OK;
}

static cm_err check_points(const cm_vec3 *ctrl, const double *w, long n, cm_status *st, const char *where)
{
    for (long i = 0; i < n; i++) {
        if (!cm_finite3(ctrl[i]))
            return cm_fail(st, CM_E_NONFINITE, where);
        if (w != NULL) {
            if (!isfinite(w[i]))
                return cm_fail(st, CM_E_NONFINITE, where);
            if (!(w[i] > 0.0))
                return cm_fail(st, CM_E_RANGE, where); /* weights must be positive */
        }
    }
    return CM_OK;
}

cm_err cm_curve_check(const cm_curve *c, cm_status *st)
{
    cm_err e = check_degree(c->p, st, __func__);
    if (e != CM_OK)
        return e;
    if (c->n_ctrl > CM_MAX_EDGE_CTRL)
        return cm_fail_limit(st, CM_LIMIT_MAX_EDGE_CTRL, (uint64_t)c->n_ctrl, CM_MAX_EDGE_CTRL, __func__);
    if ((e = cm_knots_check(c->p, c->n_ctrl, c->knots, st)) != CM_OK)
        return e;
    return check_points(c->ctrl, c->w, c->n_ctrl, st, __func__);
}

cm_err cm_surf_check(const cm_surf *s, cm_status *st)
{
    cm_err e;
    if ((e = check_degree(s->p, st, __func__)) != CM_OK || (e = check_degree(s->q, st, __func__)) != CM_OK)
        return e;
    int nmax = s->nu > s->nv ? s->nu : s->nv;
    if (nmax > CM_MAX_SURF_CTRL_DIR)
        return cm_fail_limit(st, CM_LIMIT_MAX_SURF_CTRL_DIR, (uint64_t)nmax, CM_MAX_SURF_CTRL_DIR, __func__);
    long total = (long)s->nu * (long)s->nv;
    if (total > CM_MAX_SURF_CTRL)
        return cm_fail_limit(st, CM_LIMIT_MAX_SURF_CTRL, (uint64_t)total, CM_MAX_SURF_CTRL, __func__);
    if ((e = cm_knots_check(s->p, s->nu, s->U, st)) != CM_OK || (e = cm_knots_check(s->q, s->nv, s->V, st)) != CM_OK)
        return e;
    return check_points(s->ctrl, s->w, total, st, __func__);
}

int cm_bspl_find_span(int n_ctrl, int p, const double *knots, double u)
{
    double lo = knots[p], hi = knots[n_ctrl];
    if (!(u > lo)) /* also catches NaN */
        u = lo;
    if (u >= hi) {
        /* domain end: the last non-empty span */
        int i = n_ctrl - 1;
        while (i > p && !(knots[i] < knots[i + 1]))
            i--;
        return i;
    }
    /* invariant: knots[low] <= u < knots[high]; the interval halves each
     * round, so 64 rounds bound any int range even for a corrupt vector */
    int low = p, high = n_ctrl;
    int mid = (low + high) / 2;
    for (int guard = 0; guard < 64 && (u < knots[mid] || u >= knots[mid + 1]); guard++) {
        if (u < knots[mid])
            high = mid;
        else
            low = mid;
        mid = (low + high) / 2;
    }
    return mid;
}

cm_err cm_bspl_basis(int span, double u, int p, const double *knots, double *N, cm_status *st)
{
    cm_err e = check_degree(p, st, __func__);
    if (e != CM_OK)
        return e;
    double left[CM_MAX_ORDER], right[CM_MAX_ORDER];
    N[0] = 1.0;
    for (int j = 1; j <= p; j++) {
        left[j] = u - knots[span + 1 - j];
        right[j] = knots[span + j] - u;
        double saved = 0.0;
        for (int r = 0; r < j; r++) {
            double temp = N[r] / (right[r + 1] + left[j - r]);
            N[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        N[j] = saved;
    }
    return CM_OK;
}

_Static_assert(CM_MAX_DERS <= 2, "cm_bspl_ders_basis unrolls A2.3's derivative loop for k <= 2: extend it first");

/*
 * A2.2 and A2.3 for degree p, once for each of the common degrees with p a constant (the dispatch
 * below): the compiler then unrolls the loops and keeps the triangle in registers, doing the same
 * operations in the same order, so the same bits (the unit tests hold every degree and order to
 * the textbook A2.3).  The degrees 2 and 3 of arcs and cubic nets were most of a decode's calls.
 * -O2 does not unroll a loop of three on its own where that makes the code larger: the pragmas ask
 * (gcc and clang read them; cgma__diffuser -8 % instructions for 1 KB of aarch64 text).
 */
static inline __attribute__((always_inline)) void ders_basis_p(int span, double u, const int p, int nd,
                                                               const double *knots,
                                                               double ders[CM_MAX_DERS + 1][CM_MAX_ORDER])
{
    double ndu[CM_MAX_ORDER][CM_MAX_ORDER];
    double left[CM_MAX_ORDER], right[CM_MAX_ORDER];

    ndu[0][0] = 1.0;
#pragma GCC unroll 4
    for (int j = 1; j <= p; j++) {
        left[j] = u - knots[span + 1 - j];
        right[j] = knots[span + j] - u;
        double saved = 0.0;
#pragma GCC unroll 4
        for (int r = 0; r < j; r++) {
            ndu[j][r] = right[r + 1] + left[j - r]; /* lower triangle: knot differences */
            double temp = ndu[r][j - 1] / ndu[j][r];
            ndu[r][j] = saved + right[r + 1] * temp; /* upper triangle: basis functions */
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
#pragma GCC unroll 4
    for (int j = 0; j <= p; j++)
        ders[0][j] = ndu[j][p];

    int n = nd < p ? nd : p; /* derivatives above the degree vanish */
    /* A2.3's derivative loop for k <= 2 (CM_MAX_DERS) unrolled: its inner j loop runs at most once,
       a[s1][0] = 1, and a[][] holds the last two rows.  The same operations in the same order, so
       the same bits (the unit tests keep the textbook loop and compare, every degree and order);
       1/x and -1/x round alike, so one reciprocal serves two neighbours.  (The first derivatives
       of nearly every call, normals and Newton steps, and the second of the exact patches' sides,
       spent most of their time in the loop's bookkeeping.) */
    double inv_prev = 0.0;
    double fac1 = (double)p, fac2 = fac1 * (double)(p - 1);
    /* (n >= 1 tested once, outside: with it in the loop's condition gcc -O0 drops the unroll
       annotation with a warning) */
    if (n >= 1) {
#pragma GCC unroll 4
        for (int r = 0; r <= p; r++) {
            double a10 = inv_prev, a11 = 0.0, d = 0.0;
            if (r >= 1)
                d = a10 * ndu[r - 1][p - 1];
            if (r <= p - 1) {
                double inv = 1.0 / ndu[p][r];
                a11 = -inv;
                d += a11 * ndu[r][p - 1];
                inv_prev = inv;
            }
            ders[1][r] = d * fac1;
            if (n == 2) {
                double d2 = 0.0;
                if (r >= 2)
                    d2 = (a10 / ndu[p - 1][r - 2]) * ndu[r - 2][p - 2];
                if (r >= 1 && r <= p - 1)
                    d2 += ((a11 - a10) / ndu[p - 1][r - 1]) * ndu[r - 1][p - 2];
                if (r <= p - 2)
                    d2 += (-a11 / ndu[p - 1][r]) * ndu[r][p - 2];
                ders[2][r] = d2 * fac2;
            }
        }
    }
    for (int k = n + 1; k <= nd; k++)
        for (int j = 0; j <= p; j++)
            ders[k][j] = 0.0;
}

/* ders_basis_p for a checked p (1 <= p <= CM_MAX_DEGREE) and nd (0 <= nd <= CM_MAX_DERS) */
static void ders_basis_any(int span, double u, int p, int nd, const double *knots,
                           double ders[CM_MAX_DERS + 1][CM_MAX_ORDER])
{
    switch (p) {
    case 1:
        ders_basis_p(span, u, 1, nd, knots, ders);
        break;
    case 2:
        ders_basis_p(span, u, 2, nd, knots, ders);
        break;
    case 3:
        ders_basis_p(span, u, 3, nd, knots, ders);
        break;
    default:
        ders_basis_p(span, u, p, nd, knots, ders);
        break;
    }
}

cm_err cm_bspl_ders_basis(int span, double u, int p, int nd, const double *knots,
                          double ders[CM_MAX_DERS + 1][CM_MAX_ORDER], cm_status *st)
{
    cm_err e = check_degree(p, st, __func__);
    if (e != CM_OK)
        return e;
    if (nd < 0 || nd > CM_MAX_DERS)
        return cm_fail(st, CM_E_ARG, __func__);
    ders_basis_any(span, u, p, nd, knots, ders);
    return CM_OK;
}

/*
 * A3.2 / A4.2 at span for degree p, compiled once for each of the degrees 1 to 3 with p a constant
 * (as ders_basis_p): the sums unrolled, the same operations in the same order, so the same bits.  A polynomial curve's terms are b P, not (b 1.0) P (equal), and
 * it has no weight sums.  (Edge sampling, the exact patches' sides and the face samples evaluate
 * curves: 17 % of a GREGORY-EXACT model's decode.)
 */
static inline __attribute__((always_inline)) void curve_eval_p(const cm_curve *c, double u, int span, const int p,
                                                               int nd, cm_vec3 *d)
{
    double ders[CM_MAX_DERS + 1][CM_MAX_ORDER];
    ders_basis_any(span, u, p, nd, c->knots, ders); /* (p and nd checked by the caller) */
    const cm_vec3 *P = c->ctrl + (span - p);
    if (c->w == NULL) {
        for (int k = 0; k <= nd; k++) {
            cm_vec3 acc = cm_v3(0, 0, 0);
            for (int j = 0; j <= p; j++)
                acc = cm_axpy(acc, ders[k][j], P[j]);
            d[k] = acc;
        }
        return;
    }
    const double *w = c->w + (span - p);
    cm_vec3 A[CM_MAX_DERS + 1];
    double W[CM_MAX_DERS + 1];
    for (int k = 0; k <= nd; k++) {
        cm_vec3 acc = cm_v3(0, 0, 0);
        double wacc = 0.0;
        for (int j = 0; j <= p; j++) {
            double bw = ders[k][j] * w[j];
            acc = cm_axpy(acc, bw, P[j]);
            wacc += bw;
        }
        A[k] = acc;
        W[k] = wacc;
    }
    /* A4.2: C^(k) = (A^(k) - sum_{i=1..k} binom(k,i) w^(i) C^(k-i)) / w */
    for (int k = 0; k <= nd; k++) {
        cm_vec3 v = A[k];
        for (int i = 1; i <= k; i++)
            v = cm_sub(v, cm_scale(d[k - i], binom[k][i] * W[i]));
        d[k] = cm_scale(v, 1.0 / W[0]);
    }
}

cm_err cm_curve_eval(const cm_curve *c, double u, int nd, cm_vec3 *d, cm_status *st)
{
    int p = c->p;
    cm_err e;
    if ((e = check_degree(p, st, __func__)) != CM_OK)
        return e;
    if (nd < 0 || nd > CM_MAX_DERS)
        return cm_fail(st, CM_E_ARG, __func__);
    double lo = c->knots[p], hi = c->knots[c->n_ctrl];
    if (!(u > lo))
        u = lo;
    if (u > hi)
        u = hi;
    int span = cm_bspl_find_span(c->n_ctrl, p, c->knots, u);
    switch (p) {
    case 1:
        curve_eval_p(c, u, span, 1, nd, d);
        break;
    case 2:
        curve_eval_p(c, u, span, 2, nd, d);
        break;
    case 3:
        curve_eval_p(c, u, span, 3, nd, d);
        break;
    default:
        curve_eval_p(c, u, span, p, nd, d);
        break;
    }
    return CM_OK;
}

/* t += b (P, 1): a homogeneous sum's next term, in A3.6's order */
static void hpt_add_point(cm_hpt *t, double b, cm_vec3 P)
{
    t->x += b * P.x;
    t->y += b * P.y;
    t->z += b * P.z;
    t->w += b;
}

/* a += b h, component by component */
static void hpt_add_scaled(cm_hpt *a, double b, cm_hpt h)
{
    a->x += b * h.x;
    a->y += b * h.y;
    a->z += b * h.z;
    a->w += b * h.w;
}

/*
 * cm_surf_eval's nd = 1 contraction (the point and first derivatives: normals, Newton steps, nearly
 * every call) at spans us, vs: A3.6 contracting u first, each control point loaded once for both
 * u sums, into Aw[0][0], Aw[0][1], Aw[1][0].  Compiled once for each common pair of degrees with p
 * and q constants (the dispatch in cm_surf_eval): the basis and the sums unrolled, the same
 * operations in the same order, so the same bits (test_surface_first_derivative_path_same_bits
 * holds them to nd = 2's general loop).  A polynomial net's terms are b P, not (b 1.0) P (equal),
 * and it has no weight sums.  Bicubic polynomial nets (G1FIT, NFILL, most kept B-splines) and the
 * rational linear-by-quadratic surfaces of cylinders and cones are nearly all of the corpus's
 * surface evaluations.
 */
static inline __attribute__((always_inline)) void surf_nd1_pq(const cm_surf *s, double u, double v, int us, int vs,
                                                              const int p, const int q,
                                                              cm_hpt Aw[CM_MAX_DERS + 1][CM_MAX_DERS + 1])
{
    double Nu[CM_MAX_DERS + 1][CM_MAX_ORDER], Nv[CM_MAX_DERS + 1][CM_MAX_ORDER];
    if (__builtin_constant_p(p) && __builtin_constant_p(q)) {
        ders_basis_p(us, u, p, 1, s->U, Nu);
        ders_basis_p(vs, v, q, 1, s->V, Nv);
    } else { /* the other degrees: the basis compiled per degree all the same */
        ders_basis_any(us, u, p, 1, s->U, Nu);
        ders_basis_any(vs, v, q, 1, s->V, Nv);
    }
    if (s->w == NULL) {
        cm_vec3 t0[CM_MAX_ORDER], t1[CM_MAX_ORDER];
        for (int sidx = 0; sidx <= q; sidx++) {
            cm_vec3 a = {0, 0, 0}, b = {0, 0, 0};
            for (int r = 0; r <= p; r++) {
                cm_vec3 P = s->ctrl[(long)(us - p + r) * s->nv + (vs - q + sidx)];
                a = cm_axpy(a, Nu[0][r], P);
                b = cm_axpy(b, Nu[1][r], P);
            }
            t0[sidx] = a;
            t1[sidx] = b;
        }
        cm_vec3 a00 = {0, 0, 0}, a01 = {0, 0, 0}, a10 = {0, 0, 0};
        for (int sidx = 0; sidx <= q; sidx++) {
            a00 = cm_axpy(a00, Nv[0][sidx], t0[sidx]);
            a01 = cm_axpy(a01, Nv[1][sidx], t0[sidx]);
            a10 = cm_axpy(a10, Nv[0][sidx], t1[sidx]);
        }
        Aw[0][0] = (cm_hpt){a00.x, a00.y, a00.z, 0};
        Aw[0][1] = (cm_hpt){a01.x, a01.y, a01.z, 0};
        Aw[1][0] = (cm_hpt){a10.x, a10.y, a10.z, 0};
        return;
    }
    cm_hpt temp[CM_MAX_ORDER], temp1[CM_MAX_ORDER];
    for (int sidx = 0; sidx <= q; sidx++) {
        cm_hpt t0 = {0, 0, 0, 0}, t1 = {0, 0, 0, 0};
        for (int r = 0; r <= p; r++) {
            long idx = (long)(us - p + r) * s->nv + (vs - q + sidx);
            hpt_add_point(&t0, Nu[0][r] * s->w[idx], s->ctrl[idx]);
            hpt_add_point(&t1, Nu[1][r] * s->w[idx], s->ctrl[idx]);
        }
        temp[sidx] = t0;
        temp1[sidx] = t1;
    }
    cm_hpt a00 = {0, 0, 0, 0}, a01 = {0, 0, 0, 0}, a10 = {0, 0, 0, 0};
    for (int sidx = 0; sidx <= q; sidx++) {
        hpt_add_scaled(&a00, Nv[0][sidx], temp[sidx]);
        hpt_add_scaled(&a01, Nv[1][sidx], temp[sidx]);
        hpt_add_scaled(&a10, Nv[0][sidx], temp1[sidx]);
    }
    Aw[0][0] = a00;
    Aw[0][1] = a01;
    Aw[1][0] = a10;
}

cm_err cm_surf_eval(const cm_surf *s, double u, double v, int nd, cm_vec3 S[CM_MAX_DERS + 1][CM_MAX_DERS + 1],
                    cm_status *st)
{
    double Nu[CM_MAX_DERS + 1][CM_MAX_ORDER], Nv[CM_MAX_DERS + 1][CM_MAX_ORDER];
    cm_hpt temp[CM_MAX_ORDER];
    cm_hpt Aw[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
    int p = s->p, q = s->q;
    cm_err e;
    if ((e = check_degree(p, st, __func__)) != CM_OK || (e = check_degree(q, st, __func__)) != CM_OK)
        return e;
    if (nd < 0 || nd > CM_MAX_DERS)
        return cm_fail(st, CM_E_ARG, __func__);
    double u0 = s->U[p], u1 = s->U[s->nu], v0 = s->V[q], v1 = s->V[s->nv];
    if (!(u > u0))
        u = u0;
    if (u > u1)
        u = u1;
    if (!(v > v0))
        v = v0;
    if (v > v1)
        v = v1;
    int us = cm_bspl_find_span(s->nu, p, s->U, u);
    int vs = cm_bspl_find_span(s->nv, q, s->V, v);
    for (int k = 0; k <= CM_MAX_DERS; k++)
        for (int l = 0; l <= CM_MAX_DERS; l++)
            S[k][l] = cm_v3(0, 0, 0);
    /* (Aw needs no clearing: the quotient below reads only entries k + l <= nd, all written) */
    if (nd == 1) {
        if (p == 3 && q == 3)
            surf_nd1_pq(s, u, v, us, vs, 3, 3, Aw);
        else if (p == 1 && q == 2)
            surf_nd1_pq(s, u, v, us, vs, 1, 2, Aw);
        else
            surf_nd1_pq(s, u, v, us, vs, p, q, Aw);
    } else if ((e = cm_bspl_ders_basis(us, u, p, nd, s->U, Nu, st)) != CM_OK ||
               (e = cm_bspl_ders_basis(vs, v, q, nd, s->V, Nv, st)) != CM_OK)
        return e;
    /* A3.6: contract u first into temp[s], then v; fixed summation order (nd = 1 done above) */
    for (int k = 0; k <= nd && nd != 1; k++) {
        for (int sidx = 0; sidx <= q; sidx++) {
            cm_hpt t = {0, 0, 0, 0};
            for (int r = 0; r <= p; r++) {
                long idx = (long)(us - p + r) * s->nv + (vs - q + sidx);
                double wi = s->w ? s->w[idx] : 1.0;
                hpt_add_point(&t, Nu[k][r] * wi, s->ctrl[idx]);
            }
            temp[sidx] = t;
        }
        for (int l = 0; l <= nd - k; l++) {
            cm_hpt a = {0, 0, 0, 0};
            for (int sidx = 0; sidx <= q; sidx++)
                hpt_add_scaled(&a, Nv[l][sidx], temp[sidx]);
            Aw[k][l] = a;
        }
    }
    if (s->w == NULL) {
        for (int k = 0; k <= nd; k++)
            for (int l = 0; l <= nd - k; l++)
                S[k][l] = cm_v3(Aw[k][l].x, Aw[k][l].y, Aw[k][l].z);
        return CM_OK;
    }
    /* A4.4: quotient rule for rational surfaces */
    for (int k = 0; k <= nd; k++) {
        for (int l = 0; l <= nd - k; l++) {
            cm_vec3 v2 = cm_v3(Aw[k][l].x, Aw[k][l].y, Aw[k][l].z);
            for (int j = 1; j <= l; j++)
                v2 = cm_sub(v2, cm_scale(S[k][l - j], binom[l][j] * Aw[0][j].w));
            for (int i = 1; i <= k; i++) {
                v2 = cm_sub(v2, cm_scale(S[k - i][l], binom[k][i] * Aw[i][0].w));
                cm_vec3 v3 = cm_v3(0, 0, 0);
                for (int j = 1; j <= l; j++)
                    v3 = cm_add(v3, cm_scale(S[k - i][l - j], binom[l][j] * Aw[i][j].w));
                v2 = cm_sub(v2, cm_scale(v3, binom[k][i]));
            }
            S[k][l] = cm_scale(v2, 1.0 / Aw[0][0].w);
        }
    }
    return CM_OK;
}

/* a grid parameter t clamped to the domain as cm_surf_eval clamps it, its span and its basis (the
   degree p checked by the caller); returns the span */
static int grid_basis(int n_ctrl, int p, const double *knots, double t, double N[CM_MAX_DERS + 1][CM_MAX_ORDER])
{
    double lo = knots[p], hi = knots[n_ctrl];
    if (!(t > lo))
        t = lo;
    if (t > hi)
        t = hi;
    int span = cm_bspl_find_span(n_ctrl, p, knots, t);
    ders_basis_any(span, t, p, 0, knots, N);
    return span;
}

cm_err cm_surf_eval_grid(const cm_surf *s, const double *u, int nu, const double *v, int nv, cm_vec3 *g,
                        cm_status *st)
{
    double Nu[CM_MAX_DERS + 1][CM_MAX_ORDER], Nv[CM_MAX_DERS + 1][CM_MAX_ORDER];
    cm_hpt temp[CM_MAX_ORDER];
    int p = s->p, q = s->q;
    cm_err e;
    if ((e = check_degree(p, st, __func__)) != CM_OK || (e = check_degree(q, st, __func__)) != CM_OK)
        return e;
    for (int i = 0; i < nu; i++) {
        int us = grid_basis(s->nu, p, s->U, u[i], Nu);
        int temp_vs = -1; /* the v span temp[] was contracted for: grid points in one span share it */
        for (int j = 0; j < nv; j++) {
            int vs = grid_basis(s->nv, q, s->V, v[j], Nv);
            if (vs != temp_vs) {
                for (int sidx = 0; sidx <= q; sidx++) {
                    cm_hpt t = {0, 0, 0, 0};
                    for (int r = 0; r <= p; r++) {
                        long idx = (long)(us - p + r) * s->nv + (vs - q + sidx);
                        double wi = s->w ? s->w[idx] : 1.0;
                        hpt_add_point(&t, Nu[0][r] * wi, s->ctrl[idx]);
                    }
                    temp[sidx] = t;
                }
                temp_vs = vs;
            }
            cm_hpt a = {0, 0, 0, 0};
            for (int sidx = 0; sidx <= q; sidx++)
                hpt_add_scaled(&a, Nv[0][sidx], temp[sidx]);
            cm_vec3 P = cm_v3(a.x, a.y, a.z);
            g[(long)i * nv + j] = s->w ? cm_scale(P, 1.0 / a.w) : P;
        }
    }
    return CM_OK;
}

void cm_knot_insert_steps(const double *knots, int p, int k, int s, int r, double u, cm_hpt *R, cm_hpt *out)
{
    const double *U = knots;
    int first = k - p + 1; /* out[0] is Q[first] */
    int L = k - p;
    for (int j = 1; j <= r; j++) {
        L = k - p + j;
        for (int i = 0; i <= p - j - s; i++) {
            double alpha = (u - U[L + i]) / (U[i + k + 1] - U[L + i]);
            double beta = 1.0 - alpha;
            R[i].x = alpha * R[i + 1].x + beta * R[i].x;
            R[i].y = alpha * R[i + 1].y + beta * R[i].y;
            R[i].z = alpha * R[i + 1].z + beta * R[i].z;
            R[i].w = alpha * R[i + 1].w + beta * R[i].w;
        }
        out[L - first] = R[0];
        out[k + r - j - s - first] = R[p - j - s];
    }
    for (int i = L + 1; i < k - s; i++)
        out[i - first] = R[i - L];
}

cm_err cm_curve_insert_knot(const cm_curve *c, double u, int r, double *knots_out, cm_vec3 *ctrl_out,
                            double *w_out, int cap, cm_status *st)
{
    int p = c->p, n = c->n_ctrl;
    const double *U = c->knots;
    cm_err e;
    if ((e = check_degree(p, st, __func__)) != CM_OK)
        return e;
    if (r < 1 || !(u > U[p]) || !(u < U[n]))
        return cm_fail(st, CM_E_ARG, __func__);
    int s = 0; /* multiplicity of u already in the vector */
    for (int i = 0; i < n + p + 1; i++)
        if (U[i] == u)
            s++;
    if (r + s > p)
        return cm_fail(st, CM_E_ARG, __func__);
    if (n + r > CM_MAX_EDGE_CTRL)
        return cm_fail_limit(st, CM_LIMIT_MAX_EDGE_CTRL, (uint64_t)(n + r), CM_MAX_EDGE_CTRL, __func__);
    if (n + r > cap)
        return cm_fail_nospace(st, (uint64_t)(n + r), (uint64_t)cap, __func__);

    int k = cm_bspl_find_span(n, p, U, u);
    int mp = n + p; /* index of the last knot */
    for (int i = 0; i <= k; i++)
        knots_out[i] = U[i];
    for (int i = 1; i <= r; i++)
        knots_out[k + i] = u;
    for (int i = k + 1; i <= mp; i++)
        knots_out[i + r] = U[i];

    /* unchanged control points at both ends */
    for (int i = 0; i <= k - p; i++) {
        ctrl_out[i] = c->ctrl[i];
        if (c->w)
            w_out[i] = c->w[i];
    }
    for (int i = k - s; i < n; i++) {
        ctrl_out[i + r] = c->ctrl[i];
        if (c->w)
            w_out[i + r] = c->w[i];
    }
    /* the new ones, computed homogeneous, written back Euclidean */
    cm_hpt Rw[CM_MAX_ORDER], Qw[2 * CM_MAX_ORDER];
    for (int i = 0; i <= p - s; i++) {
        cm_vec3 P = c->ctrl[k - p + i];
        double wt = c->w ? c->w[k - p + i] : 1.0;
        Rw[i] = (cm_hpt){P.x * wt, P.y * wt, P.z * wt, wt};
    }
    cm_knot_insert_steps(U, p, k, s, r, u, Rw, Qw);
    for (int i = 0; i < p - s + r - 1; i++) {
        cm_hpt a = Qw[i];
        ctrl_out[k - p + 1 + i] = cm_v3(a.x / a.w, a.y / a.w, a.z / a.w);
        if (c->w)
            w_out[k - p + 1 + i] = a.w;
    }
    return CM_OK;
}

cm_err cm_knots_uniform(int n_ctrl, int p, double *knots, cm_status *st)
{
    cm_err e;
    if ((e = check_degree(p, st, __func__)) != CM_OK)
        return e;
    if (n_ctrl < p + 1)
        return cm_fail(st, CM_E_RANGE, __func__);
    int spans = n_ctrl - p;
    for (int i = 0; i <= p; i++) {
        knots[i] = 0.0;
        knots[n_ctrl + i] = 1.0;
    }
    for (int j = 1; j < spans; j++)
        knots[p + j] = (double)j / (double)spans;
    return CM_OK;
}

cm_err cm_greville(int n_ctrl, int p, const double *knots, double *xi, cm_status *st)
{
    cm_err e;
    if ((e = check_degree(p, st, __func__)) != CM_OK)
        return e;
    for (int i = 0; i < n_ctrl; i++) {
        double s = 0.0;
        for (int j = 1; j <= p; j++)
            s += knots[i + j];
        xi[i] = s / (double)p;
    }
    return CM_OK;
}
