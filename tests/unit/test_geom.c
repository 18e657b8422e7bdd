/* test_geom.c - K10 lines and planes, K11 face frame, K12 point in polygon, a chord's S part. */
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

/*
 * cm_chord_s_part (format 4.7's refinement tests a side's quarter points where this exceeds a
 * quarter of the tolerance): curves in a tilted plane, normals in that plane.  An arc gives 0 at
 * any angle; y = A sin(2 pi x / L), which is 0 at the middle and A at the quarter points, about
 * 0.6 A for small A and never below a quarter of A; a cubic S with small slopes its own peak;
 * a half-sine (an arc-like bump) 0 again.
 */
static cm_vec3 in_plane(double x, double y)
{
    cm_vec3 ex = cm_unit(cm_v3(2, 1, -1)), ey = cm_unit(cm_cross(cm_v3(0.3, -1, 2), ex));
    return cm_add(cm_v3(7, -3, 11), cm_add(cm_scale(ex, x), cm_scale(ey, y)));
}

static cm_vec3 plane_normal(double slope) /* unit normal of a curve rising at `slope` */
{
    cm_vec3 o = in_plane(0, 0);
    return cm_unit(cm_sub(in_plane(-slope, 1), o));
}

static void test_chord_s_part(void **state)
{
    (void)state;
    const double L = 10;
    for (double a = 0.05; a < 3.0; a += 0.3) { /* an arc of radius 5 over the angle a */
        double R = 5, x0 = -R * sin(a / 2), x1 = R * sin(a / 2);
        double s = cm_chord_s_part(in_plane(x0, 0), plane_normal(tan(a / 2)), in_plane(x1, 0),
                                   plane_normal(-tan(a / 2)));
        assert_near(s, 0.0, 1e-12);
    }
    for (double A = 1e-3; A < 2.0; A *= 3) {
        double m = 2 * M_PI * A / L; /* y' at both ends */
        double s = cm_chord_s_part(in_plane(0, 0), plane_normal(m), in_plane(L, 0), plane_normal(m));
        if (!(s >= 0.25 * A && s <= A))
            fail_msg("sine of amplitude %g over %g: S part %g, not within [A/4, A]", A, L, s);
        if (A < 0.01)
            assert_near(s, 4 * M_PI * 0.0481125224324688 * A, 1e-3 * A);
    }
    /* y = B L s (1-s) (1-2s): slopes B at both ends, peak B L / (6 sqrt 3) */
    double B = 1e-3, s = cm_chord_s_part(in_plane(0, 0), plane_normal(B), in_plane(L, 0), plane_normal(B));
    assert_near(s, B * L / (6 * sqrt(3.0)), 1e-6 * B * L);
    /* y = A sin(pi x / L): slopes +m and -m */
    double m = M_PI * 0.5 / L;
    assert_near(cm_chord_s_part(in_plane(0, 0), plane_normal(m), in_plane(L, 0), plane_normal(-m)), 0.0, 1e-12);
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
        cmocka_unit_test(test_chord_s_part),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
