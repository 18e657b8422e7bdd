/* test_arith.c - range coder round trips, integer models, truncation, CRC-32. */
#include "test_util.h"

#include "cm/cm_arith.h"
#include "cm/cm_crc32.h"

static uint8_t buf[1 << 20];

/* many values of several magnitudes through two models and raw bits, back unchanged */
static void test_round_trip(void **state)
{
    (void)state;
    uint32_t seed = 99;
    enum { N = 20000 };
    static int64_t vals[N];
    static uint32_t raw[N];
    for (int i = 0; i < N; i++) {
        double r = test_rand(&seed);
        int shift = (int)(test_rand(&seed) * 33);
        int64_t mag = (int64_t)(r * (double)(1ull << shift));
        vals[i] = (i % 3 == 0) ? -mag : mag;
        raw[i] = (uint32_t)(test_rand(&seed) * 4096);
    }
    cm_ac_enc e;
    cm_ac_int ma, mb;
    cm_ac_prob pb;
    cm_ac_int_init(&ma);
    cm_ac_int_init(&mb);
    cm_ac_prob_init(&pb);
    cm_ac_enc_init(&e, buf, sizeof buf);
    for (int i = 0; i < N; i++) {
        cm_ac_enc_sint(&e, &ma, vals[i]);
        cm_ac_enc_uint(&e, &mb, (uint64_t)(i % 7));
        cm_ac_enc_bit(&e, &pb, (unsigned)(i % 5 == 0));
        cm_ac_enc_direct(&e, raw[i], 12);
    }
    size_t n = cm_ac_enc_finish(&e);
    assert_true(n > 0 && !e.overflow);
    cm_ac_dec d;
    cm_ac_int_init(&ma);
    cm_ac_int_init(&mb);
    cm_ac_prob_init(&pb);
    cm_ac_dec_init(&d, buf, n);
    for (int i = 0; i < N; i++) {
        assert_true(cm_ac_dec_sint(&d, &ma) == vals[i]);
        assert_true(cm_ac_dec_uint(&d, &mb) == (uint64_t)(i % 7));
        assert_int_equal(cm_ac_dec_bit(&d, &pb), (unsigned)(i % 5 == 0));
        assert_int_equal(cm_ac_dec_direct(&d, 12), raw[i]);
    }
    assert_false(d.overrun);
}

/* a skewed source codes well below its raw size: the models adapt */
static void test_adapts(void **state)
{
    (void)state;
    cm_ac_enc e;
    cm_ac_int m;
    cm_ac_int_init(&m);
    cm_ac_enc_init(&e, buf, sizeof buf);
    for (int i = 0; i < 10000; i++)
        cm_ac_enc_sint(&e, &m, (i % 10) == 0 ? 3 : 1);
    size_t n = cm_ac_enc_finish(&e);
    /* entropy of the source ~0.47 bit per symbol plus the sign: well under 1500 bytes */
    assert_true(n < 1500);
}

/* reading past the end never touches memory beyond the buffer and flags it */
static void test_overrun_flagged(void **state)
{
    (void)state;
    cm_ac_enc e;
    cm_ac_int m;
    cm_ac_int_init(&m);
    cm_ac_enc_init(&e, buf, sizeof buf);
    for (int i = 0; i < 100; i++)
        cm_ac_enc_uint(&e, &m, 123456789);
    size_t n = cm_ac_enc_finish(&e);
    cm_ac_dec d;
    cm_ac_int_init(&m);
    cm_ac_dec_init(&d, buf, n / 2);
    for (int i = 0; i < 100; i++)
        (void)cm_ac_dec_uint(&d, &m);
    assert_true(d.overrun);
    /* an empty buffer: every read is an overrun, values are whatever zeros decode to */
    cm_ac_dec_init(&d, buf, 0);
    (void)cm_ac_dec_uint(&d, &m);
    assert_true(d.overrun);
}

static void test_encoder_overflow(void **state)
{
    (void)state;
    uint8_t small[16];
    cm_ac_enc e;
    cm_ac_int m;
    cm_ac_int_init(&m);
    cm_ac_enc_init(&e, small, sizeof small);
    for (int i = 0; i < 1000; i++)
        cm_ac_enc_uint(&e, &m, (uint64_t)i * 7919u);
    assert_int_equal(cm_ac_enc_finish(&e), 0);
    assert_true(e.overflow);
}

static void test_crc32(void **state)
{
    (void)state;
    const uint8_t s[] = "123456789";
    assert_int_equal(cm_crc32(s, 9), 0xCBF43926u); /* the standard check value */
    uint32_t c = cm_crc32_update(0, s, 4);
    assert_int_equal(cm_crc32_update(c, s + 4, 5), 0xCBF43926u);
    assert_int_equal(cm_crc32(s, 0), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),      cmocka_unit_test(test_adapts),
        cmocka_unit_test(test_overrun_flagged), cmocka_unit_test(test_encoder_overflow),
        cmocka_unit_test(test_crc32),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
