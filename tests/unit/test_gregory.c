/* test_gregory.c - the bicubic Gregory patch of spec §6.1 (T2, exact derivatives, corners). */
#include "test_util.h"

#include "cm/cm_bezier.h"
#include "cm/cm_gregory.h"

static void rand_net(uint32_t *seed, cm_vec3 B[4][4])
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            B[i][j] = cm_add(cm_v3(i, j, 0), test_rand_vec(seed, 0.4));
}

/* Gregory patch whose interior pairs both equal the Bézier interior points */
static cm_gregory compatible(cm_vec3 B[4][4])
{
    cm_gregory g;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            g.P[i][j] = B[i][j];
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++)
            g.I[a][b][0] = g.I[a][b][1] = B[a + 1][b + 1];
    return g;
}

static void bezier_patch(cm_vec3 B[4][4], double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv)
{
    double Bu[4], dBu[4], Bv[4], dBv[4];
    cm_bernstein3(u, Bu, dBu);
    cm_bernstein3(v, Bv, dBv);
    *S = *Su = *Sv = cm_v3(0, 0, 0);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            *S = cm_axpy(*S, Bu[i] * Bv[j], B[i][j]);
            *Su = cm_axpy(*Su, dBu[i] * Bv[j], B[i][j]);
            *Sv = cm_axpy(*Sv, Bu[i] * dBv[j], B[i][j]);
        }
}

/* T2: with compatible interior pairs the Gregory patch is the Bézier patch (<= 1e-14), derivatives <= 1e-12. */
static void test_t2_gregory_equals_bezier(void **state)
{
    (void)state;
    uint32_t seed = 21;
    for (int n = 0; n < 5; n++) {
        cm_vec3 B[4][4];
        rand_net(&seed, B);
        cm_gregory g = compatible(B);
        for (int i = 0; i <= 10; i++)
            for (int j = 0; j <= 10; j++) {
                double u = i / 10.0, v = j / 10.0;
                cm_vec3 S, Su, Sv, R, Ru, Rv;
                cm_greg_eval(&g, u, v, &S, &Su, &Sv);
                bezier_patch(B, u, v, &R, &Ru, &Rv);
                assert_vec_near(S, R, 1e-14);
                assert_vec_near(Su, Ru, 1e-12);
                assert_vec_near(Sv, Rv, 1e-12);
            }
    }
}

/* Corner rule: at the four corners (denominator 0) the patch is the corner point, derivatives the boundary ones. */
static void test_corners(void **state)
{
    (void)state;
    uint32_t seed = 23;
    cm_vec3 B[4][4];
    rand_net(&seed, B);
    cm_gregory g = compatible(B);
    /* make the pairs incompatible: corner values must not depend on them */
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++)
            g.I[a][b][1] = cm_add(g.I[a][b][1], cm_v3(0.3, -0.2, 0.5));
    const double cu[4] = {0, 1, 0, 1}, cv[4] = {0, 0, 1, 1};
    for (int k = 0; k < 4; k++) {
        cm_vec3 S, Su, Sv;
        int i = cu[k] == 0 ? 0 : 3, j = cv[k] == 0 ? 0 : 3;
        cm_greg_eval(&g, cu[k], cv[k], &S, &Su, &Sv);
        assert_vec_near(S, B[i][j], 1e-15 * 4);
        /* S_u at a corner: 3(P_{1,j} - P_{0,j}) on the boundary row */
        cm_vec3 expect_u = cm_scale(i == 0 ? cm_sub(B[1][j], B[0][j]) : cm_sub(B[3][j], B[2][j]), 3.0);
        cm_vec3 expect_v = cm_scale(j == 0 ? cm_sub(B[i][1], B[i][0]) : cm_sub(B[i][3], B[i][2]), 3.0);
        assert_vec_near(Su, expect_u, 1e-13);
        assert_vec_near(Sv, expect_v, 1e-13);
        assert_true(cm_finite3(Su) && cm_finite3(Sv));
    }
}

/* Exact derivatives of a genuinely rational (incompatible) patch match central differences. */
static void test_derivatives_fd(void **state)
{
    (void)state;
    uint32_t seed = 29;
    cm_vec3 B[4][4];
    rand_net(&seed, B);
    cm_gregory g = compatible(B);
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) {
            g.I[a][b][0] = cm_add(g.I[a][b][0], test_rand_vec(&seed, 0.5));
            g.I[a][b][1] = cm_add(g.I[a][b][1], test_rand_vec(&seed, 0.5));
        }
    const double h = 1e-6;
    for (int i = 1; i < 10; i++)
        for (int j = 1; j < 10; j++) {
            double u = i / 10.0 + 0.01, v = j / 10.0 - 0.02;
            cm_vec3 S, Su, Sv, Sp, Sm, d1, d2;
            cm_greg_eval(&g, u, v, &S, &Su, &Sv);
            cm_greg_eval(&g, u + h, v, &Sp, &d1, &d2);
            cm_greg_eval(&g, u - h, v, &Sm, &d1, &d2);
            assert_vec_near(Su, cm_scale(cm_sub(Sp, Sm), 0.5 / h), 1e-7); /* O(h^2) truncation */
            cm_greg_eval(&g, u, v + h, &Sp, &d1, &d2);
            cm_greg_eval(&g, u, v - h, &Sm, &d1, &d2);
            assert_vec_near(Sv, cm_scale(cm_sub(Sp, Sm), 0.5 / h), 1e-7);
        }
}

/* The four boundaries are the input cubics; approaching a corner the patch converges to it. */
static void test_boundaries_and_continuity(void **state)
{
    (void)state;
    uint32_t seed = 31;
    cm_vec3 B[4][4];
    rand_net(&seed, B);
    cm_gregory g = compatible(B);
    g.I[0][0][0] = cm_add(g.I[0][0][0], cm_v3(1, 1, 1));
    cm_cubic e0 = {{B[0][0], B[1][0], B[2][0], B[3][0]}};
    cm_cubic e1 = {{B[3][0], B[3][1], B[3][2], B[3][3]}};
    for (int k = 0; k <= 20; k++) {
        double t = k / 20.0;
        cm_vec3 S, Su, Sv, d[3];
        cm_greg_eval(&g, t, 0.0, &S, &Su, &Sv);
        cm_cubic_eval(&e0, t, d);
        assert_vec_near(S, d[0], 1e-14);
        cm_greg_eval(&g, 1.0, t, &S, &Su, &Sv);
        cm_cubic_eval(&e1, t, d);
        assert_vec_near(S, d[0], 1e-14);
    }
    double prev = 1e300;
    for (int k = 1; k <= 12; k++) {
        double e = pow(10.0, -k);
        cm_vec3 S;
        cm_greg_eval(&g, e, 2 * e, &S, NULL, NULL);
        double d = cm_dist(S, B[0][0]);
        assert_true(d <= prev);
        prev = d;
    }
    assert_true(prev < 1e-10);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_t2_gregory_equals_bezier),
        cmocka_unit_test(test_corners),
        cmocka_unit_test(test_derivatives_fd),
        cmocka_unit_test(test_boundaries_and_continuity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
