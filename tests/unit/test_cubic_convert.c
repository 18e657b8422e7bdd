/* test_cubic_convert.c - K7 cubic edge conversion: exact cases, circular arcs (spec T4 values); format
   4.14's closed form for a one-span conic (cm_cubic_from_conic, cm_edge_cubic). */
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


/* Format 4.14: a one-span conic's cubic in closed form.  A 90 degree arc of R = 10: its ends and end
   tangents kept, its middle point on the circle, the handle 4/3 tan(22.5 deg) R (0.55228 R, inside
   T4's K7 window), its radial error 2.7e-4 R (K7's fit: 2.0e-4 R; the price of the closed form);
   the same curve with its weights scaled, the same cubic; a parabola (equal weights), its exact
   degree elevation; the wider arcs near their K7 errors.  Red with the weight taken as w1 alone
   (the scaled weights), with a = 2/3 (the arc's middle point). */
static void test_conic_closed_form(void **state)
{
    (void)state;
    arc a;
    make_arc(&a, 10.0, M_PI / 2);
    cm_cubic cu;
    assert_int_equal(cm_cubic_from_conic(&a.c, &cu), 1);
    assert_vec_near(cu.c[0], a.P[0], 0.0);
    assert_vec_near(cu.c[3], a.P[2], 0.0);
    double k = cm_dist(cu.c[1], cu.c[0]) / 10.0;
    assert_near(k, 4.0 / 3.0 * tan(M_PI / 8), 1e-14);
    assert_near(cm_dist(cu.c[2], cu.c[3]) / 10.0, k, 1e-14);
    assert_near(cu.c[1].x, 10.0, 1e-13); /* along the end tangent */
    cm_vec3 d[3];
    cm_cubic_eval(&cu, 0.5, d);
    assert_near(cm_norm(d[0]), 10.0, 1e-12);
    double err = radial_error(&cu, 10.0);
    print_message("# 90 deg arc: closed form radial error %.3g R\n", err / 10.0);
    assert_true(err >= 2.6e-4 * 10.0 && err <= 2.8e-4 * 10.0);
    /* the weights scaled (w0 = w2 = 2, w1 = 2 cos 45 deg: the same curve), the same cubic */
    arc b = a;
    b.w[0] = b.w[2] = 2.0;
    b.w[1] = 2.0 * a.w[1];
    b.c.w = b.w;
    b.c.ctrl = b.P;
    b.c.knots = b.U;
    cm_cubic cb;
    assert_int_equal(cm_cubic_from_conic(&b.c, &cb), 1);
    for (int i = 0; i < 4; i++)
        assert_vec_near(cb.c[i], cu.c[i], 1e-13);
    /* a parabola: equal weights, the quadratic's exact elevation */
    b.w[0] = b.w[1] = b.w[2] = 3.0;
    assert_int_equal(cm_cubic_from_conic(&b.c, &cb), 1);
    cm_cubic el = cm_cubic_from_quad(b.P[0], b.P[1], b.P[2]);
    for (int i = 0; i < 4; i++)
        assert_vec_near(cb.c[i], el.c[i], 1e-14);
    /* wider arcs: 120 deg within 1.5 times K7's prototype error, 170 deg short of failing */
    make_arc(&a, 1.0, 2 * M_PI / 3);
    assert_int_equal(cm_cubic_from_conic(&a.c, &cu), 1);
    double e120 = radial_error(&cu, 1.0);
    print_message("# 120 deg arc: closed form radial error %.3g R (K7's prototype 1.2e-3)\n", e120);
    assert_true(e120 <= 1.5 * 1.2e-3);
}

/* cm_edge_cubic's cubic for c (flag `conic`) is `want` to the bit; returns cm_edge_cubic_delta's measure */
static double edge_cubic_is(const cm_curve *c, int conic, const cm_cubic *want)
{
    cm_cubic cu;
    double d;
    assert_ok(cm_edge_cubic(c, conic, &cu, NULL));
    assert_ok(cm_edge_cubic_delta(c, &cu, &d, NULL));
    for (int i = 0; i < 4; i++)
        assert_vec_near(cu.c[i], want->c[i], 0.0);
    return d;
}

/* What cm_cubic_from_conic refuses (out untouched), and cm_edge_cubic's choice: K7 without the
   flag or for any other curve (the same cubic as cm_cubic_convert's, and cm_edge_cubic_delta the same
   delta as its own), the closed form with it.  Red with the flag ignored. */
static void test_edge_cubic_choice(void **state)
{
    (void)state;
    arc a;
    make_arc(&a, 10.0, M_PI / 2);
    const cm_cubic mark = {{{7, 7, 7}, {7, 7, 7}, {7, 7, 7}, {7, 7, 7}}};
    cm_cubic cu = mark, k7, cf;
    arc bad = a;
    bad.c.w = NULL; /* a polynomial quadratic: elevated exactly by K7, not a conic here */
    assert_int_equal(cm_cubic_from_conic(&bad.c, &cu), 0);
    bad = a;
    bad.w[1] = 0.0;
    bad.c.w = bad.w;
    assert_int_equal(cm_cubic_from_conic(&bad.c, &cu), 0);
    bad.w[1] = -0.5;
    assert_int_equal(cm_cubic_from_conic(&bad.c, &cu), 0);
    arc h;
    make_half_circle(&h, 10.0); /* two spans */
    assert_int_equal(cm_cubic_from_conic(&h.c, &cu), 0);
    for (int i = 0; i < 4; i++)
        assert_vec_near(cu.c[i], mark.c[i], 0.0);

    double dk;
    assert_ok(cm_cubic_convert(&a.c, 0, 1, &k7, &dk, NULL, NULL));
    assert_true(edge_cubic_is(&a.c, 0, &k7) == dk);
    assert_int_equal(cm_cubic_from_conic(&a.c, &cf), 1);
    double dc = edge_cubic_is(&a.c, 1, &cf);
    assert_true(cm_dist(cf.c[1], k7.c[1]) > 1e-4); /* the two cubics differ */
    assert_true(dc > dk && dc <= 2.8e-4 * 10.0);
    /* two spans: K7 with or without the flag */
    assert_ok(cm_cubic_convert(&h.c, 0, 1, &k7, &dk, NULL, NULL));
    assert_true(edge_cubic_is(&h.c, 1, &k7) == dk);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quarter_arc),
        cmocka_unit_test(test_wide_arcs),
        cmocka_unit_test(test_exact_cases),
        cmocka_unit_test(test_convert_errors),
        cmocka_unit_test(test_conic_closed_form),
        cmocka_unit_test(test_edge_cubic_choice),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
