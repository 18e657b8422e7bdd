/* tx_build.c - the transmitted model: the curve mesh quantised, in transmission order (see
   encode_internal.h; orient.c turns the parts before). */
#include "encode_internal.h"
#include "enc_workers.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_const.h"
#include "cm/cm_corner.h"
#include "cm/cm_crc32.h"
#include "cm/cm_cubic_convert.h"
#include "cm/cm_method.h"
#include "cm/cm_sections.h"

/* face f cannot be sent as it is; the first reason stays */
void tx_face_fault(tx *t, int f, const char *why)
{
    if (!t->fault[f]) {
        t->fault[f] = why;
        t->nfaults++;
    }
}

static void tx_edge_free(tx_edge *X)
{
    free(X->kq);
    free(X->cq);
    free(X->wq);
    X->kq = NULL;
    X->cq = NULL;
    X->wq = NULL;
}

/* drop the transmitted edges and vertices (tx_build_edges makes them again) */
void tx_free_edges(tx *t)
{
    for (int i = 0; i < t->nedges; i++)
        tx_edge_free(&t->edges[i]);
    free(t->vq);
    free(t->edges);
    free(t->edge_tx);
    free(t->vert_tx);
    t->vq = NULL;
    t->edges = NULL;
    t->edge_tx = t->vert_tx = NULL;
    t->nedges = t->nverts = 0;
}

void tx_surf_free(tx_surf *S)
{
    free(S->ku);
    free(S->kv);
    free(S->cq);
    free(S->wq);
    memset(S, 0, sizeof *S);
}

void tx_free(tx *t)
{
    tx_free_edges(t);
    free(t->fine);
    t->fine = NULL;
    for (int i = 0; i < t->nfaces; i++)
        tx_surf_free(&t->surfs[i]);
    free(t->surfs);
    for (int i = 0; t->fit && i < t->nfaces; i++)
        free(t->fit[i]);
    free(t->fit);
    free(t->method);
    free(t->layout);
    free(t->corner);
    free(t->checksum);
    free(t->turning);
    free(t->color);
    free(t->fault);
    memset(t, 0, sizeof *t);
}


/* (encode_internal.h) */
int tx_quantise(const tx *t, cm_vec3 p, int64_t out[3])
{
    double c[3] = {(p.x - t->origin[0]) / t->q, (p.y - t->origin[1]) / t->q, (p.z - t->origin[2]) / t->q};
    int ok = 1;
    for (int k = 0; k < 3; k++) {
        ok &= fabs(c[k]) <= (double)GRID_MAX; /* false for NaN too */
        out[k] = fabs(c[k]) <= (double)GRID_MAX ? llround(c[k]) : 0;
    }
    return ok;
}

/* the diagonal (mm) of the box of n grid points: it holds the curve or surface they control */
double ctrl_box_diag(const tx *t, const int64_t (*cq)[3], long n)
{
    int64_t lo[3], hi[3];
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = cq[0][k];
    for (long j = 1; j < n; j++)
        for (int k = 0; k < 3; k++) {
            lo[k] = cq[j][k] < lo[k] ? cq[j][k] : lo[k];
            hi[k] = cq[j][k] > hi[k] ? cq[j][k] : hi[k];
        }
    double s = 0;
    for (int k = 0; k < 3; k++)
        s += ((double)(hi[k] - lo[k]) * t->q) * ((double)(hi[k] - lo[k]) * t->q);
    return sqrt(s);
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

/*
 * X (its vertices and G1 flag set) as curve c on the grid: a line when c is the segment between
 * distinct vertices, else c's degree, points, weights and knots quantised, then its own step
 * (tx_coarsen_edge; `fine`: on the grid).  *why says why it cannot be sent, if so (its faces are
 * then taken out); CM_E_NOMEM only fails.
 */
static cm_err tx_edge_fill(const tx *t, tx_edge *X, const hcurve *cv, int fine, const char **why, cm_status *st)
{
    const hcurve c = *cv;
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
    if (!X->cq || !X->wq || !X->kq)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    memcpy(X->cq[0], t->vq[X->v0], sizeof X->cq[0]);
    memcpy(X->cq[n - 1], t->vq[X->v1], sizeof X->cq[0]);
    X->rational = 0;
    X->uniform = 1;
    for (int j = 0; j < n; j++)
        X->wq[j] = WEIGHT_ONE;
    if (X->kind == CM_EDGE_CURVE) {
        for (int j = 1; j < n - 1; j++)
            if (!tx_quantise(t, c.ctrl[j], X->cq[j]))
                *why = "an edge's control point lies off the coordinate grid";
        if (c.w)
            for (int j = 0; j < n; j++) {
                X->wq[j] = quantise_weight(c.w[j], c.w[0]);
                if (X->wq[j] == 0)
                    *why = "an edge's weights cannot be sent (ratio out of range)";
                if (X->wq[j] != WEIGHT_ONE)
                    X->rational = 1;
            }
        for (int j = 1; j <= interior; j++) {
            double k = c.knots[p + j];
            X->kq[j - 1] = llround(k * (double)KNOT_ONE);
            if (fabs(k - (double)j / (double)(interior + 1)) > 0.5 / (double)KNOT_ONE)
                X->uniform = 0;
        }
        /* format 3: the curve's own step from the tolerance of a face its size, which no face it
           bounds is below (the face holds the curve) */
        if (!*why && t->o)
            tx_coarsen_edge(t, X, fine,
                            encode_face_tol(t->o->rel_tol, t->o->rel_set, t->o->abs_tol, ctrl_box_diag(t, X->cq, n)));
    }
    return CM_OK;
}

cm_err tx_build_edges(loaded_model *lm, tx *t, cm_status *st)
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
                off_grid[vs[k]] = !tx_quantise(t, cm->verts[vs[k]], t->vq[t->nverts]);
                t->vert_tx[vs[k]] = t->nverts++;
            }
    }
    for (int i = 0; i < t->nedges; i++)
        if (off_grid[cm->edges[order[i]].v0] || off_grid[cm->edges[order[i]].v1])
            why[order[i]] = "a vertex lies off the coordinate grid (not finite or too far from the model)";
    free(off_grid);
    if (t->o)
        tx_coarsen_vertices(t, cm);
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
        /* fit the board: an edge over the target profile's degree or control points is
           re-approximated within a quarter of its own tolerance (fit_board.c), else left as it
           is (and the profile refuses the model, naming the limit) */
        const cm_limit_info *L = t->o ? t->o->target : NULL;
        if (L && (c.n > (int)L[CM_LIMIT_MAX_EDGE_CTRL].value || c.p > (int)L[CM_LIMIT_MAX_DEGREE].value)) {
            double tol = 0.25 * curve_face_tol(t, &c);
            int max_ctrl = c.n < (int)L[CM_LIMIT_MAX_EDGE_CTRL].value ? c.n : (int)L[CM_LIMIT_MAX_EDGE_CTRL].value;
            cm_status rst;
            cm_status_init(&rst);
            if (enc_edge_refit(&c, (int)L[CM_LIMIT_MAX_DEGREE].value, max_ctrl, tol, &rst))
                t->edges_refit++;
        }
        int fine = t->fine && t->fine[order[i]];
        const char *bad = NULL;
        if ((err = tx_edge_fill(t, X, &c, fine, &bad, st)) != CM_OK) {
            hcurve_free(&c);
            break;
        }
        /* precision from the budget: the curve as few cubic points within a sixteenth of its faces'
           tolerance (tx_coarsen.c), sent that way where it costs fewer bits */
        hcurve alt = {0};
        cm_status ast;
        cm_status_init(&ast);
        if (!bad && t->o && !fine && X->kind == CM_EDGE_CURVE && hcurve_copy(&c, &alt, &ast) == CM_OK &&
            tx_reapproximate_curve(t, &alt)) {
            tx_edge A = {.v0 = X->v0, .v1 = X->v1, .g1 = X->g1};
            const char *abad = NULL;
            if ((err = tx_edge_fill(t, &A, &alt, 0, &abad, st)) == CM_OK && !abad &&
                enc_edge_bits(t, &A, t->o->predicted) < enc_edge_bits(t, X, t->o->predicted)) {
                tx_edge_free(X);
                *X = A;
                t->edges_reapproximated++;
            } else {
                tx_edge_free(&A);
            }
        }
        hcurve_free(&alt);
        /* format 4.4: the arc it is, where that holds within the same share (on the grid: within two
           grid steps) and costs fewer bits (tx_arc.c) */
        if (!bad && err == CM_OK && t->o && X->kind == CM_EDGE_CURVE) {
            tx_edge A = {.v0 = X->v0, .v1 = X->v1, .g1 = X->g1};
            if (tx_arc_edge(t, &c, fine, &A) && enc_edge_bits(t, &A, t->o->predicted) < enc_edge_bits(t, X, t->o->predicted)) {
                tx_edge_free(X);
                *X = A;
                t->edges_arcs++;
            }
        }
        if (bad)
            why[order[i]] = bad;
        hcurve_free(&c);
    }
    for (int f = 0; f < t->nfaces && err == CM_OK; f++) {
        const cmesh_face *cf = &cm->faces[f];
        for (int l = 0; l < cf->nloops; l++) {
            const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
            for (int i = 0; i < cl->n; i++)
                if (why[cm->uses[cl->first + i].edge])
                    tx_face_fault(t, f, why[cm->uses[cl->first + i].edge]);
        }
    }
    free(why);
    free(order);
    return err;
}

static cm_err fill_surf(tx *t, const hsurf *s_in, tx_surf *S, cm_status *st);

cm_err tx_build_surface(tx *t, const hsurf *orig, tx_surf *S, const cmesh *cm, int f, cm_status *st)
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
    /* fit the board: a surface over the target profile's degree or control points is
       re-approximated within a quarter of the tolerance of a face its size (fit_board.c) */
    const cm_limit_info *L = t->o ? t->o->target : NULL;
    if (L && (s.p > (int)L[CM_LIMIT_MAX_DEGREE].value || s.q > (int)L[CM_LIMIT_MAX_DEGREE].value ||
              s.nu > (int)L[CM_LIMIT_MAX_SURF_CTRL_DIR].value || s.nv > (int)L[CM_LIMIT_MAX_SURF_CTRL_DIR].value ||
              (long)s.nu * s.nv > (long)L[CM_LIMIT_MAX_SURF_CTRL].value)) {
        double tol = 0.25 * surf_face_tol(t, &s);
        cm_status rst;
        cm_status_init(&rst);
        if (enc_surf_refit(&s, (int)L[CM_LIMIT_MAX_DEGREE].value, (int)L[CM_LIMIT_MAX_SURF_CTRL_DIR].value,
                           (int)L[CM_LIMIT_MAX_SURF_CTRL].value, tol, &rst))
            t->surfs_refit++;
    }
    /* in the budget's terms (tx_coarsen.c), where that codes in fewer bytes: a smooth net on
       uniform knots, which its predictor nearly foretells, may cost less whole */
    hsurf alt = {0};
    cm_status ast;
    cm_status_init(&ast);
    if (!(t->net_whole && t->net_whole[cm->faces[f].brep_face]) && hsurf_copy(&s, &alt, &ast) == CM_OK &&
        tx_reapproximate_surface(t, &alt, cm, f)) {
        tx_surf A = {0};
        if ((e = fill_surf(t, &s, S, st)) == CM_OK && fill_surf(t, &alt, &A, &ast) == CM_OK) {
            tx_net_predictor(t, S);
            tx_net_predictor(t, &A);
            if (enc_net_bytes(t, &A) < enc_net_bytes(t, S)) {
                tx_surf_free(S);
                *S = A;
                S->reapproximated = 1;
                memset(&A, 0, sizeof A);
                t->surfs_reapproximated++;
            }
        }
        tx_surf_free(&A);
    } else if ((e = fill_surf(t, &s, S, st)) == CM_OK) {
        tx_net_predictor(t, S); /* format 3: the net's predictor */
    }
    /* format 4.4: ruled between two arcs, where it is one and that codes in fewer bits (tx_arc.c); a
       face whose triangles it folds takes its net whole, as a re-approximated net (needs.c) */
    if (e == CM_OK && !(t->net_whole && t->net_whole[cm->faces[f].brep_face])) {
        tx_surf R = *S;
        if (tx_ruled_surface(t, &s, &R) && enc_kept_surface_bits(&R, 1) < enc_kept_surface_bits(S, t->o->predicted)) {
            *S = R; /* the same arrays, the net's fields no longer sent */
            S->reapproximated = 1;
        }
    }
    hsurf_free(&alt);
    hsurf_free(&s);
    return e;
}

/* S: surface s on the grid (its knots on [0,1]) */
static cm_err fill_surf(tx *t, const hsurf *s_in, tx_surf *S, cm_status *st)
{
    const hsurf s = *s_in;
    cm_err e = CM_OK;
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
    if (!S->ku || !S->kv || !S->cq || !S->wq)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
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
        if (!tx_quantise(t, s.ctrl[i], S->cq[i]))
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
    return e;
}

/* ---- every face's surface, on -j N processes ---- */

/* curve mesh face f's source surface */
static const hsurf *source_surface(const loaded_model *lm, int f)
{
    return &lm->brep.surfs[lm->brep.faces[lm->mesh.faces[f].brep_face].surf];
}

/* face f's surface built, its fault noted (CM_OK) unless it is the end of memory */
static cm_err build_one(tx *t, const loaded_model *lm, int f, cm_status *st)
{
    cm_status fst;
    cm_status_init(&fst);
    cm_err e = tx_build_surface(t, source_surface(lm, f), &t->surfs[f], &lm->mesh, f, &fst);
    if (e == CM_E_NOMEM) {
        *st = fst;
        return e;
    }
    if (e != CM_OK)
        tx_face_fault(t, f, fst.where ? fst.where : cm_strerror(e));
    return CM_OK;
}

/* a worker's surface: the tx_surf with its arrays (ku, kv, cq, wq, in that order) in the arena */
typedef struct surf_found {
    atomic_int done;  /* 0: not yet (or no room: the encoder builds it); 1: a worker's, the rest filled
                         in; 2: the encoder's own, in t */
    cm_err e;
    cm_status st;
    tx_surf S;        /* its array pointers are the worker's: the arrays are in the arena at `at` */
    size_t at, nku, nkv, total;
    int refit, reapproximated; /* what it added to t's counters */
} surf_found;

/* in memory shared with the workers: the faces, then the arena */
typedef struct surf_board {
    atomic_int next;
    atomic_size_t used; /* bytes of the arena taken */
    size_t cap;
    cm_err self_e;      /* the encoder's own faces: the end of memory */
    cm_status self_st;
    surf_found face[];
} surf_board;

typedef struct surf_job {
    tx *t;
    const loaded_model *lm;
    surf_board *b;
    unsigned char *arena;
} surf_job;

static void surf_item(void *ctx, int f, int self)
{
    const surf_job *J = ctx;
    tx *t = J->t;
    surf_found *F = &J->b->face[f];
    if (self) {
        if (J->b->self_e == CM_OK)
            J->b->self_e = build_one(t, J->lm, f, &J->b->self_st);
        atomic_store(&F->done, 2);
        return;
    }
    int refit = t->surfs_refit, reapproximated = t->surfs_reapproximated;
    cm_status_init(&F->st);
    tx_surf *S = &t->surfs[f];
    F->e = tx_build_surface(t, source_surface(J->lm, f), S, &J->lm->mesh, f, &F->st);
    F->refit = t->surfs_refit - refit;
    F->reapproximated = t->surfs_reapproximated - reapproximated;
    F->S = *S;
    if (F->e == CM_OK) {
        int nku = S->nu - S->p - 1, nkv = S->nv - S->q - 1;
        F->nku = (size_t)(nku > 0 ? nku : 1);
        F->nkv = (size_t)(nkv > 0 ? nkv : 1);
        F->total = (size_t)S->nu * (size_t)S->nv;
        size_t bytes = (F->nku + F->nkv + 4 * F->total) * sizeof(int64_t);
        F->at = atomic_fetch_add(&J->b->used, bytes);
        if (F->at + bytes > J->b->cap)
            return; /* no room: the encoder builds it */
        int64_t *a = (int64_t *)(void *)(J->arena + F->at);
        memcpy(a, S->ku, F->nku * sizeof *a);
        memcpy(a + F->nku, S->kv, F->nkv * sizeof *a);
        memcpy(a + F->nku + F->nkv, S->cq, 3 * F->total * sizeof *a);
        memcpy(a + F->nku + F->nkv + 3 * F->total, S->wq, F->total * sizeof *a);
    }
    atomic_store(&F->done, 1);
}

/* a worker's surface for face f taken into t (0: out of memory) */
static int take_surf(tx *t, int f, const surf_found *F, const unsigned char *arena)
{
    t->surfs_refit += F->refit;
    t->surfs_reapproximated += F->reapproximated;
    if (F->e != CM_OK) {
        tx_face_fault(t, f, F->st.where ? F->st.where : cm_strerror(F->e));
        return 1;
    }
    tx_surf *S = &t->surfs[f];
    *S = F->S;
    S->ku = malloc(F->nku * sizeof(int64_t));
    S->kv = malloc(F->nkv * sizeof(int64_t));
    S->cq = malloc(F->total * sizeof *S->cq);
    S->wq = malloc(F->total * sizeof(int64_t));
    if (!S->ku || !S->kv || !S->cq || !S->wq)
        return 0;
    const int64_t *a = (const int64_t *)(const void *)(arena + F->at);
    memcpy(S->ku, a, F->nku * sizeof *a);
    memcpy(S->kv, a + F->nku, F->nkv * sizeof *a);
    memcpy(S->cq, a + F->nku + F->nkv, 3 * F->total * sizeof *a);
    memcpy(S->wq, a + F->nku + F->nkv + 3 * F->total, F->total * sizeof *a);
    return 1;
}

cm_err tx_build_surfaces(tx *t, const loaded_model *lm, cm_status *st)
{
    int nf = t->nfaces;
    surf_board *b = NULL;
    size_t size = 0;
    unsigned char *arena = NULL;
    if (t->o->jobs > 1 && nf > 1) {
        /* room for every surface as the source has it, clamped on its domain (a degree's more knots
           at each end), twice over; a surface that does not fit is built by the encoder */
        size_t cap = (size_t)1 << 20;
        for (int f = 0; f < nf; f++) {
            const hsurf *h = source_surface(lm, f);
            size_t nu = (size_t)h->nu + 2 * (size_t)h->p + 2, nv = (size_t)h->nv + 2 * (size_t)h->q + 2;
            cap += 2 * (nu + nv + 4 * nu * nv) * sizeof(int64_t);
        }
        size = sizeof(surf_board) + (size_t)nf * sizeof(surf_found) + cap;
        if ((b = enc_shared_alloc(size)) != NULL) {
            b->cap = cap;
            arena = (unsigned char *)(b->face + nf); /* surf_found's size keeps 8-byte alignment */
            surf_job J = {t, lm, b, arena};
            enc_workers_run(t->o->jobs, nf, &b->next, surf_item, &J, t->o->jobs_die_after);
        }
    }
    cm_err e = b ? b->self_e : CM_OK;
    if (b && e != CM_OK)
        *st = b->self_st;
    for (int f = 0; f < nf && e == CM_OK; f++) {
        int done = b ? atomic_load(&b->face[f].done) : 0;
        if (done == 1 && !take_surf(t, f, &b->face[f], arena))
            e = cm_fail(st, CM_E_NOMEM, "out of memory");
        else if (done == 0)
            e = build_one(t, lm, f, st); /* in order, with one process; else a worker's that died */
    }
    enc_shared_free(b, size);
    return e;
}
