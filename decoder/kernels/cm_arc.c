/* cm_arc.c - a circular arc from its ends and its middle point (see cm_arc.h). */
#include "cm/cm_arc.h"

#include <math.h>

#include "cm/cm_bspline.h"

typedef cm_hpt hp; /* (w x, w y, w z, w) */

static hp hp_mid(hp a, hp b)
{
    hp r = {(a.x + b.x) * 0.5, (a.y + b.y) * 0.5, (a.z + b.z) * 0.5, (a.w + b.w) * 0.5};
    return r;
}

/* the point a stands for, about m (the pieces are built about the chord's midpoint, so that a part
   far from the origin keeps its digits where the weights are small) */
static cm_vec3 hp_point(hp a, cm_vec3 m)
{
    return cm_v3(m.x + a.x / a.w, m.y + a.y / a.w, m.z + a.z / a.w);
}

/* 1 + w below this (1 + w = 2 c^2 / (c^2 + h^2) = 1 + cos of half the arc's angle): the arc is
   within about 0.16 degree of a full circle, whose pieces' weights and points no longer hold their
   digits */
#define ARC_MIN_OPEN 1e-6

/* the arc from p0 through q to p2 as k pieces (1, 2 or 4; 0: as its angle asks) of a rational
   quadratic: 2k + 1 control points and weights into ctrl and w (ctrl[0] is p0, ctrl[2k] is p2, bit
   for bit); the pieces in *pieces */
static cm_err arc_pieces(cm_vec3 p0, cm_vec3 q, cm_vec3 p2, int k, cm_vec3 *ctrl, double *w, int *pieces,
                         cm_status *st)
{
    if (!isfinite(p0.x + p0.y + p0.z + q.x + q.y + q.z + p2.x + p2.y + p2.z))
        return cm_fail(st, CM_E_NONFINITE, "arc");
    cm_vec3 m = cm_v3((p0.x + p2.x) * 0.5, (p0.y + p2.y) * 0.5, (p0.z + p2.z) * 0.5);
    cm_vec3 a0 = cm_sub(p0, m), s = cm_sub(q, m), a2 = cm_sub(p2, m);
    double c2 = cm_norm2(cm_sub(p2, p0)) * 0.25, h2 = cm_norm2(s), den = c2 + h2;
    if (!(c2 > 0))
        return cm_fail(st, CM_E_DEGENERATE, "arc with coincident ends");
    double open = 2.0 * c2 / den; /* 1 + w, without the cancellation */
    if (!(open >= ARC_MIN_OPEN) || !isfinite(den))
        return cm_fail(st, CM_E_DEGENERATE, "arc of a full circle");
    double wm = (c2 - h2) / den;
    if (k == 0)
        k = wm > 0 && 2.0 * wm * wm >= 1.0 ? 1 : (wm >= 0 ? 2 : 4);
    *pieces = k;
    /* the piece [A, B, C] in homogeneous form about m (its middle point (1 + w) s, weight w), cut
       until each turns by at most 90 degrees: the whole when w >= cos 45 deg, two halves when
       w >= 0 (at most a half circle), else four */
    hp piece[4][3];
    piece[0][0] = (hp){a0.x, a0.y, a0.z, 1.0};
    piece[0][1] = (hp){open * s.x, open * s.y, open * s.z, wm};
    piece[0][2] = (hp){a2.x, a2.y, a2.z, 1.0};
    for (int have = 1; have < k; have *= 2)
        for (int i = have - 1; i >= 0; i--) { /* from the last, so that piece i's halves land at 2i, 2i+1 */
            hp a = piece[i][0], b = piece[i][1], c = piece[i][2];
            hp ab = hp_mid(a, b), bc = hp_mid(b, c), abc = hp_mid(ab, bc);
            piece[2 * i][0] = a;
            piece[2 * i][1] = ab;
            piece[2 * i][2] = abc;
            piece[2 * i + 1][0] = abc;
            piece[2 * i + 1][1] = bc;
            piece[2 * i + 1][2] = c;
        }
    ctrl[0] = p0;
    w[0] = 1.0;
    for (int i = 0; i < k; i++) {
        hp a = piece[i][0], b = piece[i][1], c = piece[i][2];
        /* the same piece with weight 1 at both ends (a change of its parameter, not of its shape) */
        ctrl[2 * i + 1] = hp_point(b, m);
        w[2 * i + 1] = b.w / sqrt(a.w * c.w);
        ctrl[2 * i + 2] = i == k - 1 ? p2 : hp_point(c, m);
        w[2 * i + 2] = 1.0;
    }
    return CM_OK;
}

/* the clamped knots of k equal pieces on [0,1], the joints doubled (2k + 4 of them) */
static void piece_knots(double *knots, int k)
{
    int j = 0;
    knots[j++] = 0.0;
    knots[j++] = 0.0;
    knots[j++] = 0.0;
    for (int i = 1; i < k; i++) {
        knots[j++] = (double)i / (double)k;
        knots[j++] = (double)i / (double)k;
    }
    knots[j++] = 1.0;
    knots[j++] = 1.0;
    knots[j] = 1.0;
}

cm_err cm_arc_nurbs(cm_vec3 p0, cm_vec3 q, cm_vec3 p2, cm_vec3 ctrl[CM_ARC_MAX_CTRL], double w[CM_ARC_MAX_CTRL],
                    double knots[CM_ARC_MAX_KNOTS], int *n, cm_status *st)
{
    *n = 0;
    int k;
    cm_err e = arc_pieces(p0, q, p2, 0, ctrl, w, &k, st);
    if (e != CM_OK)
        return e;
    *n = 2 * k + 1;
    piece_knots(knots, k);
    return CM_OK;
}

cm_err cm_circle_nurbs(cm_vec3 p0, cm_vec3 r, cm_vec3 q, cm_vec3 ctrl[CM_ARC_MAX_CTRL], double w[CM_ARC_MAX_CTRL],
                       double knots[CM_ARC_MAX_KNOTS], int *n, cm_status *st)
{
    *n = 0;
    if (!isfinite(p0.x + p0.y + p0.z + q.x + q.y + q.z))
        return cm_fail(st, CM_E_NONFINITE, "circle");
    if (!(cm_norm2(cm_sub(q, p0)) > 0))
        return cm_fail(st, CM_E_DEGENERATE, "circle whose far point is its vertex");
    /* the second half's middle point: r reflected through the centre (p0 + q) / 2 */
    cm_vec3 r2 = cm_sub(cm_add(p0, q), r);
    int k;
    cm_err e = arc_pieces(p0, r, q, 2, ctrl, w, &k, st);
    if (e == CM_OK)
        e = arc_pieces(q, r2, p0, 2, ctrl + 4, w + 4, &k, st); /* ctrl[4] is q again, w[4] 1 */
    if (e != CM_OK)
        return e;
    *n = 9;
    piece_knots(knots, 4);
    return CM_OK;
}

cm_err cm_arc_record(int closed, cm_vec3 p0, cm_vec3 mid, cm_vec3 end, cm_vec3 ctrl[CM_ARC_MAX_CTRL],
                     double w[CM_ARC_MAX_CTRL], double knots[CM_ARC_MAX_KNOTS], int *n, cm_status *st)
{
    return closed ? cm_circle_nurbs(p0, mid, end, ctrl, w, knots, n, st) : cm_arc_nurbs(p0, mid, end, ctrl, w, knots, n, st);
}
