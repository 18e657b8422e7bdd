/* cm_nfill.c - method NFILL's surface (spec §8; see cm_nfill.h). */
#include "cm/cm_nfill.h"

#include <stddef.h>
#include <string.h>

#include "cm/cm_limits_info.h"

const double cm_nfill_phi[CM_NFILL_PHI_COUNT] = {0.0, 1e-4, 1e-3, 1e-2, 1e-1};

/* spec 8.3: boundary samples weigh 10, a ray's sample 1 / (1 + (lambda |delta| / ell)^2) */
#define NFILL_W_BOUNDARY 10.0
/* spec 8.2: the rectangle is the samples' box enlarged by this fraction of its larger side */
#define NFILL_ENLARGE 0.1
/* spec 8.3: ell, the ray weights' length scale, as a fraction of the rectangle's diagonal */
#define NFILL_ELL 0.1
/* spec 8.3 step 1: no ray where the tangent plane is this close to vertical in the frame */
#define NFILL_MIN_DELTA 0.1
/* spec 8.3 step 3: reference planes the ray runs along (|delta . normal| below this) are ignored */
#define NFILL_PLANE_EPS 1e-9

static cm_err degenerate(cm_status *st, const char *where)
{
    return cm_fail(st, CM_E_DEGENERATE, where);
}

/*
 * 8.1: the outer loop's samples in the frame, with their unit inward directions d = unit(N(t) x T(t)),
 * N(t) = (1 - t) N_s + t N_e the edge's basis normals (5.4) interpolated along it.  Deviation from
 * spec 5.4, which takes d = perp(A(t), T(t)) with A linear between the end bases A = unit(N x T): on
 * an edge that turns by half a circle A_e = -A_s, so A vanishes in the middle and d with it (68 faces
 * of two corpus models, among them every half-circle edge); the normals do not turn with the edge.
 * A sample whose d is still undefined (N along T) gets no ray (d = 0), as 8.3 step 1 does for a
 * tangent plane square to the frame.
 */
static cm_err loop_samples(const cm_greg_input *in, const cm_nfill_holes *holes, cm_nfill_ws *ws, int *count,
                           cm_status *st)
{
    int k = 0;
    ws->loop_start[0] = 0;
    cm_vec3 zero = cm_v3(0.0, 0.0, 0.0);
    for (int s = 0; s < in->n; s++) {
        const cm_greg_side *gs = &in->side[s];
        double sg = gs->rev ? -1.0 : 1.0;
        /* spec 5.3: a reflex corner's geometric normal is turned to the face's side (the exact
           patches' input leaves it as the loop gives it: they never take such corners) */
        cm_vec3 Ns = cm_dot(gs->Ns, in->nF) < 0.0 ? cm_neg(gs->Ns) : gs->Ns;
        cm_vec3 Ne = cm_dot(gs->Ne, in->nF) < 0.0 ? cm_neg(gs->Ne) : gs->Ne;
        for (int j = 0; j < CM_FMT_SEG_PER_EDGE; j++) {
            double u = (double)j / (double)CM_FMT_SEG_PER_EDGE;
            cm_vec3 q[CM_MAX_DERS + 1];
            cm_err e = cm_curve_eval(&gs->curve, gs->rev ? 1.0 - u : u, 1, q, st);
            if (e != CM_OK)
                return e;
            cm_vec3 T = cm_scale(q[1], sg);
            int ok = cm_norm(T) > in->eps_len;
            cm_vec3 d = zero;
            if (ok) {
                cm_vec3 N = cm_add(cm_scale(Ns, 1.0 - u), cm_scale(Ne, u));
                d = cm_unit_or(cm_cross(N, cm_unit(T)), CM_GREG_EPS_DIR, zero, &ok);
            }
            ws->p[k] = q[0];
            ws->d[k] = ok ? d : zero;
            k++;
        }
    }
    ws->loop_start[1] = k;
    /* the holes: their samples, no directions (see cm_nfill.h) */
    for (int l = 0; holes && l < holes->n; l++) {
        for (int i = holes->start[l]; i < holes->start[l + 1]; i++) {
            ws->p[k] = holes->pts[i];
            ws->d[k] = zero;
            k++;
        }
        ws->loop_start[l + 2] = k;
    }
    *count = k;
    return CM_OK;
}

/* 8.3 step 2: the smallest lambda > 0 where the ray from sample k crosses a segment of any loop's
   polygon not incident to k (HUGE_VAL: none) */
static double ray_cross(const cm_nfill_ws *ws, int nloops, int k, cm_vec2 o, cm_vec2 dir)
{
    double best = HUGE_VAL;
    int l = 0;
    for (int i = 0; i < ws->loop_start[nloops]; i++) {
        while (i >= ws->loop_start[l + 1])
            l++;
        int i1 = i + 1 == ws->loop_start[l + 1] ? ws->loop_start[l] : i + 1; /* the loop closes */
        if (i == k || i1 == k)
            continue;
        cm_vec2 a = cm_v2(ws->p[i].x, ws->p[i].y), b = cm_v2(ws->p[i1].x, ws->p[i1].y);
        cm_vec2 e = cm_sub2(b, a), w = cm_sub2(a, o);
        double den = cm_cross2(dir, e);
        if (den == 0.0)
            continue;
        double lam = cm_cross2(w, e) / den, mu = cm_cross2(w, dir) / den;
        if (lam > 0.0 && mu >= 0.0 && mu <= 1.0 && lam < best)
            best = lam;
    }
    return best;
}

/* the hits of `side`, sorted by parameter (insertion sort, ties keep the sample order) */
static int side_hits(cm_nfill_ws *ws, int nb, int side)
{
    int m = 0;
    for (int k = 0; k < nb; k++) {
        if (ws->hit_side[k] != side)
            continue;
        int i = m++;
        while (i > 0 && ws->t[i - 1] > ws->hit_t[k]) {
            ws->t[i] = ws->t[i - 1];
            ws->q[i] = ws->q[i - 1];
            i--;
        }
        ws->t[i] = ws->hit_t[k];
        ws->q[i] = ws->hit[k];
    }
    return m;
}

/* 8.4 step 2: side s's free fit extended linearly beyond its data to parameter tau */
static cm_err side_extend(const cm_nfill_ws *ws, int s, double tau, cm_vec3 *out, cm_status *st)
{
    double kn[CM_MAX_FIT_CTRL + 4];
    cm_curve c = {3, ws->nfirst[s], kn, ws->first[s], NULL};
    cm_err e = cm_knots_uniform(ws->nfirst[s], 3, kn, st);
    if (e != CM_OK)
        return e;
    double ts = tau < ws->tmin[s] ? ws->tmin[s] : (tau > ws->tmax[s] ? ws->tmax[s] : tau);
    cm_vec3 d[CM_MAX_DERS + 1];
    if ((e = cm_curve_eval(&c, ts, 1, d, st)) != CM_OK)
        return e;
    *out = cm_add(d[0], cm_scale(d[1], tau - ts));
    return CM_OK;
}

int cm_net_unknown(const cm_net_lsq *L, int i, int j)
{
    int m = L->margin;
    if (i < m || i > L->nu - 1 - m || j < m || j > L->nv - 1 - m)
        return -1;
    return (i - m) * (L->nv - 2 * m) + (j - m);
}

/* np is at most 16 (a bicubic point's 4 x 4 basis); each point's unknown number is looked up once
   (two integer divisions each, 2 np of them where it was np (np + 1): NFILL's normal equations were
   a fifth of C1G0B0O's decode), and the sums are taken in the same order as before: the same bits */
#define NET_MAX_TERMS 16
void cm_net_accumulate(cm_net_lsq *L, const int *pts, const double *c, int np, double weight, const cm_vec3 *Q)
{
    int nv = L->nv, w = L->w, r[NET_MAX_TERMS];
    if (np > NET_MAX_TERMS)
        np = NET_MAX_TERMS;
    for (int a = 0; a < np; a++)
        r[a] = cm_net_unknown(L, pts[a] / nv, pts[a] % nv);
    for (int a = 0; a < np; a++) {
        int ra = r[a];
        if (ra < 0 || c[a] == 0.0)
            continue;
        double wa = weight * c[a];
        if (Q)
            L->rhs[ra] = cm_add(L->rhs[ra], cm_scale(*Q, wa));
        double *row = &L->band[CM_BAND_IDX(ra, ra, w)];
        for (int b = 0; b < np; b++) {
            int rb = r[b];
            if (rb < 0)
                L->rhs[ra] = cm_sub(L->rhs[ra], cm_scale(L->ctrl[pts[b]], wa * c[b]));
            else if (rb <= ra)
                row[ra - rb] += wa * c[b];
        }
    }
}

void cm_net_fairing(cm_net_lsq *L, double lf)
{
    int nu = L->nu, nv = L->nv;
    static const double c2[3] = {1.0, -2.0, 1.0}, ctw[4] = {1.0, -1.0, -1.0, 1.0};
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            int pts[4];
            if (i + 2 < nu) {
                pts[0] = i * nv + j, pts[1] = (i + 1) * nv + j, pts[2] = (i + 2) * nv + j;
                cm_net_accumulate(L, pts, c2, 3, lf, NULL);
            }
            if (j + 2 < nv) {
                pts[0] = i * nv + j, pts[1] = i * nv + j + 1, pts[2] = i * nv + j + 2;
                cm_net_accumulate(L, pts, c2, 3, lf, NULL);
            }
            if (i + 1 < nu && j + 1 < nv) {
                pts[0] = (i + 1) * nv + j + 1, pts[1] = (i + 1) * nv + j, pts[2] = i * nv + j + 1;
                pts[3] = i * nv + j;
                cm_net_accumulate(L, pts, ctw, 4, 2.0 * lf, NULL);
            }
        }
}

/* one data point (local Q at parameters u, v) into the normal equations */
static cm_err add_point(cm_net_lsq *L, const cm_nfill_surface *s, cm_vec3 Q, double u, double v, double weight,
                        cm_status *st)
{
    double Nu[CM_MAX_ORDER], Nv[CM_MAX_ORDER];
    int su = cm_bspl_find_span(s->nu, 3, s->U, u), sv = cm_bspl_find_span(s->nv, 3, s->V, v);
    cm_err e;
    if ((e = cm_bspl_basis(su, u, 3, s->U, Nu, st)) != CM_OK || (e = cm_bspl_basis(sv, v, 3, s->V, Nv, st)) != CM_OK)
        return e;
    int pts[16];
    double c[16];
    for (int a = 0; a < 4; a++)
        for (int b = 0; b < 4; b++) {
            pts[a * 4 + b] = (su - 3 + a) * s->nv + (sv - 3 + b);
            c[a * 4 + b] = Nu[a] * Nv[b];
        }
    cm_net_accumulate(L, pts, c, 16, weight, &Q);
    return CM_OK;
}

CM_ONCE_PER_FACE cm_err cm_nfill_build(const cm_greg_input *in, const cm_nfill_holes *holes, int nu, int nv, int phi, cm_frame *frame,
                      cm_nfill_surface *out, cm_nfill_ws *ws, cm_status *st)
{
    cm_err e;
    if (nu > CM_MAX_FIT_CTRL || nv > CM_MAX_FIT_CTRL)
        return cm_fail_limit(st, CM_LIMIT_MAX_FIT_CTRL, (uint64_t)(nu > nv ? nu : nv), CM_MAX_FIT_CTRL, __func__);
    if (nu < CM_NFILL_MIN_CTRL || nv < CM_NFILL_MIN_CTRL || phi < 0 || phi >= CM_NFILL_PHI_COUNT)
        return cm_fail(st, CM_E_RANGE, __func__);
    int K = (nu - 2) * (nv - 2);
    int w = 3 * (nv - 2) + 3 < K - 1 ? 3 * (nv - 2) + 3 : K - 1;
    if (K > CM_MAX_LSQ_UNKNOWNS)
        return cm_fail_limit(st, CM_LIMIT_MAX_LSQ_UNKNOWNS, (uint64_t)K, CM_MAX_LSQ_UNKNOWNS, __func__);
    if (w > CM_MAX_LSQ_BAND)
        return cm_fail_limit(st, CM_LIMIT_MAX_LSQ_BAND, (uint64_t)w, CM_MAX_LSQ_BAND, __func__);
    if (in->n < 1 || in->n > CM_NFILL_MAX_EDGES)
        return cm_fail(st, CM_E_RANGE, __func__);
    int nloops = 1 + (holes ? holes->n : 0);
    if (holes && (holes->n < 0 || holes->n > CM_NFILL_MAX_HOLES || holes->start[0] != 0 ||
                  in->n * CM_FMT_SEG_PER_EDGE + holes->start[holes->n] > CM_NFILL_MAX_BSAMP))
        return cm_fail(st, CM_E_RANGE, __func__);
    for (int l = 0; holes && l < holes->n; l++)
        if (!(holes->start[l + 1] > holes->start[l]))
            return cm_fail(st, CM_E_RANGE, __func__);

    /* 8.1 samples, K11 frame (normal from the outer loop), local coordinates */
    int nb;
    if ((e = loop_samples(in, holes, ws, &nb, st)) != CM_OK)
        return e;
    if ((e = cm_face_frame(ws->p, ws->loop_start[1], ws->p, nb, in->eps_len, frame, st)) != CM_OK)
        return e;
    for (int k = 0; k < nb; k++) {
        cm_vec3 d = ws->d[k];
        ws->p[k] = cm_frame_local(frame, ws->p[k]);
        ws->d[k] = cm_v3(cm_dot(d, frame->ex), cm_dot(d, frame->ey), cm_dot(d, frame->ez));
    }

    /* 8.2 the reference rectangle */
    double X0 = ws->p[0].x, X1 = X0, Y0 = ws->p[0].y, Y1 = Y0;
    for (int k = 1; k < nb; k++) {
        X0 = ws->p[k].x < X0 ? ws->p[k].x : X0;
        X1 = ws->p[k].x > X1 ? ws->p[k].x : X1;
        Y0 = ws->p[k].y < Y0 ? ws->p[k].y : Y0;
        Y1 = ws->p[k].y > Y1 ? ws->p[k].y : Y1;
    }
    double grow = NFILL_ENLARGE * (X1 - X0 > Y1 - Y0 ? X1 - X0 : Y1 - Y0);
    if (!(grow > in->eps_len))
        return degenerate(st, "nfill: the loop has no extent in its plane");
    X0 -= grow;
    X1 += grow;
    Y0 -= grow;
    Y1 += grow;
    double ell = NFILL_ELL * sqrt((X1 - X0) * (X1 - X0) + (Y1 - Y0) * (Y1 - Y0));

    /* 8.3 rays and hit points */
    for (int k = 0; k < nb; k++) {
        cm_vec2 o = cm_v2(ws->p[k].x, ws->p[k].y), dir = cm_v2(-ws->d[k].x, -ws->d[k].y);
        ws->lam[k] = 0.0;
        ws->hit_side[k] = -1;
        double dl = sqrt(cm_dot2(dir, dir));
        if (dl < NFILL_MIN_DELTA)
            continue; /* step 1: the tangent plane is nearly vertical in the frame */
        double lc = ray_cross(ws, nloops, k, o, dir), lp = HUGE_VAL;
        int side = -1;
        const double bound[4] = {Y0, X1, Y1, X0};
        for (int s = 0; s < 4; s++) {
            double comp = (s & 1) ? dir.x : dir.y, from = (s & 1) ? o.x : o.y;
            if (!(fabs(comp) > NFILL_PLANE_EPS) || ((s == 0 || s == 3) ? comp > 0.0 : comp < 0.0))
                continue;
            double lam = (bound[s] - from) / comp;
            if (lam > 0.0 && lam < lp) {
                lp = lam;
                side = s;
            }
        }
        if (side < 0 && !(lc < HUGE_VAL))
            continue;
        if (lc < lp) {
            ws->lam[k] = lc;
        } else {
            ws->lam[k] = lp;
            cm_vec3 q = cm_sub(ws->p[k], cm_scale(ws->d[k], lp));
            /* on its plane exactly: the side curve's in-plane coordinate is then linear (8.4) */
            if (side == 0)
                q.y = Y0;
            else if (side == 1)
                q.x = X1;
            else if (side == 2)
                q.y = Y1;
            else
                q.x = X0;
            ws->hit[k] = q;
            ws->hit_side[k] = (int8_t)side;
            ws->hit_t[k] = (side & 1) ? (q.y - Y0) / (Y1 - Y0) : (q.x - X0) / (X1 - X0);
        }
    }

    /* 8.4 side curves: a free fit, corners from the linear extensions, a refit between the corners */
    for (int s = 0; s < 4; s++) {
        int m = side_hits(ws, nb, s);
        if (m < 4)
            return degenerate(st, "nfill: fewer than 4 hit points on a side of the rectangle");
        int n = (s & 1) ? nv : nu;
        int n1 = m - 1 < 4 ? 4 : m - 1;
        n1 = n1 < n ? n1 : n;
        if ((e = cm_knots_uniform(n1, 3, ws->knots, st)) != CM_OK ||
            (e = cm_fit_curve(ws->q, ws->t, NULL, m, 3, n1, ws->knots, NULL, NULL, ws->first[s], NULL, &ws->fit, st)) !=
                CM_OK)
            return e;
        ws->nfirst[s] = n1;
        ws->tmin[s] = ws->t[0];
        ws->tmax[s] = ws->t[m - 1];
    }
    /* corners (u, v) = (0,0), (1,0), (1,1), (0,1): sides meeting there and their parameters */
    static const int cs[4][2] = {{0, 3}, {0, 1}, {1, 2}, {2, 3}};
    static const double ct[4][2] = {{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}};
    cm_vec3 corner[4];
    for (int c = 0; c < 4; c++) {
        cm_vec3 ea, eb;
        if ((e = side_extend(ws, cs[c][0], ct[c][0], &ea, st)) != CM_OK ||
            (e = side_extend(ws, cs[c][1], ct[c][1], &eb, st)) != CM_OK)
            return e;
        corner[c] = cm_scale(cm_add(ea, eb), 0.5);
        corner[c].x = (c == 0 || c == 3) ? X0 : X1;
        corner[c].y = c < 2 ? Y0 : Y1;
    }
    memset(out, 0, sizeof *out);
    out->nu = nu;
    out->nv = nv;
    if ((e = cm_knots_uniform(nu, 3, out->U, st)) != CM_OK || (e = cm_knots_uniform(nv, 3, out->V, st)) != CM_OK)
        return e;
    /* side s runs from corner a to corner b in its parameter; its points go to the net's border */
    static const int from[4] = {0, 1, 3, 0}, to[4] = {1, 2, 2, 3};
    for (int s = 0; s < 4; s++) {
        int m = side_hits(ws, nb, s), n = (s & 1) ? nv : nu;
        cm_vec3 P[CM_MAX_FIT_CTRL];
        if ((e = cm_knots_uniform(n, 3, ws->knots, st)) != CM_OK ||
            (e = cm_fit_curve(ws->q, ws->t, NULL, m, 3, n, ws->knots, &corner[from[s]], &corner[to[s]], P, NULL,
                              &ws->fit, st)) != CM_OK)
            return e;
        for (int i = 0; i < n; i++) {
            if (s == 0)
                out->ctrl[i * nv] = P[i];
            else if (s == 2)
                out->ctrl[i * nv + nv - 1] = P[i];
            else if (s == 1)
                out->ctrl[(nu - 1) * nv + i] = P[i];
            else
                out->ctrl[i] = P[i];
        }
    }

    /* 8.7 least squares: boundary samples, then each ray's samples, then the fairing */
    memset(ws->band, 0, sizeof ws->band[0] * (size_t)K * (size_t)(w + 1));
    memset(ws->rhs, 0, sizeof ws->rhs[0] * (size_t)K);
    cm_net_lsq L = {nu, nv, 1, w, ws->band, ws->rhs, out->ctrl};
    double sx = 1.0 / (X1 - X0), sy = 1.0 / (Y1 - Y0);
    for (int k = 0; k < nb; k++)
        if ((e = add_point(&L, out, ws->p[k], (ws->p[k].x - X0) * sx, (ws->p[k].y - Y0) * sy, NFILL_W_BOUNDARY,
                           st)) != CM_OK)
            return e;
    for (int k = 0; k < nb; k++) {
        if (!(ws->lam[k] > 0.0))
            continue;
        double dl = sqrt(ws->d[k].x * ws->d[k].x + ws->d[k].y * ws->d[k].y);
        for (int j = 1; j < CM_NFILL_RAY_SUB; j++) {
            double lam = (double)j * ws->lam[k] / (double)CM_NFILL_RAY_SUB, r = lam * dl / ell;
            cm_vec3 q = cm_sub(ws->p[k], cm_scale(ws->d[k], lam));
            double u = (q.x - X0) * sx, v = (q.y - Y0) * sy;
            u = u < 0.0 ? 0.0 : (u > 1.0 ? 1.0 : u);
            v = v < 0.0 ? 0.0 : (v > 1.0 ? 1.0 : v);
            if ((e = add_point(&L, out, q, u, v, 1.0 / (1.0 + r * r), st)) != CM_OK)
                return e;
        }
    }
    if (phi > 0) {
        double trace = 0.0;
        for (int r = 0; r < K; r++)
            trace += ws->band[CM_BAND_IDX(r, r, w)];
        double lf = cm_nfill_phi[phi] * trace / (double)K;
        cm_net_fairing(&L, lf);
    }
    if ((e = cm_chol_band(ws->band, K, w, st)) != CM_OK)
        return e;
    cm_chol_band_solve3(ws->band, K, w, ws->rhs);
    for (int i = 1; i < nu - 1; i++)
        for (int j = 1; j < nv - 1; j++)
            out->ctrl[i * nv + j] = ws->rhs[cm_net_unknown(&L, i, j)];
    for (int i = 0; i < nu * nv; i++) {
        if (!cm_finite3(out->ctrl[i]))
            return cm_fail(st, CM_E_NONFINITE, "nfill: control point");
        out->ctrl[i] = cm_frame_world(frame, out->ctrl[i]);
    }
    cm_nfill_surface_view(out);
    return CM_OK;
}

void cm_nfill_surface_view(cm_nfill_surface *s)
{
    s->surf.p = s->surf.q = 3;
    s->surf.nu = s->nu;
    s->surf.nv = s->nv;
    s->surf.U = s->U;
    s->surf.V = s->V;
    s->surf.ctrl = s->ctrl;
    s->surf.w = NULL;
}

static uint32_t fnv_double(uint32_t h, double x)
{
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    for (int b = 0; b < 8; b++) {
        h ^= (uint32_t)((bits >> (8 * b)) & 0xFFu);
        h *= 16777619u;
    }
    return h;
}

uint32_t cm_nfill_checksum(const cm_nfill_surface *s)
{
    uint32_t h = 2166136261u;
    int n = s->nu * s->nv;
    for (int i = 0; i < n && i < CM_MAX_FIT_CTRL * CM_MAX_FIT_CTRL; i++) {
        h = fnv_double(h, s->ctrl[i].x);
        h = fnv_double(h, s->ctrl[i].y);
        h = fnv_double(h, s->ctrl[i].z);
    }
    return h;
}
