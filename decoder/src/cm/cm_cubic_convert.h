/*
 * cm_cubic_convert.h - cubic edge conversion (spec K7).
 *
 * The Gregory-family methods need every boundary edge as one cubic Bézier.
 * A polynomial single-span curve of degree <= 3 converts exactly; anything
 * else (rational arcs, multi-span splines) is approximated with fixed end
 * points and end tangents, free handle lengths fitted by least squares
 * with Hoschek parameter correction.
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

#endif /* CM_CUBIC_CONVERT_H */
