/*
 * test_format3.c - format 3's predicted coding of curves, knots and kept surfaces (cm_predict.h,
 * docs/FORMAT.md): synthetic IGES -> encoder -> .cmz as format 3 and as format 2 -> the terminal's
 * decoder.  Both files must decode to the same model (vertices, knots and weights bit for bit; the
 * control points that format 3 sends on a coarser step of their own within its budget, tx_coarsen.c),
 * the format 3 file must not be the larger, and a format 3 file whose numbers leave their range (a
 * knot gap below zero, a weight at zero, a step too large) is refused by name.  The predictions themselves are checked exactly on the sequences they are made for.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "cm/cm_arith.h"
#include "cm/cm_crc32.h"
#include "cm/cm_decode.h"
#include "cm/cm_predict.h"
#include "cm/cm_sections.h"
#include "encode/encode.h"
#include "encode/encode_internal.h"
#include "igs_writer.h"
#include "model_load.h"

static cm_decoder dec2, dec3;

/* ---- the predictions, exactly ---- */

/* evenly spaced points are predicted exactly by the line, from the chord for the first; a circle's
   weights 1, w, 1, w, ... by the weight two places before */
static void test_predictions_exact(void **state)
{
    (void)state;
    const int n = 7;
    int64_t x[7];
    for (int j = 0; j < n; j++)
        x[j] = -300 + 1000 * j;
    for (int j = 1; j < n - 1; j++) {
        assert_true(cm_pred_ctrl(1, j, n, x[0], x[n - 1], x[j - 1], j >= 2 ? x[j - 2] : 0) == x[j]);
        assert_true(cm_pred_ctrl(0, j, n, x[0], x[n - 1], x[j - 1], 12345) == x[j - 1]);
    }
    const int64_t w[5] = {1 << 24, 11863283, 1 << 24, 11863283, 1 << 24};
    for (int j = 2; j < 5; j++)
        assert_true(cm_pred_weight(j, w[j - 1], w[j - 2]) == w[j]);
    assert_true(cm_pred_weight(1, w[0], 0) == w[0]);
    /* a net whose second differences across both directions vanish (quadratic in i along a line
       in j and back: i^2 j, i j^2, ...) is predicted exactly by the quadratic predictor from (2, 2)
       on; one whose mixed first difference vanishes (a sum f(i) + g(j), a translational surface)
       by the parallelogram from (1, 1) on */
    enum { NU = 5, NV = 6 };
    int64_t quad[NU * NV][3], bil[NU * NV][3];
    for (int i = 0; i < NU; i++)
        for (int j = 0; j < NV; j++)
            for (int k = 0; k < 3; k++) {
                quad[i * NV + j][k] = 7 * i * i - 3 * j * j + 5 * i * j * (k + 1) + 11 * i * i * j - 6 * i * j * j - 2 * k;
                bil[i * NV + j][k] = 100 + 9 * i * i - 4 * j * j * j + (k + 2) * i;
            }
    for (int i = 0; i < NU; i++)
        for (int j = 0; j < NV; j++)
            for (int k = 0; k < 3; k++) {
                if (i >= 2 && j >= 2)
                    assert_true(cm_pred_net(1, (const int64_t(*)[3])quad, NV, i, j, k) == quad[i * NV + j][k]);
                if (i >= 1 && j >= 1)
                    assert_true(cm_pred_net(0, (const int64_t(*)[3])bil, NV, i, j, k) == bil[i * NV + j][k]);
            }
    /* the first row of the quadratic predictor continues the line, the parallelogram's repeats */
    assert_true(cm_pred_net(1, (const int64_t(*)[3])bil, NV, 0, 3, 0) == 2 * bil[2][0] - bil[1][0]);
    assert_true(cm_pred_net(0, (const int64_t(*)[3])bil, NV, 0, 3, 0) == bil[2][0]);
    assert_true(cm_pred_net(1, (const int64_t(*)[3])bil, NV, 0, 0, 0) == 0);
}

/* ---- the same model both ways ---- */

/* lm encoded for format major.minor (major 0: the default, format 4), with or without the budget
   steps, GREGORY and its kin (gregory 0: planes only) and, rel > 0, --tol rel */
static void encode_with(loaded_model *lm, int major, int minor, int budget, int gregory, double rel, encode_result *r)
{
    encode_opts o;
    encode_opts_default(&o);
    if (major)
        encode_opts_for_format(&o, major, minor);
    o.budget_steps = budget;
    if (rel > 0) {
        o.rel_tol = rel;
        o.rel_set = 1;
    }
    if (!gregory) {
        o.gregory = 0;
        o.g1fit = 0;
        o.nfill = 0;
    }
    cm_status st;
    cm_status_init(&st);
    memset(r, 0, sizeof *r);
    assert_ok(encode_model(lm, &o, r, &st));
}

/* predicted: 0 format 2.6, 1 format 3 (the default's coding, its header format 3's), 2 format 3
   with --budget-steps (format 4's compact header is test_format4.c's) */
static void encode_as(loaded_model *lm, int predicted, int gregory, encode_result *r)
{
    encode_with(lm, predicted ? CM_FMT_PREDICT_MAJOR : 2, predicted ? 0 : CM_FMT_V2_MINOR, predicted == 2, gregory, 0.0,
                r);
}

static void decode_into(cm_decoder *d, const uint8_t *b, size_t len)
{
    cm_status st;
    cm_status_init(&st);
    cm_dec_init(d);
    assert_ok(cm_dec_feed(d, b, len, &st));
    assert_ok(cm_dec_finish(d, &st));
}

static int same_doubles(const double *a, const double *b, uint32_t n)
{
    return memcmp(a, b, n * sizeof *a) == 0;
}

/* what the two files are made of, counted over the format 3 model, so that a test model that no
   longer reaches a prediction or a coarser step is seen */
typedef struct reach {
    int curves, rational, repeated_knot, surfaces;
    int moved_edge_points, moved_net_points; /* points format 3 sent on a step of their own */
    int moved_vertices;
    double worst_move;                       /* mm */
} reach;

static double point_move(cm_vec3 p, cm_vec3 q)
{
    return sqrt((p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) + (p.z - q.z) * (p.z - q.z));
}

/* points p and q (n of them, of `what` number `which`) within `move` mm of each other: how many moved */
static int moved_points(const cm_vec3 *p, const cm_vec3 *q, uint32_t n, double move, const char *what, uint32_t which,
                        reach *seen)
{
    int moved = 0;
    for (uint32_t j = 0; j < n; j++) {
        double d = point_move(p[j], q[j]);
        if (!(d <= move))
            fail_msg("%s %u point %u moved %.3g mm (allowed %.3g)", what, which, j, d, move);
        moved += d > 0;
        seen->worst_move = fmax(seen->worst_move, d);
    }
    return moved;
}

/* a and b hold the same model, control points within `move` mm of each other (0: bit for bit):
   every vertex, edge curve (degree, knots, ends, weights), kept surface (sizes, knots, weights) and
   face method equal */
static void assert_same_model(const cm_model *a, const cm_model *b, double move, reach *seen)
{
    assert_int_equal(a->nverts, b->nverts);
    assert_int_equal(a->nedges, b->nedges);
    assert_int_equal(a->nfaces, b->nfaces);
    assert_int_equal(a->nsurfs, b->nsurfs);
    seen->moved_vertices += moved_points(a->verts, b->verts, a->nverts, move, "vertices", 0, seen);
    for (uint32_t i = 0; i < a->nedges; i++) {
        const cm_edge *x = &a->edges[i], *y = &b->edges[i];
        assert_int_equal(x->kind, y->kind);
        assert_int_equal(x->p, y->p);
        assert_int_equal(x->nctrl, y->nctrl);
        assert_int_equal(x->rational, y->rational);
        assert_true(same_doubles(a->knots + x->knot0, b->knots + y->knot0, (uint32_t)(x->nctrl + x->p + 1)));
        seen->moved_edge_points += moved_points(a->ctrl + x->ctrl0, b->ctrl + y->ctrl0, x->nctrl, move, "edge", i, seen);
        /* its ends are its vertices, exactly */
        assert_true(memcmp(&a->ctrl[x->ctrl0], &a->verts[x->v0], sizeof(cm_vec3)) == 0);
        assert_true(memcmp(&a->ctrl[x->ctrl0 + x->nctrl - 1u], &a->verts[x->v1], sizeof(cm_vec3)) == 0);
        assert_true(same_doubles(a->w + x->ctrl0, b->w + y->ctrl0, x->nctrl));
        if (x->kind == CM_EDGE_CURVE) {
            seen->curves++;
            seen->rational += x->rational;
            const double *K = a->knots + x->knot0;
            for (int j = x->p + 1; j < x->nctrl; j++)
                seen->repeated_knot += K[j] == K[j + 1] && K[j] < 1.0;
        }
    }
    for (uint32_t s = 0; s < a->nsurfs; s++) {
        const cm_ksurf *x = &a->surfs[s], *y = &b->surfs[s];
        assert_int_equal(x->nu, y->nu);
        assert_int_equal(x->nv, y->nv);
        assert_int_equal(x->p, y->p);
        assert_int_equal(x->q, y->q);
        assert_true(same_doubles(a->knots + x->uknot0, b->knots + y->uknot0, (uint32_t)(x->nu + x->p + 1)));
        assert_true(same_doubles(a->knots + x->vknot0, b->knots + y->vknot0, (uint32_t)(x->nv + x->q + 1)));
        uint32_t n = (uint32_t)x->nu * x->nv;
        seen->moved_net_points += moved_points(a->ctrl + x->ctrl0, b->ctrl + y->ctrl0, n, move, "surface", s, seen);
        assert_true(same_doubles(a->w + x->ctrl0, b->w + y->ctrl0, n));
        seen->surfaces++;
    }
    int kept = 0;
    for (uint32_t f = 0; f < a->nfaces; f++) {
        assert_int_equal(a->faces[f].method, b->faces[f].method);
        if (move == 0)
            assert_int_equal(a->faces[f].checksum, b->faces[f].checksum);
        if (a->faces[f].method != CM_METHOD_KEEP)
            continue;
        /* a kept face is tessellated on its own surface: its edges stay on the grid (tx_coarsen.c,
           enc_keep_fine_edges), and so do the vertices */
        kept = 1;
        const cm_face *F = &a->faces[f];
        for (uint32_t l = 0; l < F->nloops; l++) {
            const cm_loop *L = &a->loops[F->loop0 + l];
            for (uint32_t u = 0; u < L->nuse; u++) {
                const cm_edge *x = &a->edges[a->uses[L->use0 + u].edge], *y = &b->edges[a->uses[L->use0 + u].edge];
                assert_true(memcmp(a->ctrl + x->ctrl0, b->ctrl + y->ctrl0, x->nctrl * sizeof *a->ctrl) == 0);
            }
        }
    }
    if (kept)
        assert_true(memcmp(a->verts, b->verts, a->nverts * sizeof *a->verts) == 0);
}

/* lm encoded as format 2.x and as 3.0 (gregory: as encode_as) decodes to the same model, bit for
   bit; with --budget-steps the control points of format 3 within its budget (tx_coarsen.c: a sixteenth of the tolerance, which is
   at most 1e-3 of the model's diagonal by default); the 3.0 file is not the larger */
static void check_both_ways(loaded_model *lm, int gregory, reach *seen)
{
    encode_result r2, r3;
    encode_as(lm, 0, gregory, &r2);
    /* the default: the same numbers as format 2, coded otherwise */
    encode_as(lm, 1, gregory, &r3);
    decode_into(&dec2, r2.bytes, r2.len);
    decode_into(&dec3, r3.bytes, r3.len);
    reach same = {0};
    assert_same_model(&dec3.model, &dec2.model, 0, &same);
    assert_true(same.moved_vertices == 0 && same.moved_edge_points == 0 && same.moved_net_points == 0);
    if (!(r3.len <= r2.len))
        fail_msg("format 3: %zu bytes, format 2: %zu", r3.len, r2.len);
    encode_result_free(&r3);
    /* --budget-steps: points moved within their budget */
    encode_as(lm, 2, gregory, &r3);
    assert_int_equal(r2.bytes[CM_HDR_MAJOR] <= 2, 1);
    assert_int_equal(r3.bytes[CM_HDR_MAJOR], CM_FMT_PREDICT_MAJOR);
    assert_int_equal(r3.bytes[CM_HDR_MINOR], 0);
    decode_into(&dec2, r2.bytes, r2.len);
    decode_into(&dec3, r3.bytes, r3.len);
    assert_int_equal(dec3.model.predicted, 1);
    assert_int_equal(dec2.model.predicted, 0);
    assert_same_model(&dec3.model, &dec2.model, 1e-3 * brep_diag(&lm->brep) / 16.0, seen);
    if (!(r3.len <= r2.len))
        fail_msg("format 3: %zu bytes, format 2: %zu", r3.len, r2.len);
    encode_result_free(&r2);
    encode_result_free(&r3);
}

static void load(igw *w, const char *name, loaded_model *lm)
{
    cm_status st;
    cm_status_init(&st);
    assert_ok(igw_load(w, name, lm, &st));
}

/*
 * Rebuilt faces over rational half circles (a half cylinder, its split twin, a dome band), and
 * the same models with their surfaces kept (a surface of revolution's net, a bicubic B-spline):
 * every prediction is reached, and the files shrink.
 */
static void test_same_model_smaller_file(void **state)
{
    (void)state;
    reach seen = {0};
    loaded_model lm;
    igw w;
    for (int gregory = 1; gregory >= 0; gregory--) {
        igw_init(&w);
        igw_half_cylinder_120(&w, 10.0, 20.0);
        load(&w, "half-cylinder", &lm);
        check_both_ways(&lm, gregory, &seen);
        model_free(&lm);
        igw_init(&w);
        igw_split_half_cylinder_144(&w, 10.0, 20.0);
        load(&w, "split-cylinder", &lm);
        check_both_ways(&lm, gregory, &seen);
        model_free(&lm);
        igw_init(&w);
        igw_half_dome_band_144(&w, 8.0, 16.0);
        load(&w, "half-dome-band", &lm);
        check_both_ways(&lm, gregory, &seen);
        model_free(&lm);
    }
    igw_init(&w);
    igw_bicubic_128(&w);
    load(&w, "bicubic", &lm);
    check_both_ways(&lm, 0, &seen);
    model_free(&lm);
    print_message("format 3: %d curves (%d rational), %d repeated knots, %d kept surfaces compared; %d vertices, "
                  "%d edge and %d net points on a coarser step, moved at most %.3g mm\n",
                  seen.curves, seen.rational, seen.repeated_knot, seen.surfaces, seen.moved_vertices,
                  seen.moved_edge_points, seen.moved_net_points, seen.worst_move);
    assert_true(seen.rational > 0);
    assert_true(seen.repeated_knot > 0);
    assert_true(seen.surfaces > 0);
    assert_true(seen.moved_edge_points > 0);
    assert_true(seen.moved_net_points == 0); /* kept nets stay on the grid (tx_net_predictor) */
    assert_true(seen.moved_vertices > 0);
}

/* ---- format 3 EDGE sections written here, valid and hostile ---- */

/* a grid coordinate or a fixed-point number of the decoded model as its integer (exact) */
static int64_t grid_int(const cm_model *m, int k, double v)
{
    double x = (v - m->origin[k]) / m->q;
    int64_t g = llround(x);
    assert_true((double)g == x);
    return g;
}

static int64_t fixed(double v, int bits)
{
    int64_t k = llround(ldexp(v, bits));
    assert_true(ldexp((double)k, -bits) == v);
    return k;
}

/* what write_edges spoils: nothing, one knot gap below zero, one weight at zero, one curve's step past
   2^CM_FMT_MAX_STEP.  (A coordinate
   cannot be driven past the grid's range by a few points: a residual has at most 33 bits, the range
   is 2^40; the reader checks every point against it, so the line's 2 prev - prev2 stays in 2^42.) */
enum spoil { SPOIL_NONE, SPOIL_KNOT, SPOIL_WEIGHT, SPOIL_STEP };

/*
 * m's EDGE section in format 3's coding, with every curve on the line predictor (the encoder picks
 * per curve; either is a valid file) and every knot vector sent gap by gap (never "uniform"), so that
 * each prediction of the reader is reached whatever the encoder chose; `spoil` breaks the first
 * curve that can carry it.  Returns the section's length in buf.
 */
static size_t write_edges(const cm_model *m, enum spoil spoil, uint8_t *buf, size_t cap)
{
    cm_ac_enc e;
    cm_ac_enc_init(&e, buf, cap);
    cm_edge_ctx c;
    cm_edge_ctx_init(&c);
    cm_ac_enc_uint(&e, &c.count, m->nedges);
    uint32_t vnext = 0;
    for (uint32_t i = 0; i < m->nedges; i++) {
        const cm_edge *E = &m->edges[i];
        for (int end = 0; end < 2; end++) {
            uint32_t v = (uint32_t)(end ? E->v1 : E->v0);
            cm_ac_enc_bit(&e, &c.is_new, v == vnext);
            if (v == vnext)
                vnext++;
            else
                cm_ac_enc_uint(&e, &c.back, vnext - 1 - v);
        }
        cm_ac_enc_bit(&e, &c.g1, E->g1);
        cm_ac_enc_bit(&e, &c.kind, E->kind);
        if (E->kind == CM_EDGE_LINE)
            continue;
        int p = E->p, n = E->nctrl, interior = n - p - 1;
        cm_ac_enc_uint(&e, &c.degree, (uint64_t)(p - 1));
        cm_ac_enc_uint(&e, &c.ncoef, (uint64_t)interior);
        cm_ac_enc_bit(&e, &c.rational, E->rational);
        cm_ac_enc_bit(&e, &c.uniform, 0);
        const double *K = m->knots + E->knot0;
        int64_t prev = 0, last_gap = 0;
        for (int j = 1; j <= interior; j++) {
            int64_t gap = fixed(K[p + j], CM_FMT_KNOT_BITS) - prev;
            prev += gap;
            if (j == 1) {
                cm_ac_enc_uint(&e, &c.knot, (uint64_t)gap);
            } else if (spoil == SPOIL_KNOT) { /* a gap of -1 */
                cm_ac_enc_bit(&e, &c.knot_zero, 0);
                cm_ac_enc_sint(&e, &c.knot_delta, -1 - last_gap);
                spoil = SPOIL_NONE;
            } else {
                cm_ac_enc_bit(&e, &c.knot_zero, gap == 0);
                if (gap)
                    cm_ac_enc_sint(&e, &c.knot_delta, gap - last_gap);
            }
            if (gap)
                last_gap = gap;
        }
        const cm_vec3 *P = m->ctrl + E->ctrl0;
        if (n > 2) {
            cm_ac_enc_bit(&e, &c.linear, 1);
            cm_ac_enc_uint(&e, &c.step, spoil == SPOIL_STEP ? CM_FMT_MAX_STEP + 1 : 0); /* the points as they are */
            if (spoil == SPOIL_STEP)
                spoil = SPOIL_NONE;
        }
        for (int j = 1; j < n - 1; j++)
            for (int k = 0; k < 3; k++) {
                int64_t g[4];
                const double *pk[4] = {&P[0].x, &P[n - 1].x, &P[j - 1].x, &P[j >= 2 ? j - 2 : 0].x};
                for (int a = 0; a < 4; a++)
                    g[a] = grid_int(m, k, pk[a][k]);
                cm_ac_enc_sint(&e, &c.coord[k], grid_int(m, k, (&P[j].x)[k]) - cm_pred_ctrl(1, j, n, g[0], g[1], g[2], g[3]));
            }
        int64_t wprev = 1ll << CM_FMT_WEIGHT_BITS, wprev2 = wprev;
        for (int j = 1; j < n && E->rational; j++) {
            int64_t wq = fixed(m->w[E->ctrl0 + (uint32_t)j], CM_FMT_WEIGHT_BITS);
            int64_t pred = cm_pred_weight(j, wprev, wprev2);
            if (spoil == SPOIL_WEIGHT && j >= 2) { /* a weight of 0 */
                cm_ac_enc_sint(&e, &c.weight, -pred);
                spoil = SPOIL_NONE;
            } else {
                cm_ac_enc_sint(&e, &c.weight, wq - pred);
            }
            wprev2 = wprev;
            wprev = wq;
        }
    }
    size_t len = cm_ac_enc_finish(&e);
    assert_true(len > 0);
    return len;
}

/* file b (len) with its section `tag` replaced by sec (n bytes), every offset, length, CRC and the
   file-size need made to match: a well-formed file around what sec says (malloc'd, *out_len) */
static uint8_t *with_section(const uint8_t *b, size_t len, unsigned tag, const uint8_t *sec, size_t n, size_t *out_len)
{
    uint32_t nlim = b[CM_HDR_NLIMITS], H = cm_get_u32(b + CM_HDR_LENGTH);
    const uint8_t *ent = b + cm_fmt_entry_at(nlim, tag - 1);
    uint32_t off = cm_get_u32(ent + CM_ENT_OFFSET), old = cm_get_u32(ent + CM_ENT_LENGTH);
    size_t total = len - old + n;
    uint8_t *o = malloc(total);
    assert_non_null(o);
    memcpy(o, b, off);
    memcpy(o + off, sec, n);
    memcpy(o + off + n, b + off + old, len - off - old);
    for (uint32_t s = tag; s < CM_SEC_COUNT; s++) { /* the sections after it move */
        uint8_t *t = o + cm_fmt_entry_at(nlim, s);
        cm_put_u32(t + CM_ENT_OFFSET, (uint32_t)(cm_get_u32(t + CM_ENT_OFFSET) + n - old));
    }
    uint8_t *t = o + cm_fmt_entry_at(nlim, tag - 1);
    cm_put_u32(t + CM_ENT_LENGTH, (uint32_t)n);
    cm_put_u32(t + CM_ENT_CRC, cm_crc32(sec, n));
    cm_put_u32(o + CM_HDR_FILE_LENGTH, (uint32_t)total);
    cm_put_u32(o + cm_fmt_need_at(CM_LIMIT_MAX_FILE_BYTES), (uint32_t)total);
    cm_put_u32(o + H - 4, cm_crc32(o, H - 4));
    cm_put_u32(o + total - 4, cm_crc32(o, total - 4));
    *out_len = total;
    return o;
}

/*
 * The half cylinder's two half circles (rational, a repeated knot) and its kept surface's file, its
 * edges rewritten on the line predictor: the reader rebuilds the same curves.  Spoiled, each is
 * refused with its error and its field named: a knot gap below zero (CM_E_KNOTS), a weight at zero
 * (CM_E_RANGE, "weights"), a step past 2^24 grid steps (CM_E_RANGE, "edge step"; the vertices'
 * likewise, "vertex step").
 */
static void test_edges_written_here(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_half_cylinder_120(&w, 10.0, 20.0);
    loaded_model lm;
    load(&w, "half-cylinder", &lm);
    encode_result r;
    encode_as(&lm, 1, 0, &r);
    model_free(&lm);
    decode_into(&dec3, r.bytes, r.len);
    static uint8_t sec[1 << 16];
    static const struct {
        enum spoil spoil;
        cm_err code;
        const char *where;
    } cases[] = {
        {SPOIL_NONE, CM_OK, NULL},
        {SPOIL_KNOT, CM_E_KNOTS, "knots"},
        {SPOIL_WEIGHT, CM_E_RANGE, "weights"},
        {SPOIL_STEP, CM_E_RANGE, "edge step"},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        size_t n = write_edges(&dec3.model, cases[c].spoil, sec, sizeof sec), flen;
        uint8_t *f = with_section(r.bytes, r.len, CM_SEC_EDGE, sec, n, &flen);
        cm_status st;
        cm_status_init(&st);
        cm_dec_init(&dec2);
        assert_ok(cm_dec_feed(&dec2, f, flen, &st));
        cm_err e = cm_dec_finish(&dec2, &st);
        if (e != cases[c].code)
            fail_msg("case %zu: %s, expected %s", c, cm_err_name(e), cm_err_name(cases[c].code));
        if (e == CM_OK) {
            reach seen = {0};
            assert_same_model(&dec2.model, &dec3.model, 0, &seen);
            assert_true(seen.rational >= 2 && seen.repeated_knot >= 2);
        } else {
            assert_non_null(st.where);
            assert_string_equal(st.where, cases[c].where);
        }
        free(f);
    }
    /* the vertices' step past 2^24 grid steps: refused before any vertex is read */
    cm_ac_enc e;
    cm_ac_enc_init(&e, sec, sizeof sec);
    cm_vert_ctx vc;
    cm_vert_ctx_init(&vc);
    cm_ac_enc_uint(&e, &vc.count, dec3.model.nverts);
    cm_ac_enc_uint(&e, &vc.step, CM_FMT_MAX_STEP + 1);
    size_t n = cm_ac_enc_finish(&e), flen;
    uint8_t *f = with_section(r.bytes, r.len, CM_SEC_VERT, sec, n, &flen);
    cm_status st;
    cm_status_init(&st);
    cm_dec_init(&dec2);
    assert_ok(cm_dec_feed(&dec2, f, flen, &st));
    assert_int_equal(cm_dec_finish(&dec2, &st), CM_E_RANGE);
    assert_string_equal(st.where, "vertex step");
    free(f);
    encode_result_free(&r);
}

/*
 * A kept net sent on a step of its own (the format allows it; the encoder keeps nets on the grid):
 * the bicubic patch's kept surface written here with step 2^1, each point its prediction plus twice
 * the integer nearest half the difference, in closed loop as the format says; the reader must
 * rebuild exactly those points.  With a step past 2^24 the section is refused ("surface step").
 */
static void test_net_on_a_step(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_bicubic_128(&w);
    loaded_model lm;
    load(&w, "bicubic", &lm);
    encode_result r;
    encode_as(&lm, 1, 0, &r);
    model_free(&lm);
    decode_into(&dec3, r.bytes, r.len);
    const cm_model *m = &dec3.model;
    assert_int_equal(m->nsurfs, 1);
    const cm_ksurf *S = &m->surfs[0];
    int nu = S->nu, nv = S->nv;
    static int64_t want[4096][3];
    assert_true(nu * nv <= 4096);
    static uint8_t sec[1 << 16];
    for (int big = 0; big < 2; big++) {
        cm_ac_enc e;
        cm_ac_enc_init(&e, sec, sizeof sec);
        cm_surf_ctx c;
        cm_surf_ctx_init(&c);
        cm_ac_enc_uint(&e, &c.count, 1);
        const int deg[2] = {S->p, S->q}, cnt[2] = {nu, nv};
        for (int dir = 0; dir < 2; dir++) {
            cm_ac_enc_uint(&e, &c.degree, (uint64_t)(deg[dir] - 1));
            cm_ac_enc_uint(&e, &c.ncoef, (uint64_t)(cnt[dir] - deg[dir] - 1));
        }
        cm_ac_enc_bit(&e, &c.rational, S->rational);
        const uint32_t k0[2] = {S->uknot0, S->vknot0};
        for (int dir = 0; dir < 2; dir++) { /* every gap sent, as in write_edges */
            const double *K = m->knots + k0[dir];
            cm_ac_enc_bit(&e, &c.uniform, 0);
            int64_t prev = 0, last_gap = 0;
            for (int j = 1; j <= cnt[dir] - deg[dir] - 1; j++) {
                int64_t gap = fixed(K[deg[dir] + j], CM_FMT_KNOT_BITS) - prev;
                prev += gap;
                if (j == 1) {
                    cm_ac_enc_uint(&e, &c.knot, (uint64_t)gap);
                } else {
                    cm_ac_enc_bit(&e, &c.knot_zero, gap == 0);
                    if (gap)
                        cm_ac_enc_sint(&e, &c.knot_delta, gap - last_gap);
                }
                if (gap)
                    last_gap = gap;
            }
        }
        cm_ac_enc_bit(&e, &c.quadratic, 1);
        cm_ac_enc_uint(&e, &c.step, big ? CM_FMT_MAX_STEP + 1 : 1);
        for (int i = 0; i < nu * nv; i++) {
            for (int k = 0; k < 3; k++) {
                int64_t g = grid_int(m, k, (&m->ctrl[S->ctrl0 + (uint32_t)i].x)[k]);
                int64_t pred = cm_pred_net(1, (const int64_t(*)[3])want, nv, i / nv, i % nv, k);
                int64_t d = g - pred, half = d >= 0 ? (d + 1) / 2 : -((-d + 1) / 2);
                want[i][k] = pred + 2 * half;
                cm_ac_enc_sint(&e, &c.coord[k], half);
            }
            if (S->rational && i > 0) { /* the weights as the format says: parallelogram prediction */
                int a = i / nv, b = i % nv;
                const double *W = m->w + S->ctrl0;
                int64_t wq = fixed(W[i], CM_FMT_WEIGHT_BITS);
                int64_t pred = a && b ? fixed(W[i - nv], 24) + fixed(W[i - 1], 24) - fixed(W[i - nv - 1], 24)
                               : a    ? fixed(W[i - nv], 24)
                                      : fixed(W[i - 1], 24);
                cm_ac_enc_sint(&e, &c.weight, wq - pred);
            }
        }
        size_t n = cm_ac_enc_finish(&e), flen;
        assert_true(n > 0);
        uint8_t *f = with_section(r.bytes, r.len, CM_SEC_SURF, sec, n, &flen);
        cm_status st;
        cm_status_init(&st);
        cm_dec_init(&dec2);
        assert_ok(cm_dec_feed(&dec2, f, flen, &st));
        cm_err err = cm_dec_finish(&dec2, &st);
        free(f);
        if (big) {
            assert_int_equal(err, CM_E_RANGE);
            assert_string_equal(st.where, "surface step");
            continue;
        }
        assert_ok(err);
        const cm_model *m2 = &dec2.model;
        int moved = 0;
        for (int i = 0; i < nu * nv; i++)
            for (int k = 0; k < 3; k++) {
                assert_true(grid_int(m2, k, (&m2->ctrl[m2->surfs[0].ctrl0 + (uint32_t)i].x)[k]) == want[i][k]);
                moved += want[i][k] != grid_int(m, k, (&m->ctrl[S->ctrl0 + (uint32_t)i].x)[k]);
            }
        assert_true(moved > 0); /* some odd residual was rounded: the step did something */
    }
    encode_result_free(&r);
}

/* the default format, with or without the budget steps and GREGORY, --tol rel where rel > 0 */
static void encode_opts_as(loaded_model *lm, int budget, int gregory, double rel, encode_result *r)
{
    encode_with(lm, 0, 0, budget, gregory, rel, r);
}

/*
 * Curves in their budget's terms (tx_reapproximate_curve): a disc's full circle (a rational
 * quadratic of 9 points, its weights and double knots), the face held to 5 % of its box (--tol
 * 0.05), is sent as a uniform cubic B-spline of no more points, no weights, no knots, every point of
 * it within an eighth of the face's tolerance of the circle (a sixteenth for the fit, a sixteenth
 * for the step), and the file is smaller than on the grid.  At the default tolerance (1e-3 of the
 * diagonal) the circle would need more cubic points than its rational form costs (at 2 %: 11
 * points, 208 bits against 197): it stays so.  A kept face's curves are not touched: the half cylinder kept (planes only) keeps its
 * rational half circles exactly as they are on the grid.
 */
static void check_net_reapproximated(loaded_model *lm, int minor, double rim_share)
{
    const int n = 30;
    const double a = 100.0, h = 10.0;
    encode_result rb, rg;
    encode_with(lm, 4, minor, 1, 0, 0.0, &rb);
    encode_with(lm, 4, minor, 0, 0, 0.0, &rg);
    assert_int_equal(rb.faces_by_method[CM_METHOD_KEEP], 1);
    assert_int_equal(rb.surfs_reapproximated, 1);
    assert_int_equal(rg.surfs_reapproximated, 0);
    if (!(rb.len < rg.len))
        fail_msg("re-approximated: %zu bytes (SURF %zu), on the grid: %zu (SURF %zu)", rb.len, rb.section_bytes[3], rg.len, rg.section_bytes[3]);
    decode_into(&dec3, rb.bytes, rb.len);
    decode_into(&dec2, rg.bytes, rg.len);
    cm_surf sb, sg;
    cm_model_surface(&dec3.model, dec3.model.faces[0].surf, &sb);
    cm_model_surface(&dec2.model, dec2.model.faces[0].surf, &sg);
    assert_int_equal(sg.nu * sg.nv, n * n);
    assert_true(sb.nu * sb.nv < n * n * 3 / 4);
    assert_int_equal(sb.p, 3);
    assert_int_equal(sb.q, 3);
    /* the face's tolerance: 1e-3 of the model's diagonal (the face's box: z from 0 to 2 h) */
    double tol = 1e-3 * sqrt(2.0 * a * a + 4.0 * h * h), worst = 0, rim = 0;
    for (int i = 0; i <= 100; i++)
        for (int j = 0; j <= 100; j++) {
            cm_vec3 A[CM_MAX_DERS + 1][CM_MAX_DERS + 1], B[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
            cm_status st;
            cm_status_init(&st);
            assert_ok(cm_surf_eval(&sb, i / 100.0, j / 100.0, 0, A, &st));
            assert_ok(cm_surf_eval(&sg, i / 100.0, j / 100.0, 0, B, &st));
            double d = cm_dist(A[0][0], B[0][0]);
            worst = d > worst ? d : worst;
            if (i == 0 || j == 0 || i == 100 || j == 100)
                rim = d > rim ? d : rim;
        }
    if (!(worst <= tol / 4.0 && rim <= tol * rim_share))
        fail_msg("format 4.%d: the re-approximated net strays %g mm (%g on its boundary), its budget %g (%g)", minor, worst,
                 rim, tol / 4.0, tol * rim_share);
    assert_true(worst > 0);
    encode_result_free(&rb);
    encode_result_free(&rg);
}

/*
 * Kept surfaces in their budget's terms (tx_reapproximate_surface): a 30 x 30 net of a dish, flat
 * inside and steep at its rim, on uneven knots, kept (planes only), is sent as a uniform cubic net
 * of fewer points, within a quarter of the face's tolerance of the net on the grid, and the file is
 * smaller; without the budget steps the net goes whole.  For a 4.0 terminal, whose tessellation
 * tests a kept face's loop against its edges, the boundary (the face's edges run there) stays
 * within a sixteenth (held to a quarter, it strays 0.014 mm where a sixteenth is 0.009).
 */
static void test_surfaces_reapproximated(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_dense_128(&w, 30, 100.0, 10.0);
    loaded_model lm;
    load(&w, "dish", &lm);
    check_net_reapproximated(&lm, 1, 0.25);
    check_net_reapproximated(&lm, 0, 1.0 / 16.0);
    model_free(&lm);
}

static void test_face_folds(void **state)
{
    (void)state;
    float pos[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 0}};
    uint32_t quad[6] = {0, 1, 2, 0, 2, 3}, fold[6] = {0, 1, 2, 0, 1, 3}, welded[6] = {0, 1, 2, 4, 1, 3};
    cm_mesh m = {pos, NULL, quad, NULL, 5, 5, 6, 6, 0, 0, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    assert_int_equal(enc_face_folds(&m), 0);
    m.idx = fold;
    assert_int_equal(enc_face_folds(&m), 1);
    m.idx = welded;
    assert_int_equal(enc_face_folds(&m), 1);
}

static void test_curves_reapproximated(void **state)
{
    (void)state;
    const double R = 20.0, Z = 3.0;
    igw w;
    igw_init(&w);
    igw_disc_144(&w, R, Z);
    loaded_model lm;
    load(&w, "disc", &lm);
    /* format 4.3: from 4.4 the circle goes as a full circle (test_arcs), cheaper than either */
    encode_result rb, rg;
    encode_with(&lm, CM_FMT_COMPACT_MAJOR, CM_FMT_PLACE_MINOR, 1, 1, 0.0, &rb);
    assert_int_equal(rb.edges_reapproximated, 0);
    encode_result_free(&rb);
    encode_with(&lm, CM_FMT_COMPACT_MAJOR, CM_FMT_PLACE_MINOR, 1, 1, 0.05, &rb);
    encode_with(&lm, CM_FMT_COMPACT_MAJOR, CM_FMT_PLACE_MINOR, 0, 1, 0.05, &rg);
    assert_int_equal(rb.faces_by_method[CM_METHOD_PLANE], 1);
    assert_true(rb.edges_reapproximated >= 1);
    assert_int_equal(rg.edges_reapproximated, 0);
    if (!(rb.len < rg.len))
        fail_msg("re-approximated: %zu bytes, on the grid: %zu", rb.len, rg.len);
    decode_into(&dec3, rb.bytes, rb.len);
    decode_into(&dec2, rg.bytes, rg.len);
    assert_int_equal(dec3.model.nedges, 1);
    const cm_edge *E = &dec3.model.edges[0], *G = &dec2.model.edges[0];
    assert_int_equal(G->rational, 1);
    assert_int_equal(E->rational, 0);
    assert_int_equal(E->p, 3);
    assert_true(E->nctrl <= G->nctrl);
    double tol = 0.05 * 2.0 * R * sqrt(2.0), worst = 0;
    cm_curve c;
    cm_model_edge_curve(&dec3.model, 0, &c);
    for (int k = 0; k <= 720; k++) {
        cm_vec3 pt;
        cm_status st;
        cm_status_init(&st);
        assert_ok(cm_curve_eval(&c, k / 720.0, 0, &pt, &st));
        double d = hypot(hypot(pt.x, pt.y) - R, pt.z - Z);
        worst = d > worst ? d : worst;
    }
    if (!(worst <= tol / 8.0))
        fail_msg("the re-approximated circle strays %g mm, its budget %g mm", worst, tol / 8.0);
    assert_true(worst > 0); /* not the circle: a cubic near it */
    encode_result_free(&rb);
    encode_result_free(&rg);
    model_free(&lm);
    /* kept: its edges as on the grid, bit for bit (format 4.3); from 4.4 its half circles as arcs
       whose middle points are on the grid, within two grid steps of the circle */
    igw_init(&w);
    igw_half_cylinder_120(&w, 10.0, 20.0);
    load(&w, "half-cylinder", &lm);
    encode_with(&lm, CM_FMT_COMPACT_MAJOR, CM_FMT_PLACE_MINOR, 1, 0, 0.02, &rb);
    encode_with(&lm, CM_FMT_COMPACT_MAJOR, CM_FMT_PLACE_MINOR, 0, 0, 0.02, &rg);
    assert_int_equal(rb.faces_by_method[CM_METHOD_KEEP], 1);
    decode_into(&dec3, rb.bytes, rb.len);
    decode_into(&dec2, rg.bytes, rg.len);
    reach seen = {0};
    assert_same_model(&dec3.model, &dec2.model, 0, &seen);
    assert_true(seen.rational >= 2);
    encode_result_free(&rb);
    encode_opts_as(&lm, 1, 0, 0.02, &rb);
    assert_int_equal(rb.faces_by_method[CM_METHOD_KEEP], 1);
    assert_int_equal(rb.edges_arcs, 2);
    decode_into(&dec3, rb.bytes, rb.len);
    double q = dec3.model.q, off = 0;
    for (uint32_t i = 0; i < dec3.model.nedges; i++) {
        if (dec3.model.edges[i].kind != CM_EDGE_CURVE)
            continue;
        cm_curve arc;
        cm_model_edge_curve(&dec3.model, i, &arc);
        for (int k = 0; k <= 64; k++) {
            cm_vec3 pt;
            assert_ok(cm_curve_eval(&arc, k / 64.0, 0, &pt, NULL));
            off = fmax(off, fabs(hypot(pt.x, pt.y) - 10.0));
        }
    }
    if (!(off <= 2.0 * q))
        fail_msg("a kept face's arc %.3g grid steps off its circle", off / q);
    encode_result_free(&rb);
    encode_result_free(&rg);
    model_free(&lm);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_predictions_exact),
        cmocka_unit_test(test_same_model_smaller_file),
        cmocka_unit_test(test_edges_written_here),
        cmocka_unit_test(test_net_on_a_step),
        cmocka_unit_test(test_curves_reapproximated),
        cmocka_unit_test(test_surfaces_reapproximated),
        cmocka_unit_test(test_face_folds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
