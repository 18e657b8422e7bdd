/*
 * test_fit_board - an edge curve or a kept surface over a board's limits is re-approximated within
 * its tolerance, or left as it is (issue 14.5; host_tools/encode/fit_board.c).  Each result is
 * measured here independently: the distance to the original at parameters the fit never looked at.
 */
#include "../unit/test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_bspline.h"
#include "encode/encode_internal.h"
#include "geom/hnurbs.h"

/* a helix-like polynomial curve of degree 3 with n control points through points of the helix */
static void long_curve(hcurve *c, int n)
{
    assert_int_equal(hcurve_alloc(c, 3, n, 0, NULL), CM_OK);
    for (int i = 0; i <= 3; i++) {
        c->knots[i] = 0.0;
        c->knots[n + i] = 1.0;
    }
    for (int i = 1; i < n - 3; i++)
        c->knots[3 + i] = (double)i / (n - 3);
    for (int i = 0; i < n; i++) {
        double t = 6.0 * M_PI * i / (n - 1);
        c->ctrl[i] = cm_v3(20.0 * cos(t), 20.0 * sin(t), 3.0 * t);
    }
}

static double curve_gap(const hcurve *a, const hcurve *b, int samples)
{
    cm_curve va = hcurve_view(a), vb = hcurve_view(b);
    double worst = 0;
    for (int k = 0; k <= samples; k++) {
        double u = (k + 0.37) / (samples + 1.0); /* between the fit's and the check's parameters */
        cm_vec3 p, q;
        assert_int_equal(cm_curve_eval(&va, u, 0, &p, NULL), CM_OK);
        assert_int_equal(cm_curve_eval(&vb, u, 0, &q, NULL), CM_OK);
        worst = fmax(worst, cm_dist(p, q));
    }
    return worst;
}

static void test_edge_refit(void **state)
{
    (void)state;
    hcurve orig = {0}, c = {0};
    long_curve(&orig, 495);
    assert_int_equal(hcurve_copy(&orig, &c, NULL), CM_OK);
    /* 495 -> 256 control points (the terminal's MAX_EDGE_CTRL) within 0.05 mm of a 380 mm helix */
    assert_int_equal(enc_edge_refit(&c, 9, 256, 0.05, NULL), 1);
    assert_int_equal(c.n, 256);
    assert_int_equal(c.p, 3);
    assert_true(cm_dist(c.ctrl[0], orig.ctrl[0]) == 0.0 && cm_dist(c.ctrl[255], orig.ctrl[494]) == 0.0);
    double gap = curve_gap(&orig, &c, 5000);
    if (!(gap <= 0.05))
        fail_msg("the re-fitted edge is %g mm off (tolerance 0.05)", gap);
    /* degree 2 at most (a board of MAX_DEGREE 2) */
    hcurve_free(&c);
    assert_int_equal(hcurve_copy(&orig, &c, NULL), CM_OK);
    assert_int_equal(enc_edge_refit(&c, 2, 256, 0.5, NULL), 1);
    assert_int_equal(c.p, 2);
    assert_true(curve_gap(&orig, &c, 5000) <= 0.5);
    /* 8 control points cannot follow three turns within 1e-3 mm: left as it is */
    hcurve_free(&c);
    assert_int_equal(hcurve_copy(&orig, &c, NULL), CM_OK);
    assert_int_equal(enc_edge_refit(&c, 9, 8, 1e-3, NULL), 0);
    assert_int_equal(c.n, 495);
    assert_true(curve_gap(&orig, &c, 100) == 0.0);
    hcurve_free(&c);
    hcurve_free(&orig);
}

/* a swept surface, rational: quarter circles (degree 2, weights 1, sqrt(1/2), 1) in v along a long
   cubic path in u, its weights also varying along u (scaled by 1 + 0.3 sin), as a revolved B-spline
   profile has */
static void swept_surface(hsurf *s, int nu)
{
    assert_int_equal(hsurf_alloc(s, 3, 2, nu, 3, 1, NULL), CM_OK);
    for (int i = 0; i <= 3; i++) {
        s->U[i] = 0.0;
        s->U[nu + i] = 1.0;
    }
    for (int i = 1; i < nu - 3; i++)
        s->U[3 + i] = (double)i / (nu - 3);
    for (int j = 0; j < 3; j++) {
        s->V[j] = 0.0;
        s->V[3 + j] = 1.0;
    }
    static const double arc[3][2] = {{1, 0}, {1, 1}, {0, 1}};
    for (int i = 0; i < nu; i++) {
        double t = (double)i / (nu - 1), r = 5.0 + 2.0 * sin(4.0 * M_PI * t), scale = 1.0 + 0.3 * sin(7.0 * t);
        for (int j = 0; j < 3; j++) {
            s->ctrl[i * 3 + j] = cm_v3(r * arc[j][0], r * arc[j][1], 100.0 * t);
            s->w[i * 3 + j] = (j == 1 ? sqrt(0.5) : 1.0) * scale;
        }
    }
}

static double surface_gap(const hsurf *a, const hsurf *b)
{
    cm_surf va = hsurf_view(a), vb = hsurf_view(b);
    double worst = 0;
    for (int i = 0; i <= 300; i++)
        for (int j = 0; j <= 7; j++) {
            double u = (i + 0.41) / 301.0, v = (j + 0.29) / 8.0;
            cm_vec3 A[CM_MAX_DERS + 1][CM_MAX_DERS + 1], B[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
            assert_int_equal(cm_surf_eval(&va, u, v, 0, A, NULL), CM_OK);
            assert_int_equal(cm_surf_eval(&vb, u, v, 0, B, NULL), CM_OK);
            worst = fmax(worst, cm_dist(A[0][0], B[0][0]));
        }
    return worst;
}

static void test_surface_refit(void **state)
{
    (void)state;
    hsurf orig = {0}, s = {0};
    swept_surface(&orig, 178); /* Pieza1's kept surface: 178 x 3, rational both ways */
    assert_int_equal(hsurf_copy(&orig, &s, NULL), CM_OK);
    assert_int_equal(enc_surf_refit(&s, 9, 128, 8192, 0.01, NULL), 1);
    assert_int_equal(s.nu, 128);
    assert_int_equal(s.nv, 3);
    assert_non_null(s.w);
    for (int k = 0; k < s.nu * s.nv; k++)
        assert_true(s.w[k] > 0);
    double gap = surface_gap(&orig, &s);
    if (!(gap <= 0.01))
        fail_msg("the re-fitted surface is %g mm off (tolerance 0.01)", gap);
    /* 6 control points cannot follow two waves within 1e-4 mm: left as it is */
    hsurf_free(&s);
    assert_int_equal(hsurf_copy(&orig, &s, NULL), CM_OK);
    assert_int_equal(enc_surf_refit(&s, 9, 6, 8192, 1e-4, NULL), 0);
    assert_int_equal(s.nu, 178);
    assert_true(surface_gap(&orig, &s) == 0.0);
    hsurf_free(&s);
    hsurf_free(&orig);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_edge_refit),
        cmocka_unit_test(test_surface_refit),
    };
    return cmocka_run_group_tests_name("fit_board", tests, NULL, NULL);
}
