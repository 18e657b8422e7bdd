/* test_bspline.c - K1-K3, K5: basis functions, evaluation, knot insertion, validation. */
#include "test_util.h"

#include "cm/cm_bspline.h"
#include "cm/cm_limits_info.h"

/* The NURBS Book Ex. 2.3/2.4: U = {0,0,0,1,2,3,4,4,5,5,5}, p = 2, u = 5/2.
 * All values are exact binary fractions, so they are compared with ==. */
static const double ex23_U[11] = {0, 0, 0, 1, 2, 3, 4, 4, 5, 5, 5};

static void test_ex23_basis_exact(void **state)
{
    (void)state;
    double N[3];
    int span = cm_bspl_find_span(8, 2, ex23_U, 2.5);
    assert_int_equal(span, 4);
    assert_ok(cm_bspl_basis(span, 2.5, 2, ex23_U, N, NULL));
    assert_true(N[0] == 1.0 / 8 && N[1] == 6.0 / 8 && N[2] == 1.0 / 8);
}

static void test_ex24_derivatives_exact(void **state)
{
    (void)state;
    double d[CM_MAX_DERS + 1][CM_MAX_ORDER];
    assert_ok(cm_bspl_ders_basis(4, 2.5, 2, 2, ex23_U, d, NULL));
    assert_true(d[0][0] == 0.125 && d[0][1] == 0.75 && d[0][2] == 0.125);
    assert_true(d[1][0] == -0.5 && d[1][1] == 0.0 && d[1][2] == 0.5);
    assert_true(d[2][0] == 1.0 && d[2][1] == -2.0 && d[2][2] == 1.0);
}

/* FindSpan at, just inside and just outside every knot and the domain ends. */
static void test_find_span_edges(void **state)
{
    (void)state;
    int n = 8, p = 2;
    assert_int_equal(cm_bspl_find_span(n, p, ex23_U, 0.0), 2);
    assert_int_equal(cm_bspl_find_span(n, p, ex23_U, -1.0), 2);   /* below: clamped */
    assert_int_equal(cm_bspl_find_span(n, p, ex23_U, 1.0), 3);    /* at a knot: the span it starts */
    assert_int_equal(cm_bspl_find_span(n, p, ex23_U, nextafter(1.0, 0.0)), 2);
    assert_int_equal(cm_bspl_find_span(n, p, ex23_U, 4.0), 7);    /* double knot 4,4 */
    assert_int_equal(cm_bspl_find_span(n, p, ex23_U, 5.0), 7);    /* domain end: last non-empty span */
    assert_int_equal(cm_bspl_find_span(n, p, ex23_U, 7.0), 7);    /* above: clamped */
    assert_int_equal(cm_bspl_find_span(n, p, ex23_U, nan("")), 2);    /* NaN: domain start, no hang */
    for (double u = 0.0; u < 5.0; u += 0.125) {
        int s = cm_bspl_find_span(n, p, ex23_U, u);
        assert_true(ex23_U[s] <= u && u < ex23_U[s + 1]);
    }
}

/* Partition of unity and non-negativity on a non-uniform cubic vector, at and between knots. */
static void test_partition_of_unity(void **state)
{
    (void)state;
    const double U[] = {0, 0, 0, 0, 0.1, 0.35, 0.35, 0.8, 1, 1, 1, 1};
    int n = 8, p = 3;
    for (int k = 0; k <= 200; k++) {
        double u = k / 200.0, N[4], sum = 0.0;
        int s = cm_bspl_find_span(n, p, U, u);
        assert_ok(cm_bspl_basis(s, u, p, U, N, NULL));
        for (int i = 0; i <= p; i++) {
            assert_true(N[i] >= 0.0);
            sum += N[i];
        }
        assert_near(sum, 1.0, 8 * 2.2e-16); /* 4 terms, a few ulps of 1 */
    }
}

/* Basis derivatives equal central differences (h = 1e-6: error O(h^2) ~ 1e-10 for O(1) second derivatives). */
static void test_basis_derivatives_fd(void **state)
{
    (void)state;
    const double U[] = {0, 0, 0, 0, 0.2, 0.5, 0.7, 1, 1, 1, 1};
    int n = 7, p = 3;
    const double h = 1e-6;
    for (int k = 1; k < 40; k++) {
        double u = k / 40.0 + 0.003;
        double d[CM_MAX_DERS + 1][CM_MAX_ORDER], dp[CM_MAX_DERS + 1][CM_MAX_ORDER], dm[CM_MAX_DERS + 1][CM_MAX_ORDER];
        int s = cm_bspl_find_span(n, p, U, u);
        assert_ok(cm_bspl_ders_basis(s, u, p, 2, U, d, NULL));
        assert_ok(cm_bspl_ders_basis(s, u + h, p, 2, U, dp, NULL));
        assert_ok(cm_bspl_ders_basis(s, u - h, p, 2, U, dm, NULL));
        for (int i = 0; i <= p; i++) {
            assert_near(d[1][i], (dp[0][i] - dm[0][i]) / (2 * h), 1e-7);
            assert_near(d[2][i], (dp[1][i] - dm[1][i]) / (2 * h), 1e-5);
        }
    }
}

/* A rational quadratic quarter circle: every point at distance R, derivatives match differences. */
static void test_rational_circle(void **state)
{
    (void)state;
    const double R = 10.0;
    const cm_vec3 P[3] = {{R, 0, 0}, {R, R, 0}, {0, R, 0}};
    const double w[3] = {1, TEST_SQRT1_2, 1};
    const double U[6] = {0, 0, 0, 1, 1, 1};
    cm_curve c = {2, 3, U, P, w};
    assert_ok(cm_curve_check(&c, NULL));
    for (int k = 0; k <= 100; k++) {
        double u = k / 100.0;
        cm_vec3 d[3], dp[3], dm[3];
        assert_ok(cm_curve_eval(&c, u, 2, d, NULL));
        assert_near(cm_norm(d[0]), R, 4e-15 * R); /* exact circle up to rounding */
        assert_near(cm_dot(d[0], d[1]), 0.0, 1e-12 * R * R); /* tangent orthogonal to the radius */
        if (k > 0 && k < 100) {
            const double h = 1e-5;
            assert_ok(cm_curve_eval(&c, u + h, 2, dp, NULL));
            assert_ok(cm_curve_eval(&c, u - h, 2, dm, NULL));
            assert_vec_near(d[1], cm_scale(cm_sub(dp[0], dm[0]), 0.5 / h), 1e-7 * R);
            assert_vec_near(d[2], cm_scale(cm_sub(dp[1], dm[1]), 0.5 / h), 1e-6 * R);
        }
    }
}

/* A rational biquadratic patch of a sphere octant: points at distance R; partials match differences. */
static const double oct_w[9] = {1, TEST_SQRT1_2, 1, TEST_SQRT1_2, 0.5, TEST_SQRT1_2, 1, TEST_SQRT1_2, 1};
static const double oct_U[6] = {0, 0, 0, 1, 1, 1};

static void octant(cm_vec3 P[9], double R)
{
    /* u: quarter circle in the xz meridian revolved; v: around z */
    const cm_vec3 mer[3] = {{R, 0, 0}, {R, 0, R}, {0, 0, R}};
    for (int i = 0; i < 3; i++) {
        double x = mer[i].x, z = mer[i].z;
        P[i * 3 + 0] = cm_v3(x, 0, z);
        P[i * 3 + 1] = cm_v3(x, x, z);
        P[i * 3 + 2] = cm_v3(0, x, z);
    }
}

static void test_rational_sphere_surface(void **state)
{
    (void)state;
    const double R = 3.0;
    cm_vec3 P[9];
    octant(P, R);
    cm_surf s = {2, 2, 3, 3, oct_U, oct_U, P, oct_w};
    assert_ok(cm_surf_check(&s, NULL));
    const double h = 1e-5;
    for (int i = 1; i < 10; i++)
        for (int j = 1; j < 10; j++) {
            double u = i / 10.0, v = j / 10.0;
            cm_vec3 S[3][3], Sp[3][3], Sm[3][3];
            assert_ok(cm_surf_eval(&s, u, v, 2, S, NULL));
            assert_near(cm_norm(S[0][0]), R, 4e-15 * R);
            assert_ok(cm_surf_eval(&s, u + h, v, 2, Sp, NULL));
            assert_ok(cm_surf_eval(&s, u - h, v, 2, Sm, NULL));
            assert_vec_near(S[1][0], cm_scale(cm_sub(Sp[0][0], Sm[0][0]), 0.5 / h), 1e-7 * R);
            assert_vec_near(S[2][0], cm_scale(cm_sub(Sp[1][0], Sm[1][0]), 0.5 / h), 1e-6 * R);
            assert_vec_near(S[1][1], cm_scale(cm_sub(Sp[0][1], Sm[0][1]), 0.5 / h), 1e-6 * R);
            assert_ok(cm_surf_eval(&s, u, v + h, 2, Sp, NULL));
            assert_ok(cm_surf_eval(&s, u, v - h, 2, Sm, NULL));
            assert_vec_near(S[0][1], cm_scale(cm_sub(Sp[0][0], Sm[0][0]), 0.5 / h), 1e-7 * R);
            assert_vec_near(S[0][2], cm_scale(cm_sub(Sp[0][1], Sm[0][1]), 0.5 / h), 1e-6 * R);
        }
}

/* A non-rational surface is the tensor product of its curves: S(u, v) with one row of controls
 * equals the curve through them (degenerate direction of degree 1 and 2 points). */
static void test_surface_matches_curve(void **state)
{
    (void)state;
    uint32_t seed = 7;
    const double U[] = {0, 0, 0, 0, 0.3, 0.6, 1, 1, 1, 1};
    const double V[] = {0, 0, 1, 1};
    cm_vec3 row[6], net[12];
    for (int i = 0; i < 6; i++) {
        row[i] = test_rand_vec(&seed, 5.0);
        net[i * 2 + 0] = row[i];
        net[i * 2 + 1] = row[i];
    }
    cm_curve c = {3, 6, U, row, NULL};
    cm_surf s = {3, 1, 6, 2, U, V, net, NULL};
    for (int k = 0; k <= 50; k++) {
        cm_vec3 d[3], S[3][3];
        assert_ok(cm_curve_eval(&c, k / 50.0, 1, d, NULL));
        assert_ok(cm_surf_eval(&s, k / 50.0, 0.37, 1, S, NULL));
        assert_vec_near(S[0][0], d[0], 1e-14 * 5);
        assert_vec_near(S[1][0], d[1], 1e-13 * 5);
        assert_vec_near(S[0][1], cm_v3(0, 0, 0), 1e-14 * 5);
    }
}

/* T10: knot insertion reproduces the curve (<= 1e-15 relative) at 101 parameters, rational too. */
static void check_insertion(const cm_curve *c, double u, int r)
{
    double K[64], w2[64];
    cm_vec3 Q[64];
    assert_ok(cm_curve_insert_knot(c, u, r, K, Q, w2, 64, NULL));
    cm_curve d = {c->p, c->n_ctrl + r, K, Q, c->w ? w2 : NULL};
    assert_ok(cm_curve_check(&d, NULL));
    double scale = 0.0;
    for (int i = 0; i < c->n_ctrl; i++)
        scale = fmax(scale, cm_norm(c->ctrl[i]));
    for (int k = 0; k <= 100; k++) {
        double t = c->knots[c->p] + (c->knots[c->n_ctrl] - c->knots[c->p]) * k / 100.0;
        cm_vec3 a[1], b[1];
        assert_ok(cm_curve_eval(c, t, 0, a, NULL));
        assert_ok(cm_curve_eval(&d, t, 0, b, NULL));
        assert_vec_near(a[0], b[0], 4e-15 * scale); /* a few ulps of the control-point scale */
    }
}

static void test_knot_insertion_preserves_curve(void **state)
{
    (void)state;
    uint32_t seed = 11;
    /* 5 control points: even with r = 3 the result fits the tiny profile's 8 */
    const double U[] = {0, 0, 0, 0, 0.5, 1, 1, 1, 1};
    cm_vec3 P[5];
    double w[5];
    for (int i = 0; i < 5; i++) {
        P[i] = test_rand_vec(&seed, 3.0);
        w[i] = 0.5 + test_rand(&seed);
    }
    cm_curve c = {3, 5, U, P, NULL};
    check_insertion(&c, 0.4, 1);
    check_insertion(&c, 0.5, 2);  /* existing knot: multiplicity 1 -> 3 */
    check_insertion(&c, 0.1, 3);  /* full multiplicity p */
    cm_curve cr = {3, 5, U, P, w};
    check_insertion(&cr, 0.4, 1);
    check_insertion(&cr, 0.5, 2);
    check_insertion(&cr, 0.9, 3);
}

/* Inserting the knots u0..up into a cubic Bézier gives the clamped spline with p+5 control points (spec K3). */
static void test_insert_into_bezier(void **state)
{
    (void)state;
    const double U[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    cm_vec3 P[4] = {{0, 0, 0}, {1, 2, 0}, {3, 2, 1}, {4, 0, 0}};
    cm_curve c = {3, 4, U, P, NULL};
    double K[16];
    cm_vec3 Q[16];
    assert_ok(cm_curve_insert_knot(&c, 0.5, 1, K, Q, NULL, 16, NULL));
    assert_near(K[4], 0.5, 0);
    /* one insertion at 1/2: every alpha is 1/2, Q_i = (P_(i-1) + P_i)/2 for i = 1..3 (exact in binary) */
    assert_vec_near(Q[0], P[0], 0);
    assert_vec_near(Q[1], cm_v3(0.5, 1, 0), 0);
    assert_vec_near(Q[2], cm_v3(2, 2, 0.5), 0);
    assert_vec_near(Q[3], cm_v3(3.5, 1, 0.5), 0);
    assert_vec_near(Q[4], P[3], 0);
}

static void test_knot_insertion_errors(void **state)
{
    (void)state;
    const double U[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    cm_vec3 P[4] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
    cm_curve c = {3, 4, U, P, NULL};
    double K[16];
    cm_vec3 Q[16];
    cm_status st;
    assert_err(cm_curve_insert_knot(&c, 0.5, 4, K, Q, NULL, 16, NULL), CM_E_ARG); /* beyond degree */
    assert_err(cm_curve_insert_knot(&c, 0.0, 1, K, Q, NULL, 16, NULL), CM_E_ARG); /* domain end */
    cm_status_init(&st);
    assert_err(cm_curve_insert_knot(&c, 0.5, 2, K, Q, NULL, 5, &st), CM_E_NOSPACE);
    assert_int_equal(st.need, 6);
    assert_int_equal(st.have, 5);
}

/* Inserting into a curve already at CM_MAX_EDGE_CTRL control points is refused with the limit named. */
static void test_knot_insertion_limit(void **state)
{
    (void)state;
    static double U[CM_MAX_EDGE_CTRL + 4], K[CM_MAX_EDGE_CTRL + 8];
    static cm_vec3 P[CM_MAX_EDGE_CTRL], Q[CM_MAX_EDGE_CTRL + 4];
    assert_ok(cm_knots_uniform(CM_MAX_EDGE_CTRL, 3, U, NULL));
    for (int i = 0; i < CM_MAX_EDGE_CTRL; i++)
        P[i] = cm_v3(i, 0, 0);
    cm_curve c = {3, CM_MAX_EDGE_CTRL, U, P, NULL};
    assert_ok(cm_curve_check(&c, NULL)); /* at the limit: accepted */
    cm_status st;
    cm_status_init(&st);
    assert_err(cm_curve_insert_knot(&c, 0.5 * (U[3] + U[4]), 1, K, Q, NULL, CM_MAX_EDGE_CTRL + 4, &st), CM_E_LIMIT);
    assert_int_equal(st.limit, CM_LIMIT_MAX_EDGE_CTRL);
    assert_int_equal(st.need, CM_MAX_EDGE_CTRL + 1);
    assert_int_equal(st.have, CM_MAX_EDGE_CTRL);
}

static void test_knot_validation(void **state)
{
    (void)state;
    const double dec[8] = {0, 0, 0, 0, 1, 0.5, 1, 1};
    const double mult[8] = {0, 0, 0, 0, 0, 1, 1, 1}; /* 0 five times > p+1 */
    double nan_[8] = {0, 0, 0, 0, 0, 1, 1, 1};
    nan_[4] = nan("");
    const double empty[8] = {1, 1, 1, 1, 1, 1, 1, 1};
    const double ok[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    assert_err(cm_knots_check(3, 4, dec, NULL), CM_E_KNOTS);
    assert_err(cm_knots_check(3, 4, mult, NULL), CM_E_KNOTS);
    assert_err(cm_knots_check(3, 4, nan_, NULL), CM_E_NONFINITE);
    assert_err(cm_knots_check(3, 4, empty, NULL), CM_E_KNOTS);
    assert_err(cm_knots_check(3, 3, ok, NULL), CM_E_RANGE); /* fewer points than order */
    assert_err(cm_knots_check(0, 4, ok, NULL), CM_E_RANGE);
    assert_ok(cm_knots_check(3, 4, ok, NULL));
    cm_vec3 P[4] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
    double w[4] = {1, 1, 0, 1};
    P[3].y = nan("");
    cm_curve c = {3, 4, ok, P, NULL};
    assert_err(cm_curve_check(&c, NULL), CM_E_NONFINITE);
    P[3].y = 0;
    c.w = w;
    assert_err(cm_curve_check(&c, NULL), CM_E_RANGE); /* zero weight */
}

/* Every evaluator refuses a degree above CM_MAX_DEGREE with CM_E_LIMIT (never an assert). */
static void test_degree_limit(void **state)
{
    (void)state;
    enum { P = CM_MAX_DEGREE + 1 };
    static double U[2 * (P + 1)];
    static cm_vec3 ctrl[(P + 1) * (P + 1)];
    for (int i = 0; i <= P; i++) {
        U[i] = 0.0;
        U[P + 1 + i] = 1.0;
    }
    double N[P + 1], ders[CM_MAX_DERS + 1][CM_MAX_ORDER];
    cm_vec3 d[3], S[3][3];
    cm_status st;
    cm_status_init(&st);
    assert_err(cm_bspl_basis(P, 0.5, P, U, N, &st), CM_E_LIMIT);
    assert_int_equal(st.limit, CM_LIMIT_MAX_DEGREE);
    assert_int_equal(st.need, P);
    assert_err(cm_bspl_ders_basis(P, 0.5, P, 1, U, ders, NULL), CM_E_LIMIT);
    cm_curve c = {P, P + 1, U, ctrl, NULL};
    assert_err(cm_curve_eval(&c, 0.5, 0, d, NULL), CM_E_LIMIT);
    assert_err(cm_curve_check(&c, NULL), CM_E_LIMIT);
    cm_surf s = {P, 1, P + 1, 2, U, U, ctrl, NULL};
    assert_err(cm_surf_eval(&s, 0.5, 0.5, 0, S, NULL), CM_E_LIMIT);
    assert_err(cm_knots_uniform(P + 1, P, U, NULL), CM_E_LIMIT);
}

/* Surface counts above CM_MAX_SURF_CTRL_DIR / CM_MAX_SURF_CTRL are refused before any array is read. */
static void test_surface_count_limits(void **state)
{
    (void)state;
    cm_status st;
    cm_surf s = {3, 3, CM_MAX_SURF_CTRL_DIR + 1, 4, NULL, NULL, NULL, NULL};
    cm_status_init(&st);
    assert_err(cm_surf_check(&s, &st), CM_E_LIMIT);
    assert_int_equal(st.limit, CM_LIMIT_MAX_SURF_CTRL_DIR);
    /* square root of the total limit per direction, rounded up: total just above the limit */
    int n = 1;
    while ((long)n * n <= CM_MAX_SURF_CTRL)
        n++;
    if (n <= CM_MAX_SURF_CTRL_DIR) {
        cm_surf t = {3, 3, n, n, NULL, NULL, NULL, NULL};
        cm_status_init(&st);
        assert_err(cm_surf_check(&t, &st), CM_E_LIMIT);
        assert_int_equal(st.limit, CM_LIMIT_MAX_SURF_CTRL);
        assert_int_equal(st.need, (uint64_t)n * n);
    }
}

/* K5: clamped uniform cubic knots and Greville abscissae for n = 7. */
static void test_uniform_knots_greville(void **state)
{
    (void)state;
    double U[11], xi[7];
    assert_ok(cm_knots_uniform(7, 3, U, NULL));
    const double expect[11] = {0, 0, 0, 0, 0.25, 0.5, 0.75, 1, 1, 1, 1};
    for (int i = 0; i < 11; i++)
        assert_true(U[i] == expect[i]);
    assert_ok(cm_greville(7, 3, U, xi, NULL));
    const double g[7] = {0, 1.0 / 12, 3.0 / 12, 6.0 / 12, 9.0 / 12, 11.0 / 12, 1};
    for (int i = 0; i < 7; i++)
        assert_near(xi[i], g[i], 1e-16);
    assert_err(cm_knots_uniform(3, 3, U, NULL), CM_E_RANGE);
}

/* The NURBS Book A2.3 as written (the kernel's general loop before its unrolled paths for first and
   second derivatives): the reference those paths must match bit for bit. */
static void reference_ders_basis(int span, double u, int p, int nd, const double *knots,
                                 double ders[CM_MAX_DERS + 1][CM_MAX_ORDER])
{
    double ndu[CM_MAX_ORDER][CM_MAX_ORDER], a[2][CM_MAX_ORDER], left[CM_MAX_ORDER], right[CM_MAX_ORDER];
    ndu[0][0] = 1.0;
    for (int j = 1; j <= p; j++) {
        left[j] = u - knots[span + 1 - j];
        right[j] = knots[span + j] - u;
        double saved = 0.0;
        for (int r = 0; r < j; r++) {
            ndu[j][r] = right[r + 1] + left[j - r];
            double temp = ndu[r][j - 1] / ndu[j][r];
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    for (int j = 0; j <= p; j++)
        ders[0][j] = ndu[j][p];
    int n = nd < p ? nd : p;
    for (int r = 0; r <= p; r++) {
        int s1 = 0, s2 = 1;
        a[0][0] = 1.0;
        for (int k = 1; k <= n; k++) {
            double d = 0.0;
            int rk = r - k, pk = p - k;
            if (r >= k) {
                a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
                d = a[s2][0] * ndu[rk][pk];
            }
            int j1 = rk >= -1 ? 1 : -rk;
            int j2 = (r - 1 <= pk) ? k - 1 : p - r;
            for (int j = j1; j <= j2; j++) {
                a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
                d += a[s2][j] * ndu[rk + j][pk];
            }
            if (r <= pk) {
                a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
                d += a[s2][k] * ndu[r][pk];
            }
            ders[k][r] = d;
            int t = s1;
            s1 = s2;
            s2 = t;
        }
    }
    double fac = (double)p;
    for (int k = 1; k <= n; k++) {
        for (int j = 0; j <= p; j++)
            ders[k][j] *= fac;
        fac *= (double)(p - k);
    }
    for (int k = n + 1; k <= nd; k++)
        for (int j = 0; j <= p; j++)
            ders[k][j] = 0.0;
}

/* the kernel's basis and derivatives are A2.3's bits, for every degree and derivative order, on uneven
   knots with repeats, at spans' ends and inside: the decoder's tessellation and the encoder's checks
   must not move a bit */
static void test_derivative_paths_same_bits(void **state)
{
    (void)state;
    uint32_t seed = 12345u;
    for (int p = 1; p <= CM_MAX_DEGREE; p++) {
        double U[2 * CM_MAX_ORDER + 8];
        int nctrl = p + 5, nk = nctrl + p + 1;
        for (int i = 0; i < nk; i++) {
            if (i <= p)
                U[i] = -1.5;
            else if (i >= nctrl)
                U[i] = 7.25;
            else {
                seed = seed * 1103515245u + 12345u;
                U[i] = U[i - 1] + ((seed >> 16) % 4 == 0 ? 0.0 : 0.1 + (double)((seed >> 8) % 1000) / 300.0);
                if (U[i] > 7.0)
                    U[i] = 7.0;
            }
        }
        for (int t = 0; t <= 200; t++) {
            double u = -1.5 + 8.75 * t / 200.0;
            int span = cm_bspl_find_span(nctrl, p, U, u);
            for (int nd = 0; nd <= CM_MAX_DERS; nd++) {
                double got[CM_MAX_DERS + 1][CM_MAX_ORDER], want[CM_MAX_DERS + 1][CM_MAX_ORDER];
                assert_ok(cm_bspl_ders_basis(span, u, p, nd, U, got, NULL));
                reference_ders_basis(span, u, p, nd, U, want);
                for (int k = 0; k <= nd; k++)
                    assert_memory_equal(got[k], want[k], (size_t)(p + 1) * sizeof(double));
            }
        }
    }
}

/* the surfaces the same-bits tests run over: a NET_U x NET_V net of seeded points and weights, and
   for each pair of degrees (within the build's) knots uneven in u from 0 to 1, even in v from -2 to 3 */
enum { NET_U = 7, NET_V = 6 };
static const int net_degs[][2] = {{3, 3}, {1, 2}, {2, 5}, {5, 1}, {3, 2}};
typedef struct test_net {
    cm_vec3 ctrl[NET_U * NET_V];
    double w[NET_U * NET_V];
    double U[NET_U + CM_MAX_ORDER], V[NET_V + CM_MAX_ORDER];
} test_net;

static void net_points(test_net *n, uint32_t seed)
{
    for (int i = 0; i < NET_U * NET_V; i++) {
        seed = seed * 1103515245u + 12345u;
        n->ctrl[i] = cm_v3((double)(seed % 1000) / 7.0, (double)((seed >> 10) % 1000) / 3.0,
                           (double)((seed >> 20) % 1000) / 11.0);
        n->w[i] = 0.5 + (double)((seed >> 5) % 100) / 50.0;
    }
}

/* the surface of degree pair d over n (0 when the build cannot take its degrees) */
static int net_surface(test_net *n, size_t d, int rational, cm_surf *s)
{
    int p = net_degs[d][0], q = net_degs[d][1];
    if (p > CM_MAX_DEGREE || q > CM_MAX_DEGREE)
        return 0; /* the tiny profile's degree limit */
    for (int i = 0; i < NET_U + p + 1; i++)
        n->U[i] = i <= p ? 0.0 : i >= NET_U ? 1.0 : (double)(i - p) / (NET_U - p) + 0.01 * (i & 1);
    for (int i = 0; i < NET_V + q + 1; i++)
        n->V[i] = i <= q ? -2.0 : i >= NET_V ? 3.0 : -2.0 + 5.0 * (i - q) / (NET_V - q);
    *s = (cm_surf){.p = p, .q = q, .nu = NET_U, .nv = NET_V, .U = n->U, .V = n->V, .ctrl = n->ctrl,
                   .w = rational ? n->w : NULL};
    return 1;
}

/* the surface's first-derivative path (nd = 1) gives the general loop's bits (nd = 2 runs it), on
   rational and polynomial nets of several degrees, across spans and at the ends */
static void test_surface_first_derivative_path_same_bits(void **state)
{
    (void)state;
    static test_net net;
    net_points(&net, 777u);
    for (size_t d = 0; d < sizeof net_degs / sizeof net_degs[0]; d++)
        for (int rational = 0; rational <= 1; rational++) {
            cm_surf s;
            if (!net_surface(&net, d, rational, &s))
                continue;
            for (int t = 0; t <= 40; t++) {
                double u = t / 40.0, v = -2.0 + 5.0 * ((t * 7) % 41) / 40.0;
                cm_vec3 S1[CM_MAX_DERS + 1][CM_MAX_DERS + 1], S2[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
                assert_ok(cm_surf_eval(&s, u, v, 1, S1, NULL));
                assert_ok(cm_surf_eval(&s, u, v, 2, S2, NULL));
                assert_memory_equal(&S1[0][0], &S2[0][0], sizeof(cm_vec3));
                assert_memory_equal(&S1[1][0], &S2[1][0], sizeof(cm_vec3));
                assert_memory_equal(&S1[0][1], &S2[0][1], sizeof(cm_vec3));
            }
        }
}

/* the curve evaluator (compiled per degree 1-3) gives the textbook A3.2 / A4.2 sums' bits over A2.3's
   basis, every degree, derivative order and span, rational and polynomial, clamped at both ends */
static void test_curve_eval_same_bits(void **state)
{
    (void)state;
    static const double binom_ref[3][3] = {{1, 0, 0}, {1, 1, 0}, {1, 2, 1}};
    uint32_t seed = 999u;
    for (int p = 1; p <= CM_MAX_DEGREE; p++)
        for (int rational = 0; rational <= 1; rational++) {
            enum { EXTRA = 5 };
            int n = p + 1 + EXTRA;
            double U[2 * CM_MAX_ORDER + EXTRA + 1], w[CM_MAX_ORDER + EXTRA];
            cm_vec3 P[CM_MAX_ORDER + EXTRA];
            for (int i = 0; i < n + p + 1; i++)
                U[i] = i <= p ? 0.0 : i >= n ? 3.0 : U[i - 1] + 0.2 + 0.1 * (i % 3);
            for (int i = 0; i < n; i++) {
                seed = seed * 1103515245u + 12345u;
                P[i] = cm_v3((double)(seed % 1000) / 7.0, (double)((seed >> 10) % 1000) / 3.0, (double)((seed >> 20) % 1000) / 11.0);
                w[i] = 0.5 + (double)((seed >> 5) % 100) / 50.0;
            }
            cm_curve c = {.p = p, .n_ctrl = n, .knots = U, .ctrl = P, .w = rational ? w : NULL};
            for (int t = -2; t <= 62; t++) {
                double u = 3.0 * t / 60.0;
                for (int nd = 0; nd <= CM_MAX_DERS; nd++) {
                    cm_vec3 got[CM_MAX_DERS + 1], want[CM_MAX_DERS + 1];
                    assert_ok(cm_curve_eval(&c, u, nd, got, NULL));
                    double uc = u < U[p] ? U[p] : (u > U[n] ? U[n] : u);
                    int span = cm_bspl_find_span(n, p, U, uc);
                    double N[CM_MAX_DERS + 1][CM_MAX_ORDER];
                    reference_ders_basis(span, uc, p, nd, U, N);
                    cm_vec3 A[CM_MAX_DERS + 1];
                    double W[CM_MAX_DERS + 1];
                    for (int k = 0; k <= nd; k++) {
                        A[k] = cm_v3(0, 0, 0);
                        W[k] = 0.0;
                        for (int j = 0; j <= p; j++) {
                            int i = span - p + j;
                            double wi = rational ? w[i] : 1.0;
                            A[k] = cm_axpy(A[k], N[k][j] * wi, P[i]);
                            W[k] += N[k][j] * wi;
                        }
                    }
                    for (int k = 0; k <= nd; k++) {
                        if (!rational) {
                            want[k] = A[k];
                            continue;
                        }
                        cm_vec3 v = A[k];
                        for (int i = 1; i <= k; i++)
                            v = cm_sub(v, cm_scale(want[k - i], binom_ref[k][i] * W[i]));
                        want[k] = cm_scale(v, 1.0 / W[0]);
                    }
                    assert_memory_equal(got, want, (size_t)(nd + 1) * sizeof(cm_vec3));
                }
            }
        }
}

/* the grid evaluator's points are cm_surf_eval's S[0][0] bit for bit (nd = 1, the path the grid
   searches used), rational and polynomial, several degrees, grid points inside spans, on knots and
   outside the domain (clamped), several grid points per span and spans skipped */
static void test_surface_grid_same_bits(void **state)
{
    (void)state;
    enum { GU = 13, GV = 17 };
    static test_net net;
    net_points(&net, 4242u);
    double gu[GU], gv[GV];
    for (int i = 0; i < GU; i++)
        gu[i] = -0.1 + 1.2 * i / (GU - 1); /* from below the domain to above it */
    for (int j = 0; j < GV; j++)
        gv[j] = -2.0 + 5.0 * j / (GV - 1) + (j % 3 == 1 ? 1e-3 : 0.0);
    for (size_t d = 0; d < sizeof net_degs / sizeof net_degs[0]; d++)
        for (int rational = 0; rational <= 1; rational++) {
            cm_surf s;
            if (!net_surface(&net, d, rational, &s))
                continue;
            cm_vec3 g[GU * GV];
            assert_ok(cm_surf_eval_grid(&s, gu, GU, gv, GV, g, NULL));
            for (int i = 0; i < GU; i++)
                for (int j = 0; j < GV; j++) {
                    cm_vec3 S[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
                    assert_ok(cm_surf_eval(&s, gu[i], gv[j], 1, S, NULL));
                    assert_memory_equal(&S[0][0], &g[i * GV + j], sizeof(cm_vec3));
                }
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ex23_basis_exact),
        cmocka_unit_test(test_derivative_paths_same_bits),
        cmocka_unit_test(test_surface_first_derivative_path_same_bits),
        cmocka_unit_test(test_surface_grid_same_bits),
        cmocka_unit_test(test_curve_eval_same_bits),
        cmocka_unit_test(test_ex24_derivatives_exact),
        cmocka_unit_test(test_find_span_edges),
        cmocka_unit_test(test_partition_of_unity),
        cmocka_unit_test(test_basis_derivatives_fd),
        cmocka_unit_test(test_rational_circle),
        cmocka_unit_test(test_rational_sphere_surface),
        cmocka_unit_test(test_surface_matches_curve),
        cmocka_unit_test(test_knot_insertion_preserves_curve),
        cmocka_unit_test(test_insert_into_bezier),
        cmocka_unit_test(test_knot_insertion_errors),
        cmocka_unit_test(test_knot_insertion_limit),
        cmocka_unit_test(test_knot_validation),
        cmocka_unit_test(test_degree_limit),
        cmocka_unit_test(test_surface_count_limits),
        cmocka_unit_test(test_uniform_knots_greville),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
