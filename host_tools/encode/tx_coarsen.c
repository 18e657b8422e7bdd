/*
 * tx_coarsen.c - format 3's precision from the tolerance budget (issue 14.3; docs/FORMAT.md, EDGE).
 *
 * The grid (1e-6 of the model's diagonal) is fine enough for every vertex: vertices are shared by
 * many faces and a tiny face needs them exact.  The interior control points of a curve and the net
 * of a kept surface need much less: a point moved by e moves a B-spline or NURBS curve or surface by
 * at most e (its points are convex combinations of the control points), while the faces they bound
 * are held to a tolerance of up to 1e-3 of the diagonal.  So each curve and each kept net takes a
 * step of its own, 2^s grid steps, and its points are sent as multiples of it:
 *   - the budget: a sixteenth of the tolerance of the faces it bounds (a kept surface: of its face),
 *     so that the rebuild, which the encoder measures on the moved curves anyway, keeps the rest;
 *   - and the shape: no point moves by more than 4.4e-3 of the shortest leg of its polygon or net: a
 *     tangent (a difference of two points) then turns by at most tan(0.5 deg), so that two faces
 *     along a tangent edge stay within the 1 degree the G1 check holds rebuilt faces to (measured
 *     over the corpus: 2e-3 saved 4 % of the bytes, 4.4e-3 8 %, a tolerance share of 1/8 instead of
 *     1/16 under 1 % more: the legs, not the tolerance, bound the step on most curves);
 *   - a curve or net with two coincident successive points (a pole, a collapsed end) keeps the grid,
 *     since its predictions need not keep them coincident.
 * The points are moved in closed loop: each is sent as its prediction from the points already moved
 * plus a multiple of the step, nearest to the original, so each coordinate moves by at most half a
 * step whatever came before.  Everything after this (the methods' trials, the G1 check, the needs)
 * runs on the moved points, exactly as the terminal will decode them.
 */
#include "encode_internal.h"

#include <math.h>

#include "cm/cm_predict.h"

#define BUDGET_SHARE (1.0 / 16.0) /* of the faces' tolerance, for the points of a curve or net */
#define TURN_SHARE 4.4e-3         /* of the shortest leg: tan(0.5 deg) / 2, half a degree of turning */

/* the step exponent for points whose shortest leg is h_min mm (0: coincident points) */
static int choose_step(const tx *t, double tol_mm, double h_min)
{
    if (!t->o->predicted || !(tol_mm > 0) || !(h_min > 0))
        return 0;
    double allowed = fmin(BUDGET_SHARE * tol_mm, TURN_SHARE * h_min);
    int s = 0;
    /* a coordinate moves by at most half a step: the point by sqrt(3)/2 of it */
    while (s < CM_FMT_MAX_STEP && 0.8660254037844386 * ldexp(t->q, s + 1) <= allowed)
        s++;
    return s;
}

/* v / 2^s rounded to the nearest integer (halves away from zero) */
static int64_t div_step(int64_t v, int s)
{
    int64_t d = (int64_t)1 << s, h = d / 2;
    return v >= 0 ? (v + h) / d : -((-v + h) / d);
}

static double leg_mm(const tx *t, const int64_t a[3], const int64_t b[3])
{
    double s = 0;
    for (int k = 0; k < 3; k++) {
        double d = (double)(a[k] - b[k]) * t->q;
        s += d * d;
    }
    return sqrt(s);
}

void tx_coarsen_edge(const tx *t, tx_edge *X, double tol_mm)
{
    X->linear = X->step = 0;
    if (!t->o->predicted || X->kind == CM_EDGE_LINE || X->n < 3)
        return;
    int n = X->n;
    double h_min = HUGE_VAL;
    for (int j = 1; j < n; j++)
        h_min = fmin(h_min, leg_mm(t, X->cq[j], X->cq[j - 1]));
    int s = choose_step(t, tol_mm, h_min);
    /* the predictor whose residuals, at this step, cost fewer bits (estimated open loop) */
    double bits[2] = {0, 0};
    for (int linear = 0; linear < 2; linear++)
        for (int j = 1; j < n - 1; j++)
            for (int k = 0; k < 3; k++)
                bits[linear] += enc_sint_bits(div_step(
                    X->cq[j][k] - cm_pred_ctrl(linear, j, n, X->cq[0][k], X->cq[n - 1][k], X->cq[j - 1][k],
                                               j >= 2 ? X->cq[j - 2][k] : 0),
                    s));
    X->linear = bits[1] < bits[0];
    X->step = s;
    for (int j = 1; j < n - 1; j++)
        for (int k = 0; k < 3; k++) {
            int64_t pred = cm_pred_ctrl(X->linear, j, n, X->cq[0][k], X->cq[n - 1][k], X->cq[j - 1][k],
                                        j >= 2 ? X->cq[j - 2][k] : 0);
            X->cq[j][k] = pred + div_step(X->cq[j][k] - pred, s) * ((int64_t)1 << s);
        }
}

void tx_coarsen_surface(const tx *t, tx_surf *S, double tol_mm)
{
    S->quadratic = S->step = 0;
    if (!t->o->predicted)
        return;
    int nu = S->nu, nv = S->nv;
    double h_min = HUGE_VAL;
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            if (i)
                h_min = fmin(h_min, leg_mm(t, S->cq[i * nv + j], S->cq[(i - 1) * nv + j]));
            if (j)
                h_min = fmin(h_min, leg_mm(t, S->cq[i * nv + j], S->cq[i * nv + j - 1]));
        }
    int s = choose_step(t, tol_mm, h_min);
    double bits[2] = {0, 0};
    for (int quadratic = 0; quadratic < 2; quadratic++)
        for (int i = 0; i < nu * nv; i++)
            for (int k = 0; k < 3; k++)
                bits[quadratic] += enc_sint_bits(
                    div_step(S->cq[i][k] - cm_pred_net(quadratic, (const int64_t(*)[3])S->cq, nv, i / nv, i % nv, k), s));
    S->quadratic = bits[1] < bits[0];
    S->step = s;
    for (int i = 0; i < nu * nv; i++)
        for (int k = 0; k < 3; k++) {
            int64_t pred = cm_pred_net(S->quadratic, (const int64_t(*)[3])S->cq, nv, i / nv, i % nv, k);
            S->cq[i][k] = pred + div_step(S->cq[i][k] - pred, s) * ((int64_t)1 << s);
        }
}
