/*
 * fit_board.c - edge curves and kept surfaces re-approximated to fit a board's limits (issue 14.5,
 * "fit the board, don't refuse it"; see encode_internal.h).
 *
 * A target profile bounds the control points of one edge (MAX_EDGE_CTRL: the terminal has 256) and
 * the degree (MAX_DEGREE: 9).  Real models exceed both (asitus__IAD_v3 has an edge of 495 control
 * points; the issue names a degree-11 curve), and refusing the whole model for one curve is what a
 * user would least expect.  The curve is replaced by a clamped B-spline of degree min(3, limit) with
 * the board's number of control points, its ends on the edge's vertices, fitted by least squares to
 * samples of the original at equal parameter steps (The NURBS Book 9.4.1, with uniform knots, which
 * every span's samples fill), and taken only when it stays within `tol` of the original at four
 * times as many parameters (the same parameter on both: an upper bound of the distance between the
 * curves).  The faces on both sides are then verified against the transmitted curve as always.
 *
 * A kept surface over the board's control points per direction (MAX_SURF_CTRL_DIR: the terminal has
 * 128; asitus__Pieza1 keeps one of 178, asitus__IAD_v3 one of 529), its degree or its total: every
 * row of its control net, in homogeneous coordinates (w P, w), is re-fitted on one common knot
 * vector by the same least squares, then every column; the result is taken only when it stays within
 * `tol` of the original on a grid of four samples per new control point each way (same parameters),
 * with every weight positive.
 */
#include "encode_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_bspline.h"
#include "cm/cm_lsq.h"

#define SAMPLES_PER_CTRL 8 /* fitting samples per control point */
#define CHECKS_PER_SAMPLE 4

/* the least-squares fit of `dim` coordinates of m samples (rows of f_samples, at equal parameter
   steps of [0,1]) by a clamped B-spline of degree p with n control points on uniform knots (knots
   out: n + p + 1), its first and last control points the first and last samples; ctrl out: n x dim.
   Returns 1 if solved. */
static int lsq_fit(const double *samples, int m, int dim, int p, int n, double *knots, double *ctrl)
{
    int nu = n - 2, w = p, ok = 0;
    double *A = calloc((size_t)(nu > 0 ? nu : 1) * (size_t)(w + 1), sizeof *A), N[CM_MAX_DEGREE + 1];
    cm_vec3 *rhs = calloc((size_t)(nu > 0 ? nu : 1) * 2, sizeof *rhs); /* dim <= 6: two vec3 per unknown */
    if (!A || !rhs || dim > 6)
        goto done;
    for (int i = 0; i <= p; i++) {
        knots[i] = 0.0;
        knots[n + i] = 1.0;
    }
    for (int i = 1; i < n - p; i++)
        knots[p + i] = (double)i / (double)(n - p);
    for (int d = 0; d < dim; d++) {
        ctrl[d] = samples[d];
        ctrl[(n - 1) * dim + d] = samples[(m - 1) * dim + d];
    }
    for (int k = 0; k < m; k++) {
        double u = (double)k / (double)(m - 1), r[6];
        int span = cm_bspl_find_span(n, p, knots, u);
        cm_status bst;
        cm_status_init(&bst);
        if (cm_bspl_basis(span, u, p, knots, N, &bst) != CM_OK)
            goto done;
        for (int d = 0; d < dim; d++)
            r[d] = samples[k * dim + d];
        for (int a = 0; a <= p; a++) {
            int i = span - p + a;
            if (i == 0 || i == n - 1)
                for (int d = 0; d < dim; d++)
                    r[d] -= N[a] * ctrl[i * dim + d];
        }
        for (int a = 0; a <= p; a++) {
            int i = span - p + a;
            if (i == 0 || i == n - 1)
                continue;
            cm_vec3 *R0 = &rhs[2 * (i - 1)], *R1 = &rhs[2 * (i - 1) + 1];
            double add[6] = {0};
            for (int d = 0; d < dim; d++)
                add[d] = r[d] * N[a];
            *R0 = cm_add(*R0, cm_v3(add[0], add[1], add[2]));
            *R1 = cm_add(*R1, cm_v3(add[3], add[4], add[5]));
            for (int b = 0; b <= a; b++) {
                int j = span - p + b;
                if (j == 0 || j == n - 1)
                    continue;
                A[CM_BAND_IDX(i - 1, j - 1, w)] += N[a] * N[b];
            }
        }
    }
    if (nu > 0) {
        cm_status cst;
        cm_status_init(&cst);
        if (cm_chol_band(A, nu, w, &cst) != CM_OK)
            goto done;
        /* two solves of three right-hand sides each */
        cm_vec3 *b0 = malloc((size_t)nu * sizeof *b0), *b1 = malloc((size_t)nu * sizeof *b1);
        if (!b0 || !b1) {
            free(b0);
            free(b1);
            goto done;
        }
        for (int i = 0; i < nu; i++) {
            b0[i] = rhs[2 * i];
            b1[i] = rhs[2 * i + 1];
        }
        cm_chol_band_solve3(A, nu, w, b0);
        cm_chol_band_solve3(A, nu, w, b1);
        for (int i = 0; i < nu; i++) {
            double x[6] = {b0[i].x, b0[i].y, b0[i].z, b1[i].x, b1[i].y, b1[i].z};
            for (int d = 0; d < dim; d++)
                ctrl[(i + 1) * dim + d] = x[d];
        }
        free(b0);
        free(b1);
    }
    ok = 1;
done:
    free(A);
    free(rhs);
    return ok;
}

static int eval(const hcurve *c, double u, cm_vec3 *p)
{
    cm_curve v = hcurve_view(c);
    cm_status st;
    cm_status_init(&st);
    return cm_curve_eval(&v, u, 0, p, &st) == CM_OK;
}

/* by chord length: the parameter of c (on [u0, u1]) at the fraction s of its length, interpolated in
   a table of `nt` + 1 cumulative chord lengths len[] at equal parameter steps */
static double u_at_length(const double *len, int nt, double u0, double u1, double s)
{
    double target = s * len[nt];
    int lo = 0, hi = nt;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (len[mid] < target)
            lo = mid;
        else
            hi = mid;
    }
    double seg = len[hi] - len[lo], f = seg > 0 ? (target - len[lo]) / seg : 0.0;
    return u0 + (u1 - u0) * ((double)lo + f) / (double)nt;
}

int enc_edge_refit_ex(hcurve *c, int max_degree, int max_ctrl, double tol, int by_length, cm_status *st)
{
    int p = max_degree < 3 ? max_degree : 3, n = max_ctrl;
    if (p < 1 || n < p + 1 || n - 2 > CM_MAX_LSQ_UNKNOWNS || !(tol > 0))
        return 0;
    double u0, u1;
    hcurve_domain(c, &u0, &u1);
    int m = SAMPLES_PER_CTRL * n, ok = 0, nt = by_length ? 16 * CHECKS_PER_SAMPLE * m : 0;
    hcurve f = {0};
    double *smp = malloc((size_t)m * 3 * sizeof *smp), *ctrl = malloc((size_t)n * 3 * sizeof *ctrl);
    double *len = by_length ? malloc((size_t)(nt + 1) * sizeof *len) : NULL;
    if (!smp || !ctrl || (by_length && !len) || hcurve_alloc(&f, p, n, 0, st) != CM_OK)
        goto done;
    if (by_length) {
        /* the fit follows the curve's length, not its parameter: a conic's or an uneven spline's
           speed varies along it, which the same-parameter distance below would count as error */
        cm_vec3 prev;
        if (!eval(c, u0, &prev))
            goto done;
        len[0] = 0;
        for (int k = 1; k <= nt; k++) {
            cm_vec3 q;
            if (!eval(c, u0 + (u1 - u0) * (double)k / (double)nt, &q))
                goto done;
            len[k] = len[k - 1] + cm_dist(prev, q);
            prev = q;
        }
        if (!(len[nt] > 0))
            goto done;
    }
    for (int k = 0; k < m; k++) {
        cm_vec3 s;
        double frac = (double)k / (double)(m - 1);
        if (!eval(c, by_length ? u_at_length(len, nt, u0, u1, frac) : u0 + (u1 - u0) * frac, &s))
            goto done;
        smp[3 * k] = s.x;
        smp[3 * k + 1] = s.y;
        smp[3 * k + 2] = s.z;
    }
    if (!lsq_fit(smp, m, 3, p, n, f.knots, ctrl))
        goto done;
    for (int i = 0; i < n + p + 1; i++) /* back onto the original's domain, as the checks compare */
        f.knots[i] = u0 + (u1 - u0) * f.knots[i];
    for (int i = 0; i < n; i++)
        f.ctrl[i] = cm_v3(ctrl[3 * i], ctrl[3 * i + 1], ctrl[3 * i + 2]);
    /* within tol of the original everywhere it is looked at (by length: the original at the
       parameter where the fit's is, in proportion of length, a monotone matching of the two) */
    for (int k = 0; k < CHECKS_PER_SAMPLE * m; k++) {
        double frac = (double)k / (double)(CHECKS_PER_SAMPLE * m - 1), u = u0 + (u1 - u0) * frac;
        cm_vec3 a, b;
        if (!eval(c, by_length ? u_at_length(len, nt, u0, u1, frac) : u, &a) || !eval(&f, u, &b) ||
            !(cm_dist(a, b) <= tol))
            goto done;
    }
    hcurve_free(c);
    *c = f;
    memset(&f, 0, sizeof f);
    ok = 1;
done:
    hcurve_free(&f);
    free(smp);
    free(ctrl);
    free(len);
    return ok;
}

int enc_edge_refit(hcurve *c, int max_degree, int max_ctrl, double tol, cm_status *st)
{
    return enc_edge_refit_ex(c, max_degree, max_ctrl, tol, 0, st);
}

/* the net's rows (u direction) re-fitted to n_new control points of degree min(3, max_degree), in
   homogeneous coordinates: sampled at SAMPLES_PER_CTRL x n_new parameters each */
static int refit_rows(hsurf *s, int max_degree, int n_new)
{
    int p = max_degree < 3 ? max_degree : 3, m = SAMPLES_PER_CTRL * n_new, dim = s->w ? 4 : 3, ok = 0;
    if (p < 1 || n_new < p + 1 || n_new - 2 > CM_MAX_LSQ_UNKNOWNS)
        return 0;
    hcurve row = {0};
    double *smp = malloc((size_t)m * (size_t)dim * sizeof *smp), *ctrl = malloc((size_t)n_new * (size_t)dim * sizeof *ctrl);
    double *knots = malloc((size_t)(n_new + p + 1) * sizeof *knots);
    cm_vec3 *out = malloc((size_t)n_new * (size_t)s->nv * sizeof *out);
    double *wout = s->w ? malloc((size_t)n_new * (size_t)s->nv * sizeof *wout) : NULL;
    cm_status st;
    cm_status_init(&st);
    if (!smp || !ctrl || !knots || !out || (s->w && !wout) || hcurve_alloc(&row, s->p, s->nu, 0, &st) != CM_OK)
        goto done;
    memcpy(row.knots, s->U, (size_t)(s->nu + s->p + 1) * sizeof *row.knots);
    for (int j = 0; j < s->nv; j++) {
        /* the row as a polynomial curve of (w P) and, separately, of w */
        for (int part = 0; part < (s->w ? 2 : 1); part++) {
            for (int i = 0; i < s->nu; i++) {
                double wi = s->w ? s->w[i * s->nv + j] : 1.0;
                row.ctrl[i] = part == 0 ? cm_scale(s->ctrl[i * s->nv + j], wi) : cm_v3(wi, 0, 0);
            }
            for (int k = 0; k < m; k++) {
                cm_vec3 q;
                if (!eval(&row, s->U[0] + (s->U[s->nu + s->p] - s->U[0]) * (double)k / (double)(m - 1), &q))
                    goto done;
                if (part == 0) {
                    smp[k * dim] = q.x;
                    smp[k * dim + 1] = q.y;
                    smp[k * dim + 2] = q.z;
                } else {
                    smp[k * dim + 3] = q.x;
                }
            }
        }
        if (!lsq_fit(smp, m, dim, p, n_new, knots, ctrl))
            goto done;
        for (int i = 0; i < n_new; i++) {
            double wi = s->w ? ctrl[i * dim + 3] : 1.0;
            if (!(wi > 0))
                goto done;
            out[i * s->nv + j] = cm_scale(cm_v3(ctrl[i * dim], ctrl[i * dim + 1], ctrl[i * dim + 2]), 1.0 / wi);
            if (wout)
                wout[i * s->nv + j] = wi;
        }
    }
    double a = s->U[0], b = s->U[s->nu + s->p];
    for (int i = 0; i < n_new + p + 1; i++)
        knots[i] = a + (b - a) * knots[i];
    free(s->U);
    free(s->ctrl);
    free(s->w);
    s->U = knots;
    s->ctrl = out;
    s->w = wout;
    s->p = p;
    s->nu = n_new;
    knots = NULL;
    out = NULL;
    wout = NULL;
    ok = 1;
done:
    hcurve_free(&row);
    free(smp);
    free(ctrl);
    free(knots);
    free(out);
    free(wout);
    return ok;
}

/* swap the directions of s (u <-> v) */
static int transpose(hsurf *s)
{
    cm_vec3 *t = malloc((size_t)s->nu * (size_t)s->nv * sizeof *t);
    double *tw = s->w ? malloc((size_t)s->nu * (size_t)s->nv * sizeof *tw) : NULL;
    if (!t || (s->w && !tw)) {
        free(t);
        free(tw);
        return 0;
    }
    for (int i = 0; i < s->nu; i++)
        for (int j = 0; j < s->nv; j++) {
            t[j * s->nu + i] = s->ctrl[i * s->nv + j];
            if (tw)
                tw[j * s->nu + i] = s->w[i * s->nv + j];
        }
    free(s->ctrl);
    s->ctrl = t;
    if (tw) {
        free(s->w);
        s->w = tw;
    }
    double *U = s->U;
    s->U = s->V;
    s->V = U;
    int k = s->p;
    s->p = s->q;
    s->q = k;
    k = s->nu;
    s->nu = s->nv;
    s->nv = k;
    return 1;
}

/* the largest distance between s and f at the same parameters, on a grid of CHECKS_PER_SAMPLE
   samples per control point of either, each way; *rim (when not NULL) the largest on the net's
   four boundary curves */
static double surf_gap(const hsurf *s, const hsurf *f, double *rim)
{
    cm_surf a = hsurf_view(s), b = hsurf_view(f);
    int gu = CHECKS_PER_SAMPLE * (s->nu > f->nu ? s->nu : f->nu), gv = CHECKS_PER_SAMPLE * (s->nv > f->nv ? s->nv : f->nv);
    double u0, u1, v0, v1, worst = 0;
    hsurf_domain(s, &u0, &u1, &v0, &v1);
    for (int i = 0; i <= gu; i++)
        for (int j = 0; j <= gv; j++) {
            double u = u0 + (u1 - u0) * i / gu, v = v0 + (v1 - v0) * j / gv;
            cm_vec3 A[CM_MAX_DERS + 1][CM_MAX_DERS + 1], B[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
            if (cm_surf_eval(&a, u, v, 0, A, NULL) != CM_OK || cm_surf_eval(&b, u, v, 0, B, NULL) != CM_OK)
                return HUGE_VAL;
            double d = cm_dist(A[0][0], B[0][0]);
            if (!isfinite(d))
                return HUGE_VAL;
            worst = d > worst ? d : worst;
            if (rim && (i == 0 || j == 0 || i == gu || j == gv) && d > *rim)
                *rim = d;
        }
    return worst;
}

int enc_surf_refit(hsurf *s, int max_degree, int max_dir, int max_total, double tol, cm_status *st)
{
    if (max_dir < 2 || !(tol > 0))
        return 0;
    int nu = s->nu < max_dir ? s->nu : max_dir, nv = s->nv < max_dir ? s->nv : max_dir;
    while ((long)nu * nv > (long)max_total && (nu > 4 || nv > 4)) {
        if (nu >= nv)
            nu--;
        else
            nv--;
    }
    hsurf f = {0};
    if (hsurf_copy(s, &f, st) != CM_OK)
        return 0;
    int ok = 1;
    if (ok && (nu < f.nu || f.p > max_degree))
        ok = refit_rows(&f, max_degree, nu);
    if (ok && (nv < f.nv || f.q > max_degree))
        ok = transpose(&f) && refit_rows(&f, max_degree, nv) && transpose(&f);
    ok = ok && surf_gap(s, &f, NULL) <= tol;
    if (ok) {
        hsurf_free(s);
        *s = f;
    } else {
        hsurf_free(&f);
    }
    return ok;
}

int enc_surf_reduce(hsurf *s, double tol, double rim_tol, cm_status *st)
{
    if (!(tol > 0))
        return 0;
    hsurf best = {0};
    if (hsurf_copy(s, &best, st) != CM_OK)
        return 0;
    int changed = 0;
    /* the rows first, within half the tolerance, then the columns, the whole within all of it */
    for (int dir = 0; dir < 2; dir++) {
        int n0 = dir ? best.nv : best.nu, deg = dir ? best.q : best.p;
        /* as many where the degree or the knots differ */
        int most = deg == 3 && !enc_knots_uneven(dir ? best.V : best.U, deg, n0) ? n0 - 1 : n0;
        for (int n = 4; n <= most; n += 1 + n / 4) {
            hsurf f = {0};
            if (hsurf_copy(&best, &f, st) != CM_OK)
                break;
            int ok = dir == 0 ? refit_rows(&f, 3, n) : transpose(&f) && refit_rows(&f, 3, n) && transpose(&f);
            double rim = 0;
            if (ok && surf_gap(s, &f, &rim) <= (dir == 0 ? 0.5 * tol : tol) && rim <= rim_tol) {
                hsurf_free(&best);
                best = f;
                changed = 1;
                break;
            }
            hsurf_free(&f);
        }
    }
    if (changed) {
        hsurf_free(s);
        *s = best;
    } else {
        hsurf_free(&best);
    }
    return changed;
}

