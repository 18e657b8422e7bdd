/* cm_egreg.c - the Gregory patch over exact boundaries (cm_egreg.h). */
#include "cm/cm_egreg.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "cm/cm_gregory.h"

static const cm_vec3 zero3 = {0.0, 0.0, 0.0};

static double clamp01(double s)
{
    if (!(s > 0.0))
        return 0.0;
    return s > 1.0 ? 1.0 : s;
}

/* x0 + r (x1 - x0): alpha, beta and N along the edge */
static double lerp(double x0, double x1, double r) { return x0 + r * (x1 - x0); }

/* the normals' blend: A = unit(a), a = N x B', N = N0 + r (N1 - N0); a' = N' x B' + N x B'' */
static void blend_basis(const cm_egreg_turn *tb, double r, double drds, const cm_vec3 q[3], cm_vec3 *a,
                        cm_vec3 *da)
{
    cm_vec3 dN = cm_sub(tb->N1, tb->N0);
    cm_vec3 N = cm_axpy(tb->N0, r, dN);
    *a = cm_cross(N, q[1]);
    *da = cm_add(cm_cross(cm_scale(dN, drds), q[1]), cm_cross(N, q[2]));
}

/* the normals carried along a plane curve: a = alpha m - beta P, m = P x t, t = B'/|B'|;
   a' = alpha' m + alpha m' - beta' P with m' = P x t', t' = (B'' - t (t.B'')) / |B'| */
static cm_err plane_basis(const cm_egreg_turn *tb, double r, double drds, const cm_vec3 q[3], cm_vec3 *a,
                          cm_vec3 *da, cm_status *st)
{
    double len = cm_norm(q[1]);
    if (!(len > 0.0))
        return cm_fail(st, CM_E_DEGENERATE, "exact Gregory side: zero tangent");
    cm_vec3 t = cm_scale(q[1], 1.0 / len);
    cm_vec3 dt = cm_scale(cm_sub(q[2], cm_scale(t, cm_dot(t, q[2]))), 1.0 / len);
    cm_vec3 m = cm_cross(tb->P, t), dm = cm_cross(tb->P, dt);
    double al = lerp(tb->a0, tb->a1, r), be = lerp(tb->b0, tb->b1, r);
    double dal = (tb->a1 - tb->a0) * drds, dbe = (tb->b1 - tb->b0) * drds;
    *a = cm_sub(cm_scale(m, al), cm_scale(tb->P, be));
    *da = cm_sub(cm_add(cm_scale(m, dal), cm_scale(dm, al)), cm_scale(tb->P, dbe));
    return CM_OK;
}

/* the turning basis A and its derivative per unit s (cm_egreg.h) at the fraction r of the edge */
static cm_err turning_basis(const cm_egreg_turn *tb, double r, double drds, const cm_vec3 q[3], cm_vec3 *A,
                            cm_vec3 *dA, cm_status *st)
{
    cm_vec3 a = zero3, da = zero3;
    if (tb->mode == CM_EGREG_TURN_PLANE) {
        cm_err e = plane_basis(tb, r, drds, q, &a, &da, st);
        if (e != CM_OK)
            return e;
    } else {
        blend_basis(tb, r, drds, q, &a, &da);
    }
    double len = cm_norm(a);
    if (!(len > 1e-12 * (1.0 + cm_norm(q[1]))))
        return cm_fail(st, CM_E_DEGENERATE, "exact Gregory side: turning basis vanishes");
    *A = cm_scale(a, 1.0 / len);
    *dA = cm_scale(cm_sub(da, cm_scale(*A, cm_dot(*A, da))), 1.0 / len);
    return CM_OK;
}

cm_egreg_turn cm_egreg_turn_part(const cm_egreg_turn *tb, double r0, double r1)
{
    cm_egreg_turn p = *tb;
    if (tb->mode == CM_EGREG_TURN_BLEND) {
        p.N0 = cm_axpy(tb->N0, r0, cm_sub(tb->N1, tb->N0));
        p.N1 = cm_axpy(tb->N0, r1, cm_sub(tb->N1, tb->N0));
    } else if (tb->mode == CM_EGREG_TURN_PLANE) {
        p.a0 = lerp(tb->a0, tb->a1, r0);
        p.a1 = lerp(tb->a0, tb->a1, r1);
        p.b0 = lerp(tb->b0, tb->b1, r0);
        p.b1 = lerp(tb->b0, tb->b1, r1);
    }
    return p;
}

/* samples of an edge's plane test (cm_egreg_choose_turn) */
#define TURN_PLANE_SAMPLES 8
/* how far from its plane, relative to its chord, a plane curve's samples may lie */
#define TURN_PLANE_FLAT 1e-3

cm_err cm_egreg_choose_turn(const cm_egreg_side *sd, cm_vec3 Ns, cm_vec3 Ne, cm_egreg_turn *tb, cm_status *st)
{
    memset(tb, 0, sizeof *tb);
    if (!(cm_dot(sd->As, sd->Ae) < 0.0))
        return CM_OK; /* a right angle or less: the linear basis */
    cm_vec3 d0[3], dm[3], d1[3];
    cm_err e;
    if ((e = cm_egreg_side_eval(sd, 0.0, d0, NULL, st)) != CM_OK ||
        (e = cm_egreg_side_eval(sd, 0.5, dm, NULL, st)) != CM_OK ||
        (e = cm_egreg_side_eval(sd, 1.0, d1, NULL, st)) != CM_OK)
        return e;
    /* the plane through its ends and middle (the same plane, up to its sign, from either direction;
       the basis does not depend on that sign) */
    cm_vec3 a = cm_sub(dm[0], d0[0]), c = cm_sub(d1[0], d0[0]);
    cm_vec3 n = cm_cross(a, c);
    double chord = cm_norm(a) + cm_norm(c), nl = cm_norm(n);
    int plane = nl > 1e-9 * chord * chord;
    for (int i = 1; i < TURN_PLANE_SAMPLES && plane; i++) {
        cm_vec3 d[3];
        if ((e = cm_egreg_side_eval(sd, (double)i / TURN_PLANE_SAMPLES, d, NULL, st)) != CM_OK)
            return e;
        plane = fabs(cm_dot(cm_sub(d[0], d0[0]), n)) <= TURN_PLANE_FLAT * chord * nl;
    }
    double l0 = cm_norm(d0[1]), l1 = cm_norm(d1[1]);
    if (plane && l0 > 0.0 && l1 > 0.0) {
        tb->mode = CM_EGREG_TURN_PLANE;
        tb->P = cm_scale(n, 1.0 / nl);
        cm_vec3 m0 = cm_cross(tb->P, cm_scale(d0[1], 1.0 / l0)), m1 = cm_cross(tb->P, cm_scale(d1[1], 1.0 / l1));
        tb->a0 = cm_dot(Ns, tb->P);
        tb->b0 = cm_dot(Ns, m0);
        tb->a1 = cm_dot(Ne, tb->P);
        tb->b1 = cm_dot(Ne, m1);
        return CM_OK;
    }
    if (cm_dot(Ns, Ne) > cm_dot(sd->As, sd->Ae)) {
        tb->mode = CM_EGREG_TURN_BLEND;
        tb->N0 = Ns;
        tb->N1 = Ne;
    }
    return CM_OK;
}

cm_err cm_egreg_side_eval(const cm_egreg_side *sd, double s, cm_vec3 d[3], cm_vec3 x[2], cm_status *st)
{
    cm_vec3 q[3];
    s = clamp01(s);
    cm_vec3 As = sd->As, dA = cm_sub(sd->Ae, sd->As); /* the basis at s = 0 and its slope per unit s */
    double a0 = 0.0;                                 /* where As holds */
    const cm_egreg_turn *tb = sd->kind == CM_EGREG_SIDE_EDGE ? &sd->tb : NULL; /* the turning basis, */
    double frac = s, drds = 1.0; /* the fraction of its edge at s and its rate */
    if (sd->kind == CM_EGREG_SIDE_CHAIN) {
        /* the last piece that starts at or before s (fixed order: the same piece on every host) */
        int np = sd->npiece < 1 ? 1 : sd->npiece > CM_EGREG_MAX_PIECES ? CM_EGREG_MAX_PIECES : sd->npiece, j = 0;
        for (int i = 1; i < np; i++)
            if (sd->piece[i].s0 <= s)
                j = i;
        const cm_egreg_piece *P = &sd->piece[j];
        double ds = P->s1 - P->s0, dt = P->t1 - P->t0;
        if (!(ds > 0.0))
            return cm_fail(st, CM_E_DEGENERATE, "egreg: empty piece");
        cm_err e = cm_curve_eval(&P->curve, P->t0 + dt * ((s - P->s0) / ds), 2, q, st);
        if (e != CM_OK)
            return e;
        double r = dt / ds;
        q[1] = cm_scale(q[1], r);
        q[2] = cm_scale(q[2], r * r);
        As = P->As;
        dA = cm_scale(cm_sub(P->Ae, P->As), 1.0 / ds);
        a0 = P->s0;
        tb = &P->tb;
        frac = (s - P->s0) / ds;
        drds = 1.0 / ds;
    } else if (sd->kind == CM_EGREG_SIDE_EDGE) {
        double dt = sd->t1 - sd->t0;
        cm_err e = cm_curve_eval(&sd->curve, sd->t0 + dt * s, 2, q, st);
        if (e != CM_OK)
            return e;
        q[1] = cm_scale(q[1], dt);
        q[2] = cm_scale(q[2], dt * dt);
    } else {
        cm_cubic_eval(&sd->cub, s, q);
    }
    if (d) {
        d[0] = q[0];
        d[1] = q[1];
        d[2] = q[2];
    }
    if (!x)
        return CM_OK;
    if (sd->fan) {
        double B[4], dB[4];
        cm_bernstein3(s, B, dB);
        x[0] = x[1] = zero3;
        for (int i = 0; i < 4; i++) {
            x[0] = cm_axpy(x[0], B[i], sd->fx[i]);
            x[1] = cm_axpy(x[1], dB[i], sd->fx[i]);
        }
        return CM_OK;
    }
    /* X = k A + h B', X' = k' A + k A' + h' B' + h B'' (k, h linear in s; A linear in s, or on each
       piece of a chain) */
    double dk = sd->k1 - sd->k0, dh = sd->h1 - sd->h0;
    double k = sd->k0 + dk * s, h = sd->h0 + dh * s;
    cm_vec3 A = cm_axpy(As, s - a0, dA);
    if (tb && tb->mode != CM_EGREG_TURN_NONE) {
        cm_err e = turning_basis(tb, frac, drds, q, &A, &dA, st);
        if (e != CM_OK)
            return e;
    }
    x[0] = cm_add(cm_scale(A, k), cm_scale(q[1], h));
    cm_vec3 xd = cm_scale(A, dk);
    xd = cm_axpy(xd, k, dA);
    xd = cm_axpy(xd, dh, q[1]);
    x[1] = cm_axpy(xd, h, q[2]);
    return CM_OK;
}

cm_err cm_egreg_side_basis(const cm_egreg_side *sd, double s, cm_vec3 *A, cm_status *st)
{
    cm_egreg_side one = *sd; /* X = 1 A + 0 B' */
    one.fan = 0;
    one.k0 = one.k1 = 1.0;
    one.h0 = one.h1 = 0.0;
    cm_vec3 x[2];
    cm_err e = cm_egreg_side_eval(&one, s, NULL, x, st);
    if (e == CM_OK)
        *A = x[0];
    return e;
}

cm_err cm_egreg_finish(cm_egreg *g, cm_status *st)
{
    cm_vec3 d[4][2][3], x[4][2][2]; /* side, end (s = 0, 1) */
    for (int k = 0; k < 4; k++)
        for (int end = 0; end < 2; end++) {
            cm_err e = cm_egreg_side_eval(&g->side[k], (double)end, d[k][end], x[k][end], st);
            if (e != CM_OK)
                return e;
        }
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            g->M[i][j] = zero3;
    /* corners: (0,0) starts side 0, (1,0) side 1, (1,1) side 2, (0,1) side 3 */
    g->M[0][0] = d[0][0][0];
    g->M[3][0] = d[1][0][0];
    g->M[3][3] = d[2][0][0];
    g->M[0][3] = d[3][0][0];
    /* the cross derivatives at the corners: t0 = X0(u), t2 = -X2(1-u), s0 = X3(1-v), s1 = -X1(v) */
    g->M[0][1] = x[0][0][0];
    g->M[3][1] = x[0][1][0];
    g->M[0][2] = cm_neg(x[2][1][0]);
    g->M[3][2] = cm_neg(x[2][0][0]);
    g->M[1][0] = x[3][1][0];
    g->M[1][3] = x[3][0][0];
    g->M[2][0] = cm_neg(x[1][0][0]);
    g->M[2][3] = cm_neg(x[1][1][0]);
    /* twists: s0' = -X3'(1-v), s1' = -X1'(v) along the u-sides; t0' = X0'(u), t2' = X2'(1-u) */
    g->tw_a[0][0] = cm_neg(x[3][1][1]);
    g->tw_a[0][1] = cm_neg(x[3][0][1]);
    g->tw_a[1][0] = cm_neg(x[1][0][1]);
    g->tw_a[1][1] = cm_neg(x[1][1][1]);
    g->tw_b[0][0] = x[0][0][1];
    g->tw_b[1][0] = x[0][1][1];
    g->tw_b[0][1] = x[2][1][1];
    g->tw_b[1][1] = x[2][0][1];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (!cm_finite3(g->M[i][j]))
                return cm_fail(st, CM_E_NONFINITE, "exact Gregory patch: corner data");
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++)
            if (!cm_finite3(g->tw_a[a][b]) || !cm_finite3(g->tw_b[a][b]))
                return cm_fail(st, CM_E_NONFINITE, "exact Gregory patch: twist");
    return CM_OK;
}

/* cubic Hermite basis (position at 0, derivative at 0, derivative at 1, position at 1) and its derivative */
static void hermite(double s, double H[4], double dH[4])
{
    double s2 = s * s, s3 = s2 * s;
    H[0] = 1.0 - 3.0 * s2 + 2.0 * s3;
    H[1] = s - 2.0 * s2 + s3;
    H[2] = s3 - s2;
    H[3] = 3.0 * s2 - 2.0 * s3;
    dH[0] = 6.0 * s2 - 6.0 * s;
    dH[1] = 1.0 - 4.0 * s + 3.0 * s2;
    dH[2] = 3.0 * s2 - 2.0 * s;
    dH[3] = 6.0 * s - 6.0 * s2;
}

void cm_egreg_memo_reset(cm_egreg_memo *m)
{
    if (++m->gen == 0) { /* (after 2^32 patches: entries of generation 1 would come back) */
        memset(m, 0, sizeof *m);
        m->gen = 1;
    }
}

int cm_egreg_memo_slot(double s)
{
    uint64_t bits;
    memcpy(&bits, &s, sizeof bits);
#if CM_EGREG_MEMO_BITS > 0
    return (int)((bits * 0x9E3779B97F4A7C15ull) >> (64 - CM_EGREG_MEMO_BITS));
#else
    (void)bits;
    return 0;
#endif
}

/* side k at s, from the memo where it holds s */
static cm_err side_eval_memo(const cm_egreg_side *sd, int k, double s, cm_vec3 d[3], cm_vec3 x[2],
                             cm_egreg_memo *memo, cm_status *st)
{
    if (!memo)
        return cm_egreg_side_eval(sd, s, d, x, st);
    cm_egreg_memo_entry *me = &memo->e[k][cm_egreg_memo_slot(s)];
    if (me->gen == memo->gen && memcmp(&me->s, &s, sizeof s) == 0) {
        memcpy(d, me->d, sizeof me->d);
        memcpy(x, me->x, sizeof me->x);
        return CM_OK;
    }
    cm_err e = cm_egreg_side_eval(sd, s, d, x, st);
    if (e == CM_OK) {
        me->s = s;
        me->gen = memo->gen;
        memcpy(me->d, d, sizeof me->d);
        memcpy(me->x, x, sizeof me->x);
    }
    return e;
}

cm_err cm_egreg_eval(const cm_egreg *g, double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv, cm_status *st)
{
    return cm_egreg_eval_memo(g, u, v, S, Su, Sv, NULL, st);
}

cm_err cm_egreg_eval_memo(const cm_egreg *g, double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv,
                          cm_egreg_memo *memo, cm_status *st)
{
    u = clamp01(u);
    v = clamp01(v);
    cm_vec3 d[4][3], x[4][2];
    static const int at_u[4] = {1, 0, 1, 0}; /* sides 0, 2 run with u; 1, 3 with v */
    static const int backwards[4] = {0, 0, 1, 1};
    for (int k = 0; k < 4; k++) {
        double s = at_u[k] ? u : v;
        cm_err e = side_eval_memo(&g->side[k], k, backwards[k] ? 1.0 - s : s, d[k], x[k], memo, st);
        if (e != CM_OK)
            return e;
    }
    /* the v-boundaries as functions of u, the u-boundaries as functions of v, with their derivatives */
    cm_vec3 B[4] = {d[0][0], x[0][0], cm_neg(x[2][0]), d[2][0]};
    cm_vec3 dB[4] = {d[0][1], x[0][1], x[2][1], cm_neg(d[2][1])};
    cm_vec3 A[4] = {d[3][0], x[3][0], cm_neg(x[1][0]), d[1][0]};
    cm_vec3 dA[4] = {cm_neg(d[3][1]), cm_neg(x[3][1]), cm_neg(x[1][1]), d[1][1]};
    cm_vec3 M[4][4], Mu[4][4], Mv[4][4];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            M[i][j] = g->M[i][j];
            Mu[i][j] = Mv[i][j] = zero3;
        }
    cm_greg_blend(g->tw_a[0][0], g->tw_b[0][0], u, v, 1, 0, 0, 1, &M[1][1], &Mu[1][1], &Mv[1][1]);
    cm_greg_blend(g->tw_a[0][1], g->tw_b[0][1], u, 1.0 - v, 1, 0, 0, -1, &M[1][2], &Mu[1][2], &Mv[1][2]);
    cm_greg_blend(g->tw_a[1][0], g->tw_b[1][0], 1.0 - u, v, -1, 0, 0, 1, &M[2][1], &Mu[2][1], &Mv[2][1]);
    cm_greg_blend(g->tw_a[1][1], g->tw_b[1][1], 1.0 - u, 1.0 - v, -1, 0, 0, -1, &M[2][2], &Mu[2][2], &Mv[2][2]);
    double Hu[4], dHu[4], Hv[4], dHv[4];
    hermite(u, Hu, dHu);
    hermite(v, Hv, dHv);
    cm_vec3 s = zero3, su = zero3, sv = zero3;
    for (int i = 0; i < 4; i++) {
        s = cm_axpy(s, Hu[i], A[i]);
        su = cm_axpy(su, dHu[i], A[i]);
        sv = cm_axpy(sv, Hu[i], dA[i]);
    }
    for (int j = 0; j < 4; j++) {
        s = cm_axpy(s, Hv[j], B[j]);
        su = cm_axpy(su, Hv[j], dB[j]);
        sv = cm_axpy(sv, dHv[j], B[j]);
    }
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double w = Hu[i] * Hv[j];
            s = cm_axpy(s, -w, M[i][j]);
            su = cm_axpy(cm_axpy(su, -dHu[i] * Hv[j], M[i][j]), -w, Mu[i][j]);
            sv = cm_axpy(cm_axpy(sv, -Hu[i] * dHv[j], M[i][j]), -w, Mv[i][j]);
        }
    if (!cm_finite3(s) || !cm_finite3(su) || !cm_finite3(sv))
        return cm_fail(st, CM_E_NONFINITE, "exact Gregory patch");
    *S = s;
    if (Su)
        *Su = su;
    if (Sv)
        *Sv = sv;
    return CM_OK;
}
