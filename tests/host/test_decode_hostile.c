/*
 * test_decode_hostile.c - the decoder against hostile files whose CRCs are
 * all valid (issue 10): what a corrupted transfer cannot produce but a
 * broken or malicious writer can.  Each file is a small valid model in all
 * but the field under test, laid out by assemble() below with every length,
 * offset and CRC right, so the decoder reaches the check under test and not
 * a CRC refusal.
 *
 * The class under test: a count or length read from the file used before it
 * is checked (the header's section count once filled a 5-entry table with
 * up to 255 entries, and cm_dec_finish then computed a CRC over an offset
 * and length it had never checked).  Every header field is tried with
 * values around its bounds, the whole header byte by byte; each file must
 * give CM_OK or a clear error: the code, a reason and the byte offset of the
 * field, never a crash.  Then the places after the header: errors about a
 * face name the face and its record's byte offset (the FACE section, the
 * tessellation), a face that cannot be tessellated is left out of the mesh
 * (cm_decode_mesh) and the work on a face is bounded by the needs its
 * header declares.
 *
 * Seen to fail before the fix: with the old check_header the six-section
 * and 200-section files (vertex 0 of the model at grid x = -1: the sixth
 * table entry overlapped it, giving the offset 0xffffffff) crashed in
 * cm_dec_finish's CRC of that "section" (SIGSEGV), and the per-count sweep
 * too; see the report of issue 10.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <stdio.h>
#include <stdlib.h>

#include "cm/cm_arith.h"
#include "cm/cm_crc32.h"
#include "cm/cm_decode.h"
#include "cm/cm_limits_info.h"
#include "cm/cm_sections.h"
#include "cm/cm_tessellate.h"
#include "cm_report.h"

/*
 * cm_decode_mesh (platform/cm_decode_file.c, the decode path of cmz-decode, `cmz decode` and
 * cmz-terminal) is not in the archive the host tests link: its source is compiled in here.
 */
#include "cm_decode_file.c"

/* the host profile's decoder is large (static arrays sized by the host limits): allocated once,
   lazily mapped */
static cm_decoder *dec;
static cm_tess_ws tess;

#define MESH_VERTS 65536
static float mesh_pos[MESH_VERTS][3], mesh_nrm[MESH_VERTS][3];
static uint32_t mesh_idx[3 * MESH_VERTS];
static cm_mesh_face mesh_faces[64];

/* ---- a model of planar polygons, each its own face with its own line edges ---- */

#define MAX_POLY 8
#define MAX_CORNERS 512

typedef struct poly {
    int method;             /* CM_METHOD_PLANE, or KEEP (to refer to a kept surface the file lacks) */
    int n;                  /* corners */
    int64_t v[MAX_CORNERS][3]; /* on the grid (integers) */
    unsigned color;         /* palette index (0: none) */
} poly;

typedef struct tmodel {
    int npoly;
    poly p[MAX_POLY];
    int npalette;
} tmodel;

static tmodel M;

/* a square of side `side` grid steps, its first corner at (x, y, 0): counter-clockwise */
static void add_square(tmodel *m, int64_t x, int64_t y, int64_t side)
{
    poly *p = &m->p[m->npoly++];
    memset(p, 0, sizeof *p);
    p->method = CM_METHOD_PLANE;
    p->n = 4;
    int64_t c[4][2] = {{x, y}, {x + side, y}, {x + side, y + side}, {x, y + side}};
    for (int k = 0; k < 4; k++) {
        p->v[k][0] = c[k][0];
        p->v[k][1] = c[k][1];
    }
}

/* three collinear corners: a loop that closes, decodes, and has no area (its frame cannot be built) */
static void add_sliver(tmodel *m, int64_t x, int64_t y)
{
    poly *p = &m->p[m->npoly++];
    memset(p, 0, sizeof *p);
    p->method = CM_METHOD_PLANE;
    p->n = 3;
    for (int k = 0; k < 3; k++) {
        p->v[k][0] = x + 100 * k;
        p->v[k][1] = y;
    }
}

/* a regular polygon of n corners (radius r grid steps) around (x, y) */
static void add_ngon(tmodel *m, int n, int64_t x, int64_t y, double r)
{
    poly *p = &m->p[m->npoly++];
    memset(p, 0, sizeof *p);
    p->method = CM_METHOD_PLANE;
    p->n = n;
    for (int k = 0; k < n; k++) {
        p->v[k][0] = x + llround(r * cos(2 * M_PI * k / n));
        p->v[k][1] = y + llround(r * sin(2 * M_PI * k / n));
    }
}

/*
 * The reference model: three squares of 1 mm (grid 2^-10 mm) in a row.  Vertex 0 is at grid
 * (-1, 1000, 0): as decoded vertex 0 (int64 x, y) it is what an out-of-bounds sixth entry of the
 * section table would read as tag 0xff, offset 0xffffffff, length 1000.
 */
static void three_squares(tmodel *m)
{
    memset(m, 0, sizeof *m);
    add_square(m, -1, 1000, 1024);
    add_square(m, 2047, 1000, 1024);
    add_square(m, 4095, 1000, 1024);
}

/* ---- the sections, coded as the encoder codes them (cm_sections.h contexts, cm_arith.h coder) ---- */

#define SECTION_CAP 65536

typedef struct section {
    uint8_t tag, reserved[3];
    uint8_t bytes[SECTION_CAP];
    uint32_t len;
} section;

static void finish(cm_ac_enc *e, section *s)
{
    size_t n = cm_ac_enc_finish(e);
    assert_true(n > 0); /* 0: SECTION_CAP too small */
    s->len = (uint32_t)n;
}

static void put_vert(const tmodel *m, section *s)
{
    cm_ac_enc e;
    cm_ac_enc_init(&e, s->bytes, SECTION_CAP);
    cm_vert_ctx c;
    cm_vert_ctx_init(&c);
    uint32_t nv = 0;
    for (int i = 0; i < m->npoly; i++)
        nv += (uint32_t)m->p[i].n;
    cm_ac_enc_uint(&e, &c.count, nv);
    int64_t prev[3] = {0, 0, 0};
    for (int i = 0; i < m->npoly; i++)
        for (int k = 0; k < m->p[i].n; k++)
            for (int a = 0; a < 3; a++) {
                cm_ac_enc_sint(&e, &c.coord[a], m->p[i].v[k][a] - prev[a]);
                prev[a] = m->p[i].v[k][a];
            }
    finish(&e, s);
}

/* each polygon side k a line edge from corner k to corner k+1; the corners are the vertices in order:
   side 0 takes two new ones, the sides between one, the last closes on corner 0 (n - 1 back) */
static void put_ref(cm_ac_enc *e, cm_edge_ctx *c, int is_new, uint64_t back)
{
    cm_ac_enc_bit(e, &c->is_new, (unsigned)is_new);
    if (!is_new)
        cm_ac_enc_uint(e, &c->back, back);
}

static void put_edge(const tmodel *m, section *s)
{
    cm_ac_enc e;
    cm_ac_enc_init(&e, s->bytes, SECTION_CAP);
    cm_edge_ctx c;
    cm_edge_ctx_init(&c);
    uint32_t ne = 0;
    for (int i = 0; i < m->npoly; i++)
        ne += (uint32_t)m->p[i].n;
    cm_ac_enc_uint(&e, &c.count, ne);
    for (int i = 0; i < m->npoly; i++) {
        int n = m->p[i].n;
        for (int k = 0; k < n; k++) {
            put_ref(&e, &c, k == 0, 0);                        /* v0: corner k */
            put_ref(&e, &c, k < n - 1, (uint64_t)(n - 1));     /* v1: corner k+1, or corner 0 */
            cm_ac_enc_bit(&e, &c.g1, 0);
            cm_ac_enc_bit(&e, &c.kind, CM_EDGE_LINE);
        }
    }
    finish(&e, s);
}

static void put_surf(const tmodel *m, section *s)
{
    (void)m;
    cm_ac_enc e;
    cm_ac_enc_init(&e, s->bytes, SECTION_CAP);
    cm_surf_ctx c;
    cm_surf_ctx_init(&c);
    cm_ac_enc_uint(&e, &c.count, 0);
    finish(&e, s);
}

static void put_face(const tmodel *m, section *s)
{
    cm_ac_enc e;
    cm_ac_enc_init(&e, s->bytes, SECTION_CAP);
    cm_face_ctx c;
    cm_face_ctx_init(&c);
    cm_ac_enc_uint(&e, &c.count, (uint64_t)m->npoly);
    for (int i = 0; i < m->npoly; i++) {
        cm_ac_enc_uint(&e, &c.method, (uint64_t)m->p[i].method);
        cm_ac_enc_bit(&e, &c.flip, 0);
        cm_ac_enc_uint(&e, &c.loops, 1);
        cm_ac_enc_uint(&e, &c.uses, (uint64_t)m->p[i].n);
        for (int k = 0; k < m->p[i].n; k++) {
            cm_ac_enc_bit(&e, &c.is_new, 1);
            cm_ac_enc_bit(&e, &c.rev_new, 0);
        }
    }
    finish(&e, s);
}

static void put_colr(const tmodel *m, section *s)
{
    cm_ac_enc e;
    cm_ac_enc_init(&e, s->bytes, SECTION_CAP);
    cm_colr_ctx c;
    cm_colr_ctx_init(&c);
    cm_ac_enc_uint(&e, &c.count, (uint64_t)m->npalette);
    for (int i = 1; i <= m->npalette; i++)
        cm_ac_enc_direct(&e, 0x808080u + (uint32_t)i, 24);
    for (int i = 0; i < m->npoly && m->npalette; i++)
        cm_ac_enc_uint(&e, &c.index, m->p[i].color);
    finish(&e, s);
}

/* ---- the file: any number of needs and sections, every length, offset and CRC right ---- */

#define MAX_SECTIONS 255

typedef struct spec {
    cm_fmt_header hdr; /* version, flags, grid, origin, tolerances (lengths and counts are filled in by
                          assemble) */
    uint32_t nneeds, need[255];
    uint32_t nsec;
    section *sec[MAX_SECTIONS];
} spec;

static section model_sec[CM_SEC_COUNT], extra_sec; /* extra_sec: an extra section's bytes */

/* the spec of model m as the encoder would write it: format 1.0, needs measured here, 5 sections */
static void spec_of(const tmodel *m, spec *sp)
{
    memset(sp, 0, sizeof *sp);
    cm_fmt_header *h = &sp->hdr;
    h->major = 1;
    h->minor = 0;
    h->flags = (uint16_t)(m->npalette ? 1 : 0);
    h->q_exp = -10; /* grid 2^-10 mm */
    for (int k = 0; k < 3; k++)
        h->origin[k] = 0.0;
    h->tess_tol = 0.01;
    h->rel_tol = 0.01;
    sp->nneeds = CM_LIMIT_COUNT;
    /* the tessellation's needs as large as this build allows (the tests that bound the work by them
       set them); the encoder measures them */
    sp->need[CM_LIMIT_MAX_TESS_POINTS] = CM_MAX_TESS_POINTS;
    sp->need[CM_LIMIT_MAX_EDGE_SAMPLES] = CM_MAX_EDGE_SAMPLES;
    sp->need[CM_LIMIT_MAX_TRIS] = CM_MAX_TRIS;
    void (*writers[CM_SEC_COUNT])(const tmodel *, section *) = {put_vert, put_edge, put_surf, put_face, put_colr};
    sp->nsec = CM_SEC_COUNT;
    for (int s = 0; s < CM_SEC_COUNT; s++) {
        memset(model_sec[s].reserved, 0, 3);
        model_sec[s].tag = (uint8_t)(s + 1);
        writers[s](m, &model_sec[s]);
        sp->sec[s] = &model_sec[s];
    }
}

/* lay sp out; returns the malloc'd file, *len its length */
static uint8_t *assemble(const spec *sp, size_t *len)
{
    size_t H = cm_fmt_header_len(sp->nneeds, sp->nsec), total = H + 4u;
    for (uint32_t s = 0; s < sp->nsec; s++)
        total += sp->sec[s]->len;
    uint8_t *b = calloc(1, total);
    assert_non_null(b);
    cm_fmt_header h = sp->hdr;
    h.header_len = (uint32_t)H;
    h.file_len = (uint32_t)total;
    h.nlimits = (uint8_t)sp->nneeds;
    h.nsections = (uint8_t)sp->nsec;
    cm_fmt_header_pack(b, &h);
    for (uint32_t i = 0; i < sp->nneeds; i++)
        cm_put_u32(b + cm_fmt_need_at(i), sp->need[i]);
    size_t off = H;
    for (uint32_t s = 0; s < sp->nsec; s++) {
        const section *S = sp->sec[s];
        uint8_t *e = b + cm_fmt_entry_at(sp->nneeds, s);
        e[CM_ENT_TAG] = S->tag;
        memcpy(e + CM_ENT_RESERVED, S->reserved, 3);
        cm_put_u32(e + CM_ENT_OFFSET, (uint32_t)off);
        cm_put_u32(e + CM_ENT_LENGTH, S->len);
        cm_put_u32(e + CM_ENT_CRC, cm_crc32(S->bytes, S->len));
        memcpy(b + off, S->bytes, S->len);
        off += S->len;
    }
    cm_put_u32(b + H - 4, cm_crc32(b, H - 4));
    cm_put_u32(b + total - 4, cm_crc32(b, total - 4));
    *len = total;
    return b;
}

/* after a field was changed in place: every CRC the file still has room for made right again */
static void fix_crcs(uint8_t *b, size_t n)
{
    uint32_t H = cm_get_u32(b + CM_HDR_LENGTH), L = cm_get_u32(b + CM_HDR_FILE_LENGTH), nl = b[CM_HDR_NLIMITS];
    for (uint32_t s = 0; s < b[CM_HDR_NSECTIONS] && cm_fmt_entry_at(nl, s + 1) <= n; s++) {
        uint8_t *e = b + cm_fmt_entry_at(nl, s);
        uint32_t off = cm_get_u32(e + CM_ENT_OFFSET), len = cm_get_u32(e + CM_ENT_LENGTH);
        if (off <= n && len <= n - off)
            cm_put_u32(e + CM_ENT_CRC, cm_crc32(b + off, len));
    }
    if (H >= CM_FMT_FIXED_HEADER + 4 && H <= n) /* (a shorter H has no room for its CRC) */
        cm_put_u32(b + H - 4, cm_crc32(b, H - 4));
    if (L >= H + 4 && L <= n) /* (a shorter L would put it into the header) */
        cm_put_u32(b + L - 4, cm_crc32(b, L - 4));
}

/* ---- decoding and what an error must say ---- */

/* feed b in chunks of `chunk` bytes (0: all at once), then finish */
static cm_err decode_chunked(const uint8_t *b, size_t n, size_t chunk, cm_status *st)
{
    cm_status_init(st);
    cm_dec_init(dec);
    cm_err e = CM_OK;
    if (chunk == 0)
        chunk = n ? n : 1;
    for (size_t off = 0; off < n && e == CM_OK; off += chunk)
        e = cm_dec_feed(dec, b + off, n - off < chunk ? n - off : chunk, st);
    if (e == CM_OK)
        e = cm_dec_finish(dec, st);
    return e;
}

static cm_err decode(const uint8_t *b, size_t n, cm_status *st)
{
    return decode_chunked(b, n, 0, st);
}

/* the file sp describes, decoded into dec: it must be accepted */
static void decode_spec(const spec *sp)
{
    size_t n;
    uint8_t *b = assemble(sp, &n);
    cm_status st;
    assert_ok(decode(b, n, &st));
    free(b);
}

/* the status as the programs print it must contain `cause` */
static void assert_says(const cm_status *st, const char *cause)
{
    char text[512];
    cm_format_status(text, sizeof text, st);
    if (!strstr(text, cause))
        fail_msg("status \"%s\" does not say \"%s\"", text, cause);
}

/* decoding b must fail with `code` at byte `offset`, saying `cause`; whole and byte by byte alike,
   and the decoder refuses further work afterwards (no use of a half-checked header) */
static void assert_refused(const uint8_t *b, size_t n, cm_err code, uint32_t offset, const char *cause)
{
    cm_status st;
    for (int pass = 0; pass < 2; pass++) {
        cm_err e = decode_chunked(b, n, pass ? 1 : 0, &st);
        if (e != code || st.code != code || st.offset != offset || st.where == NULL) {
            char text[512];
            fail_msg("%s: expected %s at byte %u, got %s (%s)", pass ? "byte by byte" : "whole", cm_err_name(code),
                     offset, cm_err_name(e), cm_format_status(text, sizeof text, &st));
        }
        assert_says(&st, cause);
        assert_false(dec->state == CM_DEC_DONE);
        cm_status again;
        cm_status_init(&again);
        assert_err(cm_dec_finish(dec, &again), CM_E_ARG);
    }
}

static void assert_decodes(const uint8_t *b, size_t n)
{
    cm_status st;
    if (decode(b, n, &st) != CM_OK) {
        char text[512];
        fail_msg("refused: %s", cm_format_status(text, sizeof text, &st));
    }
}

/* the reference file: three squares, needs as the encoder would declare them (measured here) */
static uint8_t *reference_file(spec *sp, size_t *n)
{
    three_squares(&M);
    spec_of(&M, sp);
    return assemble(sp, n);
}

/* ---- the section table ---- */

/* issue 10's file: a sixth section (41 zero bytes, tag 6), every CRC valid (465 bytes there, on the split
   cylinder; 385 here).  It used to fill d->sec[5], past the 5-entry table, over the vertex predictors,
   and cm_dec_finish then took a CRC over that "section": offset 0xffffffff here, a crash */
static void test_six_sections_valid_crcs(void **state)
{
    (void)state;
    spec sp;
    size_t n;
    free(reference_file(&sp, &n));
    memset(&extra_sec, 0, sizeof extra_sec);
    extra_sec.tag = 6;
    extra_sec.len = 41;
    sp.sec[sp.nsec++] = &extra_sec;
    uint8_t *b = assemble(&sp, &n);
    assert_refused(b, n, CM_E_FORMAT, CM_HDR_NSECTIONS, "section count");
    free(b);
}

static void test_200_sections(void **state)
{
    (void)state;
    spec sp;
    size_t n;
    free(reference_file(&sp, &n));
    static section empty[195];
    for (int s = 0; s < 195; s++) {
        memset(&empty[s], 0, sizeof empty[s]);
        empty[s].tag = (uint8_t)(6 + s);
        sp.sec[sp.nsec++] = &empty[s];
    }
    assert_int_equal(sp.nsec, 200);
    uint8_t *b = assemble(&sp, &n);
    assert_refused(b, n, CM_E_FORMAT, CM_HDR_NSECTIONS, "section count");
    free(b);
}

/* every section count but 5, the header's length consistent with it: refused at CM_HDR_NSECTIONS (byte 17), before the
   table is read (a count below 5 was once accepted until cm_dec_finish had decoded its sections) */
static void test_every_other_section_count(void **state)
{
    (void)state;
    static section empty[MAX_SECTIONS];
    for (uint32_t count = 0; count <= 255; count++) {
        if (count == CM_SEC_COUNT)
            continue;
        spec sp;
        size_t n;
        free(reference_file(&sp, &n));
        sp.nsec = count < CM_SEC_COUNT ? count : CM_SEC_COUNT;
        for (uint32_t s = sp.nsec; s < count; s++) {
            memset(&empty[s], 0, sizeof empty[s]);
            empty[s].tag = (uint8_t)(s + 1);
            sp.sec[sp.nsec++] = &empty[s];
        }
        uint8_t *b = assemble(&sp, &n);
        cm_status st;
        assert_err(decode(b, n, &st), CM_E_FORMAT);
        if (cm_get_u32(b + CM_HDR_LENGTH) > CM_FMT_MAX_HEADER) { /* a table that long is a header too long */
            assert_int_equal(st.offset, CM_HDR_LENGTH);
            assert_says(&st, "header length");
        } else {
            assert_int_equal(st.offset, CM_HDR_NSECTIONS);
            assert_says(&st, "section count");
        }
        free(b);
    }
}

/* entries of the table: each field checked before an offset or a length addresses a byte */
static void test_section_table_entries(void **state)
{
    (void)state;
    spec sp;
    size_t n;
    uint8_t *ref = reference_file(&sp, &n);
    assert_decodes(ref, n);
    struct {
        uint32_t entry, at, value, width;
        uint32_t want_at;
        cm_err want;
        const char *cause;
    } cases[] = {
        {2, CM_ENT_TAG, 4, 1, CM_ENT_TAG, CM_E_FORMAT, "tags must be 1..5"}, /* SURF tagged FACE */
        {4, CM_ENT_TAG, 6, 1, CM_ENT_TAG, CM_E_FORMAT, "tags must be 1..5"},
        {0, CM_ENT_TAG, 0, 1, CM_ENT_TAG, CM_E_FORMAT, "tags must be 1..5"},
        /* the second reserved byte set: refused at the first one */
        {1, CM_ENT_RESERVED + 1, 1, 1, CM_ENT_RESERVED, CM_E_FORMAT, "reserved bytes"},
        {3, CM_ENT_OFFSET, 0xffffffffu, 4, CM_ENT_OFFSET, CM_E_FORMAT, "section offset"}, /* far beyond the file */
        {3, CM_ENT_OFFSET, 0, 4, CM_ENT_OFFSET, CM_E_FORMAT, "section offset"},           /* inside the header */
        {0, CM_ENT_LENGTH, 0xffffffffu, 4, CM_ENT_LENGTH, CM_E_FORMAT, "section length"}, /* offset + length wraps */
        {4, CM_ENT_LENGTH, 0x7fffffffu, 4, CM_ENT_LENGTH, CM_E_FORMAT, "section length"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        uint8_t *b = malloc(n);
        memcpy(b, ref, n);
        uint8_t *e = b + cm_fmt_entry_at(CM_LIMIT_COUNT, cases[i].entry);
        if (cases[i].width == 1)
            e[cases[i].at] = (uint8_t)cases[i].value;
        else
            cm_put_u32(e + cases[i].at, cases[i].value);
        fix_crcs(b, n);
        assert_refused(b, n, cases[i].want, cm_fmt_entry_at(CM_LIMIT_COUNT, cases[i].entry) + cases[i].want_at,
                       cases[i].cause);
        free(b);
    }
    /* a section one byte shorter leaves a byte between it and the next */
    uint8_t *b = malloc(n);
    memcpy(b, ref, n);
    uint8_t *e = b + cm_fmt_entry_at(CM_LIMIT_COUNT, 0);
    cm_put_u32(e + CM_ENT_LENGTH, cm_get_u32(e + CM_ENT_LENGTH) - 1);
    fix_crcs(b, n);
    assert_refused(b, n, CM_E_FORMAT, cm_fmt_entry_at(CM_LIMIT_COUNT, 1) + CM_ENT_OFFSET, "section offset");
    /* the last one shorter: the sections do not reach the trailer */
    memcpy(b, ref, n);
    e = b + cm_fmt_entry_at(CM_LIMIT_COUNT, CM_SEC_COUNT - 1);
    cm_put_u32(e + CM_ENT_LENGTH, cm_get_u32(e + CM_ENT_LENGTH) - 1);
    fix_crcs(b, n);
    assert_refused(b, n, CM_E_FORMAT, CM_HDR_FILE_LENGTH, "do not fill the file");
    free(b);
    free(ref);
}

/* ---- the other header fields ---- */

/* the reference file with a need table of `count` entries (the spec in *sp, the length in *n) */
static uint8_t *with_need_count(uint32_t count, spec *sp, size_t *n)
{
    free(reference_file(sp, n));
    sp->nneeds = count;
    return assemble(sp, n);
}

/* the need table may be longer than this build's list (a newer writer's extra needs 0), never
   shorter than format 1.0's 25 */
static void test_need_counts(void **state)
{
    (void)state;
    spec sp;
    size_t n;
    /* a table shorter than format 1.0's 25 needs leaves the tessellation unbounded by the file:
       refused at the count, before any need is used */
    static const uint32_t short_counts[] = {0, 1, 15, CM_FMT_MIN_NEEDS - 1};
    for (size_t i = 0; i < sizeof short_counts / sizeof short_counts[0]; i++) {
        uint8_t *b = with_need_count(short_counts[i], &sp, &n);
        assert_refused(b, n, CM_E_FORMAT, CM_HDR_NLIMITS, "need table shorter");
        free(b);
    }
    static const uint32_t counts[] = {CM_FMT_MIN_NEEDS, CM_LIMIT_COUNT, CM_LIMIT_COUNT + 1, 100, 255};
    for (size_t i = 0; i < sizeof counts / sizeof counts[0]; i++) {
        uint8_t *b = with_need_count(counts[i], &sp, &n);
        assert_decodes(b, n);
        free(b);
        if (counts[i] <= CM_LIMIT_COUNT)
            continue;
        /* the last entry, one this build does not know, needed */
        sp.need[counts[i] - 1] = 1;
        b = assemble(&sp, &n);
        assert_refused(b, n, CM_E_VERSION, cm_fmt_need_at(counts[i] - 1), "unknown limit");
        free(b);
    }
    /* a need over this build's limit: named, at its entry */
    free(reference_file(&sp, &n));
    sp.need[CM_LIMIT_MAX_FACES] = CM_MAX_FACES + 1u;
    uint8_t *b = assemble(&sp, &n);
    assert_refused(b, n, CM_E_LIMIT, cm_fmt_need_at(CM_LIMIT_MAX_FACES), "MAX_FACES");
    free(b);
}

static void test_header_and_file_lengths(void **state)
{
    (void)state;
    spec sp;
    size_t n;
    uint8_t *ref = reference_file(&sp, &n);
    uint8_t *b = malloc(n + 64);
    const uint32_t H = cm_get_u32(ref + CM_HDR_LENGTH);
    /* H that does not fit the counts (an entry less or more), too small, too large: refused at its field */
    static const uint32_t hs[] = {0, 4, CM_FMT_FIXED_HEADER + 3, 0, 0, CM_FMT_MAX_HEADER + 1, 0xffffffffu};
    for (size_t i = 0; i < sizeof hs / sizeof hs[0]; i++) {
        memcpy(b, ref, n);
        uint32_t h = hs[i] ? hs[i] : (i == 3 ? H - CM_FMT_SECTION_ENTRY : H + CM_FMT_SECTION_ENTRY);
        cm_put_u32(b + CM_HDR_LENGTH, h);
        fix_crcs(b, n);
        assert_refused(b, n, CM_E_FORMAT, CM_HDR_LENGTH, "header length");
    }
    /* L shorter than header and trailer */
    memcpy(b, ref, n);
    cm_put_u32(b + CM_HDR_FILE_LENGTH, H + 3);
    fix_crcs(b, n);
    assert_refused(b, n, CM_E_FORMAT, CM_HDR_FILE_LENGTH, "file length");
    /* L over this build's file size */
    memcpy(b, ref, n);
    cm_put_u32(b + CM_HDR_FILE_LENGTH, (uint32_t)CM_MAX_FILE_BYTES + 1u);
    fix_crcs(b, n);
    assert_refused(b, n, CM_E_LIMIT, CM_HDR_FILE_LENGTH, "MAX_FILE_BYTES");
    /* L and the table agree, but the bytes end early, or go on */
    memcpy(b, ref, n);
    cm_status st;
    assert_err(decode(b, n - 1, &st), CM_E_TRUNCATED);
    assert_int_equal(st.offset, n - 1);
    memcpy(b, ref, n);
    b[n] = 0;
    assert_err(decode(b, n + 1, &st), CM_E_RANGE);
    assert_int_equal(st.offset, n);
    free(b);
    free(ref);
}

/* the grid exponent, the origin and the tolerances: each refused at its own offset */
static void test_grid_and_tolerances(void **state)
{
    (void)state;
    spec sp;
    size_t n;
    uint8_t *ref = reference_file(&sp, &n);
    uint8_t *b = malloc(n);
    static const int8_t qes[] = {-128, -61, 21, 127};
    for (size_t i = 0; i < sizeof qes / sizeof qes[0]; i++) {
        memcpy(b, ref, n);
        b[CM_HDR_QEXP] = (uint8_t)qes[i];
        fix_crcs(b, n);
        assert_refused(b, n, CM_E_RANGE, CM_HDR_QEXP, "quantisation exponent");
    }
    for (int8_t qe = -60; qe <= 20; qe += 80) { /* the bounds themselves load */
        memcpy(b, ref, n);
        b[CM_HDR_QEXP] = (uint8_t)qe;
        fix_crcs(b, n);
        assert_decodes(b, n);
    }
    struct {
        uint32_t at;
        double v;
        cm_err want;
        const char *cause;
    } cases[] = {
        {CM_HDR_ORIGIN + 0, (double)NAN, CM_E_NONFINITE, "grid origin"}, /* x, y, z: 8 bytes each */
        {CM_HDR_ORIGIN + 8, (double)INFINITY, CM_E_NONFINITE, "grid origin"},
        {CM_HDR_ORIGIN + 16, -(double)INFINITY, CM_E_NONFINITE, "grid origin"},
        {CM_HDR_ORIGIN + 0, 1e300, CM_E_RANGE, "grid origin"},
        {CM_HDR_ORIGIN + 16, -0x1p101, CM_E_RANGE, "grid origin"},
        {CM_HDR_TESS_TOL, 0.0, CM_E_RANGE, "chordal tolerance"},
        {CM_HDR_TESS_TOL, -1.0, CM_E_RANGE, "chordal tolerance"},
        {CM_HDR_TESS_TOL, (double)NAN, CM_E_NONFINITE, "chordal tolerance"},
        {CM_HDR_TESS_TOL, (double)INFINITY, CM_E_NONFINITE, "chordal tolerance"},
        {CM_HDR_REL_TOL, -1e-9, CM_E_RANGE, "rebuild tolerance"},
        {CM_HDR_REL_TOL, (double)NAN, CM_E_NONFINITE, "rebuild tolerance"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        memcpy(b, ref, n);
        cm_put_f64(b + cases[i].at, cases[i].v);
        fix_crcs(b, n);
        assert_refused(b, n, cases[i].want, cases[i].at, cases[i].cause);
    }
    free(b);
    free(ref);
}

/* the class: every byte of the header set to values around the bounds of whatever field it is in,
   CRCs valid: CM_OK or a clear error at a byte of the file, never a crash */
static void test_every_header_byte_hostile(void **state)
{
    (void)state;
    spec sp;
    size_t n;
    uint8_t *ref = reference_file(&sp, &n);
    uint8_t *b = malloc(n);
    const uint32_t H = cm_get_u32(ref + CM_HDR_LENGTH);
    static const uint8_t values[] = {0x00, 0x01, 0x04, 0x05, 0x06, 0x7f, 0x80, 0xc4, 0xfe, 0xff};
    int refused = 0;
    for (uint32_t at = 0; at < H - 4; at++)
        for (size_t v = 0; v < sizeof values; v++) {
            memcpy(b, ref, n);
            b[at] = values[v];
            fix_crcs(b, n);
            cm_status st;
            cm_err e = decode(b, n, &st);
            if (e == CM_OK)
                continue;
            refused++;
            if (st.code != e || st.where == NULL || st.offset == CM_NO_OFFSET || st.offset > n) {
                char text[512];
                fail_msg("byte %u = 0x%02x: %s without a place: %s", at, values[v], cm_err_name(e),
                         cm_format_status(text, sizeof text, &st));
            }
        }
    assert_true(refused > 0);
    free(b);
    free(ref);
}

/* ---- after the header: the face, and its byte offset ---- */

/* an error in a face's record names the face: a KEEP face whose kept surface the file lacks */
static void test_face_record_error_names_face(void **state)
{
    (void)state;
    three_squares(&M);
    M.p[2].method = CM_METHOD_KEEP;
    spec sp;
    spec_of(&M, &sp);
    size_t n;
    uint8_t *b = assemble(&sp, &n);
    cm_status st;
    assert_err(decode(b, n, &st), CM_E_RANGE);
    assert_int_equal(st.face, 2);
    const cm_dec_section *face = &dec->sec[CM_SEC_FACE - 1];
    assert_true(st.offset >= face->off && st.offset <= face->off + face->len);
    assert_says(&st, "kept surface");
    free(b);
    /* a face's colour beyond the palette: face 1, in COLR */
    three_squares(&M);
    M.npalette = 2;
    M.p[1].color = 3;
    spec_of(&M, &sp);
    b = assemble(&sp, &n);
    assert_err(decode(b, n, &st), CM_E_RANGE);
    assert_int_equal(st.face, 1);
    assert_says(&st, "face colour");
    free(b);
    /* errors that are about no face say so */
    three_squares(&M);
    spec_of(&M, &sp);
    b = assemble(&sp, &n);
    cm_put_u32(b + cm_fmt_header_len(CM_LIMIT_COUNT, CM_SEC_COUNT) - 4u, 0); /* header CRC */
    assert_err(decode(b, n, &st), CM_E_CRC);
    assert_int_equal(st.face, CM_NO_FACE_INDEX);
    free(b);
}

/* the model with a sliver between two squares: it decodes; the sliver cannot be tessellated */
static uint8_t *sliver_file(size_t *n)
{
    memset(&M, 0, sizeof M);
    add_square(&M, -1, 1000, 1024);
    add_sliver(&M, 3000, 1000);
    add_square(&M, 4095, 1000, 1024);
    spec sp;
    spec_of(&M, &sp);
    return assemble(&sp, n);
}

/* a tessellation error carries the face and, as its place, the face's record in FACE */
static void test_tessellation_error_names_face_and_offset(void **state)
{
    (void)state;
    size_t n;
    uint8_t *b = sliver_file(&n);
    cm_status st;
    assert_ok(decode(b, n, &st));
    free(b);
    const cm_model *m = &dec->model;
    const cm_dec_section *face = &dec->sec[CM_SEC_FACE - 1];
    for (uint32_t f = 0; f < 3; f++)
        assert_true(m->faces[f].rec_off >= face->off && m->faces[f].rec_off < face->off + face->len);
    assert_true(m->faces[0].rec_off <= m->faces[1].rec_off && m->faces[1].rec_off <= m->faces[2].rec_off);
    cm_mesh mesh = {mesh_pos, mesh_nrm, mesh_idx, mesh_faces, 0, MESH_VERTS, 0, 3 * MESH_VERTS, 0, 64, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    cm_mesh_clear(&mesh);
    cm_status_init(&st);
    assert_ok(cm_tessellate_face(m, 0, m->tess_tol, &mesh, &tess, NULL, &st));
    cm_status_init(&st);
    cm_err e = cm_tessellate_face(m, 1, m->tess_tol, &mesh, &tess, NULL, &st);
    assert_true(e != CM_OK);
    assert_int_equal(st.code, e);
    assert_int_equal(st.face, 1);
    assert_int_equal(st.offset, m->faces[1].rec_off);
    assert_non_null(st.where);
}

/* one bad face never sinks a model: cm_decode_mesh leaves it out and says which */
static void test_bad_face_left_out(void **state)
{
    (void)state;
    size_t n;
    uint8_t *b = sliver_file(&n);
    cm_status st;
    assert_ok(decode(b, n, &st));
    free(b);
    cm_mesh mesh = {mesh_pos, mesh_nrm, mesh_idx, mesh_faces, 0, MESH_VERTS, 0, 3 * MESH_VERTS, 0, 64, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    cm_decode_summary sum;
    cm_status_init(&st);
    assert_ok(cm_decode_mesh(dec, 0, &mesh, &tess, &sum, &st));
    assert_int_equal(st.code, CM_OK);
    assert_int_equal(sum.faces, 3);
    assert_int_equal(sum.faces_left_out, 1);
    assert_int_equal(sum.faces_by_method[CM_METHOD_PLANE], 2);
    assert_int_equal(sum.left_out[0].face, 1);
    assert_int_equal(sum.left_out[0].offset, dec->model.faces[1].rec_off);
    assert_true(sum.left_out[0].code != CM_OK && sum.left_out[0].code != CM_E_LIMIT);
    assert_non_null(sum.left_out[0].where);
    /* the mesh holds the two squares only, and nothing of the sliver */
    assert_int_equal(mesh.nfaces, 2);
    assert_int_equal(mesh.faces[0].source_face, 0);
    assert_int_equal(mesh.faces[1].source_face, 2);
    assert_int_equal(mesh.faces[1].first_vert, mesh.faces[0].nverts);
    assert_int_equal(mesh.nverts, mesh.faces[0].nverts + mesh.faces[1].nverts);
    assert_int_equal(mesh.nindex, mesh.faces[0].nindex + mesh.faces[1].nindex);
    assert_int_equal(sum.triangles, 4);
    /* ... and it writes (a GLB of two faces) */
    cm_out w;
    cm_status_init(&st);
    assert_ok(cm_out_begin(&w, CM_OUT_GLB, &mesh, &st));

    /* a model of nothing but slivers has nothing to show: it fails, naming its first face */
    memset(&M, 0, sizeof M);
    add_sliver(&M, 0, 0);
    add_sliver(&M, 0, 500);
    spec sp;
    spec_of(&M, &sp);
    b = assemble(&sp, &n);
    assert_ok(decode(b, n, &st));
    free(b);
    cm_status_init(&st);
    cm_err e = cm_decode_mesh(dec, 0, &mesh, &tess, &sum, &st);
    assert_true(e != CM_OK);
    assert_int_equal(st.code, e);
    assert_int_equal(st.face, 0);
    assert_int_equal(st.offset, dec->model.faces[0].rec_off);
    assert_int_equal(sum.faces_left_out, 2);
}

/* the work on a face is bounded by what the header declares: a face needing far more points than the
   declared MAX_TESS_POINTS is left out (CM_E_RANGE), the others are drawn as before */
static void test_face_work_bounded_by_declared_needs(void **state)
{
    (void)state;
    memset(&M, 0, sizeof M);
    add_square(&M, -1, 1000, 1024);
    add_ngon(&M, 500, 100000, 100000, 50000.0); /* a PLANE face of 500 boundary points */
    spec sp;
    spec_of(&M, &sp);
    /* as the encoder declares it: the most points a face uses */
    sp.need[CM_LIMIT_MAX_TESS_POINTS] = 500;
    sp.need[CM_LIMIT_MAX_EDGE_SAMPLES] = 2;
    decode_spec(&sp);
    cm_status st;
    const cm_model *m = &dec->model;
    assert_int_equal(cm_tess_point_cap(m, m->tess_tol), 2 * 500 + 256);
    assert_int_equal(cm_tess_point_cap(m, m->tess_tol / 2), CM_MAX_TESS_POINTS < 16 * 1256 ? CM_MAX_TESS_POINTS : 16 * 1256);
    assert_int_equal(cm_tess_point_cap(m, m->tess_tol * 2), 1256); /* coarser: the declared bound */
    assert_int_equal(cm_tess_edge_sample_cap(m, m->tess_tol), 2 * 2 + 16);
    cm_mesh mesh = {mesh_pos, mesh_nrm, mesh_idx, mesh_faces, 0, MESH_VERTS, 0, 3 * MESH_VERTS, 0, 64, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    cm_decode_summary sum;
    cm_status_init(&st);
    assert_ok(cm_decode_mesh(dec, 0, &mesh, &tess, &sum, &st));
    assert_int_equal(sum.faces_left_out, 0);
    uint32_t tris_declared = sum.triangles;

    /* the header says a face needs at most 100 points: the 500-gon is beyond what it declares */
    sp.need[CM_LIMIT_MAX_TESS_POINTS] = 100;
    decode_spec(&sp);
    assert_int_equal(cm_tess_point_cap(&dec->model, dec->model.tess_tol), 456);
    cm_status_init(&st);
    assert_ok(cm_decode_mesh(dec, 0, &mesh, &tess, &sum, &st));
    assert_int_equal(sum.faces_left_out, 1);
    assert_int_equal(sum.left_out[0].code, CM_E_RANGE);
    assert_int_equal(sum.left_out[0].face, 1);
    assert_int_equal(sum.left_out[0].have, 456); /* need: the points when it stopped, beyond that */
    assert_true(sum.left_out[0].need > 456 && sum.left_out[0].need <= 500);
    assert_says(&sum.left_out[0], "more points than the header declares");
    assert_int_equal(sum.triangles, 2);

    /* declared 0: a file's need is never "not declared" (that would leave the build's limit, and
       the workstation's are large enough for minutes of work on a 4 KB file): the slack alone */
    sp.need[CM_LIMIT_MAX_TESS_POINTS] = 0;
    sp.need[CM_LIMIT_MAX_EDGE_SAMPLES] = 0;
    decode_spec(&sp);
    assert_int_equal(cm_tess_point_cap(&dec->model, dec->model.tess_tol), 2 * 1 + 256);
    assert_int_equal(cm_tess_edge_sample_cap(&dec->model, dec->model.tess_tol), 2 * 1 + 16);
    cm_status_init(&st);
    assert_ok(cm_decode_mesh(dec, 0, &mesh, &tess, &sum, &st));
    assert_int_equal(sum.faces_left_out, 1);
    assert_int_equal(sum.left_out[0].face, 1);
    assert_int_equal(sum.triangles, 2);

    /* as large as the build allows: the whole model */
    sp.need[CM_LIMIT_MAX_TESS_POINTS] = CM_MAX_TESS_POINTS;
    sp.need[CM_LIMIT_MAX_EDGE_SAMPLES] = CM_MAX_EDGE_SAMPLES;
    decode_spec(&sp);
    assert_int_equal(cm_tess_point_cap(&dec->model, dec->model.tess_tol), CM_MAX_TESS_POINTS);
    cm_status_init(&st);
    assert_ok(cm_decode_mesh(dec, 0, &mesh, &tess, &sum, &st));
    assert_int_equal(sum.faces_left_out, 0);
    assert_int_equal(sum.triangles, tris_declared);
}

/* and the work on the model: a header whose tolerance no longer matches its needs (a damaged or
   hostile one, 1e-300 mm) makes every face finer; the model stops at twice the declared MAX_TRIS
   plus a margin, naming the face where it stopped, instead of decoding for seconds */
static void test_model_work_bounded_by_declared_triangles(void **state)
{
    (void)state;
    memset(&M, 0, sizeof M);
    for (int k = 0; k < 6; k++)
        add_ngon(&M, 500, 100000 * k, 0, 40000.0); /* PLANE faces of about 498 triangles each */
    spec sp;
    spec_of(&M, &sp);
    sp.need[CM_LIMIT_MAX_TESS_POINTS] = 500;
    sp.need[CM_LIMIT_MAX_EDGE_SAMPLES] = 2;
    decode_spec(&sp);
    cm_status st;
    cm_mesh mesh = {mesh_pos, mesh_nrm, mesh_idx, mesh_faces, 0, MESH_VERTS, 0, 3 * MESH_VERTS, 0, 64, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    cm_decode_summary sum;
    cm_status_init(&st);
    assert_ok(cm_decode_mesh(dec, 0, &mesh, &tess, &sum, &st)); /* MAX_TRIS the build's: no bound */
    uint32_t per_face = sum.triangles / 6;
    assert_int_equal(sum.triangles, 6 * per_face);
    assert_true(per_face > 400);

    /* declared as the encoder counts it: the same mesh */
    sp.need[CM_LIMIT_MAX_TRIS] = sum.triangles;
    decode_spec(&sp);
    assert_int_equal(cm_tess_triangle_cap(&dec->model, dec->model.tess_tol), 2 * 6 * per_face + 1024);
    cm_status_init(&st);
    assert_ok(cm_decode_mesh(dec, 0, &mesh, &tess, &sum, &st));
    assert_int_equal(sum.triangles, 6 * per_face);

    /* the header declares one face's: the model stops at the face whose total passes 2 x + 1024 */
    sp.need[CM_LIMIT_MAX_TRIS] = per_face;
    decode_spec(&sp);
    uint32_t cap = (uint32_t)cm_tess_triangle_cap(&dec->model, dec->model.tess_tol);
    assert_int_equal(cap, 2 * per_face + 1024);
    assert_true(cap / per_face < 5);
    cm_status_init(&st);
    cm_err e = cm_decode_mesh(dec, 0, &mesh, &tess, &sum, &st);
    assert_int_equal(e, CM_E_RANGE);
    assert_int_equal(st.code, CM_E_RANGE);
    uint32_t stop = (cap / per_face); /* faces 0..stop: the first total beyond the cap */
    assert_int_equal(st.face, stop);
    assert_int_equal(st.offset, dec->model.faces[stop].rec_off);
    assert_int_equal(st.have, cap);
    assert_int_equal(st.need, (stop + 1) * per_face);
    assert_says(&st, "more triangles than the header declares");

    /* a viewer's finer tolerance (r = 2) scales the bound by 4 r^2 */
    assert_int_equal(cm_tess_triangle_cap(&dec->model, dec->model.tess_tol / 2), 16 * (2 * per_face + 1024));
}

static int setup(void **state)
{
    (void)state;
    dec = calloc(1, sizeof *dec);
    return dec ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    free(dec);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_six_sections_valid_crcs),
        cmocka_unit_test(test_200_sections),
        cmocka_unit_test(test_every_other_section_count),
        cmocka_unit_test(test_section_table_entries),
        cmocka_unit_test(test_need_counts),
        cmocka_unit_test(test_header_and_file_lengths),
        cmocka_unit_test(test_grid_and_tolerances),
        cmocka_unit_test(test_every_header_byte_hostile),
        cmocka_unit_test(test_face_record_error_names_face),
        cmocka_unit_test(test_tessellation_error_names_face_and_offset),
        cmocka_unit_test(test_bad_face_left_out),
        cmocka_unit_test(test_face_work_bounded_by_declared_needs),
        cmocka_unit_test(test_model_work_bounded_by_declared_triangles),
    };
    return cmocka_run_group_tests_name("decode_hostile", tests, setup, teardown);
}
