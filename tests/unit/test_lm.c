/* test_lm.c - the Levenberg-Marquardt driver of the closest-point searches (cm_lm.h). */
#include "test_util.h"

#include "cm/cm_lm.h"

/* a paraboloid S(u,v) = (u, v, a (u^2 + v^2)) with its partials */
static void parab(double a, double u, double v, cm_vec3 d[3])
{
    d[0] = cm_v3(u, v, a * (u * u + v * v));
    d[1] = cm_v3(1.0, 0.0, 2.0 * a * u);
    d[2] = cm_v3(0.0, 1.0, 2.0 * a * v);
}

static const cm_lm2_opts opts = {
    .max_steps = 50,
    .mu0 = 1e-3,
    .mu_factor = 10.0,
    .mu_min = 1e-12,
    .mu_max = 1e6,
    .step_min = 1e-12,
    .accept_equal = 0,
};

static int run(const cm_lm2_opts *o, const cm_lm2_box *box, double a, cm_vec3 P, double *u, double *v, double *f)
{
    cm_vec3 d[3];
    cm_lm2 lm;
    parab(a, *u, *v, d);
    cm_lm2_start(&lm, o, box, P, *u, *v, d);
    while (cm_lm2_next(&lm)) {
        parab(a, lm.un, lm.vn, d);
        cm_lm2_take(&lm, d);
    }
    *u = lm.u;
    *v = lm.v;
    *f = lm.f;
    return lm.steps;
}

/* A point above the paraboloid's vertex region projects onto its foot: the gradient of f vanishes there. */
static void test_converges(void **state)
{
    (void)state;
    cm_lm2_box box = {-2, 2, -2, 2, CM_LM_CLAMP_LOW, CM_LM_CLAMP_LOW};
    for (int k = 0; k < 8; k++) {
        double a = 0.3, u = -1.5 + 0.3 * k, v = 1.0 - 0.2 * k, f;
        cm_vec3 P = cm_v3(0.2 * k - 0.7, 0.4, -0.5);
        int steps = run(&opts, &box, a, P, &u, &v, &f);
        assert_true(steps >= 1 && steps <= opts.max_steps);
        cm_vec3 d[3];
        parab(a, u, v, d);
        cm_vec3 r = cm_sub(d[0], P);
        /* a stationary point of |S - P|^2, to the sqrt of rounding (f is flat to 1e-16 within 1e-8 of it) */
        assert_near(cm_dot(r, d[1]), 0.0, 1e-7);
        assert_near(cm_dot(r, d[2]), 0.0, 1e-7);
        assert_near(f, cm_norm2(r), 0.0);
    }
}

/* Proposals are kept in the box: a point far outside ends at the corner. */
static void test_clamped_to_box(void **state)
{
    (void)state;
    cm_lm2_box box = {0, 1, 0, 1, CM_LM_CLAMP, CM_LM_CLAMP};
    double u = 0.5, v = 0.5, f;
    run(&opts, &box, 0.0, cm_v3(5, 7, 0), &u, &v, &f);
    assert_true(u == 1.0 && v == 1.0);
    assert_near(f, 16.0 + 36.0, 0.0);
    /* a free direction goes past the box */
    box.bound_u = CM_LM_FREE;
    u = 0.5;
    v = 0.5;
    run(&opts, &box, 0.0, cm_v3(5, 7, 0), &u, &v, &f);
    assert_near(u, 5.0, 1e-9);
    assert_true(v == 1.0);
}

/* A surface whose partials vanish has no descent direction: nothing is proposed. */
static void test_flat_ends_at_once(void **state)
{
    (void)state;
    cm_lm2_box box = {0, 1, 0, 1, CM_LM_CLAMP, CM_LM_CLAMP};
    cm_vec3 d[3] = {{1, 2, 3}, {0, 0, 0}, {0, 0, 0}};
    cm_lm2 lm;
    cm_lm2_start(&lm, &opts, &box, cm_v3(0, 0, 0), 0.25, 0.75, d);
    assert_int_equal(cm_lm2_next(&lm), 0);
    assert_true(lm.u == 0.25 && lm.v == 0.75);
    assert_near(lm.f, 14.0, 0.0);
}

/* Every proposal refused: mu grows by mu_factor until it passes mu_max; the start is kept. */
static void test_refusals_raise_mu(void **state)
{
    (void)state;
    cm_lm2_box box = {0, 1, 0, 1, CM_LM_FREE, CM_LM_FREE};
    cm_lm2_opts o = opts;
    o.step_min = 0.0;
    cm_vec3 d[3];
    parab(0.0, 0.5, 0.5, d);
    cm_vec3 far[3] = {{100, 100, 100}, {1, 0, 0}, {0, 1, 0}};
    cm_lm2 lm;
    cm_lm2_start(&lm, &o, &box, cm_v3(0.7, 0.1, 0.0), 0.5, 0.5, d);
    int n = 0;
    while (cm_lm2_next(&lm)) {
        cm_lm2_take(&lm, far);
        n++;
    }
    int expect = 0; /* about 10: 1e-3 * 10^10 is the first value above 1e6 */
    for (double mu = o.mu0; !(mu > o.mu_max); mu *= o.mu_factor)
        expect++;
    assert_int_equal(n, expect);
    assert_true(lm.u == 0.5 && lm.v == 0.5);
    /* an equal distance is taken only with accept_equal */
    for (int eq = 0; eq < 2; eq++) {
        o.accept_equal = eq;
        o.max_steps = 1;
        cm_lm2_start(&lm, &o, &box, cm_v3(0.7, 0.1, 0.0), 0.5, 0.5, d);
        assert_int_equal(cm_lm2_next(&lm), 1);
        cm_lm2_take(&lm, d); /* the same distance as the start */
        assert_int_equal(cm_lm2_next(&lm), 0);
        assert_true(eq ? lm.u == lm.un && lm.u != 0.5 : lm.u == 0.5);
    }
}

/* The two clamps differ only on NaN and on a zero of the other sign at lo. */
static void test_bounds(void **state)
{
    (void)state;
    assert_true(cm_lm_bound_apply(-1.0, CM_LM_CLAMP, 0.0, 1.0) == 0.0);
    assert_true(cm_lm_bound_apply(2.0, CM_LM_CLAMP_LOW, 0.0, 1.0) == 1.0);
    assert_true(cm_lm_bound_apply(7.0, CM_LM_FREE, 0.0, 1.0) == 7.0);
    assert_true(isnan(cm_lm_bound_apply(nan(""), CM_LM_CLAMP, 0.0, 1.0)));
    assert_true(cm_lm_bound_apply(nan(""), CM_LM_CLAMP_LOW, 0.0, 1.0) == 0.0);
    assert_true(signbit(cm_lm_bound_apply(-0.0, CM_LM_CLAMP, 0.0, 1.0)));
    assert_false(signbit(cm_lm_bound_apply(-0.0, CM_LM_CLAMP_LOW, 0.0, 1.0)));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_converges),
        cmocka_unit_test(test_clamped_to_box),
        cmocka_unit_test(test_flat_ends_at_once),
        cmocka_unit_test(test_refusals_raise_mu),
        cmocka_unit_test(test_bounds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
