/* test_cubic_convert.c - K7 cubic edge conversion: exact cases, circular arcs (spec T4 values). */
#include "test_util.h"

#include "cm/cm_cubic_convert.h"

/* One rational quadratic span for an arc of angle phi < 180 deg in the xy plane, radius R. */
typedef struct arc {
    cm_vec3 P[5];
    double w[5], U[8];
    cm_curve c;
} arc;

static void make_arc(arc *a, double R, double phi)
{
    double h = phi / 2;
    a->P[0] = cm_v3(R, 0, 0);
    a->P[1] = cm_v3(R, R * tan(h), 0);
    a->P[2] = cm_v3(R * cos(phi), R * sin(phi), 0);
    a->w[0] = 1;
    a->w[1] = cos(h);
    a->w[2] = 1;
    const double U[6] = {0, 0, 0, 1, 1, 1};
    memcpy(a->U, U, sizeof U);
    cm_curve c = {2, 3, a->U, a->P, a->w};
    a->c = c;
}

/* A half circle as two rational quadratic spans (a single span cannot reach 180 deg). */
static void make_half_circle(arc *a, double R)
{
    const double s = TEST_SQRT1_2;
    const cm_vec3 P[5] = {{R, 0, 0}, {R, R, 0}, {0, R, 0}, {-R, R, 0}, {-R, 0, 0}};
    const double w[5] = {1, s, 1, s, 1}, U[8] = {0, 0, 0, 0.5, 0.5, 1, 1, 1};
    memcpy(a->P, P, sizeof P);
    memcpy(a->w, w, sizeof w);
    memcpy(a->U, U, sizeof U);
    cm_curve c = {2, 5, a->U, a->P, a->w};
    a->c = c;
}

/* max | |B(t)| - R | over 2001 points of the cubic */
static double radial_error(const cm_cubic *cu, double R)
{
    double e = 0.0;
    for (int k = 0; k <= 2000; k++) {
        cm_vec3 d[3];
        cm_cubic_eval(cu, k / 2000.0, d);
        e = fmax(e, fabs(cm_norm(d[0]) - R));
    }
    return e;
}

/* T4 (K7 part): 90 deg arc, R = 10: alpha/R in [0.5505, 0.5530], radial error <= 2.5e-4 R. */
static void test_quarter_arc(void **state)
{
    (void)state;
    arc a;
    make_arc(&a, 10.0, M_PI / 2);
    cm_cubic cu;
    double delta;
    int exact;
    assert_ok(cm_cubic_convert(&a.c, 0, 1, &cu, &delta, &exact, NULL));
    assert_int_equal(exact, 0);
    double alpha = cm_dist(cu.c[1], cu.c[0]) / 10.0, beta = cm_dist(cu.c[2], cu.c[3]) / 10.0;
    assert_in_range((long)(alpha * 1e5), 55050, 55300);
    assert_near(alpha, beta, 1e-9); /* symmetric arc, symmetric handles */
    double err = radial_error(&cu, 10.0);
    assert_true(err <= 2.5e-4 * 10.0);
    assert_true(delta <= 2.5e-4 * 10.0 && delta > 0.0);
    /* the end points and tangents are kept */
    assert_vec_near(cu.c[0], a.P[0], 1e-14);
    assert_vec_near(cu.c[3], a.P[2], 1e-14);
    assert_near(cu.c[1].x, 10.0, 1e-13);
}

/* Wider arcs: spec prototype errors 1.2e-3 R (120 deg) and 1.4e-2 R (180 deg); we allow +25 %. */
static void test_wide_arcs(void **state)
{
    (void)state;
    arc a;
    cm_cubic cu;
    double delta;
    make_arc(&a, 1.0, 2 * M_PI / 3);
    assert_ok(cm_cubic_convert(&a.c, 0, 1, &cu, &delta, NULL, NULL));
    double e120 = radial_error(&cu, 1.0);
    assert_true(e120 <= 1.25 * 1.2e-3 && e120 >= 0.5 * 1.2e-3);
    make_half_circle(&a, 1.0);
    assert_ok(cm_cubic_convert(&a.c, 0, 1, &cu, &delta, NULL, NULL));
    double e180 = radial_error(&cu, 1.0);
    assert_true(e180 <= 1.25 * 1.4e-2 && e180 >= 0.5 * 1.4e-2);
    assert_true(delta > 1e-3); /* a half circle fails the 0.25 tol_F gate of most faces */
}

/* Case 1: a single polynomial span of degree <= 3 converts exactly, also on a sub-range. */
static void test_exact_cases(void **state)
{
    (void)state;
    const double U2[6] = {0, 0, 0, 2, 2, 2}, U1[4] = {5, 5, 6, 6};
    cm_vec3 Q[3] = {{0, 0, 0}, {1, 2, 0}, {2, 0, 1}}, L[2] = {{0, 0, 0}, {3, 3, 3}};
    cm_curve q = {2, 3, U2, Q, NULL}, l = {1, 2, U1, L, NULL};
    cm_cubic cu;
    double delta;
    int exact;
    assert_ok(cm_cubic_convert(&l, 5, 6, &cu, &delta, &exact, NULL));
    assert_int_equal(exact, 1);
    assert_true(delta == 0.0);
    assert_vec_near(cu.c[1], cm_v3(1, 1, 1), 1e-15);
    assert_ok(cm_cubic_convert(&q, 0.5, 1.5, &cu, &delta, &exact, NULL));
    assert_int_equal(exact, 1);
    for (int k = 0; k <= 20; k++) {
        double s = k / 20.0;
        cm_vec3 a[3], b[3];
        cm_cubic_eval(&cu, s, a);
        assert_ok(cm_curve_eval(&q, 0.5 + s, 0, b, NULL));
        assert_vec_near(a[0], b[0], 1e-15 * 4);
    }
}

static void test_convert_errors(void **state)
{
    (void)state;
    const double U[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    const double Uq[7] = {0, 0, 0, 0.5, 1, 1, 1};
    cm_vec3 same[4] = {{1, 1, 1}, {1, 1, 1}, {1, 1, 1}, {1, 1, 1}};
    cm_curve pt = {3, 4, U, same, NULL};
    cm_curve pt2 = {2, 4, Uq, same, NULL}; /* two spans: goes through the fitting path */
    cm_cubic cu;
    assert_err(cm_cubic_convert(&pt, 1, 0, &cu, NULL, NULL, NULL), CM_E_ARG);
    assert_ok(cm_cubic_convert(&pt, 0, 1, &cu, NULL, NULL, NULL)); /* exact path: a point is a cubic */
    assert_err(cm_cubic_convert(&pt2, 0, 1, &cu, NULL, NULL, NULL), CM_E_DEGENERATE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quarter_arc),
        cmocka_unit_test(test_wide_arcs),
        cmocka_unit_test(test_exact_cases),
        cmocka_unit_test(test_convert_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
