/*
 * test_arcs.c - format 4.4's arc edges through the whole product: the encoder sends a half
 * cylinder's half circles as arcs (their middle points), the terminal's decoder builds them on the
 * circle within the curves' share of the tolerance, the file is smaller than 4.3's, and a 4.3 reader
 * cannot take the same bytes.  The encoder's choice (tx_arc_edge) on curves that are arcs and on
 * curves that nearly are, which it must turn back.  Then arc records as a broken or hostile writer could send them, each
 * in a file whose every length and CRC is right: refused by name, never a crash.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <stdio.h>
#include <stdlib.h>

#include "cm/cm_arith.h"
#include "cm/cm_crc32.h"
#include "cm/cm_decode.h"
#include "cm/cm_predict.h"
#include "cm/cm_sections.h"
#include "encode/encode.h"
#include "encode/encode_internal.h"
#include "cm/cm_limits_info.h"
#include "cmz_splice.h"
#include "record_io.h"
#include "igs_writer.h"
#include "model_load.h"

#define CYL_R 10.0 /* the half cylinder: radius, axis z */
#define CYL_H 20.0 /* and height */

static cm_decoder dec;

static void load_half_cylinder(loaded_model *lm)
{
    igw w;
    igw_init(&w);
    igw_half_cylinder_120(&w, CYL_R, CYL_H);
    cm_status st;
    assert_ok(igw_load(&w, "half_cylinder", lm, &st));
}

static cm_err decode(const uint8_t *b, size_t len, cm_status *st)
{
    return cmz_decode(&dec, b, len, st);
}

/* the rational quadratic edges of the decoded model: how many, and how far their points (at 64
   steps) lie from the half cylinder's circles */
static int curved_edges(const cm_model *m, double *worst)
{
    int n = 0;
    *worst = 0;
    for (uint32_t i = 0; i < m->nedges; i++) {
        if (m->edges[i].kind != CM_EDGE_CURVE)
            continue;
        assert_int_equal(m->edges[i].p, 2);
        assert_int_equal(m->edges[i].rational, 1);
        n++;
        cm_curve c;
        cm_model_edge_curve(m, i, &c);
        for (int k = 0; k <= 64; k++) {
            cm_vec3 x;
            assert_ok(cm_curve_eval(&c, k / 64.0, 0, &x, NULL));
            *worst = fmax(*worst, fabs(sqrt(x.x * x.x + x.y * x.y) - CYL_R));
        }
    }
    return n;
}

/*
 * Its two half circles go as arcs (two pieces each, A7.1's), on the circle within a sixteenth of
 * the tolerance (1e-3 of the model's diagonal at most), the file smaller than format 4.3's, which
 * sends them as rational NURBS; the 4.4 bytes read as 4.3 do not decode to the same edges.
 */
static void test_half_circles_as_arcs(void **state)
{
    (void)state;
    loaded_model lm;
    load_half_cylinder(&lm);
    encode_result r, r43;
    encode_for_minor(&lm, -1, &r);
    assert_int_equal(r.bytes[CM_HDR_MINOR], CM_FMT_VERSION_MINOR);
    assert_int_equal(r.edges_arcs, 2);
    cm_status st;
    assert_ok(decode(r.bytes, r.len, &st));
    double worst, diag = sqrt(4 * CYL_R * CYL_R + CYL_R * CYL_R + CYL_H * CYL_H);
    assert_int_equal(curved_edges(&dec.model, &worst), 2);
    for (uint32_t i = 0; i < dec.model.nedges; i++)
        if (dec.model.edges[i].kind == CM_EDGE_CURVE)
            assert_int_equal(dec.model.edges[i].nctrl, 5);
    if (!(worst <= 1e-3 * diag / 16))
        fail_msg("an arc %.3g mm off its circle", worst);
    encode_for_minor(&lm, (int)CM_FMT_PLACE_MINOR, &r43);
    assert_int_equal(r43.edges_arcs, 0);
    if (!(r.len < r43.len))
        fail_msg("4.4: %zu bytes, 4.3: %zu", r.len, r43.len);
    assert_ok(decode(r43.bytes, r43.len, &st));
    assert_int_equal(curved_edges(&dec.model, &worst), 2);
    /* the 4.4 file as a 4.3 writer would have labelled it: its arc bits are read as degrees */
    uint8_t *b = malloc(r.len);
    assert_non_null(b);
    memcpy(b, r.bytes, r.len);
    b[CM_HDR_MINOR] = (uint8_t)CM_FMT_PLACE_MINOR;
    uint32_t at = CM_FMT_COMPACT_AT_H;
    uint64_t H = 0;
    assert_true(cm_fmt_get_varint(b, (uint32_t)r.len, &at, &H));
    cm_put_u32(b + H - 4, cm_crc32(b, (size_t)H - 4));
    cm_put_u32(b + r.len - 4, cm_crc32(b, r.len - 4));
    cm_err e = decode(b, r.len, &st);
    if (e == CM_OK) {
        assert_int_equal(curved_edges(&dec.model, &worst), 2);
        assert_true(worst > 1e-3 * diag);
    }
    free(b);
    encode_result_free(&r);
    encode_result_free(&r43);
    model_free(&lm);
}

/*
 * A full cylinder (a line revolved by 2 pi, untrimmed: its loop two circles and the seam twice):
 * its circles go as full circles, and the band is rebuilt, not kept.  Its two circles run opposite
 * ways round the loop, so the loop has no mean normal; the encoder's reflex-corner test once read
 * one from rounding noise, and with the circles as arcs called the band reflex
 * (occt__OCC8842_cylinder_Ideas kept; enc_gregory.c, NO_SIDE_AREA).
 */
static void test_full_cylinder_band(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    int axis = igw_add(&w, 110, 0, "0,0,0,0,0,1");
    int gen = igw_add(&w, 110, 0, "%.17g,0,0,%.17g,0,%.17g", CYL_R, CYL_R, CYL_H);
    igw_add(&w, 120, 0, "%d,%d,0,%.17g", axis, gen, 2 * M_PI);
    loaded_model lm;
    cm_status st;
    assert_ok(igw_load(&w, "cylinder", &lm, &st));
    encode_result r;
    encode_for_minor(&lm, -1, &r);
    assert_int_equal(r.edges_arcs, 2);
    assert_int_equal(r.faces_by_method[CM_METHOD_KEEP], 0);
    assert_ok(decode(r.bytes, r.len, &st));
    double worst;
    assert_int_equal(curved_edges(&dec.model, &worst), 2);
    for (uint32_t i = 0; i < dec.model.nedges; i++)
        if (dec.model.edges[i].kind == CM_EDGE_CURVE)
            assert_int_equal(dec.model.edges[i].v0, dec.model.edges[i].v1);
    double diag = sqrt(4 * CYL_R * CYL_R * 2 + CYL_H * CYL_H);
    if (!(worst <= 1e-3 * diag / 16))
        fail_msg("a circle %.3g mm off", worst);
    encode_result_free(&r);
    model_free(&lm);
}

/* ---- what the encoder sends as an arc ---- */

#define ARC_R 10.0 /* the test curves' radius (mm) */

/* the rational quadratic of k pieces of 90 degrees on the circle of radius ARC_R about the origin
   in the plane z = 0, from angle 0 (A7.1's form) */
static void circle_nurbs(hcurve *c, int k)
{
    assert_ok(hcurve_alloc(c, 2, 2 * k + 1, 1, NULL));
    const double h = 0.70710678118654752440;
    for (int i = 0; i <= 2 * k; i++) {
        double a = i * M_PI / 4;
        c->ctrl[i] = i % 2 ? cm_v3(ARC_R * cos(a) / h, ARC_R * sin(a) / h, 0) : cm_v3(ARC_R * cos(a), ARC_R * sin(a), 0);
        c->w[i] = i % 2 ? h : 1.0;
    }
    for (int i = 0; i < 3; i++) {
        c->knots[i] = 0;
        c->knots[2 * k + 1 + i] = 1;
    }
    for (int i = 1; i < k; i++)
        c->knots[2 * i + 1] = c->knots[2 * i + 2] = (double)i / k;
    if (k == 4)
        c->ctrl[8] = c->ctrl[0]; /* closed, bit for bit */
}

/* a uniform cubic B-spline of n points on the quarter circle (a polynomial near it: within 3e-5 mm
   for n = 400), point `bump` moved outwards by `by` mm */
static void quarter_spline(hcurve *c, int n, int bump, double by)
{
    assert_ok(hcurve_alloc(c, 3, n, 0, NULL));
    for (int i = 0; i < n; i++) {
        double a = (M_PI / 2) * i / (n - 1), r = ARC_R + (i == bump ? by : 0.0);
        c->ctrl[i] = cm_v3(r * cos(a), r * sin(a), 0);
    }
    for (int i = 0; i < 4; i++) {
        c->knots[i] = 0;
        c->knots[n + i] = 1;
    }
    for (int j = 1; j < n - 3; j++)
        c->knots[3 + j] = (double)j / (n - 3);
}

/* tx_arc_edge on curve c alone (its ends the vertices, on a grid of 2^-16 mm about the origin),
   for a target board of `board_ctrl` control points an edge (0: none); the arc's points in *n */
static int arc_for(hcurve *c, unsigned board_ctrl, int *n)
{
    static cm_limit_info board[CM_LIMIT_COUNT];
    memcpy(board, cm_limit_table, sizeof board);
    board[CM_LIMIT_MAX_EDGE_CTRL].value = board_ctrl;
    encode_opts o;
    encode_opts_default(&o);
    o.target = board_ctrl ? board : NULL;
    tx t;
    memset(&t, 0, sizeof t);
    t.o = &o;
    t.q_exp = -16;
    t.q = ldexp(1.0, t.q_exp);
    int64_t vq[2][3];
    cm_vec3 ends[2] = {c->ctrl[0], c->ctrl[c->n - 1]};
    for (int v = 0; v < 2; v++) {
        vq[v][0] = llround(ends[v].x / t.q);
        vq[v][1] = llround(ends[v].y / t.q);
        vq[v][2] = llround(ends[v].z / t.q);
    }
    t.vq = vq;
    t.nverts = 2;
    tx_edge A;
    memset(&A, 0, sizeof A);
    A.v0 = 0;
    A.v1 = memcmp(&ends[0], &ends[1], sizeof ends[0]) == 0 ? 0 : 1; /* a closed edge: one vertex */
    int ok = tx_arc_edge(&t, c, 0, &A);
    *n = A.n;
    if (ok) {
        assert_int_equal(A.arc, 1);
        assert_int_equal(A.kind, CM_EDGE_CURVE);
        assert_true(A.step > 0); /* on a step of the budget's, not the grid */
    }
    hcurve_free(c);
    return ok;
}

/*
 * Arcs of one, two and three quarters and full circles, rational or a dense polynomial near the
 * circle, go as arcs (of 3 and 9 points); a board of 8 points an edge (the tiny profile) takes the
 * quarter but not the three quarters.  Curves that nearly are arcs are turned back: a quarter and a
 * full ellipse (a tenth flatter),
 * an S, and a dense spline of 4000 points with one moved 0.05 mm out: a spike 0.033 mm high (four
 * times the curves' share of the tolerance) over 0.016 mm of its length, between two of the
 * samples a check at 65 even parameters takes, narrower than twice the share (so that no point of
 * the arc is farther from the spline than that): such a check, tried, let it through.
 */
static void test_arc_choice(void **state)
{
    (void)state;
    hcurve c = {0};
    int n;
    circle_nurbs(&c, 1);
    assert_true(arc_for(&c, 0, &n));
    assert_int_equal(n, 3);
    circle_nurbs(&c, 3);
    assert_true(arc_for(&c, 0, &n));
    assert_int_equal(n, 9);
    circle_nurbs(&c, 3);
    assert_false(arc_for(&c, 8, &n));
    circle_nurbs(&c, 4); /* a full circle, closed */
    assert_true(arc_for(&c, 0, &n));
    assert_int_equal(n, 9);
    circle_nurbs(&c, 4);
    for (int i = 0; i < 9; i++)
        c.ctrl[i].y *= 0.9;
    assert_false(arc_for(&c, 0, &n));
    circle_nurbs(&c, 1);
    assert_true(arc_for(&c, 8, &n));
    quarter_spline(&c, 400, -1, 0);
    assert_true(arc_for(&c, 0, &n));
    quarter_spline(&c, 4000, 640, 0.05); /* support [637/3997, 641/3997], between 10/64 and 11/64 */
    assert_false(arc_for(&c, 0, &n));
    circle_nurbs(&c, 1);
    for (int i = 0; i < 3; i++)
        c.ctrl[i].y *= 0.9;
    assert_false(arc_for(&c, 0, &n));
    assert_ok(hcurve_alloc(&c, 3, 4, 0, NULL));
    const cm_vec3 S[4] = {{0, 0, 0}, {3, 3, 0}, {7, -3, 0}, {10, 0, 0}};
    for (int i = 0; i < 4; i++) {
        c.ctrl[i] = S[i];
        c.knots[i] = 0;
        c.knots[4 + i] = 1;
    }
    assert_false(arc_for(&c, 0, &n));
}

/* ---- arc records as a writer could send them ---- */

/* one arc record's fields: where its vertices are referenced from, its step and its residual */
typedef struct arc_edit {
    int far_on_vertex; /* the first circle's far point on its vertex */
    uint64_t step;     /* every arc's step exponent */
    int64_t add;       /* added to the first arc's residual, coordinate y */
    int cut;           /* the stream ends after the first arc's arc bit */
} arc_edit;

static void put_vref(cm_ac_enc *e, cm_edge_ctx *c, uint32_t *next, uint32_t v)
{
    cm_ac_enc_bit(e, &c->is_new, v == *next);
    if (v == *next)
        (*next)++;
    else
        cm_ac_enc_uint(e, &c->back, (uint64_t)(*next - 1 - v));
}

/* the EDGE section of the model decoded last into dec (lines, arcs and full circles only) coded
   again, each point on the grid at its step, with the edit; returns its length */
static size_t edge_section(uint8_t *buf, size_t cap, const arc_edit *ed)
{
    const cm_model *m = &dec.model;
    cm_ac_enc e;
    cm_ac_enc_init(&e, buf, cap);
    cm_edge_ctx c;
    cm_edge_ctx_init(&c);
    cm_ac_enc_uint(&e, &c.count, m->nedges);
    uint32_t next = 0;
    int first = 1;
    for (uint32_t i = 0; i < m->nedges; i++) {
        const cm_edge *E = &m->edges[i];
        int arc = E->kind == CM_EDGE_CURVE, edit = arc && first;
        put_vref(&e, &c, &next, (uint32_t)E->v0);
        put_vref(&e, &c, &next, (uint32_t)E->v1);
        cm_ac_enc_bit(&e, &c.g1, E->g1);
        cm_ac_enc_bit(&e, &c.kind, E->kind);
        if (!arc)
            continue;
        cm_ac_enc_bit(&e, &c.arc, 1);
        if (edit && ed->cut)
            break;
        cm_ac_enc_uint(&e, &c.arc_step, ed->step);
        /* an arc's middle point (t = 1/2); a circle's far point (1/2), then its halfway point (1/4) */
        cm_curve cv;
        cm_model_edge_curve(m, i, &cv);
        int closed = E->v0 == E->v1;
        cm_vec3 pt[2];
        assert_ok(cm_curve_eval(&cv, 0.5, 0, &pt[0], NULL));
        assert_ok(cm_curve_eval(&cv, 0.25, 0, &pt[1], NULL));
        int64_t g[2][3];
        for (int j = 0; j < 2; j++) {
            double xyz[3] = {pt[j].x, pt[j].y, pt[j].z};
            for (int k = 0; k < 3; k++)
                g[j][k] = llround((xyz[k] - m->origin[k]) / m->q);
        }
        if (edit && ed->far_on_vertex)
            memcpy(g[0], dec.vq[E->v0], sizeof g[0]);
        for (int j = 0; j < (closed ? 2 : 1); j++)
            for (int k = 0; k < 3; k++) {
                int64_t pred = !closed ? cm_pred_arc_mid(dec.vq[E->v0][k], dec.vq[E->v1][k])
                                       : (j == 0 ? dec.vq[E->v0][k] : cm_pred_arc_mid(dec.vq[E->v0][k], g[0][k]));
                int64_t res = (g[j][k] - pred) >> ed->step;
                cm_ac_enc_sint(&e, &c.arc_coord[k], res + (edit && j == 0 && k == 1 ? ed->add : 0));
            }
        first = 0;
    }
    size_t n = cm_ac_enc_finish_trimmed(&e);
    assert_false(e.overflow);
    return n;
}

static void assert_refused(const encode_result *r, const arc_edit *ed, cm_err code, const char *cause)
{
    static uint8_t sec[1 << 16];
    cm_status st;
    assert_ok(decode(r->bytes, r->len, &st)); /* the model the section is coded from */
    size_t n = edge_section(sec, sizeof sec, ed);
    const char *why = cmz_section_refused(&dec, r, CM_SEC_EDGE, sec, n, code, cause);
    if (why)
        fail_msg("%s", why);
}

/* model lm encoded, its EDGE section coded again here as the encoder meant it (every point on the
   grid itself): decoded, the same curves bit for bit */
static void recoded_the_same(loaded_model *lm, encode_result *r)
{
    /* format 4.4: the records are 4.4's, and the decoder's grid vertices (dec.vq, which this coder
       predicts from) outlast the decode only up to 4.4 (from 4.5 FACE reuses their storage) */
    encode_for_minor(lm, (int)CM_FMT_ARC_MINOR, r);
    assert_true(r->edges_arcs >= 1);
    cm_status st;
    assert_ok(decode(r->bytes, r->len, &st));
    static cm_vec3 ctrl[CM_MAX_MODEL_CTRL];
    static double w[CM_MAX_MODEL_CTRL];
    uint32_t nctrl = dec.model.nctrl;
    memcpy(ctrl, dec.model.ctrl, nctrl * sizeof *ctrl);
    memcpy(w, dec.model.w, nctrl * sizeof *w);
    static uint8_t sec[1 << 16];
    arc_edit same = {0};
    size_t n = edge_section(sec, sizeof sec, &same), len;
    uint8_t *b = cmz_with_section(r, CM_SEC_EDGE, sec, n, &len);
    assert_non_null(b);
    assert_ok(decode(b, len, &st));
    assert_int_equal(dec.model.nctrl, nctrl);
    assert_memory_equal(dec.model.ctrl, ctrl, nctrl * sizeof *ctrl);
    assert_memory_equal(dec.model.w, w, nctrl * sizeof *w);
    free(b);
}

/*
 * The half cylinder's and a disc's EDGE sections coded again here: as the encoder meant them, they
 * decode to the same curves bit for bit; then each field out of what the decoder takes: a middle
 * point that makes a full circle of a short chord or lies beyond the grid, a step beyond 24, a
 * stream that ends inside the record, a circle whose far point is its vertex.
 */
static void test_arc_records_refused(void **state)
{
    (void)state;
    loaded_model lm;
    load_half_cylinder(&lm);
    encode_result r;
    recoded_the_same(&lm, &r);
    arc_edit full = {.add = (int64_t)1 << 30}; /* the coder carries up to 2^33 - 1 */
    assert_refused(&r, &full, CM_E_DEGENERATE, "arc of a full circle");
    arc_edit far = {.step = CM_FMT_MAX_STEP, .add = (int64_t)1 << 30};
    assert_refused(&r, &far, CM_E_RANGE, "arc middle point");
    arc_edit step = {.step = CM_FMT_MAX_STEP + 1};
    assert_refused(&r, &step, CM_E_RANGE, "arc step");
    arc_edit cut = {.cut = 1};
    /* a trimmed stream reads as zeros for a few fields past its end (cm_arith.h): truncated where
       the reader runs out, a field or a few later */
    assert_refused(&r, &cut, CM_E_TRUNCATED, "");
    encode_result_free(&r);
    model_free(&lm);

    igw w;
    igw_init(&w);
    assert_true(igw_disc_144(&w, 20.0, 3.0) > 0);
    cm_status st;
    assert_ok(igw_load(&w, "disc", &lm, &st));
    recoded_the_same(&lm, &r);
    assert_int_equal(dec.model.edges[0].v0, dec.model.edges[0].v1);
    assert_int_equal(dec.model.edges[0].nctrl, 9);
    arc_edit on_vertex = {.far_on_vertex = 1};
    assert_refused(&r, &on_vertex, CM_E_DEGENERATE, "circle whose far point is its vertex");
    arc_edit far_circle = {.step = CM_FMT_MAX_STEP, .add = (int64_t)1 << 30};
    assert_refused(&r, &far_circle, CM_E_RANGE, "circle's far point");
    encode_result_free(&r);
    model_free(&lm);
}

/* ---- kept surfaces ruled between two arcs ---- */

static void encode_kept(loaded_model *lm, int minor, encode_result *r)
{
    encode_opts o;
    encode_opts_default(&o);
    if (minor >= 0)
        encode_opts_for_format(&o, 4, minor);
    o.gregory = o.g1fit = o.nfill = 0; /* planes only: the curved faces are kept */
    cm_status st;
    cm_status_init(&st);
    memset(r, 0, sizeof *r);
    assert_ok(encode_model(lm, &o, r, &st));
}

/* the farthest (mm) any of 17 x 17 points of kept surface s lies off the cylinder of radius CYL_R
   about the z axis */
static double off_cylinder(const cm_model *m, uint32_t s)
{
    cm_surf sv;
    cm_model_surface(m, s, &sv);
    double worst = 0;
    for (int i = 0; i <= 16; i++)
        for (int j = 0; j <= 16; j++) {
            cm_vec3 d[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
            assert_ok(cm_surf_eval(&sv, i / 16.0, j / 16.0, 0, d, NULL));
            worst = fmax(worst, fabs(hypot(d[0][0].x, d[0][0].y) - CYL_R));
        }
    return worst;
}

/*
 * Kept cylinders go ruled between their arcs: the half cylinder of revolution (its arcs along v)
 * and the full one (full circles along v): the terminal's surface is the source's net in form (the
 * same directions, degree 2 along the arcs, 1 across), on the cylinder within two grid steps, the
 * file smaller than 4.3's net.
 */
static void test_kept_cylinders_ruled(void **state)
{
    (void)state;
    for (int full = 0; full < 2; full++) {
        igw w;
        igw_init(&w);
        int axis = igw_add(&w, 110, 0, "0,0,0,0,0,1");
        int gen = igw_add(&w, 110, 0, "%.17g,0,0,%.17g,0,%.17g", CYL_R, CYL_R, CYL_H);
        igw_add(&w, 120, 0, "%d,%d,0,%.17g", axis, gen, full ? 2 * M_PI : M_PI);
        loaded_model lm;
        cm_status st;
        assert_ok(igw_load(&w, "cylinder", &lm, &st));
        encode_result r, r43;
        encode_kept(&lm, -1, &r);
        encode_kept(&lm, (int)CM_FMT_PLACE_MINOR, &r43);
        assert_int_equal(r.faces_by_method[CM_METHOD_KEEP], 1);
        if (!(r.len + 20 < r43.len))
            fail_msg("%s cylinder kept ruled: %zu bytes, as a net (4.3): %zu", full ? "full" : "half", r.len, r43.len);
        assert_ok(decode(r.bytes, r.len, &st));
        const cm_ksurf *S = &dec.model.surfs[0];
        assert_int_equal(dec.model.nsurfs, 1);
        assert_int_equal(S->p, 1); /* a line revolved: v along the arcs, as the source */
        assert_int_equal(S->q, 2);
        assert_int_equal(S->nu, 2);
        assert_int_equal(S->nv, full ? 9 : 5);
        double off = off_cylinder(&dec.model, 0);
        if (!(off <= 2.0 * dec.model.q))
            fail_msg("the ruled cylinder %.3g grid steps off", off / dec.model.q);
        encode_result_free(&r);
        encode_result_free(&r43);
        model_free(&lm);
    }
}

/* one kept ruled surface's record as a writer could send it: the decoded model's two arcs again,
   the second row's middle point pulled towards its chord by `flatten` (0: as it was) */
static size_t ruled_section(uint8_t *buf, size_t cap, double flatten)
{
    const cm_model *m = &dec.model;
    const cm_ksurf *S = &m->surfs[0];
    cm_surf sv;
    cm_model_surface(m, 0, &sv);
    int along_v = S->p == 1;
    int64_t pt[2][3][3];
    for (int row = 0; row < 2; row++) {
        /* first point, end, middle */
        const double at[3] = {0.0, 1.0, 0.5};
        for (int j = 0; j < 3; j++) {
            cm_vec3 d[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
            assert_ok(cm_surf_eval(&sv, along_v ? row : at[j], along_v ? at[j] : row, 0, d, NULL));
            double xyz[3] = {d[0][0].x, d[0][0].y, d[0][0].z};
            for (int k = 0; k < 3; k++)
                pt[row][j][k] = llround((xyz[k] - m->origin[k]) / m->q);
        }
    }
    for (int k = 0; k < 3 && flatten > 0; k++) {
        int64_t mid = cm_pred_arc_mid(pt[1][0][k], pt[1][1][k]);
        pt[1][2][k] = mid + (int64_t)((double)(pt[1][2][k] - mid) * (1.0 - flatten));
    }
    cm_ac_enc e;
    cm_ac_enc_init(&e, buf, cap);
    cm_surf_ctx c;
    cm_surf_ctx_init(&c);
    cm_ac_enc_uint(&e, &c.count, 1);
    cm_ac_enc_bit(&e, &c.ruled, 1);
    cm_ac_enc_bit(&e, &c.closed, 0);
    cm_ac_enc_bit(&e, &c.along_v, (unsigned)along_v);
    cm_ac_enc_uint(&e, &c.ruled_step, 0);
    for (int row = 0; row < 2; row++)
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++)
                cm_ac_enc_sint(&e, &c.ruled_coord[k], pt[row][j][k] - cm_pred_ruled((const int64_t(*)[3][3])pt, row, j, k));
    size_t n = cm_ac_enc_finish_trimmed(&e);
    assert_false(e.overflow);
    return n;
}

/* The kept half cylinder's SURF section coded again here decodes to the same net bit for bit; with
   its second arc flattened to a single piece (the first has two), it is refused by name. */
static void test_ruled_records_refused(void **state)
{
    (void)state;
    loaded_model lm;
    load_half_cylinder(&lm);
    encode_result r;
    /* format 4.5: a section of its own stream can be replaced (4.6's five are one stream) */
    encode_kept(&lm, (int)CM_FMT_USE_ADJ_MINOR, &r);
    cm_status st;
    assert_ok(decode(r.bytes, r.len, &st));
    static cm_vec3 ctrl[CM_MAX_MODEL_CTRL];
    static double w[CM_MAX_MODEL_CTRL];
    uint32_t c0 = dec.model.surfs[0].ctrl0, nc = (uint32_t)dec.model.surfs[0].nu * dec.model.surfs[0].nv;
    memcpy(ctrl, dec.model.ctrl + c0, nc * sizeof *ctrl);
    memcpy(w, dec.model.w + c0, nc * sizeof *w);
    static uint8_t sec[1 << 12];
    size_t n = ruled_section(sec, sizeof sec, 0), len;
    uint8_t *b = cmz_with_section(&r, CM_SEC_SURF, sec, n, &len);
    assert_ok(decode(b, len, &st));
    assert_memory_equal(dec.model.ctrl + dec.model.surfs[0].ctrl0, ctrl, nc * sizeof *ctrl);
    assert_memory_equal(dec.model.w + dec.model.surfs[0].ctrl0, w, nc * sizeof *w);
    free(b);
    assert_ok(decode(r.bytes, r.len, &st));
    n = ruled_section(sec, sizeof sec, 0.8);
    b = cmz_with_section(&r, CM_SEC_SURF, sec, n, &len);
    assert_int_equal(decode(b, len, &st), CM_E_FORMAT);
    assert_string_equal(st.where, "ruled surface's arcs of different pieces");
    free(b);
    encode_result_free(&r);
    model_free(&lm);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_half_circles_as_arcs),
        cmocka_unit_test(test_full_cylinder_band),
        cmocka_unit_test(test_arc_choice),
        cmocka_unit_test(test_kept_cylinders_ruled),
        cmocka_unit_test(test_ruled_records_refused),
        cmocka_unit_test(test_arc_records_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
