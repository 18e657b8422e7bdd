/* test_bezier.c - K4: cubic evaluation, split, elevation (T10 for splits). */
#include "test_util.h"

#include "cm/cm_bezier.h"
#include "cm/cm_limits_info.h"

static cm_cubic rand_cubic(uint32_t *seed)
{
    cm_cubic c;
    for (int i = 0; i < 4; i++)
        c.c[i] = test_rand_vec(seed, 10.0);
    return c;
}

/* de Casteljau reference: the slow, obviously correct evaluator */
static cm_vec3 decasteljau(const cm_vec3 *P, int p, double t)
{
    cm_vec3 tmp[16];
    for (int i = 0; i <= p; i++)
        tmp[i] = P[i];
    for (int k = 1; k <= p; k++)
        for (int i = 0; i <= p - k; i++)
            tmp[i] = cm_lerp(tmp[i], tmp[i + 1], t);
    return tmp[0];
}

/* Bézier-as-B-spline equals de Casteljau; the Bernstein derivatives equal the B-spline ones. */
static void test_cubic_eval_matches_bspline(void **state)
{
    (void)state;
    uint32_t seed = 3;
    for (int n = 0; n < 10; n++) {
        cm_cubic c = rand_cubic(&seed);
        cm_curve v = cm_cubic_as_curve(&c);
        for (int k = 0; k <= 20; k++) {
            double t = k / 20.0;
            cm_vec3 a[3], b[3];
            cm_cubic_eval(&c, t, a);
            assert_ok(cm_curve_eval(&v, t, 2, b, NULL));
            assert_vec_near(a[0], decasteljau(c.c, 3, t), 1e-13);
            assert_vec_near(a[0], b[0], 1e-13);
            assert_vec_near(a[1], b[1], 1e-12);
            assert_vec_near(a[2], b[2], 1e-11);
        }
    }
}

/* T10: split at 1/2 (and elsewhere) reproduces the cubic at 101 parameters, <= 1e-15 relative. */
static void test_cubic_split_reproduces(void **state)
{
    (void)state;
    uint32_t seed = 5;
    const double cuts[3] = {0.5, 0.3, 0.9};
    for (int n = 0; n < 3; n++) {
        cm_cubic c = rand_cubic(&seed), a, b;
        double t0 = cuts[n];
        cm_cubic_split(&c, t0, &a, &b);
        for (int k = 0; k <= 100; k++) {
            double t = k / 100.0;
            cm_vec3 x[3], y[3];
            cm_cubic_eval(&c, t, x);
            if (t <= t0)
                cm_cubic_eval(&a, t / t0, y);
            else
                cm_cubic_eval(&b, (t - t0) / (1 - t0), y);
            assert_vec_near(x[0], y[0], 1e-15 * 10 * 4); /* relative to the control scale 10, a few ulps */
        }
        assert_vec_near(a.c[3], b.c[0], 0);
    }
}

static void test_general_split_and_elevate(void **state)
{
    (void)state;
    uint32_t seed = 9;
    /* degree 5 elevated to 8 where the profile allows, else 2 to CM_MAX_DEGREE */
    const int p = CM_MAX_DEGREE >= 8 ? 5 : 2, t = CM_MAX_DEGREE >= 8 ? 3 : CM_MAX_DEGREE - 2;
    cm_vec3 P[6], L[6], R[6], E[9];
    for (int i = 0; i <= p; i++)
        P[i] = test_rand_vec(&seed, 2.0);
    assert_ok(cm_bez_split(P, p, 0.25, L, R, NULL));
    assert_ok(cm_bez_elevate(P, p, t, E, NULL));
    for (int k = 0; k <= 40; k++) {
        double s = k / 40.0;
        cm_vec3 x = decasteljau(P, p, s);
        cm_vec3 y = s <= 0.25 ? decasteljau(L, p, s / 0.25) : decasteljau(R, p, (s - 0.25) / 0.75);
        assert_vec_near(x, y, 1e-14);
        assert_vec_near(x, decasteljau(E, p + t, s), 1e-14); /* elevation keeps the curve */
    }
    /* end points are kept exactly */
    assert_vec_near(E[0], P[0], 0);
    assert_vec_near(E[p + t], P[p], 0);
}

/* K4 special cases: line -> thirds, quadratic -> the same as general elevation. */
static void test_line_and_quadratic_to_cubic(void **state)
{
    (void)state;
    cm_vec3 A = {0, 0, 0}, B = {3, 6, 9};
    cm_cubic l = cm_cubic_from_line(A, B);
    assert_vec_near(l.c[1], cm_v3(1, 2, 3), 1e-15);
    assert_vec_near(l.c[2], cm_v3(2, 4, 6), 1e-15);
    cm_vec3 Q[3] = {{0, 0, 0}, {1, 2, 0}, {2, 0, 1}}, E[4];
    cm_cubic q = cm_cubic_from_quad(Q[0], Q[1], Q[2]);
    assert_ok(cm_bez_elevate(Q, 2, 1, E, NULL));
    for (int i = 0; i < 4; i++)
        assert_vec_near(q.c[i], E[i], 1e-15);
    cm_cubic r = cm_cubic_reverse(&q);
    cm_vec3 x[3], y[3];
    cm_cubic_eval(&q, 0.3, x);
    cm_cubic_eval(&r, 0.7, y);
    assert_vec_near(x[0], y[0], 1e-15);
    assert_vec_near(x[1], cm_neg(y[1]), 1e-14);
}

static void test_bezier_limits(void **state)
{
    (void)state;
    cm_vec3 P[CM_MAX_ORDER + 1], Q[CM_MAX_ORDER + 2], R[CM_MAX_ORDER + 2];
    for (int i = 0; i <= CM_MAX_ORDER; i++)
        P[i] = cm_v3(i, 0, 0);
    cm_status st;
    cm_status_init(&st);
    assert_err(cm_bez_elevate(P, CM_MAX_DEGREE, 1, Q, &st), CM_E_LIMIT);
    assert_int_equal(st.limit, CM_LIMIT_MAX_DEGREE);
    assert_int_equal(st.need, CM_MAX_DEGREE + 1);
    assert_err(cm_bez_split(P, CM_MAX_DEGREE + 1, 0.5, Q, R, NULL), CM_E_LIMIT);
    assert_ok(cm_bez_split(P, CM_MAX_DEGREE, 0.5, Q, R, NULL)); /* at the limit: fine */
    assert_vec_near(Q[CM_MAX_DEGREE], R[0], 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cubic_eval_matches_bspline),
        cmocka_unit_test(test_cubic_split_reproduces),
        cmocka_unit_test(test_general_split_and_elevate),
        cmocka_unit_test(test_line_and_quadratic_to_cubic),
        cmocka_unit_test(test_bezier_limits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
