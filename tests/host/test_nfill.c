/*
 * test_nfill.c - NFILL faces (spec §8) through the whole product: synthetic
 * IGES -> encoder (§8.9 search, §12) -> .cmz -> the terminal's decoder
 * (checksum) -> triangles.  Spec §17 T8 on its L-shaped face (without the
 * hole: this version fills outer loops only), the Gregory patches' refusal
 * of its reflex corner, the weighting of the rays, and the checksum check.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <stdio.h>
#include <stdlib.h>

#include "cm/cm_corner.h"
#include "cm/cm_decode.h"
#include "cm/cm_nfill.h"
#include "cm/cm_project.h"
#include "cm/cm_rebuild.h"
#include "cm/cm_tessellate.h"
#include "encode/encode.h"
#include "encode/verify.h"
#include "igs_writer.h"
#include "mesh/mesh_topo.h"
#include "model_load.h"

static cm_decoder dec;
static cm_tess_ws tess;
static cm_rebuild_ws rbws;
#define MESH_TRIS 100000
static float pos[MESH_TRIS + 1024][3], nrm[MESH_TRIS + 1024][3];
static uint32_t idx[3 * MESH_TRIS];
static cm_mesh_face mfaces[8];

/* the T8 surface */
static double t8_z(double x, double y)
{
    return 0.02 * (x * x - 0.5 * y * y) + 0.1 * x + 0.01 * x * y;
}

static void load_l_shape(loaded_model *lm)
{
    igw w;
    igw_init(&w);
    igw_l_shape_144(&w);
    cm_status st;
    assert_ok(igw_load(&w, "l_shape", lm, &st));
    assert_int_equal(lm->mesh.nfaces, 1);
}

static void encode_with(loaded_model *lm, int nfill, double rel_tol, encode_result *r)
{
    encode_opts o;
    encode_opts_default(&o);
    o.nfill = nfill;
    o.g1fit = 0; /* NFILL's faces alone (G1FIT: test_g1fit.c) */
    o.rel_tol = rel_tol;
    o.rel_set = 1;
    cm_status st;
    cm_status_init(&st);
    memset(r, 0, sizeof *r);
    assert_ok(encode_model(lm, &o, r, &st));
}

static void decode(const encode_result *r)
{
    cm_status st;
    cm_status_init(&st);
    cm_dec_init(&dec);
    assert_ok(cm_dec_feed(&dec, r->bytes, r->len, &st));
    assert_ok(cm_dec_finish(&dec, &st));
}

/* triangles of face 0 of r's file as the terminal tessellates it */
static uint32_t face_triangles(const encode_result *r)
{
    decode(r);
    cm_mesh mesh = {pos, nrm, idx, mfaces, 0, MESH_TRIS + 1024, 0, 3 * MESH_TRIS, 0, 8, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    cm_mesh_clear(&mesh);
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_tessellate_face(&dec.model, 0, dec.model.tess_tol, &mesh, &tess, NULL, &st));
    return mesh.nindex / 3;
}

/* The L-shaped face has a reflex corner: no Gregory patch takes it, and without NFILL it keeps its
   surface for that reason */
static void test_l_shape_kept_without_nfill(void **state)
{
    (void)state;
    loaded_model lm;
    encode_result r;
    load_l_shape(&lm);
    encode_with(&lm, 0, 0.01, &r);
    assert_int_equal(r.faces_by_method[CM_METHOD_KEEP], 1);
    assert_non_null(r.faces[0].why);
    assert_non_null(strstr(r.faces[0].why, "reflex"));
    encode_result_free(&r);
    model_free(&lm);
}

/*
 * T8 (without the hole) at T8's bound as the tolerance: NFILL rebuilds the face within 0.5 % of its
 * size, measured three ways - the
 * encoder's §12, §12 again on the decoded file, and every vertex of the terminal's mesh against the
 * true surface z(x, y); the record's checksum is what the terminal rebuilds, and a changed one is
 * refused.
 */
static void test_l_shape_nfill(void **state)
{
    (void)state;
    loaded_model lm;
    encode_result r;
    load_l_shape(&lm);
    /* the face kept: its triangles at the file's chordal tolerance, for the rebuilt one below */
    encode_with(&lm, 0, 0.005, &r);
    uint32_t kept_tris = face_triangles(&r);
    encode_result_free(&r);
    encode_with(&lm, 1, 0.005, &r); /* T8's bound as the tolerance: the search must reach a fine net */
    assert_int_equal(r.faces_by_method[CM_METHOD_NFILL], 1);
    assert_int_equal(r.faces_by_method[CM_METHOD_KEEP], 0);
    assert_true(r.faces[0].ratio < 0.005);
    decode(&r);
    cm_model *m = &dec.model;
    assert_int_equal(m->faces[0].method, CM_METHOD_NFILL);
    assert_int_equal(m->faces[0].fill_nu, r.faces[0].layout);
    cm_rebuilt rb;
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_rebuild_face(m, 0, &rb, &rbws, &st)); /* the checksum matches */
    assert_int_equal(rb.repr, CM_REPR_NURBS);
    face_error fe;
    assert_true(verify_face(&lm, m, 0, &rb, HUGE_VAL, &fe));
    assert_true(fe.complete);
    assert_true(fe.grid_points > 100);
    assert_true(fe.ratio < 0.005);
    assert_near(fe.max, r.faces[0].rebuild_max, 1e-12 + 1e-9 * fe.max);
    /* the mesh against the true surface: vertical distance, a bound of the normal one */
    cm_mesh mesh = {pos, nrm, idx, mfaces, 0, MESH_TRIS + 1024, 0, 3 * MESH_TRIS, 0, 8, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    cm_mesh_clear(&mesh);
    assert_ok(cm_tessellate_face(m, 0, m->tess_tol, &mesh, &tess, NULL, &st));
    assert_true(mesh.nverts > 20);
    double worst = 0;
    for (uint32_t i = 0; i < mesh.nverts; i++) {
        double x = (double)pos[i][0], y = (double)pos[i][1], z = (double)pos[i][2];
        /* inside the L up to the rebuild's error (interior points are the net's, not the loop's) */
        const double e = 0.005 * 25.6;
        if (x < -e || x > 20 + e || y < -e || y > 16 + e || (x > 8 + e && y > 8 + e))
            fail_msg("vertex %u (%g, %g) outside the L", i, x, y);
        double d = fabs(z - t8_z(x, y));
        worst = d > worst ? d : worst;
        /* normals upwards: the face's side */
        assert_true(nrm[i][2] > 0.5f);
    }
    if (!(worst < 0.005 * rb.bbox))
        fail_msg("T8: mesh %.4g mm off the surface (%.3g %% of the face)", worst, 100 * worst / rb.bbox);
    mesh_topo t;
    assert_int_equal(mesh_topo_analyse(&mesh, &t), 0);
    assert_int_equal((int)t.degenerate, 0);
    mesh_topo_free(&t);
    /* the loop is up to the tolerance off the rebuilt surface: the refinement must not chase that.
       Measured from the loop's own points: 7936 triangles; from the surface's: 1294; the face kept
       (its exact biquadratic surface): 158 - the fitted net's ripples curve more than the surface */
    if (!(mesh.nindex / 3 <= 10 * kept_tris))
        fail_msg("%u triangles rebuilt, %u kept", mesh.nindex / 3, kept_tris);
    /* a changed checksum: the terminal refuses the face */
    m->faces[0].checksum ^= 1u;
    cm_status_init(&st);
    assert_int_equal(cm_rebuild_face(m, 0, &rb, &rbws, &st), CM_E_CHECKSUM);
    encode_result_free(&r);
    model_free(&lm);
}

/*
 * Spec T8 on the kernel alone: the 8 x 8 net, every point of a 0.5 mm grid over the L within 0.5 % of
 * the face's diagonal of the net.  The spec's prototype reached 0.15 % at phi = 1e-4 with the true
 * surface normals; with the 5.4 basis (corner normals interpolated along each edge, all a terminal
 * has) a sweep gave 0.51 % at phi = 1e-4, 0.33 % at 1e-3 (taken here), and 0.17-0.19 % at c = 12, 16
 * with phi = 1e-1: larger nets need more fairing, as 8.9 says.
 */
static void test_t8_kernel_net(void **state)
{
    (void)state;
    loaded_model lm;
    encode_result r;
    load_l_shape(&lm);
    encode_with(&lm, 1, 0.01, &r);
    decode(&r);
    cm_model *m = &dec.model;
    static cm_greg_input in;
    static cm_corner_ws cws;
    static cm_nfill_surface s;
    static cm_nfill_ws ws;
    cm_frame fr;
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_greg_input_build(m, 0, 1, &in, &cws, &st));
    assert_ok(cm_nfill_build(&in, NULL, 8, 8, 2, &fr, &s, &ws, &st));
    double worst = 0, diag = hypot(20.0, 16.0);
    for (int i = 0; i <= 40; i++)
        for (int j = 0; j <= 32; j++) {
            double x = 0.5 * i, y = 0.5 * j;
            if (x > 8.0 && y > 8.0)
                continue;
            /* the net's point above (x, y): the local frame's (u, v) are linear in x, y only near
               enough; project instead */
            cm_vec3 p = cm_v3(x, y, t8_z(x, y));
            cm_patch pt = cm_patch_of_surf(&s.surf);
            double u, v, d;
            assert_ok(cm_patch_project(&pt, p, &u, &v, &d, &st));
            worst = d > worst ? d : worst;
        }
    if (!(worst < 0.005 * diag))
        fail_msg("T8 kernel: %.4g mm (%.3g %%)", worst, 100 * worst / diag);
    encode_result_free(&r);
    model_free(&lm);
}

/*
 * A face with a hole (a curved square with a round hole, the case of spec T8's hole): no Gregory
 * patch takes holes; NFILL fits the outer loop's samples and rays and the hole's samples (no rays:
 * see cm_nfill.h), within the tolerance, and the terminal's mesh lies on the paraboloid, outside the
 * hole and inside the square.
 */
static void test_square_with_hole(void **state)
{
    (void)state;
    loaded_model lm;
    encode_result r;
    igw w;
    igw_init(&w);
    igw_dome_square_hole_144(&w, 12.0, 4.0);
    cm_status st;
    assert_ok(igw_load(&w, "dome_hole", &lm, &st));
    assert_int_equal(lm.mesh.nfaces, 1);
    encode_with(&lm, 0, 0.01, &r);
    assert_int_equal(r.faces_by_method[CM_METHOD_KEEP], 1);
    assert_string_equal(r.faces[0].why, "holes");
    encode_result_free(&r);
    encode_with(&lm, 1, 0.01, &r);
    assert_int_equal(r.faces_by_method[CM_METHOD_NFILL], 1);
    assert_true(r.faces[0].ratio < 0.01);
    decode(&r);
    cm_model *m = &dec.model;
    assert_int_equal(m->faces[0].nloops, 2);
    cm_mesh mesh = {pos, nrm, idx, mfaces, 0, MESH_TRIS + 1024, 0, 3 * MESH_TRIS, 0, 8, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    cm_mesh_clear(&mesh);
    cm_status_init(&st);
    assert_ok(cm_tessellate_face(m, 0, m->tess_tol, &mesh, &tess, NULL, &st));
    double worst = 0, bbox = r.faces[0].bbox, e = 0.01 * bbox;
    for (uint32_t i = 0; i < mesh.nverts; i++) {
        double x = (double)pos[i][0], y = (double)pos[i][1];
        double d = fabs((double)pos[i][2] - 5.0 * (1.0 - (x * x + y * y) / 400.0));
        worst = d > worst ? d : worst;
        if (hypot(x, y) < 4.0 - e || fabs(x) > 12.0 + e || fabs(y) > 12.0 + e)
            fail_msg("vertex %u (%g, %g) in the hole or outside the square", i, x, y);
    }
    if (!(worst < 0.01 * bbox))
        fail_msg("mesh %.4g mm off the paraboloid (%.3g %%)", worst, 100 * worst / bbox);
    encode_result_free(&r);
    model_free(&lm);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_l_shape_kept_without_nfill),
        cmocka_unit_test(test_l_shape_nfill),
        cmocka_unit_test(test_t8_kernel_net),
        cmocka_unit_test(test_square_with_hole),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
