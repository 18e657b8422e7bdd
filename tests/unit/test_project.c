/* test_project.c - K9: curve and surface point projection. */
#include "test_util.h"

#include "cm/cm_param.h"
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

/* ---- cm_loop_uv's global searches: the grid's points kept for the loop, and forgotten after it ----
   A washboard (ridges across u) and the same washboard shifted by half a wave.  A loop of points
   high above the boards (each one a global search) is walked on the shifted board with a fresh
   workspace; then, with another fresh one, on the board and then on the shifted board at the same
   address: the second walk on the shifted board gives the first polygon to the bit, and the grids
   the workspace holds afterwards are the shifted board's points, not the board's. */
static cm_param_ws LOOP_WS;
static cm_vec2 LOOP_UV[2][2 * 64 + 2];
static int LOOP_SRC[2 * 64 + 2];

enum { WASH_NU = 10 };
static void washboard(cm_vec3 P[WASH_NU * 4], double phase)
{
    for (int i = 0; i < WASH_NU; i++)
        for (int j = 0; j < 4; j++)
            P[i * 4 + j] = cm_v3(10.0 * i / (WASH_NU - 1), 10.0 * j / 3.0, 2.0 * cos(M_PI * (i + phase)));
}

static int walk_loop(cm_psurf *ps, const cm_vec3 *pts, int n, cm_vec2 *out)
{
    int nout = 0, wu = 0, wv = 0;
    double gap = 0;
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_loop_uv(ps, pts, n, 0.01, out, LOOP_SRC, 2 * 64 + 2, &nout, &wu, &wv, &gap, &LOOP_WS, &st));
    return nout;
}

static void test_loop_grid_cache_per_loop(void **state)
{
    (void)state;
    static const double U[WASH_NU + 4] = {0, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7};
    static const double V[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    cm_vec3 P[WASH_NU * 4], Q[WASH_NU * 4];
    washboard(P, 0.0);
    washboard(Q, 1.0);
    cm_surf board = {3, 3, WASH_NU, 4, U, V, P, NULL}, shifted = {3, 3, WASH_NU, 4, U, V, Q, NULL};
    cm_psurf ps;
    cm_status st;
    cm_status_init(&st);
    enum { N = 24 };
    cm_vec3 pts[N];
    for (int k = 0; k < N; k++) /* a small circle high above the middle of the board */
        pts[k] = cm_v3(5.0 + 0.5 * cos(2 * M_PI * k / N), 5.0 + 0.5 * sin(2 * M_PI * k / N), 40.0);
    memset(&LOOP_WS, 0, sizeof LOOP_WS);
    assert_ok(cm_psurf_init(&ps, &shifted, 1e-9, &st));
    int n0 = walk_loop(&ps, pts, N, LOOP_UV[0]);
    memset(&LOOP_WS, 0, sizeof LOOP_WS);
    assert_ok(cm_psurf_init(&ps, &board, 1e-9, &st));
    (void)walk_loop(&ps, pts, N, LOOP_UV[1]);
    assert_ok(cm_psurf_init(&ps, &shifted, 1e-9, &st));
    int n1 = walk_loop(&ps, pts, N, LOOP_UV[1]);
    assert_int_equal(n1, n0);
    assert_memory_equal(LOOP_UV[1], LOOP_UV[0], (size_t)n0 * sizeof LOOP_UV[0][0]);
#if CM_PARAM_GRID_CACHE
    /* and the grids the workspace holds now are the shifted board's (the walk's searches used them) */
    int checked = 0;
    for (int which = 0; which < 2; which++) {
        int n = which ? 41 : 17;
        if (!LOOP_WS.grid_have[which])
            continue;
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++) {
                cm_vec3 d[3];
                assert_ok(cm_psurf_eval(&ps, ps.u0 + (ps.u1 - ps.u0) * i / (n - 1), ps.v0 + (ps.v1 - ps.v0) * j / (n - 1), d, &st));
                assert_memory_equal(&LOOP_WS.grid[(which ? 17 * 17 : 0) + i * n + j], &d[0], sizeof d[0]);
                checked++;
            }
    }
    assert_int_equal(checked, 17 * 17 + 41 * 41); /* points 40 mm off the board: both grids searched */
#endif
}

/* ---- format 4.8: a loop's first point from the control net ----
   A loop lying on the washboard is walked from the grids (net_start 0) and from the net: the same
   polygon (within the walks' precision: 4.8's searches stop at a step of 1e-10 of the domain), and
   from the net no grid is evaluated.  A loop 40 mm above the board cannot land from the net: the
   grids are searched as before, and the polygon is the same again. */
static void test_loop_net_start(void **state)
{
    (void)state;
    static const double U[WASH_NU + 4] = {0, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7};
    static const double V[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    cm_vec3 P[WASH_NU * 4];
    washboard(P, 0.3);
    cm_surf board = {3, 3, WASH_NU, 4, U, V, P, NULL};
    cm_psurf ps;
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_psurf_init(&ps, &board, 1e-9, &st));
    enum { N = 24 };
    cm_vec3 pts[N];
    for (int above = 0; above < 2; above++) {
        for (int k = 0; k < N; k++) { /* a circle in (u,v) round (4.6, 0.55), on the board or above it */
            cm_vec3 d[3];
            assert_ok(cm_psurf_eval(&ps, 4.6 + 1.5 * cos(2 * M_PI * k / N), 0.55 + 0.3 * sin(2 * M_PI * k / N), d, &st));
            pts[k] = above ? cm_v3(5.0 + 0.5 * cos(2 * M_PI * k / N), 5.0 + 0.5 * sin(2 * M_PI * k / N), 40.0) : d[0];
        }
        int n[2];
        for (int net = 0; net < 2; net++) {
            memset(&LOOP_WS, 0, sizeof LOOP_WS);
            LOOP_WS.net_start = net;
            n[net] = walk_loop(&ps, pts, N, LOOP_UV[net]);
#if CM_PARAM_GRID_CACHE
            /* the coarse grid: searched from the grids, and from the net only where it cannot land */
            assert_int_equal(LOOP_WS.grid_have[0], !net || above);
#endif
        }
        assert_int_equal(n[1], n[0]);
        for (int k = 0; k < n[0]; k++) {
            assert_near(LOOP_UV[1][k].x, LOOP_UV[0][k].x, 1e-7);
            assert_near(LOOP_UV[1][k].y, LOOP_UV[0][k].y, 1e-7);
        }
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
        cmocka_unit_test(test_loop_grid_cache_per_loop),
        cmocka_unit_test(test_loop_net_start),
        cmocka_unit_test(test_nurbs_surface_projection),
        cmocka_unit_test(test_gregory_projection),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
