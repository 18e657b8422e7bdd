/*
 * test_format4.c - format 4's compact header, trimmed section streams and vertices among recent
 * values (cm_fmt_compact_pack, cm_ac_enc_finish_trimmed, cm_vcache; docs/FORMAT.md): the varints
 * and the coder exactly; synthetic IGES ->
 * encoder -> .cmz as format 4 (the default) and as format 3 -> the terminal's decoder: the same
 * model but for the sub-step shift of the grid's origin, every face rebuilt the same way, the format
 * 4 file smaller by the header; and format 4 headers whose fields are out of place or range, each
 * refused by name at the field's own byte, before any byte of the body is read.
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
#include "cm/cm_predict.h"
#include "cm/cm_sections.h"
#include "encode/encode.h"
#include "cmz_splice.h"
#include "igs_writer.h"
#include "model_load.h"

static cm_decoder dec3, dec4;

/* ---- varints and the trimmed coder, exactly ---- */

static void test_varints(void **state)
{
    (void)state;
    static const uint64_t vals[] = {0, 1, 127, 128, 300, 16383, 16384, (1ull << 32) - 1, 1ull << 35, UINT64_MAX};
    static const uint32_t lens[] = {1, 1, 1, 2, 2, 2, 3, 5, 6, 10};
    for (size_t i = 0; i < sizeof vals / sizeof vals[0]; i++) {
        uint8_t b[CM_FMT_VARINT_MAX + 2];
        uint32_t n = cm_fmt_put_varint(b, vals[i]), at = 0;
        assert_int_equal(n, lens[i]);
        uint64_t v = 0;
        assert_true(cm_fmt_get_varint(b, n, &at, &v));
        assert_true(v == vals[i]);
        assert_int_equal(at, n);
        at = 0; /* one byte short: not ended */
        assert_false(cm_fmt_get_varint(b, n - 1, &at, &v));
    }
    /* past 64 bits: a tenth byte above 1, or an eleventh byte */
    uint8_t big[11] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x02, 0};
    uint32_t at = 0;
    uint64_t v;
    assert_false(cm_fmt_get_varint(big, 11, &at, &v));
    big[9] = 0x81;
    at = 0;
    assert_false(cm_fmt_get_varint(big, 11, &at, &v));
    for (int64_t s = -70; s <= 70; s++)
        assert_true(cm_fmt_unzigzag(cm_fmt_zigzag(s)) == s);
    assert_true(cm_fmt_unzigzag(cm_fmt_zigzag(INT64_MIN)) == INT64_MIN);
    assert_true(cm_fmt_unzigzag(cm_fmt_zigzag(INT64_MAX)) == INT64_MAX);
    assert_true(cm_fmt_zigzag(-1) == 1 && cm_fmt_zigzag(1) == 2);
    /* the chordal tolerance format 4 can say: a multiple >= 1 of the grid step */
    assert_true(cm_fmt_compact_tess(0.3, -2) == 0.25);
    assert_true(cm_fmt_compact_tess(1e-9, -2) == 0.25);
    assert_true(cm_fmt_compact_tess(10.0, 3) == 8.0);
}

/* streams of every length up to 300 fields: the trimmed one four bytes shorter than the full one
   (three zeros and the leading 0; a fourth zero sometimes), decoded the same without an overrun;
   read past its pad, it overruns */
static void test_trimmed_streams(void **state)
{
    (void)state;
    static uint8_t full[1 << 14], trim[1 << 14];
    uint32_t seed = 7;
    for (int nf = 0; nf <= 300; nf += 1 + nf / 10) {
        cm_ac_enc e;
        cm_ac_int m1, m2;
        cm_ac_prob p1, p2;
        size_t n[2];
        for (int pass = 0; pass < 2; pass++) {
            uint32_t s = seed;
            cm_ac_int_init(&m1);
            cm_ac_int_init(&m2);
            cm_ac_prob_init(&p1);
            cm_ac_enc_init(&e, pass ? trim : full, sizeof full);
            for (int i = 0; i < nf; i++) {
                cm_ac_enc_sint(&e, &m1, (int64_t)(test_rand(&s) * 2000.0) - 1000);
                cm_ac_enc_bit(&e, &p1, test_rand(&s) < 0.9);
                cm_ac_enc_uint(&e, &m2, (uint64_t)(test_rand(&s) * 5.0));
            }
            n[pass] = pass ? cm_ac_enc_finish_trimmed(&e) : cm_ac_enc_finish(&e);
            assert_false(e.overflow);
        }
        if (!(n[1] + 4 <= n[0] && n[1] + 5 >= n[0]))
            fail_msg("%d fields: trimmed %zu bytes, full %zu", nf, n[1], n[0]);
        cm_ac_dec d;
        cm_ac_dec_init_trimmed(&d, trim, n[1]);
        uint32_t s = seed;
        cm_ac_int_init(&m1);
        cm_ac_int_init(&m2);
        cm_ac_prob_init(&p2);
        for (int i = 0; i < nf; i++) {
            int64_t a = (int64_t)(test_rand(&s) * 2000.0) - 1000;
            unsigned bit = test_rand(&s) < 0.9;
            uint64_t c = (uint64_t)(test_rand(&s) * 5.0);
            assert_true(cm_ac_dec_sint(&d, &m1) == a);
            assert_int_equal(cm_ac_dec_bit(&d, &p2), bit);
            assert_true(cm_ac_dec_uint(&d, &m2) == c);
        }
        assert_false(d.overrun);
        /* past what the stream and its pad hold: an overrun */
        for (int i = 0; i < 64 && !d.overrun; i++)
            (void)cm_ac_dec_direct(&d, 8);
        assert_true(d.overrun);
        seed += 17;
    }
    /* nothing coded but a likely bit: no byte at all, which decodes */
    cm_ac_enc e;
    cm_ac_prob p;
    cm_ac_prob_init(&p);
    cm_ac_enc_init(&e, trim, sizeof trim);
    cm_ac_enc_bit(&e, &p, 0);
    assert_int_equal(cm_ac_enc_finish_trimmed(&e), 0);
    cm_ac_dec d;
    cm_ac_dec_init_trimmed(&d, trim, 0);
    cm_ac_prob_init(&p);
    assert_int_equal(cm_ac_dec_bit(&d, &p), 0);
    assert_false(d.overrun);
}

/* ---- the same model both ways ---- */

/* format `major` (0: the default), every point on the grid (the budget steps would move them by
   a share of the tolerance, differently about either origin: the header is what differs here) */
static void encode_as_minor(loaded_model *lm, int major, int minor, encode_result *r)
{
    encode_opts o;
    encode_opts_default(&o);
    o.budget_steps = 0;
    if (major)
        encode_opts_for_format(&o, major, minor);
    cm_status st;
    cm_status_init(&st);
    memset(r, 0, sizeof *r);
    assert_ok(encode_model(lm, &o, r, &st));
}

static void encode_as(loaded_model *lm, int major, encode_result *r) { encode_as_minor(lm, major, 0, r); }

static void decode_into(cm_decoder *d, const uint8_t *b, size_t len)
{
    cm_status st;
    cm_status_init(&st);
    cm_dec_init(d);
    assert_ok(cm_dec_feed(d, b, len, &st));
    assert_ok(cm_dec_finish(d, &st));
}

static void load(igw *w, const char *name, loaded_model *lm)
{
    size_t len = 0;
    char *text = igw_text(w, &len);
    cm_status st;
    cm_status_init(&st);
    assert_ok(model_load_data(name, text, len, lm, NULL, NULL, &st));
    free(text);
    igw_free(w);
}

/* format 4 (the default) and format 3 of one model: the same vertices, edges and faces within a grid
   step (the origin moved onto the grid by less than one), the same methods, the header's fields the
   same (needs, grid, tolerances up to format 4's rounding), and the format 4 file smaller by what
   its header and streams save */
static void check_both_ways(loaded_model *lm)
{
    encode_result r3, r4, r41;
    encode_as(lm, 3, &r3);
    encode_as_minor(lm, 4, 0, &r4);
    encode_as_minor(lm, 4, CM_FMT_SHORT_ORIGIN_MINOR, &r41);
    assert_int_equal(r3.bytes[CM_HDR_MAJOR], CM_FMT_PREDICT_MAJOR);
    assert_int_equal(r4.bytes[CM_HDR_MAJOR], CM_FMT_COMPACT_MAJOR);
    assert_int_equal(r4.bytes[CM_HDR_MINOR], 0);
    assert_int_equal(r41.bytes[CM_HDR_MAJOR], CM_FMT_COMPACT_MAJOR);
    assert_int_equal(r41.bytes[CM_HDR_MINOR], CM_FMT_SHORT_ORIGIN_MINOR);
    /* format 4.1: the origin on a coarse power-of-two step, the same points (one grid, about
       either origin), the header shorter */
    decode_into(&dec3, r4.bytes, r4.len);
    decode_into(&dec4, r41.bytes, r41.len);
    assert_int_equal(dec3.model.nverts, dec4.model.nverts);
    for (uint32_t v = 0; v < dec3.model.nverts; v++)
        assert_true(cm_dist(dec3.model.verts[v], dec4.model.verts[v]) == 0.0);
    for (int k = 0; k < 3; k++)
        assert_true(dec4.model.origin[k] <= dec3.model.origin[k]);
    assert_true(fabs(dec4.model.rel_tol - dec3.model.rel_tol) == 0.0);
    if (!(r41.section_bytes[0] < r4.section_bytes[0]))
        fail_msg("format 4.1's header %zu bytes, 4.0's %zu", r41.section_bytes[0], r4.section_bytes[0]);
    encode_result_free(&r41);
    decode_into(&dec3, r3.bytes, r3.len);
    decode_into(&dec4, r4.bytes, r4.len);
    const cm_model *a = &dec3.model, *b = &dec4.model;
    assert_int_equal(a->nverts, b->nverts);
    assert_int_equal(a->nedges, b->nedges);
    assert_int_equal(a->nfaces, b->nfaces);
    assert_int_equal(a->nsurfs, b->nsurfs);
    assert_true(a->q == b->q);
    for (uint32_t v = 0; v < a->nverts; v++)
        assert_true(cm_dist(a->verts[v], b->verts[v]) <= 1.75 * a->q);
    for (uint32_t f = 0; f < a->nfaces; f++)
        assert_int_equal(a->faces[f].method, b->faces[f].method);
    for (int k = 0; k < 3; k++) {
        assert_true(b->origin[k] <= a->origin[k] && a->origin[k] - b->origin[k] < b->q);
        assert_true(b->origin[k] == floor(b->origin[k] / b->q) * b->q);
    }
    assert_true(fabs(b->tess_tol - a->tess_tol) <= 0.5 * b->q);
    /* the needs but the file's bytes and what the tessellation makes (at a tolerance rounded to the
       grid, possibly a triangle apart) */
    for (int i = 0; i < CM_LIMIT_COUNT; i++)
        if (i != CM_LIMIT_MAX_FILE_BYTES && i != CM_LIMIT_MAX_TRIS && i != CM_LIMIT_MAX_TESS_POINTS &&
            i != CM_LIMIT_MAX_EDGE_SAMPLES)
            assert_int_equal(dec3.need[i], dec4.need[i]);
    assert_int_equal(dec4.need[CM_LIMIT_MAX_FILE_BYTES], r4.len);
    /* format 3's header: 248 bytes; format 4's well under 100 for these; 4 bytes a stream; repeated
       vertex coordinates */
    if (!(r4.len + 150 + 4 * CM_SEC_COUNT <= r3.len + 8))
        fail_msg("format 4: %zu bytes, format 3: %zu", r4.len, r3.len);
    encode_result_free(&r3);
    encode_result_free(&r4);
}

static void test_same_model_smaller_file(void **state)
{
    (void)state;
    igw w;
    loaded_model lm;
    igw_init(&w);
    igw_box_with_hole_144(&w, 40.0, 30.0, 20.0, 6.0);
    load(&w, "box", &lm);
    check_both_ways(&lm);
    model_free(&lm);
    igw_init(&w);
    igw_half_cylinder_120(&w, 10.0, 20.0);
    load(&w, "half-cylinder", &lm);
    check_both_ways(&lm);
    model_free(&lm);
    igw_init(&w);
    igw_bicubic_128(&w);
    load(&w, "bicubic", &lm);
    check_both_ways(&lm);
    model_free(&lm);
}

/* ---- hostile compact headers ---- */

static uint8_t *good;
static size_t good_len;
static uint32_t good_H;
static uint64_t fields[CM_FMT_MAX_HEADER];
static uint32_t nfields;

static int setup_good(void **state)
{
    (void)state;
    igw w;
    loaded_model lm;
    igw_init(&w);
    igw_box_with_hole_144(&w, 40.0, 30.0, 20.0, 6.0);
    load(&w, "box", &lm);
    encode_result r;
    encode_as_minor(&lm, 4, (int)CM_FMT_USE_ADJ_MINOR, &r); /* the varint header (4.6's: test_stream_header) */
    model_free(&lm);
    good = r.bytes;
    good_len = r.len;
    r.bytes = NULL;
    encode_result_free(&r);
    /* its fields (format 4.1): H, then flags, N, the needs, S, the lengths, e, the origin's step and
       multiples, the tolerances */
    uint32_t at = CM_FMT_COMPACT_AT_H;
    uint64_t v;
    assert_true(cm_fmt_get_varint(good, (uint32_t)good_len, &at, &v));
    good_H = (uint32_t)v;
    nfields = 0;
    while (at < good_H - 4)
        assert_true(cm_fmt_get_varint(good, good_H - 4, &at, &fields[nfields++]));
    assert_int_equal(at, good_H - 4);
    /* (a model without placed copies declares format 1.0's 25 needs: MAX_PLACEMENTS, the 26th, is 0) */
    assert_int_equal(nfields, 1 + 1 + CM_FMT_MIN_NEEDS + 1 + CM_SEC_COUNT + 1 + 1 + 3 + 2);
    return 0;
}

static int teardown_good(void **state)
{
    (void)state;
    free(good);
    return 0;
}

static size_t with_header_body(uint8_t *out, const uint64_t *f, uint32_t n, uint32_t H, uint32_t *field_at,
                               const uint8_t *body_in, size_t body_len);

/* the good file's body behind a header of the fields f (n of them, H computed unless `H` is not 0),
   every CRC valid; *field_at[i] the offset of field i.  Returns the length. */
static size_t with_header(uint8_t *out, const uint64_t *f, uint32_t n, uint32_t H, uint32_t *field_at)
{
    return with_header_body(out, f, n, H, field_at, good + good_H, good_len - good_H);
}

/* ... with body_in (the sections and 4 bytes for the trailer) after it */
static size_t with_header_body(uint8_t *out, const uint64_t *f, uint32_t n, uint32_t H, uint32_t *field_at,
                               const uint8_t *body_in, size_t body_len)
{
    uint8_t body[CM_FMT_MAX_HEADER * 2];
    uint32_t nb = 0, pos[CM_FMT_MAX_HEADER];
    for (uint32_t k = 0; k < n; k++) {
        pos[k] = nb;
        nb += cm_fmt_put_varint(body + nb, f[k]);
    }
    uint32_t lh = 1;
    if (H == 0)
        for (; lh <= 5; lh++)
            if (cm_fmt_put_varint(out, CM_FMT_COMPACT_AT_H + lh + nb + 4u) == lh) {
                H = CM_FMT_COMPACT_AT_H + lh + nb + 4u;
                break;
            }
    memcpy(out, good, CM_FMT_COMPACT_AT_H);
    lh = cm_fmt_put_varint(out + CM_FMT_COMPACT_AT_H, H);
    memcpy(out + CM_FMT_COMPACT_AT_H + lh, body, nb);
    for (uint32_t k = 0; k < n; k++)
        field_at[k] = CM_FMT_COMPACT_AT_H + lh + pos[k];
    uint32_t hl = CM_FMT_COMPACT_AT_H + lh + nb + 4u;
    cm_put_u32(out + hl - 4, cm_crc32(out, hl - 4));
    memcpy(out + hl, body_in, body_len);
    size_t total = hl + body_len;
    cm_put_u32(out + total - 4, cm_crc32(out, total - 4));
    return total;
}

/* the header alone (and then the file) fed: refused with `want` at byte `at`, naming `where` */
static void assert_refused(const uint8_t *b, size_t n, size_t hl, cm_err want, uint32_t at, const char *where)
{
    const char *why = cmz_header_refused(&dec4, b, n, hl, want, at, where);
    if (why)
        fail_msg("%s", why);
}

static void test_hostile_headers(void **state)
{
    (void)state;
    static uint8_t b[1 << 20];
    static uint64_t f[CM_FMT_MAX_HEADER];
    static uint32_t at[CM_FMT_MAX_HEADER];
    assert_true(good_len < sizeof b - 4096);
    const uint32_t N = CM_FMT_MIN_NEEDS, iS = 2 + N, iLen = 3 + N, iE = 3 + N + CM_SEC_COUNT, iShift = iE + 1, iO = iE + 2,
                   iTess = iO + 3, iRel = iTess + 1;
    /* the good header re-emitted: the same file, which decodes */
    size_t n = with_header(b, fields, nfields, 0, at);
    assert_int_equal(n, good_len);
    assert_memory_equal(b, good, good_len);
    cm_status st;
    cm_status_init(&st);
    cm_dec_init(&dec4);
    assert_ok(cm_dec_feed(&dec4, b, n, &st));
    assert_ok(cm_dec_finish(&dec4, &st));
#define FIELDS_WITH(i, v) (memcpy(f, fields, nfields * sizeof *f), f[(i)] = (v), f)
    size_t hl;
    /* a need over this build's limit, and a limit this build does not know that the model needs */
    n = with_header(b, FIELDS_WITH(2 + CM_LIMIT_MAX_FACES, CM_MAX_FACES + 1u), nfields, 0, at);
    hl = n - (good_len - good_H);
    assert_refused(b, n, hl, CM_E_LIMIT, at[2 + CM_LIMIT_MAX_FACES], "header needs");
    {
        /* the needs this build knows beyond the file's (0), then one it does not know (1) */
        const uint32_t extra = CM_LIMIT_COUNT + 1u - N;
        uint64_t g[CM_FMT_MAX_HEADER];
        memcpy(g, fields, 2 * sizeof *g);
        g[1] = N + extra;
        memcpy(g + 2, fields + 2, N * sizeof *g);
        for (uint32_t i = 0; i < extra; i++)
            g[2 + N + i] = i + 1 == extra; /* the unknown need */
        memcpy(g + 2 + N + extra, fields + 2 + N, (nfields - 2 - N) * sizeof *g);
        n = with_header(b, g, nfields + extra, 0, at);
        assert_refused(b, n, n - (good_len - good_H), CM_E_VERSION, at[2 + N + extra - 1], "unknown limit");
        g[2 + N + extra - 1] = 0; /* needed 0: read */
        n = with_header(b, g, nfields + extra, 0, at);
        cm_dec_init(&dec4);
        assert_ok(cm_dec_feed(&dec4, b, n, &st));
        assert_ok(cm_dec_finish(&dec4, &st));
    }
    /* counts */
    n = with_header(b, FIELDS_WITH(1, 24), nfields, 0, at);
    assert_refused(b, n, n - (good_len - good_H), CM_E_FORMAT, at[1], "need table shorter");
    n = with_header(b, FIELDS_WITH(1, 256), nfields, 0, at);
    assert_refused(b, n, n - (good_len - good_H), CM_E_FORMAT, at[1], "need count");
    n = with_header(b, FIELDS_WITH(iS, 6), nfields, 0, at);
    assert_refused(b, n, n - (good_len - good_H), CM_E_FORMAT, at[iS], "section count");
    /* a section past MAX_FILE_BYTES, named with the need and this build's limit */
    n = with_header(b, FIELDS_WITH(iLen + 1, (uint64_t)CM_MAX_FILE_BYTES), nfields, 0, at);
    assert_refused(b, n, n - (good_len - good_H), CM_E_LIMIT, at[iLen + 1], "file length");
    n = with_header(b, FIELDS_WITH(iLen, (uint64_t)UINT32_MAX + 1u), nfields, 0, at);
    assert_refused(b, n, n - (good_len - good_H), CM_E_FORMAT, at[iLen], "section length");
    /* grid and tolerances */
    n = with_header(b, FIELDS_WITH(iE, cm_fmt_zigzag(21)), nfields, 0, at);
    assert_refused(b, n, n - (good_len - good_H), CM_E_RANGE, at[iE], "quantisation exponent");
    n = with_header(b, FIELDS_WITH(iE, cm_fmt_zigzag(-61)), nfields, 0, at);
    assert_refused(b, n, n - (good_len - good_H), CM_E_RANGE, at[iE], "quantisation exponent");
    n = with_header(b, FIELDS_WITH(iTess, 0), nfields, 0, at);
    assert_refused(b, n, n - (good_len - good_H), CM_E_RANGE, at[iTess], "chordal tolerance");
    {
        /* 2^63 grid steps of 2^-60 mm at least: inside 2^100 mm only for small steps; at e = 20 out */
        memcpy(f, fields, nfields * sizeof *f);
        f[iE] = cm_fmt_zigzag(20);
        f[iO + 1] = cm_fmt_zigzag(INT64_MIN);
        n = with_header(b, f, nfields, 0, at);
        cm_dec_init(&dec4);
        cm_status_init(&st);
        cm_err e = cm_dec_feed(&dec4, b, n, &st);
        /* 2^63 * 2^20 = 2^83 mm: within 2^100, the header accepted (the body's points then fail) */
        assert_true(e == CM_OK || e == CM_E_RANGE);
    }
    /* fields that end before the CRC, or run past it */
    memcpy(f, fields, nfields * sizeof *f);
    f[nfields] = 0;
    n = with_header(b, f, nfields + 1, 0, at);
    assert_refused(b, n, n - (good_len - good_H), CM_E_FORMAT, at[nfields], "fields end before");
    n = with_header(b, fields, nfields - 1, 0, at); /* the rebuild tolerance missing: at the CRC */
    hl = n - (good_len - good_H);
    assert_refused(b, n, hl, CM_E_FORMAT, (uint32_t)hl - 4u, "rebuild tolerance");
    /* format 4.1: an origin step past 2^62 grid steps; a rebuild tolerance below zero; a minor
       this reader does not know */
    n = with_header(b, FIELDS_WITH(iShift, CM_FMT_MAX_ORIGIN_SHIFT + 1u), nfields, 0, at);
    assert_refused(b, n, n - (good_len - good_H), CM_E_FORMAT, at[iShift], "grid origin step");
    n = with_header(b, FIELDS_WITH(iRel, cm_fmt_zigzag(-(int64_t)CM_FMT_REL_TOL_DEFAULT - 1)), nfields, 0, at);
    assert_refused(b, n, n - (good_len - good_H), CM_E_RANGE, at[iRel], "rebuild tolerance");
    n = with_header(b, FIELDS_WITH(iRel, cm_fmt_zigzag(-(int64_t)CM_FMT_REL_TOL_DEFAULT)), nfields, 0, at);
    cm_dec_init(&dec4);
    cm_status_init(&st);
    assert_ok(cm_dec_feed(&dec4, b, n, &st)); /* a tolerance of 0: read */
    n = with_header(b, fields, nfields, 0, at);
    b[CM_HDR_MINOR] = CM_FMT_VERSION_MINOR + 1;
    assert_refused(b, n, n - (good_len - good_H), CM_E_VERSION, CM_HDR_MINOR, "minor newer");
    /* H itself: unterminated within five bytes, below any header, past the bound */
    memcpy(b, good, good_len);
    memset(b + CM_FMT_COMPACT_AT_H, 0x80, 6);
    assert_refused(b, good_len, good_len, CM_E_FORMAT, CM_FMT_COMPACT_AT_H, "header length");
    n = with_header(b, fields, nfields, 20, at);
    assert_refused(b, n, n, CM_E_FORMAT, CM_FMT_COMPACT_AT_H, "header length");
    n = with_header(b, fields, nfields, CM_FMT_MAX_HEADER + 1, at);
    assert_refused(b, n, n, CM_E_FORMAT, CM_FMT_COMPACT_AT_H, "header length");
    /* a header CRC that does not match: refused before any field is believed */
    n = with_header(b, fields, nfields, 0, at);
    b[at[2]] ^= 0x01;
    assert_refused(b, n, good_H, CM_E_CRC, good_H - 4, "header CRC");
#undef FIELDS_WITH
}

/*
 * Format 4's vertices: a coordinate sent as its place among the axis's recent values (cm_vcache).
 * The box's vertices (two values per axis) decode as format 3's (test_same_model_smaller_file); a
 * VERT section whose first coordinate names a place in the still empty list is refused by name,
 * as is one past the values it holds.
 */
static void test_vertex_repeats(void **state)
{
    (void)state;
    static uint8_t b[1 << 20], body[1 << 20], sec[4096];
    static uint32_t at[CM_FMT_MAX_HEADER];
    static uint64_t f[CM_FMT_MAX_HEADER];
    const uint32_t iLen = 3 + CM_FMT_MIN_NEEDS;
    for (int past = 0; past < 2; past++) {
        cm_ac_enc e;
        cm_ac_enc_init(&e, sec, sizeof sec);
        cm_vert_ctx c;
        cm_vert_ctx_init(&c);
        cm_ac_enc_uint(&e, &c.count, 8);
        cm_ac_enc_uint(&e, &c.step, 0);
        if (past) { /* one vertex by differences, then the second's x at place 1 of a list of 1 */
            for (int k = 0; k < 3; k++) {
                cm_ac_enc_bit(&e, &c.repeat[k], 0);
                cm_ac_enc_sint(&e, &c.coord[k], 100 + k);
            }
        }
        cm_ac_enc_bit(&e, &c.repeat[0], 1);
        cm_ac_enc_uint(&e, &c.slot[0], (uint64_t)past);
        size_t n = cm_ac_enc_finish_trimmed(&e);
        memcpy(f, fields, nfields * sizeof *f);
        size_t old = fields[iLen];
        f[iLen] = n;
        memcpy(body, sec, n);
        memcpy(body + n, good + good_H + old, good_len - good_H - old);
        size_t len = with_header_body(b, f, nfields, 0, at, body, n + good_len - good_H - old);
        cm_status st;
        cm_status_init(&st);
        cm_dec_init(&dec4);
        assert_ok(cm_dec_feed(&dec4, b, len, &st));
        assert_err(cm_dec_finish(&dec4, &st), CM_E_RANGE);
        assert_non_null(st.where);
        if (!strstr(st.where, "vertex repeat"))
            fail_msg("says \"%s\"", st.where);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_varints),
        cmocka_unit_test(test_trimmed_streams),
        cmocka_unit_test(test_same_model_smaller_file),
        cmocka_unit_test_setup_teardown(test_hostile_headers, setup_good, teardown_good),
        cmocka_unit_test_setup_teardown(test_vertex_repeats, setup_good, teardown_good),
    };
    return cmocka_run_group_tests_name("format4", tests, NULL, NULL);
}
