/* test_arc.c - format 4.4's arcs: cm_arc_nurbs against exact circles, its pieces, its refusals. */
#include "test_util.h"

#include "cm/cm_arc.h"
#include "cm/cm_bspline.h"

/* a circle of radius r about c in the plane of the unit vectors a, b (a tilted plane, far from the
   origin: the digits a real part's coordinates have) */
typedef struct circle {
    cm_vec3 c, a, b;
    double r;
} circle;

static circle tilted(double r)
{
    cm_vec3 a = cm_unit(cm_v3(1, 2, 2)), b = cm_unit(cm_cross(cm_v3(0, 0, 1), a));
    circle k = {cm_v3(1234.5, -987.25, 431.0), a, b, r};
    return k;
}

static cm_vec3 at(const circle *k, double deg)
{
    double t = deg * M_PI / 180.0;
    return cm_add(k->c, cm_add(cm_scale(k->a, k->r * cos(t)), cm_scale(k->b, k->r * sin(t))));
}

/* the angle (degrees, in [0, 360)) of p about the circle */
static double angle(const circle *k, cm_vec3 p)
{
    cm_vec3 d = cm_sub(p, k->c);
    double t = atan2(cm_dot(d, k->b), cm_dot(d, k->a)) * 180.0 / M_PI;
    return t < 0 ? t + 360.0 : t;
}

/* Arcs of 10 to 359 degrees: the pieces A7.1 takes (at most 90 degrees each), the ends bit for bit,
   every point on the circle and in its plane, running forward, through the middle point at t = 1/2,
   the end tangents along the circle's, and tangent where the pieces meet. */
static void test_arc_is_the_circle(void **state)
{
    (void)state;
    const double sweeps[] = {10, 45, 89.9, 90, 90.1, 135, 179.9, 180, 180.1, 240, 270, 300, 359};
    circle k = tilted(7.0);
    for (size_t s = 0; s < sizeof sweeps / sizeof sweeps[0]; s++) {
        double sw = sweeps[s], start = 20.0;
        cm_vec3 p0 = at(&k, start), q = at(&k, start + sw / 2), p2 = at(&k, start + sw);
        cm_vec3 P[CM_ARC_MAX_CTRL];
        double W[CM_ARC_MAX_CTRL], K[CM_ARC_MAX_KNOTS];
        int n = -1;
        assert_ok(cm_arc_nurbs(p0, q, p2, P, W, K, &n, NULL));
        int want = sw <= 90.0 - 1e-9 ? 3 : (sw <= 180.0 - 1e-9 ? 5 : 9);
        if (sw == 90.0 || sw == 180.0)
            assert_true(n == want || n == (sw == 90.0 ? 5 : 9)); /* at the bound, rounding decides */
        else
            assert_int_equal(n, want);
        assert_memory_equal(&P[0], &p0, sizeof p0);
        assert_memory_equal(&P[n - 1], &p2, sizeof p2);
        cm_curve c = {2, n, K, P, W};
        if (n <= CM_MAX_EDGE_CTRL) /* the tiny profile takes arcs of up to two pieces */
            assert_ok(cm_curve_check(&c, NULL));
        double prev = -1;
        for (int i = 0; i <= 400; i++) {
            cm_vec3 d[2];
            assert_ok(cm_curve_eval(&c, i / 400.0, 1, d, NULL));
            /* coordinates of size 1e3 carry about 1e-13; the construction divides by 1 + w, which
               near a full circle is small (3e-4 at 359 degrees) */
            double tol = sw < 300 ? 1e-10 : 1e-8;
            if (!(fabs(cm_dist(d[0], k.c) - k.r) <= tol))
                fail_msg("sweep %g, t %g: off the circle by %g", sw, i / 400.0, fabs(cm_dist(d[0], k.c) - k.r));
            double off = fabs(cm_dot(cm_sub(d[0], k.c), cm_cross(k.a, k.b)));
            if (!(off <= tol))
                fail_msg("sweep %g, t %g: off the plane by %g", sw, i / 400.0, off);
            double a = angle(&k, d[0]) - start;
            a = a < -1e-6 ? a + 360.0 : a;
            assert_true(a >= prev - 1e-9 && a <= sw + 1e-6);
            prev = a;
            /* the tangent along the circle, forward */
            cm_vec3 along = cm_cross(cm_cross(k.a, k.b), cm_sub(d[0], k.c));
            assert_near(cm_dot(cm_unit(d[1]), cm_unit(along)), 1.0, 1e-9);
        }
        cm_vec3 mid;
        assert_ok(cm_curve_eval(&c, 0.5, 0, &mid, NULL));
        assert_vec_near(mid, q, sw < 300 ? 1e-10 : 1e-8);
    }
}

/* A middle point off the circle (on the coordinate grid, a step away) moves the arc by about as
   much: the conic through the three points stays within twice the offset of the circle. */
static void test_arc_off_by_a_step(void **state)
{
    (void)state;
    circle k = tilted(25.0);
    const double step = 1e-3, sweeps[] = {60, 170, 200, 330};
    for (size_t s = 0; s < sizeof sweeps / sizeof sweeps[0]; s++) {
        cm_vec3 p0 = at(&k, 0), q = cm_add(at(&k, sweeps[s] / 2), cm_v3(0.5 * step, -0.5 * step, 0.5 * step)),
                p2 = at(&k, sweeps[s]);
        cm_vec3 P[CM_ARC_MAX_CTRL];
        double W[CM_ARC_MAX_CTRL], K[CM_ARC_MAX_KNOTS];
        int n;
        assert_ok(cm_arc_nurbs(p0, q, p2, P, W, K, &n, NULL));
        cm_curve c = {2, n, K, P, W};
        double worst = 0;
        for (int i = 0; i <= 200; i++) {
            cm_vec3 x;
            assert_ok(cm_curve_eval(&c, i / 200.0, 0, &x, NULL));
            worst = fmax(worst, fabs(cm_dist(x, k.c) - k.r));
        }
        assert_true(worst > 0);
        assert_true(worst <= 2.0 * 0.8660254 * step);
    }
}

/* What no arc is: coincident ends, a full circle or nearly (the middle point far beyond a short
   chord), points that are not finite; a middle point on the chord is its straight segment.  What
   no full circle is: one whose far point is its vertex, or whose halves are nearly full circles. */
static void test_arc_refusals(void **state)
{
    (void)state;
    cm_vec3 P[CM_ARC_MAX_CTRL];
    double W[CM_ARC_MAX_CTRL], K[CM_ARC_MAX_KNOTS];
    int n;
    cm_status st;
    cm_status_init(&st);
    assert_int_equal(cm_arc_nurbs(cm_v3(1, 2, 3), cm_v3(4, 5, 6), cm_v3(1, 2, 3), P, W, K, &n, &st), CM_E_DEGENERATE);
    assert_string_equal(st.where, "arc with coincident ends");
    assert_int_equal(n, 0);
    cm_status_init(&st);
    assert_int_equal(cm_arc_nurbs(cm_v3(0, 0, 0), cm_v3(0, 1e4, 0), cm_v3(1e-1, 0, 0), P, W, K, &n, &st),
                     CM_E_DEGENERATE);
    assert_string_equal(st.where, "arc of a full circle");
    cm_status_init(&st);
    assert_int_equal(cm_arc_nurbs(cm_v3(0, 0, 0), cm_v3((double)NAN, 0, 0), cm_v3(1, 0, 0), P, W, K, &n, &st), CM_E_NONFINITE);
    assert_int_equal(cm_arc_nurbs(cm_v3(0, 0, 0), cm_v3(0, 0, 0), cm_v3((double)INFINITY, 0, 0), P, W, K, &n, NULL),
                     CM_E_NONFINITE);
    /* 359.8 degrees still builds, its weights positive */
    circle k = tilted(1.0);
    assert_ok(cm_arc_nurbs(at(&k, 0), at(&k, 179.9), at(&k, 359.8), P, W, K, &n, NULL));
    assert_int_equal(n, 9);
    for (int i = 0; i < n; i++)
        assert_true(W[i] > 0);
    /* the chord's own midpoint: the segment, weight 1 */
    assert_ok(cm_arc_nurbs(cm_v3(0, 0, 0), cm_v3(1, 1, 1), cm_v3(2, 2, 2), P, W, K, &n, NULL));
    assert_int_equal(n, 3);
    assert_vec_near(P[1], cm_v3(1, 1, 1), 0);
    assert_near(W[1], 1.0, 0);
    /* a circle whose far point is its vertex; not finite; each half nearly a full circle */
    cm_status_init(&st);
    assert_int_equal(cm_circle_nurbs(cm_v3(1, 0, 0), cm_v3(0, 1, 0), cm_v3(1, 0, 0), P, W, K, &n, &st), CM_E_DEGENERATE);
    assert_string_equal(st.where, "circle whose far point is its vertex");
    assert_int_equal(cm_circle_nurbs(cm_v3(1, 0, 0), cm_v3(0, 1, 0), cm_v3((double)NAN, 0, 0), P, W, K, &n, NULL),
                     CM_E_NONFINITE);
    /* the halfway point far beyond a short diameter: each half nearly a full circle */
    cm_status_init(&st);
    assert_int_equal(cm_circle_nurbs(cm_v3(0, 0, 0), cm_v3(0, 1e4, 0), cm_v3(1e-1, 0, 0), P, W, K, &n, &st),
                     CM_E_DEGENERATE);
    assert_string_equal(st.where, "arc of a full circle");
}

/* Full circles (closed edges) from their vertex, the point halfway round and the point across:
   on the circle, through those points at t = 1/4 and 1/2, closed bit for bit, forward. */
static void test_full_circle(void **state)
{
    (void)state;
    circle k = tilted(3.0);
    for (int start = 0; start < 360; start += 50) {
        cm_vec3 p0 = at(&k, start), r = at(&k, start + 90), q = at(&k, start + 180);
        cm_vec3 P[CM_ARC_MAX_CTRL];
        double W[CM_ARC_MAX_CTRL], K[CM_ARC_MAX_KNOTS];
        int n = -1;
        assert_ok(cm_circle_nurbs(p0, r, q, P, W, K, &n, NULL));
        assert_int_equal(n, 9);
        assert_memory_equal(&P[0], &p0, sizeof p0);
        assert_memory_equal(&P[8], &p0, sizeof p0);
        assert_near(K[3], 0.25, 0);
        assert_near(K[6], 0.5, 0);
        cm_curve c = {2, n, K, P, W};
        if (n <= CM_MAX_EDGE_CTRL)
            assert_ok(cm_curve_check(&c, NULL));
        double prev = -1;
        for (int i = 0; i <= 400; i++) {
            cm_vec3 x;
            assert_ok(cm_curve_eval(&c, i / 400.0, 0, &x, NULL));
            assert_near(cm_dist(x, k.c), k.r, 1e-10);
            double a = angle(&k, x) - start;
            a = a < -1e-6 ? a + 360.0 : a;
            if (i == 400)
                a = 360.0; /* back at the start */
            assert_true(a >= prev - 1e-9);
            prev = a;
        }
        cm_vec3 x;
        assert_ok(cm_curve_eval(&c, 0.25, 0, &x, NULL));
        assert_vec_near(x, r, 1e-10);
        assert_ok(cm_curve_eval(&c, 0.5, 0, &x, NULL));
        assert_vec_near(x, q, 1e-10);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_arc_is_the_circle),
        cmocka_unit_test(test_arc_off_by_a_step),
        cmocka_unit_test(test_arc_refusals),
        cmocka_unit_test(test_full_circle),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
