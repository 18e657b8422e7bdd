/* write_sections.c - the transmitted model and the methods' records as .cmz bytes (docs/FORMAT.md). */
#include "encode_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_const.h"
#include "cm/cm_corner.h"
#include "cm/cm_crc32.h"
#include "cm/cm_cubic_convert.h"
#include "cm/cm_method.h"
#include "fit_correction.h"
#include "cm/cm_sections.h"
#include "cm/cm_use_adj.h"

/* ---- writing ---- */

typedef struct outbuf {
    uint8_t *p;
    size_t len;
} outbuf;

/* a section's writer: 0, or -1 when memory runs out */
typedef int (*section_fn)(const tx *t, cm_ac_enc *e, const loaded_model *lm);

/* a knot vector's interior knots (docs/FORMAT.md, "Knots"): format 2 sends each gap, format 3 the
   first gap, then per gap a bit "zero" and otherwise the gap less the last gap that was not zero */
typedef struct knot_models {
    cm_ac_prob *uniform, *zero;
    cm_ac_int *gap, *delta;
} knot_models;

static void put_knots(cm_ac_enc *e, const knot_models *km, int predicted, int uniform, const int64_t *kq, int interior)
{
    cm_ac_enc_bit(e, km->uniform, (unsigned)uniform);
    if (uniform)
        return;
    int64_t prev = 0, last_gap = 0;
    for (int j = 0; j < interior; j++) {
        int64_t gap = kq[j] - prev;
        prev = kq[j];
        if (!predicted || j == 0) {
            cm_ac_enc_uint(e, km->gap, (uint64_t)gap);
        } else {
            cm_ac_enc_bit(e, km->zero, gap == 0);
            if (gap)
                cm_ac_enc_sint(e, km->delta, gap - last_gap);
        }
        if (gap)
            last_gap = gap;
    }
}

/*
 * The vertices' step: the one the tolerance allows (tx_coarsen_vertices), or a coarser one on which
 * every vertex already lies.  Parts drawn in round units put their corners on a round grid (the
 * 10 mm cube's are 10 mm from the origin: 2^17 grid steps divide them, where the tolerance allowed
 * 2^8): the same vertices, each coordinate sent in 9 fewer bits.  Lossless, so nothing else changes.
 */
static int vert_step(const tx *t)
{
    uint64_t all = 0; /* the bits set in any coordinate: its lowest is the common power of two */
    for (int i = 0; i < t->nverts; i++)
        for (int k = 0; k < 3; k++)
            all |= (uint64_t)t->vq[i][k];
    int s = t->vstep;
    while (s < CM_FMT_MAX_STEP && (all & ((uint64_t)1 << s)) == 0)
        s++;
    return s;
}

static int sec_vert(const tx *t, cm_ac_enc *e, const loaded_model *lm)
{
    (void)lm;
    cm_vert_ctx ctx;
    cm_vert_ctx_init(&ctx);
    cm_ac_enc_uint(e, &ctx.count, (uint64_t)t->nverts);
    /* format 3: the vertices' step (tx_coarsen_vertices), the deltas in steps */
    int step = t->o->predicted ? vert_step(t) : 0;
    if (t->o->predicted)
        cm_ac_enc_uint(e, &ctx.step, (uint64_t)step);
    /* format 4: a coordinate met lately on its axis as its place in the list (cm_vcache) */
    int recent = enc_compact_header(t->o);
    cm_vcache cache[3] = {{{0}, 0}, {{0}, 0}, {{0}, 0}};
    int64_t prev[3] = {0, 0, 0};
    for (int i = 0; i < t->nverts; i++)
        for (int k = 0; k < 3; k++) {
            int slot = recent ? cm_vcache_find(&cache[k], t->vq[i][k]) : -1;
            if (recent)
                cm_ac_enc_bit(e, &ctx.repeat[k], slot >= 0);
            if (slot >= 0)
                cm_ac_enc_uint(e, &ctx.slot[k], (uint64_t)slot);
            else
                cm_ac_enc_sint(e, &ctx.coord[k], (t->vq[i][k] - prev[k]) / ((int64_t)1 << step));
            if (recent)
                cm_vcache_front(&cache[k], slot, t->vq[i][k]);
            prev[k] = t->vq[i][k];
        }
    return 0;
}

static void put_vref(cm_ac_enc *e, cm_ac_prob *pnew, cm_ac_int *mb, int *next, int v)
{
    if (v == *next) {
        cm_ac_enc_bit(e, pnew, 1);
        (*next)++;
    } else {
        cm_ac_enc_bit(e, pnew, 0);
        cm_ac_enc_uint(e, mb, (uint64_t)(*next - 1 - v));
    }
}

static int sec_edge(const tx *t, cm_ac_enc *e, const loaded_model *lm)
{
    (void)lm;
    int pred = t->o->predicted;
    cm_edge_ctx ctx;
    cm_edge_ctx_init(&ctx);
    cm_ac_enc_uint(e, &ctx.count, (uint64_t)t->nedges);
    int vnext = 0;
    for (int i = 0; i < t->nedges; i++) {
        const tx_edge *X = &t->edges[i];
        put_vref(e, &ctx.is_new, &ctx.back, &vnext, X->v0);
        put_vref(e, &ctx.is_new, &ctx.back, &vnext, X->v1);
        cm_ac_enc_bit(e, &ctx.g1, (unsigned)X->g1);
        cm_ac_enc_bit(e, &ctx.kind, (unsigned)X->kind);
        if (X->kind == CM_EDGE_LINE)
            continue;
        if (enc_arcs(t->o)) {
            cm_ac_enc_bit(e, &ctx.arc, (unsigned)X->arc);
            if (X->arc) {
                cm_ac_enc_uint(e, &ctx.arc_step, (uint64_t)X->step);
                for (int k = 0; k < tx_arc_fields(X); k++)
                    cm_ac_enc_sint(e, &ctx.arc_coord[k % 3], tx_arc_residual(t, X, k));
                continue;
            }
        }
        cm_ac_enc_uint(e, &ctx.degree, (uint64_t)(X->p - 1));
        cm_ac_enc_uint(e, &ctx.ncoef, (uint64_t)(X->n - X->p - 1));
        cm_ac_enc_bit(e, &ctx.rational, (unsigned)X->rational);
        knot_models km = {&ctx.uniform, &ctx.knot_zero, &ctx.knot, &ctx.knot_delta};
        put_knots(e, &km, pred, X->uniform, X->kq, X->n - X->p - 1);
        /* format 3: the predictor and step tx_coarsen_edge chose; the points are multiples of the
           step away from their predictions */
        int linear = pred ? X->linear : 0, step = pred ? X->step : 0;
        if (pred && X->n > 2) {
            cm_ac_enc_bit(e, &ctx.linear, (unsigned)linear);
            cm_ac_enc_uint(e, &ctx.step, (uint64_t)step);
        }
        for (int j = 1; j < X->n - 1; j++)
            for (int k = 0; k < 3; k++)
                cm_ac_enc_sint(e, &ctx.coord[k], (X->cq[j][k] - tx_edge_pred(X, linear, j, k)) / ((int64_t)1 << step));
        if (X->rational)
            for (int j = 1; j < X->n; j++)
                cm_ac_enc_sint(e, &ctx.weight, X->wq[j] - (pred ? cm_pred_weight(j, X->wq[j - 1], j >= 2 ? X->wq[j - 2] : 0)
                                                                : X->wq[j - 1]));
    }
    return 0;
}

/* a kept surface's control point (i, j), coordinate k, less its prediction from the points before
   it in the grid (cm_pred_net; docs/FORMAT.md, SURF) */
static int64_t surf_coord_residual(const tx_surf *S, int quadratic, int i, int j, int k)
{
    return S->cq[i * S->nv + j][k] - cm_pred_net(quadratic, (const int64_t(*)[3])S->cq, S->nv, i, j, k);
}

/* its weight likewise ((i, j) != (0, 0): the first weight is 1 and not sent) */
static int64_t surf_weight_residual(const tx_surf *S, int i, int j)
{
    int nv = S->nv, idx = i * nv + j;
    int64_t pred = i && j ? S->wq[idx - nv] + S->wq[idx - 1] - S->wq[idx - nv - 1] : i ? S->wq[idx - nv] : S->wq[idx - 1];
    return S->wq[idx] - pred;
}

/* ---- what a face costs, estimated (spec §14 step 6) ----
   The arithmetic coder's contexts adapt over the whole section, so one face's bytes are not known
   until the file is written.  The estimate counts what a number costs once the contexts have learnt
   the usual lengths: about two bits for its length, the bits below its leading one (close to
   incompressible), one for the sign.  Kept surfaces and records are estimated the same way, so the
   comparison is fair even where the estimate is not exact. */
static double est_uint_bits(uint64_t v)
{
    unsigned k = 0;
    while (k < 64 && (v >> k))
        k++;
    return 2.0 + (k > 1 ? (double)(k - 1) : 0.0);
}

static double est_sint_bits(int64_t v)
{
    return v == 0 ? est_uint_bits(0) : est_uint_bits(v < 0 ? (uint64_t)(-(v + 1)) + 1u : (uint64_t)v) + 1.0;
}

double enc_sint_bits(int64_t v)
{
    return est_sint_bits(v);
}

/* as put_knots codes them: a repeated knot about a fifth of a bit once the model has learnt it */
static double est_knot_bits(int predicted, int uniform, const int64_t *kq, int interior)
{
    double b = 1.0;
    int64_t prev = 0, last_gap = 0;
    for (int j = 0; !uniform && j < interior; j++) {
        int64_t gap = kq[j] - prev;
        prev = kq[j];
        if (!predicted || j == 0)
            b += est_uint_bits((uint64_t)gap);
        else
            b += gap ? 1.0 + est_sint_bits(gap - last_gap) : 0.2;
        if (gap)
            last_gap = gap;
    }
    return b;
}

double enc_edge_bits(const tx *t, const tx_edge *X, int predicted)
{
    double b = 2.0; /* kind, g1 */
    if (X->kind == CM_EDGE_LINE)
        return b;
    if (enc_arcs(t->o))
        b += 1.0; /* the arc bit */
    if (X->arc) {
        b += est_uint_bits((uint64_t)X->step);
        for (int k = 0; k < tx_arc_fields(X); k++)
            b += est_sint_bits(tx_arc_residual(t, X, k));
        return b;
    }
    b += est_uint_bits((uint64_t)(X->p - 1)) + est_uint_bits((uint64_t)(X->n - X->p - 1)) + 1.0;
    b += est_knot_bits(predicted, X->uniform, X->kq, X->n - X->p - 1);
    int linear = predicted ? X->linear : 0, step = predicted ? X->step : 0;
    if (predicted && X->n > 2)
        b += 1.0 + est_uint_bits((uint64_t)step);
    for (int j = 1; j < X->n - 1; j++)
        for (int k = 0; k < 3; k++)
            b += est_sint_bits((X->cq[j][k] - tx_edge_pred(X, linear, j, k)) / ((int64_t)1 << step));
    if (X->rational)
        for (int j = 1; j < X->n; j++)
            b += est_sint_bits(X->wq[j] - (predicted ? cm_pred_weight(j, X->wq[j - 1], j >= 2 ? X->wq[j - 2] : 0)
                                                      : X->wq[j - 1]));
    return b;
}

double enc_kept_surface_bits(const tx_surf *S, int predicted)
{
    if (S->ruled) {
        double b = 4.0 + est_uint_bits(0); /* ruled, closed, along v, step */
        for (int row = 0; row < 2; row++)
            for (int j = 0; j < 3; j++)
                for (int k = 0; k < 3; k++)
                    b += est_sint_bits(S->rp[row][j][k] - cm_pred_ruled((const int64_t(*)[3][3])S->rp, row, j, k));
        return b;
    }
    double b = 4 * est_uint_bits(3) + 1.0 + (predicted ? 1.0 + est_uint_bits(0) : 0.0);
    int quadratic = predicted ? S->quadratic : 0;
    b += est_knot_bits(predicted, S->uniform_u, S->ku, S->nu - S->p - 1) +
         est_knot_bits(predicted, S->uniform_v, S->kv, S->nv - S->q - 1);
    for (int i = 0; i < S->nu; i++)
        for (int j = 0; j < S->nv; j++) {
            for (int k = 0; k < 3; k++)
                b += est_sint_bits(surf_coord_residual(S, quadratic, i, j, k));
            if (S->rational && (i || j))
                b += est_sint_bits(surf_weight_residual(S, i, j));
        }
    return b;
}

double enc_fit_record_bits(const fit_record *fr)
{
    double b = 2 * est_uint_bits(CM_MAX_SIDES) + 32.0; /* layout, corner, checksum */
    b += est_uint_bits((uint64_t)fr->m) + est_uint_bits((uint64_t)fr->npatch) + est_uint_bits((uint64_t)fr->exp);
    for (int i = 0; i < fr->npatch * fr->m * fr->m; i++)
        for (int a = 0; a < 3; a++)
            b += est_sint_bits(fr->q[i][a]);
    for (int k = 0; k < fr->ntwist; k++) {
        b += 1.0;
        for (int j = 0; j < CM_TWIST_N; j++)
            b += est_sint_bits((int64_t)fr->twist[k][j] - (j ? fr->twist[k][j - 1] : 0));
    }
    return b;
}

static void put_net(const tx *t, cm_ac_enc *e, cm_surf_ctx *cx, const tx_surf *S);

static int sec_surf(const tx *t, cm_ac_enc *e, const loaded_model *lm)
{
    (void)lm;
    cm_surf_ctx ctx;
    cm_surf_ctx_init(&ctx);
    int nkeep = 0;
    for (int f = 0; f < t->nfaces; f++)
        nkeep += enc_kept(t->method[f]);
    cm_ac_enc_uint(e, &ctx.count, (uint64_t)nkeep);
    for (int f = 0; f < t->nfaces; f++) {
        if (!enc_kept(t->method[f]))
            continue;
        put_net(t, e, &ctx, &t->surfs[f]);
    }
    return 0;
}

size_t enc_net_bytes(const tx *t, const tx_surf *S)
{
    size_t cap = 64 + 32 * (size_t)S->nu * (size_t)S->nv;
    uint8_t *buf = malloc(cap);
    if (!buf)
        return SIZE_MAX;
    cm_surf_ctx ctx;
    cm_surf_ctx_init(&ctx);
    cm_ac_enc e;
    cm_ac_enc_init(&e, buf, cap);
    put_net(t, &e, &ctx, S);
    size_t n = cm_ac_enc_finish(&e);
    free(buf);
    return e.overflow ? SIZE_MAX : n;
}

/* a kept net: degrees, counts, knots, its predictor and its points */
static void put_net(const tx *t, cm_ac_enc *e, cm_surf_ctx *cx, const tx_surf *S)
{
    if (enc_arcs(t->o)) { /* format 4.4: ruled between two arcs (tx_ruled_surface) */
        cm_ac_enc_bit(e, &cx->ruled, (unsigned)S->ruled);
        if (S->ruled) {
            cm_ac_enc_bit(e, &cx->closed, (unsigned)S->ruled_closed);
            cm_ac_enc_bit(e, &cx->along_v, (unsigned)S->ruled_along_v);
            cm_ac_enc_uint(e, &cx->ruled_step, 0); /* on the grid, as every kept net */
            for (int row = 0; row < 2; row++)
                for (int j = 0; j < 3; j++)
                    for (int k = 0; k < 3; k++)
                        cm_ac_enc_sint(e, &cx->ruled_coord[k],
                                       S->rp[row][j][k] - cm_pred_ruled((const int64_t(*)[3][3])S->rp, row, j, k));
            return;
        }
    }
    cm_ac_enc_uint(e, &cx->degree, (uint64_t)(S->p - 1));
    cm_ac_enc_uint(e, &cx->ncoef, (uint64_t)(S->nu - S->p - 1));
    cm_ac_enc_uint(e, &cx->degree, (uint64_t)(S->q - 1));
    cm_ac_enc_uint(e, &cx->ncoef, (uint64_t)(S->nv - S->q - 1));
    cm_ac_enc_bit(e, &cx->rational, (unsigned)S->rational);
    knot_models km = {&cx->uniform, &cx->knot_zero, &cx->knot, &cx->knot_delta};
    put_knots(e, &km, t->o->predicted, S->uniform_u, S->ku, S->nu - S->p - 1);
    put_knots(e, &km, t->o->predicted, S->uniform_v, S->kv, S->nv - S->q - 1);
    int nu = S->nu, nv = S->nv, pred = t->o->predicted;
    int quadratic = pred ? S->quadratic : 0;
    if (pred) { /* the net's predictor; its step is 0: kept nets stay on the grid (tx_net_predictor) */
        cm_ac_enc_bit(e, &cx->quadratic, (unsigned)quadratic);
        cm_ac_enc_uint(e, &cx->step, 0);
    }
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            int idx = i * nv + j;
            for (int k = 0; k < 3; k++)
                cm_ac_enc_sint(e, &cx->coord[k], surf_coord_residual(S, quadratic, i, j, k));
            if (S->rational && idx > 0)
                cm_ac_enc_sint(e, &cx->weight, surf_weight_residual(S, i, j));
        }
}

/*
 * Format 4.3: copy k of lm's placed copies places the faces of instance proto, which the model sends
 * as its faces [first, first + count) (the importer adds an instance's faces together and nothing
 * reorders them; faces left out leave the rest in order).  0 when none of them is left (the copy
 * is left out with them), -1 when they are not together (then the file cannot say it).
 */
static int placement_faces(const tx *t, const loaded_model *lm, int k, uint32_t *first, uint32_t *count)
{
    int proto = lm->brep.placements[k].proto, f0 = -1, n = 0;
    for (int f = 0; f < t->nfaces; f++)
        if (lm->brep.faces[lm->mesh.faces[f].brep_face].instance == proto) {
            if (f0 < 0)
                f0 = f;
            else if (f != f0 + n)
                return -1;
            n++;
        }
    *first = (uint32_t)(f0 < 0 ? 0 : f0);
    *count = (uint32_t)n;
    return n > 0;
}

/* copy x's displacement of the grid origin o along axis i, in grid steps: x(o) - o = R o + t - o,
   which for a copy inside the model's box is as bounded as the model's coordinates (its t need
   not be: a part turned far from the world's origin) */
static double placement_shift_mm(const tx *t, const haffine *x, int i)
{
    const double tt[3] = {x->t.x, x->t.y, x->t.z};
    return x->R[i][0] * t->origin[0] + x->R[i][1] * t->origin[1] + x->R[i][2] * t->origin[2] + tt[i] - t->origin[i];
}

static int64_t placement_shift(const tx *t, const haffine *x, int i)
{
    return (int64_t)llround(placement_shift_mm(t, x, i) / t->q);
}

/* a double as its 64 bits, most significant first (read_double, cm_decode.c) */
static void write_double(cm_ac_enc *e, double v)
{
    uint64_t b;
    memcpy(&b, &v, sizeof b);
    for (int i = 3; i >= 0; i--)
        cm_ac_enc_direct(e, (uint32_t)(b >> (16 * i)) & 0xffffu, 16);
}

/* format 4.3: the placed copies after the faces (docs/FORMAT.md, FACE) */
static void write_placements(const tx *t, cm_ac_enc *e, const loaded_model *lm, cm_face_ctx *ctx)
{
    uint32_t n = 0, first, count;
    for (int k = 0; k < lm->brep.nplacements; k++)
        n += placement_faces(t, lm, k, &first, &count) > 0;
    cm_ac_enc_uint(e, &ctx->place_n, n);
    for (int k = 0; k < lm->brep.nplacements; k++) {
        if (placement_faces(t, lm, k, &first, &count) <= 0)
            continue;
        cm_ac_enc_uint(e, &ctx->place_first, first);
        cm_ac_enc_uint(e, &ctx->place_count, count - 1u);
        const haffine *x = &lm->brep.placements[k].xf;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double v = x->R[i][j];
                unsigned cls = v == 0.0 ? 0u : v == 1.0 ? 1u : v == -1.0 ? 2u : 3u;
                cm_ac_enc_uint(e, &ctx->place_entry, cls);
                if (cls == 3u)
                    write_double(e, v);
            }
        /* the translation as the grid origin's displacement on the grid (read_placements) */
        for (int i = 0; i < 3; i++)
            cm_ac_enc_sint(e, &ctx->place_shift, placement_shift(t, x, i));
    }
}

cm_err enc_check_placements(const tx *t, const loaded_model *lm, cm_status *st)
{
    uint32_t first, count;
    for (int k = 0; k < lm->brep.nplacements; k++) {
        if (placement_faces(t, lm, k, &first, &count) < 0)
            return cm_fail(st, CM_E_FORMAT, "a placed part's faces are not sent together");
        const haffine *x = &lm->brep.placements[k].xf;
        double m[12];
        haffine_rows(x, m);
        const char *fault = cm_fmt_placement_fault(m);
        for (int i = 0; i < 3 && !fault; i++)
            if (!(fabs(placement_shift_mm(t, x, i) / t->q) <= (double)CM_FMT_PLACE_MAX_STEPS))
                fault = "placement's translation (beyond the grid)";
        if (fault)
            return cm_fail(st, CM_E_RANGE, fault);
    }
    return CM_OK;
}

int encode_placement_is(const double m[12], const haffine *x, double q, const double origin[3])
{
    double want[12];
    haffine_rows(x, want);
    for (int i = 0; i < 12; i++) {
        if (i % 4 != 3 && m[i] != want[i])
            return 0;
        if (i % 4 == 3 && !(fabs(m[i] - want[i]) <= 0.5 * q * (1.0 + 1e-6) +
                                                    1e-12 * (1.0 + fabs(want[i]) + fabs(origin[i / 4]))))
            return 0;
    }
    return 1;
}

cm_err enc_placements_decoded(const tx *t, const loaded_model *lm, const cm_model *dm, cm_status *st)
{
    uint32_t first, count, k = 0;
    for (int j = 0; j < lm->brep.nplacements; j++) {
        if (placement_faces(t, lm, j, &first, &count) <= 0)
            continue;
        int same = k < dm->nplacements && dm->placements[k].first == first && dm->placements[k].count == count &&
                   encode_placement_is(dm->placements[k].m, &lm->brep.placements[j].xf, t->q, t->origin);
        if (!same)
            return cm_fail(st, CM_E_FORMAT, "the encoder's check of its own file: a placed copy decodes "
                                            "elsewhere (an encoder bug: please report it with the model)");
        k++;
    }
    return k == dm->nplacements ? CM_OK : cm_fail(st, CM_E_FORMAT, "the encoder's check of its own file: placed copies");
}

/* format 4.5's lists of the edges at each vertex (cm_use_adj.h), over the transmitted edges */
typedef struct use_lists {
    cm_edge *edges;
    cm_use_adj adj;
} use_lists;

static int use_lists_begin(use_lists *ul, const tx *t)
{
    ul->edges = calloc((size_t)t->nedges + 1, sizeof *ul->edges);
    ul->adj.head = malloc(((size_t)t->nverts + 1) * sizeof *ul->adj.head);
    ul->adj.next = malloc(((size_t)t->nedges + 1) * sizeof *ul->adj.next);
    ul->adj.nuse = malloc((size_t)t->nedges + 1);
    if (!ul->edges || !ul->adj.head || !ul->adj.next || !ul->adj.nuse)
        return 0;
    for (int i = 0; i < t->nedges; i++) {
        ul->edges[i].v0 = t->edges[i].v0;
        ul->edges[i].v1 = t->edges[i].v1;
    }
    cm_use_adj_begin(&ul->adj, (uint32_t)t->nverts);
    return 1;
}

static void use_lists_end(use_lists *ul)
{
    free(ul->edges);
    free(ul->adj.head);
    free(ul->adj.next);
    free(ul->adj.nuse);
}

/* format 4.5: use k > 0 of a loop (the reader's read_use_at), of transmitted edge ex, beginning at v */
static void put_use_at(cm_ac_enc *e, cm_face_ctx *ctx, use_lists *ul, int ex, int rev, int32_t v, int *enext)
{
    int fresh = ex == *enext;
    cm_ac_enc_bit(e, &ctx->is_new, (unsigned)fresh);
    if (fresh) {
        (*enext)++;
    } else {
        uint32_t cand[CM_USE_CANDIDATES];
        int n = cm_use_adj_list(&ul->adj, ul->edges, v, cand), i = 0;
        while (i < n && cand[i] != (uint32_t)ex)
            i++;
        cm_ac_enc_uint(e, &ctx->cand, (uint64_t)i);
        if (i == n) /* beyond the entries looked at: named as in 4.4 */
            cm_ac_enc_uint(e, &ctx->back, (uint64_t)(*enext - 1 - ex));
    }
    if (ul->edges[ex].v0 == ul->edges[ex].v1)
        cm_ac_enc_bit(e, &ctx->rev_closed, (unsigned)rev);
    cm_use_adj_use(&ul->adj, ul->edges, (uint32_t)ex, fresh);
}

static int sec_face(const tx *t, cm_ac_enc *e, const loaded_model *lm)
{
    const cmesh *cm = &lm->mesh;
    cm_face_ctx ctx;
    cm_face_ctx_init(&ctx);
    ctx.net_fit = enc_net_fit(t->o);
    ctx.placements = enc_placement_tail(t->o);
    ctx.hints = enc_hints(t->o);
    cm_ac_enc_uint(e, &ctx.count, (uint64_t)t->nfaces);
    if (ctx.hints) {
        /* format 4.13: whether any record has corner hints (else none has their field) */
        int any = 0;
        for (int f = 0; f < t->nfaces && !any; f++)
            any = t->fit[f] && t->fit[f]->hint_mask;
        cm_ac_enc_bit(e, &ctx.hint_any, (unsigned)any);
        ctx.hints = any;
    }
    int enext = 0;
    use_lists ul = {0};
    int by_vertex = enc_use_adj(t->o);
    if (by_vertex && !use_lists_begin(&ul, t)) {
        use_lists_end(&ul);
        return -1;
    }
    for (int f = 0; f < t->nfaces; f++) {
        const cmesh_face *cf = &cm->faces[f];
        cm_ac_enc_uint(e, &ctx.method, (uint64_t)t->method[f]);
        const cm_method *M = cm_method_of((unsigned)t->method[f]);
        if (M->has_record) {
            cm_face rec = {0};
            enc_record_fields(&rec, t->method[f], t->layout[f], t->corner[f]);
            rec.checksum = t->checksum[f];
            cm_fit_q fit = {0};
            if (t->fit[f])
                fit = fit_record_view(t->fit[f]);
            cm_method_write_record(M, e, &ctx, &rec, t->fit[f] ? &fit : NULL);
        }
        cm_ac_enc_bit(e, &ctx.flip, (unsigned)lm->brep.faces[cf->brep_face].flip);
        cm_ac_enc_uint(e, &ctx.loops, (uint64_t)cf->nloops);
        for (int l = 0; l < cf->nloops; l++) {
            const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
            cm_ac_enc_uint(e, &ctx.uses, (uint64_t)cl->n);
            for (int i = 0; i < cl->n; i++) {
                const cmesh_use *u = &cm->uses[cl->first + i];
                int ex = t->edge_tx[u->edge];
                /* the transmitted edge runs in its cmesh direction: rev carries over */
                if (by_vertex && i > 0) {
                    const cmesh_use *p = u - 1;
                    const tx_edge *P = &t->edges[t->edge_tx[p->edge]];
                    put_use_at(e, &ctx, &ul, ex, u->rev, p->rev ? P->v0 : P->v1, &enext);
                    continue;
                }
                if (by_vertex)
                    cm_use_adj_use(&ul.adj, ul.edges, (uint32_t)ex, ex == enext);
                if (ex == enext) {
                    cm_ac_enc_bit(e, &ctx.is_new, 1);
                    cm_ac_enc_bit(e, &ctx.rev_new, (unsigned)u->rev);
                    enext++;
                } else {
                    cm_ac_enc_bit(e, &ctx.is_new, 0);
                    cm_ac_enc_uint(e, &ctx.back, (uint64_t)(enext - 1 - ex));
                    cm_ac_enc_bit(e, &ctx.rev_old, (unsigned)u->rev);
                }
            }
        }
    }
    if (ctx.placements)
        write_placements(t, e, lm, &ctx);
    use_lists_end(&ul);
    return 0;
}

/* one face's or copy's part (read_parts in cm_decode.c): the previous one's, the next new one, or by number */
static void write_part(cm_ac_enc *e, cm_colr_ctx *ctx, int i, int part, int *prev, int *top)
{
    if (i > 0)
        cm_ac_enc_bit(e, &ctx->part_same, part == *prev);
    if (i == 0 || part != *prev) {
        cm_ac_enc_bit(e, &ctx->part_next, part == *top + 1);
        if (part != *top + 1)
            cm_ac_enc_uint(e, &ctx->part, (uint64_t)(part - 1));
    }
    *prev = part;
    *top = part > *top ? part : *top;
}

/* format 4.12: the parts' names after them (read_part_names in cm_decode.c): each part's first name
   (parts.c: an IGES label or subfigure name, a STEP product's), a byte below a space sent as one;
   that of the nearest earlier part again by how far back (an assembly's bolts: C1G0B0O's 24 names
   are 7), else its length and bytes; the bytes sent in all first, 0 when no part has a name */
static int write_part_names(cm_ac_enc *e, cm_colr_ctx *ctx, const loaded_model *lm, const enc_parts *p)
{
    char (*name)[80] = calloc((size_t)p->nparts + 1, sizeof *name), two[2][80];
    if (!name)
        return -1;
    for (int k = 1; k <= p->nparts; k++) {
        int nf;
        if (enc_part_names(lm, p, k, two, &nf) > 0)
            for (int c = 0; (name[k][c] = two[0][c]) != 0; c++)
                name[k][c] = (unsigned char)name[k][c] < 0x20u ? ' ' : name[k][c];
    }
    _Static_assert(sizeof name[0] - 1 <= CM_FMT_MAX_PART_NAME, "a part's name within the format's");
    uint64_t total = 0;
    int *again = calloc((size_t)p->nparts + 1, sizeof *again);
    if (!again) {
        free(name);
        return -1;
    }
    for (int k = 1; k <= p->nparts; k++) {
        for (int q = k - 1; q >= 1 && name[k][0] && !again[k]; q--)
            again[k] = strcmp(name[q], name[k]) == 0 ? q : 0;
        total += again[k] ? 0 : strlen(name[k]);
    }
    cm_ac_enc_uint(e, &ctx->name_bytes, total);
    for (int k = 1; k <= p->nparts && total > 0; k++) {
        if (k > 1)
            cm_ac_enc_bit(e, &ctx->name_again, again[k] != 0);
        if (again[k]) {
            cm_ac_enc_uint(e, &ctx->name_back, (uint64_t)(k - 1 - again[k]));
            continue;
        }
        size_t len = strlen(name[k]);
        cm_ac_enc_uint(e, &ctx->name_len, (uint64_t)len);
        for (size_t c = 0; c < len; c++)
            cm_ac_enc_direct(e, (unsigned char)name[k][c], 8);
    }
    free(again);
    free(name);
    return 0;
}

/* format 4.11: the parts in the order of the terminal's assembly steps (parts.c), after the colours:
   their count (0 for a model of one part), each face's, each copy's */
static int write_parts(const tx *t, cm_ac_enc *e, const loaded_model *lm, cm_colr_ctx *ctx)
{
    enc_parts p;
    char why[256];
    cm_status st;
    cm_status_init(&st);
    /* (encode_model read the steps file before anything was chosen: it is not read wrong here) */
    if (enc_parts_build(lm, t->o->steps, &p, why, sizeof why, &st) != CM_OK &&
        enc_parts_build(lm, NULL, &p, why, sizeof why, &st) != CM_OK)
        return -1;
    /* a model whose faces are all loose gets no parts unless steps order them: the viewer joins its
       faces itself (across edges of three faces too, which this does not) */
    int send = p.nparts >= 2 && lm->mesh.nfaces == t->nfaces && (p.held > 0 || t->o->steps);
    if (t->o->test_parts) {
        t->o->test_parts(&p);
        send = p.nparts > 0;
    }
    cm_ac_enc_uint(e, &ctx->nparts, send ? (uint64_t)p.nparts : 0u);
    int i = 0, prev = 0, top = 0;
    uint32_t first, count;
    for (int f = 0; send && f < t->nfaces; f++)
        write_part(e, ctx, i++, p.face_part[f], &prev, &top);
    for (int k = 0; send && k < lm->brep.nplacements; k++)
        if (placement_faces(t, lm, k, &first, &count) > 0)
            write_part(e, ctx, i++, p.place_part[k], &prev, &top);
    int err = send && t->o->compact_minor >= (int)CM_FMT_PART_NAMES_MINOR ? write_part_names(e, ctx, lm, &p) : 0;
    enc_parts_free(&p);
    return err;
}

static int sec_colr(const tx *t, cm_ac_enc *e, const loaded_model *lm)
{
    cm_colr_ctx ctx;
    cm_colr_ctx_init(&ctx);
    cm_ac_enc_uint(e, &ctx.count, (uint64_t)t->npalette);
    for (int i = 1; i <= t->npalette; i++)
        cm_ac_enc_direct(e, t->palette[i], 24);
    for (int f = 0; f < t->nfaces && t->npalette > 0; f++)
        cm_ac_enc_uint(e, &ctx.index, (uint64_t)t->color[f]);
    if (enc_compact_header(t->o) && t->o->compact_minor >= (int)CM_FMT_PARTS_MINOR)
        return write_parts(t, e, lm, &ctx);
    return 0;
}

/*
 * The sections fns[0..n) coded into one stream of the range coder (each starting its own models),
 * into a buffer grown until it holds them.  Format 4 trims the stream (cm_arith.h), which may leave
 * no byte at all.  bytes[s]: what section s took, the coder's output position at its end (bytes
 * written and the pending carry run, less the trimmed leading 0); the flush goes to the last, so
 * they add up to the stream.  Format 4.6 codes the five sections so, one stream (no section pays its
 * own flush, the header no length per section); older formats one stream per section.
 */
static cm_err run_stream(const section_fn *fns, int n, const tx *t, const loaded_model *lm, outbuf *out,
                         size_t *bytes, cm_status *st)
{
    int trimmed = enc_compact_header(t->o);
    size_t cap = 1 << 16;
    for (int attempt = 0; attempt < 24; attempt++, cap *= 2) {
        uint8_t *buf = malloc(cap);
        if (!buf)
            return cm_fail(st, CM_E_NOMEM, "out of memory");
        cm_ac_enc e;
        cm_ac_enc_init(&e, buf, cap);
        size_t at = 0;
        for (int s = 0; s < n; s++) {
            if (fns[s](t, &e, lm) != 0) {
                free(buf);
                return cm_fail(st, CM_E_NOMEM, "out of memory");
            }
            size_t now = e.pos + (size_t)e.cache_size;
            now = now > 0 ? now - 1 : 0;
            bytes[s] = now > at ? now - at : 0;
            at += bytes[s];
        }
        size_t len = trimmed ? cm_ac_enc_finish_trimmed(&e) : cm_ac_enc_finish(&e);
        if (!e.overflow) {
            size_t before = at - bytes[n - 1];
            bytes[n - 1] = len >= before ? len - before : 0;
            out->p = buf;
            out->len = len;
            return CM_OK;
        }
        free(buf);
    }
    return cm_fail(st, CM_E_NOSPACE, "section too large");
}

double enc_file_tess(const tx *t, double tess)
{
    return enc_compact_header(t->o) ? cm_fmt_compact_tess(tess, t->q_exp) : tess;
}

/* assemble header + sections + trailer; needs may be NULL (all zero) */
cm_err enc_write_file(const tx *t, const loaded_model *lm, const encode_opts *o, const uint32_t *need,
                         encode_result *r, cm_status *st)
{
    static const section_fn fns[CM_SEC_COUNT] = {sec_vert, sec_edge, sec_surf, sec_face, sec_colr};
    outbuf sec[CM_SEC_COUNT];
    memset(sec, 0, sizeof sec);
    cm_err e = enc_check_placements(t, lm, st);
    int compact = enc_compact_header(t->o);
    int one_stream = compact && t->o->compact_minor >= (int)CM_FMT_ONE_STREAM_MINOR;
    size_t sec_bytes[CM_SEC_COUNT];
    if (one_stream && e == CM_OK)
        e = run_stream(fns, CM_SEC_COUNT, t, lm, &sec[0], sec_bytes, st);
    for (int s = 0; s < CM_SEC_COUNT && e == CM_OK && !one_stream; s++)
        e = run_stream(&fns[s], 1, t, lm, &sec[s], &sec_bytes[s], st);
    uint8_t hb[CM_FMT_MAX_HEADER];
    cm_fmt_header h = {0};
    uint32_t seclen[CM_SEC_COUNT];
    for (int s = 0; s < CM_SEC_COUNT; s++)
        seclen[s] = (uint32_t)sec[s].len;
    /* the needs up to the last that is not 0, at least format 1.0's 25: format 4.3's MAX_PLACEMENTS
       only with copies (a file without stays as it was, byte for byte) */
    h.nlimits = CM_FMT_MIN_NEEDS;
    for (uint32_t i = CM_FMT_MIN_NEEDS; need && i < CM_LIMIT_COUNT; i++)
        if (need[i])
            h.nlimits = (uint8_t)(i + 1);
    h.nsections = CM_SEC_COUNT;
    h.q_exp = (int8_t)t->q_exp;
    for (int k = 0; k < 3; k++)
        h.origin[k] = t->origin[k];
    h.tess_tol = enc_file_tess(t, o->tess_rel * brep_diag(&lm->brep));
    h.rel_tol = o->rel_tol;
    h.flags = (uint16_t)(t->npalette ? 1 : 0);
    if (compact) {
        h.major = CM_FMT_COMPACT_MAJOR;
        h.minor = (uint8_t)t->o->compact_minor;
    }
    size_t H = cm_fmt_header_len(h.nlimits, CM_SEC_COUNT);
    if (compact) {
        /* the file's own length is one of its needs, and in format 4 the needs' varints size the
           header: packed again until the declared length is the length (twice, at most thrice) */
        uint32_t nd[CM_LIMIT_COUNT] = {0};
        if (need)
            memcpy(nd, need, sizeof nd);
        for (int k = 0; k < 4; k++) {
            H = one_stream ? cm_fmt_stream_pack(hb, &h, nd, (uint32_t)sec[0].len) : cm_fmt_compact_pack(hb, &h, nd, seclen);
            if (!need || H == 0 || nd[CM_LIMIT_MAX_FILE_BYTES] == h.file_len)
                break;
            nd[CM_LIMIT_MAX_FILE_BYTES] = h.file_len;
        }
    }
    if (H == 0 && e == CM_OK)
        e = cm_fail(st, CM_E_FORMAT, "the header does not fit its format's bound");
    size_t total = H + 4;
    for (int s = 0; s < CM_SEC_COUNT; s++) {
        total += sec[s].len;
        r->section_bytes[s + 1] = e == CM_OK ? sec_bytes[s] : 0;
    }
    r->section_bytes[0] = H;
    uint8_t *b = e == CM_OK ? calloc(1, total) : NULL;
    if (e == CM_OK && !b)
        e = cm_fail(st, CM_E_NOMEM, "out of memory");
    if (e == CM_OK && total > 0x7fffffffu)
        e = cm_fail(st, CM_E_NOSPACE, "file larger than 2 GiB");
    if (e == CM_OK) {
        if (compact) {
            memcpy(b, hb, H);
        } else {
            /* the oldest version that can say it: format 1 readers still load files of format 1's methods */
            int major = 1, minor = 0;
            for (int f = 0; f < t->nfaces; f++) {
                const cm_method *M = cm_method_of((unsigned)t->method[f]);
                if (M->since_major > major || (M->since_major == major && M->since_minor > minor)) {
                    major = M->since_major;
                    minor = M->since_minor;
                }
                /* the joined-side layout came with format 2.3 */
                if (M->layouts && t->layout[f] == CM_GREG_LAYOUT_JOINED && major == 2 && minor < 3)
                    minor = 3;
                /* the exact patches' turning basis came with format 2.6 (cm_egreg.h); a face none of whose
                   sides turns rebuilds the same under 2.5 */
                if (t->turning[f] && major == 2 && minor < CM_FMT_TURNING_MINOR)
                    minor = CM_FMT_TURNING_MINOR;
            }
            /* format 3 codes the model predicted, on steps from its tolerance budget (tx_coarsen.c) */
            if (t->o->predicted) {
                major = CM_FMT_PREDICT_MAJOR;
                minor = 0;
            }
            h.major = (uint8_t)major;
            h.minor = (uint8_t)minor;
            h.header_len = (uint32_t)H;
            h.file_len = (uint32_t)total;
            cm_fmt_header_pack(b, &h);
            for (uint32_t i = 0; i < h.nlimits; i++)
                cm_put_u32(b + cm_fmt_need_at(i), need ? need[i] : 0);
            size_t off = H;
            for (uint32_t s = 0; s < CM_SEC_COUNT; s++) {
                uint8_t *ent = b + cm_fmt_entry_at(h.nlimits, s);
                ent[CM_ENT_TAG] = (uint8_t)(s + 1);
                cm_put_u32(ent + CM_ENT_OFFSET, (uint32_t)off);
                cm_put_u32(ent + CM_ENT_LENGTH, (uint32_t)sec[s].len);
                cm_put_u32(ent + CM_ENT_CRC, cm_crc32(sec[s].p, sec[s].len));
                off += sec[s].len;
            }
            cm_put_u32(b + H - 4, cm_crc32(b, H - 4));
        }
        /* the sections back to back after the header, then the file's CRC */
        size_t off = H;
        for (uint32_t s = 0; s < CM_SEC_COUNT; s++) {
            if (sec[s].len)
                memcpy(b + off, sec[s].p, sec[s].len);
            off += sec[s].len;
        }
        cm_put_u32(b + total - 4, cm_crc32(b, total - 4));
        free(r->bytes);
        r->bytes = b;
        r->len = total;
    }
    for (int s = 0; s < CM_SEC_COUNT; s++)
        free(sec[s].p);
    return e;
}
