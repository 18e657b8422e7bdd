/*
 * test_gregory_errors.c - the terminal decoder's refusals of malformed
 * GREGORY faces (docs/FORMAT.md, FACE and Errors), one named test per path:
 * GREGORY in a 1.x file, a record field out of range, holes and side
 * counts that do not fit the layout, more sides than this build's
 * MAX_SIDES, and a record whose checksum no longer matches.
 *
 * Every malformed file is a well-formed one in all but the one field under
 * test: a model is built in memory (the encoder's split cylinder, decoded,
 * or a polygon made here), the field is changed, and the model is written
 * back with write_cmz() below, valid CRCs included, so the decoder reaches
 * the check under test and not an earlier one.  write_cmz() codes every
 * section as the encoder's writer does (the shared contexts of
 * cm_sections.h, the range coder, cm_crc32); the first test proves it by
 * reproducing the encoder's file byte for byte.  Each test asserts the exact
 * code and that the status, as cm_format_status() prints it, names the cause.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <stdio.h>
#include <stdlib.h>

#include "cm/cm_arith.h"
#include "cm/cm_crc32.h"
#include "cm/cm_decode.h"
#include "cm/cm_limits_info.h"
#include "cm/cm_nfill.h"
#include "cm/cm_patchfit.h"
#include "cm/cm_rebuild.h"
#include "cm/cm_sections.h"
#include "cm_report.h"
#include "encode/encode.h"
#include "igs_writer.h"
#include "model_load.h"

/* src holds the model a test alters, dec decodes the result: 2 x 750 MB with the host profile,
   too much for static storage next to the encoder's own decoder, so allocated (lazily mapped) */
static cm_decoder *src, *dec;
static cm_rebuild_ws rbws;

#define WEIGHT_ONE (1ll << CM_FMT_WEIGHT_BITS)
#define KNOT_ONE (1ll << CM_FMT_KNOT_BITS)
#define SECTION_CAP (1u << 20) /* far more than the test models need; overflow fails the test */

/* ---- a .cmz writer for models held in a cm_model ---- */

/* the grid integer of coordinate x on axis a; a point off the file's grid is a bug of the test */
static int64_t grid_coord(const cm_model *m, int a, double x)
{
    int64_t k = llround((x - m->origin[a]) / m->q);
    if (!(m->origin[a] + m->q * (double)k == x))
        fail_msg("coordinate %.17g (axis %d) is not on the grid", x, a);
    return k;
}

static void grid_point(const cm_model *m, cm_vec3 p, int64_t k[3])
{
    k[0] = grid_coord(m, 0, p.x);
    k[1] = grid_coord(m, 1, p.y);
    k[2] = grid_coord(m, 2, p.z);
}

/* a quantised value v (knot or weight) as the integer v * one; it must be exact */
static int64_t fixed_point(double v, int64_t one, const char *what)
{
    int64_t k = llround(v * (double)one);
    if (!((double)k / (double)one == v))
        fail_msg("%s %.17g is not a multiple of 1/%lld", what, v, (long long)one);
    return k;
}

static void put_vertices(const cm_model *m, cm_ac_enc *e)
{
    cm_vert_ctx c;
    cm_vert_ctx_init(&c);
    cm_ac_enc_uint(e, &c.count, m->nverts);
    int64_t prev[3] = {0, 0, 0};
    for (uint32_t i = 0; i < m->nverts; i++) {
        int64_t k[3];
        grid_point(m, m->verts[i], k);
        for (int a = 0; a < 3; a++) {
            cm_ac_enc_sint(e, &c.coord[a], k[a] - prev[a]);
            prev[a] = k[a];
        }
    }
}

/* a vertex reference: the next vertex not referenced yet, or one already referenced */
static void put_vertex_ref(cm_ac_enc *e, cm_edge_ctx *c, uint32_t *next, int32_t v)
{
    if ((uint32_t)v == *next) {
        cm_ac_enc_bit(e, &c->is_new, 1);
        (*next)++;
        return;
    }
    if (v < 0 || (uint32_t)v > *next)
        fail_msg("vertex %d referenced before vertex %u: not expressible in the format", v, *next);
    cm_ac_enc_bit(e, &c->is_new, 0);
    cm_ac_enc_uint(e, &c->back, *next - 1 - (uint32_t)v);
}

static void put_edges(const cm_model *m, cm_ac_enc *e)
{
    cm_edge_ctx c;
    cm_edge_ctx_init(&c);
    cm_ac_enc_uint(e, &c.count, m->nedges);
    uint32_t vnext = 0;
    for (uint32_t i = 0; i < m->nedges; i++) {
        const cm_edge *E = &m->edges[i];
        put_vertex_ref(e, &c, &vnext, E->v0);
        put_vertex_ref(e, &c, &vnext, E->v1);
        cm_ac_enc_bit(e, &c.g1, E->g1);
        cm_ac_enc_bit(e, &c.kind, E->kind);
        if (E->kind == CM_EDGE_LINE)
            continue;
        int p = E->p, n = E->nctrl, interior = n - p - 1;
        cm_ac_enc_uint(e, &c.degree, (uint64_t)(p - 1));
        cm_ac_enc_uint(e, &c.ncoef, (uint64_t)interior);
        cm_ac_enc_bit(e, &c.rational, E->rational);
        /* the decoder's uniform vector is exactly j / (interior + 1): any other vector has gaps */
        const double *K = m->knots + E->knot0;
        int uniform = 1;
        for (int j = 1; j <= interior; j++)
            uniform &= K[p + j] == (double)j / (double)(interior + 1);
        cm_ac_enc_bit(e, &c.uniform, (unsigned)uniform);
        int64_t kprev = 0;
        for (int j = 1; j <= interior && !uniform; j++) {
            int64_t kq = fixed_point(K[p + j], KNOT_ONE, "knot");
            cm_ac_enc_uint(e, &c.knot, (uint64_t)(kq - kprev));
            kprev = kq;
        }
        int64_t prev[3];
        grid_point(m, m->verts[E->v0], prev);
        for (int j = 1; j < n - 1; j++) {
            int64_t k[3];
            grid_point(m, m->ctrl[E->ctrl0 + (uint32_t)j], k);
            for (int a = 0; a < 3; a++) {
                cm_ac_enc_sint(e, &c.coord[a], k[a] - prev[a]);
                prev[a] = k[a];
            }
        }
        int64_t wprev = WEIGHT_ONE;
        for (int j = 1; j < n && E->rational; j++) {
            int64_t wq = fixed_point(m->w[E->ctrl0 + (uint32_t)j], WEIGHT_ONE, "weight");
            cm_ac_enc_sint(e, &c.weight, wq - wprev);
            wprev = wq;
        }
    }
}

/* the test models have no kept surface (GREGORY and PLANE faces only) */
static void put_surfaces(const cm_model *m, cm_ac_enc *e)
{
    cm_surf_ctx c;
    cm_surf_ctx_init(&c);
    for (uint32_t f = 0; f < m->nfaces; f++)
        if (m->faces[f].method == CM_METHOD_KEEP)
            fail_msg("face %u is KEEP: write_cmz does not write kept surfaces", f);
    cm_ac_enc_uint(e, &c.count, 0);
}

/* GREGORY-FIT's correction as put_faces writes it for every such face: the fields as set, every
   coordinate of every coefficient the same integer q */
static struct {
    int m, patches, exp;
    int64_t q;
} fit_w = {1, 1, 0, 3};

/* FACE exactly as the format says, whatever the record holds: the fields under test go out as set */
static void put_faces(const cm_model *m, cm_ac_enc *e)
{
    cm_face_ctx c;
    cm_face_ctx_init(&c);
    cm_ac_enc_uint(e, &c.count, m->nfaces);
    uint32_t enext = 0;
    for (uint32_t f = 0; f < m->nfaces; f++) {
        const cm_face *F = &m->faces[f];
        cm_ac_enc_uint(e, &c.method, F->method);
        if (F->method == CM_METHOD_GREGORY || F->method == CM_METHOD_GREGORY_EXACT ||
            F->method == CM_METHOD_GREGORY_FIT) { /* the same record, FIT's correction after it */
            cm_ac_enc_uint(e, &c.layout, F->layout);
            cm_ac_enc_uint(e, &c.corner, F->corner);
            cm_ac_enc_direct(e, F->checksum & 0xffffu, 16);
            cm_ac_enc_direct(e, F->checksum >> 16, 16);
        }
        if (F->method == CM_METHOD_NFILL) { /* nu - 4, nv - 4 (5 bits each), phi (3 bits), checksum */
            cm_ac_enc_direct(e, (uint32_t)(F->fill_nu - 4), 5);
            cm_ac_enc_direct(e, (uint32_t)(F->fill_nv - 4), 5);
            cm_ac_enc_direct(e, F->fill_phi, 3);
            cm_ac_enc_direct(e, F->checksum & 0xffffu, 16);
            cm_ac_enc_direct(e, F->checksum >> 16, 16);
        }
        if (F->method == CM_METHOD_G1FIT) { /* nu - 4, nv - 4 (5 bits each), mode (1 bit), checksum */
            cm_ac_enc_direct(e, (uint32_t)(F->fill_nu - 4), 5);
            cm_ac_enc_direct(e, (uint32_t)(F->fill_nv - 4), 5);
            cm_ac_enc_direct(e, F->fill_phi, 1);
            cm_ac_enc_direct(e, F->checksum & 0xffffu, 16);
            cm_ac_enc_direct(e, F->checksum >> 16, 16);
        }
        if (F->method == CM_METHOD_GREGORY_FIT) {
            cm_ac_enc_uint(e, &c.fit_m, (uint64_t)fit_w.m);
            cm_ac_enc_uint(e, &c.fit_patches, (uint64_t)fit_w.patches);
            cm_ac_enc_uint(e, &c.fit_exp, (uint64_t)fit_w.exp);
            for (int i = 0; i < 3 * fit_w.patches * fit_w.m * fit_w.m; i++)
                cm_ac_enc_sint(e, &c.fit_coef, fit_w.q);
        }
        cm_ac_enc_bit(e, &c.flip, F->flip);
        cm_ac_enc_uint(e, &c.loops, F->nloops);
        for (uint32_t l = 0; l < F->nloops; l++) {
            const cm_loop *L = &m->loops[F->loop0 + l];
            cm_ac_enc_uint(e, &c.uses, L->nuse);
            for (uint32_t u = 0; u < L->nuse; u++) {
                const cm_use *U = &m->uses[L->use0 + u];
                if (U->edge == enext) {
                    cm_ac_enc_bit(e, &c.is_new, 1);
                    cm_ac_enc_bit(e, &c.rev_new, U->rev);
                    enext++;
                } else {
                    if (U->edge > enext)
                        fail_msg("edge %u used before edge %u: not expressible in the format", U->edge, enext);
                    cm_ac_enc_bit(e, &c.is_new, 0);
                    cm_ac_enc_uint(e, &c.back, enext - 1 - U->edge);
                    cm_ac_enc_bit(e, &c.rev_old, U->rev);
                }
            }
        }
    }
}

static void put_colours(const cm_model *m, cm_ac_enc *e)
{
    cm_colr_ctx c;
    cm_colr_ctx_init(&c);
    cm_ac_enc_uint(e, &c.count, m->npalette);
    for (uint32_t i = 1; i <= m->npalette; i++)
        cm_ac_enc_direct(e, m->palette[i], 24);
    for (uint32_t f = 0; f < m->nfaces && m->npalette; f++)
        cm_ac_enc_uint(e, &c.index, m->faces[f].color);
}

typedef void (*section_writer)(const cm_model *m, cm_ac_enc *e);

/* the minor version write_cmz writes (the tests of format 2.1 set it) */
static int write_minor;

/**
 * Write model m as a .cmz file of major version `major` (minor write_minor) with the need table `need`
 * (CM_FMT_MIN_NEEDS entries, as the encoder declares a model without placed copies; NULL: all 0,
 * which every build accepts) and every CRC computed.
 * Returns the malloc'd file; *len its length.
 */
static uint8_t *write_cmz(const cm_model *m, int major, const uint32_t *need, size_t *len)
{
    static const section_writer writers[CM_SEC_COUNT] = {put_vertices, put_edges, put_surfaces, put_faces,
                                                         put_colours};
    uint8_t *sec[CM_SEC_COUNT];
    size_t seclen[CM_SEC_COUNT];
    const size_t H = cm_fmt_header_len(CM_FMT_MIN_NEEDS, CM_SEC_COUNT);
    size_t total = H + 4u;
    for (int s = 0; s < CM_SEC_COUNT; s++) {
        sec[s] = malloc(SECTION_CAP);
        assert_non_null(sec[s]);
        cm_ac_enc e;
        cm_ac_enc_init(&e, sec[s], SECTION_CAP);
        writers[s](m, &e);
        seclen[s] = cm_ac_enc_finish(&e);
        assert_true(seclen[s] > 0); /* 0: the buffer overflowed */
        total += seclen[s];
    }
    uint8_t *b = calloc(1, total);
    assert_non_null(b);
    int qe = ilogb(m->q);
    if (!(ldexp(1.0, qe) == m->q))
        fail_msg("grid step %.17g is not a power of 2", m->q);
    cm_fmt_header h = {0};
    h.major = (uint8_t)major;
    h.minor = (uint8_t)write_minor;
    h.flags = (uint16_t)(m->npalette ? 1 : 0);
    h.header_len = (uint32_t)H;
    h.file_len = (uint32_t)total;
    h.nlimits = CM_FMT_MIN_NEEDS;
    h.nsections = CM_SEC_COUNT;
    h.q_exp = (int8_t)qe;
    for (int k = 0; k < 3; k++)
        h.origin[k] = m->origin[k];
    h.tess_tol = m->tess_tol;
    h.rel_tol = m->rel_tol;
    cm_fmt_header_pack(b, &h);
    for (uint32_t i = 0; i < CM_FMT_MIN_NEEDS; i++)
        cm_put_u32(b + cm_fmt_need_at(i), need ? need[i] : 0);
    size_t off = H;
    for (int s = 0; s < CM_SEC_COUNT; s++) {
        uint8_t *ent = b + cm_fmt_entry_at(CM_FMT_MIN_NEEDS, (uint32_t)s);
        ent[CM_ENT_TAG] = (uint8_t)(s + 1);
        cm_put_u32(ent + CM_ENT_OFFSET, (uint32_t)off);
        cm_put_u32(ent + CM_ENT_LENGTH, (uint32_t)seclen[s]);
        cm_put_u32(ent + CM_ENT_CRC, cm_crc32(sec[s], seclen[s]));
        memcpy(b + off, sec[s], seclen[s]);
        off += seclen[s];
        free(sec[s]);
    }
    cm_put_u32(b + H - 4, cm_crc32(b, H - 4));
    cm_put_u32(b + total - 4, cm_crc32(b, total - 4));
    *len = total;
    return b;
}

/* ---- models ---- */

/* the split half cylinder of spec T5 encoded with GREGORY on: two layout-0 faces, format 2 */
static const encode_result *split_cylinder(void)
{
    static encode_result r;
    if (r.bytes)
        return &r;
    igw w;
    igw_init(&w);
    igw_split_half_cylinder_144(&w, 10.0, 20.0);
    size_t len = 0;
    char *text = igw_text(&w, &len);
    igw_free(&w);
    cm_status st;
    cm_status_init(&st);
    loaded_model lm;
    assert_ok(model_load_data("split-cylinder", text, len, &lm, NULL, NULL, &st));
    free(text);
    encode_opts o;
    encode_opts_default(&o);
    o.rel_tol = 0.01;
    o.rel_set = 1;
    o.gregory = 1;
    o.predicted = 0; /* write_cmz writes format 2's coding */
    assert_ok(encode_model(&lm, &o, &r, &st));
    model_free(&lm);
    assert_int_equal(r.faces_by_method[CM_METHOD_GREGORY], 2);
    assert_int_equal(r.bytes[CM_HDR_MAJOR], 2);
    return &r;
}

static cm_err decode_bytes(cm_decoder *d, const uint8_t *b, size_t n, cm_status *st)
{
    cm_status_init(st);
    cm_dec_init(d);
    cm_err e = cm_dec_feed(d, b, n, st);
    return e != CM_OK ? e : cm_dec_finish(d, st);
}

/* src->model := the split cylinder as the terminal decodes it */
static void load_split_cylinder(void)
{
    const encode_result *r = split_cylinder();
    cm_status st;
    assert_ok(decode_bytes(src, r->bytes, r->len, &st));
    assert_int_equal(src->model.nfaces, 2);
    for (int f = 0; f < 2; f++) {
        assert_int_equal(src->model.faces[f].method, CM_METHOD_GREGORY);
        assert_int_equal(src->model.faces[f].layout, CM_GREG_LAYOUT_QUAD);
        assert_int_equal(src->model.loops[src->model.faces[f].loop0].nuse, 4);
    }
}

/* a vertex of a hand-built model, moved to the grid */
static uint32_t add_vertex(cm_model *m, double x, double y)
{
    cm_vec3 p = cm_v3(m->q * (double)llround(x / m->q), m->q * (double)llround(y / m->q), 0.0);
    m->verts[m->nverts] = p;
    return m->nverts++;
}

static void add_line(cm_model *m, uint32_t v0, uint32_t v1)
{
    cm_edge *E = &m->edges[m->nedges++];
    memset(E, 0, sizeof *E);
    E->v0 = (int32_t)v0;
    E->v1 = (int32_t)v1;
    E->kind = CM_EDGE_LINE;
    E->p = 1;
    E->nctrl = 2;
}

/* a loop of face 0 through the vertices v0 .. v0+n-1, closed, each side a new line edge */
static void add_loop(cm_model *m, uint32_t v0, int n)
{
    uint32_t e0 = m->nedges;
    for (int k = 0; k < n; k++)
        add_line(m, v0 + (uint32_t)k, v0 + (uint32_t)((k + 1) % n));
    cm_loop *L = &m->loops[m->nloops++];
    L->use0 = m->nuses;
    L->nuse = (uint16_t)n;
    for (int k = 0; k < n; k++) {
        m->uses[m->nuses].edge = e0 + (uint32_t)k;
        m->uses[m->nuses++].rev = 0;
    }
    m->faces[0].nloops++;
}

/*
 * src->model := one planar face whose outer loop is a regular polygon of `sides` line edges (radius
 * 10 mm, counter-clockwise) and, with `hole`, a clockwise polygon inside it (1: a triangle; 3 or
 * more: of that many edges), with the given record.
 * The checksum is 0: the decoder does not rebuild, so these models test the reading only.
 */
static void polygon_face(int sides, int hole, int method, int layout, int corner)
{
    cm_model *m = &src->model;
    m->origin[0] = m->origin[1] = m->origin[2] = 0.0;
    m->q = 1.0 / 1024.0;
    m->tess_tol = 0.01;
    m->rel_tol = 0.01;
    m->nverts = m->nedges = m->nfaces = m->nloops = m->nuses = m->nsurfs = m->nctrl = m->nknots = 0;
    m->npalette = 0;
    cm_face *F = &m->faces[m->nfaces++];
    memset(F, 0, sizeof *F);
    F->method = (uint8_t)method;
    F->layout = (uint8_t)layout;
    F->corner = (uint8_t)corner;
    F->loop0 = 0;
    uint32_t first = m->nverts;
    for (int k = 0; k < sides; k++)
        add_vertex(m, 10.0 * cos(2 * M_PI * k / sides), 10.0 * sin(2 * M_PI * k / sides));
    add_loop(m, first, sides);
    if (hole) {
        int hn = hole < 3 ? 3 : hole; /* 1: a triangle; 3 or more: that many edges */
        first = m->nverts;
        for (int k = 0; k < hn; k++) /* clockwise: the face stays on the left */
            add_vertex(m, 2.0 * cos(-2 * M_PI * k / hn), 2.0 * sin(-2 * M_PI * k / hn));
        add_loop(m, first, hn);
    }
}

/* ---- checks ---- */

/* the status as the terminal prints it must contain `cause` */
static void assert_says(const cm_status *st, const char *cause)
{
    char text[512];
    cm_format_status(text, sizeof text, st);
    if (!strstr(text, cause))
        fail_msg("status \"%s\" does not say \"%s\"", text, cause);
}

/* src->model written as format `major` must decode (a control: only the field under test is wrong) */
static void assert_decodes(int major)
{
    size_t len;
    uint8_t *b = write_cmz(&src->model, major, NULL, &len);
    cm_status st;
    cm_err e = decode_bytes(dec, b, len, &st);
    free(b);
    if (e != CM_OK) {
        char text[512];
        fail_msg("control model refused: %s", cm_format_status(text, sizeof text, &st));
    }
}

/*
 * src->model written as format `major` (valid CRCs): the header must be accepted, and decoding the
 * body must fail in the FACE section with `code`, the status naming `cause`.
 */
static void assert_face_refused(int major, cm_err code, const char *cause, cm_status *st)
{
    size_t len;
    uint8_t *b = write_cmz(&src->model, major, NULL, &len);
    cm_status_init(st);
    cm_dec_init(dec);
    assert_ok(cm_dec_feed(dec, b, len, st));
    assert_true(cm_dec_header_ok(dec));
    assert_int_equal(dec->version_major, major);
    assert_err(cm_dec_finish(dec, st), code);
    free(b);
    assert_int_equal(st->code, code);
    const cm_dec_section *face = &dec->sec[CM_SEC_FACE - 1];
    if (!(st->offset >= face->off && st->offset <= face->off + face->len))
        fail_msg("error at byte %u, outside FACE (bytes %u..%u)", st->offset, face->off, face->off + face->len);
    assert_says(st, cause);
}

/* ---- tests ---- */

/* the writer of these tests says what the encoder says: its output is the encoder's, byte for byte */
static void test_writer_reproduces_encoder(void **state)
{
    (void)state;
    const encode_result *r = split_cylinder();
    load_split_cylinder();
    size_t len;
    uint8_t *b = write_cmz(&src->model, src->version_major, src->need, &len);
    assert_int_equal(len, r->len);
    assert_memory_equal(b, r->bytes, len);
    free(b);
}

/* FORMAT.md: "A GREGORY method in a 1.x file is CM_E_UNSUPPORTED": a real 1.0 file, CRCs valid */
static void test_gregory_in_format_1_unsupported(void **state)
{
    (void)state;
    load_split_cylinder();
    cm_status st;
    assert_face_refused(1, CM_E_UNSUPPORTED, "GREGORY face in a format 1 file", &st);
    assert_says(&st, "CM_E_UNSUPPORTED");
    /* the same faces as PLANE are what a 1.0 file may say, and it loads */
    for (int f = 0; f < 2; f++)
        src->model.faces[f].method = CM_METHOD_PLANE;
    assert_decodes(1);
}

/* a record field beyond what the format defines: CM_E_RANGE, as soon as the record is read */
static void test_gregory_record_out_of_range(void **state)
{
    (void)state;
    cm_status st;
    /* layout 4 does not exist (0 quad, 1 N-split, 2 degenerate quad, 3 joined sides) */
    load_split_cylinder();
    src->model.faces[1].layout = 4;
    assert_face_refused(2, CM_E_RANGE, "GREGORY layout", &st);
    /* layout 3 came with format 2.3 (this file says 2.0) */
    load_split_cylinder();
    src->model.faces[1].layout = CM_GREG_LAYOUT_JOINED;
    assert_face_refused(2, CM_E_UNSUPPORTED, "older than format 2.3", &st);
    /* layout 2's collapsed vertex is an index in a loop of at most MAX_SIDES edges */
    load_split_cylinder();
    src->model.faces[0].layout = CM_GREG_LAYOUT_DEGEN;
    src->model.faces[0].corner = CM_MAX_SIDES;
    assert_face_refused(2, CM_E_RANGE, "GREGORY corner", &st);
    src->model.faces[0].corner = 255;
    assert_face_refused(2, CM_E_RANGE, "GREGORY corner", &st);
    /* layouts 0 and 1 have no collapsed vertex: their corner is 0 */
    load_split_cylinder();
    src->model.faces[0].corner = 1;
    assert_face_refused(2, CM_E_RANGE, "GREGORY corner", &st);
    polygon_face(5, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_SPLIT, 2);
    assert_face_refused(2, CM_E_RANGE, "GREGORY corner", &st);
    polygon_face(5, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_SPLIT, 0);
    assert_decodes(2);
}

/* format 4.13's hints (spec 15.3): only a flat corner with no G1 edge takes one; a hint at a corner
   with a normal of its own (each of a pentagon's) is not the encoder's, and the face is refused by
   name when it is rebuilt (test_hints.c has the record's own refusals) */
static void test_hint_at_own_normal(void **state)
{
    (void)state;
    write_minor = 1;
    polygon_face(5, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_SPLIT, 0);
    assert_decodes(2); /* (the model as the terminal has it) */
    write_minor = 0;
    cm_model *m = &dec->model;
    cm_face *F = &m->faces[0];
    cm_rebuilt rb;
    cm_status st;
    cm_status_init(&st);
    /* (without the hint the flat pentagon is no Gregory face either, but not for a hint) */
    assert_true(cm_rebuild_face_ex(m, 0, 0, &rb, &rbws, &st) != CM_E_FORMAT);
    F->surf = m->nctrl;
    m->ctrl[m->nctrl++] = cm_v3(0, 0, 1);
    F->fill_nu = 1u << 3;
    assert_int_equal(cm_rebuild_face_ex(m, 0, 0, &rb, &rbws, &st), CM_E_FORMAT);
    assert_says(&st, "GREGORY hint at a corner that has its own normal");
    /* (a net's fields are no mask) */
    F->method = CM_METHOD_NFILL;
    assert_int_equal(cm_face_hint_mask(F), 0);
}

/* GREGORY faces are one loop whose side count fits the layout, else CM_E_FORMAT */
static void test_gregory_loop_malformed(void **state)
{
    (void)state;
    cm_status st;
    /* holes: a square with a triangular hole is a valid PLANE face, not a GREGORY one */
    polygon_face(4, 1, CM_METHOD_PLANE, 0, 0);
    assert_decodes(2);
    polygon_face(4, 1, CM_METHOD_GREGORY, CM_GREG_LAYOUT_QUAD, 0);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY face with holes", &st);
    polygon_face(5, 1, CM_METHOD_GREGORY, CM_GREG_LAYOUT_SPLIT, 0);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY face with holes", &st);
    /* layout 0 is one quad: 4 sides */
    polygon_face(4, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_QUAD, 0);
    assert_decodes(2);
    polygon_face(3, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_QUAD, 0);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY sides do not fit the layout", &st);
    polygon_face(5, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_QUAD, 0);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY sides do not fit the layout", &st);
    /* layout 2 is a quad collapsed at one of 3 vertices */
    polygon_face(3, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_DEGEN, 2);
    assert_decodes(2);
    polygon_face(4, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_DEGEN, 2);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY sides do not fit the layout", &st);
    /* ... and its corner, in range for the record (< MAX_SIDES), must be one of those 3
       (FORMAT.md: "layout 2: exactly 3, corner < 3, else CM_E_FORMAT") */
    polygon_face(3, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_DEGEN, 3);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY corner beyond the loop", &st);
    /* every layout needs 3 sides at least: a loop of two lines is refused, whatever the build */
    polygon_face(2, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_SPLIT, 0);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY face with fewer than 3 sides", &st);
    polygon_face(3, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_SPLIT, 0);
    assert_decodes(2);
}

/* an N-split face with more sides than this build's MAX_SIDES is valid input, too large: CM_E_LIMIT */
static void test_gregory_sides_over_limit(void **state)
{
    (void)state;
    cm_status st;
    char want[160];
    polygon_face(CM_MAX_SIDES, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_SPLIT, 0);
    assert_decodes(2);
    /* a header that does not declare the need (0): the FACE section's own check refuses the face */
    polygon_face(CM_MAX_SIDES + 1, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_SPLIT, 0);
    assert_face_refused(2, CM_E_LIMIT, "GREGORY sides", &st);
    assert_int_equal(st.limit, CM_LIMIT_MAX_SIDES);
    assert_int_equal(st.need, CM_MAX_SIDES + 1);
    assert_int_equal(st.have, CM_MAX_SIDES);
    snprintf(want, sizeof want, "needs MAX_SIDES=%u, this build (profile %s) has %u", CM_MAX_SIDES + 1,
             cm_profile_name, CM_MAX_SIDES);
    assert_says(&st, want);
    /* a header that declares it, as the encoder writes: refused at the header, before the body */
    uint32_t need[CM_LIMIT_COUNT] = {0};
    need[CM_LIMIT_MAX_SIDES] = CM_MAX_SIDES + 1;
    size_t len;
    uint8_t *b = write_cmz(&src->model, 2, need, &len);
    cm_status_init(&st);
    cm_dec_init(dec);
    assert_err(cm_dec_feed(dec, b, len, &st), CM_E_LIMIT);
    free(b);
    assert_false(cm_dec_header_ok(dec));
    assert_int_equal(st.limit, CM_LIMIT_MAX_SIDES);
    assert_int_equal(st.offset, cm_fmt_need_at(CM_LIMIT_MAX_SIDES));
    assert_says(&st, want);
}

/* GREGORY-EXACT (format 2.1): GREGORY's record and loop rules, refused by name, and not in a 2.0 file */
static void test_gregory_exact_records(void **state)
{
    (void)state;
    cm_status st;
    write_minor = 1;
    polygon_face(5, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_SPLIT, 0);
    assert_decodes(2);
    polygon_face(5, 0, CM_METHOD_GREGORY_EXACT, 4, 0);
    assert_face_refused(2, CM_E_RANGE, "GREGORY layout", &st);
    polygon_face(5, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_JOINED, 15);
    assert_face_refused(2, CM_E_UNSUPPORTED, "GREGORY layout 3 (joined sides) in a file older than format 2.3", &st);
    /* format 2.3: layout 3 names four corners of a loop of 5 to 8 edges, on exact patches */
    write_minor = 3;
    polygon_face(5, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_JOINED, 15);
    assert_decodes(2);
    polygon_face(5, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_JOINED, 7);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY layout 3 corners", &st);
    polygon_face(5, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_JOINED, 32 + 7);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY layout 3 corners", &st);
    polygon_face(5, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_JOINED, 31);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY layout 3 corners", &st);
    polygon_face(10, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_JOINED, 0x63); /* 1, 4, 1, 4 edges */
    assert_decodes(2);
    polygon_face(10, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_JOINED, 0x0f); /* a side of 7 edges */
    assert_face_refused(2, CM_E_FORMAT, "GREGORY layout 3 corners", &st);
    polygon_face(13, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_JOINED, 0x249); /* 13 edges: over 12 */
    assert_face_refused(2, CM_E_FORMAT, "GREGORY layout 3 corners", &st);
    polygon_face(4, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_JOINED, 15);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY sides do not fit the layout", &st);
    polygon_face(5, 0, CM_METHOD_GREGORY, CM_GREG_LAYOUT_JOINED, 15);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY layout 3 on cubic patches", &st);
    write_minor = 1;
    polygon_face(5, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_SPLIT, 2);
    assert_face_refused(2, CM_E_RANGE, "GREGORY corner", &st);
    polygon_face(5, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_QUAD, 0);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY sides do not fit the layout", &st);
    polygon_face(5, 1, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_SPLIT, 0);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY face with holes", &st);
    polygon_face(CM_MAX_SIDES + 1, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_SPLIT, 0);
    assert_face_refused(2, CM_E_LIMIT, "GREGORY sides", &st);
    assert_int_equal(st.limit, CM_LIMIT_MAX_SIDES);
    /* the same valid face in a file that says 2.0 */
    write_minor = 0;
    polygon_face(5, 0, CM_METHOD_GREGORY_EXACT, CM_GREG_LAYOUT_SPLIT, 0);
    assert_face_refused(2, CM_E_UNSUPPORTED, "GREGORY-EXACT face in a file older than format 2.1", &st);
}

/* GREGORY-FIT (format 2.2): GREGORY's record, then the correction's fields, each refused by name; the
   corrections must match the layout's patches; not in a 2.1 file */
static void test_gregory_fit_records(void **state)
{
    (void)state;
    cm_status st;
    write_minor = 2;
    fit_w.m = 2;
    fit_w.patches = 1;
    fit_w.exp = 3;
    fit_w.q = -7;
    polygon_face(4, 0, CM_METHOD_GREGORY_FIT, CM_GREG_LAYOUT_QUAD, 0);
    assert_decodes(2);
    /* the coefficients landed in the pool, dequantised: -7 * 2^3 grid steps */
    const cm_face *F = &dec->model.faces[0];
    assert_int_equal(cm_face_fit_m(F), 2);
    assert_int_equal(cm_face_fit_patches(F), 1);
    assert_int_equal(dec->model.nctrl - F->surf, 4);
    assert_true(dec->model.ctrl[F->surf + 3].y == -7.0 * 8.0 * src->model.q);
    polygon_face(5, 0, CM_METHOD_GREGORY_FIT, CM_GREG_LAYOUT_SPLIT, 0);
    assert_face_refused(2, CM_E_FORMAT, "GREGORY-FIT corrections do not fit the layout", &st);
    fit_w.patches = 5;
    assert_decodes(2);
    fit_w.patches = 1;
    polygon_face(4, 0, CM_METHOD_GREGORY_FIT, CM_GREG_LAYOUT_QUAD, 0);
    fit_w.m = 0;
    assert_face_refused(2, CM_E_RANGE, "GREGORY-FIT coefficients per direction", &st);
    fit_w.m = CM_FIT_MAX_M + 1;
    assert_face_refused(2, CM_E_RANGE, "GREGORY-FIT coefficients per direction", &st);
    fit_w.m = 1;
    fit_w.patches = 0;
    assert_face_refused(2, CM_E_RANGE, "GREGORY-FIT patches", &st);
    fit_w.patches = CM_HARD_MAX_GREG + 1;
    assert_face_refused(2, CM_E_RANGE, "GREGORY-FIT patches", &st);
#if CM_MAX_GREG < CM_HARD_MAX_GREG
    fit_w.patches = CM_MAX_GREG + 1;
    assert_face_refused(2, CM_E_LIMIT, "GREGORY-FIT patches", &st);
    assert_int_equal(st.limit, CM_LIMIT_MAX_GREG);
#endif
    fit_w.patches = 1;
    fit_w.exp = CM_FIT_MAX_EXP + 1;
    assert_face_refused(2, CM_E_RANGE, "GREGORY-FIT step", &st);
    fit_w.exp = CM_FIT_MAX_EXP;
    fit_w.q = -(int64_t)CM_FIT_MAX_INT - 1;
    assert_face_refused(2, CM_E_RANGE, "GREGORY-FIT coefficient", &st);
    fit_w.q = CM_FIT_MAX_INT;
    assert_decodes(2);
    /* the same valid face in a file that says 2.1 */
    write_minor = 1;
    assert_face_refused(2, CM_E_UNSUPPORTED, "GREGORY-FIT face in a file older than format 2.2", &st);
    write_minor = 0;
    fit_w.m = 1;
    fit_w.exp = 0;
    fit_w.q = 3;
}

/* the NFILL record of polygon_face's face 0 */
static void nfill_record(int nu, int nv, int phi)
{
    cm_face *F = &src->model.faces[0];
    F->fill_nu = (uint8_t)nu;
    F->fill_nv = (uint8_t)nv;
    F->fill_phi = (uint8_t)phi;
}

/* NFILL (format 2.4): nu, nv, phi; an outer loop of 3 to 12 edges, 64 in all its loops; the net within the build's limits,
   each refused by name; not in a 2.3 file */
static void test_nfill_records(void **state)
{
    (void)state;
    cm_status st;
    write_minor = 4;
    polygon_face(6, 0, CM_METHOD_NFILL, 0, 0);
    nfill_record(8, 6, 2);
    assert_decodes(2);
    assert_int_equal(dec->model.faces[0].fill_nu, 8);
    assert_int_equal(dec->model.faces[0].fill_nv, 6);
    assert_int_equal(dec->model.faces[0].fill_phi, 2);
    nfill_record(8, 6, CM_NFILL_PHI_COUNT);
    assert_face_refused(2, CM_E_RANGE, "NFILL phi", &st);
    polygon_face(6, 1, CM_METHOD_NFILL, 0, 0); /* holes are fine ... */
    nfill_record(8, 6, 2);
    assert_decodes(2);
    polygon_face(12, 52, CM_METHOD_NFILL, 0, 0); /* ... up to 64 edges in all */
    nfill_record(8, 6, 2);
    assert_decodes(2);
    polygon_face(12, 53, CM_METHOD_NFILL, 0, 0);
    nfill_record(8, 6, 2);
    assert_face_refused(2, CM_E_FORMAT, "NFILL face of more than 64 edges", &st);
    polygon_face(13, 0, CM_METHOD_NFILL, 0, 0);
    nfill_record(8, 6, 2);
    assert_face_refused(2, CM_E_FORMAT, "NFILL loop of more than 12 edges", &st);
    polygon_face(2, 0, CM_METHOD_NFILL, 0, 0);
    nfill_record(8, 6, 2);
    assert_face_refused(2, CM_E_FORMAT, "NFILL face with fewer than 3 edges", &st);
    /* the largest net the build solves, and one more point per direction (the field goes to 35) */
    polygon_face(12, 0, CM_METHOD_NFILL, 0, 0);
    nfill_record(CM_MAX_FIT_CTRL, CM_MAX_FIT_CTRL, 4);
    assert_decodes(2);
#if CM_MAX_FIT_CTRL < CM_NFILL_MAX_CTRL_FIELD
    nfill_record(CM_MAX_FIT_CTRL + 1, 4, 4);
    assert_face_refused(2, CM_E_LIMIT, "NFILL control points", &st);
    assert_int_equal(st.limit, CM_LIMIT_MAX_FIT_CTRL);
    assert_int_equal(st.need, CM_MAX_FIT_CTRL + 1);
#endif
    /* the same valid face in a file that says 2.3 */
    nfill_record(8, 6, 2);
    write_minor = 3;
    assert_face_refused(2, CM_E_UNSUPPORTED, "NFILL face in a file older than format 2.4", &st);
    write_minor = 0;
}

/* G1FIT (format 2.5): nu, nv, mode; an outer loop of 4 to 12 edges (holes trimmed); the net within the
   build's limits, each refused by name; not in a 2.4 file */
static void test_g1fit_records(void **state)
{
    (void)state;
    cm_status st;
    write_minor = 5;
    polygon_face(6, 0, CM_METHOD_G1FIT, 0, 0);
    nfill_record(8, 6, 1);
    assert_decodes(2);
    assert_int_equal(dec->model.faces[0].method, CM_METHOD_G1FIT);
    assert_int_equal(dec->model.faces[0].fill_nu, 8);
    assert_int_equal(dec->model.faces[0].fill_nv, 6);
    assert_int_equal(dec->model.faces[0].fill_phi, 1);
    polygon_face(4, 1, CM_METHOD_G1FIT, 0, 0); /* holes are fine */
    nfill_record(8, 6, 0);
    assert_decodes(2);
    polygon_face(3, 0, CM_METHOD_G1FIT, 0, 0);
    nfill_record(8, 6, 0);
    assert_face_refused(2, CM_E_FORMAT, "G1FIT face with fewer than 4 edges", &st);
    polygon_face(13, 0, CM_METHOD_G1FIT, 0, 0);
    nfill_record(8, 6, 0);
    assert_face_refused(2, CM_E_FORMAT, "G1FIT loop of more than 12 edges", &st);
    polygon_face(12, 0, CM_METHOD_G1FIT, 0, 0);
    nfill_record(CM_MAX_FIT_CTRL, CM_MAX_FIT_CTRL, 1);
    assert_decodes(2);
#if CM_MAX_FIT_CTRL < CM_NFILL_MAX_CTRL_FIELD
    nfill_record(4, CM_MAX_FIT_CTRL + 1, 0);
    assert_face_refused(2, CM_E_LIMIT, "G1FIT control points", &st);
    assert_int_equal(st.limit, CM_LIMIT_MAX_FIT_CTRL);
    assert_int_equal(st.need, CM_MAX_FIT_CTRL + 1);
#endif
    /* the same valid face in a file that says 2.4 */
    nfill_record(8, 6, 1);
    write_minor = 4;
    assert_face_refused(2, CM_E_UNSUPPORTED, "G1FIT face in a file older than format 2.5", &st);
    write_minor = 0;
}

/* a checksum changed in the file (CRCs valid): the file loads, the face's rebuild refuses it */
static void test_gregory_checksum_in_file(void **state)
{
    (void)state;
    load_split_cylinder();
    src->model.faces[1].checksum ^= 0x80000000u; /* the high half: the second 16-bit word */
    size_t len;
    uint8_t *b = write_cmz(&src->model, 2, src->need, &len);
    cm_status st;
    assert_ok(decode_bytes(dec, b, len, &st));
    free(b);
    cm_rebuilt rb;
    assert_ok(cm_rebuild_face(&dec->model, 0, &rb, &rbws, &st));
    cm_status_init(&st);
    assert_err(cm_rebuild_face(&dec->model, 1, &rb, &rbws, &st), CM_E_CHECKSUM);
    assert_int_equal(st.code, CM_E_CHECKSUM);
    assert_says(&st, "GREGORY face rebuilt differently from the encoder");
}

static int alloc_decoders(void **state)
{
    (void)state;
    src = calloc(1, sizeof *src);
    dec = calloc(1, sizeof *dec);
    return src && dec ? 0 : -1;
}

static int free_decoders(void **state)
{
    (void)state;
    free(src);
    free(dec);
    return 0;
}

/*
 * The decode's corner cache (cm_corner_cache_begin): the split cylinder's two GREGORY faces share a
 * G1 edge of rational arcs (K7 converts it) and ask for each other's normal.  With the cache on, the
 * same surfaces as without; the second face is then built from what the first left in the cache
 * (a change to the model in between goes unseen, which is why the encoder leaves it off), and
 * cm_corner_cache_end computes everything again.
 */
static void test_corner_cache(void **state)
{
    (void)state;
    load_split_cylinder();
    cm_model *m = &src->model;
    static cm_rebuild_ws off, on;
    cm_status st;
    uint32_t sum_off[2], sum_on[2];
    static cm_greg_input in_off[2];
    for (uint32_t f = 0; f < 2; f++) {
        cm_rebuilt rb;
        cm_status_init(&st);
        assert_ok(cm_rebuild_face(m, f, &rb, &off, &st));
        sum_off[f] = rb.checksum;
        in_off[f] = off.gin;
    }
    cm_corner_cache_begin(&on.corner, m);
    for (uint32_t f = 0; f < 2; f++) {
        cm_rebuilt rb;
        cm_status_init(&st);
        assert_ok(cm_rebuild_face(m, f, &rb, &on, &st));
        sum_on[f] = rb.checksum;
        /* the construction's input, bit for bit: n_F and its box, the cubics, the normals */
        const cm_greg_input *a = &in_off[f], *b = &on.gin;
        assert_int_equal(a->n, b->n);
        assert_memory_equal(&a->nF, &b->nF, sizeof a->nF);
        assert_memory_equal(&a->eps_len, &b->eps_len, sizeof a->eps_len);
        for (int k = 0; k < a->n; k++) {
            assert_memory_equal(&a->corner_normal[k], &b->corner_normal[k], sizeof(cm_vec3));
            assert_memory_equal(&a->side[k].c, &b->side[k].c, sizeof(cm_cubic));
            assert_memory_equal(&a->side[k].Ns, &b->side[k].Ns, sizeof(cm_vec3));
            assert_memory_equal(&a->side[k].Ne, &b->side[k].Ne, sizeof(cm_vec3));
        }
    }
    assert_int_equal(sum_on[0], sum_off[0]);
    assert_int_equal(sum_on[1], sum_off[1]);
    assert_int_equal(on.corner.normal_cache[1].face, 1); /* face 0 asked for its partner's normal */

    /* move the middle control point of one of face 1's arcs: the cache does not see it, the end does */
    int arc = -1;
    const cm_loop *L = &m->loops[m->faces[1].loop0];
    for (uint32_t k = 0; k < L->nuse; k++)
        if (m->edges[m->uses[L->use0 + k].edge].nctrl >= 3)
            arc = (int)m->uses[L->use0 + k].edge;
    assert_true(arc >= 0);
    cm_vec3 *P = &m->ctrl[m->edges[arc].ctrl0 + 1];
    cm_vec3 keep = *P;
    P->z += 0.5;
    cm_rebuilt rb;
    cm_status_init(&st);
    assert_ok(cm_rebuild_face_ex(m, 1, 0, &rb, &on, &st));
    assert_int_equal(rb.checksum, sum_off[1]); /* from the cache: the old edge */
    cm_corner_cache_end(&on.corner);
    cm_status_init(&st);
    assert_ok(cm_rebuild_face_ex(m, 1, 0, &rb, &on, &st));
    uint32_t moved = rb.checksum;
    assert_int_not_equal(moved, sum_off[1]);
    cm_status_init(&st);
    assert_ok(cm_rebuild_face_ex(m, 1, 0, &rb, &off, &st)); /* never on: the same as after the end */
    assert_int_equal(rb.checksum, moved);
    *P = keep;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_writer_reproduces_encoder),
        cmocka_unit_test(test_gregory_in_format_1_unsupported),
        cmocka_unit_test(test_gregory_record_out_of_range),
        cmocka_unit_test(test_gregory_loop_malformed),
        cmocka_unit_test(test_hint_at_own_normal),
        cmocka_unit_test(test_gregory_sides_over_limit),
        cmocka_unit_test(test_gregory_checksum_in_file),
        cmocka_unit_test(test_gregory_exact_records),
        cmocka_unit_test(test_gregory_fit_records),
        cmocka_unit_test(test_nfill_records),
        cmocka_unit_test(test_g1fit_records),
        cmocka_unit_test(test_corner_cache),
    };
    return cmocka_run_group_tests_name("gregory_errors", tests, alloc_decoders, free_decoders);
}
