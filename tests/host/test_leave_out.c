/*
 * test_leave_out.c - one bad face never sinks a model (issue 10, part 3).
 *
 * A box with a through hole (7 good faces) plus one planar face whose two holes cross each other:
 * its boundary imports and its plane is found, but no triangulation exists.  The encoder must
 * try it as KEEP, then leave it out with a warning naming its entity, and send the other 7; the file
 * decodes and tessellates on the terminal's code.  --strict (opts.strict) makes it an error instead.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_decode.h"
#include "cm/cm_tessellate.h"
#include "encode/encode.h"
#include "igs_writer.h"
#include "model_load.h"

static cm_decoder dec;
static cm_tess_ws tess;
#define MESH_TRIS 100000
static float pos[MESH_TRIS + 1024][3], nrm[MESH_TRIS + 1024][3];
static uint32_t idx[3 * MESH_TRIS];
static cm_mesh_face mfaces[64];

static int add_line(igw *w, double ax, double ay, double az, double bx, double by, double bz)
{
    int de = igw_add(w, 110, 0, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", ax, ay, az, bx, by, bz);
    igw_set(w, de, 1, 0, 0);
    return de;
}

static int add_sub(igw *w, int type, const char *params)
{
    int de = igw_add(w, type, 0, "%s", params);
    igw_set(w, de, 1, 0, 0);
    return de;
}

/* the square [20,30]^2 at z = -5 on a bilinear 128 with two holes, circles of radius 2 whose centres
   are 1 mm apart: the holes cross each other, no triangulation of the face exists; returns the 144's DE */
static int add_face_with_crossing_holes(igw *w)
{
    const double z = -5, a = 20, b = 30;
    char buf[1024];
    snprintf(buf, sizeof buf,
             "1,1,1,1,1,0,1,0,0,0,0,1,1,0,0,1,1,1,1,1,1,"
             "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,0,1,0,1",
             a, a, z, b, a, z, a, b, z, b, b, z);
    int s = add_sub(w, 128, buf);
    int m[4] = {add_line(w, a, a, z, b, a, z), add_line(w, b, a, z, b, b, z), add_line(w, b, b, z, a, b, z),
                add_line(w, a, b, z, a, a, z)};
    snprintf(buf, sizeof buf, "4,%d,%d,%d,%d", m[0], m[1], m[2], m[3]);
    int outer_c = add_sub(w, 102, buf);
    snprintf(buf, sizeof buf, "0,%d,0,%d,2", s, outer_c);
    int outer = add_sub(w, 142, buf);
    int hole[2];
    for (int k = 0; k < 2; k++) {
        double cx = 24.5 + k, cy = 25;
        snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", z, cx, cy, cx + 2, cy, cx + 2, cy);
        int circle = add_sub(w, 100, buf);
        snprintf(buf, sizeof buf, "0,%d,0,%d,2", s, circle);
        hole[k] = add_sub(w, 142, buf);
    }
    return igw_add(w, 144, 0, "%d,1,2,%d,%d,%d", s, outer, hole[0], hole[1]);
}

static void load(loaded_model *lm)
{
    igw w;
    igw_init(&w);
    igw_box_with_hole_144(&w, 10, 8, 6, 2);
    int de = add_face_with_crossing_holes(&w);
    assert_true(de > 0);
    size_t len = 0;
    char *text = igw_text(&w, &len);
    igw_free(&w);
    cm_status st;
    cm_status_init(&st);
    if (getenv("LEAVE_OUT_SAVE")) { FILE *fp = fopen(getenv("LEAVE_OUT_SAVE"), "wb"); fwrite(text, 1, len, fp); fclose(fp); }
    assert_ok(model_load_data("leave_out", text, len, lm, NULL, NULL, &st));
    free(text);
    /* the importer sees all 8 faces: the bad one is bad only for the triangulator */
    assert_int_equal(lm->brep.nfaces, 8);
    assert_int_equal(lm->mesh.nfaces, 8);
    assert_int_equal(lm->nleft_out, 0);
}

static void test_untessellatable_face_is_left_out_and_named(void **state)
{
    (void)state;
    loaded_model lm;
    load(&lm);
    int bad_de = lm.brep.faces[7].src_de;
    encode_opts o;
    encode_opts_default(&o);
    encode_result r;
    cm_status st;
    cm_status_init(&st);
    assert_ok(encode_model(&lm, &o, &r, &st));
    /* one face left out, warned with its entity */
    assert_int_equal(r.faces_left_out, 1);
    assert_int_equal(lm.nleft_out, 1);
    const char *msg = lm.iges.warn[lm.left_out[0]].msg;
    char want[64];
    snprintf(want, sizeof want, "(DE %d): left out: ", bad_de);
    if (!strstr(msg, want))
        fail_msg("warning '%s' does not name DE %d", msg, bad_de);
    assert_int_equal(lm.mesh.nfaces, 7);
    int counted = 0;
    for (int i = 0; i < CM_METHOD_COUNT; i++)
        counted += r.faces_by_method[i];
    assert_int_equal(counted, 7);
    /* the file holds the 7 others and every one of them tessellates with the terminal's code */
    cm_dec_init(&dec);
    cm_status_init(&st);
    assert_ok(cm_dec_feed(&dec, r.bytes, r.len, &st));
    assert_ok(cm_dec_finish(&dec, &st));
    assert_int_equal(dec.model.nfaces, 7);
    cm_mesh mesh = {pos, nrm, idx, mfaces, 0, MESH_TRIS + 1024, 0, 3 * MESH_TRIS, 0, 64, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    cm_mesh_clear(&mesh);
    for (uint32_t f = 0; f < dec.model.nfaces; f++) {
        cm_tess_info info;
        cm_status_init(&st);
        assert_ok(cm_tessellate_face(&dec.model, f, dec.model.tess_tol, &mesh, &tess, &info, &st));
        assert_true(info.triangles > 0);
    }
    encode_result_free(&r);
    model_free(&lm);
}

static void test_strict_refuses_the_model_naming_the_face(void **state)
{
    (void)state;
    loaded_model lm;
    load(&lm);
    int bad_de = lm.brep.faces[7].src_de;
    encode_opts o;
    encode_opts_default(&o);
    o.strict = 1;
    encode_result r;
    cm_status st;
    cm_status_init(&st);
    assert_int_equal(encode_model(&lm, &o, &r, &st), CM_E_DEGENERATE);
    assert_null(r.bytes);
    char want[64];
    snprintf(want, sizeof want, "(DE %d) cannot be sent", bad_de);
    if (!strstr(r.refusal, want))
        fail_msg("refusal '%s' does not name DE %d", r.refusal, bad_de);
    encode_result_free(&r);
    model_free(&lm);
}

/* a good model goes through untouched: nothing left out, nothing warned */
static void test_good_model_leaves_nothing_out(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_box_with_hole_144(&w, 10, 8, 6, 2);
    size_t len = 0;
    char *text = igw_text(&w, &len);
    igw_free(&w);
    loaded_model lm;
    cm_status st;
    cm_status_init(&st);
    assert_ok(model_load_data("good", text, len, &lm, NULL, NULL, &st));
    free(text);
    encode_opts o;
    encode_opts_default(&o);
    o.strict = 1;
    encode_result r;
    assert_ok(encode_model(&lm, &o, &r, &st));
    assert_int_equal(r.faces_left_out, 0);
    assert_int_equal(lm.nleft_out, 0);
    assert_int_equal(lm.mesh.nfaces, 7);
    encode_result_free(&r);
    model_free(&lm);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_untessellatable_face_is_left_out_and_named),
        cmocka_unit_test(test_strict_refuses_the_model_naming_the_face),
        cmocka_unit_test(test_good_model_leaves_nothing_out),
    };
    return cmocka_run_group_tests_name("leave_out", tests, NULL, NULL);
}
