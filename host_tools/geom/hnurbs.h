/*
 * hnurbs.h - owned (heap-allocated) NURBS curves and surfaces for the
 * workstation tools, and the exact constructions that turn every IGES
 * curve and surface kind into one.
 *
 * Host code only: may allocate, never runs on the terminal.  Evaluation
 * goes through the shared kernels (decoder/kernels) via the cm_curve /
 * cm_surf views, so the workstation and the terminal evaluate a NURBS with
 * the same code.
 *
 * Conventions are those of cm_bspline.h: `p`/`q` degrees, `n`/`nu`/`nv`
 * control point counts, full knot vectors (n+p+1 values), surfaces
 * row-major in u (ctrl[i*nv + j], i along u), `w == NULL` = polynomial.
 * Every construction is exact (rational where needed): a circle is a
 * circle, not an approximation.
 *
 * Ownership: a zero-initialised struct is empty; builders write into an
 * empty struct (or one that may be freed first: they call *_free on `out`
 * before writing).  *_free releases everything and leaves an empty struct.
 * Errors: CM_E_ARG for invalid arguments (e.g. zero radius, angles out of
 * range), CM_E_DEGENERATE for degenerate geometry, CM_E_NOMEM on allocation
 * failure (reported as "out of memory" by the callers), CM_E_KNOTS for bad
 * knot vectors.  Errors are also recorded in `st` (may be NULL).  On error a
 * builder leaves `out` empty.
 */
#ifndef HNURBS_H
#define HNURBS_H

#include "cm/cm_bspline.h"
#include "cm/cm_error.h"
#include "cm/cm_vec.h"

typedef struct hcurve {
    int p;          /* degree >= 1 */
    int n;          /* control points >= p+1 */
    double *knots;  /* n + p + 1 */
    cm_vec3 *ctrl;  /* n */
    double *w;      /* n, or NULL (polynomial) */
} hcurve;

typedef struct hsurf {
    int p, q;       /* degrees in u, v */
    int nu, nv;     /* control points per direction */
    double *U, *V;  /* nu+p+1, nv+q+1 */
    cm_vec3 *ctrl;  /* nu*nv, ctrl[i*nv + j] */
    double *w;      /* nu*nv, or NULL */
} hsurf;

/* An affine map x -> R x + t (IGES 124 transformation matrix). */
typedef struct haffine {
    double R[3][3];
    cm_vec3 t;
} haffine;

/* ---- storage ---- */
CM_NODISCARD cm_err hcurve_alloc(hcurve *c, int p, int n, int rational, cm_status *st);
CM_NODISCARD cm_err hsurf_alloc(hsurf *s, int p, int q, int nu, int nv, int rational, cm_status *st);
void hcurve_free(hcurve *c);
void hsurf_free(hsurf *s);
CM_NODISCARD cm_err hcurve_copy(const hcurve *c, hcurve *out, cm_status *st);
CM_NODISCARD cm_err hsurf_copy(const hsurf *s, hsurf *out, cm_status *st);

/** Views for the shared kernels (cm_curve_eval, cm_surf_eval, projections); they point into c/s. */
cm_curve hcurve_view(const hcurve *c);
cm_surf hsurf_view(const hsurf *s);
void hcurve_domain(const hcurve *c, double *t0, double *t1);
void hsurf_domain(const hsurf *s, double *u0, double *u1, double *v0, double *v1);

/* ---- curve constructions (all exact) ---- */

/** Segment a -> b, degree 1, parameter [0,1]. */
CM_NODISCARD cm_err hcurve_line(cm_vec3 a, cm_vec3 b, hcurve *out, cm_status *st);

/** Polyline through n >= 2 points, degree 1, knots 0,0,1,2,...,n-1,n-1 (parameter = point index). */
CM_NODISCARD cm_err hcurve_polyline(const cm_vec3 *pts, int n, hcurve *out, cm_status *st);

/**
 * Elliptical arc c + a cos(t) X + b sin(t) Y for t in [t0, t1] (radians,
 * t0 < t1 <= t0 + 2 pi; X, Y orthonormal), as a rational quadratic with at
 * most 90 degrees per span.  A circle is a = b.  The parameter domain of the
 * result is [t0, t1] with the span boundaries at equal angle steps (the
 * parameter equals the angle at the knots, not in between).
 */
CM_NODISCARD cm_err hcurve_ellipse_arc(cm_vec3 c, cm_vec3 X, cm_vec3 Y, double a, double b, double t0, double t1,
                                       hcurve *out, cm_status *st);

/**
 * One conic arc from P0 to P2 with tangent lines meeting at P1, as a single
 * rational quadratic span with middle weight w1 (w1 < 1 ellipse, = 1
 * parabola, > 1 hyperbola).  Parameter [0,1].
 */
CM_NODISCARD cm_err hcurve_conic_span(cm_vec3 P0, cm_vec3 P1, cm_vec3 P2, double w1, hcurve *out, cm_status *st);

/**
 * Piecewise cubic polynomial (IGES 112 parametric spline): nseg segments,
 * breakpoints T[0..nseg], segment i is
 *   C(u) = A_i + B_i s + C_i s^2 + D_i s^3,  s = u - T[i], u in [T[i], T[i+1]]
 * with coef[i*4 + 0..3] = A_i, B_i, C_i, D_i (vectors).  Result: a cubic
 * B-spline with knots T (each interior breakpoint of multiplicity 3, so it
 * is exact even where the input is only C0), domain [T[0], T[nseg]].
 */
CM_NODISCARD cm_err hcurve_from_cubic_segments(const double *T, const cm_vec3 *coef, int nseg, hcurve *out,
                                               cm_status *st);

/** Apply x -> R x + t to the control points (exact for affine maps, rational curves too). */
void hcurve_transform(hcurve *c, const haffine *m);

/** Reverse the direction; the domain [t0,t1] maps to [t0,t1] (u -> t0 + t1 - u). */
void hcurve_reverse(hcurve *c);

/** Map the domain linearly onto [a, b] (a < b) without changing the shape. */
void hcurve_reparam(hcurve *c, double a, double b);

/**
 * The piece [t0, t1] (inside the domain, t0 < t1) as its own clamped
 * curve, by knot insertion to full multiplicity (exact).  Domain [t0, t1].
 * Also works for unclamped (periodic) input knot vectors.
 */
CM_NODISCARD cm_err hcurve_subrange(const hcurve *c, double t0, double t1, hcurve *out, cm_status *st);

/** Raise the degree to new_p >= p (exact; Bezier decomposition, elevation, reassembly). */
CM_NODISCARD cm_err hcurve_elevate(const hcurve *c, int new_p, hcurve *out, cm_status *st);

/**
 * Make two curves compatible for a tensor-product construction: both
 * clamped, reparametrised to [0,1], same degree (the higher), same knot
 * vector (the union, by knot insertion), both rational if either is.
 * The shapes do not change.
 */
CM_NODISCARD cm_err hcurve_make_compatible(hcurve *a, hcurve *b, cm_status *st);

/** A copy made clamped (knots p+1-fold at both ends of the domain), same domain. */
CM_NODISCARD cm_err hcurve_clamp(const hcurve *c, hcurve *out, cm_status *st);

/* ---- surface constructions (all exact) ---- */

/** Plane patch S(u,v) = o + u X + v Y on [u0,u1] x [v0,v1], bilinear. */
CM_NODISCARD cm_err hsurf_plane(cm_vec3 o, cm_vec3 X, cm_vec3 Y, double u0, double u1, double v0, double v1,
                                hsurf *out, cm_status *st);

/**
 * Ruled surface between curves a (v = 0) and b (v = 1), joining points of
 * equal relative parameter (IGES 118 form 1); u in [0,1] after
 * make_compatible, v in [0,1], degree 1 in v.
 */
CM_NODISCARD cm_err hsurf_ruled(const hcurve *a, const hcurve *b, hsurf *out, cm_status *st);

/**
 * Surface of revolution (IGES 120): generatrix g rotated about the axis
 * through `axis_pt` with direction `axis_dir` (need not be unit), by angles
 * [a0, a1] (radians, a0 < a1 <= a0 + 2 pi, right-handed about axis_dir).
 * u = generatrix parameter (g's domain), v = angle parameter on [a0, a1]
 * (rational quadratic in v, <= 90 degrees per span, as hcurve_ellipse_arc).
 */
CM_NODISCARD cm_err hsurf_revolve(const hcurve *g, cm_vec3 axis_pt, cm_vec3 axis_dir, double a0, double a1,
                                  hsurf *out, cm_status *st);

/** Tabulated cylinder (IGES 122): S(u,v) = c(u) + v d, u in c's domain, v in [0,1]. */
CM_NODISCARD cm_err hsurf_extrude(const hcurve *c, cm_vec3 d, hsurf *out, cm_status *st);

/**
 * Analytic surfaces (IGES 190-198) on a parameter rectangle, in the frame
 * (o; X, Y, Z) with X, Y, Z orthonormal right-handed:
 *   cylinder  o + r cos(u) X + r sin(u) Y + v Z
 *   cone      o + (r + v tan(semi)) (cos(u) X + sin(u) Y) + v Z
 *   sphere    o + r cos(v) (cos(u) X + sin(u) Y) + r sin(v) Z,  v in [-pi/2, pi/2]
 *   torus     o + (R + r cos(v)) (cos(u) X + sin(u) Y) + r sin(v) Z
 * u (and v for sphere/torus) are angles in radians with u1 - u0 <= 2 pi;
 * the result's parameter equals the angle at knots (as for arcs) and the
 * linear parameter exactly.
 */
CM_NODISCARD cm_err hsurf_cylinder(cm_vec3 o, cm_vec3 X, cm_vec3 Y, cm_vec3 Z, double r, double u0, double u1,
                                   double v0, double v1, hsurf *out, cm_status *st);
CM_NODISCARD cm_err hsurf_cone(cm_vec3 o, cm_vec3 X, cm_vec3 Y, cm_vec3 Z, double r, double semi_angle, double u0,
                               double u1, double v0, double v1, hsurf *out, cm_status *st);
CM_NODISCARD cm_err hsurf_sphere(cm_vec3 o, cm_vec3 X, cm_vec3 Y, cm_vec3 Z, double r, double u0, double u1, double v0,
                                 double v1, hsurf *out, cm_status *st);
CM_NODISCARD cm_err hsurf_torus(cm_vec3 o, cm_vec3 X, cm_vec3 Y, cm_vec3 Z, double R, double r, double u0, double u1,
                                double v0, double v1, hsurf *out, cm_status *st);

/** Apply x -> R x + t to the control net. */
void hsurf_transform(hsurf *s, const haffine *m);

/**
 * The part [u0,u1] x [v0,v1] of s as its own surface, clamped on that
 * rectangle (knot insertion column by column, then row by row; exact).
 * With the whole domain it clamps an unclamped surface.
 */
CM_NODISCARD cm_err hsurf_subrange(const hsurf *s, double u0, double u1, double v0, double v1, hsurf *out,
                                   cm_status *st);

/** The iso-curve at u = u0 (a curve in v) or v = v0 (a curve in u), exact. */
CM_NODISCARD cm_err hsurf_iso_u(const hsurf *s, double u, hcurve *out, cm_status *st);
CM_NODISCARD cm_err hsurf_iso_v(const hsurf *s, double v, hcurve *out, cm_status *st);

/**
 * 1 if the surface closes on itself in u (S(u0, v) == S(u1, v) within tol
 * at 9 values of v), else 0; same for v.
 */
int hsurf_closed_u(const hsurf *s, double tol);
int hsurf_closed_v(const hsurf *s, double tol);

/* ---- lists ---- */
/** A growable list of owned curves (the pieces of a composite curve). */
typedef struct hcurve_list {
    hcurve *c;
    int n, cap;
} hcurve_list;

void hcurve_list_free(hcurve_list *l);
/** Move `c` into the list (c is left empty). */
CM_NODISCARD cm_err hcurve_list_push(hcurve_list *l, hcurve *c, cm_status *st);

/* ---- testing ---- */
/**
 * Fault injection for the tests: after `n` more successful allocations by
 * this module (in the calling thread) the next one fails, once, so the
 * function that asked returns CM_E_NOMEM; n < 0 disarms.
 */
void hnurbs_fail_alloc_after(int n);
/** 1 while an armed failure has not happened yet (the work done made fewer allocations). */
int hnurbs_fail_alloc_pending(void);

/* ---- affine helpers ---- */
haffine haffine_identity(void);
/** a o b: first b, then a. */
haffine haffine_compose(const haffine *a, const haffine *b);
cm_vec3 haffine_apply(const haffine *m, cm_vec3 x);
/** R x (no translation): for directions. */
cm_vec3 haffine_apply_dir(const haffine *m, cm_vec3 x);
/** m inverted into *out; 0 (out untouched) when R is singular (|det| <= 1e-12). */
int haffine_invert(const haffine *m, haffine *out);
/** m as rows {R11, R12, R13, t1, R21, ..., t3} (cm_placement.m's layout). */
void haffine_rows(const haffine *m, double rows[12]);

#endif /* HNURBS_H */
