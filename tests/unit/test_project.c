/* test_project.c - K9: curve and surface point projection. */
#include "test_util.h"

#include "cm/cm_project.h"

static const double q_U[6] = {0, 0, 0, 1, 1, 1};

/* A point off a quarter circle projects radially; a point on it returns its own parameter. */
static void test_curve_projection(void **state)
{
    (void)state;
    const double R = 7.0;
    const cm_vec3 P[3] = {{R, 0, 0}, {R, R, 0}, {0, R, 0}};
    const double w[3] = {1, TEST_SQRT1_2, 1};
    cm_curve c = {2, 3, q_U, P, w};
    for (int k = 0; k <= 10; k++) {
        double th = (M_PI / 2) * k / 10.0;
        cm_vec3 X = cm_v3(1.3 * R * cos(th), 1.3 * R * sin(th), 0.0), d[1];
        double t, dist;
        assert_ok(cm_curve_project(&c, 0, 1, X, &t, &dist, NULL));
        assert_near(dist, 0.3 * R, 1e-12 * R);
        assert_ok(cm_curve_eval(&c, t, 0, d, NULL));
        assert_vec_near(d[0], cm_v3(R * cos(th), R * sin(th), 0), 1e-9 * R);
        /* on the curve */
        cm_vec3 on;
        assert_ok(cm_curve_eval(&c, k / 10.0, 0, d, NULL));
        on = d[0];
        assert_ok(cm_curve_project(&c, 0, 1, on, &t, &dist, NULL));
        assert_near(dist, 0.0, 1e-12 * R);
        assert_near(t, k / 10.0, 1e-9);
    }
}

/* Sphere octant (rational biquadratic): S(u,v)*1.2 projects back to (u,v) at distance 0.2 R. */
static void test_nurbs_surface_projection(void **state)
{
    (void)state;
    const double R = 4.0, s = TEST_SQRT1_2;
    const double w[9] = {1, s, 1, s, 0.5, s, 1, s, 1};
    cm_vec3 P[9];
    const double mx[3] = {R, R, 0}, mz[3] = {0, R, R};
    for (int i = 0; i < 3; i++) {
        P[i * 3 + 0] = cm_v3(mx[i], 0, mz[i]);
        P[i * 3 + 1] = cm_v3(mx[i], mx[i], mz[i]);
        P[i * 3 + 2] = cm_v3(0, mx[i], mz[i]);
    }
    cm_surf surf = {2, 2, 3, 3, q_U, q_U, P, w};
    cm_patch pa = cm_patch_of_surf(&surf);
    for (int i = 1; i < 8; i++)
        for (int j = 1; j < 8; j++) {
            double u = i / 8.0 + 0.01, v = j / 8.0 - 0.02, uu, vv, dist;
            cm_vec3 d[3];
            assert_ok(cm_patch_eval(&pa, u, v, d, NULL));
            assert_ok(cm_patch_project(&pa, cm_scale(d[0], 1.2), &uu, &vv, &dist, NULL));
            assert_near(dist, 0.2 * R, 1e-10 * R);
            assert_near(uu, u, 1e-7); /* parameters: sqrt of the distance tolerance */
            assert_near(vv, v, 1e-7);
        }
}

static cm_gregory test_patch(uint32_t *seed, int collapse)
{
    cm_gregory g;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            g.P[i][j] = cm_add(cm_v3(i, j, 0.3 * i * j / 3.0), test_rand_vec(seed, 0.2));
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) {
            g.I[a][b][0] = cm_add(g.P[a + 1][b + 1], test_rand_vec(seed, 0.1));
            g.I[a][b][1] = cm_add(g.P[a + 1][b + 1], test_rand_vec(seed, 0.1));
        }
    if (collapse) /* side u = 0 collapsed to one point: a 3-sided degenerate patch (spec 6.5 layout 2) */
        for (int j = 0; j < 4; j++)
            g.P[0][j] = g.P[0][0];
    return g;
}

/* Points of a Gregory patch project onto themselves, also next to a collapsed corner (LM, not Newton). */
static void test_gregory_projection(void **state)
{
    (void)state;
    uint32_t seed = 51;
    for (int collapse = 0; collapse <= 1; collapse++) {
        cm_gregory g = test_patch(&seed, collapse);
        cm_patch pa = cm_patch_of_gregory(&g);
        const double us[6] = {0.5, 0.1, 0.9, 0.02, 0.003, 0.7}, vs[6] = {0.5, 0.8, 0.05, 0.5, 0.6, 0.999};
        for (int k = 0; k < 6; k++) {
            cm_vec3 S, Su, Sv;
            cm_greg_eval(&g, us[k], vs[k], &S, &Su, &Sv);
            double u, v, dist;
            assert_ok(cm_patch_project(&pa, S, &u, &v, &dist, NULL));
            assert_near(dist, 0.0, 1e-9); /* the point lies on the patch */
            if (!collapse) {
                assert_near(u, us[k], 1e-6);
                assert_near(v, vs[k], 1e-6);
            }
            /* lifted along the normal by 0.01: distance 0.01 unless near the collapsed side */
            cm_vec3 n = cm_cross(Su, Sv);
            if (cm_norm(n) > 1e-3) {
                assert_ok(cm_patch_project(&pa, cm_axpy(S, 0.01, cm_unit(n)), &u, &v, &dist, NULL));
                assert_near(dist, 0.01, 1e-6);
            }
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_curve_projection),
        cmocka_unit_test(test_nurbs_surface_projection),
        cmocka_unit_test(test_gregory_projection),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
