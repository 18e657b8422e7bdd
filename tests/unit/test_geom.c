/* test_geom.c - K10 lines and planes, K11 face frame, K12 point in polygon. */
#include "test_util.h"

#include "cm/cm_geom.h"

static void test_lines_closest(void **state)
{
    (void)state;
    double lam, mu;
    /* x axis and the line through (0,1,1) along y: closest points (0,0,0) and (0,0,1) */
    assert_int_equal(cm_lines_closest(cm_v3(5, 0, 0), cm_v3(2, 0, 0), cm_v3(0, 1, 1), cm_v3(0, -1, 0), &lam, &mu), 1);
    assert_near(lam, -2.5, 1e-15);
    assert_near(mu, 1.0, 1e-15);
    assert_int_equal(cm_lines_closest(cm_v3(0, 0, 0), cm_v3(1, 1, 0), cm_v3(0, 1, 0), cm_v3(-2, -2, 0), &lam, &mu), 0);
}

/* K10: rays closer than 5 deg to the plane are refused; 6 deg is accepted. */
static void test_ray_plane(void **state)
{
    (void)state;
    double lam;
    cm_vec3 m = cm_v3(0, 0, 1);
    assert_int_equal(cm_ray_plane(cm_v3(0, 0, 0), cm_v3(0, 0, 2), m, 3.0, &lam), 1);
    assert_near(lam, 1.5, 0);
    double a4 = 4.0 * M_PI / 180, a6 = 6.0 * M_PI / 180;
    assert_int_equal(cm_ray_plane(cm_v3(0, 0, 0), cm_v3(cos(a4), 0, sin(a4)), m, 1.0, &lam), 0);
    assert_int_equal(cm_ray_plane(cm_v3(0, 0, 0), cm_v3(cos(a6), 0, sin(a6)), m, 1.0, &lam), 1);
    assert_near(lam, 1.0 / sin(a6), 1e-12);
}

/* K11 on a 4 x 1 rectangle in a tilted plane: normal, origin, long axis, sign rule, right-handedness. */
static void test_face_frame_rectangle(void **state)
{
    (void)state;
    cm_vec3 a = cm_unit(cm_v3(1, 1, 0)), b = cm_unit(cm_v3(-1, 1, 1)), n = cm_cross(a, b);
    cm_vec3 c = cm_v3(100, -50, 20); /* far from the origin on purpose */
    cm_vec3 pts[40];
    int k = 0;
    /* CCW around n: 10 samples per side */
    for (int i = 0; i < 10; i++) pts[k++] = cm_add(c, cm_add(cm_scale(a, -2 + 0.4 * i), cm_scale(b, -0.5)));
    for (int i = 0; i < 10; i++) pts[k++] = cm_add(c, cm_add(cm_scale(a, 2), cm_scale(b, -0.5 + 0.1 * i)));
    for (int i = 0; i < 10; i++) pts[k++] = cm_add(c, cm_add(cm_scale(a, 2 - 0.4 * i), cm_scale(b, 0.5)));
    for (int i = 0; i < 10; i++) pts[k++] = cm_add(c, cm_add(cm_scale(a, -2), cm_scale(b, 0.5 - 0.1 * i)));
    cm_frame f;
    assert_ok(cm_face_frame(pts, 40, pts, 40, 1e-9, &f, NULL));
    assert_vec_near(f.ez, n, 1e-12);
    assert_vec_near(f.o, c, 1e-12);
    assert_near(fabs(cm_dot(f.ex, a)), 1.0, 1e-12); /* major inertia axis = long side */
    assert_true(cm_dot(cm_sub(pts[0], f.o), f.ex) <= 0.0);
    assert_vec_near(f.ey, cm_cross(f.ez, f.ex), 1e-15);
    cm_vec3 l = cm_frame_local(&f, pts[5]);
    assert_near(l.z, 0.0, 1e-12);
    assert_vec_near(cm_frame_world(&f, l), pts[5], 1e-12);
    /* the reversed loop flips the normal */
    cm_vec3 rev[40];
    for (int i = 0; i < 40; i++)
        rev[i] = pts[39 - i];
    assert_ok(cm_face_frame(rev, 40, rev, 40, 1e-9, &f, NULL));
    assert_vec_near(f.ez, cm_neg(n), 1e-12);
}

/* A square has isotropic inertia: the fixed fallback axis is used, deterministically. */
static void test_face_frame_square_and_degenerate(void **state)
{
    (void)state;
    cm_vec3 sq[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    cm_frame f;
    assert_ok(cm_face_frame(sq, 4, sq, 4, 1e-9, &f, NULL));
    assert_vec_near(f.ez, cm_v3(0, 0, 1), 0);
    assert_near(cm_dot(f.ex, f.ez), 0.0, 1e-16);
    assert_true(cm_dot(cm_sub(sq[0], f.o), f.ex) <= 0.0);
    cm_vec3 line[3] = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
    assert_err(cm_face_frame(line, 3, line, 3, 1e-9, &f, NULL), CM_E_DEGENERATE);
}

/* K12: inside, outside, on edges and vertices (inside), and a concave L-shape. */
static void test_point_in_polygon(void **state)
{
    (void)state;
    const cm_vec2 sq[4] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
    assert_int_equal(cm_point_in_polygon(sq, 4, cm_v2(1, 1)), 1);
    assert_int_equal(cm_point_in_polygon(sq, 4, cm_v2(3, 1)), 0);
    assert_int_equal(cm_point_in_polygon(sq, 4, cm_v2(2, 1)), 1);  /* on an edge */
    assert_int_equal(cm_point_in_polygon(sq, 4, cm_v2(0, 0)), 1);  /* a vertex */
    assert_int_equal(cm_point_in_polygon(sq, 4, cm_v2(1, 2)), 1);  /* on the top edge */
    assert_int_equal(cm_point_in_polygon(sq, 4, cm_v2(-1, 2)), 0); /* level with an edge, outside */
    const cm_vec2 L[6] = {{0, 0}, {20, 0}, {20, 8}, {8, 8}, {8, 16}, {0, 16}};
    assert_int_equal(cm_point_in_polygon(L, 6, cm_v2(4, 12)), 1);
    assert_int_equal(cm_point_in_polygon(L, 6, cm_v2(12, 12)), 0); /* in the notch */
    assert_int_equal(cm_point_in_polygon(L, 6, cm_v2(15, 4)), 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lines_closest),
        cmocka_unit_test(test_ray_plane),
        cmocka_unit_test(test_face_frame_rectangle),
        cmocka_unit_test(test_face_frame_square_and_degenerate),
        cmocka_unit_test(test_point_in_polygon),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
