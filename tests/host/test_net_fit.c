/*
 * test_net_fit.c - format 4.2's interior correction of the fitted nets (NFILL, G1FIT): the kernel
 * (cm_fit_net_add) leaves the border rows, the record's field is read only from 4.2 and every value
 * beyond the build is refused by name, and a face no net from its boundary can rebuild (a bump over a
 * square, flat with its cross slopes on its edges) goes through the whole product as a corrected
 * net: encoder (fit, §12), .cmz, the terminal's decoder (checksum), within the tolerance both ways.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <stdio.h>
#include <stdlib.h>

#include "cm/cm_arith.h"
#include "cm/cm_bspline.h"
#include "cm/cm_const.h"
#include "cm/cm_crc32.h"
#include "cm/cm_decode.h"
#include "cm/cm_method.h"
#include "cm/cm_patchfit.h"
#include "cm/cm_rebuild.h"
#include "cm/cm_sections.h"
#include "encode/encode.h"
#include "encode/verify.h"
#include "igs_writer.h"
#include "model_load.h"
#include "record_io.h"

static cm_decoder dec;
static cm_rebuild_ws rbws;

/* a clamped bicubic net of nu x nv points on uniform knots, with a correction of m x m: only the
   points inside the two outer rings move, each by D at its Greville abscissae */
static void test_net_add_keeps_border(void **state)
{
    (void)state;
    enum { NU = 9, NV = 7, M = 3 };
    double U[NU + 4], V[NV + 4];
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_knots_uniform(NU, 3, U, &st));
    assert_ok(cm_knots_uniform(NV, 3, V, &st));
    cm_vec3 net[NU * NV], before[NU * NV], c[M * M];
    for (int i = 0; i < NU * NV; i++)
        net[i] = before[i] = cm_v3(i % NV, i / NV, 0.1 * (i % 5));
    for (int k = 0; k < M * M; k++)
        c[k] = cm_v3(0.5 * k, -0.25 * k, 1.0 + k);
    cm_fit_net_add(net, NU, NV, U, V, c, M);
    double xi[NU], eta[NV];
    assert_ok(cm_greville(NU, 3, U, xi, &st));
    assert_ok(cm_greville(NV, 3, V, eta, &st));
    int moved = 0;
    for (int i = 0; i < NU; i++)
        for (int j = 0; j < NV; j++) {
            cm_vec3 d = cm_sub(net[i * NV + j], before[i * NV + j]);
            if (i < 2 || i > NU - 3 || j < 2 || j > NV - 3) {
                /* bit for bit: the border and the cross derivatives along it are the net's own */
                assert_true(d.x == 0 && d.y == 0 && d.z == 0);
                continue;
            }
            cm_vec3 D = cm_v3(0, 0, 0);
            cm_fit_add(c, M, xi[i], eta[j], &D, NULL, NULL);
            assert_near(cm_dist(d, D), 0, 1e-12);
            moved += cm_norm(d) > 0;
        }
    assert_int_equal(moved, (NU - 4) * (NV - 4));
}

/* ---- the record's field ---- */

/* a G1FIT record (8 x 8, mode 0) as the format writes it, then (from 4.2) the correction's field: m,
   and when m > 0 the step and every coordinate of m x m coefficients as q; then the twists: none
   (twist_n 0), or twist_n uses each with every sample's sine tq / 4096 */
static size_t g1fit_record(uint8_t *buf, size_t cap, int with_field, uint64_t m, uint64_t exp, int64_t q,
                           uint64_t twist_n, int64_t tq)
{
    cm_ac_enc e;
    cm_face_ctx c;
    cm_face_ctx_init(&c);
    cm_ac_enc_init(&e, buf, cap);
    cm_ac_enc_direct(&e, 4, 5);
    cm_ac_enc_direct(&e, 4, 5);
    cm_ac_enc_direct(&e, 0, 1);
    cm_ac_enc_direct(&e, 0x1234, 16);
    cm_ac_enc_direct(&e, 0x5678, 16);
    if (with_field) {
        cm_ac_enc_uint(&e, &c.fit_m, m);
        if (m > 0) {
            cm_ac_enc_uint(&e, &c.fit_exp, exp);
            for (uint64_t i = 0; i < 3 * m * m; i++)
                cm_ac_enc_sint(&e, &c.fit_coef, q);
        }
        cm_ac_enc_bit(&e, &c.twist_on, twist_n > 0);
        if (twist_n > 0) {
            cm_ac_enc_uint(&e, &c.twist_n, twist_n);
            for (uint64_t k = 0; k < twist_n; k++) {
                cm_ac_enc_bit(&e, &c.twist_use, 1);
                for (int j = 0; j < CM_TWIST_N; j++)
                    cm_ac_enc_sint(&e, &c.twist, j ? 0 : tq);
            }
        }
    }
    cm_ac_enc_uint(&e, &c.count, 77); /* what follows the record */
    return cm_ac_enc_finish(&e);
}

/* read it back as a reader of 4.2 (net_fit) or older would: the record's fault, and what follows */
static cm_err read_record(const uint8_t *buf, size_t len, int net_fit, cm_face *F, cm_method_fault *why,
                          uint64_t *after)
{
    return record_read(&dec.model, CM_METHOD_G1FIT, buf, len, (record_flags){net_fit, 0}, F, why, after);
}

static void assert_record_refused(const uint8_t *buf, size_t len, cm_err code, const char *what)
{
    record_assert_refused(&dec.model, CM_METHOD_G1FIT, buf, len, (record_flags){1, 0}, code, what);
}

static void test_net_records(void **state)
{
    (void)state;
    uint8_t buf[4096];
    cm_face F;
    cm_method_fault why;
    uint64_t after;
    cm_dec_init(&dec);
    dec.model.q = 0.001;
    /* a correction of 2 x 2 lands in the model's pool, dequantised: -7 * 2^3 grid steps */
    size_t n = g1fit_record(buf, sizeof buf, 1, 2, 3, -7, 0, 0);
    assert_ok(read_record(buf, n, 1, &F, &why, &after));
    assert_int_equal(after, 77);
    assert_int_equal(cm_face_fit_m(&F), 2);
    assert_int_equal(cm_face_fit_patches(&F), 1);
    assert_int_equal(dec.model.nctrl - F.surf, 4);
    assert_true(dec.model.ctrl[F.surf + 3].z == -7.0 * 8.0 * 0.001);
    /* m = 0: none, and nothing more read */
    dec.model.nctrl = 0;
    n = g1fit_record(buf, sizeof buf, 1, 0, 0, 0, 0, 0);
    assert_ok(read_record(buf, n, 1, &F, &why, &after));
    assert_int_equal(after, 77);
    assert_int_equal(F.fit, 0);
    /* before 4.2 there is no field: a 4.1 record is read whole, and what follows is next */
    n = g1fit_record(buf, sizeof buf, 0, 0, 0, 0, 0, 0);
    assert_ok(read_record(buf, n, 0, &F, &why, &after));
    assert_int_equal(after, 77);
    assert_int_equal(F.fit, 0);
    /* every value beyond the format or the build, by name */
    n = g1fit_record(buf, sizeof buf, 1, CM_FIT_MAX_M + 1, 0, 0, 0, 0);
    assert_record_refused(buf, n, CM_E_RANGE, "net correction's coefficients per direction");
    n = g1fit_record(buf, sizeof buf, 1, 1, CM_FIT_MAX_EXP + 1, 0, 0, 0);
    assert_record_refused(buf, n, CM_E_RANGE, "net correction step");
    n = g1fit_record(buf, sizeof buf, 1, 1, 0, (int64_t)CM_FIT_MAX_INT + 1, 0, 0);
    assert_record_refused(buf, n, CM_E_RANGE, "net correction coefficient");
    n = g1fit_record(buf, sizeof buf, 1, 2, 0, 1, 0, 0);
    assert_record_refused(buf, 6, CM_E_TRUNCATED, "face record");
    dec.model.nctrl = CM_MAX_MODEL_CTRL - 3; /* the pool holds 3 more: 4 asked for */
    assert_record_refused(buf, n, CM_E_LIMIT, "net correction coefficients");
    dec.model.nctrl = 0;
    /* twists: 4 uses, each sample's sine 100 / 4096, three to a point after the correction's */
    n = g1fit_record(buf, sizeof buf, 1, 2, 3, -7, 4, 100);
    assert_ok(read_record(buf, n, 1, &F, &why, &after));
    assert_int_equal(after, 77);
    assert_true(F.fill_phi & 2u);
    assert_int_equal(F.corner, 4);
    assert_int_equal(dec.model.nctrl - F.surf, 4 + 12);
    assert_true(dec.model.ctrl[F.surf + 4 + 11].z == 100.0 / 4096.0);
    dec.model.nctrl = 0;
    n = g1fit_record(buf, sizeof buf, 1, 0, 0, 0, 5, -3);
    assert_ok(read_record(buf, n, 1, &F, &why, &after));
    assert_int_equal(F.fit, 0);
    assert_int_equal(dec.model.nctrl - F.surf, 15);
    assert_true(dec.model.ctrl[F.surf].x == -3.0 / 4096.0);
    /* ... the loop must have as many uses (checked when the loops are read) */
    cm_method_fault lw = {0};
    dec.model.loops[0] = (cm_loop){0, 4};
    F.loop0 = 0;
    assert_int_equal(cm_method_check_loops(cm_method_of(CM_METHOD_G1FIT), &dec.model, &F, &lw), CM_E_FORMAT);
    assert_string_equal(lw.what, "G1FIT twists do not fit the loop");
    dec.model.loops[0].nuse = 5;
    assert_ok(cm_method_check_loops(cm_method_of(CM_METHOD_G1FIT), &dec.model, &F, &lw));
    /* ... and out of range, by name */
    dec.model.nctrl = 0;
    n = g1fit_record(buf, sizeof buf, 1, 0, 0, 0, 3, 1);
    assert_record_refused(buf, n, CM_E_RANGE, "G1FIT twists' count");
    n = g1fit_record(buf, sizeof buf, 1, 0, 0, 0, 13, 1);
    assert_record_refused(buf, n, CM_E_RANGE, "G1FIT twists' count");
    n = g1fit_record(buf, sizeof buf, 1, 0, 0, 0, 4, CM_TWIST_MAX + 1);
    assert_record_refused(buf, n, CM_E_RANGE, "G1FIT twist");
    n = g1fit_record(buf, sizeof buf, 1, 0, 0, 0, 4, 1);
    dec.model.nctrl = CM_MAX_MODEL_CTRL - 11; /* 12 asked for */
    assert_record_refused(buf, n, CM_E_LIMIT, "G1FIT twists");
    dec.model.nctrl = 0;
}

/* ---- the whole product ---- */

#define BUMP_A 10.0 /* the bump's square */
#define BUMP_H 2.0  /* and height: every net from the boundary is flat, 0.5 mm off; tolerance 0.14 mm */

static void load_bump(loaded_model *lm)
{
    igw w;
    igw_init(&w);
    igw_bump_144(&w, BUMP_A, BUMP_H);
    cm_status st;
    assert_ok(igw_load(&w, "bump", lm, &st));
    assert_int_equal(lm->mesh.nfaces, 1);
}

static void encode_minor(loaded_model *lm, int minor, int gregory_fit, encode_result *r)
{
    encode_opts o;
    encode_opts_default(&o);
    encode_opts_for_format(&o, 4, minor);
    o.gregory_fit = gregory_fit;
    cm_status st;
    cm_status_init(&st);
    memset(r, 0, sizeof *r);
    assert_ok(encode_model(lm, &o, r, &st));
}

static void decode(const uint8_t *b, size_t len)
{
    cm_status st;
    cm_status_init(&st);
    cm_dec_init(&dec);
    assert_ok(cm_dec_feed(&dec, b, len, &st));
    assert_ok(cm_dec_finish(&dec, &st));
}

/* the file's minor version set to `minor`, both CRCs made again (what a writer of that minor with the
   same bytes would have sent) */
static uint8_t *as_minor(const encode_result *r, int minor)
{
    uint8_t *b = malloc(r->len);
    assert_non_null(b);
    memcpy(b, r->bytes, r->len);
    b[CM_HDR_MINOR] = (uint8_t)minor;
    uint32_t at = CM_FMT_COMPACT_AT_H;
    uint64_t H = 0;
    assert_true(cm_fmt_get_varint(b, (uint32_t)r->len, &at, &H));
    cm_put_u32(b + H - 4, cm_crc32(b, (size_t)H - 4));
    cm_put_u32(b + r->len - 4, cm_crc32(b, r->len - 4));
    return b;
}

/*
 * The bump: GREGORY, GREGORY-EXACT and every plain net are the flat square.  In format 4.2 a net
 * with a correction takes it: the terminal's rebuild (checksum verified) within the tolerance both
 * ways, its border rows the plain net's.  Read as 4.1 (no field), the same bytes do not rebuild.
 * In 4.1 it is GREGORY-FIT, as before; in 4.1 without GREGORY-FIT, kept.
 */
static void test_bump_corrected_net(void **state)
{
    (void)state;
    loaded_model lm;
    encode_result r, r41, rk;
    load_bump(&lm);
    encode_minor(&lm, 2, 1, &r);
    int method = r.faces[0].method;
    if (method != CM_METHOD_G1FIT && method != CM_METHOD_NFILL)
        fail_msg("the bump went %s, not a net", cm_method_name((unsigned)method));
    assert_true(r.faces[0].fit_m >= 1 && r.faces[0].fit_m <= CM_FIT_MAX_M);
    decode(r.bytes, r.len);
    assert_int_equal(dec.buf[CM_HDR_MINOR], 2);
    const cm_model *m = &dec.model;
    cm_rebuilt rb;
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_rebuild_face(m, 0, &rb, &rbws, &st)); /* the checksum matches */
    assert_int_equal(rb.repr, CM_REPR_NURBS);
    face_error fe;
    double tol = encode_face_tol(0.01, 0, 0, rb.bbox);
    assert_true(verify_face(&lm, m, 0, &rb, HUGE_VAL, &fe));
    if (!(fe.max < tol))
        fail_msg("the corrected net %.3g mm off, tolerance %.3g", fe.max, tol);
    /* the same net without its correction: far off, and the same border rows */
    static cm_vec3 corrected[CM_MAX_FIT_CTRL * CM_MAX_FIT_CTRL];
    int nu = rb.surf.nu, nv = rb.surf.nv;
    memcpy(corrected, rb.surf.ctrl, sizeof(cm_vec3) * (size_t)(nu * nv));
    dec.model.faces[0].fit = 0;
    assert_ok(cm_rebuild_face_ex(&dec.model, 0, 0, &rb, &rbws, &st));
    assert_true(verify_face(&lm, m, 0, &rb, HUGE_VAL, &fe));
    if (!(fe.max > 2 * tol))
        fail_msg("the net without its correction only %.3g mm off", fe.max);
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++)
            if (i < 2 || i > nu - 3 || j < 2 || j > nv - 3)
                assert_true(cm_dist(corrected[i * nv + j], rb.surf.ctrl[i * nv + j]) == 0.0);
    /* read as 4.1: the record's field is not there for that reader, the face does not rebuild */
    uint8_t *b = as_minor(&r, 1);
    cm_dec_init(&dec);
    cm_status_init(&st);
    cm_err e = cm_dec_feed(&dec, b, r.len, &st);
    if (e == CM_OK)
        e = cm_dec_finish(&dec, &st);
    if (e == CM_OK)
        e = cm_rebuild_face(&dec.model, 0, &rb, &rbws, &st);
    assert_int_not_equal(e, CM_OK);
    free(b);
    /* format 4.1: no corrected nets */
    encode_minor(&lm, 1, 1, &r41);
    assert_int_equal(r41.faces[0].method, CM_METHOD_GREGORY_FIT);
    encode_minor(&lm, 1, 0, &rk);
    assert_int_equal(rk.faces[0].method, CM_METHOD_KEEP);
    encode_result_free(&r);
    encode_result_free(&r41);
    encode_result_free(&rk);
    model_free(&lm);
}

/* ---- twists ---- */

#define TW_A 10.0 /* the twisted pair's half width */
#define TW_H 3.0  /* and height: the normal turns 17 degrees each way along the shared edge */

static void encode_g1fit_minor(loaded_model *lm, int minor, encode_result *r)
{
    encode_opts o;
    encode_opts_default(&o);
    encode_opts_for_format(&o, 4, minor);
    o.gregory = 0; /* planes, then G1FIT only */
    o.nfill = 0;
    o.rel_tol = 0.01; /* 1 % of each face's box (--tol 0.01): the twist, not the tolerance, is the test */
    o.rel_set = 1;
    cm_status st;
    cm_status_init(&st);
    memset(r, 0, sizeof *r);
    assert_ok(encode_model(lm, &o, r, &st));
}

/* the largest angle (degrees) between the rebuilt face f's normal and the true one at the shared
   edge's inner points (0, y, 0) at `steps` even steps */
static double edge_normal_off(const cm_model *m, uint32_t f, int steps)
{
    cm_rebuilt rb;
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_rebuild_face(m, f, &rb, &rbws, &st));
    assert_int_equal(rb.repr, CM_REPR_NURBS);
    double worst = 0;
    int have = 0;
    double u = 0.5, v = 0.5;
    for (int j = 1; j < steps; j++) {
        double y = -TW_A + 2.0 * TW_A * j / steps, t = y / TW_A;
        cm_vec3 P = cm_v3(0, y, 0);
        verify_surf_foot(&rb.surf, 1e-6, P, &have, &u, &v);
        cm_vec3 D[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
        assert_ok(cm_surf_eval(&rb.surf, u, v, 1, D, &st));
        cm_vec3 nr = cm_unit(cm_cross(D[1][0], D[0][1])), truth = cm_unit(cm_v3(-TW_H / TW_A * t * t * t, 0, 1));
        double c = fabs(cm_dot(nr, truth));
        worst = fmax(worst, acos(c > 1 ? 1 : c) * 180 / M_PI);
    }
    return worst;
}

/*
 * Two faces of z = h (x/a)(y/a)^3 sharing the line x = 0, along which the surface's normal twists
 * by 90 degrees (igw_twisted_pair_144).  Normals carried from the edge's ends cannot follow: in
 * format 4.1 G1FIT cannot keep its promise there.  Format 4.2 sends the twist: both faces G1FIT, a
 * record that says so, within the tolerance and 0.5 degree of the true normal along the edge.
 */
static void test_twisted_edge(void **state)
{
    (void)state;
    loaded_model lm;
    encode_result r, r41;
    igw w;
    igw_init(&w);
    igw_twisted_pair_144(&w, TW_A, TW_H);
    cm_status st;
    assert_ok(igw_load(&w, "twisted_pair", &lm, &st));
    assert_int_equal(lm.mesh.nfaces, 2);
    encode_g1fit_minor(&lm, 1, &r41);
    encode_g1fit_minor(&lm, 2, &r);
    for (int f = 0; f < 2; f++) {
        if (r.faces[f].method != CM_METHOD_G1FIT)
            fail_msg("face %d went %s (%s)", f, cm_method_name((unsigned)r.faces[f].method),
                     r.faces[f].why ? r.faces[f].why : "-");
        if (!(r.faces[f].g1_cos >= CM_COS_G1))
            fail_msg("face %d: %.3f deg across the edge", f, acos(r.faces[f].g1_cos) * 180 / M_PI);
    }
    decode(r.bytes, r.len);
    for (uint32_t f = 0; f < 2; f++) {
        assert_true(dec.model.faces[f].fill_phi & 2u); /* the record carries twists */
        /* at the edge's samples, where the twist is sent, within G1FIT's promise; between them the
           net's own shape */
        double at = edge_normal_off(&dec.model, f, 10), between = edge_normal_off(&dec.model, f, 40);
        if (!(at < 0.5 && between < 2.0))
            fail_msg("4.2, face %u: normal %.3f deg off at the edge's samples, %.3f between", f, at, between);
    }
    /* 4.1: no twist; a face that still went G1FIT is far off along the edge */
    decode(r41.bytes, r41.len);
    int worse = 0;
    for (uint32_t f = 0; f < 2; f++) {
        if (r41.faces[f].method != CM_METHOD_G1FIT) {
            worse = 1;
            continue;
        }
        worse |= edge_normal_off(&dec.model, f, 10) > 2.0;
    }
    assert_true(worse);
    encode_result_free(&r);
    encode_result_free(&r41);
    model_free(&lm);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_net_add_keeps_border),
        cmocka_unit_test(test_net_records),
        cmocka_unit_test(test_bump_corrected_net),
        cmocka_unit_test(test_twisted_edge),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
