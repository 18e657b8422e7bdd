/*
 * test_instances.c - an assembly's placed copies (format 4.3): a part placed several times by IGES
 * subfigure instances is folded out of the model on import (brep_fold_instances), sent once with a
 * transform per further placement, and placed again by the terminal (cm_mesh_place): every copy's
 * triangles are the part's moved by its transform (a mirrored one turned so its front stays out),
 * the file is smaller than the expanded model's, and a transform the format cannot say is refused.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "cm/cm_decode.h"
#include "cm/cm_out.h"
#include "cm/cm_place.h"
#include "cm/cm_tessellate.h"
#include "encode/encode.h"
#include "igs_writer.h"
#include "model_load.h"

#define MAX_TRIS 200000
static cm_decoder dec;
static cm_tess_ws tess;
static float pos[3 * MAX_TRIS][3], nrm[3 * MAX_TRIS][3];
static uint32_t idx[3 * MAX_TRIS];
static cm_mesh_face mfaces[256];

/* four placements: as defined, turned a quarter about z and moved, moved up, mirrored (x -> -x) */
static const double xf[4][12] = {
    {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0},
    {0, -1, 0, 100, 1, 0, 0, 20, 0, 0, 1, 0},
    {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 50.25},
    {-1, 0, 0, -10, 0, 1, 0, 0, 0, 0, 1, 0},
};

static void load(int copies, int flags, loaded_model *lm)
{
    igw w;
    igw_init(&w);
    igw_placed_boxes(&w, copies, xf);
    size_t len = 0;
    char *text = igw_text(&w, &len);
    cm_status st;
    cm_status_init(&st);
    assert_ok(model_load_data_ex("boxes", text, len, lm, flags, NULL, NULL, &st));
    free(text);
    igw_free(&w);
}

static void encode(loaded_model *lm, int instances, encode_result *r)
{
    encode_opts o;
    encode_opts_default(&o);
    o.instances = instances;
    cm_status st;
    cm_status_init(&st);
    memset(r, 0, sizeof *r);
    assert_ok(encode_model(lm, &o, r, &st));
}

/* the file decoded, its faces tessellated in order and its copies placed, as cm_decode_mesh does */
static void decode_mesh(const encode_result *r, cm_mesh *mesh)
{
    cm_status st;
    cm_status_init(&st);
    cm_dec_init(&dec);
    assert_ok(cm_dec_feed(&dec, r->bytes, r->len, &st));
    assert_ok(cm_dec_finish(&dec, &st));
    *mesh = (cm_mesh){pos, nrm, idx, mfaces, 0, 3 * MAX_TRIS, 0, 3 * MAX_TRIS, 0, 256, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    for (uint32_t f = 0; f < dec.model.nfaces; f++) {
        cm_tess_info info;
        assert_ok(cm_tessellate_face(&dec.model, f, dec.model.tess_tol, mesh, &tess, &info, &st));
    }
    assert_ok(cm_mesh_place(&dec.model, mesh, &st));
}

static double signed_volume(const cm_mesh *m, uint32_t f0, uint32_t f1)
{
    double v = 0;
    for (uint32_t f = f0; f < f1; f++)
        for (uint32_t t = 0; t < m->faces[f].nindex; t += 3) {
            double p[3][3];
            for (int k = 0; k < 3; k++)
                for (int i = 0; i < 3; i++)
                    p[k][i] = (double)m->pos[m->idx[m->faces[f].first_index + t + (uint32_t)k]][i];
            const double *a = p[0], *b = p[1], *c = p[2];
            v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                  a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
        }
    return v;
}

/*
 * Four placements of the box: the model keeps the first's 7 faces and three copies; the file says
 * so (format 4.3) and is smaller than the expanded model's; the terminal's mesh has 28 faces, each
 * copy's vertices the part's moved by its transform within float rounding, its normals turned with
 * it, and every copy a closed solid of the part's volume with its front outside (the mirrored one
 * too: its triangles reversed).
 */
static void test_copies_placed(void **state)
{
    (void)state;
    loaded_model lm, whole;
    load(4, MODEL_LOAD_FOLD, &lm);
    assert_int_equal(lm.brep.nplacements, 3);
    assert_int_equal(lm.mesh.nfaces, 7);
    load(4, 0, &whole);
    assert_int_equal(whole.brep.nplacements, 0);
    assert_int_equal(whole.mesh.nfaces, 28);
    /* the model's diagonal is the whole assembly's: the same tolerances either way */
    assert_true(fabs(brep_diag(&lm.brep) - brep_diag(&whole.brep)) <= 1e-9 * brep_diag(&whole.brep));
    encode_result r, rw;
    encode(&lm, 1, &r);
    encode(&whole, 1, &rw);
    assert_true(r.bytes[CM_HDR_MINOR] >= CM_FMT_PLACE_MINOR);
    assert_int_equal(r.placements, 3);
    assert_int_equal(r.placed_faces, 21);
    assert_int_equal(r.need[CM_LIMIT_MAX_PLACEMENTS], 3);
    assert_int_equal(r.need[CM_LIMIT_MAX_FACES], 28);
    /* the part once and three transforms: less than half the body of the four parts (the header
       and the file's CRC, about 60 bytes, are the same kind in both) */
    size_t body = r.len - r.section_bytes[0] - 4, body_w = rw.len - rw.section_bytes[0] - 4;
    if (!(2 * body < body_w))
        fail_msg("folded %zu bytes (body %zu), expanded %zu (body %zu)", r.len, body, rw.len, body_w);
    cm_mesh mesh;
    decode_mesh(&r, &mesh);
    assert_int_equal(mesh.nfaces, 28);
    assert_true(r.need[CM_LIMIT_MAX_TRIS] == mesh.nindex / 3); /* the header counts the copies */
    const double part = signed_volume(&mesh, 0, 7);
    assert_true(part > 0.9 * (40 * 30 * 20 - M_PI * 25 * 20) && part < 1.1 * (40 * 30 * 20));
    for (int k = 1; k < 4; k++) {
        const double *a = dec.model.placements[k - 1].m;
        for (int i = 0; i < 12; i++)
            assert_true(fabs(a[i] - xf[k][i]) <= (i % 4 == 3 ? dec.model.q : 0.0));
        for (uint32_t f = 0; f < 7; f++) {
            const cm_mesh_face *P = &mesh.faces[f], *C = &mesh.faces[7 * k + f];
            assert_int_equal(C->source_face, P->source_face);
            assert_int_equal(C->nverts, P->nverts);
            assert_int_equal(C->nindex, P->nindex);
            for (uint32_t v = 0; v < P->nverts; v++) {
                double p[3], c[3], n[3], cn[3];
                for (int i = 0; i < 3; i++) {
                    p[i] = (double)pos[P->first_vert + v][i];
                    c[i] = (double)pos[C->first_vert + v][i];
                    n[i] = (double)nrm[P->first_vert + v][i];
                    cn[i] = (double)nrm[C->first_vert + v][i];
                }
                for (int i = 0; i < 3; i++) {
                    double want = a[4 * i] * p[0] + a[4 * i + 1] * p[1] + a[4 * i + 2] * p[2] + a[4 * i + 3];
                    double wn = xf[k][4 * i] * n[0] + xf[k][4 * i + 1] * n[1] + xf[k][4 * i + 2] * n[2];
                    if (!(fabs(c[i] - want) <= 1e-5 * (1.0 + fabs(want))) || !(fabs(cn[i] - wn) <= 1e-6))
                        fail_msg("copy %d face %u vertex %u axis %d: %g, want %g (normal %g, want %g)", k, f, v, i,
                                 c[i], want, cn[i], wn);
                }
            }
        }
        double vol = signed_volume(&mesh, 7u * (uint32_t)k, 7u * (uint32_t)k + 7u);
        if (!(fabs(vol - part) <= 1e-4 * part))
            fail_msg("copy %d encloses %g mm^3, the part %g", k, vol, part);
    }
    encode_result_free(&r);
    encode_result_free(&rw);
    model_free(&whole);
    /* format 4.2 cannot say a copy: a folded model is refused, not sent without its copies */
    encode_opts o;
    encode_opts_default(&o);
    encode_opts_for_format(&o, 4, 2);
    cm_status st;
    cm_status_init(&st);
    assert_int_equal(encode_model(&lm, &o, &r, &st), CM_E_ARG);
    model_free(&lm);
}

/* the whole file a writer makes of mesh (static storage, as the terminal's) */
static uint8_t file[1 << 22];
static size_t write_all(cm_out_format fmt, const cm_mesh *mesh)
{
    static cm_out w;
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_out_begin(&w, fmt, mesh, &st));
    size_t n = 0;
    for (int done = 0; !done;) {
        size_t got = 0;
        assert_true(n + 4096 <= sizeof file);
        assert_ok(cm_out_next(&w, file + n, 4096, &got, &done, &st));
        n += got;
    }
    return n;
}

/*
 * The GLB shares the part between nodes: its buffers hold the model's own 7 faces, the root node has
 * a child per copy whose matrix is the copy's placement (column-major) and whose mesh lists the
 * part's primitives; STL holds every copy's triangles (binary STL: 84 bytes + 50 per triangle).
 */
static void test_glb_nodes(void **state)
{
    (void)state;
    loaded_model lm;
    load(4, MODEL_LOAD_FOLD, &lm);
    encode_result r;
    encode(&lm, 1, &r);
    cm_mesh mesh;
    decode_mesh(&r, &mesh);
    assert_int_equal(mesh.nplace, 3);
    assert_int_equal(mesh.nbase_faces, 7);
    size_t n = write_all(CM_OUT_STL, &mesh);
    assert_int_equal(n, 84u + 50u * (mesh.nindex / 3u));
    n = write_all(CM_OUT_GLB, &mesh);
    uint32_t json_len = (uint32_t)file[12] | (uint32_t)file[13] << 8 | (uint32_t)file[14] << 16 | (uint32_t)file[15] << 24;
    char *json = malloc(json_len + 1);
    memcpy(json, file + 20, json_len);
    json[json_len] = '\0';
    assert_non_null(strstr(json, "\"children\":[1,2,3]}"));
    /* copy 2: moved up by 50.25 mm; copy 3 mirrored (x -> -x) and moved by -10 */
    assert_non_null(strstr(json, "{\"name\":\"copy\",\"mesh\":1,\"matrix\":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,50.25,1]}"));
    assert_non_null(strstr(json, "{\"name\":\"copy\",\"mesh\":1,\"matrix\":[-1,0,0,0,0,1,0,0,0,0,1,0,-10,0,0,1]}"));
    assert_non_null(strstr(json, "{\"name\":\"part\",\"primitives\":["));
    assert_null(strstr(json, "\"mesh\":2"));
    /* the binary chunk: the model's own vertices (positions, normals) and indices only */
    uint32_t bin_len = (uint32_t)file[20 + ((json_len + 3u) & ~3u)] | (uint32_t)file[21 + ((json_len + 3u) & ~3u)] << 8 |
                       (uint32_t)file[22 + ((json_len + 3u) & ~3u)] << 16;
    assert_int_equal(bin_len, 24u * mesh.nbase_verts + 4u * mesh.nbase_index);
    free(json);
    encode_result_free(&r);
    model_free(&lm);
}

/* a mesh too small for the copies: refused by name (MAX_FACES, then MAX_TRIS), the part's own faces
   left as they were */
static void test_copies_over_the_mesh(void **state)
{
    (void)state;
    loaded_model lm;
    load(3, MODEL_LOAD_FOLD, &lm);
    encode_result r;
    encode(&lm, 1, &r);
    cm_mesh mesh;
    decode_mesh(&r, &mesh); /* all 21 faces fit */
    const uint32_t part_index = mesh.faces[7].first_index;
    for (int which = 0; which < 2; which++) {
        cm_mesh small = mesh;
        cm_mesh_rollback(&small, &(cm_mesh_mark){mesh.faces[7].first_vert, part_index, 7});
        if (which == 0)
            small.cap_faces = 10; /* the first copy does not fit */
        else
            small.cap_index = part_index + 3u; /* one triangle more than the part */
        cm_status st;
        cm_status_init(&st);
        assert_int_equal(cm_mesh_place(&dec.model, &small, &st), CM_E_LIMIT);
        assert_int_equal(st.limit, which == 0 ? CM_LIMIT_MAX_FACES : CM_LIMIT_MAX_TRIS);
        assert_int_equal(small.nfaces, 7);
        assert_int_equal(small.nindex, part_index);
    }
    encode_result_free(&r);
    model_free(&lm);
}

/* --no-instances (or a model loaded without MODEL_LOAD_FOLD): every face sent, no copy, 4.3 says 0 */
static void test_without_instances(void **state)
{
    (void)state;
    loaded_model lm;
    load(3, 0, &lm);
    encode_result r;
    encode(&lm, 0, &r);
    assert_int_equal(r.placements, 0);
    assert_int_equal(r.need[CM_LIMIT_MAX_PLACEMENTS], 0);
    cm_mesh mesh;
    decode_mesh(&r, &mesh);
    assert_int_equal(mesh.nfaces, 21);
    encode_result_free(&r);
    model_free(&lm);
}

/*
 * A transform the format cannot say, or one the terminal must refuse, never reaches a file: a
 * singular one (the encoder's own decoder refuses the bytes, naming the placement) and a
 * translation beyond the grid's range.
 */
static void test_bad_transforms_refused(void **state)
{
    (void)state;
    for (int bad = 0; bad < 2; bad++) {
        loaded_model lm;
        load(2, MODEL_LOAD_FOLD, &lm);
        assert_int_equal(lm.brep.nplacements, 1);
        haffine *x = &lm.brep.placements[0].xf;
        if (bad == 0)
            x->R[2][0] = x->R[2][1] = x->R[2][2] = 0.0;
        else
            x->t.x = 1e10; /* beyond CM_FMT_PLACE_MAX_SHIFT */
        encode_opts o;
        encode_opts_default(&o);
        cm_status st;
        cm_status_init(&st);
        encode_result r;
        memset(&r, 0, sizeof r);
        assert_int_equal(encode_model(&lm, &o, &r, &st), CM_E_RANGE);
        assert_non_null(st.where);
        if (!strstr(st.where, "placement"))
            fail_msg("case %d: %s", bad, st.where);
        encode_result_free(&r);
        model_free(&lm);
    }
}

/*
 * A copy is folded only when it is the part moved: one whose surface differs from the prototype's
 * moved one by more than the model's tolerance (here a control point of its first face lifted by
 * 1 mm after import) stays expanded; the others are still folded.
 */
static void test_different_copy_not_folded(void **state)
{
    (void)state;
    loaded_model lm;
    load(3, 0, &lm);
    assert_int_equal(lm.brep.nfaces, 21);
    /* (the fold runs before the face domains are built: these are of the expanded model) */
    for (int f = 0; f < lm.brep.nfaces; f++)
        face_domain_free(&lm.fds[f]);
    free(lm.fds);
    lm.fds = NULL;
    /* the third instance's first face */
    hsurf *s = &lm.brep.surfs[lm.brep.faces[14].surf];
    s->ctrl[0].z += 1.0;
    cm_status st;
    cm_status_init(&st);
    int folded = -1;
    assert_ok(brep_fold_instances(&lm.brep, &folded, &st));
    assert_int_equal(folded, 1);
    assert_int_equal(lm.brep.nplacements, 1);
    assert_int_equal(lm.brep.nfaces, 14);
    assert_int_equal(lm.brep.placed_faces, 7);
    model_free(&lm);
}

/* the check cmz eval and the encoder's own decode make of a copy: linear part exact, translation
   within half a grid step */
static void test_placement_is(void **state)
{
    (void)state;
    haffine x = haffine_identity();
    x.R[0][0] = 0.0, x.R[0][1] = -1.0, x.R[1][0] = 1.0, x.R[1][1] = 0.0;
    x.t = cm_v3(100.0, 20.0, -3.0);
    double m[12], q = 1.0 / 1024.0, origin[3] = {-50.0, 0.0, 7.0};
    haffine_rows(&x, m);
    assert_true(encode_placement_is(m, &x, q, origin));
    m[3] += 0.4 * q;
    assert_true(encode_placement_is(m, &x, q, origin));
    m[3] += 0.2 * q; /* 0.6 of a step off */
    assert_false(encode_placement_is(m, &x, q, origin));
    haffine_rows(&x, m);
    m[1] = nextafter(m[1], 0.0); /* the linear part travels exactly */
    assert_false(encode_placement_is(m, &x, q, origin));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_copies_placed),
        cmocka_unit_test(test_glb_nodes),
        cmocka_unit_test(test_placement_is),
        cmocka_unit_test(test_copies_over_the_mesh),
        cmocka_unit_test(test_without_instances),
        cmocka_unit_test(test_bad_transforms_refused),
        cmocka_unit_test(test_different_copy_not_folded),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
