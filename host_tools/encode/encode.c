/* encode.c - loaded model -> .cmz v1 (see encode.h and docs/FORMAT.md). */
#include "encode.h"
#include "verify.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_arith.h"
#include "cm/cm_corner.h"
#include "cm/cm_cubic_convert.h"
#include "cm/cm_decode.h"
#include "cm/cm_format.h"
#include "cm/cm_rebuild.h"
#include "cm/cm_sections.h"
#include "cm/cm_tessellate.h"

#define WEIGHT_ONE (1ll << CM_FMT_WEIGHT_BITS)
#define KNOT_ONE (1ll << CM_FMT_KNOT_BITS)
/* what the decoder accepts: a value beyond cannot be sent */
#define GRID_MAX CM_FMT_COORD_MAX
#define WEIGHT_MAX CM_FMT_WEIGHT_MAX

void encode_opts_default(encode_opts *o)
{
    o->rel_tol = 0.01;    /* spec §1 RATIO_TOL: 1 % of the face's bounding box */
    o->quant_rel = 1e-6;  /* grid step: 1e-6 of the diagonal, far below any rebuild tolerance */
    o->tess_rel = 5e-4;   /* chordal tolerance for viewers: 0.05 % of the diagonal */
    o->target = NULL;
    o->target_name = NULL;
    o->gregory = 1;
    o->strict = 0;
    o->abs_tol = 0;
    o->rel_set = 0;
    o->progress = NULL;
    o->progress_ctx = NULL;
}

double encode_face_tol(double rel_tol, int rel_set, double abs_tol, double bbox)
{
    if (!(abs_tol > 0))
        return rel_tol * bbox;
    return rel_set && rel_tol * bbox < abs_tol ? rel_tol * bbox : abs_tol;
}

void encode_result_free(encode_result *r)
{
    free(r->bytes);
    free(r->faces);
    memset(r, 0, sizeof *r);
}

/* ---- the transmitted model (quantised, in transmission order) ---- */

typedef struct tx_edge {
    int v0, v1;       /* transmitted vertex numbers */
    int g1, kind, p, n, rational, uniform;
    int64_t *kq;      /* n - p - 1 interior knots */
    int64_t (*cq)[3]; /* n control points on the grid (ends = vertices) */
    int64_t *wq;      /* n weights */
} tx_edge;

typedef struct tx_surf {
    int p, q, nu, nv, rational, uniform_u, uniform_v;
    int64_t *ku, *kv;
    int64_t (*cq)[3];
    int64_t *wq;
} tx_surf;

typedef struct tx {
    double origin[3], q;
    int q_exp;
    int nverts, nedges, nfaces, nsurfs;
    int64_t (*vq)[3];   /* vertices in transmission order */
    tx_edge *edges;     /* in transmission order */
    int *edge_tx;       /* cmesh edge -> transmission number */
    int *vert_tx;       /* cmesh vertex -> transmission number */
    tx_surf *surfs;     /* one per face (used for KEEP faces) */
    int *method;        /* per face */
    int *layout, *corner; /* per GREGORY face: its record (spec 15.2) */
    uint32_t *checksum;
    uint32_t palette[CM_FMT_MAX_PALETTE + 1];
    int npalette;
    int *color;         /* per face palette index */
    const unsigned char *keep_only; /* per B-rep face: KEEP, a rebuilt surface did not tessellate */
    const char **fault; /* per face: why it cannot be sent (NULL: it can); see encode_model */
    int nfaults;
} tx;

/* face f cannot be sent as it is; the first reason stays */
static void face_fault(tx *t, int f, const char *why)
{
    if (!t->fault[f]) {
        t->fault[f] = why;
        t->nfaults++;
    }
}

/* drop the transmitted edges and vertices (build_edges makes them again) */
static void tx_free_edges(tx *t)
{
    for (int i = 0; i < t->nedges; i++) {
        free(t->edges[i].kq);
        free(t->edges[i].cq);
        free(t->edges[i].wq);
    }
    free(t->vq);
    free(t->edges);
    free(t->edge_tx);
    free(t->vert_tx);
    t->vq = NULL;
    t->edges = NULL;
    t->edge_tx = t->vert_tx = NULL;
    t->nedges = t->nverts = 0;
}

static void tx_free(tx *t)
{
    tx_free_edges(t);
    for (int i = 0; i < t->nfaces; i++) {
        free(t->surfs[i].ku);
        free(t->surfs[i].kv);
        free(t->surfs[i].cq);
        free(t->surfs[i].wq);
    }
    free(t->surfs);
    free(t->method);
    free(t->layout);
    free(t->corner);
    free(t->checksum);
    free(t->color);
    free(t->fault);
    memset(t, 0, sizeof *t);
}


/* p on the grid; 0 when it is not finite or beyond what the decoder accepts (out is then 0) */
static int quantise(const tx *t, cm_vec3 p, int64_t out[3])
{
    double c[3] = {(p.x - t->origin[0]) / t->q, (p.y - t->origin[1]) / t->q, (p.z - t->origin[2]) / t->q};
    int ok = 1;
    for (int k = 0; k < 3; k++) {
        ok &= fabs(c[k]) <= (double)GRID_MAX; /* false for NaN too */
        out[k] = fabs(c[k]) <= (double)GRID_MAX ? llround(c[k]) : 0;
    }
    return ok;
}

/* a weight relative to the first on the format's grid; 0 when it cannot be sent */
static int64_t quantise_weight(double w, double w0)
{
    double r = (double)WEIGHT_ONE * w / w0;
    if (!(r > 0 && r <= (double)WEIGHT_MAX))
        return 0;
    int64_t q = llround(r);
    return q < 1 ? 1 : q;
}

/* ---- orientation: every part's faces agree on shared edges (they run both ways) ---- */

static void flip_face(loaded_model *lm, int f)
{
    cmesh *cm = &lm->mesh;
    const cmesh_face *cf = &cm->faces[f];
    for (int l = 0; l < cf->nloops; l++) {
        const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
        for (int i = 0; i < cl->n / 2; i++) {
            cmesh_use t = cm->uses[cl->first + i];
            cm->uses[cl->first + i] = cm->uses[cl->first + cl->n - 1 - i];
            cm->uses[cl->first + cl->n - 1 - i] = t;
        }
        for (int i = 0; i < cl->n; i++)
            cm->uses[cl->first + i].rev ^= 1;
    }
    lm->brep.faces[cf->brep_face].flip ^= 1;
}

static int orient_parts(loaded_model *lm)
{
    cmesh *cm = &lm->mesh;
    int nf = cm->nfaces, flips = 0;
    /* per edge: the face and rev of its first two uses */
    int *ef = malloc((size_t)cm->nedges * 2 * sizeof(int)), *er = malloc((size_t)cm->nedges * 2 * sizeof(int));
    int *cnt = calloc((size_t)cm->nedges + 1, sizeof(int));
    int *queue = malloc((size_t)(nf + 1) * sizeof(int));
    unsigned char *seen = calloc((size_t)nf + 1, 1), *flip = calloc((size_t)nf + 1, 1);
    if (!ef || !er || !cnt || !queue || !seen || !flip)
        goto done;
    for (int f = 0; f < nf; f++) {
        const cmesh_face *cf = &cm->faces[f];
        for (int l = 0; l < cf->nloops; l++) {
            const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
            for (int i = 0; i < cl->n; i++) {
                const cmesh_use *u = &cm->uses[cl->first + i];
                if (cnt[u->edge] < 2) {
                    ef[2 * u->edge + cnt[u->edge]] = f;
                    er[2 * u->edge + cnt[u->edge]] = u->rev;
                }
                cnt[u->edge]++;
            }
        }
    }
    for (int s = 0; s < nf; s++) {
        if (seen[s])
            continue;
        int head = 0, tail = 0;
        queue[tail++] = s;
        seen[s] = 1;
        while (head < tail) {
            int f = queue[head++];
            const cmesh_face *cf = &cm->faces[f];
            for (int l = 0; l < cf->nloops; l++) {
                const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
                for (int i = 0; i < cl->n; i++) {
                    int e = cm->uses[cl->first + i].edge;
                    if (cm->edges[e].kind != CMESH_SHARED)
                        continue;
                    int side = ef[2 * e] == f ? 0 : 1, g = ef[2 * e + 1 - side];
                    if (seen[g])
                        continue;
                    int rf = er[2 * e + side] ^ flip[f], rg = er[2 * e + 1 - side];
                    flip[g] = rf == rg; /* the same way in both: turn g */
                    seen[g] = 1;
                    queue[tail++] = g;
                }
            }
        }
    }
    for (int f = 0; f < nf; f++)
        if (flip[f]) {
            flip_face(lm, f);
            flips++;
        }
done:
    free(ef);
    free(er);
    free(cnt);
    free(queue);
    free(seen);
    free(flip);
    return flips;
}

/* ---- building the transmitted model ---- */

/*
 * Clean a clamped knot vector on [0,1] for transmission: knots closer than
 * a few quanta of the format's knot grid are made equal (exporters write
 * spans of 1e-16 at the ends of arcs), then every basis function whose
 * support has become empty is dropped with its control point: it has no
 * influence on the curve.  Shape changes by the length of the dropped
 * spans (far below the coordinate grid).  keep[j] tells which control
 * points stay; the knot vector is compacted in place; returns the new
 * count of control points.
 */
static int clean_knots(int p, int n, double *U, unsigned char *keep)
{
    const double eps = 4.0 / (double)KNOT_ONE;
    int m = n + p + 1;
    for (int j = 1; j < m; j++) {
        if (U[j] - U[j - 1] < eps)
            U[j] = U[j - 1];
        if (1.0 - U[j] < eps)
            U[j] = 1.0;
    }
    int nn = 0;
    for (int j = 0; j < n; j++) {
        keep[j] = U[j] != U[j + p + 1];
        nn += keep[j];
    }
    int k = 0;
    for (int j = 0; j < m; j++)
        if (j >= n || keep[j])
            U[k++] = U[j];
    return nn;
}

/* 1 if the curve is the straight segment between its ends (collinear, monotone control points) */
static int is_segment(const hcurve *c, double tol)
{
    cm_vec3 a = c->ctrl[0], b = c->ctrl[c->n - 1], d = cm_sub(b, a);
    double L = cm_norm(d);
    if (!(L > 10 * tol))
        return 0;
    cm_vec3 u = cm_scale(d, 1.0 / L);
    double prev = -1;
    for (int i = 0; i < c->n; i++) {
        cm_vec3 r = cm_sub(c->ctrl[i], a);
        double t = cm_dot(r, u);
        if (cm_norm(cm_sub(r, cm_scale(u, t))) > tol || t < prev - tol)
            return 0;
        prev = t;
    }
    return 1;
}

static cm_err build_edges(loaded_model *lm, tx *t, cm_status *st)
{
    cmesh *cm = &lm->mesh;
    t->edge_tx = malloc((size_t)(cm->nedges + 1) * sizeof(int));
    t->vert_tx = malloc((size_t)(cm->nverts + 1) * sizeof(int));
    t->edges = calloc((size_t)cm->nedges + 1, sizeof *t->edges);
    t->vq = malloc((size_t)(cm->nverts + 1) * sizeof *t->vq);
    if (!t->edge_tx || !t->vert_tx || !t->edges || !t->vq)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    for (int e = 0; e < cm->nedges; e++)
        t->edge_tx[e] = -1;
    for (int v = 0; v < cm->nverts; v++)
        t->vert_tx[v] = -1;
    /* edges in the order the faces first use them; vertices as the edges first touch them */
    int *order = malloc((size_t)(cm->nedges + 1) * sizeof(int));
    if (!order)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    /* the same walk as sec_face (faces, their loops, the loops' uses): the cmesh
       use array need not be in that order (a hole's loop may be stored later) */
    for (int f = 0; f < t->nfaces; f++) {
        const cmesh_face *cf = &cm->faces[f];
        for (int l = 0; l < cf->nloops; l++) {
            const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
            for (int i = 0; i < cl->n; i++) {
                int e = cm->uses[cl->first + i].edge;
                if (t->edge_tx[e] < 0) {
                    order[t->nedges] = e;
                    t->edge_tx[e] = t->nedges++;
                }
            }
        }
    }
    /* an edge that cannot be sent (its curve or an end off the grid) takes its faces out: why[e] */
    const char **why = calloc((size_t)cm->nedges + 1, sizeof *why);
    unsigned char *off_grid = calloc((size_t)cm->nverts + 1, 1);
    if (!why || !off_grid) {
        free(why);
        free(off_grid);
        free(order);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    for (int i = 0; i < t->nedges; i++) {
        const cmesh_edge *E = &cm->edges[order[i]];
        int vs[2] = {E->v0, E->v1};
        for (int k = 0; k < 2; k++)
            if (t->vert_tx[vs[k]] < 0) {
                off_grid[vs[k]] = !quantise(t, cm->verts[vs[k]], t->vq[t->nverts]);
                t->vert_tx[vs[k]] = t->nverts++;
            }
    }
    for (int i = 0; i < t->nedges; i++)
        if (off_grid[cm->edges[order[i]].v0] || off_grid[cm->edges[order[i]].v1])
            why[order[i]] = "a vertex lies off the coordinate grid (not finite or too far from the model)";
    free(off_grid);
    cm_err err = CM_OK;
    for (int i = 0; i < t->nedges && err == CM_OK; i++) {
        const cmesh_edge *E = &cm->edges[order[i]];
        tx_edge *X = &t->edges[i];
        X->v0 = t->vert_tx[E->v0];
        X->v1 = t->vert_tx[E->v1];
        X->g1 = E->g1;
        if (why[order[i]])
            continue;
        hcurve c = {0};
        cm_status cst;
        cm_status_init(&cst);
        if ((err = hcurve_clamp(&E->c, &c, &cst)) != CM_OK) {
            if (err == CM_E_NOMEM)
                break;
            why[order[i]] = "an edge curve cannot be clamped to its ends";
            err = CM_OK;
            continue;
        }
        hcurve_reparam(&c, 0.0, 1.0);
        {
            unsigned char *keep = malloc((size_t)c.n);
            if (!keep) {
                hcurve_free(&c);
                err = cm_fail(st, CM_E_NOMEM, "out of memory");
                break;
            }
            int nn = clean_knots(c.p, c.n, c.knots, keep), k = 0;
            for (int j = 0; j < c.n; j++)
                if (keep[j]) {
                    c.ctrl[k] = c.ctrl[j];
                    if (c.w)
                        c.w[k] = c.w[j];
                    k++;
                }
            c.n = nn;
            free(keep);
        }
        if (X->v0 != X->v1 && (c.n == 2 || is_segment(&c, t->q))) {
            X->kind = CM_EDGE_LINE;
            X->p = 1;
            X->n = 2;
        } else {
            X->kind = CM_EDGE_CURVE;
            X->p = c.p;
            X->n = c.n;
        }
        int n = X->n, p = X->p, interior = n - p - 1;
        X->cq = malloc((size_t)n * sizeof *X->cq);
        X->wq = malloc((size_t)n * sizeof *X->wq);
        X->kq = malloc((size_t)(interior > 0 ? interior : 1) * sizeof *X->kq);
        if (!X->cq || !X->wq || !X->kq) {
            hcurve_free(&c);
            err = cm_fail(st, CM_E_NOMEM, "out of memory");
            break;
        }
        memcpy(X->cq[0], t->vq[X->v0], sizeof X->cq[0]);
        memcpy(X->cq[n - 1], t->vq[X->v1], sizeof X->cq[0]);
        X->rational = 0;
        X->uniform = 1;
        for (int j = 0; j < n; j++)
            X->wq[j] = WEIGHT_ONE;
        if (X->kind == CM_EDGE_CURVE) {
            for (int j = 1; j < n - 1; j++)
                if (!quantise(t, c.ctrl[j], X->cq[j]))
                    why[order[i]] = "an edge's control point lies off the coordinate grid";
            if (c.w)
                for (int j = 0; j < n; j++) {
                    X->wq[j] = quantise_weight(c.w[j], c.w[0]);
                    if (X->wq[j] == 0)
                        why[order[i]] = "an edge's weights cannot be sent (ratio out of range)";
                    if (X->wq[j] != WEIGHT_ONE)
                        X->rational = 1;
                }
            for (int j = 1; j <= interior; j++) {
                double k = c.knots[p + j];
                X->kq[j - 1] = llround(k * (double)KNOT_ONE);
                if (fabs(k - (double)j / (double)(interior + 1)) > 0.5 / (double)KNOT_ONE)
                    X->uniform = 0;
            }
        }
        hcurve_free(&c);
    }
    for (int f = 0; f < t->nfaces && err == CM_OK; f++) {
        const cmesh_face *cf = &cm->faces[f];
        for (int l = 0; l < cf->nloops; l++) {
            const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
            for (int i = 0; i < cl->n; i++)
                if (why[cm->uses[cl->first + i].edge])
                    face_fault(t, f, why[cm->uses[cl->first + i].edge]);
        }
    }
    free(why);
    free(order);
    return err;
}

static cm_err build_surface(const tx *t, const hsurf *orig, tx_surf *S, cm_status *st)
{
    hsurf s = {0};
    double u0, u1, v0, v1;
    hsurf_domain(orig, &u0, &u1, &v0, &v1);
    cm_err e = hsurf_subrange(orig, u0, u1, v0, v1, &s, st); /* clamped on its domain */
    if (e != CM_OK)
        return e;
    /* knots on [0,1], cleaned like the edges' (rows and columns without influence dropped) */
    for (int i = 0; i < s.nu + s.p + 1; i++)
        s.U[i] = i <= s.p ? 0.0 : (i >= s.nu ? 1.0 : (s.U[i] - u0) / (u1 - u0));
    for (int i = 0; i < s.nv + s.q + 1; i++)
        s.V[i] = i <= s.q ? 0.0 : (i >= s.nv ? 1.0 : (s.V[i] - v0) / (v1 - v0));
    unsigned char *ku = malloc((size_t)s.nu), *kv = malloc((size_t)s.nv);
    if (!ku || !kv) {
        free(ku);
        free(kv);
        hsurf_free(&s);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    int nu = clean_knots(s.p, s.nu, s.U, ku), nv = clean_knots(s.q, s.nv, s.V, kv), kept = 0;
    for (int i = 0; i < s.nu; i++)
        for (int j = 0; j < s.nv; j++)
            if (ku[i] && kv[j]) {
                s.ctrl[kept] = s.ctrl[i * s.nv + j];
                if (s.w)
                    s.w[kept] = s.w[i * s.nv + j];
                kept++;
            }
    s.nu = nu;
    s.nv = nv;
    free(ku);
    free(kv);
    S->p = s.p;
    S->q = s.q;
    S->nu = s.nu;
    S->nv = s.nv;
    int nku = s.nu - s.p - 1, nkv = s.nv - s.q - 1;
    long total = (long)s.nu * s.nv;
    S->ku = malloc((size_t)(nku > 0 ? nku : 1) * sizeof(int64_t));
    S->kv = malloc((size_t)(nkv > 0 ? nkv : 1) * sizeof(int64_t));
    S->cq = malloc((size_t)total * sizeof *S->cq);
    S->wq = malloc((size_t)total * sizeof *S->wq);
    if (!S->ku || !S->kv || !S->cq || !S->wq) {
        hsurf_free(&s);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    S->uniform_u = S->uniform_v = 1;
    for (int j = 1; j <= nku; j++) {
        double k = s.U[s.p + j];
        S->ku[j - 1] = llround(k * (double)KNOT_ONE);
        if (fabs(k - (double)j / (double)(nku + 1)) > 0.5 / (double)KNOT_ONE)
            S->uniform_u = 0;
    }
    for (int j = 1; j <= nkv; j++) {
        double k = s.V[s.q + j];
        S->kv[j - 1] = llround(k * (double)KNOT_ONE);
        if (fabs(k - (double)j / (double)(nkv + 1)) > 0.5 / (double)KNOT_ONE)
            S->uniform_v = 0;
    }
    S->rational = 0;
    for (long i = 0; i < total && e == CM_OK; i++) {
        if (!quantise(t, s.ctrl[i], S->cq[i]))
            e = cm_fail(st, CM_E_RANGE, "a surface control point lies off the coordinate grid");
        S->wq[i] = WEIGHT_ONE;
        if (s.w) {
            S->wq[i] = quantise_weight(s.w[i], s.w[0]);
            if (S->wq[i] == 0)
                e = cm_fail(st, CM_E_RANGE, "the surface's weights cannot be sent (ratio out of range)");
            if (S->wq[i] != WEIGHT_ONE)
                S->rational = 1;
        }
    }
    hsurf_free(&s);
    return e;
}

/* ---- writing ---- */

typedef struct outbuf {
    uint8_t *p;
    size_t len;
} outbuf;

typedef void (*section_fn)(const tx *t, cm_ac_enc *e, const loaded_model *lm);

static void put_knots(cm_ac_enc *e, cm_ac_prob *puni, cm_ac_int *mk, int uniform, const int64_t *kq, int interior)
{
    cm_ac_enc_bit(e, puni, (unsigned)uniform);
    if (uniform)
        return;
    int64_t prev = 0;
    for (int j = 0; j < interior; j++) {
        cm_ac_enc_uint(e, mk, (uint64_t)(kq[j] - prev));
        prev = kq[j];
    }
}

static void sec_vert(const tx *t, cm_ac_enc *e, const loaded_model *lm)
{
    (void)lm;
    cm_vert_ctx ctx;
    cm_vert_ctx_init(&ctx);
    cm_ac_enc_uint(e, &ctx.count, (uint64_t)t->nverts);
    int64_t prev[3] = {0, 0, 0};
    for (int i = 0; i < t->nverts; i++)
        for (int k = 0; k < 3; k++) {
            cm_ac_enc_sint(e, &ctx.coord[k], t->vq[i][k] - prev[k]);
            prev[k] = t->vq[i][k];
        }
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

static void sec_edge(const tx *t, cm_ac_enc *e, const loaded_model *lm)
{
    (void)lm;
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
        cm_ac_enc_uint(e, &ctx.degree, (uint64_t)(X->p - 1));
        cm_ac_enc_uint(e, &ctx.ncoef, (uint64_t)(X->n - X->p - 1));
        cm_ac_enc_bit(e, &ctx.rational, (unsigned)X->rational);
        put_knots(e, &ctx.uniform, &ctx.knot, X->uniform, X->kq, X->n - X->p - 1);
        int64_t prev[3] = {X->cq[0][0], X->cq[0][1], X->cq[0][2]};
        for (int j = 1; j < X->n - 1; j++)
            for (int k = 0; k < 3; k++) {
                cm_ac_enc_sint(e, &ctx.coord[k], X->cq[j][k] - prev[k]);
                prev[k] = X->cq[j][k];
            }
        if (X->rational)
            for (int j = 1; j < X->n; j++)
                cm_ac_enc_sint(e, &ctx.weight, X->wq[j] - X->wq[j - 1]);
    }
}

static void sec_surf(const tx *t, cm_ac_enc *e, const loaded_model *lm)
{
    (void)lm;
    cm_surf_ctx ctx;
    cm_surf_ctx_init(&ctx);
    int nkeep = 0;
    for (int f = 0; f < t->nfaces; f++)
        nkeep += t->method[f] == CM_METHOD_KEEP;
    cm_ac_enc_uint(e, &ctx.count, (uint64_t)nkeep);
    for (int f = 0; f < t->nfaces; f++) {
        if (t->method[f] != CM_METHOD_KEEP)
            continue;
        const tx_surf *S = &t->surfs[f];
        cm_ac_enc_uint(e, &ctx.degree, (uint64_t)(S->p - 1));
        cm_ac_enc_uint(e, &ctx.ncoef, (uint64_t)(S->nu - S->p - 1));
        cm_ac_enc_uint(e, &ctx.degree, (uint64_t)(S->q - 1));
        cm_ac_enc_uint(e, &ctx.ncoef, (uint64_t)(S->nv - S->q - 1));
        cm_ac_enc_bit(e, &ctx.rational, (unsigned)S->rational);
        put_knots(e, &ctx.uniform, &ctx.knot, S->uniform_u, S->ku, S->nu - S->p - 1);
        put_knots(e, &ctx.uniform, &ctx.knot, S->uniform_v, S->kv, S->nv - S->q - 1);
        int nu = S->nu, nv = S->nv;
        for (int i = 0; i < nu; i++)
            for (int j = 0; j < nv; j++) {
                int idx = i * nv + j;
                for (int k = 0; k < 3; k++) {
                    int64_t pred = i && j ? S->cq[idx - nv][k] + S->cq[idx - 1][k] - S->cq[idx - nv - 1][k]
                                   : i    ? S->cq[idx - nv][k]
                                   : j    ? S->cq[idx - 1][k]
                                          : 0;
                    cm_ac_enc_sint(e, &ctx.coord[k], S->cq[idx][k] - pred);
                }
                if (S->rational && idx > 0) {
                    int64_t pred = i && j ? S->wq[idx - nv] + S->wq[idx - 1] - S->wq[idx - nv - 1]
                                   : i    ? S->wq[idx - nv]
                                          : S->wq[idx - 1];
                    cm_ac_enc_sint(e, &ctx.weight, S->wq[idx] - pred);
                }
            }
    }
}

static void sec_face(const tx *t, cm_ac_enc *e, const loaded_model *lm)
{
    const cmesh *cm = &lm->mesh;
    cm_face_ctx ctx;
    cm_face_ctx_init(&ctx);
    cm_ac_enc_uint(e, &ctx.count, (uint64_t)t->nfaces);
    int enext = 0;
    for (int f = 0; f < t->nfaces; f++) {
        const cmesh_face *cf = &cm->faces[f];
        cm_ac_enc_uint(e, &ctx.method, (uint64_t)t->method[f]);
        if (t->method[f] == CM_METHOD_GREGORY) {
            cm_ac_enc_uint(e, &ctx.layout, (uint64_t)t->layout[f]);
            cm_ac_enc_uint(e, &ctx.corner, (uint64_t)t->corner[f]);
            cm_ac_enc_direct(e, t->checksum[f] & 0xffffu, 16);
            cm_ac_enc_direct(e, t->checksum[f] >> 16, 16);
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
}

static void sec_colr(const tx *t, cm_ac_enc *e, const loaded_model *lm)
{
    (void)lm;
    cm_colr_ctx ctx;
    cm_colr_ctx_init(&ctx);
    cm_ac_enc_uint(e, &ctx.count, (uint64_t)t->npalette);
    for (int i = 1; i <= t->npalette; i++)
        cm_ac_enc_direct(e, t->palette[i], 24);
    if (t->npalette == 0)
        return;
    for (int f = 0; f < t->nfaces; f++)
        cm_ac_enc_uint(e, &ctx.index, (uint64_t)t->color[f]);
}

static cm_err run_section(section_fn fn, const tx *t, const loaded_model *lm, outbuf *out, cm_status *st)
{
    size_t cap = 1 << 16;
    for (int attempt = 0; attempt < 24; attempt++, cap *= 2) {
        uint8_t *buf = malloc(cap);
        if (!buf)
            return cm_fail(st, CM_E_NOMEM, "out of memory");
        cm_ac_enc e;
        cm_ac_enc_init(&e, buf, cap);
        fn(t, &e, lm);
        size_t n = cm_ac_enc_finish(&e);
        if (n > 0) {
            out->p = buf;
            out->len = n;
            return CM_OK;
        }
        free(buf);
    }
    return cm_fail(st, CM_E_NOSPACE, "section too large");
}

/* assemble header + sections + trailer; needs may be NULL (all zero) */
static cm_err write_file(const tx *t, const loaded_model *lm, const encode_opts *o, const uint32_t *need,
                         encode_result *r, cm_status *st)
{
    static const section_fn fns[CM_SEC_COUNT] = {sec_vert, sec_edge, sec_surf, sec_face, sec_colr};
    outbuf sec[CM_SEC_COUNT];
    memset(sec, 0, sizeof sec);
    cm_err e = CM_OK;
    for (int s = 0; s < CM_SEC_COUNT && e == CM_OK; s++)
        e = run_section(fns[s], t, lm, &sec[s], st);
    size_t H = CM_FMT_FIXED_HEADER + 4u * CM_LIMIT_COUNT + CM_FMT_SECTION_ENTRY * CM_SEC_COUNT + 4u;
    size_t total = H + 4;
    for (int s = 0; s < CM_SEC_COUNT; s++) {
        total += sec[s].len;
        r->section_bytes[s + 1] = sec[s].len;
    }
    r->section_bytes[0] = H;
    uint8_t *b = e == CM_OK ? calloc(1, total) : NULL;
    if (e == CM_OK && !b)
        e = cm_fail(st, CM_E_NOMEM, "out of memory");
    if (e == CM_OK && total > 0x7fffffffu)
        e = cm_fail(st, CM_E_NOSPACE, "file larger than 2 GiB");
    if (e == CM_OK) {
        b[0] = CM_FMT_MAGIC0;
        b[1] = CM_FMT_MAGIC1;
        b[2] = CM_FMT_MAGIC2;
        b[3] = CM_FMT_MAGIC3;
        /* the oldest version that can say it: format 1 readers still load PLANE/KEEP-only files */
        int greg = 0;
        for (int f = 0; f < t->nfaces; f++)
            greg |= t->method[f] == CM_METHOD_GREGORY;
        b[4] = greg ? CM_FMT_VERSION_MAJOR : 1;
        b[5] = greg ? CM_FMT_VERSION_MINOR : 0;
        cm_put_u16(b + 6, (uint16_t)(t->npalette ? 1 : 0));
        cm_put_u32(b + 8, (uint32_t)H);
        cm_put_u32(b + 12, (uint32_t)total);
        b[16] = CM_LIMIT_COUNT;
        b[17] = CM_SEC_COUNT;
        b[18] = (uint8_t)(int8_t)t->q_exp;
        for (int k = 0; k < 3; k++)
            cm_put_f64(b + 20 + 8 * k, t->origin[k]);
        double diag = brep_diag(&lm->brep);
        cm_put_f64(b + 44, o->tess_rel * diag);
        cm_put_f64(b + 52, o->rel_tol);
        for (int i = 0; i < CM_LIMIT_COUNT; i++)
            cm_put_u32(b + CM_FMT_FIXED_HEADER + 4 * i, need ? need[i] : 0);
        size_t off = H;
        for (int s = 0; s < CM_SEC_COUNT; s++) {
            uint8_t *ent = b + CM_FMT_FIXED_HEADER + 4 * CM_LIMIT_COUNT + CM_FMT_SECTION_ENTRY * s;
            ent[0] = (uint8_t)(s + 1);
            cm_put_u32(ent + 4, (uint32_t)off);
            cm_put_u32(ent + 8, (uint32_t)sec[s].len);
            cm_put_u32(ent + 12, cm_crc32(sec[s].p, sec[s].len));
            memcpy(b + off, sec[s].p, sec[s].len);
            off += sec[s].len;
        }
        cm_put_u32(b + H - 4, cm_crc32(b, H - 4));
        cm_put_u32(b + total - 4, cm_crc32(b, total - 4));
        free(r->bytes);
        r->bytes = b;
        r->len = total;
    }
    for (int s = 0; s < CM_SEC_COUNT; s++)
        free(sec[s].p);
    return e;
}

/* ---- decoding what we wrote, with the terminal's code ---- */

static cm_decoder dec; /* large: static, like on the terminal */

static cm_err decode_back(const encode_result *r, cm_status *st)
{
    cm_dec_init(&dec);
    cm_err e = cm_dec_feed(&dec, r->bytes, r->len, st);
    if (e == CM_OK)
        e = cm_dec_finish(&dec, st);
    if (e != CM_OK && st && e != CM_E_NOMEM) {
        /* a byte of a file the user never sees names nothing: the fault is the encoder's */
        st->offset = CM_NO_OFFSET;
        st->where = "the encoder's check of its own file (an encoder bug: please report it with the model)";
    }
    return e;
}

/* ---- method choice per face ---- */

static cm_rebuild_ws rbws;

/* spec §1 SIN_FLAT and the K7 acceptance of spec 6 */
#define SIN_FLAT 0.08715574274765817
#define K7_ACCEPT 0.25

/* rebuild face f of the decoded model with a trial record (decoder code, no checksum yet) */
static cm_err trial_rebuild(int f, int method, int layout, int corner, cm_rebuilt *rb)
{
    cm_face *F = &dec.model.faces[f];
    cm_face saved = *F;
    F->method = (uint8_t)method;
    F->layout = (uint8_t)layout;
    F->corner = (uint8_t)corner;
    cm_err e = cm_rebuild_face_ex(&dec.model, (uint32_t)f, 0, rb, &rbws, NULL);
    *F = saved;
    return e;
}

/* spec 5A applicability and §12 verification of PLANE for face f of the decoded model */
static int try_plane(const loaded_model *lm, int f, const encode_opts *o, face_report *rep, face_surface *fs)
{
    cm_model *m = &dec.model;
    cm_rebuilt rb;
    if (trial_rebuild(f, CM_METHOD_PLANE, 0, 0, &rb) != CM_OK)
        return 0;
    double tol = encode_face_tol(o->rel_tol, o->rel_set, o->abs_tol, rb.bbox);
    int n, n_outer;
    if (cm_face_samples(m, (uint32_t)f, rbws.samples, CM_MAX_FACE_SAMPLES, &n, &n_outer, NULL) != CM_OK)
        return 0;
    double dev = 0;
    for (int i = 0; i < n; i++)
        dev = fmax(dev, fabs(cm_frame_local(&rb.frame, rbws.samples[i]).z));
    rep->plane_dev = dev;
    rep->bbox = rb.bbox;
    if (dev > 0.25 * tol)
        return 0; /* spec 5A: the boundary is not flat enough */
    face_error fe;
    if (!verify_face(lm, m, f, &rb, tol, &fe))
        return 0;
    rep->rebuild_max = fe.max;
    rep->rebuild_avg = fe.avg;
    rep->ratio = fe.ratio;
    if (!(fe.max < tol))
        return 0;
    return face_surface_set(&fs[f], &rb);
}

/*
 * Spec §6 applicability of GREGORY for face f: an outer loop of 3..CM_MAX_SIDES edges, each
 * cubic-convertible within a quarter of the tolerance (K7), no reflex corner.  This version also
 * asks for no holes: the rebuilt patches cover the outer loop, and a terminal would have to trim
 * them by the holes' projections (left to the fitting methods).  Fills the corner angles' cosines
 * for the layout-2 order.  Returns 0 (and why, in rep->why) when not applicable.
 */
static int gregory_applicable(int f, double tol, double *corner_cos, face_report *rep)
{
    const cm_model *m = &dec.model;
    const cm_face *F = &m->faces[f];
    const cm_loop *L = &m->loops[F->loop0];
    int n = (int)L->nuse;
    if (F->nloops != 1) {
        rep->why = "holes";
        return 0;
    }
    if (n < 3 || n > CM_MAX_SIDES) {
        rep->why = n < 3 ? "fewer than 3 sides" : "too many sides";
        return 0;
    }
    cm_cubic cub[CM_MAX_SIDES];
    for (int k = 0; k < n; k++) {
        const cm_use *U = &m->uses[L->use0 + (uint32_t)k];
        cm_curve c;
        cm_model_edge_curve(m, U->edge, &c);
        double delta = 0;
        if (cm_cubic_convert(&c, 0.0, 1.0, &cub[k], &delta, NULL, NULL) != CM_OK || !(delta <= K7_ACCEPT * tol)) {
            rep->why = "edge not cubic-convertible";
            return 0;
        }
        if (U->rev)
            cub[k] = cm_cubic_reverse(&cub[k]);
    }
    double bbox;
    cm_vec3 nF;
    if (cm_face_normal(m, (uint32_t)f, rbws.samples, &bbox, &nF, NULL) != CM_OK) {
        rep->why = "no face normal";
        return 0;
    }
    for (int k = 0; k < n; k++) {
        const cm_cubic *in = &cub[(k + n - 1) % n], *out = &cub[k];
        cm_vec3 ta = cm_sub(in->c[3], in->c[2]), tb = cm_sub(out->c[1], out->c[0]);
        if (!(cm_norm(ta) > 0) || !(cm_norm(tb) > 0)) {
            rep->why = "degenerate edge";
            return 0;
        }
        cm_vec3 a = cm_neg(cm_unit(ta)), b = cm_unit(tb), x = cm_cross(b, a);
        corner_cos[k] = cm_dot(a, b);
        if (cm_norm(x) >= SIN_FLAT && cm_dot(x, nF) <= 0) {
            rep->why = "reflex corner";
            return 0;
        }
    }
    return 1;
}

/* spec §14 candidate list of the GREGORY family; the first that passes §12 wins */
static int try_gregory(const loaded_model *lm, int f, const encode_opts *o, face_report *rep, face_surface *fs,
                       tx *t)
{
    double ccos[CM_MAX_SIDES];
    double tol = encode_face_tol(o->rel_tol, o->rel_set, o->abs_tol, rep->bbox);
    if (!gregory_applicable(f, tol, ccos, rep))
        return 0;
    int n = (int)dec.model.loops[dec.model.faces[f].loop0].nuse;
    int cand_layout[4], cand_j[4], nc = 0;
    if (n == 4) {
        cand_layout[nc] = CM_GREG_LAYOUT_QUAD;
        cand_j[nc++] = 0;
    } else {
        cand_layout[nc] = CM_GREG_LAYOUT_SPLIT;
        cand_j[nc++] = 0;
    }
    if (n == 3) {
        /* layout 2 with j by increasing corner angle: decreasing cosine of the angle between a, b */
        int order[3] = {0, 1, 2};
        for (int i = 1; i < 3; i++)
            for (int k = i; k > 0 && ccos[order[k]] > ccos[order[k - 1]]; k--) {
                int x = order[k];
                order[k] = order[k - 1];
                order[k - 1] = x;
            }
        for (int i = 0; i < 3; i++) {
            cand_layout[nc] = CM_GREG_LAYOUT_DEGEN;
            cand_j[nc++] = order[i];
        }
    }
    double best_ratio = HUGE_VAL;
    for (int c = 0; c < nc; c++) {
        cm_rebuilt rb;
        if (trial_rebuild(f, CM_METHOD_GREGORY, cand_layout[c], cand_j[c], &rb) != CM_OK) {
            rep->why = "construction failed";
            continue;
        }
        face_error fe;
        if (!verify_face(lm, &dec.model, f, &rb, tol, &fe)) {
            rep->why = "no source domain";
            continue;
        }
        if (fe.ratio < best_ratio) {
            best_ratio = fe.ratio;
            rep->greg_ratio = fe.ratio;
        }
        if (!(fe.max < tol)) {
            rep->why = "error";
            continue;
        }
        if (!face_surface_set(&fs[f], &rb))
            return 0;
        t->layout[f] = cand_layout[c];
        t->corner[f] = cand_j[c];
        t->checksum[f] = rb.checksum;
        rep->layout = cand_layout[c];
        rep->corner = cand_j[c];
        rep->rebuild_max = fe.max;
        rep->rebuild_avg = fe.avg;
        rep->ratio = fe.ratio;
        rep->why = NULL;
        return 1;
    }
    return 0;
}

/* distance between the original surface and the kept one at a 21 x 21 grid of the same parameters */
static void measure_keep(const loaded_model *lm, int f, face_report *rep)
{
    const hsurf *orig = &lm->brep.surfs[lm->brep.faces[lm->mesh.faces[f].brep_face].surf];
    cm_surf kept;
    cm_model_surface(&dec.model, dec.model.faces[f].surf, &kept);
    cm_surf ov = hsurf_view(orig);
    double u0, u1, v0, v1, worst = 0;
    hsurf_domain(orig, &u0, &u1, &v0, &v1);
    for (int i = 0; i <= 20; i++)
        for (int j = 0; j <= 20; j++) {
            cm_vec3 a[3][3], b[3][3];
            double s = i / 20.0, t = j / 20.0;
            if (cm_surf_eval(&ov, u0 + (u1 - u0) * s, v0 + (v1 - v0) * t, 0, a, NULL) != CM_OK ||
                cm_surf_eval(&kept, s, t, 0, b, NULL) != CM_OK)
                continue;
            worst = fmax(worst, cm_dist(a[0][0], b[0][0]));
        }
    rep->rebuild_max = worst;
    rep->ratio = rep->bbox > 0 ? worst / rep->bbox : 0;
    rep->surf_ctrl = kept.nu * kept.nv;
}

/* spec §1 COS_G1 = cos 1 deg */
#define COS_G1 0.9998476951563913

/*
 * Spec §14 steps 3-4 on the decoded model (the transmitted edges): per face PLANE, then the
 * GREGORY candidates, else KEEP; then the G1 fix-point: every G1 edge next to a rebuilt face is
 * checked on the final surfaces (§13), and where it fails the rebuilt face with the larger error
 * goes back to KEEP, until nothing changes (faces only move to KEEP: at most #faces rounds).
 */
static cm_err choose_methods(const loaded_model *lm, tx *t, const encode_opts *o, encode_result *r, cm_status *st)
{
    const cm_model *m = &dec.model;
    int nf = t->nfaces;
    face_surface *fs = calloc((size_t)nf + 1, sizeof *fs);
    if (!fs)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    for (int f = 0; f < nf; f++) {
        if (o->progress)
            o->progress("choosing methods", f + 1, nf, o->progress_ctx);
        face_report *rep = &r->faces[f];
        memset(rep, 0, sizeof *rep);
        rep->g1_cos = 1.0;
        rep->layout = -1;
        t->method[f] = CM_METHOD_KEEP;
        t->layout[f] = t->corner[f] = 0;
        t->checksum[f] = 0;
        if (t->keep_only[lm->mesh.faces[f].brep_face])
            rep->why = "rebuilt surface did not tessellate";
        else if (try_plane(lm, f, o, rep, fs))
            t->method[f] = CM_METHOD_PLANE;
        else if (o->gregory && try_gregory(lm, f, o, rep, fs, t))
            t->method[f] = CM_METHOD_GREGORY;
        fs[f].method = t->method[f];
    }
    /* each G1 edge is measured once, and again only when one of its faces went back to KEEP */
    double *ecos = malloc(((size_t)m->nedges + 1) * sizeof *ecos);
    int *eworse = malloc(((size_t)m->nedges + 1) * sizeof *eworse);
    unsigned char *dirty = malloc((size_t)m->nedges + 1);
    if (!ecos || !eworse || !dirty) {
        free(ecos);
        free(eworse);
        free(dirty);
        for (int f = 0; f < nf; f++)
            face_surface_free(&fs[f]);
        free(fs);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    memset(dirty, 1, (size_t)m->nedges + 1);
    for (int round = 0; round <= nf; round++) {
        int changed = 0;
        for (int f = 0; f < nf; f++)
            r->faces[f].g1_cos = 1.0;
        for (uint32_t e = 0; e < m->nedges; e++) {
            int32_t a = m->edge_face[e][0], b = m->edge_face[e][1];
            if (!m->edges[e].g1 || a < 0 || b < 0 || a == b)
                continue;
            if (t->method[a] == CM_METHOD_KEEP && t->method[b] == CM_METHOD_KEEP)
                continue;
            if (dirty[e])
                ecos[e] = verify_g1_edge(lm, m, e, fs, &eworse[e]);
            dirty[e] = 0;
            double c = ecos[e];
            for (int s = 0; s < 2; s++) {
                face_report *rep = &r->faces[s ? b : a];
                rep->g1_cos = c < rep->g1_cos ? c : rep->g1_cos;
            }
            if (c >= COS_G1)
                continue;
            /* spec 14.4 reverts the rebuilt face with the larger Max error; on the corpus that often
               turned back an exact PLANE next to a Gregory face whose error is smaller in millimetres
               but whose normal is the one that strays.  The face whose normal is farther from its own
               source surface goes back (a KEEP face's is exact, so a rebuilt one is always picked). */
            int pick = t->method[a] == CM_METHOD_KEEP ? b : a;
            if (t->method[a] != CM_METHOD_KEEP && t->method[b] != CM_METHOD_KEEP)
                pick = eworse[e] ? b : a;
            t->method[pick] = CM_METHOD_KEEP;
            fs[pick].method = CM_METHOD_KEEP;
            face_surface_free(&fs[pick]);
            r->faces[pick].why = "G1";
            changed = 1;
            /* its edges are measured again next round (this one included: now against a KEEP face) */
            const cm_face *F = &m->faces[pick];
            for (uint32_t l = 0; l < F->nloops; l++) {
                const cm_loop *L = &m->loops[F->loop0 + l];
                for (uint32_t u = 0; u < L->nuse; u++)
                    dirty[m->uses[L->use0 + u].edge] = 1;
            }
        }
        if (!changed)
            break;
    }
    free(ecos);
    free(eworse);
    free(dirty);
    r->faces_plane = r->faces_gregory = r->faces_keep = 0;
    for (int f = 0; f < nf; f++) {
        face_report *rep = &r->faces[f];
        rep->method = t->method[f];
        if (t->method[f] == CM_METHOD_PLANE)
            r->faces_plane++;
        else if (t->method[f] == CM_METHOD_GREGORY)
            r->faces_gregory++;
        else {
            r->faces_keep++;
            t->layout[f] = t->corner[f] = 0;
            t->checksum[f] = 0;
            rep->layout = -1;
            measure_keep(lm, f, rep);
        }
        face_surface_free(&fs[f]);
    }
    free(fs);
    return CM_OK;
}

/*
 * The file with every face kept (so that every face can be measured against a decoded model that
 * has all surfaces), decoded; the methods chosen on it; the file with those, decoded again.
 */
static cm_err choose_and_write(loaded_model *lm, tx *t, const encode_opts *o, encode_result *r, cm_status *st)
{
    for (int f = 0; f < t->nfaces; f++)
        t->method[f] = CM_METHOD_KEEP;
    cm_err e = write_file(t, lm, o, NULL, r, st);
    if (e == CM_OK)
        e = decode_back(r, st);
    if (e == CM_OK)
        e = choose_methods(lm, t, o, r, st);
    if (e == CM_OK)
        e = write_file(t, lm, o, NULL, r, st);
    if (e == CM_OK)
        e = decode_back(r, st);
    return e;
}

/* ---- needs ---- */

/* the terminal's tessellation of every face, one face at a time: triangles, points, edge samples */
static cm_tess_ws tess_ws;
static float face_pos[CM_MAX_TESS_POINTS][3], face_nrm[CM_MAX_TESS_POINTS][3];
static uint32_t face_idx[3 * CM_MAX_TESS_TRIS];

/* why a face does not tessellate, for its warning */
static const char *tess_fault(cm_err e)
{
    switch (e) {
    case CM_E_DEGENERATE: return "its boundary cannot be triangulated (loops cross, or are degenerate)";
    case CM_E_LIMIT: return "its tessellation exceeds a limit of every profile";
    case CM_E_NONFINITE: return "its surface gives non-finite points";
    default: return "it cannot be tessellated";
    }
}

/* a face that does not tessellate is a fault of that face (see encode_model), not of the model */
static cm_err tessellation_needs(tx *t, uint32_t *need, double *face_volume, const encode_opts *o, cm_status *st)
{
    const cm_model *m = &dec.model;
    cm_mesh_face mf;
    cm_mesh mesh = {face_pos, face_nrm, face_idx, &mf, 0, CM_MAX_TESS_POINTS, 0, 3 * CM_MAX_TESS_TRIS, 0, 1};
    uint64_t tris = 0;
    for (uint32_t f = 0; f < m->nfaces; f++) {
        if (o->progress)
            o->progress("tessellating", (int)f + 1, (int)m->nfaces, o->progress_ctx);
        cm_tess_info info;
        cm_mesh_clear(&mesh);
        cm_status fst;
        cm_status_init(&fst);
        cm_err e = cm_tessellate_face(m, f, m->tess_tol, &mesh, &tess_ws, &info, &fst);
        if (e == CM_E_NOMEM) {
            *st = fst;
            return e;
        }
        face_volume[f] = 0;
        if (e != CM_OK) {
            face_fault(t, (int)f, tess_fault(e));
            continue;
        }
        tris += (uint64_t)info.triangles;
        /* the face's share of its part's signed volume (divergence theorem, relative to the origin) */
        double vol = 0;
        for (uint32_t i = 0; i < mesh.nindex; i += 3) {
            const float *a = face_pos[face_idx[i]], *b = face_pos[face_idx[i + 1]], *c = face_pos[face_idx[i + 2]];
            cm_vec3 A = cm_v3f(a), B = cm_v3f(b), C = cm_v3f(c);
            vol += cm_dot(A, cm_cross(B, C)) / 6.0;
        }
        face_volume[f] = vol;
        if ((uint32_t)info.points > need[CM_LIMIT_MAX_TESS_POINTS])
            need[CM_LIMIT_MAX_TESS_POINTS] = (uint32_t)info.points;
        if ((uint32_t)info.max_edge_samples > need[CM_LIMIT_MAX_EDGE_SAMPLES])
            need[CM_LIMIT_MAX_EDGE_SAMPLES] = (uint32_t)info.max_edge_samples;
    }
    need[CM_LIMIT_MAX_TRIS] = tris > UINT32_MAX ? UINT32_MAX : (uint32_t)tris;
    return CM_OK;
}

/* flip every closed part (no free edges) whose faces enclose a negative volume; returns faces flipped */
static int outward_parts(loaded_model *lm, const double *fvol, encode_result *r)
{
    cmesh *cm = &lm->mesh;
    int *comp = malloc((size_t)(cm->nfaces + 1) * sizeof *comp);
    if (!comp)
        return 0;
    int nc = cmesh_components(cm, comp), flipped = 0;
    double *vol = calloc((size_t)nc + 1, sizeof *vol);
    unsigned char *open = calloc((size_t)nc + 1, 1);
    if (vol && open && nc > 0) {
        for (int e = 0; e < cm->nedges; e++)
            if (cm->edges[e].kind == CMESH_FREE)
                open[comp[cm->edges[e].face[0]]] = 1;
        for (int f = 0; f < cm->nfaces; f++)
            vol[comp[f]] += fvol[f];
        for (int f = 0; f < cm->nfaces; f++)
            if (!open[comp[f]] && vol[comp[f]] < 0) {
                flip_face(lm, f);
                flipped++;
            }
    }
    r->faces_flipped += flipped;
    free(vol);
    free(open);
    free(comp);
    return flipped;
}

static void compute_needs(const encode_result *r, uint32_t *need)
{
    const cm_model *m = &dec.model;
    memset(need, 0, sizeof(uint32_t) * CM_LIMIT_COUNT);
#define NEED(id, v)                                                                                                    \
    do {                                                                                                               \
        uint64_t v_ = (uint64_t)(v);                                                                                   \
        if (v_ > need[CM_LIMIT_##id])                                                                                  \
            need[CM_LIMIT_##id] = (uint32_t)v_;                                                                        \
    } while (0)
    for (uint32_t e = 0; e < m->nedges; e++) {
        NEED(MAX_DEGREE, m->edges[e].p);
        NEED(MAX_EDGE_CTRL, m->edges[e].nctrl);
    }
    for (uint32_t s = 0; s < m->nsurfs; s++) {
        const cm_ksurf *S = &m->surfs[s];
        NEED(MAX_DEGREE, S->p);
        NEED(MAX_DEGREE, S->q);
        NEED(MAX_SURF_CTRL_DIR, S->nu);
        NEED(MAX_SURF_CTRL_DIR, S->nv);
        NEED(MAX_SURF_CTRL, (uint32_t)S->nu * S->nv);
    }
    for (uint32_t f = 0; f < m->nfaces; f++) {
        const cm_face *F = &m->faces[f];
        uint32_t uses = 0;
        NEED(MAX_LOOPS, F->nloops);
        if (F->method == CM_METHOD_GREGORY) { /* sides of the outer loop; N-split: one patch per side */
            NEED(MAX_SIDES, m->loops[F->loop0].nuse);
            NEED(MAX_GREG, F->layout == CM_GREG_LAYOUT_SPLIT ? m->loops[F->loop0].nuse : 1u);
        }
        for (uint32_t l = 0; l < F->nloops; l++) {
            NEED(MAX_LOOP_EDGES, m->loops[F->loop0 + l].nuse);
            uses += m->loops[F->loop0 + l].nuse;
        }
        NEED(MAX_FACE_EDGES, uses);
    }
    NEED(MAX_FACES, m->nfaces);
    NEED(MAX_EDGES, m->nedges);
    NEED(MAX_VERTICES, m->nverts);
    NEED(MAX_FILE_BYTES, r->len);
    NEED(MAX_MODEL_CTRL, m->nctrl);
    NEED(MAX_MODEL_KNOTS, m->nknots);
    NEED(MAX_MODEL_LOOPS, m->nloops);
    NEED(MAX_MODEL_USES, m->nuses);
#undef NEED
}

/*
 * One try at the whole file.  Faces that cannot be sent as they are come back in fault[] (per curve
 * mesh face, *nfaults of them) with CM_OK and no file; anything else that fails is the model's.
 */
static cm_err encode_pass(loaded_model *lm, const encode_opts *o, const unsigned char *keep_only, const char **fault,
                          int *nfaults, encode_result *r, cm_status *st)
{
    memset(r, 0, sizeof *r);
    *nfaults = 0;
    tx t;
    memset(&t, 0, sizeof t);
    t.keep_only = keep_only;
    cm_err e = CM_OK;
    double diag = brep_diag(&lm->brep);
    if (!(diag > 0))
        return cm_fail(st, CM_E_DEGENERATE, "empty model");
    if (!isfinite(diag) || !isfinite(log2(o->quant_rel * diag)))
        return cm_fail(st, CM_E_NONFINITE, "the model's extent is not finite");
    r->faces_flipped = orient_parts(lm);
    /* the grid: the largest power of two not above quant_rel * diagonal */
    t.q_exp = (int)floor(log2(o->quant_rel * diag));
    if (t.q_exp < -60)
        t.q_exp = -60;
    if (t.q_exp > 20) /* the decoder's bound (cm_decode.c, check_header): a grid step over 1 km */
        return cm_fail(st, CM_E_RANGE, "the model is too large for the format's coordinate grid");
    t.q = ldexp(1.0, t.q_exp);
    r->q = t.q;
    t.origin[0] = lm->brep.box.lo.x;
    t.origin[1] = lm->brep.box.lo.y;
    t.origin[2] = lm->brep.box.lo.z;
    t.nfaces = lm->mesh.nfaces;
    t.method = calloc((size_t)t.nfaces + 1, sizeof(int));
    t.layout = calloc((size_t)t.nfaces + 1, sizeof(int));
    t.corner = calloc((size_t)t.nfaces + 1, sizeof(int));
    t.checksum = calloc((size_t)t.nfaces + 1, sizeof(uint32_t));
    t.color = calloc((size_t)t.nfaces + 1, sizeof(int));
    t.surfs = calloc((size_t)t.nfaces + 1, sizeof *t.surfs);
    t.fault = calloc((size_t)t.nfaces + 1, sizeof *t.fault);
    r->faces = calloc((size_t)t.nfaces + 1, sizeof *r->faces);
    if (!t.method || !t.layout || !t.corner || !t.checksum || !t.color || !t.surfs || !t.fault || !r->faces) {
        tx_free(&t);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    if ((e = build_edges(lm, &t, st)) != CM_OK) {
        tx_free(&t);
        return e;
    }
    for (int f = 0; f < t.nfaces && e == CM_OK; f++) {
        t.method[f] = CM_METHOD_KEEP;
        const brep_face *bf = &lm->brep.faces[lm->mesh.faces[f].brep_face];
        cm_status fst;
        cm_status_init(&fst);
        e = build_surface(&t, &lm->brep.surfs[bf->surf], &t.surfs[f], &fst);
        if (e == CM_E_NOMEM)
            *st = fst;
        else if (e != CM_OK) {
            face_fault(&t, f, fst.where ? fst.where : cm_strerror(e));
            e = CM_OK;
        }
        if (bf->has_color) {
            int k = 1;
            while (k <= t.npalette && t.palette[k] != bf->rgb)
                k++;
            if (k > t.npalette && t.npalette < CM_FMT_MAX_PALETTE)
                t.palette[++t.npalette] = bf->rgb;
            t.color[f] = k <= t.npalette ? k : 0;
        }
    }
    /* pass 1: everything kept, decoded back to have exactly the transmitted edges; the methods;
       pass 2: the final methods, decoded again, needs taken from what the terminal will see */
    if (e == CM_OK && t.nfaults == 0)
        e = choose_and_write(lm, &t, o, r, st);
    if (e == CM_OK) {
        for (int i = 0; i < t.nedges; i++) {
            r->edges_line += t.edges[i].kind == CM_EDGE_LINE;
            r->edges_curve += t.edges[i].kind == CM_EDGE_CURVE;
        }
    }
    double *fvol = calloc((size_t)t.nfaces + 1, sizeof(double));
    if (e == CM_OK && !fvol)
        e = cm_fail(st, CM_E_NOMEM, "out of memory");
    if (e == CM_OK && t.nfaults == 0) {
        compute_needs(r, r->need);
        e = tessellation_needs(&t, r->need, fvol, o, st);
    }
    /* closed parts face outwards: a part whose volume comes out negative is turned inside out */
    if (e == CM_OK && t.nfaults == 0 && outward_parts(lm, fvol, r) > 0) {
        /* turned faces walk their loops the other way: edges and vertices are numbered by
           first use in that walk, so number them again */
        tx_free_edges(&t);
        e = build_edges(lm, &t, st);
        /* the turned faces' loops run the other way: their Gregory patches change; choose again */
        if (e == CM_OK)
            e = choose_and_write(lm, &t, o, r, st);
        if (e == CM_OK) {
            compute_needs(r, r->need);
            e = tessellation_needs(&t, r->need, fvol, o, st);
        }
    }
    free(fvol);
    if (e == CM_OK && t.nfaults > 0) {
        /* faces that cannot be sent: encode_model settles them and calls again */
        for (int f = 0; f < t.nfaces; f++)
            if (t.fault[f])
                fault[f] = t.fault[f];
        *nfaults = t.nfaults;
        tx_free(&t);
        return CM_OK;
    }
    if (e == CM_OK) {
        e = write_file(&t, lm, o, r->need, r, st);
        r->need[CM_LIMIT_MAX_FILE_BYTES] = (uint32_t)r->len;
    }
    if (e == CM_OK)
        e = decode_back(r, st); /* the final bytes must decode: any inconsistency is ours */
    tx_free(&t);
    if (e != CM_OK)
        return e;
    if (o->target) {
        for (int i = 0; i < CM_LIMIT_COUNT; i++)
            if (r->need[i] > o->target[i].value) {
                snprintf(r->refusal, sizeof r->refusal,
                         "the model needs %s=%u, profile %s has %u: it cannot be loaded there", o->target[i].name,
                         r->need[i], o->target_name ? o->target_name : "?", o->target[i].value);
                return cm_fail_limit(st, (unsigned)i, r->need[i], o->target[i].value, "target profile");
            }
    }
    return CM_OK;
}

/*
 * One bad face never sinks a model.  A face that cannot be sent as it is (an edge or its surface off
 * the grid, a surface that does not tessellate) is settled and the file made again: a rebuilt face
 * that did not tessellate is tried once more as KEEP; a face that fails as KEEP is left out of the
 * model with a warning naming its entity (o->strict: the model fails instead).  Every round settles
 * at least one face for good, so the rounds end.
 */
cm_err encode_model(loaded_model *lm, const encode_opts *o, encode_result *r, cm_status *st)
{
    int nb = lm->brep.nfaces;
    unsigned char *keep_only = calloc((size_t)nb + 1, 1), *flip0 = malloc((size_t)nb + 1);
    if (!keep_only || !flip0) {
        free(keep_only);
        free(flip0);
        memset(r, 0, sizeof *r);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    for (int b = 0; b < nb; b++)
        flip0[b] = (unsigned char)lm->brep.faces[b].flip;
    int left_out = 0;
    cm_err e;
    for (;;) {
        int nf = lm->mesh.nfaces, nfaults = 0;
        const char **fault = calloc((size_t)nf + 1, sizeof *fault);
        if (!fault) {
            e = cm_fail(st, CM_E_NOMEM, "out of memory");
            break;
        }
        e = encode_pass(lm, o, keep_only, fault, &nfaults, r, st);
        if (e != CM_OK || nfaults == 0) {
            free(fault);
            break;
        }
        /* settle the faulty faces: KEEP once more where a rebuilt surface failed, else leave out */
        int *out = malloc((size_t)nfaults * sizeof *out), nout = 0, retried = 0;
        if (!out) {
            free(fault);
            e = cm_fail(st, CM_E_NOMEM, "out of memory");
            break;
        }
        for (int f = 0; f < nf; f++) {
            if (!fault[f])
                continue;
            int b = lm->mesh.faces[f].brep_face;
            if (r->faces && r->faces[f].method != CM_METHOD_KEEP && !keep_only[b]) {
                keep_only[b] = 1;
                retried++;
            } else {
                out[nout++] = f;
            }
        }
        char refusal[sizeof r->refusal] = "";
        if (nout > 0 && o->strict) {
            const brep_face *F = &lm->brep.faces[lm->mesh.faces[out[0]].brep_face];
            snprintf(refusal, sizeof refusal, "face of entity %d (DE %d) cannot be sent: %s (--strict)", F->src_type,
                     F->src_de, fault[out[0]]);
            e = cm_fail(st, CM_E_DEGENERATE, "a face cannot be sent (--strict)");
        }
        if (e == CM_OK && nout > 0) {
            /* back to the orientation the face domains were built with, then the curve mesh anew */
            int *bad = malloc((size_t)nout * sizeof *bad);
            char (*why)[160] = malloc((size_t)nout * sizeof *why);
            if (!bad || !why)
                e = cm_fail(st, CM_E_NOMEM, "out of memory");
            for (int i = 0; e == CM_OK && i < nout; i++) {
                bad[i] = lm->mesh.faces[out[i]].brep_face;
                snprintf(why[i], sizeof why[i], "%s", fault[out[i]]);
            }
            for (int b = 0; e == CM_OK && b < nb; b++)
                lm->brep.faces[b].flip = flip0[b];
            /* from the last: a face left out moves the later ones down */
            for (int i = nout - 1; e == CM_OK && i >= 0; i--) {
                e = model_leave_out_face(lm, bad[i], why[i], st);
                left_out++;
            }
            free(bad);
            free(why);
        }
        free(out);
        free(fault);
        encode_result_free(r);
        memcpy(r->refusal, refusal, sizeof refusal);
        if (e != CM_OK)
            break;
        if (lm->mesh.nfaces == 0) {
            e = cm_fail(st, CM_E_DEGENERATE, "no face of the model can be sent (see warnings)");
            break;
        }
    }
    r->faces_left_out = left_out;
    free(keep_only);
    free(flip0);
    return e;
}
