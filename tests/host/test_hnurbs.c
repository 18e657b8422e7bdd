/*
 * test_hnurbs.c - owned NURBS and the exact constructions of hnurbs.h.
 *
 * Every construction is compared with its closed form at many parameters.
 * Where a rational arc's parameter is not the angle (between knots), the
 * angle is read off a unit arc built for the same range (arc_angle) -- the
 * arc itself is checked first: on the circle, monotone, equal to the angle
 * at every knot.  Tolerances are relative to the size of the geometry:
 * REL = 1e-13 (the errors measured are about 1e-15) unless a comment says
 * otherwise.
 */
#include "../unit/test_util.h"

#include <limits.h>
#include <stdlib.h>

#include "cm/cm_bspline.h"
#include "geom/hnurbs.h"

#define REL 1e-13
#define DEG (M_PI / 180.0)

/* an orthonormal right-handed frame tilted against the coordinate axes */
static const cm_vec3 FX = {1.0 / 3, 2.0 / 3, 2.0 / 3};
static const cm_vec3 FY = {2.0 / 3, 1.0 / 3, -2.0 / 3};
static const cm_vec3 FZ = {-2.0 / 3, 2.0 / 3, -1.0 / 3};

/* ---- helpers ---- */

static cm_vec3 cpt(const hcurve *c, double u)
{
    cm_curve v = hcurve_view(c);
    cm_vec3 d[CM_MAX_DERS + 1];
    assert_ok(cm_curve_eval(&v, u, 0, d, NULL));
    return d[0];
}

static cm_vec3 cder(const hcurve *c, double u)
{
    cm_curve v = hcurve_view(c);
    cm_vec3 d[CM_MAX_DERS + 1];
    assert_ok(cm_curve_eval(&v, u, 1, d, NULL));
    return d[1];
}

static cm_vec3 spt(const hsurf *s, double u, double v)
{
    cm_surf sv = hsurf_view(s);
    cm_vec3 S[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
    assert_ok(cm_surf_eval(&sv, u, v, 0, S, NULL));
    return S[0][0];
}

static double t0_of(const hcurve *c)
{
    double a, b;
    hcurve_domain(c, &a, &b);
    return a;
}

static double t1_of(const hcurve *c)
{
    double a, b;
    hcurve_domain(c, &a, &b);
    return b;
}

static cm_vec3 ellipse_pt(cm_vec3 c, cm_vec3 X, cm_vec3 Y, double a, double b, double t)
{
    return cm_add(c, cm_add(cm_scale(X, a * cos(t)), cm_scale(Y, b * sin(t))));
}

/* implicit ellipse equation (x/a)^2 + (y/b)^2 - 1 in the frame (c; X, Y), X, Y orthonormal */
static double ellipse_residual(cm_vec3 P, cm_vec3 c, cm_vec3 X, cm_vec3 Y, double a, double b)
{
    cm_vec3 d = cm_sub(P, c);
    double x = cm_dot(d, X) / a, y = cm_dot(d, Y) / b;
    return x * x + y * y - 1.0;
}

/* the angle of the unit arc built for [t0, t1] at parameter t (equal to t at the knots) */
static double arc_angle(double t0, double t1, double t)
{
    hcurve c = {0};
    assert_ok(hcurve_ellipse_arc(cm_v3(0, 0, 0), cm_v3(1, 0, 0), cm_v3(0, 1, 0), 1, 1, t0, t1, &c, NULL));
    cm_vec3 P = cpt(&c, t);
    hcurve_free(&c);
    /* rotate P by -t: the remaining angle is small */
    return t + atan2(-P.x * sin(t) + P.y * cos(t), P.x * cos(t) + P.y * sin(t));
}

/* p rotated by theta about the axis through a with unit direction k (Rodrigues) */
static cm_vec3 rodrigues(cm_vec3 p, cm_vec3 a, cm_vec3 k, double theta)
{
    cm_vec3 v = cm_sub(p, a);
    double c = cos(theta), s = sin(theta);
    cm_vec3 r = cm_add(cm_scale(v, c), cm_scale(cm_cross(k, v), s));
    r = cm_add(r, cm_scale(k, cm_dot(k, v) * (1.0 - c)));
    return cm_add(a, r);
}

/* c1 on [a1,b1] and c2 on [a2,b2] (linearly related parameters) trace the same points */
static void assert_same_curve(const hcurve *c1, double a1, double b1, const hcurve *c2, double a2, double b2,
                              int samples, double tol)
{
    for (int k = 0; k <= samples; k++) {
        double s = (double)k / samples;
        double u1 = k == samples ? b1 : a1 + (b1 - a1) * s, u2 = k == samples ? b2 : a2 + (b2 - a2) * s;
        assert_vec_near(cpt(c1, u1), cpt(c2, u2), tol);
    }
}

/* multiplicity of the value knots[i] in the whole vector */
static int mult_at(const hcurve *c, double u)
{
    int m = 0;
    for (int i = 0; i < c->n + c->p + 1; i++)
        m += c->knots[i] == u;
    return m;
}

/* knots within tol of u */
static int mult_near(const hcurve *c, double u, double tol)
{
    int m = 0;
    for (int i = 0; i < c->n + c->p + 1; i++)
        m += fabs(c->knots[i] - u) <= tol;
    return m;
}

static int is_clamped(const hcurve *c)
{
    for (int i = 0; i < c->p; i++)
        if (c->knots[i] != c->knots[c->p] || c->knots[c->n + 1 + i] != c->knots[c->n])
            return 0;
    return 1;
}

/*
 * A random B-spline of degree p with n control points: clamped on [0,1]
 * with a repeated interior knot (mult) when `clamped`, else the uniform
 * unclamped vector 0,1,...,n+p (domain [p, n]); weights in [0.5, 2] when
 * `rational`.
 */
static void random_curve(hcurve *c, int p, int n, int rational, int clamped, int mult, uint32_t seed)
{
    uint32_t s = seed;
    assert_ok(hcurve_alloc(c, p, n, rational, NULL));
    int m = n + p + 1;
    if (clamped) {
        int ni = n - p - 1; /* interior knots */
        for (int i = 0; i <= p; i++) {
            c->knots[i] = 0.0;
            c->knots[m - 1 - i] = 1.0;
        }
        double u = 0.0;
        for (int i = 0; i < ni; i++) {
            if (!(i > 0 && i < mult))
                u += (0.5 + test_rand(&s)) / (ni + 1.5);
            c->knots[p + 1 + i] = u;
        }
        assert_true(u < 1.0);
    } else {
        for (int i = 0; i < m; i++)
            c->knots[i] = (double)i;
    }
    for (int i = 0; i < n; i++) {
        c->ctrl[i] = test_rand_vec(&s, 5.0);
        if (rational)
            c->w[i] = 0.5 + 1.5 * test_rand(&s);
    }
    cm_curve v = hcurve_view(c);
    assert_ok(cm_curve_check(&v, NULL));
}

/* ---- storage ---- */

static void test_alloc_copy_free(void **state)
{
    (void)state;
    hcurve c = {0}, d = {0};
    assert_ok(hcurve_alloc(&c, 3, 5, 1, NULL));
    assert_int_equal(c.p, 3);
    assert_int_equal(c.n, 5);
    for (int i = 0; i < 9; i++)
        assert_true(c.knots[i] == 0.0);
    for (int i = 0; i < 5; i++)
        assert_true(c.w[i] == 1.0 && c.ctrl[i].x == 0.0);
    for (int i = 0; i < 9; i++)
        c.knots[i] = i < 4 ? 0.0 : i < 5 ? 0.5 : 2.0;
    for (int i = 0; i < 5; i++) {
        c.ctrl[i] = cm_v3(i, 2 * i, -i);
        c.w[i] = 1.0 + i;
    }
    cm_curve v = hcurve_view(&c);
    assert_true(v.p == 3 && v.n_ctrl == 5 && v.knots == c.knots && v.ctrl == c.ctrl && v.w == c.w);
    assert_near(t0_of(&c), 0.0, 0.0);
    assert_near(t1_of(&c), 2.0, 0.0);
    assert_ok(hcurve_copy(&c, &d, NULL));
    assert_true(d.knots != c.knots && d.ctrl != c.ctrl && d.w != c.w);
    assert_memory_equal(d.knots, c.knots, 9 * sizeof(double));
    assert_memory_equal(d.ctrl, c.ctrl, 5 * sizeof(cm_vec3));
    assert_memory_equal(d.w, c.w, 5 * sizeof(double));
    /* copy into itself: a fresh copy replaces the old storage */
    assert_ok(hcurve_copy(&d, &d, NULL));
    assert_memory_equal(d.ctrl, c.ctrl, 5 * sizeof(cm_vec3));
    /* a builder frees what `out` held before */
    assert_ok(hcurve_line(cm_v3(0, 0, 0), cm_v3(1, 0, 0), &d, NULL));
    assert_int_equal(d.n, 2);
    assert_null(d.w);
    hcurve_free(&c);
    hcurve_free(&d);
    hcurve_free(&d); /* twice is harmless */
    assert_true(c.knots == NULL && c.ctrl == NULL && c.w == NULL && c.n == 0 && c.p == 0);
    hcurve_free(NULL);

    cm_status st;
    cm_status_init(&st);
    assert_err(hcurve_alloc(&c, 0, 5, 0, &st), CM_E_ARG);
    assert_int_equal(st.code, CM_E_ARG);
    assert_err(hcurve_alloc(&c, 3, 3, 0, NULL), CM_E_ARG);
    assert_err(hcurve_alloc(&c, CM_MAX_DEGREE + 1, 40, 0, NULL), CM_E_LIMIT);
    assert_err(hcurve_alloc(NULL, 1, 2, 0, NULL), CM_E_ARG);
    assert_null(c.knots);

    hsurf s = {0}, t = {0};
    assert_ok(hsurf_alloc(&s, 2, 1, 3, 4, 0, NULL));
    assert_true(s.U && s.V && s.ctrl && s.w == NULL && s.nu == 3 && s.nv == 4);
    for (int i = 0; i < 6; i++)
        s.U[i] = i < 3 ? 0.0 : 1.0;
    for (int i = 0; i < 6; i++)
        s.V[i] = i < 2 ? -1.0 : i < 4 ? 0.5 * i : 3.0;
    for (int i = 0; i < 12; i++)
        s.ctrl[i] = cm_v3(i, i * i, 1);
    double u0, u1, v0, v1;
    hsurf_domain(&s, &u0, &u1, &v0, &v1);
    assert_true(u0 == 0.0 && u1 == 1.0 && v0 == -1.0 && v1 == 3.0);
    assert_ok(hsurf_copy(&s, &t, NULL));
    assert_memory_equal(t.ctrl, s.ctrl, 12 * sizeof(cm_vec3));
    assert_memory_equal(t.V, s.V, 6 * sizeof(double));
    cm_surf sv = hsurf_view(&t);
    assert_true(sv.U == t.U && sv.nv == 4 && sv.w == NULL);
    assert_err(hsurf_alloc(&t, 2, 1, 2, 4, 1, NULL), CM_E_ARG);
    assert_null(t.ctrl); /* alloc empties first */
    hsurf_free(&s);
    hsurf_free(&t);
    hsurf_free(NULL);
    assert_true(s.U == NULL && s.nu == 0);
}

/* Every allocation of every builder may fail: CM_E_NOMEM, `out` empty, nothing leaked (run under ASan),
 * and make_compatible leaves its inputs untouched. */
enum { OP_ARC, OP_CUBIC, OP_SUBRANGE, OP_ELEVATE, OP_COMPAT, OP_RULED, OP_REVOLVE, OP_SPHERE, OP_CONE, OP_ISO,
       OP_EXTRUDE, OP_COPY, OP_COUNT };

static cm_err run_op(int op, const hcurve *rat, const hcurve *poly, hcurve *co, hsurf *so)
{
    const double T[3] = {0, 1, 3};
    const cm_vec3 coef[8] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {1, 2, 3}, {0, 0, 0}, {0, 0, 0}};
    switch (op) {
    case OP_ARC:
        return hcurve_ellipse_arc(cm_v3(0, 0, 0), FX, FY, 2, 1, 0, 5, co, NULL);
    case OP_CUBIC:
        return hcurve_from_cubic_segments(T, coef, 2, co, NULL);
    case OP_SUBRANGE:
        return hcurve_subrange(rat, 3.3, 6.1, co, NULL);
    case OP_ELEVATE:
        return hcurve_elevate(rat, 5, co, NULL);
    case OP_RULED:
        return hsurf_ruled(rat, poly, so, NULL);
    case OP_REVOLVE:
        return hsurf_revolve(rat, cm_v3(0, 0, 0), cm_v3(0, 0, 1), 0, 4, so, NULL);
    case OP_SPHERE:
        return hsurf_sphere(cm_v3(0, 0, 0), FX, FY, FZ, 2, 0, 6, -1, 1.5, so, NULL);
    case OP_CONE:
        return hsurf_cone(cm_v3(0, 0, 0), FX, FY, FZ, 2, 0.3, 0, 6, -1, 1.5, so, NULL);
    case OP_ISO:
        return hsurf_iso_u(so, 0.3, co, NULL);
    case OP_EXTRUDE:
        return hsurf_extrude(rat, cm_v3(1, 1, 1), so, NULL);
    case OP_COPY:
        return hcurve_copy(rat, co, NULL);
    default: /* OP_COMPAT is run by the caller: it checks that the inputs survive */
        fail_msg("op %d", op);
    }
    return CM_OK;
}

static void test_alloc_failure_injection(void **state)
{
    (void)state;
    hcurve rat = {0}, poly = {0};
    random_curve(&rat, 3, 7, 1, 0, 1, 11u);  /* unclamped rational, domain [3, 7] */
    random_curve(&poly, 2, 6, 0, 1, 2, 12u); /* clamped polynomial with a double knot */
    for (int op = 0; op < OP_COUNT; op++) {
        int failures = 0;
        for (int k = 0; k < 200; k++) {
            hcurve co = {0};
            hsurf so = {0};
            if (op == OP_ISO)
                assert_ok(hsurf_sphere(cm_v3(0, 0, 0), FX, FY, FZ, 2, 0, 6, -1, 1.5, &so, NULL));
            cm_err e;
            if (op == OP_COMPAT) {
                hcurve a = {0}, b = {0};
                assert_ok(hcurve_copy(&rat, &a, NULL));
                assert_ok(hcurve_copy(&poly, &b, NULL));
                double *ka = a.knots, *kb = b.knots;
                hnurbs_fail_alloc_after(k);
                e = hcurve_make_compatible(&a, &b, NULL);
                hnurbs_fail_alloc_after(-1);
                if (e != CM_OK) {
                    assert_true(a.knots == ka && b.knots == kb && a.n == rat.n && b.n == poly.n);
                    assert_memory_equal(a.ctrl, rat.ctrl, (size_t)rat.n * sizeof(cm_vec3));
                }
                hcurve_free(&a);
                hcurve_free(&b);
            } else {
                hnurbs_fail_alloc_after(k);
                e = run_op(op, &rat, &poly, &co, &so);
                hnurbs_fail_alloc_after(-1);
                if (e != CM_OK && op != OP_ISO) {
                    assert_null(co.knots);
                    assert_null(so.ctrl);
                }
            }
            hcurve_free(&co);
            hsurf_free(&so);
            if (e == CM_OK)
                break;
            assert_int_equal(e, CM_E_NOMEM);
            failures++;
        }
        assert_true(failures >= 1); /* every op allocates */
        assert_true(failures < 200);
    }
    /* the status records CM_E_NOMEM */
    cm_status st;
    cm_status_init(&st);
    hcurve c = {0};
    hnurbs_fail_alloc_after(0);
    assert_err(hcurve_elevate(&poly, 4, &c, &st), CM_E_NOMEM);
    hnurbs_fail_alloc_after(-1);
    assert_int_equal(st.code, CM_E_NOMEM);
    assert_null(c.knots);
    hcurve_free(&rat);
    hcurve_free(&poly);
}

/* ---- curves ---- */

static void test_line_and_polyline(void **state)
{
    (void)state;
    hcurve c = {0};
    cm_vec3 A = cm_v3(1, -2, 3), B = cm_v3(4, 0.5, -1);
    assert_ok(hcurve_line(A, B, &c, NULL));
    assert_true(c.p == 1 && c.n == 2 && c.w == NULL && t0_of(&c) == 0.0 && t1_of(&c) == 1.0);
    for (int k = 0; k <= 16; k++)
        assert_vec_near(cpt(&c, k / 16.0), cm_lerp(A, B, k / 16.0), 1e-15 * 8);
    assert_err(hcurve_line(A, A, &c, NULL), CM_E_DEGENERATE);
    assert_null(c.knots);
    assert_err(hcurve_line(cm_v3(nan(""), 0, 0), B, &c, NULL), CM_E_ARG);

    const cm_vec3 P[5] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {3, 2, 1}};
    assert_ok(hcurve_polyline(P, 5, &c, NULL));
    const double K[7] = {0, 0, 1, 2, 3, 4, 4};
    assert_memory_equal(c.knots, K, sizeof K);
    for (int i = 0; i < 5; i++)
        assert_true(cm_dist(cpt(&c, i), P[i]) == 0.0); /* parameter = point index, exactly */
    for (int i = 0; i < 4; i++)
        assert_vec_near(cpt(&c, i + 0.25), cm_lerp(P[i], P[i + 1], 0.25), 1e-15 * 8);
    assert_err(hcurve_polyline(P, 1, &c, NULL), CM_E_ARG);
    assert_err(hcurve_polyline(NULL, 3, &c, NULL), CM_E_ARG);
    hcurve_free(&c);
}

/*
 * Ellipse arcs of 10 .. 360 degrees: the span count, the knots at equal
 * angle steps, the point at every knot equal to the closed form, every
 * point in between on the ellipse (implicit equation) with a monotone
 * angle, tangents parallel to the closed form's, end points exact.
 */
static void test_ellipse_arc_sweeps(void **state)
{
    (void)state;
    const double sweeps[7] = {10, 90, 91, 180, 270, 359.9, 360};
    const int spans[7] = {1, 1, 2, 2, 3, 4, 4};
    const double starts[3] = {0.0, 0.7, -2.5};
    const cm_vec3 C = cm_v3(10, -4, 2.5);
    const double a = 3.0, b = 1.25, scale = 13.0;
    for (int si = 0; si < 3; si++) {
        for (int k = 0; k < 7; k++) {
            double t0 = starts[si], t1 = k == 6 ? t0 + 2 * M_PI : t0 + sweeps[k] * DEG;
            hcurve c = {0};
            assert_ok(hcurve_ellipse_arc(C, FX, FY, a, b, t0, t1, &c, NULL));
            int ns = spans[k];
            assert_int_equal(c.p, 2);
            assert_int_equal(c.n, 2 * ns + 1);
            assert_non_null(c.w);
            assert_true(t0_of(&c) == t0 && t1_of(&c) == t1);
            assert_true(is_clamped(&c));
            double h = (t1 - t0) / ns;
            for (int j = 1; j < ns; j++) {
                double kn = c.knots[2 * j + 1];
                assert_true(c.knots[2 * j + 2] == kn); /* double interior knots */
                assert_near(kn, t0 + j * h, 4e-16 * (fabs(t0) + 2 * M_PI));
                /* the parameter equals the angle at every knot */
                assert_vec_near(cpt(&c, kn), ellipse_pt(C, FX, FY, a, b, kn), REL * scale * 0.01);
                assert_near(c.w[2 * j + 1], cos(h / 2), 1e-15);
            }
            assert_near(c.w[1], cos(h / 2), 1e-15);
            /* end points */
            assert_vec_near(cpt(&c, t0), ellipse_pt(C, FX, FY, a, b, t0), 1e-15 * scale);
            assert_vec_near(cpt(&c, t1), ellipse_pt(C, FX, FY, a, b, t1), 1e-15 * scale);
            if (k == 6)
                assert_memory_equal(&c.ctrl[0], &c.ctrl[c.n - 1], sizeof(cm_vec3)); /* closes exactly */
            /* in between: on the ellipse, angle increasing, tangent along the ellipse's */
            double prev = -HUGE_VAL;
            for (int q = 0; q <= 400; q++) {
                double u = t0 + (t1 - t0) * q / 400.0;
                cm_vec3 P = cpt(&c, u), D = cder(&c, u);
                assert_near(ellipse_residual(P, C, FX, FY, a, b), 0.0, 1e-14);
                cm_vec3 d = cm_sub(P, C);
                double th = atan2(cm_dot(d, FY) / b, cm_dot(d, FX) / a);
                while (th < u - M_PI)
                    th += 2 * M_PI;
                while (th > u + M_PI)
                    th -= 2 * M_PI;
                assert_true(fabs(th - u) < 0.03); /* rational parametrisation: near the angle (<= 0.016 rad for 90 degrees) */
                assert_true(th > prev - 1e-15);
                prev = th;
                cm_vec3 Et = cm_add(cm_scale(FX, -a * sin(th)), cm_scale(FY, b * cos(th)));
                assert_near(cm_norm(cm_cross(D, Et)) / (cm_norm(D) * cm_norm(Et)), 0.0, 1e-13);
                assert_true(cm_dot(D, Et) > 0.0);
            }
            hcurve_free(&c);
        }
    }
}

/* A circle (a == b) in a plane far from the origin, through the IGES-style call with t1 = t0 + 2 pi. */
static void test_circle_arc_far_from_origin(void **state)
{
    (void)state;
    const cm_vec3 C = cm_v3(1000, -2000, 500);
    const double r = 25.0;
    hcurve c = {0};
    double t0 = 4.1, t1 = t0 + 2 * M_PI;
    assert_ok(hcurve_ellipse_arc(C, FX, FY, r, r, t0, t1, &c, NULL));
    assert_int_equal(c.n, 9);
    for (int q = 0; q <= 300; q++) {
        double u = t0 + (t1 - t0) * q / 300.0;
        assert_near(cm_dist(cpt(&c, u), C), r, REL * 2000);
        assert_near(cm_dot(cm_sub(cpt(&c, u), C), FZ), 0.0, REL * 2000); /* planar */
    }
    for (int j = 0; j <= 4; j++) {
        double kn = j < 4 ? c.knots[2 * j + 2] : t1;
        assert_vec_near(cpt(&c, kn), ellipse_pt(C, FX, FY, r, r, kn), REL * 2000);
    }
    hcurve_free(&c);
}

static void test_ellipse_arc_errors(void **state)
{
    (void)state;
    hcurve c = {0};
    cm_vec3 O = cm_v3(0, 0, 0);
    assert_ok(hcurve_line(O, cm_v3(1, 0, 0), &c, NULL)); /* `out` must be emptied by the failures */
    cm_status st;
    cm_status_init(&st);
    assert_err(hcurve_ellipse_arc(O, FX, FY, 0, 1, 0, 1, &c, &st), CM_E_ARG);
    assert_int_equal(st.code, CM_E_ARG);
    assert_null(c.knots);
    assert_err(hcurve_ellipse_arc(O, FX, FY, 1, -1, 0, 1, &c, NULL), CM_E_ARG);
    assert_err(hcurve_ellipse_arc(O, FX, FY, 1, 1, 1, 1, &c, NULL), CM_E_ARG);
    assert_err(hcurve_ellipse_arc(O, FX, FY, 1, 1, 1, 0.5, &c, NULL), CM_E_ARG);
    assert_err(hcurve_ellipse_arc(O, FX, FY, 1, 1, 0, 2 * M_PI + 1e-6, &c, NULL), CM_E_ARG);
    assert_err(hcurve_ellipse_arc(O, FX, FY, 1, 1, 0, nan(""), &c, NULL), CM_E_ARG);
    assert_err(hcurve_ellipse_arc(O, FX, FX, 1, 1, 0, 1, &c, NULL), CM_E_DEGENERATE);
    assert_err(hcurve_ellipse_arc(O, FX, cm_v3(0, 0, 0), 1, 1, 0, 1, &c, NULL), CM_E_DEGENERATE);
    assert_err(hcurve_ellipse_arc(O, FX, FY, 1, 1, 0, 1, NULL, NULL), CM_E_ARG);
    /* a start far from 0 with t1 = t0 + 2 pi rounded up is still a full circle */
    double t0 = 123.456;
    assert_ok(hcurve_ellipse_arc(O, FX, FY, 1, 1, t0, t0 + 2 * M_PI, &c, NULL));
    assert_int_equal(c.n, 9);
    hcurve_free(&c);
}

/* Parabola y = x^2 from its tangent points: w1 = 1, polynomial, every point on it. */
static void test_conic_parabola(void **state)
{
    (void)state;
    /* tangents at x = -1 (y = -2x - 1) and x = 2 (y = 4x - 4) meet at (0.5, -2) */
    cm_vec3 P0 = cm_v3(-1, 1, 0), P1 = cm_v3(0.5, -2, 0), P2 = cm_v3(2, 4, 0);
    hcurve c = {0};
    assert_ok(hcurve_conic_span(P0, P1, P2, 1.0, &c, NULL));
    assert_true(c.p == 2 && c.n == 3 && c.w == NULL && t0_of(&c) == 0.0 && t1_of(&c) == 1.0);
    assert_true(cm_dist(cpt(&c, 0), P0) == 0.0 && cm_dist(cpt(&c, 1), P2) == 0.0);
    for (int k = 0; k <= 100; k++) {
        cm_vec3 P = cpt(&c, k / 100.0);
        assert_near(P.y, P.x * P.x, REL * 4);
        assert_near(P.z, 0.0, 0.0);
        assert_near(P.x, -1 + 3 * k / 100.0, REL * 4); /* a quadratic Bezier of a parabola is uniform in x */
    }
    hcurve_free(&c);
}

/* Hyperbola x y = 1 between (1/2, 2) and (2, 1/2): tangents meet at (0.8, 0.8), shoulder (1,1) gives w = 1.25. */
static void test_conic_hyperbola(void **state)
{
    (void)state;
    hcurve c = {0};
    assert_ok(hcurve_conic_span(cm_v3(0.5, 2, 1), cm_v3(0.8, 0.8, 1), cm_v3(2, 0.5, 1), 1.25, &c, NULL));
    assert_non_null(c.w);
    assert_true(c.w[0] == 1.0 && c.w[1] == 1.25 && c.w[2] == 1.0);
    assert_vec_near(cpt(&c, 0.5), cm_v3(1, 1, 1), REL);
    double prev = 0.0;
    for (int k = 0; k <= 200; k++) {
        cm_vec3 P = cpt(&c, k / 200.0);
        assert_near(P.x * P.y, 1.0, REL);
        assert_near(P.z, 1.0, 1e-15); /* w P / w: one rounding */
        assert_true(P.x >= prev); /* one branch, traversed once */
        prev = P.x;
    }
    hcurve_free(&c);
}

/*
 * Elliptic conic spans: the quarter of x^2/4 + y^2 = 1 from its tangent
 * points (w = 1/sqrt 2), and a 100 degree arc of an ellipse in a tilted
 * plane with w = cos 50 degrees and P1 at the tangents' intersection.
 */
static void test_conic_ellipse(void **state)
{
    (void)state;
    hcurve c = {0};
    assert_ok(hcurve_conic_span(cm_v3(2, 0, 0), cm_v3(2, 1, 0), cm_v3(0, 1, 0), TEST_SQRT1_2, &c, NULL));
    for (int k = 0; k <= 200; k++) {
        cm_vec3 P = cpt(&c, k / 200.0);
        assert_near(P.x * P.x / 4 + P.y * P.y, 1.0, REL);
    }
    const cm_vec3 C = cm_v3(1, 2, 3);
    const double a = 4, b = 1.5, t0 = 0.3, d = 100 * DEG;
    cm_vec3 P0 = ellipse_pt(C, FX, FY, a, b, t0), P2 = ellipse_pt(C, FX, FY, a, b, t0 + d);
    cm_vec3 P1 = ellipse_pt(C, FX, FY, a / cos(d / 2), b / cos(d / 2), t0 + d / 2);
    assert_ok(hcurve_conic_span(P0, P1, P2, cos(d / 2), &c, NULL));
    for (int k = 0; k <= 200; k++)
        assert_near(ellipse_residual(cpt(&c, k / 200.0), C, FX, FY, a, b), 0.0, REL);
    assert_vec_near(cpt(&c, 0.5), ellipse_pt(C, FX, FY, a, b, t0 + d / 2), REL * 10); /* shoulder */
    assert_err(hcurve_conic_span(P0, P1, P2, 0.0, &c, NULL), CM_E_ARG);
    assert_null(c.knots);
    assert_err(hcurve_conic_span(P0, P1, P2, -1.0, &c, NULL), CM_E_ARG);
    assert_err(hcurve_conic_span(P0, P1, P2, nan(""), &c, NULL), CM_E_ARG);
    assert_err(hcurve_conic_span(P0, P1, P0, 0.5, &c, NULL), CM_E_DEGENERATE);
    hcurve_free(&c);
}

static cm_vec3 cubic_poly(const cm_vec3 *cf, double s)
{
    return cm_add(cm_add(cf[0], cm_scale(cf[1], s)), cm_add(cm_scale(cf[2], s * s), cm_scale(cf[3], s * s * s)));
}

static cm_vec3 cubic_poly_d(const cm_vec3 *cf, double s)
{
    return cm_add(cf[1], cm_add(cm_scale(cf[2], 2 * s), cm_scale(cf[3], 3 * s * s)));
}

/*
 * IGES 112 segments on non-uniform breakpoints, joined C0 only (a corner at
 * the second breakpoint): the B-spline equals each polynomial and its
 * derivative inside the segment, and the breakpoint values exactly.
 */
static void test_cubic_segments(void **state)
{
    (void)state;
    const double T[5] = {-1.0, 0.5, 2.0, 2.25, 4.0};
    cm_vec3 coef[16];
    uint32_t s = 77u;
    for (int i = 0; i < 16; i++)
        coef[i] = test_rand_vec(&s, 3.0);
    for (int i = 1; i < 4; i++) /* C0: each segment starts where the previous ends */
        coef[4 * i] = cubic_poly(&coef[4 * (i - 1)], T[i] - T[i - 1]);
    hcurve c = {0};
    assert_ok(hcurve_from_cubic_segments(T, coef, 4, &c, NULL));
    assert_true(c.p == 3 && c.n == 13 && c.w == NULL);
    assert_true(t0_of(&c) == T[0] && t1_of(&c) == T[4] && is_clamped(&c));
    for (int i = 1; i < 4; i++)
        assert_int_equal(mult_at(&c, T[i]), 3);
    double scale = 60.0;
    for (int i = 0; i < 4; i++) {
        for (int k = 0; k <= 50; k++) {
            double sl = (T[i + 1] - T[i]) * k / 50.0, u = T[i] + sl;
            assert_vec_near(cpt(&c, u), cubic_poly(&coef[4 * i], sl), REL * scale);
            if (k > 0 && k < 50)
                assert_vec_near(cder(&c, u), cubic_poly_d(&coef[4 * i], sl), REL * scale * 4);
        }
        /* exact at the breakpoints (the control point there is A_i itself) */
        assert_memory_equal(&c.ctrl[3 * i], &coef[4 * i], sizeof(cm_vec3));
    }
    assert_vec_near(cpt(&c, T[4]), cubic_poly(&coef[12], T[4] - T[3]), REL * scale);

    /* a gap in the input is closed at the breakpoint by segment i's own start */
    coef[4] = cm_add(coef[4], cm_v3(0.5, 0, 0));
    assert_ok(hcurve_from_cubic_segments(T, coef, 2, &c, NULL));
    assert_vec_near(cpt(&c, T[1]), coef[4], REL * scale);
    assert_vec_near(cpt(&c, 1.0), cubic_poly(&coef[4], 0.5), REL * scale);

    /* one segment: a plain cubic Bezier */
    assert_ok(hcurve_from_cubic_segments(T + 1, coef + 4, 1, &c, NULL));
    assert_int_equal(c.n, 4);
    for (int k = 0; k <= 20; k++)
        assert_vec_near(cpt(&c, T[1] + 1.5 * k / 20), cubic_poly(&coef[4], 1.5 * k / 20), REL * scale);

    const double Tbad[3] = {0, 1, 1};
    assert_err(hcurve_from_cubic_segments(Tbad, coef, 2, &c, NULL), CM_E_KNOTS);
    assert_null(c.knots);
    const double Tnan[3] = {0, nan(""), 1};
    assert_err(hcurve_from_cubic_segments(Tnan, coef, 2, &c, NULL), CM_E_KNOTS);
    assert_err(hcurve_from_cubic_segments(T, coef, 0, &c, NULL), CM_E_ARG);
    assert_err(hcurve_from_cubic_segments(NULL, coef, 1, &c, NULL), CM_E_ARG);
    hcurve_free(&c);
}

static haffine test_map(void)
{
    /* rotation about FZ by 0.7, then a non-uniform scale (still affine), then a translation */
    haffine m;
    for (int i = 0; i < 3; i++) {
        cm_vec3 e = cm_v3(i == 0, i == 1, i == 2);
        cm_vec3 r = rodrigues(e, cm_v3(0, 0, 0), FZ, 0.7);
        m.R[0][i] = 2.0 * r.x;
        m.R[1][i] = r.y;
        m.R[2][i] = 0.5 * r.z;
    }
    m.t = cm_v3(3, -1, 7);
    return m;
}

static void test_affine_helpers(void **state)
{
    (void)state;
    haffine I = haffine_identity();
    cm_vec3 x = cm_v3(1.5, -2, 0.25);
    assert_true(cm_dist(haffine_apply(&I, x), x) == 0.0);
    haffine m = test_map();
    cm_vec3 r = rodrigues(x, cm_v3(0, 0, 0), FZ, 0.7);
    cm_vec3 ex = cm_v3(2 * r.x + 3, r.y - 1, 0.5 * r.z + 7);
    assert_vec_near(haffine_apply(&m, x), ex, 1e-14);
    assert_vec_near(haffine_apply_dir(&m, x), cm_v3(2 * r.x, r.y, 0.5 * r.z), 1e-14);
    /* a o b: first b, then a */
    haffine b = haffine_identity();
    b.t = cm_v3(0, 0, 1);
    b.R[0][0] = 3.0;
    haffine ab = haffine_compose(&m, &b), ba = haffine_compose(&b, &m);
    assert_vec_near(haffine_apply(&ab, x), haffine_apply(&m, haffine_apply(&b, x)), 1e-13);
    assert_vec_near(haffine_apply(&ba, x), haffine_apply(&b, haffine_apply(&m, x)), 1e-13);
    assert_true(cm_dist(haffine_apply(&ab, x), haffine_apply(&ba, x)) > 0.1);
    haffine mi = haffine_compose(&m, &I);
    assert_vec_near(haffine_apply(&mi, x), haffine_apply(&m, x), 0.0);
}

/* An affine map of a rational arc: the mapped closed form, at every parameter. */
static void test_curve_transform(void **state)
{
    (void)state;
    hcurve c = {0}, d = {0};
    const cm_vec3 C = cm_v3(1, 2, 3);
    assert_ok(hcurve_ellipse_arc(C, FX, FY, 2, 1, 0.2, 4.0, &c, NULL));
    assert_ok(hcurve_copy(&c, &d, NULL));
    haffine m = test_map();
    hcurve_transform(&d, &m);
    for (int k = 0; k <= 200; k++) {
        double u = 0.2 + 3.8 * k / 200.0;
        assert_vec_near(cpt(&d, u), haffine_apply(&m, cpt(&c, u)), REL * 20);
    }
    for (int j = 0; j < 3; j++) { /* the knots are still the angles */
        double kn = j == 0 ? 0.2 : c.knots[2 * j + 2];
        assert_vec_near(cpt(&d, kn), haffine_apply(&m, ellipse_pt(C, FX, FY, 2, 1, kn)), REL * 20);
    }
    assert_memory_equal(d.knots, c.knots, (size_t)(c.n + 3) * sizeof(double));
    assert_memory_equal(d.w, c.w, (size_t)c.n * sizeof(double));
    hcurve_transform(NULL, &m); /* harmless */
    hcurve_free(&c);
    hcurve_free(&d);
}

static void test_reverse(void **state)
{
    (void)state;
    hcurve c = {0}, d = {0};
    /* clamped rational */
    assert_ok(hcurve_ellipse_arc(cm_v3(0, 0, 0), FX, FY, 3, 2, -0.4, 3.9, &c, NULL));
    assert_ok(hcurve_copy(&c, &d, NULL));
    hcurve_reverse(&d);
    assert_true(t0_of(&d) == -0.4 && t1_of(&d) == 3.9 && is_clamped(&d));
    assert_same_curve(&c, -0.4, 3.9, &d, 3.9, -0.4, 300, REL * 5);
    assert_true(cm_dist(cpt(&d, -0.4), cpt(&c, 3.9)) == 0.0);
    hcurve_reverse(&d); /* twice: the original again */
    assert_same_curve(&c, -0.4, 3.9, &d, -0.4, 3.9, 100, REL * 5);
    hcurve_free(&d);
    /* unclamped rational cubic */
    random_curve(&c, 3, 9, 1, 0, 1, 5u);
    assert_ok(hcurve_copy(&c, &d, NULL));
    hcurve_reverse(&d);
    assert_true(t0_of(&d) == 3.0 && t1_of(&d) == 9.0);
    cm_curve v = hcurve_view(&d);
    assert_ok(cm_curve_check(&v, NULL));
    assert_same_curve(&c, 3, 9, &d, 9, 3, 300, REL * 10);
    hcurve_free(&c);
    hcurve_free(&d);
}

static void test_reparam(void **state)
{
    (void)state;
    hcurve c = {0}, d = {0};
    random_curve(&c, 2, 8, 1, 1, 2, 9u);
    assert_ok(hcurve_copy(&c, &d, NULL));
    hcurve_reparam(&d, -3.0, 10.0);
    assert_true(t0_of(&d) == -3.0 && t1_of(&d) == 10.0 && is_clamped(&d));
    assert_same_curve(&c, 0, 1, &d, -3, 10, 300, REL * 10);
    for (int i = 0; i < 8 + 2; i++) /* the double knot stays double */
        assert_int_equal(mult_at(&d, d.knots[i]), mult_at(&c, c.knots[i]));
    /* an invalid range changes nothing */
    hcurve_reparam(&d, 5.0, 5.0);
    hcurve_reparam(&d, 6.0, 5.0);
    hcurve_reparam(&d, nan(""), 5.0);
    assert_true(t0_of(&d) == -3.0 && t1_of(&d) == 10.0);
    hcurve_free(&c);
    hcurve_free(&d);
    /* unclamped: the knots outside the domain move with it */
    random_curve(&c, 3, 7, 0, 0, 1, 10u);
    assert_ok(hcurve_copy(&c, &d, NULL));
    hcurve_reparam(&d, 0.0, 1.0);
    assert_true(t0_of(&d) == 0.0 && t1_of(&d) == 1.0);
    assert_near(d.knots[0], -0.75, 1e-15);
    assert_near(d.knots[10], 1.75, 1e-15);
    assert_same_curve(&c, 3, 7, &d, 0, 1, 200, REL * 10);
    hcurve_free(&c);
    hcurve_free(&d);
}

static void check_subrange(const hcurve *c, double a, double b, double tol)
{
    hcurve s = {0};
    assert_ok(hcurve_subrange(c, a, b, &s, NULL));
    assert_true(t0_of(&s) == a && t1_of(&s) == b);
    assert_true(is_clamped(&s));
    assert_true(s.p == c->p && (s.w != NULL) == (c->w != NULL));
    cm_curve v = hcurve_view(&s);
    assert_ok(cm_curve_check(&v, NULL));
    assert_same_curve(c, a, b, &s, a, b, 200, tol);
    assert_vec_near(cpt(&s, a), cpt(c, a), tol);
    assert_vec_near(cpt(&s, b), cpt(c, b), tol);
    hcurve_free(&s);
}

/* Clamped rational arc: pieces between arbitrary parameters, knots and the ends. */
static void test_subrange_clamped(void **state)
{
    (void)state;
    hcurve c = {0};
    const cm_vec3 C = cm_v3(1, 1, 1);
    assert_ok(hcurve_ellipse_arc(C, FX, FY, 2, 2, 0, 270 * DEG, &c, NULL));
    double k1 = c.knots[3], k2 = c.knots[5], t1 = t1_of(&c);
    check_subrange(&c, 0.1, t1 - 0.2, REL * 5);
    check_subrange(&c, k1, k2, REL * 5);
    check_subrange(&c, 0, k1, REL * 5);
    check_subrange(&c, k2, t1, REL * 5);
    check_subrange(&c, 0, t1, REL * 5);
    check_subrange(&c, 1.0, 1.0 + 1e-6, REL * 5);
    /* a piece is still a circle, and a knot-aligned piece is the corresponding exact span */
    hcurve s = {0};
    assert_ok(hcurve_subrange(&c, 0.3, 4.5, &s, NULL));
    for (int k = 0; k <= 100; k++)
        assert_near(cm_dist(cpt(&s, 0.3 + 4.2 * k / 100), C), 2.0, REL * 2);
    assert_ok(hcurve_subrange(&c, k1, k2, &s, NULL));
    assert_int_equal(s.n, 3);
    assert_near(s.w[1], cos(45 * DEG), 1e-15);
    /* out may alias the input */
    assert_ok(hcurve_subrange(&s, k1, k1 + 0.5, &s, NULL));
    assert_vec_near(cpt(&s, k1 + 0.25), cpt(&c, k1 + 0.25), REL * 5);
    hcurve_free(&s);
    hcurve_free(&c);

    /* polynomial cubic with a triple (C0) knot */
    random_curve(&c, 3, 10, 0, 1, 3, 21u);
    double kd = c.knots[5];
    check_subrange(&c, 0.05, 0.95, REL * 10);
    check_subrange(&c, kd, 1.0, REL * 10);
    check_subrange(&c, 0.0, kd, REL * 10);
    hcurve_free(&c);

    /* a jump (knot 0.5 of multiplicity p+1): each side's piece ends on that side's limit */
    assert_ok(hcurve_alloc(&c, 2, 6, 1, NULL));
    const double K[9] = {0, 0, 0, 0.5, 0.5, 0.5, 1, 1, 1};
    memcpy(c.knots, K, sizeof K);
    uint32_t seed = 17u;
    for (int i = 0; i < 6; i++) {
        c.ctrl[i] = test_rand_vec(&seed, 2.0);
        c.w[i] = 0.5 + test_rand(&seed);
    }
    hcurve l = {0}, r = {0};
    assert_ok(hcurve_subrange(&c, 0.0, 0.5, &l, NULL));
    assert_ok(hcurve_subrange(&c, 0.5, 1.0, &r, NULL));
    assert_true(l.n == 3 && r.n == 3);
    assert_vec_near(cpt(&l, 0.5), c.ctrl[2], 1e-15 * 4); /* left limit */
    assert_vec_near(cpt(&r, 0.5), c.ctrl[3], 1e-15 * 4); /* right value */
    assert_same_curve(&c, 0.0, nextafter(0.5, 0.0), &l, 0.0, nextafter(0.5, 0.0), 100, REL * 4);
    assert_same_curve(&c, 0.5, 1.0, &r, 0.5, 1.0, 100, REL * 4);
    hcurve_free(&l);
    hcurve_free(&r);
    hcurve_free(&c);
}

/* Unclamped (uniform, "periodic-style") knot vectors: pieces and the whole domain. */
static void test_subrange_unclamped(void **state)
{
    (void)state;
    for (int rational = 0; rational <= 1; rational++) {
        hcurve c = {0};
        random_curve(&c, 3, 7, rational, 0, 1, 31u + (uint32_t)rational); /* knots 0..10, domain [3, 7] */
        check_subrange(&c, 3.0, 7.0, REL * 10);
        check_subrange(&c, 3.5, 6.2, REL * 10);
        check_subrange(&c, 4.0, 5.0, REL * 10);
        check_subrange(&c, 3.0, 3.25, REL * 10);
        check_subrange(&c, 6.75, 7.0, REL * 10);
        hcurve_free(&c);
        /* degree 2, unclamped with a double knot inside */
        assert_ok(hcurve_alloc(&c, 2, 6, rational, NULL));
        const double K[9] = {-2, -1, 0, 1, 1, 2.5, 4, 5, 7};
        memcpy(c.knots, K, sizeof K);
        uint32_t s = 41u;
        for (int i = 0; i < 6; i++) {
            c.ctrl[i] = test_rand_vec(&s, 4.0);
            if (rational)
                c.w[i] = 0.5 + test_rand(&s);
        }
        check_subrange(&c, 0.0, 4.0, REL * 10);
        check_subrange(&c, 1.0, 2.5, REL * 10);
        check_subrange(&c, 0.5, 3.0, REL * 10);
        hcurve_free(&c);
    }
}

static void test_subrange_errors(void **state)
{
    (void)state;
    hcurve c = {0}, s = {0};
    random_curve(&c, 3, 7, 0, 0, 1, 3u);
    assert_err(hcurve_subrange(&c, 5, 5, &s, NULL), CM_E_ARG);
    assert_err(hcurve_subrange(&c, 5, 4, &s, NULL), CM_E_ARG);
    assert_err(hcurve_subrange(&c, 2.9, 4, &s, NULL), CM_E_ARG);
    assert_err(hcurve_subrange(&c, 4, 7.1, &s, NULL), CM_E_ARG);
    assert_err(hcurve_subrange(&c, nan(""), 4, &s, NULL), CM_E_ARG);
    assert_null(s.knots);
    c.knots[5] = 3.0; /* decreasing */
    cm_status st;
    cm_status_init(&st);
    assert_err(hcurve_subrange(&c, 4, 5, &s, &st), CM_E_KNOTS);
    assert_int_equal(st.code, CM_E_KNOTS);
    c.knots[5] = 5.0;
    c.ctrl[2].y = nan("");
    assert_err(hcurve_subrange(&c, 4, 5, &s, NULL), CM_E_NONFINITE);
    hcurve empty = {0};
    assert_err(hcurve_subrange(&empty, 0, 1, &s, NULL), CM_E_ARG);
    hcurve_free(&c);
}

/* Host curves may exceed CM_MAX_EDGE_CTRL: subrange and elevation have no such limit. */
static void test_large_curve(void **state)
{
    (void)state;
    const int n = CM_MAX_EDGE_CTRL + 1808; /* 10000 on the host profile */
    cm_vec3 *P = malloc((size_t)n * sizeof *P);
    assert_non_null(P);
    for (int i = 0; i < n; i++)
        P[i] = cm_v3(i, sin(0.01 * i), cos(0.003 * i));
    hcurve c = {0}, s = {0}, e = {0};
    assert_ok(hcurve_polyline(P, n, &c, NULL));
    assert_ok(hcurve_subrange(&c, 100.5, n - 1000.25, &s, NULL));
    assert_int_equal(s.n, n - 1100 + 1);
    for (int k = 0; k <= 500; k++) {
        double u = 100.5 + (n - 1100.75) * k / 500.0;
        assert_vec_near(cpt(&s, u), cpt(&c, u), 1e-12 * n);
    }
    assert_ok(hcurve_elevate(&c, 2, &e, NULL));
    assert_int_equal(e.n, 2 * (n - 1) + 1);
    for (int k = 0; k <= 500; k++) {
        double u = (n - 1) * k / 500.0;
        assert_vec_near(cpt(&e, u), cpt(&c, u), 1e-12 * n);
    }
    hcurve_free(&c);
    hcurve_free(&s);
    hcurve_free(&e);
    free(P);
}

static void test_clamp(void **state)
{
    (void)state;
    hcurve c = {0}, d = {0};
    random_curve(&c, 4, 9, 1, 0, 1, 8u); /* knots 0..13, domain [4, 9] */
    assert_ok(hcurve_clamp(&c, &d, NULL));
    assert_true(is_clamped(&d));
    assert_true(t0_of(&d) == 4.0 && t1_of(&d) == 9.0);
    assert_int_equal(d.n, 9 - 4 + 4); /* spans + p */
    for (int i = 5; i <= 8; i++)
        assert_int_equal(mult_at(&d, (double)i), 1);
    assert_same_curve(&c, 4, 9, &d, 4, 9, 300, REL * 10);
    /* clamping a clamped curve changes nothing */
    hcurve e = {0};
    assert_ok(hcurve_clamp(&d, &e, NULL));
    assert_int_equal(e.n, d.n);
    assert_memory_equal(e.knots, d.knots, (size_t)(d.n + d.p + 1) * sizeof(double));
    for (int i = 0; i < d.n; i++) {
        assert_vec_near(e.ctrl[i], d.ctrl[i], 1e-14 * 10);
        assert_near(e.w[i], d.w[i], 1e-15);
    }
    hcurve_free(&c);
    hcurve_free(&d);
    hcurve_free(&e);
}

/* Degree 1 -> 3 of a polyline: Bezier segments reassembled with triple knots. */
static void test_elevate_polyline_1_to_3(void **state)
{
    (void)state;
    const cm_vec3 P[5] = {{0, 0, 0}, {1, 0, 0}, {1, 2, 0}, {1, 2, 3}, {-1, 0.5, 2}};
    hcurve c = {0}, e = {0};
    assert_ok(hcurve_polyline(P, 5, &c, NULL));
    assert_ok(hcurve_elevate(&c, 3, &e, NULL));
    assert_true(e.p == 3 && e.n == 13 && e.w == NULL && is_clamped(&e));
    const double K[17] = {0, 0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3, 4, 4, 4, 4};
    assert_memory_equal(e.knots, K, sizeof K);
    for (int i = 0; i < 5; i++)
        assert_true(cm_dist(e.ctrl[3 * i], P[i]) == 0.0); /* corners kept exactly */
    for (int i = 0; i < 4; i++) /* a line as a cubic: thirds */
        assert_vec_near(e.ctrl[3 * i + 1], cm_lerp(P[i], P[i + 1], 1.0 / 3), 1e-15 * 8);
    assert_same_curve(&c, 0, 4, &e, 0, 4, 400, REL * 4);
    hcurve_free(&c);
    hcurve_free(&e);
}

/* Degree 2 -> 5 of a 3-span rational ellipse arc and of a polynomial multi-span curve with a double knot. */
static void test_elevate_2_to_5(void **state)
{
    (void)state;
    hcurve c = {0}, e = {0};
    const cm_vec3 C = cm_v3(-3, 2, 1);
    assert_ok(hcurve_ellipse_arc(C, FX, FY, 5, 2, 0.5, 0.5 + 250 * DEG, &c, NULL));
    assert_ok(hcurve_elevate(&c, 5, &e, NULL));
    assert_true(e.p == 5 && e.n == 3 * 5 + 1 && e.w != NULL && is_clamped(&e));
    assert_int_equal(mult_at(&e, c.knots[3]), 5);
    assert_int_equal(mult_at(&e, c.knots[5]), 5);
    assert_true(t0_of(&e) == t0_of(&c) && t1_of(&e) == t1_of(&c));
    assert_same_curve(&c, t0_of(&c), t1_of(&c), &e, t0_of(&e), t1_of(&e), 500, REL * 10);
    for (int k = 0; k <= 300; k++)
        assert_near(ellipse_residual(cpt(&e, 0.5 + 250 * DEG * k / 300), C, FX, FY, 5, 2), 0.0, REL);
    assert_vec_near(cpt(&e, c.knots[3]), ellipse_pt(C, FX, FY, 5, 2, c.knots[3]), REL * 10);
    hcurve_free(&c);
    hcurve_free(&e);

    random_curve(&c, 2, 9, 0, 1, 2, 55u);
    assert_ok(hcurve_elevate(&c, 5, &e, NULL));
    assert_true(e.p == 5 && e.w == NULL);
    assert_same_curve(&c, 0, 1, &e, 0, 1, 500, REL * 10);
    hcurve_free(&e);
    /* rational multi-span with random weights, 2 -> 3 and 2 -> 5 */
    hcurve_free(&c);
    random_curve(&c, 2, 9, 1, 1, 1, 56u);
    for (int np = 3; np <= 5; np += 2) {
        assert_ok(hcurve_elevate(&c, np, &e, NULL));
        assert_int_equal(e.p, np);
        assert_same_curve(&c, 0, 1, &e, 0, 1, 500, REL * 10);
    }
    hcurve_free(&c);
    hcurve_free(&e);
}

/* Unclamped input, a discontinuous (full multiplicity) knot, degree == p, and the errors. */
static void test_elevate_special(void **state)
{
    (void)state;
    hcurve c = {0}, e = {0};
    random_curve(&c, 3, 8, 1, 0, 1, 66u); /* domain [3, 8] */
    assert_ok(hcurve_elevate(&c, 4, &e, NULL));
    assert_true(e.p == 4 && is_clamped(&e) && t0_of(&e) == 3.0 && t1_of(&e) == 8.0);
    assert_same_curve(&c, 3, 8, &e, 3, 8, 400, REL * 10);
    hcurve_free(&c);

    /* degree 2 with knot 0.5 of multiplicity 3: two separate pieces */
    assert_ok(hcurve_alloc(&c, 2, 6, 0, NULL));
    const double K[9] = {0, 0, 0, 0.5, 0.5, 0.5, 1, 1, 1};
    memcpy(c.knots, K, sizeof K);
    uint32_t s = 3u;
    for (int i = 0; i < 6; i++)
        c.ctrl[i] = test_rand_vec(&s, 2.0);
    assert_ok(hcurve_elevate(&c, 3, &e, NULL));
    assert_int_equal(mult_at(&e, 0.5), 4); /* the jump survives */
    assert_int_equal(e.n, 8);
    assert_same_curve(&c, 0, 1, &e, 0, 1, 400, REL * 4);
    assert_vec_near(cpt(&e, nextafter(0.5, 0.0)), c.ctrl[2], 1e-14); /* left limit */
    assert_vec_near(cpt(&e, 0.5), c.ctrl[3], 1e-14);                   /* right value */

    /* same degree: a copy */
    assert_ok(hcurve_elevate(&c, 2, &e, NULL));
    assert_int_equal(e.n, c.n);
    assert_memory_equal(e.ctrl, c.ctrl, 6 * sizeof(cm_vec3));
    assert_err(hcurve_elevate(&c, 1, &e, NULL), CM_E_ARG);
    assert_null(e.knots);
    cm_status st;
    cm_status_init(&st);
    assert_err(hcurve_elevate(&c, CM_MAX_DEGREE + 1, &e, &st), CM_E_LIMIT);
    assert_int_equal(st.need, CM_MAX_DEGREE + 1);
    assert_ok(hcurve_elevate(&c, CM_MAX_DEGREE, &e, NULL));
    assert_same_curve(&c, 0, 1, &e, 0, 1, 100, REL * 10);
    hcurve_free(&c);
    hcurve_free(&e);
}

/*
 * A line and a 3-span rational circle arc: same degree, identical knots
 * (bit for bit), both rational, both on [0,1], shapes unchanged: the line
 * keeps its linear parameter, the arc stays on its circle with the angle
 * steps at the knots 1/3 and 2/3.
 */
static void test_make_compatible_line_arc(void **state)
{
    (void)state;
    const cm_vec3 A = cm_v3(0, 0, 0), B = cm_v3(4, 0, 1), C = cm_v3(0, 3, 0);
    const double r = 2.0, a0 = 0.25, a1 = 0.25 + 270 * DEG;
    hcurve l = {0}, c = {0}, c0 = {0};
    assert_ok(hcurve_line(A, B, &l, NULL));
    assert_ok(hcurve_ellipse_arc(C, FX, FY, r, r, a0, a1, &c, NULL));
    assert_ok(hcurve_copy(&c, &c0, NULL));
    assert_ok(hcurve_make_compatible(&l, &c, NULL));
    assert_true(l.p == 2 && c.p == 2 && l.n == c.n && l.n == 7);
    assert_memory_equal(l.knots, c.knots, (size_t)(l.n + 3) * sizeof(double));
    assert_true(l.w != NULL && c.w != NULL);
    assert_true(t0_of(&l) == 0.0 && t1_of(&l) == 1.0 && is_clamped(&l) && is_clamped(&c));
    for (int i = 0; i < l.n; i++)
        assert_true(l.w[i] == 1.0);
    for (int k = 0; k <= 300; k++) {
        double u = k / 300.0;
        assert_vec_near(cpt(&l, u), cm_lerp(A, B, u), REL * 5);
        assert_near(cm_dist(cpt(&c, u), C), r, REL * 5);
        assert_vec_near(cpt(&c, u), cpt(&c0, a0 + (a1 - a0) * u), REL * 5);
    }
    for (int j = 1; j <= 2; j++) {
        double kn = c.knots[2 * j + 1];
        assert_near(kn, j / 3.0, 1e-15);
        assert_vec_near(cpt(&c, kn), ellipse_pt(C, FX, FY, r, r, a0 + j * 90 * DEG), REL * 5);
    }
    hcurve_free(&l);
    hcurve_free(&c);
    hcurve_free(&c0);
}

/* Random curves of different degrees, knots, clamping and rationality; and a failure leaves both alone. */
static void test_make_compatible_random(void **state)
{
    (void)state;
    for (int trial = 0; trial < 6; trial++) {
        hcurve a = {0}, b = {0}, a0 = {0}, b0 = {0};
        random_curve(&a, 1 + trial % 3, 6 + trial, trial & 1, trial % 3 != 0, 2, 100u + (uint32_t)trial);
        random_curve(&b, 3, 5 + 2 * trial, (trial & 2) != 0, trial % 2 == 0, 1, 200u + (uint32_t)trial);
        assert_ok(hcurve_copy(&a, &a0, NULL));
        assert_ok(hcurve_copy(&b, &b0, NULL));
        assert_ok(hcurve_make_compatible(&a, &b, NULL));
        assert_true(a.p == 3 && b.p == 3 && a.n == b.n);
        assert_memory_equal(a.knots, b.knots, (size_t)(a.n + 4) * sizeof(double));
        assert_true((a.w != NULL) == (a0.w != NULL || b0.w != NULL) && (b.w != NULL) == (a.w != NULL));
        assert_same_curve(&a0, t0_of(&a0), t1_of(&a0), &a, 0, 1, 300, REL * 20);
        assert_same_curve(&b0, t0_of(&b0), t1_of(&b0), &b, 0, 1, 300, REL * 20);
        /* every knot of either input (mapped to [0,1]) is in the result with at least its multiplicity */
        for (int i = a0.p + 1; i < a0.n; i++) {
            double u = (a0.knots[i] - t0_of(&a0)) / (t1_of(&a0) - t0_of(&a0));
            assert_true(mult_near(&a, u, 1e-15) >= mult_at(&a0, a0.knots[i]));
        }
        hcurve_free(&a);
        hcurve_free(&b);
        hcurve_free(&a0);
        hcurve_free(&b0);
    }
    hcurve a = {0}, b = {0};
    random_curve(&a, 2, 5, 0, 1, 1, 1u);
    random_curve(&b, 2, 5, 0, 1, 1, 2u);
    double *ka = a.knots;
    b.w = malloc(5 * sizeof(double));
    assert_non_null(b.w);
    for (int i = 0; i < 5; i++)
        b.w[i] = i == 3 ? -1.0 : 1.0; /* invalid weight */
    assert_err(hcurve_make_compatible(&a, &b, NULL), CM_E_RANGE);
    assert_true(a.knots == ka && a.n == 5 && a.w == NULL);
    assert_err(hcurve_make_compatible(&a, &a, NULL), CM_E_ARG);
    hcurve_free(&a);
    hcurve_free(&b);
}

/* ---- surfaces ---- */

/* Ruled surface between a line and a rational circle arc: rails exact, every ruling straight. */
static void test_ruled_line_arc(void **state)
{
    (void)state;
    const cm_vec3 A = cm_v3(0, 0, -1), B = cm_v3(4, 0, 1), C = cm_v3(0, 3, 2);
    hcurve l = {0}, c = {0};
    hsurf s = {0};
    assert_ok(hcurve_line(A, B, &l, NULL));
    assert_ok(hcurve_ellipse_arc(C, FX, FY, 2, 2, 0, 200 * DEG, &c, NULL));
    assert_ok(hsurf_ruled(&l, &c, &s, NULL));
    assert_true(s.p == 2 && s.q == 1 && s.nv == 2 && s.w != NULL);
    double u0, u1, v0, v1;
    hsurf_domain(&s, &u0, &u1, &v0, &v1);
    assert_true(u0 == 0.0 && u1 == 1.0 && v0 == 0.0 && v1 == 1.0);
    for (int i = 0; i <= 40; i++) {
        double u = i / 40.0;
        cm_vec3 a = cm_lerp(A, B, u), b = cpt(&c, 200 * DEG * u);
        assert_vec_near(spt(&s, u, 0), a, REL * 10);
        assert_vec_near(spt(&s, u, 1), b, REL * 10);
        double prev = -1.0;
        for (int j = 0; j <= 10; j++) {
            cm_vec3 P = spt(&s, u, j / 10.0), ab = cm_sub(b, a);
            double f = cm_dot(cm_sub(P, a), ab) / cm_norm2(ab);
            assert_vec_near(P, cm_add(a, cm_scale(ab, f)), REL * 10); /* on the ruling */
            assert_true(f >= -1e-15 && f <= 1 + 1e-15 && f >= prev);
            prev = f;
        }
    }
    /* the inputs are untouched */
    assert_true(l.p == 1 && l.n == 2 && c.n == 7);
    hcurve_free(&l);
    hcurve_free(&c);
    hsurf_free(&s);
}

/* Polynomial rails: the ruled surface is the linear interpolation exactly. */
static void test_ruled_polynomial(void **state)
{
    (void)state;
    hcurve a = {0}, b = {0};
    hsurf s = {0};
    random_curve(&a, 3, 6, 0, 1, 1, 301u);
    random_curve(&b, 2, 5, 0, 0, 1, 302u); /* unclamped, domain [2, 5] */
    assert_ok(hsurf_ruled(&a, &b, &s, NULL));
    assert_null(s.w);
    for (int i = 0; i <= 30; i++) {
        double u = i / 30.0;
        cm_vec3 pa = cpt(&a, u), pb = cpt(&b, 2 + 3 * u);
        for (int j = 0; j <= 6; j++)
            assert_vec_near(spt(&s, u, j / 6.0), cm_lerp(pa, pb, j / 6.0), REL * 20);
    }
    hcurve empty = {0};
    assert_err(hsurf_ruled(&a, &empty, &s, NULL), CM_E_ARG);
    assert_null(s.ctrl);
    hcurve_free(&a);
    hcurve_free(&b);
}

/* S(u,v) == the generatrix point rotated by the arc angle of v (Rodrigues), everywhere; == v at knots. */
static void check_revolution(const hsurf *s, const hcurve *g, cm_vec3 ap, cm_vec3 ad, double a0, double a1,
                             double tol)
{
    cm_vec3 k = cm_unit(ad);
    double g0 = t0_of(g), g1 = t1_of(g);
    double u0, u1, v0, v1;
    hsurf_domain(s, &u0, &u1, &v0, &v1);
    assert_true(u0 == g0 && u1 == g1 && v0 == a0 && v1 == a1);
    for (int i = 0; i <= 24; i++) {
        double u = g0 + (g1 - g0) * i / 24.0;
        cm_vec3 P = cpt(g, u);
        for (int j = 0; j <= 48; j++) {
            double v = a0 + (a1 - a0) * j / 48.0;
            assert_vec_near(spt(s, u, v), rodrigues(P, ap, k, arc_angle(a0, a1, v)), tol);
        }
        for (int j = 0; j < s->nv + s->q + 1; j++) /* at the knots, the angle is v itself */
            assert_vec_near(spt(s, u, s->V[j]), rodrigues(P, ap, k, s->V[j]), tol);
    }
}

static void test_revolve_line_cylinder_cone(void **state)
{
    (void)state;
    const cm_vec3 ap = cm_v3(1, -2, 0.5), ad = cm_v3(0.3, 0.4, 1.2); /* not unit */
    cm_vec3 k = cm_unit(ad), n = cm_unit(cm_cross(k, cm_v3(1, 0, 0)));
    hcurve g = {0};
    hsurf s = {0};
    /* parallel to the axis at distance 3: a cylinder */
    cm_vec3 P = cm_add(ap, cm_scale(n, 3.0));
    assert_ok(hcurve_line(cm_sub(P, k), cm_add(P, cm_scale(k, 2.0)), &g, NULL));
    assert_ok(hsurf_revolve(&g, ap, ad, 0.4, 2.9, &s, NULL));
    assert_true(s.p == 1 && s.q == 2 && s.nu == 2 && s.nv == 5 && s.w != NULL);
    check_revolution(&s, &g, ap, ad, 0.4, 2.9, REL * 10);
    for (int i = 0; i <= 10; i++) /* distance 3 from the axis everywhere */
        for (int j = 0; j <= 10; j++) {
            cm_vec3 d = cm_sub(spt(&s, i / 10.0, 0.4 + 2.5 * j / 10), ap);
            assert_near(cm_norm(cm_cross(d, k)), 3.0, REL * 10);
        }
    /* full turn */
    assert_ok(hsurf_revolve(&g, ap, ad, 0, 2 * M_PI, &s, NULL));
    assert_int_equal(s.nv, 9);
    check_revolution(&s, &g, ap, ad, 0, 2 * M_PI, REL * 10);
    /* slanted line from a point on the axis: a cone with its apex on the axis */
    assert_ok(hcurve_line(ap, cm_add(P, cm_scale(k, 4.0)), &g, NULL));
    assert_ok(hsurf_revolve(&g, ap, ad, -1.0, 2.0, &s, NULL));
    check_revolution(&s, &g, ap, ad, -1.0, 2.0, REL * 10);
    for (int j = 0; j <= 10; j++)
        assert_vec_near(spt(&s, 0.0, -1.0 + 3.0 * j / 10), ap, REL * 10); /* the apex stays put */
    hcurve_free(&g);
    hsurf_free(&s);
}

/* A circle arc in a plane through the axis, revolved: a torus piece (tube radius r around a circle of radius R). */
static void test_revolve_arc_torus(void **state)
{
    (void)state;
    const cm_vec3 ap = cm_v3(0.5, 0.5, -1), k = FZ;
    const double R = 5.0, r = 1.5;
    cm_vec3 ctr = cm_add(ap, cm_scale(FX, R));
    hcurve g = {0};
    hsurf s = {0};
    assert_ok(hcurve_ellipse_arc(ctr, FX, FZ, r, r, -2.0, 1.5, &g, NULL));
    assert_ok(hsurf_revolve(&g, ap, k, 0.3, 0.3 + 200 * DEG, &s, NULL));
    assert_true(s.p == 2 && s.q == 2 && s.nu == g.n && g.n == 7 && s.nv == 7);
    check_revolution(&s, &g, ap, k, 0.3, 0.3 + 200 * DEG, REL * 20);
    for (int i = 0; i <= 20; i++)
        for (int j = 0; j <= 20; j++) {
            cm_vec3 d = cm_sub(spt(&s, -2.0 + 3.5 * i / 20, 0.3 + 200 * DEG * j / 20), ap);
            double h = cm_dot(d, k), rho = cm_norm(cm_sub(d, cm_scale(k, h)));
            assert_near((rho - R) * (rho - R) + h * h, r * r, REL * 50); /* torus equation */
        }
    /* a rational generatrix on an unclamped knot vector */
    hcurve g2 = {0};
    random_curve(&g2, 3, 7, 1, 0, 1, 77u);
    assert_ok(hsurf_revolve(&g2, ap, cm_v3(1, 1, 0), 1.0, 1.0 + 2 * M_PI, &s, NULL));
    check_revolution(&s, &g2, ap, cm_v3(1, 1, 0), 1.0, 1.0 + 2 * M_PI, REL * 20);
    hcurve_free(&g);
    hcurve_free(&g2);
    hsurf_free(&s);
}

static void test_revolve_errors(void **state)
{
    (void)state;
    hcurve g = {0};
    hsurf s = {0};
    assert_ok(hcurve_line(cm_v3(1, 0, 0), cm_v3(1, 0, 1), &g, NULL));
    assert_err(hsurf_revolve(&g, cm_v3(0, 0, 0), cm_v3(0, 0, 0), 0, 1, &s, NULL), CM_E_DEGENERATE);
    assert_err(hsurf_revolve(&g, cm_v3(0, 0, 0), cm_v3(0, 0, 1), 1, 1, &s, NULL), CM_E_ARG);
    assert_err(hsurf_revolve(&g, cm_v3(0, 0, 0), cm_v3(0, 0, 1), 0, 7, &s, NULL), CM_E_ARG);
    assert_err(hsurf_revolve(&g, cm_v3(nan(""), 0, 0), cm_v3(0, 0, 1), 0, 1, &s, NULL), CM_E_ARG);
    assert_err(hsurf_revolve(NULL, cm_v3(0, 0, 0), cm_v3(0, 0, 1), 0, 1, &s, NULL), CM_E_ARG);
    assert_null(s.ctrl);
    hcurve_free(&g);
}

static void test_extrude_and_plane(void **state)
{
    (void)state;
    hcurve c = {0};
    hsurf s = {0};
    const cm_vec3 d = cm_v3(0.5, -1, 3);
    assert_ok(hcurve_ellipse_arc(cm_v3(1, 2, 3), FX, FY, 2, 1, 0.1, 5.0, &c, NULL));
    assert_ok(hsurf_extrude(&c, d, &s, NULL));
    assert_true(s.q == 1 && s.nu == c.n && s.w != NULL);
    for (int i = 0; i <= 40; i++) {
        double u = 0.1 + 4.9 * i / 40;
        for (int j = 0; j <= 8; j++)
            assert_vec_near(spt(&s, u, j / 8.0), cm_add(cpt(&c, u), cm_scale(d, j / 8.0)), REL * 10);
    }
    assert_err(hsurf_extrude(&c, cm_v3(0, 0, 0), &s, NULL), CM_E_DEGENERATE);
    assert_null(s.ctrl);

    const cm_vec3 o = cm_v3(1, 1, 1), X = cm_v3(2, 0, 1), Y = cm_v3(0, 1, 0.5);
    assert_ok(hsurf_plane(o, X, Y, -1, 3, 2, 2.5, &s, NULL));
    assert_true(s.p == 1 && s.q == 1 && s.nu == 2 && s.nv == 2 && s.w == NULL);
    double u0, u1, v0, v1;
    hsurf_domain(&s, &u0, &u1, &v0, &v1);
    assert_true(u0 == -1 && u1 == 3 && v0 == 2 && v1 == 2.5);
    for (int i = 0; i <= 10; i++)
        for (int j = 0; j <= 10; j++) {
            double u = -1 + 0.4 * i, v = 2 + 0.05 * j;
            assert_vec_near(spt(&s, u, v), cm_add(o, cm_add(cm_scale(X, u), cm_scale(Y, v))), REL * 10);
        }
    assert_err(hsurf_plane(o, X, cm_scale(X, 2), 0, 1, 0, 1, &s, NULL), CM_E_DEGENERATE);
    assert_err(hsurf_plane(o, X, Y, 1, 0, 0, 1, &s, NULL), CM_E_ARG);
    hcurve_free(&c);
    hsurf_free(&s);
}

/* the analytic surfaces of the header, at angles (theta_u, theta_v) */
enum { CYL, CONE, SPHERE, TORUS };

static cm_vec3 analytic(int kind, cm_vec3 o, double r, double R, double semi, double tu, double v)
{
    cm_vec3 ring = cm_add(cm_scale(FX, cos(tu)), cm_scale(FY, sin(tu)));
    switch (kind) {
    case CYL:
        return cm_add(o, cm_add(cm_scale(ring, r), cm_scale(FZ, v)));
    case CONE:
        return cm_add(o, cm_add(cm_scale(ring, r + v * tan(semi)), cm_scale(FZ, v)));
    case SPHERE:
        return cm_add(o, cm_add(cm_scale(ring, r * cos(v)), cm_scale(FZ, r * sin(v))));
    default:
        return cm_add(o, cm_add(cm_scale(ring, R + r * cos(v)), cm_scale(FZ, r * sin(v))));
    }
}

static void check_analytic(const hsurf *s, int kind, cm_vec3 o, double r, double R, double semi, double u0,
                           double u1, double v0, double v1, double tol)
{
    double a0, a1, b0, b1;
    hsurf_domain(s, &a0, &a1, &b0, &b1);
    assert_true(a0 == u0 && a1 == u1 && b0 == v0 && b1 == v1);
    int v_angle = kind == SPHERE || kind == TORUS;
    for (int i = 0; i <= 36; i++) {
        double u = u0 + (u1 - u0) * i / 36, tu = arc_angle(u0, u1, u);
        for (int j = 0; j <= 24; j++) {
            double v = v0 + (v1 - v0) * j / 24, tv = v_angle ? arc_angle(v0, v1, v) : v;
            assert_vec_near(spt(s, u, v), analytic(kind, o, r, R, semi, tu, tv), tol);
        }
    }
    /* at every pair of knots the parameters are the angles (and the linear parameter) themselves */
    for (int i = s->p; i <= s->nu; i++)
        for (int j = s->q; j <= s->nv; j++)
            assert_vec_near(spt(s, s->U[i], s->V[j]), analytic(kind, o, r, R, semi, s->U[i], s->V[j]), tol);
}

static void test_cylinder_cone(void **state)
{
    (void)state;
    const cm_vec3 o = cm_v3(5, -5, 2);
    hsurf s = {0};
    assert_ok(hsurf_cylinder(o, FX, FY, FZ, 2.5, 0, 2 * M_PI, -1, 4, &s, NULL));
    assert_true(s.p == 2 && s.q == 1 && s.nu == 9 && s.nv == 2);
    check_analytic(&s, CYL, o, 2.5, 0, 0, 0, 2 * M_PI, -1, 4, REL * 10);
    assert_ok(hsurf_cylinder(o, FX, FY, FZ, 2.5, 1.0, 1.0 + 100 * DEG, 0.5, 0.75, &s, NULL));
    assert_int_equal(s.nu, 5);
    check_analytic(&s, CYL, o, 2.5, 0, 0, 1.0, 1.0 + 100 * DEG, 0.5, 0.75, REL * 10);
    assert_ok(hsurf_cone(o, FX, FY, FZ, 2.0, 20 * DEG, -0.5, 3.0, -1, 3, &s, NULL));
    check_analytic(&s, CONE, o, 2.0, 0, 20 * DEG, -0.5, 3.0, -1, 3, REL * 10);
    assert_ok(hsurf_cone(o, FX, FY, FZ, 0.0, -30 * DEG, 0, 2 * M_PI, -4, 0, &s, NULL)); /* apex at v = 0 */
    check_analytic(&s, CONE, o, 0.0, 0, -30 * DEG, 0, 2 * M_PI, -4, 0, REL * 10);
    assert_err(hsurf_cylinder(o, FX, FY, FZ, 0.0, 0, 1, 0, 1, &s, NULL), CM_E_ARG);
    assert_null(s.ctrl);
    assert_err(hsurf_cylinder(o, FX, FY, FZ, 1.0, 0, 1, 1, 1, &s, NULL), CM_E_ARG);
    assert_err(hsurf_cylinder(o, FX, FY, FZ, 1.0, 0, 7, 0, 1, &s, NULL), CM_E_ARG);
    assert_err(hsurf_cone(o, FX, FY, FZ, -1.0, 0.1, 0, 1, 0, 1, &s, NULL), CM_E_ARG);
    assert_err(hsurf_cone(o, FX, FY, FZ, 1.0, M_PI / 2, 0, 1, 0, 1, &s, NULL), CM_E_ARG);
    hsurf_free(&s);
}

static void test_sphere_torus(void **state)
{
    (void)state;
    const cm_vec3 o = cm_v3(-1, 2, 3);
    hsurf s = {0};
    assert_ok(hsurf_sphere(o, FX, FY, FZ, 3.0, 0, 2 * M_PI, -M_PI / 2, M_PI / 2, &s, NULL));
    assert_true(s.p == 2 && s.q == 2 && s.nu == 9 && s.nv == 5);
    check_analytic(&s, SPHERE, o, 3.0, 0, 0, 0, 2 * M_PI, -M_PI / 2, M_PI / 2, REL * 10);
    for (int i = 0; i <= 30; i++)
        for (int j = 0; j <= 30; j++)
            assert_near(cm_dist(spt(&s, 2 * M_PI * i / 30, -M_PI / 2 + M_PI * j / 30), o), 3.0, REL * 10);
    assert_vec_near(spt(&s, 1.234, M_PI / 2), cm_add(o, cm_scale(FZ, 3.0)), REL * 10); /* the pole */
    assert_ok(hsurf_sphere(o, FX, FY, FZ, 3.0, 0.5, 2.0, -0.3, 1.2, &s, NULL));
    check_analytic(&s, SPHERE, o, 3.0, 0, 0, 0.5, 2.0, -0.3, 1.2, REL * 10);
    assert_err(hsurf_sphere(o, FX, FY, FZ, 3.0, 0, 1, -2.0, 0, &s, NULL), CM_E_ARG);
    assert_err(hsurf_sphere(o, FX, FY, FZ, 0.0, 0, 1, -1, 0, &s, NULL), CM_E_ARG);

    assert_ok(hsurf_torus(o, FX, FY, FZ, 5.0, 1.5, 0, 2 * M_PI, -M_PI, M_PI, &s, NULL));
    assert_true(s.nu == 9 && s.nv == 9);
    check_analytic(&s, TORUS, o, 1.5, 5.0, 0, 0, 2 * M_PI, -M_PI, M_PI, REL * 10);
    assert_ok(hsurf_torus(o, FX, FY, FZ, 5.0, 1.5, -0.5, 1.0, 0.25, 4.0, &s, NULL));
    check_analytic(&s, TORUS, o, 1.5, 5.0, 0, -0.5, 1.0, 0.25, 4.0, REL * 10);
    assert_err(hsurf_torus(o, FX, FY, FZ, 0.0, 1.5, 0, 1, 0, 1, &s, NULL), CM_E_ARG);
    assert_err(hsurf_torus(o, FX, FY, FZ, 5.0, 1.5, 0, 1, 0, 7, &s, NULL), CM_E_ARG);
    assert_null(s.ctrl);
    hsurf_free(&s);
}

/* Iso-curves of a rational torus piece and of a random polynomial surface equal the surface. */
static void test_iso_curves(void **state)
{
    (void)state;
    hsurf s = {0};
    hcurve c = {0};
    assert_ok(hsurf_torus(cm_v3(1, 2, 3), FX, FY, FZ, 4.0, 1.0, 0.2, 4.0, -1.0, 2.5, &s, NULL));
    for (int pass = 0; pass < 2; pass++) {
        double u0, u1, v0, v1;
        hsurf_domain(&s, &u0, &u1, &v0, &v1);
        for (int i = 0; i <= 12; i++) {
            double u = u0 + (u1 - u0) * i / 12, v = v0 + (v1 - v0) * i / 12;
            assert_ok(hsurf_iso_u(&s, u, &c, NULL));
            assert_true(c.p == s.q && c.n == s.nv && (c.w != NULL) == (s.w != NULL));
            assert_true(t0_of(&c) == v0 && t1_of(&c) == v1);
            for (int j = 0; j <= 20; j++) {
                double t = v0 + (v1 - v0) * j / 20;
                assert_vec_near(cpt(&c, t), spt(&s, u, t), REL * 10);
            }
            assert_ok(hsurf_iso_v(&s, v, &c, NULL));
            assert_true(c.p == s.p && c.n == s.nu && t0_of(&c) == u0 && t1_of(&c) == u1);
            for (int j = 0; j <= 20; j++) {
                double t = u0 + (u1 - u0) * j / 20;
                assert_vec_near(cpt(&c, t), spt(&s, t, v), REL * 10);
            }
        }
        assert_err(hsurf_iso_u(&s, u1 + 0.1, &c, NULL), CM_E_ARG);
        assert_null(c.knots);
        assert_err(hsurf_iso_v(&s, v0 - 0.1, &c, NULL), CM_E_ARG);
        /* second pass: a polynomial bicubic x biquadratic surface on clamped/unclamped knots */
        hsurf_free(&s);
        assert_ok(hsurf_alloc(&s, 3, 2, 6, 5, 0, NULL));
        for (int i = 0; i < 10; i++)
            s.U[i] = i < 4 ? 0.0 : i > 5 ? 1.0 : 0.3 * (i - 3);
        for (int j = 0; j < 8; j++)
            s.V[j] = (double)j;
        uint32_t seed = 9u;
        for (int k = 0; k < 30; k++)
            s.ctrl[k] = test_rand_vec(&seed, 3.0);
    }
    hsurf_free(&s);
    hcurve_free(&c);
}

static void test_closed(void **state)
{
    (void)state;
    const cm_vec3 o = cm_v3(2, 3, 4);
    hsurf s = {0};
    assert_ok(hsurf_cylinder(o, FX, FY, FZ, 2.0, 0.5, 0.5 + 2 * M_PI, 0, 3, &s, NULL));
    assert_int_equal(hsurf_closed_u(&s, 1e-12), 1);
    assert_int_equal(hsurf_closed_v(&s, 1e-12), 0);
    assert_ok(hsurf_cylinder(o, FX, FY, FZ, 2.0, 0, M_PI / 2, 0, 3, &s, NULL));
    assert_int_equal(hsurf_closed_u(&s, 1e-9), 0);
    assert_int_equal(hsurf_closed_v(&s, 1e-9), 0);
    assert_ok(hsurf_torus(o, FX, FY, FZ, 5.0, 1.0, 0, 2 * M_PI, -M_PI, M_PI, &s, NULL));
    assert_int_equal(hsurf_closed_u(&s, 1e-12), 1);
    assert_int_equal(hsurf_closed_v(&s, 1e-12), 1);
    /* the torus seam moved by 1e-6 at one corner: open at tol 1e-9, closed at tol 1e-3 */
    s.ctrl[s.nu * s.nv - 1].x += 1e-6;
    assert_int_equal(hsurf_closed_u(&s, 1e-9), 0);
    assert_int_equal(hsurf_closed_u(&s, 1e-3), 1);
    hsurf empty = {0};
    assert_int_equal(hsurf_closed_u(&empty, 1.0), 0);
    assert_int_equal(hsurf_closed_v(&empty, 1.0), 0);
    hsurf_free(&s);
}

static void test_surface_transform(void **state)
{
    (void)state;
    hsurf s = {0}, t = {0};
    assert_ok(hsurf_sphere(cm_v3(1, 0, 0), FX, FY, FZ, 2.0, 0.3, 5.0, -1.0, 1.4, &s, NULL));
    assert_ok(hsurf_copy(&s, &t, NULL));
    haffine m = test_map();
    hsurf_transform(&t, &m);
    for (int i = 0; i <= 20; i++)
        for (int j = 0; j <= 20; j++) {
            double u = 0.3 + 4.7 * i / 20, v = -1.0 + 2.4 * j / 20;
            assert_vec_near(spt(&t, u, v), haffine_apply(&m, spt(&s, u, v)), REL * 20);
        }
    assert_memory_equal(t.w, s.w, (size_t)(s.nu * s.nv) * sizeof(double));
    hsurf_transform(NULL, &m);
    hsurf_free(&s);
    hsurf_free(&t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_alloc_copy_free),
        cmocka_unit_test(test_alloc_failure_injection),
        cmocka_unit_test(test_line_and_polyline),
        cmocka_unit_test(test_ellipse_arc_sweeps),
        cmocka_unit_test(test_circle_arc_far_from_origin),
        cmocka_unit_test(test_ellipse_arc_errors),
        cmocka_unit_test(test_conic_parabola),
        cmocka_unit_test(test_conic_hyperbola),
        cmocka_unit_test(test_conic_ellipse),
        cmocka_unit_test(test_cubic_segments),
        cmocka_unit_test(test_affine_helpers),
        cmocka_unit_test(test_curve_transform),
        cmocka_unit_test(test_reverse),
        cmocka_unit_test(test_reparam),
        cmocka_unit_test(test_subrange_clamped),
        cmocka_unit_test(test_subrange_unclamped),
        cmocka_unit_test(test_subrange_errors),
        cmocka_unit_test(test_large_curve),
        cmocka_unit_test(test_clamp),
        cmocka_unit_test(test_elevate_polyline_1_to_3),
        cmocka_unit_test(test_elevate_2_to_5),
        cmocka_unit_test(test_elevate_special),
        cmocka_unit_test(test_make_compatible_line_arc),
        cmocka_unit_test(test_make_compatible_random),
        cmocka_unit_test(test_ruled_line_arc),
        cmocka_unit_test(test_ruled_polynomial),
        cmocka_unit_test(test_revolve_line_cylinder_cone),
        cmocka_unit_test(test_revolve_arc_torus),
        cmocka_unit_test(test_revolve_errors),
        cmocka_unit_test(test_extrude_and_plane),
        cmocka_unit_test(test_cylinder_cone),
        cmocka_unit_test(test_sphere_torus),
        cmocka_unit_test(test_iso_curves),
        cmocka_unit_test(test_closed),
        cmocka_unit_test(test_surface_transform),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
