/*
 * test_methods.c - the table of face methods (cm_method.h): every number on
 * the wire has exactly one module, the fallback is last and keeps its
 * surface, every module can rebuild, and each record that the writer puts
 * down the reader takes back unchanged (the two halves of a method cannot
 * disagree on its fields).  A new method gets these checks by its row.
 */
#include "test_util.h"

#include "cm/cm_method.h"
#include "cm/cm_patchfit.h"

#include <math.h>

static cm_model model; /* where records put what they carry beyond the face's fields */

static void test_every_number_has_one_module(void **state)
{
    (void)state;
    for (unsigned id = 0; id < CM_METHOD_COUNT; id++) {
        const cm_method *M = cm_method_of(id);
        assert_non_null(M);
        assert_int_equal(M->id, id);
        int rows = 0;
        for (int i = 0; i < CM_METHOD_COUNT; i++)
            rows += cm_method_table[i]->id == id;
        assert_int_equal(rows, 1);
        assert_non_null(M->name);
        assert_string_equal(cm_method_name(id), M->name);
        assert_true(M->since_major >= CM_FMT_VERSION_MIN_MAJOR && M->since_major <= CM_FMT_VERSION_MAJOR);
        /* a method newer than format 1 must say so when an older file carries it */
        if (M->since_major > CM_FMT_VERSION_MIN_MAJOR)
            assert_non_null(M->too_new);
        /* layouts are chosen in a record */
        assert_true(M->layouts == 0 || M->has_record);
    }
    assert_null(cm_method_of(CM_METHOD_COUNT));
    assert_null(cm_method_of(255));
    assert_string_equal(cm_method_name(CM_METHOD_COUNT), "?");
}

static void test_fallback_is_last_and_kept(void **state)
{
    (void)state;
    const cm_method *last = cm_method_table[CM_METHOD_COUNT - 1];
    assert_int_equal(last->id, CM_METHOD_FALLBACK);
    assert_true(last->kept_surface);
    assert_false(last->has_record); /* nothing to choose: always applicable */
    for (int i = 0; i < CM_METHOD_COUNT - 1; i++)
        assert_false(cm_method_table[i]->kept_surface);
}

/* every field of every method's record through the range coder and back */
static void test_records_round_trip(void **state)
{
    (void)state;
    static uint8_t buf[1 << 12];
    for (int i = 0; i < CM_METHOD_COUNT; i++) {
        const cm_method *M = cm_method_table[i];
        if (!M->has_record)
            continue;
        /* the fields a record can hold: layouts 0..2 with their corners, checksums at the extremes */
        cm_face in[6] = {{0}};
        for (int k = 0; k < 6; k++) {
            in[k].method = M->id;
            in[k].layout = (uint8_t)(M->layouts ? k % M->layouts : 0);
            in[k].corner = (uint8_t)(in[k].layout == 2 ? k % 3 : 0);
            in[k].checksum = k == 0 ? 0u : k == 1 ? 0xffffffffu : 0x9e3779b9u * (uint32_t)k;
        }
        /* GREGORY-FIT's corrections: m 1..3, one patch or five, every step, coordinates of both signs
           up to the largest the reader takes (the other methods ignore them) */
        static int32_t q[6][CM_FIT_MAX_COEF * 5][3];
        cm_fit_q fit[6];
        for (int k = 0; k < 6; k++) {
            fit[k].m = 1 + k % CM_FIT_MAX_M;
            /* five patches where the build holds them (the tiny profile's pool and MAX_GREG do not) */
            int most = CM_MAX_MODEL_CTRL / (fit[k].m * fit[k].m);
            most = most < CM_MAX_GREG ? most : CM_MAX_GREG;
            fit[k].patches = in[k].layout == 1 ? (most < 5 ? most : 5) : 1;
            fit[k].exp = k == 5 ? CM_FIT_MAX_EXP : k;
            fit[k].q = (const int32_t(*)[3])q[k];
            for (int c = 0; c < fit[k].patches * fit[k].m * fit[k].m; c++)
                for (int a = 0; a < 3; a++)
                    q[k][c][a] = c == 0 && a == 0 ? (k % 2 ? -CM_FIT_MAX_INT : CM_FIT_MAX_INT) : (c - 3 * a) * (k + 1);
        }
        cm_ac_enc e;
        cm_face_ctx ctx;
        cm_face_ctx_init(&ctx);
        cm_ac_enc_init(&e, buf, sizeof buf);
        for (int k = 0; k < 6; k++)
            cm_method_write_record(M, &e, &ctx, &in[k], &fit[k]);
        size_t n = cm_ac_enc_finish(&e);
        assert_true(n > 0 && !e.overflow);
        cm_ac_dec d;
        cm_face_ctx_init(&ctx);
        cm_ac_dec_init(&d, buf, n);
        model.q = 1.0 / 1024.0;
        for (int k = 0; k < 6; k++) {
            cm_face out = {0};
            cm_method_fault why = {0};
            model.nctrl = 0; /* one record's coefficients at a time: the tiny profile's pool is small */
            assert_int_equal(cm_method_read_record(M, &d, &ctx, &model, &out, &why), CM_OK);
            assert_int_equal(out.layout, in[k].layout);
            assert_int_equal(out.corner, in[k].corner);
            assert_int_equal(out.checksum, in[k].checksum);
            if (!out.fit)
                continue;
            /* the correction, dequantised into the model's pool */
            assert_int_equal(cm_face_fit_m(&out), fit[k].m);
            assert_int_equal(cm_face_fit_patches(&out), fit[k].patches);
            for (int j = 0; j < fit[k].patches * fit[k].m * fit[k].m; j++) {
                cm_vec3 c = model.ctrl[out.surf + (uint32_t)j];
                assert_true(c.x == ldexp(q[k][j][0], fit[k].exp) * model.q);
                assert_true(c.y == ldexp(q[k][j][1], fit[k].exp) * model.q);
                assert_true(c.z == ldexp(q[k][j][2], fit[k].exp) * model.q);
            }
        }
        /* cut short: the reader says truncated, naming the record */
        cm_face_ctx_init(&ctx);
        cm_ac_dec_init(&d, buf, 1);
        cm_face out = {0};
        cm_method_fault why = {0};
        cm_err got = CM_OK;
        model.nctrl = 0;
        for (int k = 0; k < 6 && got == CM_OK; k++)
            got = cm_method_read_record(M, &d, &ctx, &model, &out, &why);
        assert_int_equal(got, CM_E_TRUNCATED);
        assert_non_null(why.what);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_number_has_one_module),
        cmocka_unit_test(test_fallback_is_last_and_kept),
        cmocka_unit_test(test_records_round_trip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
