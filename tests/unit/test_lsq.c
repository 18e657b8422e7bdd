/* test_lsq.c - K6, K8: Cramer, dense and banded Cholesky, least-squares curves. */
#include "test_util.h"

#include "cm/cm_bspline.h"
#include "cm/cm_limits_info.h"
#include "cm/cm_lsq.h"

static void test_cramer(void **state)
{
    (void)state;
    const double A[4] = {2, 1, 1, 3}, b[2] = {3, 5};
    double x[2], y[3];
    assert_ok(cm_solve2(A, b, 0.0, x, NULL));
    assert_near(x[0], 0.8, 1e-15);
    assert_near(x[1], 1.4, 1e-15);
    const double S[4] = {1, 2, 2, 4};
    assert_err(cm_solve2(S, b, 0.0, x, NULL), CM_E_SINGULAR);
    const double A3[9] = {4, 1, 0, 1, 3, 1, 0, 1, 2}, b3[3] = {6, 9.5, 7}; /* x = (1, 2, 2.5) */
    assert_ok(cm_solve3(A3, b3, 0.0, y, NULL));
    assert_near(y[0], 1.0, 1e-14);
    assert_near(y[1], 2.0, 1e-14);
    assert_near(y[2], 2.5, 1e-14);
}

/* SPD matrix A = M^T M + n I from a seeded M */
static void spd(uint32_t *seed, int n, double *A)
{
    double M[64];
    for (int i = 0; i < n * n; i++)
        M[i] = 2 * test_rand(seed) - 1;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double s = i == j ? n : 0.0;
            for (int k = 0; k < n; k++)
                s += M[k * n + i] * M[k * n + j];
            A[i * n + j] = s;
        }
}

static void test_dense_cholesky_solves(void **state)
{
    (void)state;
    uint32_t seed = 41;
    enum { N = 6 };
    double A[N * N], L[N * N];
    cm_vec3 x[N], b[N];
    spd(&seed, N, A);
    for (int i = 0; i < N; i++)
        x[i] = test_rand_vec(&seed, 1.0);
    for (int i = 0; i < N; i++) {
        b[i] = cm_v3(0, 0, 0);
        for (int j = 0; j < N; j++)
            b[i] = cm_axpy(b[i], A[i * N + j], x[j]);
    }
    memcpy(L, A, sizeof L);
    assert_ok(cm_chol_dense(L, N, N, NULL));
    cm_chol_dense_solve3(L, N, N, b);
    for (int i = 0; i < N; i++)
        assert_vec_near(b[i], x[i], 1e-13); /* condition number ~ 10: a few ulps times kappa */
    const double S[4] = {1, 2, 2, 4};
    double T[4];
    memcpy(T, S, sizeof T);
    assert_err(cm_chol_dense(T, 2, 2, NULL), CM_E_SINGULAR);
}

/* Banded Cholesky gives the same solution as dense on a banded SPD matrix (n = 14, w = 3). */
static void test_band_cholesky_matches_dense(void **state)
{
    (void)state;
    enum { N = 14, W = 3 };
    uint32_t seed = 43;
    static double band[N * (W + 1)];
    cm_vec3 x[N], b[N];
    double dense[N][N];
    memset(dense, 0, sizeof dense);
    for (int i = 0; i < N; i++)
        for (int j = (i - W > 0 ? i - W : 0); j <= i; j++) {
            double v = i == j ? 4.0 + test_rand(&seed) : 0.5 * (2 * test_rand(&seed) - 1) / (i - j);
            dense[i][j] = dense[j][i] = v;
            band[CM_BAND_IDX(i, j, W)] = v;
        }
    for (int i = 0; i < N; i++)
        x[i] = test_rand_vec(&seed, 2.0);
    for (int i = 0; i < N; i++) {
        b[i] = cm_v3(0, 0, 0);
        for (int j = 0; j < N; j++)
            b[i] = cm_axpy(b[i], dense[i][j], x[j]);
    }
    if (N > CM_MAX_LSQ_UNKNOWNS) {
        assert_err(cm_chol_band(band, N, W, NULL), CM_E_LIMIT);
        return;
    }
    assert_ok(cm_chol_band(band, N, W, NULL));
    cm_chol_band_solve3(band, N, W, b);
    for (int i = 0; i < N; i++)
        assert_vec_near(b[i], x[i], 1e-13); /* diagonally dominant: well conditioned */
    double zero[2 * (W + 1)] = {0};
    assert_err(cm_chol_band(zero, 2, W, NULL), CM_E_SINGULAR);
}

static void test_solver_limits(void **state)
{
    (void)state;
    static double big[(CM_MAX_DENSE + 1) * (CM_MAX_DENSE + 1)];
    static double band[(CM_MAX_LSQ_UNKNOWNS + 1) * (CM_MAX_LSQ_BAND + 2)];
    cm_status st;
    cm_status_init(&st);
    assert_err(cm_chol_dense(big, CM_MAX_DENSE + 1, CM_MAX_DENSE + 1, &st), CM_E_LIMIT);
    assert_int_equal(st.need, CM_MAX_DENSE + 1);
    cm_status_init(&st);
    assert_err(cm_chol_band(band, CM_MAX_LSQ_UNKNOWNS + 1, 1, &st), CM_E_LIMIT);
    assert_int_equal(st.limit, CM_LIMIT_MAX_LSQ_UNKNOWNS);
    cm_status_init(&st);
    assert_err(cm_chol_band(band, 4, CM_MAX_LSQ_BAND + 1, &st), CM_E_LIMIT);
    assert_int_equal(st.limit, CM_LIMIT_MAX_LSQ_BAND);
    /* at the limit the band solver runs (identity matrix) */
    for (int i = 0; i < CM_MAX_LSQ_UNKNOWNS; i++)
        band[CM_BAND_IDX(i, i, CM_MAX_LSQ_BAND)] = 1.0;
    assert_ok(cm_chol_band(band, CM_MAX_LSQ_UNKNOWNS, CM_MAX_LSQ_BAND, NULL));
}

/* K6 reproduces a cubic polynomial curve with fixed ends.  The fairing term lambda = 1e-6 trace/n
 * biases the result by O(1e-6) of the curve size, so the tolerance is 1e-5 of it. */
static void test_fit_reproduces_polynomial(void **state)
{
    (void)state;
    enum { M = 60 };
    int n = CM_MAX_DENSE < 7 ? CM_MAX_DENSE : 7;
    double U[16], t[M], rms;
    cm_vec3 Q[M], P[16];
    static cm_fit_curve_ws ws;
    assert_ok(cm_knots_uniform(n, 3, U, NULL));
    for (int k = 0; k < M; k++) {
        double s = k / (double)(M - 1);
        t[k] = s;
        Q[k] = cm_v3(10 * s, 5 * s * s - 2 * s, s * s * s + 1); /* a cubic: inside every spline space */
    }
    assert_ok(cm_fit_curve(Q, t, NULL, M, 3, n, U, &Q[0], &Q[M - 1], P, &rms, &ws, NULL));
    assert_vec_near(P[0], Q[0], 0);
    assert_vec_near(P[n - 1], Q[M - 1], 0);
    assert_true(rms < 1e-5 * 10);
    cm_curve c = {3, n, U, P, NULL};
    for (int k = 0; k < M; k++) {
        cm_vec3 d[1];
        assert_ok(cm_curve_eval(&c, t[k], 0, d, NULL));
        assert_vec_near(d[0], Q[k], 1e-5 * 10);
    }
    /* free ends fit too, and weights change nothing for exact data */
    double w[M];
    for (int k = 0; k < M; k++)
        w[k] = 1.0 + (k % 3);
    assert_ok(cm_fit_curve(Q, t, w, M, 3, n, U, NULL, NULL, P, &rms, &ws, NULL));
    assert_true(rms < 1e-5 * 10);
}

/* Too few data for the unknowns is fine (the fairing keeps it SPD), over-limit counts are not. */
static void test_fit_sparse_and_limits(void **state)
{
    (void)state;
    int n = CM_MAX_DENSE < 8 ? CM_MAX_DENSE : 8;
    double U[40], t[2] = {0.2, 0.8}, rms;
    cm_vec3 Q[2] = {{1, 0, 0}, {2, 1, 0}}, P[40], a = {0, 0, 0}, b = {3, 0, 0};
    static cm_fit_curve_ws ws;
    assert_ok(cm_knots_uniform(n, 3, U, NULL));
    assert_ok(cm_fit_curve(Q, t, NULL, 2, 3, n, U, &a, &b, P, &rms, &ws, NULL));
    for (int i = 0; i < n; i++)
        assert_true(cm_finite3(P[i]));
    cm_status st;
    cm_status_init(&st);
    assert_err(cm_fit_curve(Q, t, NULL, 2, 3, CM_MAX_DENSE + 1, U, &a, &b, P, &rms, &ws, &st), CM_E_LIMIT);
    assert_int_equal(st.limit, CM_LIMIT_MAX_FIT_CTRL);
    assert_err(cm_fit_curve(Q, t, NULL, 0, 3, n, U, &a, &b, P, &rms, &ws, NULL), CM_E_RANGE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cramer),
        cmocka_unit_test(test_dense_cholesky_solves),
        cmocka_unit_test(test_band_cholesky_matches_dense),
        cmocka_unit_test(test_solver_limits),
        cmocka_unit_test(test_fit_reproduces_polynomial),
        cmocka_unit_test(test_fit_sparse_and_limits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
