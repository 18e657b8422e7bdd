/* cmesh.c - curve mesh: vertex merge, T-junction split, edge pairing, G1 flags, corner normals. */
#include "cmesh.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_const.h"
#include "cm/cm_geom.h"
#include "cm/cm_project.h"

/* ---- a spatial hash of points ---- */

/*
 * Points in cubic cells of side `cell`, hashed by cell.  Its work is bounded whatever the numbers:
 * non-finite points are left out (they are near nothing), cell indices are computed in double and
 * saturated before any conversion to an integer, and a query visits only the cells of its box
 * that overlap the box of the inserted points, and at most `cap` of them.
 */
typedef struct grid {
    double cell;
    cm_vec3 lo, hi; /* box of the (finite) points inserted */
    int empty;
    int *head;    /* hash bucket -> first point, -1 */
    int *next;    /* point -> next point in bucket */
    int64_t *key; /* point -> its cell key */
    unsigned mask;
} grid;

#define CELL_SAT 1e15 /* |cell index| saturates here: exact in a double, far inside a long */

static long cell_of(double x, double cell)
{
    double c = floor(x / cell);
    if (!(c > -CELL_SAT)) /* NaN too */
        return -(long)CELL_SAT;
    if (c > CELL_SAT)
        return (long)CELL_SAT;
    return (long)c;
}

static int64_t cell_key(long x, long y, long z)
{
    return (int64_t)((uint64_t)(x & 0x1fffff) | ((uint64_t)(y & 0x1fffff) << 21) | ((uint64_t)(z & 0x1fffff) << 42));
}

static unsigned hash_key(int64_t k, unsigned mask)
{
    uint64_t h = (uint64_t)k * 0x9E3779B97F4A7C15ull;
    return (unsigned)(h >> 32) & mask;
}

static int grid_init(grid *g, const cm_vec3 *p, int n, double cell)
{
    memset(g, 0, sizeof *g);
    g->cell = cell > 0 && isfinite(cell) ? cell : 1.0;
    g->empty = 1;
    unsigned sz = 1024;
    while (sz < 2u * (unsigned)n && sz < (1u << 30))
        sz <<= 1;
    g->mask = sz - 1;
    g->head = malloc(sz * sizeof(int));
    g->next = malloc((size_t)(n ? n : 1) * sizeof(int));
    g->key = malloc((size_t)(n ? n : 1) * sizeof(int64_t));
    if (!g->head || !g->next || !g->key)
        return -1;
    for (unsigned i = 0; i < sz; i++)
        g->head[i] = -1;
    for (int i = 0; i < n; i++) {
        g->next[i] = -1;
        g->key[i] = -1; /* no cell_key is negative: the top bit is never set */
        if (!cm_finite3(p[i]))
            continue;
        if (g->empty) {
            g->lo = g->hi = p[i];
            g->empty = 0;
        } else {
            g->lo = cm_v3(fmin(g->lo.x, p[i].x), fmin(g->lo.y, p[i].y), fmin(g->lo.z, p[i].z));
            g->hi = cm_v3(fmax(g->hi.x, p[i].x), fmax(g->hi.y, p[i].y), fmax(g->hi.z, p[i].z));
        }
        g->key[i] = cell_key(cell_of(p[i].x, g->cell), cell_of(p[i].y, g->cell), cell_of(p[i].z, g->cell));
        unsigned h = hash_key(g->key[i], g->mask);
        g->next[i] = g->head[h];
        g->head[h] = i;
    }
    return 0;
}

static void grid_free(grid *g)
{
    free(g->head);
    free(g->next);
    free(g->key);
}

/* call fn(i, ctx) for every point in the cells overlapping [lo, hi]; at most `cap` cells, else returns -1 */
typedef void (*grid_fn)(int i, void *ctx);
static int grid_query(const grid *g, cm_vec3 lo, cm_vec3 hi, long cap, grid_fn fn, void *ctx)
{
    if (g->empty)
        return 0;
    /* only where points are (fmax/fmin also drop a NaN bound for the grid's own) */
    lo = cm_v3(fmax(lo.x, g->lo.x), fmax(lo.y, g->lo.y), fmax(lo.z, g->lo.z));
    hi = cm_v3(fmin(hi.x, g->hi.x), fmin(hi.y, g->hi.y), fmin(hi.z, g->hi.z));
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z))
        return 0;
    long x0 = cell_of(lo.x, g->cell), x1 = cell_of(hi.x, g->cell);
    long y0 = cell_of(lo.y, g->cell), y1 = cell_of(hi.y, g->cell);
    long z0 = cell_of(lo.z, g->cell), z1 = cell_of(hi.z, g->cell);
    /* the product in double: three spans of up to 2e15 cells overflow any integer */
    if ((double)(x1 - x0 + 1) * (double)(y1 - y0 + 1) * (double)(z1 - z0 + 1) > (double)cap)
        return -1;
    for (long x = x0; x <= x1; x++)
        for (long y = y0; y <= y1; y++)
            for (long z = z0; z <= z1; z++) {
                int64_t k = cell_key(x, y, z);
                for (int i = g->head[hash_key(k, g->mask)]; i >= 0; i = g->next[i])
                    if (g->key[i] == k)
                        fn(i, ctx);
            }
    return 0;
}

/* ---- union-find ---- */

static int uf_find(int *par, int i)
{
    while (par[i] != i) {
        par[i] = par[par[i]];
        i = par[i];
    }
    return i;
}

static void uf_union(int *par, int a, int b)
{
    a = uf_find(par, a);
    b = uf_find(par, b);
    if (a != b) {
        if (a < b)
            par[b] = a;
        else
            par[a] = b; /* the lower index represents the set: deterministic */
    }
}

/* ---- curve helpers ---- */

static cm_vec3 curve_point(const hcurve *c, double s)
{
    double t0, t1;
    hcurve_domain(c, &t0, &t1);
    cm_curve v = hcurve_view(c);
    cm_vec3 d[1] = {{0, 0, 0}};
    if (cm_curve_eval(&v, t0 + (t1 - t0) * s, 0, d, NULL) != CM_OK)
        return cm_v3((double)NAN, (double)NAN, (double)NAN);
    return d[0];
}

static cm_vec3 curve_tangent(const hcurve *c, double s)
{
    double t0, t1;
    hcurve_domain(c, &t0, &t1);
    cm_curve v = hcurve_view(c);
    cm_vec3 d[2] = {{0, 0, 0}, {0, 0, 0}};
    if (cm_curve_eval(&v, t0 + (t1 - t0) * s, 1, d, NULL) != CM_OK)
        return cm_v3(0, 0, 0);
    return d[1];
}

static double dist_to_curve(const hcurve *c, cm_vec3 p, double *t)
{
    double t0, t1, d = HUGE_VAL;
    hcurve_domain(c, &t0, &t1);
    cm_curve v = hcurve_view(c);
    if (cm_curve_project(&v, t0, t1, p, t, &d, NULL) != CM_OK)
        return HUGE_VAL;
    return d;
}

static void curve_box(const hcurve *c, cm_vec3 *lo, cm_vec3 *hi)
{
    /* the control polygon's box contains the curve (convex hull property, weights > 0) */
    *lo = *hi = c->ctrl[0];
    for (int i = 1; i < c->n; i++) {
        lo->x = fmin(lo->x, c->ctrl[i].x);
        lo->y = fmin(lo->y, c->ctrl[i].y);
        lo->z = fmin(lo->z, c->ctrl[i].z);
        hi->x = fmax(hi->x, c->ctrl[i].x);
        hi->y = fmax(hi->y, c->ctrl[i].y);
        hi->z = fmax(hi->z, c->ctrl[i].z);
    }
}

/* ---- building ---- */

typedef struct piece {
    hcurve c;       /* owned until moved into an edge */
    int va, vb;     /* vertices at start / end */
    int face, loop; /* brep face index, cmesh loop index */
    int order;      /* position in the loop (for rebuilding loops) */
    int edge, rev;  /* result of pairing */
} piece;

/* what one cmesh_build works on, handed from phase to phase */
typedef struct builder {
    const brep_model *m;
    cmesh *cm;
    cm_status *st;
    double diag; /* of the model box */
    double tol;  /* cm->tol_vertex */
    int *vid;    /* phase 1 -> 2: segment end (2 s its start, 2 s + 1 its end) -> vertex */
    int *vbody;  /* phase 1 -> 2: vertex -> body */
    piece *pc;   /* phase 2 -> 4: the segments cut at T-junctions, in loop order */
    int npc, cappc;
} builder;

static int push_piece(builder *b, piece *p)
{
    if (b->npc == b->cappc) {
        int cap = b->cappc ? 2 * b->cappc : 1024;
        piece *q = realloc(b->pc, (size_t)cap * sizeof *q);
        if (!q)
            return -1;
        b->pc = q;
        b->cappc = cap;
    }
    b->pc[b->npc++] = *p;
    return 0;
}

typedef struct split_ctx {
    const hcurve *c;
    const cm_vec3 *verts;
    const int *vbody;
    int va, vb;
    double tol;
    double *ts;
    int *tv;
    int nts, capts;
} split_ctx;

static void split_candidate(int v, void *vctx)
{
    split_ctx *x = vctx;
    if (v == x->va || v == x->vb || x->nts >= x->capts || x->vbody[v] != x->vbody[x->va])
        return;
    cm_vec3 p = x->verts[v];
    if (cm_dist(p, x->verts[x->va]) <= x->tol || cm_dist(p, x->verts[x->vb]) <= x->tol)
        return;
    double t;
    if (dist_to_curve(x->c, p, &t) <= x->tol) {
        double t0, t1;
        hcurve_domain(x->c, &t0, &t1);
        double s = (t - t0) / (t1 - t0);
        if (s > 1e-9 && s < 1 - 1e-9) {
            x->ts[x->nts] = t;
            x->tv[x->nts] = v;
            x->nts++;
        }
    }
}

typedef struct merge_ctx {
    const cm_vec3 *ends;
    const int *body;
    int *par;
    double tol;
    int i;
} merge_ctx;

static void merge_candidate(int j, void *vctx)
{
    merge_ctx *x = vctx;
    int i = x->i;
    if (j > i && x->body[i] == x->body[j] && cm_dist(x->ends[i], x->ends[j]) <= x->tol)
        uf_union(x->par, i, j);
}

/* a piece's sort key for pairing: its end vertices, lower first, then its index (a total order) */
typedef struct piece_key {
    int lo, hi, i;
} piece_key;

static int cmp_piece_key(const void *a, const void *b)
{
    const piece_key *p = a, *q = b;
    if (p->lo != q->lo)
        return p->lo < q->lo ? -1 : 1;
    if (p->hi != q->hi)
        return p->hi < q->hi ? -1 : 1;
    return p->i - q->i;
}

/*
 * Phase 1, vertices: the segments' end points merged within tol (through a grid of cells of side
 * tol); the two ends at a loop joint are always one vertex, however far apart (counted in
 * nforced).  A vertex is the mean of its merged ends.  Sets cm->verts, b->vid and b->vbody.
 */
static cm_err merge_vertices(builder *b)
{
    const brep_model *m = b->m;
    cmesh *out = b->cm;
    double tol = b->tol;
    int ns = m->nsegs;
    cm_vec3 *ends = malloc((size_t)(2 * ns + 1) * sizeof *ends);
    int *par = malloc((size_t)(2 * ns + 1) * sizeof *par);
    /* a body is one subfigure instance: edges pair only inside a body, so two placed parts
     * of an assembly that touch do not become one non-manifold solid.  Shells do not
     * separate bodies: some exporters write every face of a solid as its own shell. */
    int *body = malloc((size_t)(2 * ns + 1) * sizeof *body);
    int *cnt = calloc((size_t)(2 * ns + 1), sizeof *cnt);
    b->vid = malloc((size_t)(2 * ns + 1) * sizeof *b->vid);
    b->vbody = malloc((size_t)(2 * ns + 1) * sizeof *b->vbody);
    out->verts = malloc((size_t)(2 * ns + 1) * sizeof *out->verts);
    cm_err err = CM_OK;
    if (!ends || !par || !body || !cnt || !b->vid || !b->vbody || !out->verts) {
        err = cm_fail(b->st, CM_E_NOMEM, "out of memory");
    } else {
        /* a segment no face's loop uses (a band's loops as imported, kept while it is cut open:
           brep_seam.h) has a body of its own and no vertex: it must not cut or join the others */
        for (int i = 0; i < 2 * ns; i++)
            body[i] = -1 - i;
        for (int f = 0; f < m->nfaces; f++) {
            const brep_face *bf = &m->faces[f];
            int key = bf->instance;
            for (int l = 0; l < bf->nloops; l++) {
                const brep_loop *lp = &m->loops[bf->first_loop + l];
                for (int i = 0; i < lp->n; i++)
                    body[2 * (lp->first + i)] = body[2 * (lp->first + i) + 1] = key;
            }
        }
        for (int s = 0; s < ns; s++) {
            ends[2 * s] = curve_point(&m->segs[s], 0.0);
            ends[2 * s + 1] = curve_point(&m->segs[s], 1.0);
            par[2 * s] = 2 * s;
            par[2 * s + 1] = 2 * s + 1;
        }
        for (int f = 0; f < m->nfaces; f++) {
            for (int l = m->faces[f].first_loop; l < m->faces[f].first_loop + m->faces[f].nloops; l++) {
                const brep_loop *lp = &m->loops[l];
                for (int i = 0; i < lp->n; i++) {
                    int s = lp->first + i, nxt = lp->first + (i + 1) % lp->n;
                    double gap = cm_dist(ends[2 * s + 1], ends[2 * nxt]);
                    if (gap > tol) {
                        out->nforced++;
                        if (gap > out->max_forced_gap)
                            out->max_forced_gap = gap;
                    }
                    uf_union(par, 2 * s + 1, 2 * nxt);
                }
            }
        }
        grid g;
        if (grid_init(&g, ends, 2 * ns, tol > 0 ? tol : 1e-12) != 0) {
            err = cm_fail(b->st, CM_E_NOMEM, "out of memory");
        } else {
            merge_ctx mc = {ends, body, par, tol, 0};
            for (int i = 0; i < 2 * ns; i++) {
                if (!cm_finite3(ends[i]))
                    continue; /* near nothing: stays a vertex of its own (or its loop joint) */
                cm_vec3 lo = cm_sub(ends[i], cm_v3(tol, tol, tol)), hi = cm_add(ends[i], cm_v3(tol, tol, tol));
                mc.i = i;
                /* +-tol in cells of side tol: 3 per axis, 27 cells (the cap is never reached) */
                if (grid_query(&g, lo, hi, 64, merge_candidate, &mc) != 0)
                    for (int j = i + 1; j < 2 * ns; j++)
                        merge_candidate(j, &mc);
            }
        }
        grid_free(&g);
    }
    if (err == CM_OK) {
        int *vid = b->vid;
        for (int i = 0; i < 2 * ns; i++)
            vid[i] = -1;
        for (int i = 0; i < 2 * ns; i++) {
            if (body[i] < 0)
                continue; /* (used by no face) */
            int r = uf_find(par, i);
            if (vid[r] < 0) {
                vid[r] = out->nverts;
                b->vbody[out->nverts] = body[i];
                out->verts[out->nverts++] = cm_v3(0, 0, 0);
            }
            vid[i] = vid[r];
            out->verts[vid[i]] = cm_add(out->verts[vid[i]], ends[i]);
            cnt[vid[i]]++;
        }
        for (int v = 0; v < out->nverts; v++)
            out->verts[v] = cm_scale(out->verts[v], 1.0 / cnt[v]); /* the mean of the merged ends */
    }
    free(cnt);
    free(body);
    free(par);
    free(ends);
    return err;
}

#define MAX_CUTS 64 /* T-junction cuts looked for on one segment */

/*
 * The vertices of c's body other than its ends va, vb (and farther than tol from both) that lie
 * within tol of segment c strictly inside it: their curve parameters in ts and vertices in tv,
 * sorted by parameter.  Returns their number (at most MAX_CUTS).
 */
static int find_cuts(const builder *b, const grid *vg, const hcurve *c, int va, int vb, double *ts, int *tv)
{
    const cmesh *out = b->cm;
    double tol = b->tol;
    split_ctx x;
    memset(&x, 0, sizeof x);
    x.c = c;
    x.verts = out->verts;
    x.vbody = b->vbody;
    x.va = va;
    x.vb = vb;
    x.tol = tol;
    x.capts = MAX_CUTS;
    x.ts = ts;
    x.tv = tv;
    cm_vec3 lo, hi;
    curve_box(c, &lo, &hi);
    lo = cm_sub(lo, cm_v3(tol, tol, tol));
    hi = cm_add(hi, cm_v3(tol, tol, tol));
    if (grid_query(vg, lo, hi, 1 << 20, split_candidate, &x) != 0)
        for (int v = 0; v < out->nverts; v++)
            split_candidate(v, &x);
    /* sort the cut parameters (insertion sort: few) */
    for (int a = 1; a < x.nts; a++)
        for (int k = a; k > 0 && ts[k] < ts[k - 1]; k--) {
            double t = ts[k];
            ts[k] = ts[k - 1];
            ts[k - 1] = t;
            int q = tv[k];
            tv[k] = tv[k - 1];
            tv[k - 1] = q;
        }
    return x.nts;
}

/*
 * Segment s (of loop li of face f) as its pieces between the vertices that cut it, appended to
 * b->pc; *order is the next position in the loop.  A cut the knot insertion refuses keeps the
 * segment whole.
 */
static cm_err cut_segment(builder *b, const grid *vg, int f, int li, int s, int *order)
{
    cmesh *out = b->cm;
    cm_status *st = b->st;
    const hcurve *c = &b->m->segs[s];
    int va = b->vid[2 * s], vb = b->vid[2 * s + 1];
    double ts[MAX_CUTS];
    int tv[MAX_CUTS];
    int nts = find_cuts(b, vg, c, va, vb, ts, tv);
    double t0, t1;
    hcurve_domain(c, &t0, &t1);
    double prev_t = t0;
    int prev_v = va;
    int first_piece = b->npc, first_order = *order, splits = out->nsplits;
    cm_err err = CM_OK;
    for (int k = 0; k <= nts && err == CM_OK; k++) {
        double nt = k < nts ? ts[k] : t1;
        int nv = k < nts ? tv[k] : vb;
        if (k < nts && (nv == prev_v || nt - prev_t <= 1e-9 * (t1 - t0)))
            continue;
        piece p;
        memset(&p, 0, sizeof p);
        if (nts == 0)
            err = hcurve_copy(c, &p.c, st);
        else
            err = hcurve_subrange(c, prev_t, nt, &p.c, st);
        if (err != CM_OK && err != CM_E_NOMEM && nts > 0) {
            /* the cut was refused (a parameter the knot insertion cannot use): keep the
             * segment whole, as if no vertex lay on it, rather than lose the model */
            while (b->npc > first_piece)
                hcurve_free(&b->pc[--b->npc].c);
            *order = first_order;
            out->nsplits = splits;
            if (st)
                cm_status_init(st);
            nts = 0;
            k = -1;
            prev_t = t0;
            prev_v = va;
            err = CM_OK;
            continue;
        }
        if (err != CM_OK)
            break;
        p.va = prev_v;
        p.vb = nv;
        p.face = f;
        p.loop = li;
        p.order = (*order)++;
        p.edge = -1;
        if (push_piece(b, &p)) {
            hcurve_free(&p.c);
            err = cm_fail(st, CM_E_NOMEM, "out of memory");
        }
        if (k < nts)
            out->nsplits++;
        prev_t = nt;
        prev_v = nv;
    }
    return err;
}

/* Phase 2, split: every segment, face by face and in loop order, cut where another vertex lies on it */
static cm_err split_segments(builder *b)
{
    const brep_model *m = b->m;
    grid vg;
    cm_err err = CM_OK;
    if (grid_init(&vg, b->cm->verts, b->cm->nverts, b->diag > 0 ? b->diag / 64 : 1.0) != 0)
        err = cm_fail(b->st, CM_E_NOMEM, "out of memory");
    for (int f = 0; f < m->nfaces && err == CM_OK; f++) {
        const brep_face *bf = &m->faces[f];
        for (int l = 0; l < bf->nloops && err == CM_OK; l++) {
            int li = bf->first_loop + l;
            const brep_loop *lp = &m->loops[li];
            int order = 0;
            for (int i = 0; i < lp->n && err == CM_OK; i++)
                err = cut_segment(b, &vg, f, li, lp->first + i, &order);
        }
    }
    grid_free(&vg);
    return err;
}

/*
 * Phase 3, pair: pieces with the same end vertices whose curves coincide (the midpoint of each
 * within tol_pair of the other) are one edge, stored once in the direction of its first use in
 * the order (end vertices, piece index).  Sets cm->edges, each edge's uses and faces, and each
 * piece's edge and direction.
 */
static cm_err pair_pieces(builder *b)
{
    cmesh *out = b->cm;
    piece_key *key = malloc((size_t)(b->npc + 1) * sizeof *key);
    out->edges = calloc((size_t)(b->npc + 1), sizeof *out->edges);
    if (!key || !out->edges) {
        free(key);
        return cm_fail(b->st, CM_E_NOMEM, "out of memory");
    }
    for (int i = 0; i < b->npc; i++) {
        const piece *p = &b->pc[i];
        key[i].lo = p->va < p->vb ? p->va : p->vb;
        key[i].hi = p->va < p->vb ? p->vb : p->va;
        key[i].i = i;
    }
    qsort(key, (size_t)b->npc, sizeof *key, cmp_piece_key);
    int gstart = 0; /* the first edge made for the current end-vertex pair */
    for (int k = 0; k < b->npc; k++) {
        piece *p = &b->pc[key[k].i];
        if (k > 0 && (key[k - 1].lo != key[k].lo || key[k - 1].hi != key[k].hi))
            gstart = out->nedges;
        cm_vec3 mid = curve_point(&p->c, 0.5);
        int found = -1;
        for (int e = gstart; e < out->nedges && found < 0; e++) {
            cmesh_edge *E = &out->edges[e];
            if (dist_to_curve(&E->c, mid, NULL) <= out->tol_pair &&
                dist_to_curve(&p->c, curve_point(&E->c, 0.5), NULL) <= out->tol_pair)
                found = e;
        }
        if (found < 0) {
            cmesh_edge *E = &out->edges[out->nedges];
            E->c = p->c;
            memset(&p->c, 0, sizeof p->c);
            E->v0 = p->va;
            E->v1 = p->vb;
            E->face[0] = E->face[1] = -1;
            p->edge = out->nedges++;
            p->rev = 0;
        } else {
            cmesh_edge *E = &out->edges[found];
            p->edge = found;
            if (E->v0 != E->v1) {
                p->rev = p->va != E->v0;
            } else {
                double t;
                dist_to_curve(&E->c, mid, &t);
                double t0, t1;
                hcurve_domain(&E->c, &t0, &t1);
                p->rev = cm_dot(curve_tangent(&p->c, 0.5), curve_tangent(&E->c, (t - t0) / (t1 - t0))) < 0;
            }
        }
        cmesh_edge *E = &out->edges[p->edge];
        if (E->nuse < 2)
            E->face[E->nuse] = p->face;
        E->nuse++;
    }
    free(key);
    return CM_OK;
}

/* Phase 4, loops: each face's loops as edge uses in loop order (the pieces were made in that order) */
static cm_err build_loops(builder *b)
{
    const brep_model *m = b->m;
    cmesh *out = b->cm;
    out->uses = malloc((size_t)(b->npc + 1) * sizeof *out->uses);
    out->corners = calloc((size_t)(b->npc + 1), sizeof *out->corners);
    out->loops = malloc((size_t)(m->nloops + 1) * sizeof *out->loops);
    out->faces = malloc((size_t)(m->nfaces + 1) * sizeof *out->faces);
    if (!out->uses || !out->corners || !out->loops || !out->faces)
        return cm_fail(b->st, CM_E_NOMEM, "out of memory");
    int k = 0;
    for (int f = 0; f < m->nfaces; f++) {
        const brep_face *bf = &m->faces[f];
        cmesh_face *cf = &out->faces[out->nfaces++];
        cf->brep_face = f;
        cf->first_loop = out->nloops;
        cf->nloops = bf->nloops;
        for (int l = 0; l < bf->nloops; l++) {
            cmesh_loop *cl = &out->loops[out->nloops++];
            cl->first = out->nuses;
            while (k < b->npc && b->pc[k].loop == bf->first_loop + l) {
                out->uses[out->nuses].edge = b->pc[k].edge;
                out->uses[out->nuses].rev = b->pc[k].rev;
                out->nuses++;
                k++;
            }
            cl->n = out->nuses - cl->first;
        }
    }
    return CM_OK;
}

/*
 * Phase 5, kinds: free, shared, seam or non-manifold by the edge's uses; a shared edge whose two
 * uses run the same way (not one forward, one reversed) counts as inconsistent.
 */
static void classify_edges(cmesh *out)
{
    for (int e = 0; e < out->nedges; e++) {
        cmesh_edge *E = &out->edges[e];
        E->kind = E->nuse == 1   ? CMESH_FREE
                  : E->nuse == 2 ? (E->face[0] == E->face[1] ? CMESH_SEAM : CMESH_SHARED)
                                 : CMESH_NONMANIFOLD;
        E->g1_min_cos = 1.0;
    }
    int *rev_sum = calloc((size_t)out->nedges + 1, sizeof(int));
    if (rev_sum) {
        for (int u = 0; u < out->nuses; u++)
            rev_sum[out->uses[u].edge] += out->uses[u].rev;
        for (int e = 0; e < out->nedges; e++)
            if (out->edges[e].kind == CMESH_SHARED && rev_sum[e] != 1)
                out->inconsistent++;
        free(rev_sum);
    }
}

/* Phase 6, face normals: the frame normal (K11, spec 8.1) of 10 samples per outer edge use */
static void face_normals(cmesh *out, double diag)
{
    for (int f = 0; f < out->nfaces; f++) {
        cmesh_face *cf = &out->faces[f];
        const cmesh_loop *ol = &out->loops[cf->first_loop];
        int n = ol->n * 10;
        cm_vec3 *smp = malloc((size_t)(n > 0 ? n : 1) * sizeof *smp);
        cf->normal_ok = 0;
        if (!smp)
            continue;
        for (int i = 0; i < ol->n; i++) {
            const cmesh_use *u = &out->uses[ol->first + i];
            for (int k = 0; k < 10; k++)
                smp[i * 10 + k] = curve_point(&out->edges[u->edge].c, u->rev ? 1.0 - k / 10.0 : k / 10.0);
        }
        cm_frame fr;
        if (n >= 3 && cm_face_frame(smp, n, smp, n, CM_EPS_LEN_REL * diag, &fr, NULL) == CM_OK) {
            cf->normal = fr.ez;
            cf->normal_ok = 1;
        }
        free(smp);
    }
}

/*
 * The unit normal of face D's surface at P, the point at s = k / 10 of edge curve c: P projected
 * onto the surface starting from D's nearest boundary sample; at a degenerate point (a pole) the
 * point 1e-3 further along the edge is used instead (spec §13).  0 if it cannot be evaluated.
 */
static int surface_normal_near(const face_domain *D, const hcurve *c, cm_vec3 P, double s, int k, cm_vec3 *n)
{
    int best = 0;
    double bd = HUGE_VAL;
    for (int i = 0; i < D->npts; i++) {
        if (!cm_finite3(D->xyz[i]))
            continue;
        double d = cm_norm2(cm_sub(D->xyz[i], P));
        if (d < bd) {
            bd = d;
            best = i;
        }
    }
    double u = D->uv[best].x, v = D->uv[best].y, dist;
    cm_vec3 d3[3];
    if (cm_psurf_project_from(&D->ps, P, &u, &v, &dist, NULL) != CM_OK ||
        cm_psurf_eval(&D->ps, u, v, d3, NULL) != CM_OK)
        return 0;
    cm_vec3 nn = cm_cross(d3[1], d3[2]);
    if (!(cm_norm(nn) > CM_EPS_CROSS_REL * cm_norm(d3[1]) * cm_norm(d3[2]))) {
        cm_vec3 P2 = curve_point(c, k < 10 ? s + 1e-3 : s - 1e-3);
        if (cm_psurf_project_from(&D->ps, P2, &u, &v, &dist, NULL) != CM_OK ||
            cm_psurf_eval(&D->ps, u, v, d3, NULL) != CM_OK)
            return 0;
        nn = cm_cross(d3[1], d3[2]);
    }
    if (!(cm_norm(nn) > 0))
        return 0;
    *n = cm_unit(nn);
    return 1;
}

/* min |nA . nB| of the two faces' normals over the 11 points s = 0, 0.1, ..., 1 of edge E; 0 if one fails */
static double edge_min_cos(const cmesh_edge *E, const face_domain *A, const face_domain *B)
{
    double worst = 1.0;
    for (int k = 0; k <= 10; k++) {
        double s = k / 10.0;
        cm_vec3 P = curve_point(&E->c, s), na, nb;
        if (!surface_normal_near(A, &E->c, P, s, k, &na) || !surface_normal_near(B, &E->c, P, s, k, &nb))
            return 0.0;
        double c = fabs(cm_dot(na, nb));
        if (c < worst)
            worst = c;
    }
    return worst;
}

/* Phase 7, G1 flags (spec 5.2): both faces' surface normals at 11 points of the edge agree within 1 deg */
static void g1_flags(cmesh *out, const face_domain *fds)
{
    for (int e = 0; e < out->nedges; e++) {
        cmesh_edge *E = &out->edges[e];
        if (E->kind != CMESH_SHARED && E->kind != CMESH_SEAM)
            continue;
        const face_domain *A = &fds[E->face[0]], *B = &fds[E->face[1]];
        if (!A->uv || !B->uv)
            continue;
        E->g1_min_cos = edge_min_cos(E, A, B);
        E->g1 = E->g1_min_cos >= CM_COS_G1;
    }
}

/*
 * Phase 8a, corner normals (spec 5.3): the cross product of the two edge tangents at the corner,
 * turned to the face normal's side; where the tangents are (nearly) parallel the corner is flat
 * and takes the face normal (fallback iii) for now.
 */
static void corner_normals(cmesh *out)
{
    for (int f = 0; f < out->nfaces; f++) {
        const cmesh_face *cf = &out->faces[f];
        for (int l = 0; l < cf->nloops; l++) {
            const cmesh_loop *cl = &out->loops[cf->first_loop + l];
            for (int i = 0; i < cl->n; i++) {
                const cmesh_use *uin = &out->uses[cl->first + (i + cl->n - 1) % cl->n];
                const cmesh_use *uout = &out->uses[cl->first + i];
                cm_vec3 tin = curve_tangent(&out->edges[uin->edge].c, uin->rev ? 0.0 : 1.0);
                cm_vec3 tout = curve_tangent(&out->edges[uout->edge].c, uout->rev ? 1.0 : 0.0);
                if (uin->rev)
                    tin = cm_neg(tin);
                if (uout->rev)
                    tout = cm_neg(tout);
                cmesh_corner *co = &out->corners[cl->first + i];
                int ok1, ok2;
                cm_vec3 a = cm_neg(cm_unit_or(tin, 0, cm_v3(0, 0, 0), &ok1));
                cm_vec3 bb = cm_unit_or(tout, 0, cm_v3(0, 0, 0), &ok2);
                cm_vec3 x = cm_cross(bb, a);
                if (ok1 && ok2 && cm_norm(x) >= CM_SIN_FLAT) {
                    co->n = cm_unit(x);
                    if (cf->normal_ok && cm_dot(co->n, cf->normal) < 0)
                        co->n = cm_neg(co->n);
                    co->flat = 0;
                    co->source = 0;
                } else {
                    co->flat = 1;
                    co->source = 3;
                    co->n = cf->normal;
                }
            }
        }
    }
}

/*
 * Phase 8b, fallback (i): a flat corner next to a G1 shared edge takes the partner face's
 * geometric normal at the same vertex.
 */
static void corner_normals_from_partners(cmesh *out)
{
    for (int f = 0; f < out->nfaces; f++) {
        const cmesh_face *cf = &out->faces[f];
        for (int l = 0; l < cf->nloops; l++) {
            const cmesh_loop *cl = &out->loops[cf->first_loop + l];
            for (int i = 0; i < cl->n; i++) {
                cmesh_corner *co = &out->corners[cl->first + i];
                if (!co->flat)
                    continue;
                const cmesh_use *us[2] = {&out->uses[cl->first + (i + cl->n - 1) % cl->n], &out->uses[cl->first + i]};
                const cmesh_use *uo = us[1];
                int vtx = uo->rev ? out->edges[uo->edge].v1 : out->edges[uo->edge].v0;
                for (int k = 0; k < 2 && co->source == 3; k++) {
                    const cmesh_edge *E = &out->edges[us[k]->edge];
                    if (!E->g1 || E->kind != CMESH_SHARED)
                        continue;
                    int partner = E->face[0] == f ? E->face[1] : E->face[0];
                    const cmesh_face *gf = &out->faces[partner];
                    for (int gl = 0; gl < gf->nloops && co->source == 3; gl++) {
                        const cmesh_loop *gll = &out->loops[gf->first_loop + gl];
                        for (int j = 0; j < gll->n; j++) {
                            const cmesh_use *gu = &out->uses[gll->first + j];
                            int gv = gu->rev ? out->edges[gu->edge].v1 : out->edges[gu->edge].v0;
                            const cmesh_corner *gc = &out->corners[gll->first + j];
                            if (gv == vtx && !gc->flat) {
                                co->n = cf->normal_ok && cm_dot(gc->n, cf->normal) < 0 ? cm_neg(gc->n) : gc->n;
                                co->source = 1;
                                break;
                            }
                        }
                    }
                }
            }
        }
    }
}

cm_err cmesh_build(const brep_model *m, const face_domain *fds, cmesh *out, cm_status *st)
{
    memset(out, 0, sizeof *out);
    builder b;
    memset(&b, 0, sizeof b);
    b.m = m;
    b.cm = out;
    b.st = st;
    b.diag = brep_diag(m);
    out->tol_vertex = brep_tolerance(m);
    out->tol_pair = 10 * out->tol_vertex;
    b.tol = out->tol_vertex;

    /* topology (the phases of cmesh.h): vertices, segments cut into pieces, pieces paired into
     * edges, loops of edge uses */
    cm_err err = merge_vertices(&b); /* 1 */
    if (err == CM_OK)
        err = split_segments(&b); /* 2 */
    free(b.vid);
    free(b.vbody);
    if (err == CM_OK)
        err = pair_pieces(&b); /* 3 */
    if (err == CM_OK)
        err = build_loops(&b); /* 4 */
    for (int i = 0; i < b.npc; i++)
        hcurve_free(&b.pc[i].c);
    free(b.pc);
    if (err != CM_OK) {
        cmesh_free(out);
        return err;
    }

    /* geometry on that topology */
    classify_edges(out);       /* 5 */
    face_normals(out, b.diag); /* 6 */
    if (fds)
        g1_flags(out, fds); /* 7 */
    corner_normals(out);    /* 8 */
    corner_normals_from_partners(out);
    return CM_OK;
}

void cmesh_free(cmesh *cm)
{
    for (int e = 0; e < cm->nedges; e++)
        hcurve_free(&cm->edges[e].c);
    free(cm->edges);
    free(cm->verts);
    free(cm->uses);
    free(cm->corners);
    free(cm->loops);
    free(cm->faces);
    memset(cm, 0, sizeof *cm);
}

void cmesh_counts(const cmesh *cm, int *free_e, int *shared, int *seam, int *nonmanifold, int *g1)
{
    int c[4] = {0, 0, 0, 0}, ng = 0;
    for (int e = 0; e < cm->nedges; e++) {
        c[cm->edges[e].kind]++;
        ng += cm->edges[e].g1;
    }
    if (free_e)
        *free_e = c[CMESH_FREE];
    if (shared)
        *shared = c[CMESH_SHARED];
    if (seam)
        *seam = c[CMESH_SEAM];
    if (nonmanifold)
        *nonmanifold = c[CMESH_NONMANIFOLD];
    if (g1)
        *g1 = ng;
}

int cmesh_components(const cmesh *cm, int *comp)
{
    int *par = malloc((size_t)(cm->nfaces + 1) * sizeof *par);
    if (!par)
        return -1;
    for (int f = 0; f < cm->nfaces; f++)
        par[f] = f;
    for (int e = 0; e < cm->nedges; e++) {
        const cmesh_edge *E = &cm->edges[e];
        if (E->nuse >= 2 && E->face[0] >= 0 && E->face[1] >= 0)
            uf_union(par, E->face[0], E->face[1]);
    }
    int n = 0;
    int *id = malloc((size_t)(cm->nfaces + 1) * sizeof *id);
    if (!id) {
        free(par);
        return -1;
    }
    for (int f = 0; f < cm->nfaces; f++)
        id[f] = -1;
    for (int f = 0; f < cm->nfaces; f++) {
        int r = uf_find(par, f);
        if (id[r] < 0)
            id[r] = n++;
        comp[f] = id[r];
    }
    free(id);
    free(par);
    return n;
}
