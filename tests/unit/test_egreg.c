/*
 * test_egreg.c - the Gregory patch over exact boundaries (cm_egreg.h) on its
 * own: the properties its formula promises, checked on a warped patch whose
 * sides are cubics and whose cross derivatives are given explicitly and
 * agree at the corners (the case Gregory's construction makes exact):
 *   - the four boundary curves are interpolated;
 *   - the cross derivative along each side is the given one, all along it
 *     (the compatibility-corrected twists at work);
 *   - S_u and S_v are the true partial derivatives (central differences);
 *   - a surface linear in v between two curved sides is reproduced.
 */
#include "test_util.h"

#include "cm/cm_egreg.h"

/* the loop: side 0 v=0 (+u), side 1 u=1 (+v), side 2 v=1 (-u), side 3 u=0 (-v), as cubics */
static const cm_vec3 C00 = {0, 0, 0}, C10 = {10, 0, 1}, C11 = {11, 9, 3}, C01 = {-1, 10, 2};

static cm_cubic cubic_between(cm_vec3 a, cm_vec3 b, cm_vec3 bend)
{
    cm_vec3 d = cm_sub(b, a);
    cm_cubic c = {{a, cm_add(cm_axpy(a, 1.0 / 3.0, d), bend), cm_sub(cm_axpy(b, -1.0 / 3.0, d), bend), b}};
    return c;
}

/* cubic derivative (per unit s) at the ends */
static cm_vec3 d_start(const cm_cubic *c) { return cm_scale(cm_sub(c->c[1], c->c[0]), 3.0); }
static cm_vec3 d_end(const cm_cubic *c) { return cm_scale(cm_sub(c->c[3], c->c[2]), 3.0); }

/*
 * A patch with cubic sides and explicit (Bezier) cross derivatives X_k into the patch, chosen to
 * agree with the neighbouring sides at the corners: X_k(0) = -B_{k-1}'(1), X_k(1) = B_{k+1}'(0),
 * and free inner coefficients (a bulge of the cross derivative).
 */
static void warped_patch(cm_egreg *g, double bulge)
{
    memset(g, 0, sizeof *g);
    cm_cubic s[4] = {cubic_between(C00, C10, cm_v3(0, -1, 2)), cubic_between(C10, C11, cm_v3(1, 0, -1)),
                     cubic_between(C11, C01, cm_v3(0, 1, 1)), cubic_between(C01, C00, cm_v3(-1, 0, 0.5))};
    for (int k = 0; k < 4; k++) {
        cm_egreg_side *sd = &g->side[k];
        sd->kind = CM_EGREG_SIDE_CUBIC;
        sd->cub = s[k];
        sd->fan = 1;
        cm_vec3 x0 = cm_neg(d_end(&s[(k + 3) & 3])), x3 = d_start(&s[(k + 1) & 3]);
        /* inner coefficients lifted differently, so that X_k'(0) and X_k'(1) differ (twists) */
        cm_vec3 lift1 = cm_v3(0, 0, bulge * (k + 1)), lift2 = cm_v3(bulge * (k + 2), -bulge, 0);
        sd->fx[0] = x0;
        sd->fx[1] = cm_add(cm_axpy(x0, 1.0 / 3.0, cm_sub(x3, x0)), lift1);
        sd->fx[2] = cm_add(cm_axpy(x3, -1.0 / 3.0, cm_sub(x3, x0)), lift2);
        sd->fx[3] = x3;
    }
    cm_status st;
    cm_status_init(&st);
    assert_int_equal(cm_egreg_finish(g, &st), CM_OK);
}

static cm_vec3 side_point(const cm_egreg *g, int k, double s, cm_vec3 *x)
{
    cm_vec3 d[3], xx[2];
    assert_int_equal(cm_egreg_side_eval(&g->side[k], s, d, xx, NULL), CM_OK);
    if (x)
        *x = xx[0];
    return d[0];
}

static void eval(const cm_egreg *g, double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv)
{
    assert_int_equal(cm_egreg_eval(g, u, v, S, Su, Sv, NULL), CM_OK);
}

static void test_boundary_and_cross_derivatives(void **state)
{
    (void)state;
    cm_egreg g;
    warped_patch(&g, 3.0);
    for (int i = 0; i <= 16; i++) {
        double t = i / 16.0;
        cm_vec3 S, Su, Sv, X;
        /* side 0: S(t,0) = B0(t), S_v(t,0) = X0(t) */
        eval(&g, t, 0, &S, &Su, &Sv);
        assert_vec_near(S, side_point(&g, 0, t, &X), 1e-12);
        assert_vec_near(Sv, X, 1e-9);
        /* side 1: S(1,t) = B1(t), S_u(1,t) = -X1(t) (X points into the patch) */
        eval(&g, 1, t, &S, &Su, &Sv);
        assert_vec_near(S, side_point(&g, 1, t, &X), 1e-12);
        assert_vec_near(Su, cm_neg(X), 1e-9);
        /* side 2: S(t,1) = B2(1-t), S_v(t,1) = -X2(1-t) */
        eval(&g, t, 1, &S, &Su, &Sv);
        assert_vec_near(S, side_point(&g, 2, 1 - t, &X), 1e-12);
        assert_vec_near(Sv, cm_neg(X), 1e-9);
        /* side 3: S(0,t) = B3(1-t), S_u(0,t) = X3(1-t) */
        eval(&g, 0, t, &S, &Su, &Sv);
        assert_vec_near(S, side_point(&g, 3, 1 - t, &X), 1e-12);
        assert_vec_near(Su, X, 1e-9);
    }
}

static void test_partials_are_derivatives(void **state)
{
    (void)state;
    cm_egreg g;
    warped_patch(&g, 3.0);
    const double h = 1e-6;
    for (int i = 1; i < 8; i++)
        for (int j = 1; j < 8; j++) {
            double u = i / 8.0 + 0.01, v = j / 8.0 - 0.02;
            cm_vec3 S, Su, Sv, a, b;
            eval(&g, u, v, &S, &Su, &Sv);
            eval(&g, u + h, v, &a, NULL, NULL);
            eval(&g, u - h, v, &b, NULL, NULL);
            assert_vec_near(Su, cm_scale(cm_sub(a, b), 0.5 / h), 1e-5 * (1 + cm_norm(Su)));
            eval(&g, u, v + h, &a, NULL, NULL);
            eval(&g, u, v - h, &b, NULL, NULL);
            assert_vec_near(Sv, cm_scale(cm_sub(a, b), 0.5 / h), 1e-5 * (1 + cm_norm(Sv)));
        }
}

/* between two equal arcs (as cubics) at z = 0 and z = 5 joined by lines, with the cross derivative
   along the arcs the line vector: S(u,v) = arc(u) + v (0,0,5) exactly */
static void test_linear_between_curves(void **state)
{
    (void)state;
    cm_egreg g;
    memset(&g, 0, sizeof g);
    cm_cubic arc = {{{10, 0, 0}, {10, 5.5, 0}, {5.5, 10, 0}, {0, 10, 0}}};
    cm_vec3 up = {0, 0, 5};
    cm_cubic top = arc, line1, line3;
    for (int i = 0; i < 4; i++)
        top.c[i] = cm_add(arc.c[i], up);
    line1 = cubic_between(arc.c[3], top.c[3], cm_v3(0, 0, 0));
    line3 = cubic_between(arc.c[0], top.c[0], cm_v3(0, 0, 0));
    g.side[0].cub = arc;
    g.side[1].cub = line1;
    g.side[2].cub = cm_cubic_reverse(&top);
    g.side[3].cub = cm_cubic_reverse(&line3);
    for (int k = 0; k < 4; k++) {
        g.side[k].kind = CM_EGREG_SIDE_CUBIC;
        g.side[k].fan = 1;
    }
    /* arcs: the cross derivative is +-up; lines: the arc's tangent at its end, into the patch */
    for (int i = 0; i < 4; i++) {
        g.side[0].fx[i] = up;
        g.side[2].fx[i] = cm_neg(up);
    }
    cm_vec3 t1 = d_end(&arc), t0 = d_start(&arc);
    for (int i = 0; i < 4; i++) {
        g.side[1].fx[i] = cm_neg(t1);
        g.side[3].fx[i] = t0;
    }
    assert_int_equal(cm_egreg_finish(&g, NULL), CM_OK);
    for (int i = 0; i <= 8; i++)
        for (int j = 0; j <= 8; j++) {
            cm_vec3 S, d[3];
            eval(&g, i / 8.0, j / 8.0, &S, NULL, NULL);
            cm_cubic_eval(&arc, i / 8.0, d);
            assert_vec_near(S, cm_axpy(d[0], j / 8.0, up), 1e-12);
        }
}

/* hostile numbers in a patch: clean answers, never a NaN out */
static void test_nonfinite(void **state)
{
    (void)state;
    cm_egreg g;
    warped_patch(&g, 0.0);
    cm_vec3 S, Su, Sv;
    cm_status st;
    /* a NaN reaching a patch that was built: the evaluation says so */
    g.side[1].fx[1].x = nan("");
    cm_status_init(&st);
    assert_int_equal(cm_egreg_eval(&g, 0.9, 0.5, &S, &Su, &Sv, &st), CM_E_NONFINITE);
    assert_int_equal(st.code, CM_E_NONFINITE);
    /* ... and building with it: the twists use it, the corner data refuse it */
    cm_status_init(&st);
    assert_int_equal(cm_egreg_finish(&g, &st), CM_E_NONFINITE);
    assert_int_equal(st.code, CM_E_NONFINITE);
    g.side[1].fx[1].x = 0;
    g.side[1].fx[0].y = HUGE_VAL;
    cm_status_init(&st);
    assert_int_equal(cm_egreg_finish(&g, &st), CM_E_NONFINITE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_boundary_and_cross_derivatives),
        cmocka_unit_test(test_partials_are_derivatives),
        cmocka_unit_test(test_linear_between_curves),
        cmocka_unit_test(test_nonfinite),
    };
    return cmocka_run_group_tests_name("egreg", tests, NULL, NULL);
}
