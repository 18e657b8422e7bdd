/*
 * cm_predict.h - how format 3 predicts a curve's numbers from the ones sent before them
 * (docs/FORMAT.md, EDGE and "Knots"), one definition for the writer and the reader.
 *
 * Format 2 sent each control point as its difference from the one before.  On a smooth curve the
 * differences themselves change slowly, so format 3 lets each curve choose (one bit) between that
 * and a straight-line prediction: the first interior point on the chord from v0 towards v1, the
 * others continuing the last step.  A circle's coarse control polygon turns sharply at every point,
 * where the previous point is the better guess; dense B-spline polygons, where the line wins, are
 * most of the bytes (measured on the corpus: 204 KB of control points become 161 KB).
 * Weights repeat with period two on conics (1, w, 1, w, ...: every IGES circle), so a weight is
 * predicted by the one two places before it.  Knot gaps are zero (a repeated knot) or, on the
 * vectors exporters write, mostly equal to the last gap that was not zero.
 * All integer arithmetic on grid numbers below 2^41: exact, the same on every machine.
 */
#ifndef CM_PREDICT_H
#define CM_PREDICT_H

#include <stdint.h>

/* control point j (1 <= j <= n - 2) of a curve of n points, coordinate by coordinate: first and
   last are its vertices' grid numbers, prev and prev2 points j - 1 and j - 2 (prev2 unused for
   j = 1); `linear` is the curve's predictor bit */
static inline int64_t cm_pred_ctrl(int linear, int j, int n, int64_t first, int64_t last, int64_t prev, int64_t prev2)
{
    if (!linear)
        return prev;
    if (j == 1)
        return first + (last - first) / (int64_t)(n - 1);
    return 2 * prev - prev2;
}

/* format 4.4: an arc's middle point, coordinate by coordinate, from its ends: the chord's midpoint
   (the integer quotient rounded towards zero, as C's /), which leaves the arc's sagitta to send */
static inline int64_t cm_pred_arc_mid(int64_t first, int64_t last)
{
    return first + (last - first) / 2;
}

/* format 4.4: the points of a ruled surface's two arcs (docs/FORMAT.md, SURF, "Ruled"), point j of
   row `row`, coordinate by coordinate from those before it, pt[row][j]: the first row's first point
   absolute, its second from its first, its third from the midpoint of those two; the second row's
   each from the first row's, moved as its first point moved */
static inline int64_t cm_pred_ruled(const int64_t pt[2][3][3], int row, int j, int k)
{
    if (row == 0)
        return j == 0 ? 0 : (j == 1 ? pt[0][0][k] : cm_pred_arc_mid(pt[0][0][k], pt[0][1][k]));
    return j == 0 ? pt[0][0][k] : pt[0][j][k] + (pt[1][0][k] - pt[0][0][k]);
}

/* weight j (j >= 1; weight 0 is one, w_one): the weight two places before it, or for j = 1 the first */
static inline int64_t cm_pred_weight(int j, int64_t prev, int64_t prev2)
{
    return j >= 2 ? prev2 : prev;
}

/* a kept surface's control point (i, j), coordinate k, from the points before it in its net q
   (row-major, nv per row): the value for which the mixed difference of orders (min(i, o), min(j, o))
   vanishes, o = 1 the parallelogram P[i-1][j] + P[i][j-1] - P[i-1][j-1] of format 2 (and of a
   format 3 surface whose bit says so), o = 2 for a net whose rows and columns bend smoothly
   (format 3: its bit; measured on the corpus's kept surfaces, a quarter fewer bits on a ship hull) */
static inline int64_t cm_pred_net(int quadratic, const int64_t (*q)[3], int nv, int i, int j, int k)
{
    static const int64_t diff[3][3] = {{1, 0, 0}, {1, -1, 0}, {1, -2, 1}};
    int o = quadratic ? 2 : 1, ou = i < o ? i : o, ov = j < o ? j : o;
    int64_t pred = 0;
    for (int x = 0; x <= ou; x++)
        for (int y = 0; y <= ov; y++)
            if (x || y)
                pred -= diff[ou][x] * diff[ov][y] * q[(i - x) * nv + (j - y)][k];
    return pred;
}

/*
 * Format 4: the values a vertex coordinate took lately, per axis, most recent first.  CAD parts
 * repeat their coordinates (a box has two per axis; a machined part a few dozen planes): a value met
 * before is sent as its place in this list instead of a difference.  A value used or newly sent
 * moves to the front; the list keeps CM_VCACHE of them.
 */
#define CM_VCACHE 64
typedef struct cm_vcache {
    int64_t v[CM_VCACHE];
    int n;
} cm_vcache;

/* the place of v in the list, or -1 */
static inline int cm_vcache_find(const cm_vcache *c, int64_t v)
{
    for (int i = 0; i < c->n; i++)
        if (c->v[i] == v)
            return i;
    return -1;
}

/* entry i (< n) moved to the front; a new value (i = -1) put there, the last dropped if full */
static inline void cm_vcache_front(cm_vcache *c, int i, int64_t v)
{
    if (i < 0) {
        i = c->n < CM_VCACHE ? c->n++ : CM_VCACHE - 1;
    }
    for (; i > 0; i--)
        c->v[i] = c->v[i - 1];
    c->v[0] = v;
}

#endif /* CM_PREDICT_H */
