/*
 * test_patchfit.c - GREGORY-FIT's interior correction (cm_patchfit.h) on its
 * own, the properties the method relies on:
 *   - each basis function and its derivative are zero at both ends, so the
 *     correction leaves a patch's sides and cross derivatives untouched;
 *   - the derivatives are the basis functions' true ones (central differences),
 *     so normals of a corrected patch are right;
 *   - the correction adds what its coefficients say, nothing for m = 0 or out
 *     of range;
 *   - dequantisation is an exact power-of-two scaling (x86-64 and ARM agree).
 */
#include "test_util.h"

#include <math.h>

#include "cm/cm_patchfit.h"

static void test_basis_vanishes_on_the_sides(void **state)
{
    (void)state;
    for (int m = 1; m <= CM_FIT_MAX_M; m++) {
        double b[CM_FIT_MAX_M], db[CM_FIT_MAX_M];
        for (int end = 0; end <= 1; end++) {
            cm_fit_basis(m, (double)end, b, db);
            for (int i = 0; i < m; i++) {
                assert_true(b[i] == 0.0);
                assert_true(db[i] == 0.0);
            }
        }
        /* inside, every function is positive: a coefficient moves the patch */
        cm_fit_basis(m, 0.5, b, db);
        for (int i = 0; i < m; i++)
            assert_true(b[i] > 0.01);
    }
}

static void test_derivatives(void **state)
{
    (void)state;
    const double h = 1e-6;
    for (int m = 1; m <= CM_FIT_MAX_M; m++)
        for (int k = 1; k < 10; k++) {
            double t = k / 10.0, b[CM_FIT_MAX_M], db[CM_FIT_MAX_M], bp[CM_FIT_MAX_M], bm[CM_FIT_MAX_M];
            cm_fit_basis(m, t, b, db);
            cm_fit_basis(m, t + h, bp, NULL);
            cm_fit_basis(m, t - h, bm, NULL);
            for (int i = 0; i < m; i++)
                assert_near(db[i], (bp[i] - bm[i]) / (2 * h), 1e-7);
        }
}

static void test_add(void **state)
{
    (void)state;
    cm_vec3 c[CM_FIT_MAX_COEF];
    for (int i = 0; i < CM_FIT_MAX_COEF; i++)
        c[i] = cm_v3(i + 1.0, -2.0 * i, 0.5);
    for (int m = 0; m <= CM_FIT_MAX_M + 1; m++) {
        double u = 0.3, v = 0.65;
        cm_vec3 S = cm_v3(1, 2, 3), Su = cm_v3(0, 0, 0), Sv = cm_v3(0, 0, 0);
        cm_fit_add(c, m, u, v, &S, &Su, &Sv);
        cm_vec3 want = cm_v3(1, 2, 3), wu = cm_v3(0, 0, 0), wv = cm_v3(0, 0, 0);
        if (m >= 1 && m <= CM_FIT_MAX_M) {
            double bu[CM_FIT_MAX_M], dbu[CM_FIT_MAX_M], bv[CM_FIT_MAX_M], dbv[CM_FIT_MAX_M];
            cm_fit_basis(m, u, bu, dbu);
            cm_fit_basis(m, v, bv, dbv);
            for (int i = 0; i < m; i++)
                for (int j = 0; j < m; j++) {
                    want = cm_axpy(want, bu[i] * bv[j], c[i * m + j]);
                    wu = cm_axpy(wu, dbu[i] * bv[j], c[i * m + j]);
                    wv = cm_axpy(wv, bu[i] * dbv[j], c[i * m + j]);
                }
            assert_true(cm_dist(want, cm_v3(1, 2, 3)) > 0.01); /* it did move */
        }
        assert_near(cm_dist(S, want), 0, 1e-12);
        assert_near(cm_dist(Su, wu), 0, 1e-12);
        assert_near(cm_dist(Sv, wv), 0, 1e-12);
        /* the partials may be left out */
        cm_vec3 S2 = cm_v3(1, 2, 3);
        cm_fit_add(c, m, u, v, &S2, NULL, NULL);
        assert_true(S2.x == S.x && S2.y == S.y && S2.z == S.z);
    }
}

static void test_dequantise(void **state)
{
    (void)state;
    assert_true(cm_fit_dequantise(3, 0.25, 2) == 3.0);
    assert_true(cm_fit_dequantise(-5, ldexp(1.0, -20), 7) == -5.0 * ldexp(1.0, -13));
    assert_true(cm_fit_dequantise(CM_FIT_MAX_INT, ldexp(1.0, -60), CM_FIT_MAX_EXP) ==
                ldexp((double)CM_FIT_MAX_INT, CM_FIT_MAX_EXP - 60));
    assert_true(cm_fit_dequantise(0, 1.0, 0) == 0.0);
}

/* B^d_k(t) as the kernel formed it before its powers table (format 2.2's definition): the binomial
   as c (d-k+i) / i, then t^k and (1-t)^(d-k) by repeated products */
static double reference_bernstein(int d, int k, double t)
{
    if (k < 0 || k > d)
        return 0.0;
    double c = 1.0, s = 1.0 - t, r = 1.0;
    for (int i = 1; i <= k; i++)
        c = c * (double)(d - k + i) / (double)i;
    for (int i = 0; i < k; i++)
        r *= t;
    for (int i = 0; i < d - k; i++)
        r *= s;
    return c * r;
}

/* the basis and its derivatives are the reference's bits for every m and many t, ends included */
static void test_basis_same_bits(void **state)
{
    (void)state;
    for (int m = 1; m <= CM_FIT_MAX_M; m++)
        for (int k = 0; k <= 1000; k++) {
            double t = (double)k / 1000.0 + (k % 7 == 3 ? 1e-9 : 0.0);
            double b[CM_FIT_MAX_M], db[CM_FIT_MAX_M];
            cm_fit_basis(m, t, b, db);
            int d = m + 3;
            for (int i = 0; i < m; i++) {
                double wb = reference_bernstein(d, i + 2, t);
                double wdb = (double)d * (reference_bernstein(d - 1, i + 1, t) - reference_bernstein(d - 1, i + 2, t));
                assert_memory_equal(&b[i], &wb, sizeof(double));
                assert_memory_equal(&db[i], &wdb, sizeof(double));
            }
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_basis_vanishes_on_the_sides),
        cmocka_unit_test(test_derivatives),
        cmocka_unit_test(test_add),
        cmocka_unit_test(test_basis_same_bits),
        cmocka_unit_test(test_dequantise),
    };
    return cmocka_run_group_tests_name("patchfit", tests, NULL, NULL);
}
