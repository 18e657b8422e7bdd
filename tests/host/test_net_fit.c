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

/* a G1FIT record (8 x 8, mode 0) as the format writes it, then the correction's field: m, and when
   m > 0 the step and every coordinate of m x m coefficients as q */
static size_t g1fit_record(uint8_t *buf, size_t cap, int with_field, uint64_t m, uint64_t exp, int64_t q)
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
    }
    cm_ac_enc_uint(&e, &c.count, 77); /* what follows the record */
    return cm_ac_enc_finish(&e);
}

/* read it back as a reader of 4.2 (net_fit) or older would: the record's fault, and what follows */
static cm_err read_record(const uint8_t *buf, size_t len, int net_fit, cm_face *F, cm_method_fault *why,
                          uint64_t *after)
{
    cm_ac_dec d;
    cm_face_ctx c;
    cm_face_ctx_init(&c);
    c.net_fit = net_fit;
    cm_ac_dec_init(&d, buf, len);
    memset(F, 0, sizeof *F);
    F->method = CM_METHOD_G1FIT;
    memset(why, 0, sizeof *why);
    cm_err e = cm_method_read_record(cm_method_of(CM_METHOD_G1FIT), &d, &c, &dec.model, F, why);
    *after = cm_ac_dec_uint(&d, &c.count);
    return e;
}

static void assert_record_refused(const uint8_t *buf, size_t len, cm_err code, const char *what)
{
    cm_face F;
    cm_method_fault why;
    uint64_t after;
    cm_err e = read_record(buf, len, 1, &F, &why, &after);
    if (e != code || !why.what || strcmp(why.what, what) != 0)
        fail_msg("refused %s (%s), expected %s (%s)", cm_strerror(e), why.what ? why.what : "-", cm_strerror(code),
                 what);
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
    size_t n = g1fit_record(buf, sizeof buf, 1, 2, 3, -7);
    assert_ok(read_record(buf, n, 1, &F, &why, &after));
    assert_int_equal(after, 77);
    assert_int_equal(cm_face_fit_m(&F), 2);
    assert_int_equal(cm_face_fit_patches(&F), 1);
    assert_int_equal(dec.model.nctrl - F.surf, 4);
    assert_true(dec.model.ctrl[F.surf + 3].z == -7.0 * 8.0 * 0.001);
    /* m = 0: none, and nothing more read */
    dec.model.nctrl = 0;
    n = g1fit_record(buf, sizeof buf, 1, 0, 0, 0);
    assert_ok(read_record(buf, n, 1, &F, &why, &after));
    assert_int_equal(after, 77);
    assert_int_equal(F.fit, 0);
    /* before 4.2 there is no field: a 4.1 record is read whole, and what follows is next */
    n = g1fit_record(buf, sizeof buf, 0, 0, 0, 0);
    assert_ok(read_record(buf, n, 0, &F, &why, &after));
    assert_int_equal(after, 77);
    assert_int_equal(F.fit, 0);
    /* every value beyond the format or the build, by name */
    n = g1fit_record(buf, sizeof buf, 1, CM_FIT_MAX_M + 1, 0, 0);
    assert_record_refused(buf, n, CM_E_RANGE, "net correction's coefficients per direction");
    n = g1fit_record(buf, sizeof buf, 1, 1, CM_FIT_MAX_EXP + 1, 0);
    assert_record_refused(buf, n, CM_E_RANGE, "net correction step");
    n = g1fit_record(buf, sizeof buf, 1, 1, 0, (int64_t)CM_FIT_MAX_INT + 1);
    assert_record_refused(buf, n, CM_E_RANGE, "net correction coefficient");
    n = g1fit_record(buf, sizeof buf, 1, 2, 0, 1);
    assert_record_refused(buf, 6, CM_E_TRUNCATED, "face record");
    dec.model.nctrl = CM_MAX_MODEL_CTRL - 3; /* the pool holds 3 more: 4 asked for */
    assert_record_refused(buf, n, CM_E_LIMIT, "net correction coefficients");
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_net_add_keeps_border),
        cmocka_unit_test(test_net_records),
        cmocka_unit_test(test_bump_corrected_net),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
