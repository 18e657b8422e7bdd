/*
 * cm_cubic_convert.h - cubic edge conversion (spec K7).
 *
 * The Gregory-family methods need every boundary edge as one cubic Bézier.
 * A polynomial single-span curve of degree <= 3 converts exactly; anything
 * else (rational arcs, multi-span splines) is approximated with fixed end
 * points and end tangents, free handle lengths fitted by least squares
 * with Hoschek parameter correction.  From format 4.14 a one-span conic
 * (an arc) takes a closed form instead (cm_cubic_from_conic, cm_edge_cubic).
 */
#ifndef CM_CUBIC_CONVERT_H
#define CM_CUBIC_CONVERT_H

#include "cm/cm_bezier.h"
#include "cm/cm_bspline.h"
#include "cm/cm_error.h"

#define CM_K7_SAMPLES 33 /* spec K7: Q_k = C(t0 + k(t1-t0)/32) */
#define CM_K7_ITERS 6    /* spec K7: 6 solves, Newton parameter correction between */

/**
 * Convert the part [t0,t1] of curve c into a cubic (K7).
 * @param[out] out    the cubic, in the direction t0 -> t1
 * @param[out] delta  max distance of the 33 samples of c to the cubic (K9);
 *                    0 for an exact conversion.  May be NULL.
 * @param[out] exact  1 if the conversion is exact (case 1), else 0; may be NULL
 * @return CM_E_DEGENERATE if the curve has zero length on [t0,t1],
 *         errors of cm_curve_eval
 */
CM_NODISCARD cm_err cm_cubic_convert(const cm_curve *c, double t0, double t1, cm_cubic *out, double *delta,
                                     int *exact, cm_status *st);

/**
 * The cubic of a one-span rational quadratic (a conic: every arc of format 4.4 up to a half circle)
 * over its whole span, in closed form: its ends, its end tangents and its middle point (format 4.14).
 * @return 1 and *out, or 0 (out untouched) when c is no such curve or a weight is not positive
 */
int cm_cubic_from_conic(const cm_curve *c, cm_cubic *out);

/**
 * An edge's cubic (its curve over [0,1]) as a GREGORY side takes it: with `conic` (cm_model's
 * conic_cubic, format 4.14 on) a one-span conic's by cm_cubic_from_conic, any other curve's by K7
 * (cm_cubic_convert).  The decoder and the encoder's GREGORY both take their sides from here.
 */
CM_NODISCARD cm_err cm_edge_cubic(const cm_curve *c, int conic, cm_cubic *out, cm_status *st);

/**
 * K7's measure of an edge's cubic (the encoder's test of a GREGORY side): *delta, the largest
 * distance from cu of the 33 samples of c over [0,1] (the same as cm_cubic_convert's on its own fit).
 */
CM_NODISCARD cm_err cm_edge_cubic_delta(const cm_curve *c, const cm_cubic *cu, double *delta, cm_status *st);

#endif /* CM_CUBIC_CONVERT_H */
