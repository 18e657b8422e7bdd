/* cm_g1fit.c - method G1FIT's surface (spec §9 as this project builds it; see cm_g1fit.h). */
#include "cm/cm_g1fit.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "cm/cm_limits_info.h"

/* spec 9.4 stage 2: two sides' normals closer than this (|n1 x n2|) are one plane */
#define G1FIT_MIN_SIN 1e-3

/* the unit tangent of side s of the loop at its start (end = 0) or end (end = 1), in face direction */
static cm_err side_tangent(const cm_greg_input *in, int s, int end, cm_vec3 *T, cm_status *st)
{
    const cm_greg_side *gs = &in->side[s];
    cm_vec3 q[CM_MAX_DERS + 1];
    double u = end ? 1.0 : 0.0;
    cm_err e = cm_curve_eval(&gs->curve, gs->rev ? 1.0 - u : u, 1, q, st);
    if (e != CM_OK)
        return e;
    int ok;
    *T = cm_unit_or(gs->rev ? cm_neg(q[1]) : q[1], in->eps_len, cm_v3(0.0, 0.0, 0.0), &ok);
    return ok ? CM_OK : cm_fail(st, CM_E_DEGENERATE, "g1fit: an edge without a tangent at its end");
}

cm_err cm_g1fit_corners(const cm_greg_input *in, int corner[4], cm_status *st)
{
    int n = in->n;
    if (n < CM_G1FIT_MIN_EDGES || n > CM_G1FIT_MAX_EDGES)
        return cm_fail(st, CM_E_RANGE, __func__);
    /* turn at vertex k (the start of side k): 1 - cos of the angle between the incoming and the
       outgoing tangent; the four largest, ties to the lower index, in loop order */
    double turn[CM_G1FIT_MAX_EDGES];
    for (int k = 0; k < n; k++) {
        cm_vec3 a, b;
        cm_err e;
        if ((e = side_tangent(in, (k + n - 1) % n, 1, &a, st)) != CM_OK || (e = side_tangent(in, k, 0, &b, st)) != CM_OK)
            return e;
        turn[k] = 1.0 - cm_dot(a, b);
    }
    int taken[CM_G1FIT_MAX_EDGES] = {0};
    for (int c = 0; c < 4; c++) {
        int best = -1;
        for (int k = 0; k < n; k++)
            if (!taken[k] && (best < 0 || turn[k] > turn[best]))
                best = k;
        taken[best] = 1;
    }
    int c = 0;
    for (int k = 0; k < n; k++)
        if (taken[k])
            corner[c++] = k;
    return CM_OK;
}

/* steps of the normals' transport between two samples of an edge */
#define G1FIT_RMF_SUB 8

/* cm_g1fit.h: the ends' normals carried along the edge (double reflection) and blended */
cm_err cm_g1fit_edge_normals(const cm_greg_side *gs, cm_vec3 *N, cm_status *st)
{
    enum { SEG = CM_FMT_SEG_PER_EDGE, K = CM_FMT_SEG_PER_EDGE * G1FIT_RMF_SUB };
    cm_vec3 carried[2][CM_FMT_SEG_PER_EDGE + 1];
    /* the edge's points and tangents at the K + 1 steps, once for both directions */
    cm_vec3 pt[K + 1][2];
    for (int k = 0; k <= K; k++) {
        double u = (double)k / (double)K;
        cm_vec3 q[CM_MAX_DERS + 1];
        cm_err e = cm_curve_eval(&gs->curve, gs->rev ? 1.0 - u : u, 1, q, st);
        if (e != CM_OK)
            return e;
        pt[k][0] = q[0];
        pt[k][1] = q[1];
    }
    for (int dir = 0; dir < 2; dir++) {
        cm_vec3 r = dir ? gs->Ne : gs->Ns, x = cm_v3(0.0, 0.0, 0.0), T = x;
        for (int i = 0; i <= K; i++) {
            int k = dir ? K - i : i;
            const cm_vec3 *q = pt[k];
            double tl = cm_norm(q[1]);
            cm_vec3 T1 = tl > 0.0 ? cm_scale(q[1], (gs->rev ? -1.0 : 1.0) / tl) : T;
            if (i == 0) {
                r = cm_sub(r, cm_scale(T1, cm_dot(r, T1))); /* square to the edge */
            } else {
                cm_vec3 v1 = cm_sub(q[0], x);
                double c1 = cm_dot(v1, v1);
                cm_vec3 rL = r, tL = T;
                if (c1 > 0.0) {
                    rL = cm_sub(r, cm_scale(v1, 2.0 * cm_dot(v1, r) / c1));
                    tL = cm_sub(T, cm_scale(v1, 2.0 * cm_dot(v1, T) / c1));
                }
                cm_vec3 v2 = cm_sub(T1, tL);
                double c2 = cm_dot(v2, v2);
                r = c2 > 0.0 ? cm_sub(rL, cm_scale(v2, 2.0 * cm_dot(v2, rL) / c2)) : rL;
            }
            double rl = cm_norm(r);
            if (!(rl > 0.0))
                return cm_fail(st, CM_E_DEGENERATE, "g1fit: an edge's normal along its tangent");
            r = cm_scale(r, 1.0 / rl);
            x = q[0];
            T = T1;
            if (k % G1FIT_RMF_SUB == 0)
                carried[dir][k / G1FIT_RMF_SUB] = r;
        }
    }
    /* the end normals' signs may disagree (spec 5.3 turns each corner's to the face's side): the
       carried start normal decides */
    double sg = cm_dot(carried[0][SEG], carried[1][SEG]) < 0.0 ? -1.0 : 1.0;
    for (int j = 0; j <= SEG; j++) {
        double a = (double)j / (double)SEG;
        int ok;
        N[j] = cm_unit_or(cm_add(cm_scale(carried[0][j], 1.0 - a), cm_scale(carried[1][j], sg * a)), CM_GREG_EPS_DIR,
                          carried[0][j], &ok);
    }
    return CM_OK;
}

/* side k's sine at inner sample j (1..9): three to a point (cm_g1fit_build) */
static double twist_sine(const cm_vec3 *twist, int k, int j)
{
    cm_vec3 t = twist[3 * k + (j - 1) / 3];
    int c = (j - 1) % 3;
    return c == 0 ? t.x : (c == 1 ? t.y : t.z);
}

/* N turned about the unit tangent along d by the angle of sine s (|s| < 1): sqrt(1 - s^2) N + s unit(T x N) */
static cm_vec3 twisted(cm_vec3 N, cm_vec3 d, double s, double eps)
{
    int ok;
    cm_vec3 T = cm_unit_or(d, eps, cm_v3(0.0, 0.0, 0.0), &ok);
    if (!ok || s == 0.0)
        return N;
    cm_vec3 B = cm_unit_or(cm_cross(T, N), CM_GREG_EPS_DIR, cm_v3(0.0, 0.0, 0.0), &ok);
    if (!ok)
        return N;
    return cm_add(cm_scale(N, sqrt(1.0 - s * s)), cm_scale(B, s));
}

/*
 * The samples of the chain of sides from..to-1 (cyclic), in loop order, reversed when `reverse`:
 * points, unit normals (cm_g1fit_edge_normals) and chord-length parameters on [0, 1].
 */
static cm_err chain_samples(const cm_greg_input *in, int from, int to, int reverse, const cm_vec3 *twist,
                            cm_g1fit_ws *ws, int *count, cm_status *st)
{
    int m = 0, n = in->n, s = from;
    do {
        const cm_greg_side *gs = &in->side[s];
        cm_vec3 N[CM_FMT_SEG_PER_EDGE + 1];
        cm_err e = cm_g1fit_edge_normals(gs, N, st);
        if (e != CM_OK)
            return e;
        int last = (s + 1) % n == to;
        for (int j = 0; j <= CM_FMT_SEG_PER_EDGE; j++) {
            if (j == CM_FMT_SEG_PER_EDGE && !last)
                break; /* the next edge's first sample */
            double u = (double)j / (double)CM_FMT_SEG_PER_EDGE;
            cm_vec3 q[CM_MAX_DERS + 1];
            if ((e = cm_curve_eval(&gs->curve, gs->rev ? 1.0 - u : u, twist ? 1 : 0, q, st)) != CM_OK)
                return e;
            ws->p[m] = q[0];
            ws->N[m] = N[j];
            if (twist && j > 0 && j < CM_FMT_SEG_PER_EDGE)
                ws->N[m] = twisted(N[j], gs->rev ? cm_neg(q[1]) : q[1], twist_sine(twist, s, j), in->eps_len);
            m++;
        }
        s = (s + 1) % n;
    } while (s != to);
    if (reverse)
        for (int i = 0, j = m - 1; i < j; i++, j--) {
            cm_vec3 tp = ws->p[i], tn = ws->N[i];
            ws->p[i] = ws->p[j];
            ws->N[i] = ws->N[j];
            ws->p[j] = tp;
            ws->N[j] = tn;
        }
    ws->t[0] = 0.0;
    for (int i = 1; i < m; i++)
        ws->t[i] = ws->t[i - 1] + cm_dist(ws->p[i], ws->p[i - 1]);
    double L = ws->t[m - 1];
    if (!(L > in->eps_len))
        return cm_fail(st, CM_E_DEGENERATE, "g1fit: a side of no length");
    /* a side that closes on itself (a full circle between two corners at one vertex: a periodic face,
       its seam twice among the other sides) makes a tube whose border meets itself; its trimming
       then refines without end (occt__OCC8842_cylinder_Ideas: 288 -> 4612 triangles, 11 -> 802 M
       instructions); periodic faces are for splitting (spec 11.2) */
    if (!(cm_dist(ws->p[0], ws->p[m - 1]) > in->eps_len))
        return cm_fail(st, CM_E_DEGENERATE, "g1fit: a side that closes on itself (a periodic face)");
    for (int i = 1; i < m - 1; i++)
        ws->t[i] /= L;
    ws->t[m - 1] = 1.0;
    *count = m;
    return CM_OK;
}

/* the chain's unit normal at parameter x: linear between the samples that bracket it */
static cm_vec3 chain_normal(const cm_g1fit_ws *ws, int m, double x, cm_vec3 fallback)
{
    int i = 0;
    while (i + 2 < m && ws->t[i + 1] < x)
        i++;
    double dt = ws->t[i + 1] - ws->t[i], a = dt > 0.0 ? (x - ws->t[i]) / dt : 0.0;
    a = a < 0.0 ? 0.0 : (a > 1.0 ? 1.0 : a);
    int ok;
    return cm_unit_or(cm_add(cm_scale(ws->N[i], 1.0 - a), cm_scale(ws->N[i + 1], a)), CM_GREG_EPS_DIR, fallback, &ok);
}

static double greville(const double *knots, int i)
{
    return (knots[i + 1] + knots[i + 2] + knots[i + 3]) / 3.0;
}

/* spec 9.4 stage 2: Q moved into the planes through b[k] with normals n[k] (one or two) */
static cm_vec3 restrict_point(cm_vec3 Q, const cm_vec3 *b, const cm_vec3 *n, int k)
{
    if (k == 0)
        return Q;
    if (k == 2 && cm_norm(cm_cross(n[0], n[1])) < G1FIT_MIN_SIN) {
        int ok;
        cm_vec3 nn = cm_unit_or(cm_add(n[0], n[1]), CM_GREG_EPS_DIR, n[0], &ok);
        cm_vec3 bb = cm_scale(cm_add(b[0], b[1]), 0.5);
        return cm_sub(Q, cm_scale(nn, cm_dot(cm_sub(Q, bb), nn)));
    }
    if (k == 1)
        return cm_sub(Q, cm_scale(n[0], cm_dot(cm_sub(Q, b[0]), n[0])));
    double g = cm_dot(n[0], n[1]), r1 = cm_dot(cm_sub(Q, b[0]), n[0]), r2 = cm_dot(cm_sub(Q, b[1]), n[1]);
    double det = 1.0 - g * g;
    double a1 = (r1 - g * r2) / det, a2 = (r2 - g * r1) / det;
    return cm_sub(cm_sub(Q, cm_scale(n[0], a1)), cm_scale(n[1], a2));
}

CM_ONCE_PER_FACE cm_err cm_g1fit_build(const cm_greg_input *in, int nu, int nv, int mode, const cm_vec3 *twist, cm_nfill_surface *out,
                      cm_g1fit_ws *ws, cm_status *st)
{
    cm_err e;
    if (nu > CM_MAX_FIT_CTRL || nv > CM_MAX_FIT_CTRL)
        return cm_fail_limit(st, CM_LIMIT_MAX_FIT_CTRL, (uint64_t)(nu > nv ? nu : nv), CM_MAX_FIT_CTRL, __func__);
    if (nu < CM_NFILL_MIN_CTRL || nv < CM_NFILL_MIN_CTRL || mode < 0 || mode >= CM_G1FIT_MODES)
        return cm_fail(st, CM_E_RANGE, __func__);
    int Ku = nu - 4, Kv = nv - 4, K = Ku * Kv;
    int w = 2 * Kv < K - 1 ? 2 * Kv : K - 1; /* the second difference across rows */
    if (mode == 1 && K > CM_MAX_LSQ_UNKNOWNS)
        return cm_fail_limit(st, CM_LIMIT_MAX_LSQ_UNKNOWNS, (uint64_t)K, CM_MAX_LSQ_UNKNOWNS, __func__);
    if (mode == 1 && w > CM_MAX_LSQ_BAND)
        return cm_fail_limit(st, CM_LIMIT_MAX_LSQ_BAND, (uint64_t)w, CM_MAX_LSQ_BAND, __func__);
    int corner[4];
    if ((e = cm_g1fit_corners(in, corner, st)) != CM_OK)
        return e;

    /* the sides: 0 (v = 0) and 1 (u = 1) run with the loop, 2 (v = 1) and 3 (u = 0) against it */
    memset(out, 0, sizeof *out);
    out->nu = nu;
    out->nv = nv;
    if ((e = cm_knots_uniform(nu, 3, out->U, st)) != CM_OK || (e = cm_knots_uniform(nv, 3, out->V, st)) != CM_OK)
        return e;
    for (int s = 0; s < 4; s++) {
        int m = 0, n = (s & 1) ? nv : nu;
        if ((e = chain_samples(in, corner[s], corner[(s + 1) % 4], s >= 2, twist, ws, &m, st)) != CM_OK)
            return e;
        const double *kn = (s & 1) ? out->V : out->U;
        if ((e = cm_fit_curve(ws->p, ws->t, NULL, m, 3, n, kn, &ws->p[0], &ws->p[m - 1], ws->side[s], NULL, &ws->fit,
                              st)) != CM_OK)
            return e;
        for (int i = 0; i < n; i++)
            ws->sn[s][i] = chain_normal(ws, m, greville(kn, i), in->nF);
    }

    /* the bilinearly blended Coons net of the sides, at the Greville abscissae (linear precision) */
    cm_vec3 C00 = ws->side[0][0], C10 = ws->side[0][nu - 1], C01 = ws->side[2][0], C11 = ws->side[2][nu - 1];
    for (int i = 0; i < nu; i++) {
        double u = greville(out->U, i);
        for (int j = 0; j < nv; j++) {
            double v = greville(out->V, j);
            cm_vec3 P;
            if (j == 0)
                P = ws->side[0][i];
            else if (j == nv - 1)
                P = ws->side[2][i];
            else if (i == 0)
                P = ws->side[3][j];
            else if (i == nu - 1)
                P = ws->side[1][j];
            else {
                P = cm_add(cm_add(cm_scale(ws->side[0][i], 1.0 - v), cm_scale(ws->side[2][i], v)),
                           cm_add(cm_scale(ws->side[3][j], 1.0 - u), cm_scale(ws->side[1][j], u)));
                cm_vec3 B = cm_add(cm_add(cm_scale(C00, (1.0 - u) * (1.0 - v)), cm_scale(C10, u * (1.0 - v))),
                                   cm_add(cm_scale(C01, (1.0 - u) * v), cm_scale(C11, u * v)));
                P = cm_sub(P, B);
            }
            out->ctrl[i * nv + j] = P;
        }
    }

    /* the second ring into the sides' tangent planes */
    for (int i = 1; i < nu - 1; i++)
        for (int j = 1; j < nv - 1; j++) {
            cm_vec3 b[2], n[2];
            int k = 0;
            if (j == 1)
                b[k] = out->ctrl[i * nv], n[k++] = ws->sn[0][i];
            if (j == nv - 2)
                b[k] = out->ctrl[i * nv + nv - 1], n[k++] = ws->sn[2][i];
            if (i == 1 && k < 2)
                b[k] = out->ctrl[j], n[k++] = ws->sn[3][j];
            if (i == nu - 2 && k < 2)
                b[k] = out->ctrl[(nu - 1) * nv + j], n[k++] = ws->sn[1][j];
            out->ctrl[i * nv + j] = restrict_point(out->ctrl[i * nv + j], b, n, k);
        }

    /* mode 1: the interior of least thin-plate energy, the two outer rings fixed */
    if (mode == 1 && K > 0) {
        memset(ws->band, 0, sizeof ws->band[0] * (size_t)K * (size_t)(w + 1));
        memset(ws->rhs, 0, sizeof ws->rhs[0] * (size_t)K);
        cm_net_lsq L = {nu, nv, 2, w, ws->band, ws->rhs, out->ctrl};
        cm_net_fairing(&L, 1.0);
        if ((e = cm_chol_band(ws->band, K, w, st)) != CM_OK)
            return e;
        cm_chol_band_solve3(ws->band, K, w, ws->rhs);
        for (int i = 2; i < nu - 2; i++)
            for (int j = 2; j < nv - 2; j++)
                out->ctrl[i * nv + j] = ws->rhs[cm_net_unknown(&L, i, j)];
    }
    for (int i = 0; i < nu * nv; i++)
        if (!cm_finite3(out->ctrl[i]))
            return cm_fail(st, CM_E_NONFINITE, "g1fit: control point");
    cm_nfill_surface_view(out);
    return CM_OK;
}
