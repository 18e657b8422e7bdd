/*
 * cm_arc.h - a circular arc from its ends and its middle point, as the rational quadratic NURBS the
 * rest of the decoder evaluates (format 4.4's arc edges, docs/FORMAT.md, EDGE).
 *
 * CAD models are full of circles: holes, fillets' ends, bosses.  Sent as NURBS, an arc costs its
 * degree, count, knots, its middle control points and their weights; but an arc whose ends are
 * known (the edge's vertices) is fixed by one point more, its middle.  Given that point q, the
 * conic through p0, q and p2 with q at t = 1/2 and the weight w = (c^2 - h^2) / (c^2 + h^2) in the
 * middle (c half the chord, h the distance of q from the chord's midpoint m: w is the cosine of
 * half the arc's angle) is that circle when q lies as far from p0 as from p2, and with q on the
 * coordinate grid within a step of it otherwise.  In homogeneous form about m its middle point is
 * ((1 + w)(q - m), w), finite for every arc short of a full circle (w < 0 beyond a half circle), so
 * it is cut in halves by de Casteljau's rule until every piece turns by at most 90 degrees (1, 2 or
 * 4 pieces, as The NURBS Book's A7.1), each piece then written with weight 1 at its ends.  Only
 * + - * / and one square root per piece: the same bits on every machine.  The arithmetic, in its
 * order, is the format's (docs/FORMAT.md, "Arcs"); the kernel vectors (make check-cross) hold it.
 */
#ifndef CM_ARC_H
#define CM_ARC_H

#include "cm/cm_error.h"
#include "cm/cm_vec.h"

#define CM_ARC_MAX_CTRL 9   /* four pieces */
#define CM_ARC_MAX_KNOTS 12 /* CM_ARC_MAX_CTRL + 3 */

/**
 * The arc from p0 through q to p2 as a clamped rational quadratic on [0,1]: *n (3, 5 or 9) control
 * points in ctrl (ctrl[0] is p0 and ctrl[*n - 1] is p2, bit for bit), their weights in w (1 at
 * the ends of every piece), *n + 3 knots (the pieces equally long in parameter).
 * @return CM_OK; CM_E_DEGENERATE when p0 == p2 or the arc is within about 0.16 degree of a full
 *         circle (1 + w < 1e-6); CM_E_NONFINITE when a point is not finite.
 */
CM_NODISCARD cm_err cm_arc_nurbs(cm_vec3 p0, cm_vec3 q, cm_vec3 p2, cm_vec3 ctrl[CM_ARC_MAX_CTRL],
                                 double w[CM_ARC_MAX_CTRL], double knots[CM_ARC_MAX_KNOTS], int *n, cm_status *st);

/**
 * A full circle (a closed edge, from p0 back to p0): through p0, r and q in that order, q the point
 * across from p0 and r the one halfway to it; the halves p0-r-q and q-r'-p0 (r' = p0 + q - r, r
 * reflected through the centre) are each the arc above in two pieces: 9 control points (ctrl[0] and
 * ctrl[8] are p0, bit for bit), knots 0 0 0 1/4 1/4 1/2 1/2 3/4 3/4 1 1 1.
 * @return CM_OK; CM_E_DEGENERATE when q == p0 or r makes a half a full circle; CM_E_NONFINITE.
 */
CM_NODISCARD cm_err cm_circle_nurbs(cm_vec3 p0, cm_vec3 r, cm_vec3 q, cm_vec3 ctrl[CM_ARC_MAX_CTRL],
                                    double w[CM_ARC_MAX_CTRL], double knots[CM_ARC_MAX_KNOTS], int *n, cm_status *st);

/**
 * The arc a format 4.4 record names: from p0 through mid to end (cm_arc_nurbs), or when `closed`
 * the full circle from p0 through mid and round by its far point `end` (cm_circle_nurbs).
 */
CM_NODISCARD cm_err cm_arc_record(int closed, cm_vec3 p0, cm_vec3 mid, cm_vec3 end, cm_vec3 ctrl[CM_ARC_MAX_CTRL],
                                  double w[CM_ARC_MAX_CTRL], double knots[CM_ARC_MAX_KNOTS], int *n, cm_status *st);

#endif /* CM_ARC_H */
