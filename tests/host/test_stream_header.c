/*
 * test_stream_header.c - format 4.6: the header's fields one range-coded stream, the five sections
 * one stream (cm_fmt_stream_pack / cm_fmt_stream_unpack, docs/FORMAT.md "Header, format 4.6").
 * The fields exactly, 64-bit ones and needs past the build's list included; synthetic IGES ->
 * encoder -> .cmz in 4.5 and 4.6 -> the terminal's decoder: the same model to the bit, the 10 mm
 * box under Draco's 80 bytes; 4.6 headers out of range or cut short, each refused by name before any
 * byte of the body is read, and a body cut short refused as truncated.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_arith.h"
#include "cm/cm_crc32.h"
#include "cm/cm_decode.h"
#include "cm/cm_limits_info.h"
#include "encode/encode.h"
#include "cmz_splice.h"
#include "igs_writer.h"
#include "model_load.h"

static cm_decoder dec, dec45;

/* ---- the fields, exactly ---- */

static void test_fields_round_trip(void **state)
{
    (void)state;
    static uint8_t b[CM_FMT_MAX_HEADER];
    cm_fmt_header h = {0}, back;
    h.major = CM_FMT_COMPACT_MAJOR;
    h.minor = CM_FMT_ONE_STREAM_MINOR;
    h.flags = 1;
    h.nlimits = CM_LIMIT_COUNT + 3; /* needs past this build's list: two zero, one not */
    h.q_exp = -17;
    double q = ldexp(1.0, -17);
    /* an origin far from the part: multiples of its step past the coder's 2^33 (the escape) */
    h.origin[0] = -3.0 * ldexp(1.0, 40) * q;
    h.origin[1] = 0.0;
    h.origin[2] = 5.0 * ldexp(1.0, 3) * q;
    h.tess_tol = 1234.0 * q;
    h.rel_tol = 0.004;
    uint32_t need[CM_LIMIT_COUNT + 3], got[CM_LIMIT_COUNT + 3];
    for (uint32_t i = 0; i < CM_LIMIT_COUNT; i++)
        need[i] = i * 977u + (i == CM_LIMIT_MAX_EDGES ? 4000000000u : 0u); /* one far from its prediction */
    need[CM_LIMIT_COUNT] = 0;
    need[CM_LIMIT_COUNT + 1] = 7;
    need[CM_LIMIT_COUNT + 2] = 0;
    uint32_t H = cm_fmt_stream_pack(b, &h, need, 123456u);
    assert_true(H >= CM_FMT_STREAM_MIN_HEADER && H < 256);
    assert_int_equal(h.header_len, H);
    assert_int_equal(h.file_len, H + 123456u + 4u);
    assert_int_equal(cm_get_u32(b + H - 4), cm_crc32(b, H - 4));
    uint32_t unknown;
    const char *why = cm_fmt_stream_unpack(b, H, &back, got, CM_LIMIT_COUNT, &unknown);
    assert_null(why);
    assert_int_equal(unknown, CM_LIMIT_COUNT + 1);
    for (uint32_t i = 0; i < CM_LIMIT_COUNT; i++)
        assert_int_equal(got[i], i == CM_LIMIT_MAX_FILE_BYTES ? h.file_len : need[i]);
    assert_int_equal(back.flags, 1);
    assert_int_equal(back.nlimits, CM_LIMIT_COUNT + 3);
    assert_int_equal(back.q_exp, -17);
    assert_int_equal(back.file_len, h.file_len);
    for (int k = 0; k < 3; k++)
        assert_true(back.origin[k] == h.origin[k]);
    assert_true(back.tess_tol == h.tess_tol);
    assert_true(fabs(back.rel_tol - 0.004) <= ldexp(1.0, -25));
    /* the reader's other entry (cmz send's profile check) sees the same needs */
    uint32_t count;
    assert_true(cm_fmt_header_needs(b, H, got, CM_LIMIT_COUNT, &count));
    assert_int_equal(count, CM_LIMIT_COUNT + 3);
    assert_int_equal(got[CM_LIMIT_MAX_EDGES], need[CM_LIMIT_MAX_EDGES]);
    /* needs far from what the others predict (a prediction past 2^32 - 1, one below 0): still exact */
    uint32_t far[CM_LIMIT_COUNT] = {0};
    far[CM_LIMIT_MAX_EDGES] = far[CM_LIMIT_MAX_MODEL_CTRL] = UINT32_MAX; /* knots predicted past 2^33 */
    far[CM_LIMIT_MAX_FACES] = UINT32_MAX;                                /* vertices predicted below 0 */
    far[CM_LIMIT_MAX_VERTICES] = 5;
    h.nlimits = CM_LIMIT_COUNT;
    H = cm_fmt_stream_pack(b, &h, far, 10u);
    assert_true(H > 0);
    assert_null(cm_fmt_stream_unpack(b, H, &back, got, CM_LIMIT_COUNT, &unknown));
    for (uint32_t i = 0; i < CM_LIMIT_COUNT; i++)
        if (i != CM_LIMIT_MAX_FILE_BYTES)
            assert_int_equal(got[i], far[i]);
    /* bytes after the fields, before the CRC: no field's, refused */
    H = cm_fmt_stream_pack(b, &h, far, 10u);
    assert_true(H + 8 < 128);
    uint8_t pad[CM_FMT_MAX_HEADER];
    memcpy(pad, b, H - 4);
    memset(pad + H - 4, 0x5A, 8);
    pad[CM_FMT_COMPACT_AT_H] = (uint8_t)(H + 8); /* (one byte) */
    cm_put_u32(pad + H + 4, cm_crc32(pad, H + 4));
    why = cm_fmt_stream_unpack(pad, H + 8, &back, got, CM_LIMIT_COUNT, &unknown);
    assert_non_null(why);
    assert_non_null(strstr(why, "fields end before the header CRC"));
    /* the stream cut: its fields run past the CRC */
    uint8_t cut[CM_FMT_MAX_HEADER];
    memcpy(cut, b, 8);
    cut[CM_FMT_COMPACT_AT_H] = 12; /* H = 12: one byte of fields */
    cm_put_u32(cut + 8, cm_crc32(cut, 8));
    why = cm_fmt_stream_unpack(cut, 12, &back, got, CM_LIMIT_COUNT, &unknown);
    assert_non_null(why);
    assert_non_null(strstr(why, "past the header CRC"));
}

/* ---- the same model in 4.5 and 4.6 ---- */

static void load(igw *w, const char *name, loaded_model *lm)
{
    cm_status st;
    assert_ok(igw_load(w, name, lm, &st));
}

static void encode_minor(loaded_model *lm, int minor, encode_result *r)
{
    encode_opts o;
    encode_opts_default(&o);
    encode_opts_for_format(&o, CM_FMT_COMPACT_MAJOR, minor);
    cm_status st;
    cm_status_init(&st);
    memset(r, 0, sizeof *r);
    assert_ok(encode_model(lm, &o, r, &st));
}

static void decode_into(cm_decoder *d, const uint8_t *b, size_t len)
{
    cm_status st;
    assert_ok(cmz_decode(d, b, len, &st));
}

/* r5 and r6 decode to one model, bit for bit, with the same needs; 4.6 saves at least `saved` */
static void assert_same_model(const encode_result *r5, const encode_result *r6, size_t saved)
{
    assert_int_equal(r6->bytes[CM_HDR_MINOR], CM_FMT_ONE_STREAM_MINOR);
    decode_into(&dec45, r5->bytes, r5->len);
    decode_into(&dec, r6->bytes, r6->len);
    const cm_model *a = &dec45.model, *b = &dec.model;
    assert_int_equal(a->nverts, b->nverts);
    assert_int_equal(a->nedges, b->nedges);
    assert_int_equal(a->nfaces, b->nfaces);
    assert_int_equal(a->nsurfs, b->nsurfs);
    assert_int_equal(a->nuses, b->nuses);
    assert_int_equal(a->nctrl, b->nctrl);
    assert_memory_equal(a->verts, b->verts, a->nverts * sizeof *a->verts);
    assert_memory_equal(a->ctrl, b->ctrl, a->nctrl * sizeof *a->ctrl);
    for (uint32_t f = 0; f < a->nfaces; f++) {
        assert_int_equal(a->faces[f].method, b->faces[f].method);
        assert_int_equal(a->faces[f].color, b->faces[f].color);
    }
    for (int k = 0; k < 3; k++)
        assert_true(a->origin[k] == b->origin[k]);
    assert_true(a->q == b->q && a->tess_tol == b->tess_tol && a->rel_tol == b->rel_tol);
    for (int i = 0; i < CM_LIMIT_COUNT; i++)
        if (i != CM_LIMIT_MAX_FILE_BYTES)
            assert_int_equal(dec45.need[i], dec.need[i]);
    assert_int_equal(dec.need[CM_LIMIT_MAX_FILE_BYTES], r6->len);
    if (!(r6->len + saved <= r5->len))
        fail_msg("4.6: %zu bytes, 4.5: %zu", r6->len, r5->len);
    /* the writer's share of each section adds up to the body */
    size_t body = 0;
    for (int s = 1; s <= CM_SEC_COUNT; s++)
        body += r6->section_bytes[s];
    assert_int_equal(body, r6->len - r6->section_bytes[0] - 4);
}

static void test_same_model_both_minors(void **state)
{
    (void)state;
    igw w;
    loaded_model lm;
    encode_result r5, r6;
    /* the 10 mm box: Draco's mesh of such a cube takes 80 bytes (README, benchmarks) */
    igw_init(&w);
    igw_box_144(&w, 10.0, 10.0, 10.0);
    load(&w, "cube", &lm);
    encode_minor(&lm, (int)CM_FMT_USE_ADJ_MINOR, &r5);
    encode_minor(&lm, (int)CM_FMT_ONE_STREAM_MINOR, &r6);
    assert_same_model(&r5, &r6, 20);
    if (!(r6.len < 80))
        fail_msg("the 10 mm box: %zu bytes", r6.len);
    encode_result_free(&r5);
    encode_result_free(&r6);
    model_free(&lm);
    igw_init(&w);
    igw_box_with_hole_144(&w, 40.0, 30.0, 20.0, 6.0);
    load(&w, "box", &lm);
    encode_minor(&lm, (int)CM_FMT_USE_ADJ_MINOR, &r5);
    encode_minor(&lm, (int)CM_FMT_ONE_STREAM_MINOR, &r6);
    assert_same_model(&r5, &r6, 10);
    encode_result_free(&r5);
    encode_result_free(&r6);
    model_free(&lm);
}

/* ---- hostile 4.6 headers ---- */

static encode_result good;
static cm_fmt_header good_h;
static uint32_t good_need[CM_LIMIT_COUNT + 8];

static int setup_good(void **state)
{
    (void)state;
    igw w;
    loaded_model lm;
    igw_init(&w);
    igw_box_with_hole_144(&w, 40.0, 30.0, 20.0, 6.0);
    load(&w, "box", &lm);
    encode_minor(&lm, (int)CM_FMT_ONE_STREAM_MINOR, &good);
    model_free(&lm);
    uint32_t unknown;
    uint32_t H = (uint32_t)good.section_bytes[0];
    assert_null(cm_fmt_stream_unpack(good.bytes, H, &good_h, good_need, CM_LIMIT_COUNT + 8, &unknown));
    assert_int_equal(unknown, UINT32_MAX);
    return 0;
}

static int teardown_good(void **state)
{
    (void)state;
    encode_result_free(&good);
    return 0;
}

/* the good file's body (its sections' stream) behind the header packed from h, need and body_len;
   every CRC valid.  Returns the file's length, *hl the header's. */
static size_t with_header(uint8_t *out, cm_fmt_header h, const uint32_t *need, uint32_t body_len, uint32_t *hl)
{
    uint32_t H = (uint32_t)good.section_bytes[0];
    size_t body = good.len - H - 4;
    *hl = cm_fmt_stream_pack(out, &h, need, body_len);
    assert_true(*hl > 0);
    memcpy(out + *hl, good.bytes + H, body);
    size_t total = *hl + body + 4;
    cm_put_u32(out + total - 4, cm_crc32(out, total - 4));
    return total;
}

/* the header alone (and then the file) fed: refused with `want` at byte `at`, naming `where` */
static void assert_refused(const uint8_t *b, size_t n, size_t hl, cm_err want, uint32_t at, const char *where)
{
    const char *why = cmz_header_refused(&dec, b, n, hl, want, at, where);
    if (why)
        fail_msg("%s", why);
}

/* the good header coded here field by field as cm_fmt_stream_pack does, but its rebuild tolerance's
   field the raw 64-bit value `rel` (what no writer sends: the reader must not overflow on it) */
static void put_wide_raw(cm_ac_enc *e, cm_ac_int *m, uint64_t v)
{
    const uint64_t esc = (1ull << 33) - 1u;
    cm_ac_enc_uint(e, m, v < esc ? v : esc);
    if (v >= esc)
        for (int k = 3; k >= 0; k--)
            cm_ac_enc_direct(e, (uint32_t)(v >> (16 * k)) & 0xFFFFu, 16);
}

static uint32_t header_with_rel(uint8_t *out, uint64_t rel, uint32_t body)
{
    cm_ac_int flags, extra, bodym, need, diff, qexp, oshift, origin, tess, relm;
    cm_ac_int *all[] = {&flags, &extra, &bodym, &need, &diff, &qexp, &oshift, &origin, &tess, &relm};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
        cm_ac_int_init(all[i]);
    uint8_t fields[CM_FMT_MAX_HEADER];
    cm_ac_enc e;
    cm_ac_enc_init(&e, fields, sizeof fields);
    cm_ac_enc_uint(&e, &flags, good_h.flags);
    cm_ac_enc_uint(&e, &extra, good_h.nlimits - CM_FMT_MIN_NEEDS);
    cm_ac_enc_uint(&e, &bodym, body);
    for (uint32_t i = 0; i < good_h.nlimits; i++) {
        if (i == CM_LIMIT_MAX_FILE_BYTES)
            continue;
        int64_t pred = cm_fmt_need_pred(i, good_need);
        if (pred == 0)
            cm_ac_enc_uint(&e, &need, good_need[i]);
        else
            cm_ac_enc_sint(&e, &diff, (int64_t)good_need[i] - pred);
    }
    /* grid and origin as the good header's: read back from its own bytes below is not needed, the
       reader only has to reach the tolerance; e = the good one, the origin at 0, a tolerance of 1 */
    cm_ac_enc_sint(&e, &qexp, good_h.q_exp);
    cm_ac_enc_uint(&e, &oshift, 0);
    for (int k = 0; k < 3; k++)
        put_wide_raw(&e, &origin, 0);
    put_wide_raw(&e, &tess, 1);
    put_wide_raw(&e, &relm, rel);
    size_t n = cm_ac_enc_finish_trimmed(&e);
    uint32_t H = (uint32_t)(CM_FMT_COMPACT_AT_H + 1u + n + 4u);
    assert_true(H < 128);
    memcpy(out, good.bytes, CM_FMT_COMPACT_AT_H);
    out[CM_FMT_COMPACT_AT_H] = (uint8_t)H;
    memcpy(out + CM_FMT_COMPACT_AT_H + 1, fields, n);
    cm_put_u32(out + H - 4, cm_crc32(out, H - 4));
    return H;
}

static void test_hostile_stream_headers(void **state)
{
    (void)state;
    static uint8_t b[1 << 20];
    static uint32_t need[CM_LIMIT_COUNT + 8];
    const uint32_t body = good.len - (uint32_t)good.section_bytes[0] - 4, fields_at = CM_FMT_COMPACT_AT_H + 1;
    uint32_t hl;
    cm_fmt_header h;
    /* the good header packed again: the same file, which decodes */
    size_t n = with_header(b, good_h, good_need, body, &hl);
    assert_int_equal(n, good.len);
    assert_memory_equal(b, good.bytes, good.len);
    decode_into(&dec, b, n);
#define NEEDS_WITH(i, v) (memcpy(need, good_need, sizeof need), need[(i)] = (v), need)
    /* a need over this build's limit; a limit this build does not know that the model needs (and one
       it needs 0 of: read) */
    n = with_header(b, good_h, NEEDS_WITH(CM_LIMIT_MAX_FACES, CM_MAX_FACES + 1u), body, &hl);
    assert_refused(b, n, hl, CM_E_LIMIT, fields_at, "header needs");
    h = good_h;
    h.nlimits = CM_LIMIT_COUNT + 1;
    n = with_header(b, h, NEEDS_WITH(CM_LIMIT_COUNT, 1), body, &hl);
    assert_refused(b, n, hl, CM_E_VERSION, fields_at, "unknown limit");
    n = with_header(b, h, NEEDS_WITH(CM_LIMIT_COUNT, 0), body, &hl);
    decode_into(&dec, b, n);
    /* a body past MAX_FILE_BYTES, named with the limit */
    n = with_header(b, good_h, good_need, (uint32_t)CM_MAX_FILE_BYTES, &hl);
    assert_refused(b, n, hl, CM_E_LIMIT, fields_at, "file length");
    /* a body longer than the bytes that come: truncated at the end, not read past it */
    n = with_header(b, good_h, good_need, body + 1, &hl);
    {
        cm_status st;
        assert_err(cmz_decode(&dec, b, n, &st), CM_E_TRUNCATED);
    }
    /* grid and tolerances */
    h = good_h;
    h.q_exp = 21;
    n = with_header(b, h, good_need, body, &hl);
    assert_refused(b, n, hl, CM_E_RANGE, fields_at, "quantisation exponent");
    h = good_h;
    h.tess_tol = 0;
    n = with_header(b, h, good_need, body, &hl);
    assert_refused(b, n, hl, CM_E_RANGE, fields_at, "chordal tolerance");
    h = good_h;
    h.rel_tol = -0.5;
    n = with_header(b, h, good_need, body, &hl);
    assert_refused(b, n, hl, CM_E_RANGE, fields_at, "rebuild tolerance");
    /* the fields cut short (H = 12: one byte of them), below any header, a CRC that does not match,
       a minor this reader does not know */
    n = with_header(b, good_h, good_need, body, &hl);
    memmove(b + 12, b + hl, n - hl);
    b[CM_FMT_COMPACT_AT_H] = 12;
    cm_put_u32(b + 8, cm_crc32(b, 8));
    n = n - hl + 12;
    cm_put_u32(b + n - 4, cm_crc32(b, n - 4));
    assert_refused(b, n, 12, CM_E_FORMAT, fields_at, "past the header CRC");
    b[CM_FMT_COMPACT_AT_H] = 11;
    assert_refused(b, n, 12, CM_E_FORMAT, CM_FMT_COMPACT_AT_H, "header length");
    n = with_header(b, good_h, good_need, body, &hl);
    b[fields_at] ^= 0x10;
    assert_refused(b, n, hl, CM_E_CRC, hl - 4, "header CRC");
    n = with_header(b, good_h, good_need, body, &hl);
    b[CM_HDR_MINOR] = CM_FMT_VERSION_MINOR + 1;
    assert_refused(b, n, hl, CM_E_VERSION, CM_HDR_MINOR, "minor newer");
    /* a rebuild tolerance's field at the top of 64 bits (zigzag: +2^63 - 1): read without overflow,
       a huge tolerance, finite and positive (it is informative); the body is read as before */
    {
        uint32_t H = header_with_rel(b, UINT64_MAX - 1u, body);
        memcpy(b + H, good.bytes + good.section_bytes[0], body);
        n = H + body + 4;
        cm_put_u32(b + n - 4, cm_crc32(b, n - 4));
        decode_into(&dec, b, n);
        assert_true(dec.model.rel_tol > 1e11 && isfinite(dec.model.rel_tol));
    }
    /* bytes after the sections' stream (the header counting them): no section's, refused */
    {
        n = with_header(b, good_h, good_need, body + 16, &hl);
        size_t end = hl + body;
        memset(b + end, 0x77, 16);
        n = end + 16 + 4;
        cm_put_u32(b + n - 4, cm_crc32(b, n - 4));
        cm_status st;
        cm_err e = cmz_decode(&dec, b, n, &st);
        if (e == CM_OK)
            fail_msg("16 bytes after the sections: read");
        if (e == CM_E_FORMAT && !strstr(st.where, "bytes after the sections"))
            fail_msg("16 bytes after the sections: says \"%s\"", st.where);
    }
    /* the sections' stream cut by a few bytes (the header saying so, every CRC valid): truncated */
    for (uint32_t cut = 1; cut <= 8 && cut < body; cut++) {
        n = with_header(b, good_h, good_need, body - cut, &hl);
        n -= cut;
        cm_put_u32(b + n - 4, cm_crc32(b, n - 4));
        cm_status st;
        cm_err e = cmz_decode(&dec, b, n, &st);
        if (e != CM_E_TRUNCATED && e != CM_E_RANGE && e != CM_E_FORMAT)
            fail_msg("body cut by %u: %s (%s)", cut, cm_err_name(e), st.where ? st.where : "?");
    }
#undef NEEDS_WITH
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fields_round_trip),
        cmocka_unit_test(test_same_model_both_minors),
        cmocka_unit_test_setup_teardown(test_hostile_stream_headers, setup_good, teardown_good),
    };
    return cmocka_run_group_tests_name("stream_header", tests, NULL, NULL);
}
