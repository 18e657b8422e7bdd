/*
 * cm_geom.h - lines and planes (K10), the face frame (K11) and the 2D
 * point-in-polygon test (K12).
 */
#ifndef CM_GEOM_H
#define CM_GEOM_H

#include "cm/cm_const.h"
#include "cm/cm_error.h"
#include "cm/cm_vec.h"

/**
 * K10 closest points of the lines p + lam d and q + mu e.
 * @return 0 if the lines are parallel (|d x e|^2 < 1e-12 |d|^2 |e|^2;
 *         lam, mu untouched), else 1
 */
int cm_lines_closest(cm_vec3 p, cm_vec3 d, cm_vec3 q, cm_vec3 e, double *lam, double *mu);

/**
 * K10 ray p + lam d against the plane {x : m.x = c} (m unit).
 * @return 0 if the ray is within 5 deg of the plane (|d.m| < sin 5 deg |d|),
 *         else 1 with *lam set
 */
int cm_ray_plane(cm_vec3 p, cm_vec3 d, cm_vec3 m, double c, double *lam);

/**
 * How far a smooth curve between p0 and p1, whose unit normals there are n0 and n1 (the surface's,
 * the curve in its tangent planes), strays from its chord where the middle cannot tell: the peak
 * of the S-shaped part of the cubic through the ends with the ends' slopes, which is zero at the
 * middle and largest at 0.21 and 0.79 of the chord.  An arc (symmetric) gives 0; y = A sin(2 pi x
 * / L) about 0.6 A.  Only + - * and fabs: the same bits everywhere.
 */
double cm_chord_s_part(cm_vec3 p0, cm_vec3 n0, cm_vec3 p1, cm_vec3 n1);

/**
 * The same cubic's C-shaped (symmetric) part at the middle of the chord: |(p1 - p0).(n0 - n1)| / 8,
 * the sagitta the ends' normals imply.  An arc of radius R and angle a: R a^2 / 8 to leading order
 * (its true sagitta R (1 - cos a/2)); a line of a cylinder or of any ruled surface: 0.  Only + - *
 * and fabs: the same bits everywhere.
 */
double cm_chord_c_part(cm_vec3 p0, cm_vec3 n0, cm_vec3 p1, cm_vec3 n1);

/** A right-handed orthonormal face frame: origin and axes, ez = face normal. */
typedef struct cm_frame {
    cm_vec3 o, ex, ey, ez;
} cm_frame;

/**
 * K11 face frame (after OCCT GeomPlate_BuildAveragePlane): normal by Newell
 * over the outer-loop samples, origin the mean of all samples, ex the major
 * inertia axis in the plane, signed so that (outer[0]-o).ex <= 0.
 * Deviation from spec K11, which sums p_k x p_(k+1) of absolute positions:
 * the sum here is taken of (p_k - o), mathematically identical for a
 * closed loop but without losing digits on parts far from the origin.
 * @param outer, n_outer  outer-loop samples in loop order (cyclic)
 * @param all, n_all      samples of all loops (outer included)
 * @param eps_len         model length below which a vector is "zero"
 * @return CM_E_DEGENERATE if the Newell normal is shorter than eps_len^2
 */
CM_NODISCARD cm_err cm_face_frame(const cm_vec3 *outer, int n_outer, const cm_vec3 *all, int n_all, double eps_len,
                                  cm_frame *f, cm_status *st);

/** Local coordinates L(p) = ((p-o).ex, (p-o).ey, (p-o).ez). */
cm_vec3 cm_frame_local(const cm_frame *f, cm_vec3 p);

/** World point of local coordinates (x, y, z). */
cm_vec3 cm_frame_world(const cm_frame *f, cm_vec3 l);

/**
 * K12 point in a closed 2D polygon (crossing number, half-open rule
 * (y_a > y) != (y_b > y)); points exactly on an edge count as inside.
 * @return 1 inside or on the boundary, 0 outside
 */
int cm_point_in_polygon(const cm_vec2 *poly, int n, cm_vec2 p);

#endif /* CM_GEOM_H */
