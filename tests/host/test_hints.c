/*
 * test_hints.c - format 4.13's corner hints (spec 15.3): a GREGORY-family record ends with the
 * normals of its flat corners that have no G1 edge, which the rebuild takes instead of n_F.  The
 * octahedral coding keeps a normal within the spec's 0.005 degrees; the field is read only from
 * 4.13 (an older reader misreads the same bytes, as it refuses a newer minor by version); every value
 * beyond the format or the build is refused by name.  (The workstation's side, a band cut at a
 * T-vertex rebuilt exactly with its hint: test_step.c, test_band_cut_open.)
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "cm/cm_arith.h"
#include "cm/cm_decode.h"
#include "cm/cm_gregface.h"
#include "cm/cm_method.h"
#include "cm/cm_sections.h"
#include "record_io.h"

static cm_decoder dec;

/* spec 15.3: any unit normal comes back within 0.005 degrees, the axes and the folds' edges too */
static void test_octahedral_round_trip(void **state)
{
    (void)state;
    double worst = 0.0;
    for (int i = 0; i <= 64; i++)
        for (int j = 0; j < 128; j++) {
            double th = M_PI * i / 64, ph = 2 * M_PI * j / 128;
            cm_vec3 n = cm_v3(sin(th) * cos(ph), sin(th) * sin(ph), cos(th));
            int16_t q[2];
            cm_hint_encode(n, q);
            assert_true(q[0] >= -CM_FMT_HINT_ONE && q[0] <= CM_FMT_HINT_ONE);
            assert_true(q[1] >= -CM_FMT_HINT_ONE && q[1] <= CM_FMT_HINT_ONE);
            cm_vec3 b = cm_hint_decode(q[0], q[1]);
            assert_near(cm_norm(b), 1.0, 1e-15);
            double d = cm_dot(n, b), a = acos(d > 1.0 ? 1.0 : d) * 180.0 / M_PI;
            worst = a > worst ? a : worst;
        }
    if (!(worst <= 0.005))
        fail_msg("a normal came back %.4g degrees off", worst);
    /* (and the same bits every time: a pure function of the two integers) */
    cm_vec3 a = cm_hint_decode(-12345, 20000), b = cm_hint_decode(-12345, 20000);
    assert_memory_equal(&a, &b, sizeof a);
}

/* a GREGORY-EXACT record (layout 1, checksum) as the writer sends it, then from 4.13 the hints: a bit
   (any), the corner mask and two octahedral coordinates (qx, qy) per hinted corner; then a value of
   what follows the record */
static size_t exact_record(uint8_t *buf, size_t cap, int with_field, uint64_t mask, int64_t qx, int64_t qy)
{
    cm_ac_enc e;
    cm_face_ctx c;
    cm_face_ctx_init(&c);
    cm_ac_enc_init(&e, buf, cap);
    cm_ac_enc_uint(&e, &c.layout, CM_GREG_LAYOUT_SPLIT);
    cm_ac_enc_uint(&e, &c.corner, 0);
    cm_ac_enc_direct(&e, 0x1234, 16);
    cm_ac_enc_direct(&e, 0x5678, 16);
    if (with_field) {
        cm_ac_enc_bit(&e, &c.hint_any, mask != 0);
        if (mask) {
            cm_ac_enc_uint(&e, &c.hint_mask, mask);
            for (int k = 0; k < 16; k++)
                if ((mask >> k) & 1u) {
                    cm_ac_enc_sint(&e, &c.hint_oct, qx);
                    cm_ac_enc_sint(&e, &c.hint_oct, qy);
                }
        }
    }
    cm_ac_enc_uint(&e, &c.count, 77); /* what follows the record */
    return cm_ac_enc_finish(&e);
}

/* read back as a reader of 4.13 (hints) or of 4.12 would */
static const record_flags v413 = {1, 1}, v412 = {1, 0};

static void test_hint_records(void **state)
{
    (void)state;
    uint8_t buf[4096];
    cm_face F;
    cm_method_fault why;
    uint64_t after;
    cm_dec_init(&dec);
    dec.model.nctrl = 5; /* (the pool holds others' points before the face's) */
    /* corners 1 and 3 hinted: two normals in the pool from F.surf, in corner order */
    size_t n = exact_record(buf, sizeof buf, 1, 0xa, 0, -CM_FMT_HINT_ONE);
    assert_ok(record_read(&dec.model, CM_METHOD_GREGORY_EXACT, buf, n, v413, &F, &why, &after));
    assert_int_equal(after, 77);
    assert_int_equal(cm_face_hint_mask(&F), 0xa);
    assert_int_equal(cm_face_hint_first(&F), 5);
    assert_int_equal(dec.model.nctrl, 7);
    cm_vec3 h = dec.model.ctrl[6];
    assert_true(h.x == 0.0 && h.y == -1.0 && h.z == 0.0);
    /* none: a bit, nothing more, the pool untouched */
    dec.model.nctrl = 0;
    n = exact_record(buf, sizeof buf, 1, 0, 0, 0);
    assert_ok(record_read(&dec.model, CM_METHOD_GREGORY_EXACT, buf, n, v413, &F, &why, &after));
    assert_int_equal(after, 77);
    assert_int_equal(cm_face_hint_mask(&F), 0);
    assert_int_equal(dec.model.nctrl, 0);
    /* before 4.13 there is no field: a 4.12 record is read whole and what follows is next; a 4.13
       record read as 4.12 is misread (which is why a 4.12 reader refuses 4.13 by its version) */
    n = exact_record(buf, sizeof buf, 0, 0, 0, 0);
    assert_ok(record_read(&dec.model, CM_METHOD_GREGORY_EXACT, buf, n, v412, &F, &why, &after));
    assert_int_equal(after, 77);
    n = exact_record(buf, sizeof buf, 1, 0x3, 100, 200);
    assert_ok(record_read(&dec.model, CM_METHOD_GREGORY_EXACT, buf, n, v412, &F, &why, &after));
    assert_true(after != 77);
    /* out of the format, by name: corners beyond 12 edges, a coordinate beyond the unit */
    dec.model.nctrl = 0;
    n = exact_record(buf, sizeof buf, 1, 1u << CM_GREG_JOINED_MAX_EDGES, 0, 0);
    record_assert_refused(&dec.model, CM_METHOD_GREGORY_EXACT, buf, n, v413, CM_E_RANGE, "GREGORY hints");
    n = exact_record(buf, sizeof buf, 1, 1, CM_FMT_HINT_ONE + 1, 0);
    record_assert_refused(&dec.model, CM_METHOD_GREGORY_EXACT, buf, n, v413, CM_E_RANGE, "GREGORY hint normal");
    n = exact_record(buf, sizeof buf, 1, 1, 0, -CM_FMT_HINT_ONE - 1);
    record_assert_refused(&dec.model, CM_METHOD_GREGORY_EXACT, buf, n, v413, CM_E_RANGE, "GREGORY hint normal");
    /* cut short, and beyond the build's pool (MAX_MODEL_CTRL, named) */
    n = exact_record(buf, sizeof buf, 1, 0xfff, 30000, -30000);
    record_assert_refused(&dec.model, CM_METHOD_GREGORY_EXACT, buf, 9, v413, CM_E_TRUNCATED, "face record");
    dec.model.nctrl = CM_MAX_MODEL_CTRL - 11; /* 12 asked for */
    record_assert_refused(&dec.model, CM_METHOD_GREGORY_EXACT, buf, n, v413, CM_E_LIMIT, "GREGORY hints");
    cm_face G;
    memset(&why, 0, sizeof why);
    assert_int_equal(record_read(&dec.model, CM_METHOD_GREGORY_EXACT, buf, n, v413, &G, &why, &after), CM_E_LIMIT);
    assert_int_equal(why.limit, CM_LIMIT_MAX_MODEL_CTRL);
    assert_int_equal(why.need, CM_MAX_MODEL_CTRL + 1);
    dec.model.nctrl = 0;
    /* a hinted corner must be on the loop (checked when the loops are read) */
    n = exact_record(buf, sizeof buf, 1, 0x20, 0, 0);
    assert_ok(record_read(&dec.model, CM_METHOD_GREGORY_EXACT, buf, n, v413, &F, &why, &after));
    cm_method_fault lw = {0};
    dec.model.loops[0] = (cm_loop){0, 5};
    F.loop0 = 0;
    F.nloops = 1;
    assert_int_equal(cm_method_check_loops(cm_method_of(CM_METHOD_GREGORY_EXACT), &dec.model, &F, &lw), CM_E_FORMAT);
    assert_string_equal(lw.what, "GREGORY hint beyond the loop");
    dec.model.loops[0].nuse = 6;
    assert_ok(cm_method_check_loops(cm_method_of(CM_METHOD_GREGORY_EXACT), &dec.model, &F, &lw));
    /* the nets' fields are their own: an NFILL face's nu is no mask */
    F.method = CM_METHOD_NFILL;
    assert_int_equal(cm_face_hint_mask(&F), 0);
}

/* GREGORY-FIT's hints follow its correction: in the record, and in the pool (cm_face_hint_first) */
static void test_fit_hints_follow_correction(void **state)
{
    (void)state;
    uint8_t buf[512];
    cm_ac_enc e;
    cm_face_ctx c;
    cm_face_ctx_init(&c);
    cm_ac_enc_init(&e, buf, sizeof buf);
    cm_ac_enc_uint(&e, &c.layout, CM_GREG_LAYOUT_QUAD);
    cm_ac_enc_uint(&e, &c.corner, 0);
    cm_ac_enc_direct(&e, 0x1234, 16);
    cm_ac_enc_direct(&e, 0x5678, 16);
    cm_ac_enc_uint(&e, &c.fit_m, 2); /* 2 x 2 coefficients of one patch, each (5, 5, 5) grid steps */
    cm_ac_enc_uint(&e, &c.fit_patches, 1);
    cm_ac_enc_uint(&e, &c.fit_exp, 0);
    for (int i = 0; i < 12; i++)
        cm_ac_enc_sint(&e, &c.fit_coef, 5);
    cm_ac_enc_bit(&e, &c.hint_any, 1);
    cm_ac_enc_uint(&e, &c.hint_mask, 0x4);
    cm_ac_enc_sint(&e, &c.hint_oct, CM_FMT_HINT_ONE);
    cm_ac_enc_sint(&e, &c.hint_oct, 0);
    cm_ac_enc_uint(&e, &c.count, 77);
    size_t n = cm_ac_enc_finish(&e);
    cm_dec_init(&dec);
    dec.model.q = 0.5;
    dec.model.nctrl = 3;
    cm_ac_dec d;
    cm_face_ctx r;
    cm_face_ctx_init(&r);
    r.hints = 1;
    cm_ac_dec_init(&d, buf, n);
    cm_face F;
    memset(&F, 0, sizeof F);
    F.method = CM_METHOD_GREGORY_FIT;
    cm_method_fault why = {0};
    assert_ok(cm_method_read_record(cm_method_of(CM_METHOD_GREGORY_FIT), &d, &r, &dec.model, &F, &why));
    assert_int_equal(cm_ac_dec_uint(&d, &r.count), 77);
    assert_int_equal(F.surf, 3);
    assert_int_equal(cm_face_hint_mask(&F), 0x4);
    assert_int_equal(cm_face_hint_first(&F), 3 + 4);
    assert_int_equal(dec.model.nctrl, 3 + 4 + 1);
    assert_true(dec.model.ctrl[3].x == 2.5 && dec.model.ctrl[6].z == 2.5);
    cm_vec3 h = dec.model.ctrl[7];
    assert_true(h.x == 1.0 && h.y == 0.0 && h.z == 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_octahedral_round_trip),
        cmocka_unit_test(test_hint_records),
        cmocka_unit_test(test_fit_hints_follow_correction),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
