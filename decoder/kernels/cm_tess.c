/*
 * cm_tess.c - heap-free constrained Delaunay triangulation of a polygon with
 * holes and interior points (the core of tessellation, see cm_tess.h).
 *
 * Steps:
 *  1. Check the arguments.  Scale every point by the power of two that
 *     brings the boundary's larger extent into (1/2, 1]: exact, so every
 *     predicate decides as it would on the caller's coordinates, and every
 *     tolerance below is relative to the face's size.
 *  2. Touching loops: boundary points of different loops (or of one loop,
 *     not neighbours on it) within EPS_TOUCH get one position, so that a
 *     vertex shared by two loops but mapped into the parameter domain twice
 *     with different rounding is seen exactly shared.
 *  3. Link each loop into a ring of nodes (node k = point k), drop a point
 *     that repeats its predecessor (a zero-length segment is nobody's side),
 *     leave out holes with fewer than 3 points or no area (they take nothing
 *     away), refuse such an outer loop, reverse a loop given in the wrong
 *     orientation.
 *  4. Bridge the holes into the outer ring (Eberly's hole elimination, with
 *     the tie rules of mapbox/earcut): holes in order of increasing min x;
 *     from the hole's leftmost vertex M a ray to -x finds the nearest ring
 *     edge; its end with the smaller x, or the ring vertex inside the
 *     triangle (M, hit, end) with the least angle to the ray, becomes the
 *     bridge end P, and the ring becomes ... P M ...hole... M' P' ... with
 *     copies M', P'.  (The brief proposed the mirror image, rightmost vertex
 *     and a ray to +x: the same method; earcut's side conventions were kept
 *     so that its tested tie rules apply unchanged.)  A hole whose M is at a
 *     ring vertex (touching loops) is spliced in there without a bridge.
 *  5. Ear clipping.  An ear b (neighbours a, c) is strictly convex and no
 *     other node lies in the closed triangle abc (or within EPS_TOUCH outside
 *     it).  Only nodes that are not strictly convex, or that share their
 *     position with another node (bridge copies, touching loops), can lie in
 *     an ear: they are the candidates, and an ear test visits the nodes
 *     between its box's corners in z-order (earcut's hashing).  A candidate
 *     at b's position blocks when one of its ring edges enters the ear's
 *     angle.  Zero-length ring edges and spikes (two ring edges folding back
 *     onto each other, left where a cut runs along a boundary segment at a
 *     touching point) are removed as soon as they appear, pairing what lies
 *     across them.  Ears are searched around the ring as in earcut (after a
 *     cut, go on after the next node); a node that failed is not tested
 *     again until its neighbours change or a whole turn finds no ear.  When
 *     a whole turn finds no ear (near-collinear nodes, loops overlapping by
 *     rounding), a relaxed test (only points strictly inside block) is
 *     tried, then the least-bad node: the largest sine of its turn among the
 *     unblocked ones; one that turns clearly the wrong way (sine < -SIN_TOL)
 *     means the loops cross, or touch in a way ear clipping cannot take
 *     apart: the fallback (5b).  Adjacency is built while
 *     clipping: every ring edge remembers the triangle side across it.
 *     Every strict ear is counter-clockwise, and each cut changes the ring's
 *     winding number exactly where its triangle lies, so the triangles tile
 *     the region exactly.
 *  5b. Fallback (cdt_region): where ear clipping fails, or leaves (after
 *     the flips of step 6) a flat triangle that the input does not force,
 *     the boundary points go into a Delaunay triangulation inside an
 *     enclosing triangle, every boundary segment is forced in as a fixed
 *     side (split at the vertices lying on it, which then get flat
 *     triangles keeping the segment a side), and the triangles of positive
 *     winding number are kept.  It needs no simple ring: loops through a
 *     point twice, vertices on segments, holes sharing runs with the outer
 *     loop, spikes and slits are ordinary there.  Inputs the ear clipping
 *     triangulates without such a flat triangle never get here, so their
 *     output is as before.
 *  6. Lawson flips over all non-fixed sides: a side is flipped when the
 *     opposite vertex is inside the circumcircle (certainly: the determinant
 *     beyond its rounding bound, evaluated from both triangles as a sliver's
 *     own circle is ill-conditioned) or one of its triangles is flat, and
 *     only if the quadrilateral is strictly convex.  Boundary sides are
 *     fixed.  The result is the constrained Delaunay triangulation of the
 *     boundary points.
 *  7. Interior points, in input order: locate (a grid of cells over the box
 *     remembers a triangle meeting each cell, -1 where none does: those
 *     points are outside at once; else walk from the cell's triangle, then
 *     from the last one, then scan all), skip points outside, within
 *     max(min_dist, EPS_SNAP) of a used point or of a boundary segment (a
 *     breadth-first search over the triangles that meet that disc finds
 *     every such point and segment), split the triangle (or the two
 *     triangles of the side it lies on) and restore the Delaunay property
 *     with flips around it.
 *  8. A final Lawson pass; copy out.
 *
 * Only + - * / and comparisons on doubles (fabs, sqrt, floor),
 * -ffp-contract=off: bit-identical on every architecture.  No recursion;
 * every loop has a bound; all storage is the caller's cm_tri_ws.
 */
#include "cm/cm_tess.h"

#include <float.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "cm/cm_limits_info.h"

/* Tolerances, in the scaled coordinates (the boundary's larger extent is in (1/2, 1]). */
#define EPS_DUP 1e-14   /* closer points are at one position (rounding noise of ~50 ulp) */
#define EPS_REL 1e-14   /* orientation |det| <= EPS_REL (|l| + |r|) counts as collinear (error bound 3.3e-16) */
#define EPS_IC 1e-14    /* incircle det must exceed EPS_IC * permanent to flip (error bound 1.1e-15) */
#define EPS_TOUCH 1e-10 /* boundary points of different loops this close touch (the loops meet there) */
#define EPS_SNAP 1e-10  /* interior points nearer than this to a vertex or the boundary are skipped */
#define EPS_ON 1e-13    /* an interior point this close to a side is inserted on that side */
#define EPS_AREA 1e-12  /* a loop with |2 area| <= EPS_AREA * extent^2 has no area */
#define SIN_TOL 1e-8    /* a fallback ear may turn the wrong way by at most this sine */
#define EPS_FLAT 1e-10  /* a triangle whose largest angle is this close (sine) to straight is flat */

/* triangle flags */
#define FIX(s) (1u << (s))    /* side s is fixed */
#define QUEUED(s) (8u << (s)) /* side s is in the flip queue */
#define FIX_ALL 7u
/* node flags */
#define NF_DUP 1u   /* another node has the same position */
#define NF_CAND 2u  /* a candidate: not strictly convex, or NF_DUP (cand_update) */
#define NF_DEAD 4u  /* removed from the ring */
#define NF_NOEAR 8u /* failed the ear test, and nothing near it changed since */

typedef struct tess_ctx {
    cm_tri_ws *ws;
    int nn;          /* nodes allocated */
    int ntri;        /* triangles */
    int sp;          /* flip queue size */
    int overflow;    /* a triangle was needed beyond CM_MAX_TESS_TRIS (cannot happen for valid counts) */
    double box[4];   /* the boundary's box: xmin, ymin, xmax, ymax */
    double zinv;     /* z-order: cells per unit (32767 over the box's extent) */
    int grid;        /* cells per side of the location grid over the box, 0 if none */
    int grid_ntri;   /* the triangles there were when it was built */
    double ghx, ghy; /* its cell size */
    double fold;     /* a fallback ear turning the wrong way is still cut when no higher than this */
    long cdt_budget; /* the fallback's steps allowed (ws->cdt_work) */
} tess_ctx;

static int n3(int i) { return i == 2 ? 0 : i + 1; }
static int p3(int i) { return i == 0 ? 2 : i - 1; }

/* ---------------------------------------------------------------- predicates */

static double dist2(cm_vec2 a, cm_vec2 b)
{
    double dx = a.x - b.x, dy = a.y - b.y;
    return dx * dx + dy * dy;
}

static int same_pos(cm_vec2 a, cm_vec2 b) { return fabs(a.x - b.x) <= EPS_DUP && fabs(a.y - b.y) <= EPS_DUP; }

/*
 * Twice the signed area of abc (> 0: counter-clockwise); *err: its rounding
 * tolerance.  The determinant is taken at the corner opposite the longest
 * side (orientation is invariant under rotation of the corners): the two
 * shortest sides give the smallest products, hence the smallest error, which
 * keeps the sign certain for slivers next to very short boundary segments.
 */
static double orient(cm_vec2 a, cm_vec2 b, cm_vec2 c, double *err)
{
    double lab = dist2(a, b), lbc = dist2(b, c), lca = dist2(c, a);
    cm_vec2 o = a, u = b, v = c; /* longest side bc: pivot a */
    if (lab >= lbc && lab >= lca) { /* longest ab: pivot c */
        o = c;
        u = a;
        v = b;
    } else if (lca >= lbc) { /* longest ca: pivot b */
        o = b;
        u = c;
        v = a;
    }
    double l = (u.x - o.x) * (v.y - o.y), r = (u.y - o.y) * (v.x - o.x);
    *err = EPS_REL * (fabs(l) + fabs(r));
    return l - r;
}

/* orientation beyond its tolerance: +1 counter-clockwise, -1 clockwise, 0 collinear.
 * First the determinant at corner a, without choosing the pivot: where it is far beyond both
 * tolerances its sign is the pivot's, and the answer is the same.  (Each determinant is within
 * about 5 ulp of (|l| + |r|) of the exact one of the three points, and the pivot's |l| + |r|, of
 * the two shortest sides, is at most |b - a|^2 + |c - a|^2 = q: past 2e-14 (|l| + |r| + q) at a,
 * the pivot's determinant has that sign and exceeds its EPS_REL (|l| + |r|).  Most of a Lawson
 * pass's orientations are of well-shaped triangles, far from 0; a sliver takes the pivot.) */
static int orient_sign(cm_vec2 a, cm_vec2 b, cm_vec2 c)
{
    double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y;
    double l = bx * cy, r = by * cx, o = l - r;
    double far = 2e-14 * (fabs(l) + fabs(r) + (bx * bx + by * by + cx * cx + cy * cy));
    if (o > far)
        return 1;
    if (o < -far)
        return -1;
    double e;
    o = orient(a, b, c, &e);
    return o > e ? 1 : (o < -e ? -1 : 0);
}

/* > 0 if d is inside the circle through the counter-clockwise a, b, c (Shewchuk's incircle) */
static double incircle(cm_vec2 a, cm_vec2 b, cm_vec2 c, cm_vec2 d, double *err)
{
    double adx = a.x - d.x, ady = a.y - d.y, bdx = b.x - d.x, bdy = b.y - d.y, cdx = c.x - d.x, cdy = c.y - d.y;
    double bc1 = bdx * cdy, bc2 = cdx * bdy, ca1 = cdx * ady, ca2 = adx * cdy, ab1 = adx * bdy, ab2 = bdx * ady;
    double al = adx * adx + ady * ady, bl = bdx * bdx + bdy * bdy, cl = cdx * cdx + cdy * cdy;
    double det = al * (bc1 - bc2) + bl * (ca1 - ca2) + cl * (ab1 - ab2);
    *err = EPS_IC * ((fabs(bc1) + fabs(bc2)) * al + (fabs(ca1) + fabs(ca2)) * bl + (fabs(ab1) + fabs(ab2)) * cl);
    return det;
}

/* squared distance from q to the segment ab */
static double seg_dist2(cm_vec2 q, cm_vec2 a, cm_vec2 b)
{
    double ex = b.x - a.x, ey = b.y - a.y, l2 = ex * ex + ey * ey;
    if (!(l2 > 0.0))
        return dist2(q, a);
    double t = ((q.x - a.x) * ex + (q.y - a.y) * ey) / l2;
    if (t <= 0.0)
        return dist2(q, a);
    if (t >= 1.0)
        return dist2(q, b);
    return dist2(q, cm_v2(a.x + t * ex, a.y + t * ey));
}

/* earcut's exact point-in-triangle (closed), used with its bridge rules */
static int ec_in_triangle(double ax, double ay, double bx, double by, double cx, double cy, double px, double py)
{
    return (cx - px) * (ay - py) >= (ax - px) * (cy - py) && (ax - px) * (by - py) >= (bx - px) * (ay - py) &&
           (bx - px) * (cy - py) >= (cx - px) * (by - py);
}

static double cross3(cm_vec2 a, cm_vec2 b, cm_vec2 c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }

/* --------------------------------------------------------------- node rings */

static cm_vec2 npos(const cm_tri_ws *ws, int k) { return ws->p[ws->node_pt[k]]; }

/* node k strictly convex (turns left beyond the tolerance) */
static int node_convex(const cm_tri_ws *ws, int k)
{
    return orient_sign(npos(ws, ws->prev[k]), npos(ws, k), npos(ws, ws->next[k])) > 0;
}

/*
 * Candidates: the nodes an ear test must look at, those not strictly convex
 * or sharing their position with another node (NF_CAND).  All live nodes
 * are also linked in z-order (Morton order of their cell in a 32768 x 32768
 * grid over the box, as in earcut), so an ear test visits only the nodes
 * whose z lies between those of its triangle's box corners: a superset of
 * the nodes in the box, found from the ear's own node in both directions.
 */
static void cand_update(tess_ctx *c, int k)
{
    cm_tri_ws *ws = c->ws;
    ws->nflag[k] = (unsigned char)(ws->nflag[k] & ~NF_NOEAR); /* its neighbours changed: test again */
    if ((ws->nflag[k] & NF_DUP) || !node_convex(ws, k))
        ws->nflag[k] = (unsigned char)(ws->nflag[k] | NF_CAND);
    else
        ws->nflag[k] = (unsigned char)(ws->nflag[k] & ~NF_CAND);
}

/* node k leaves the ring: out of the z-order list too */
static void node_remove(tess_ctx *c, int k)
{
    cm_tri_ws *ws = c->ws;
    if (ws->zprev[k] >= 0)
        ws->znext[ws->zprev[k]] = ws->znext[k];
    if (ws->znext[k] >= 0)
        ws->zprev[ws->znext[k]] = ws->zprev[k];
    ws->nflag[k] = (unsigned char)((ws->nflag[k] & ~NF_CAND) | NF_DEAD);
}

/* bit b of x (x < 2^16) moved to bit 2b, by masks (a loop over the bits took ~300 instructions a
   code: 4 % of a GREGORY-EXACT model's decode, in the ear tests) */
static uint32_t spread_bits(uint32_t x)
{
    x = (x | (x << 8)) & 0x00FF00FFu;
    x = (x | (x << 4)) & 0x0F0F0F0Fu;
    x = (x | (x << 2)) & 0x33333333u;
    return (x | (x << 1)) & 0x55555555u;
}

/* Morton code of the cell holding (x, y): 15 bits per axis, interleaved */
static uint32_t zcode(const tess_ctx *c, double x, double y)
{
    double fx = (x - c->box[0]) * c->zinv, fy = (y - c->box[1]) * c->zinv;
    uint32_t ix = fx <= 0.0 ? 0u : (fx >= 32767.0 ? 32767u : (uint32_t)fx);
    uint32_t iy = fy <= 0.0 ? 0u : (fy >= 32767.0 ? 32767u : (uint32_t)fy);
    return spread_bits(ix) | spread_bits(iy) << 1;
}

/* move ring-edge state s to node k (fixing the back reference of a pending bridge twin) */
static void set_side(cm_tri_ws *ws, int k, int s)
{
    ws->side[k] = s;
    if (s <= -2)
        ws->side[-s - 2] = -2 - k;
}

/* ----------------------------------------------------------------- triangles */

static int new_tri(tess_ctx *c, int a, int b, int d)
{
    if (c->ntri >= CM_MAX_TESS_TRIS) {
        c->overflow = 1;
        return -1;
    }
    cm_tri_ws *ws = c->ws;
    int t = c->ntri++;
    ws->tri[t][0] = a;
    ws->tri[t][1] = b;
    ws->tri[t][2] = d;
    ws->adj[t][0] = ws->adj[t][1] = ws->adj[t][2] = -1;
    ws->flag[t] = 0;
    ws->mark[t] = 0;
    return t;
}

static void set_fixed(cm_tri_ws *ws, int t, int s, int on)
{
    if (on)
        ws->flag[t] = (unsigned char)(ws->flag[t] | FIX(s));
    else
        ws->flag[t] = (unsigned char)(ws->flag[t] & ~FIX(s));
}

/* side s of triangle t lies on ring edge k -> next[k]: link it to what is across */
static void attach(cm_tri_ws *ws, int t, int s, int k)
{
    int S = ws->side[k];
    ws->adj[t][s] = -1;
    if (S == -1) {
        set_fixed(ws, t, s, 1);
    } else if (S >= 0) {
        ws->adj[t][s] = S;
        ws->adj[S / 3][S % 3] = 3 * t + s;
    } else {
        ws->side[-S - 2] = 3 * t + s; /* the twin edge will link when it is cut */
    }
}

/* a ring edge that vanishes without a triangle on it: whatever waited for it becomes boundary */
static void drop_state(cm_tri_ws *ws, int S)
{
    if (S >= 0)
        set_fixed(ws, S / 3, S % 3, 1);
    else if (S <= -2)
        ws->side[-S - 2] = -1;
}

/* two ring edges that are the same segment traversed both ways: pair what is across them */
static void pair_states(cm_tri_ws *ws, int S1, int S2)
{
    if (S1 >= 0 && S2 >= 0) {
        int t1 = S1 / 3, s1 = S1 % 3, t2 = S2 / 3, s2 = S2 % 3;
        ws->adj[t1][s1] = S2;
        ws->adj[t2][s2] = S1;
        /* sides made of different (coincident) points: never flipped, count as boundary */
        if (ws->tri[t1][s1] != ws->tri[t2][n3(s2)] || ws->tri[t1][n3(s1)] != ws->tri[t2][s2]) {
            set_fixed(ws, t1, s1, 1);
            set_fixed(ws, t2, s2, 1);
        }
        return;
    }
    drop_state(ws, S1);
    drop_state(ws, S2);
}

/* ------------------------------------------------------------- sorting nodes */

/* order of nodes: by_z 0: position (x, then y), 1: z-order; then id */
static int node_less(const cm_tri_ws *ws, int by_z, int i, int j)
{
    if (by_z) {
        if (ws->zkey[i] != ws->zkey[j])
            return ws->zkey[i] < ws->zkey[j];
        return i < j;
    }
    cm_vec2 a = npos(ws, i), b = npos(ws, j);
    if (a.x != b.x)
        return a.x < b.x;
    if (a.y != b.y)
        return a.y < b.y;
    return i < j;
}

static void sift_down(const cm_tri_ws *ws, int by_z, int *v, int root, int n)
{
    for (int child = 2 * root + 1; child < n; child = 2 * root + 1) {
        if (child + 1 < n && node_less(ws, by_z, v[child], v[child + 1]))
            child++;
        if (!node_less(ws, by_z, v[root], v[child]))
            return;
        int t = v[root];
        v[root] = v[child];
        v[child] = t;
        root = child;
    }
}

/* heapsort of node ids (node_less): O(n log n), no recursion */
static void sort_nodes(const cm_tri_ws *ws, int by_z, int *v, int n)
{
    for (int s = n / 2 - 1; s >= 0; s--)
        sift_down(ws, by_z, v, s, n);
    for (int e = n - 1; e > 0; e--) {
        int t = v[0];
        v[0] = v[e];
        v[e] = t;
        sift_down(ws, by_z, v, 0, e);
    }
}

/* ------------------------------------------------------------------- loops */

/*
 * Link loop [s, e) into a ring of nodes s.. (node = point), dropping points
 * that repeat their predecessor.  Reverses the ring if its orientation is not
 * the wanted one (want > 0: counter-clockwise).  Returns the first node, or
 * -1 if the loop has fewer than 3 points or no area.
 */
static int make_ring(cm_tri_ws *ws, int s, int e, int want)
{
    int first = -1, last = -1, cnt = 0;
    for (int k = s; k < e; k++) {
        ws->node_pt[k] = k;
        ws->nflag[k] = 0;
        ws->side[k] = -1;
        if (last >= 0 && same_pos(ws->p[k], ws->p[last]))
            continue;
        if (last >= 0) {
            ws->next[last] = k;
            ws->prev[k] = last;
        } else {
            first = k;
        }
        last = k;
        cnt++;
    }
    for (int g = e - s; g > 0 && cnt > 1 && same_pos(ws->p[last], ws->p[first]); g--) {
        last = ws->prev[last];
        cnt--;
    }
    if (cnt < 3)
        return -1;
    ws->next[last] = first;
    ws->prev[first] = last;
    double a2 = 0.0, xmin = ws->p[first].x, xmax = xmin, ymin = ws->p[first].y, ymax = ymin;
    int k = first;
    for (int g = 0; g < cnt; g++, k = ws->next[k]) {
        cm_vec2 q = ws->p[k];
        a2 += cross3(ws->p[first], q, ws->p[ws->next[k]]);
        xmin = q.x < xmin ? q.x : xmin;
        xmax = q.x > xmax ? q.x : xmax;
        ymin = q.y < ymin ? q.y : ymin;
        ymax = q.y > ymax ? q.y : ymax;
    }
    double ext = xmax - xmin > ymax - ymin ? xmax - xmin : ymax - ymin;
    if (!(fabs(a2) > EPS_AREA * ext * ext))
        return -1;
    if ((a2 > 0.0) != (want > 0)) {
        k = first;
        for (int g = 0; g < cnt; g++) {
            int nx = ws->next[k];
            ws->next[k] = ws->prev[k];
            ws->prev[k] = nx;
            k = nx;
        }
    }
    return first;
}

/* earcut: the sector of node a contains the direction to b */
static int locally_inside(const cm_tri_ws *ws, int a, cm_vec2 b)
{
    cm_vec2 A = npos(ws, a), P = npos(ws, ws->prev[a]), N = npos(ws, ws->next[a]);
    if (cross3(P, A, N) > 0.0)
        return cross3(A, b, N) <= 0.0 && cross3(A, P, b) <= 0.0;
    return cross3(A, b, P) > 0.0 || cross3(A, N, b) > 0.0;
}

/* earcut: the sector of m contains the sector of p (same position) */
static int sector_contains(const cm_tri_ws *ws, int m, int p)
{
    cm_vec2 M = npos(ws, m);
    return cross3(npos(ws, ws->prev[m]), M, npos(ws, ws->prev[p])) > 0.0 &&
           cross3(npos(ws, ws->next[p]), M, npos(ws, ws->next[m])) > 0.0;
}

/*
 * earcut's findHoleBridge: the ring node (of the ring through `outer`, `len`
 * nodes) that hole node `h` connects to, or -1 if the ray meets no edge.
 */
static int find_bridge(const cm_tri_ws *ws, int h, int outer, int len)
{
    cm_vec2 H = npos(ws, h);
    double hx = H.x, hy = H.y, qx = 0.0;
    int m = -1, same = -1, touch = 0, p = outer;
    for (int g = 0; g < len; g++) {
        int n = ws->next[p];
        cm_vec2 P = npos(ws, p), N = npos(ws, n);
        /* a ring vertex at H (touching loops): that one, preferring a copy whose sector holds H */
        if (same_pos(P, H) && (same < 0 || (!locally_inside(ws, same, H) && locally_inside(ws, p, H))))
            same = p;
        if (hy <= P.y && hy >= N.y && N.y != P.y) {
            double x = P.x + (hy - P.y) * (N.x - P.x) / (N.y - P.y);
            if (x <= hx && (m < 0 || x > qx)) {
                qx = x;
                m = P.x < N.x ? p : n;
                touch = x == hx; /* the hole touches this edge: its end with the smaller x */
            }
        }
        p = n;
        if (p == outer)
            break;
    }
    if (same >= 0)
        return same;
    if (m < 0 || touch)
        return m;
    /* a ring vertex inside the triangle (hole point, hit, m) is a better end: least angle to the ray */
    cm_vec2 Mv = npos(ws, m);
    double mx = Mv.x, my = Mv.y, tan_min = 0.0;
    int have = 0, stop = m;
    p = m;
    for (int g = 0; g < len; g++) {
        cm_vec2 P = npos(ws, p);
        if (hx >= P.x && P.x >= mx && hx != P.x &&
            ec_in_triangle(hy < my ? hx : qx, hy, mx, my, hy < my ? qx : hx, hy, P.x, P.y)) {
            double tn = fabs(hy - P.y) / (hx - P.x);
            cm_vec2 Mc = npos(ws, m);
            if (locally_inside(ws, p, H) &&
                (!have || tn < tan_min ||
                 (tn == tan_min && (P.x > Mc.x || (P.x == Mc.x && sector_contains(ws, m, p)))))) {
                m = p;
                tan_min = tn;
                have = 1;
            }
        }
        p = ws->next[p];
        if (p == stop)
            break;
    }
    return m;
}

/*
 * Splice the hole ring through node h into the ring at node m: bridge
 * m -> h ... h' -> m' (copies m', h').  merge: h and m are at one position
 * (loops that touch), the hole goes in without a bridge, its node h dropped
 * and m standing for it.
 */
static int splice_hole(tess_ctx *c, int m, int h, int merge)
{
    cm_tri_ws *ws = c->ws;
    int mn = ws->next[m], hp = ws->prev[h];
    if (c->nn + 2 > CM_TESS_MAX_NODES)
        return -1;
    int m2 = c->nn++;
    ws->node_pt[m2] = ws->node_pt[m];
    ws->nflag[m2] = NF_DUP;
    ws->nflag[m] = (unsigned char)(ws->nflag[m] | NF_DUP);
    set_side(ws, m2, ws->side[m]);
    if (merge) {
        int hn = ws->next[h];
        ws->next[m] = hn;
        ws->prev[hn] = m;
        set_side(ws, m, ws->side[h]);
        ws->next[hp] = m2;
        ws->prev[m2] = hp;
    } else {
        int h2 = c->nn++;
        ws->node_pt[h2] = ws->node_pt[h];
        ws->nflag[h2] = NF_DUP;
        ws->nflag[h] = (unsigned char)(ws->nflag[h] | NF_DUP);
        ws->next[m] = h;
        ws->prev[h] = m;
        ws->next[hp] = h2;
        ws->prev[h2] = hp;
        ws->next[h2] = m2;
        ws->prev[m2] = h2;
        ws->side[m] = -2 - h2; /* m -> h and h' -> m' are the two sides of the bridge */
        ws->side[h2] = -2 - m;
    }
    ws->next[m2] = mn;
    ws->prev[mn] = m2;
    return 0;
}

/* ------------------------------------------------------------ ear clipping */

/* a node k at the ear tip's position b blocks if one of its ring edges enters the ear's angle */
static int wedge_blocks(const cm_tri_ws *ws, int k, cm_vec2 A, cm_vec2 B, cm_vec2 C)
{
    cm_vec2 X[2] = {npos(ws, ws->prev[k]), npos(ws, ws->next[k])};
    for (int i = 0; i < 2; i++)
        if (!same_pos(X[i], B) && orient_sign(B, C, X[i]) > 0 && orient_sign(B, X[i], A) > 0)
            return 1;
    return 0;
}

/* p is left of the line uv, on it, or less than EPS_TOUCH right of it */
static int near_side(cm_vec2 u, cm_vec2 v, cm_vec2 p)
{
    double e, o = orient(u, v, p, &e);
    return o >= -e || o * o <= EPS_TOUCH * EPS_TOUCH * dist2(u, v);
}

/*
 * Is node b an ear?  strict: b strictly convex and no candidate node in the
 * closed triangle or less than EPS_TOUCH outside it (where loops touch or
 * overlap by rounding, a cut must not pass on the wrong side of a vertex
 * that pokes through a side); relaxed: b convex by the sign alone and no
 * candidate strictly inside; convex_test 0: b's turn is not looked at
 * (least-bad fallback).
 */
static int is_ear(const tess_ctx *c, int b, int relaxed, int convex_test)
{
    const cm_tri_ws *ws = c->ws;
    int a = ws->prev[b], d = ws->next[b];
    cm_vec2 A = npos(ws, a), B = npos(ws, b), C = npos(ws, d);
    if (convex_test) {
        double e, o = orient(A, B, C, &e);
        if (!(o > (relaxed ? 0.0 : e)))
            return 0;
    }
    double pad = EPS_TOUCH;
    double x0 = A.x < B.x ? A.x : B.x, x1 = A.x > B.x ? A.x : B.x;
    double y0 = A.y < B.y ? A.y : B.y, y1 = A.y > B.y ? A.y : B.y;
    x0 = (C.x < x0 ? C.x : x0) - pad;
    x1 = (C.x > x1 ? C.x : x1) + pad;
    y0 = (C.y < y0 ? C.y : y0) - pad;
    y1 = (C.y > y1 ? C.y : y1) + pad;
    uint32_t zlo = zcode(c, x0, y0), zhi = zcode(c, x1, y1);
    int k = ws->znext[b], back = 0;
    for (int g = 0; g < c->nn; g++) {
        if (!back && (k < 0 || ws->zkey[k] > zhi)) { /* forward done: now backward from b */
            back = 1;
            k = ws->zprev[b];
        }
        if (back && (k < 0 || ws->zkey[k] < zlo))
            break;
        int cur = k;
        k = back ? ws->zprev[k] : ws->znext[k];
        if (!(ws->nflag[cur] & NF_CAND) || cur == a || cur == d)
            continue;
        cm_vec2 P = npos(ws, cur);
        if (P.x < x0 || P.x > x1 || P.y < y0 || P.y > y1)
            continue;
        if (same_pos(P, A) || same_pos(P, C))
            continue;
        if (same_pos(P, B)) {
            if (wedge_blocks(ws, cur, A, B, C))
                return 0;
            continue;
        }
        if (relaxed ? (orient_sign(A, B, P) > 0 && orient_sign(B, C, P) > 0 && orient_sign(C, A, P) > 0)
                    : (near_side(A, B, P) && near_side(B, C, P) && near_side(C, A, P)))
            return 0;
    }
    return 1;
}

/* cut ear b: triangle (prev b, b, next b) */
static int clip(tess_ctx *c, int b)
{
    cm_tri_ws *ws = c->ws;
    int a = ws->prev[b], d = ws->next[b];
    int t = new_tri(c, ws->node_pt[a], ws->node_pt[b], ws->node_pt[d]);
    if (t < 0)
        return -1;
    attach(ws, t, 0, a);
    attach(ws, t, 1, b);
    ws->side[a] = 3 * t + 2; /* the new ring edge a -> d is side 2, until cut */
    ws->next[a] = d;
    ws->prev[d] = a;
    node_remove(c, b);
    cand_update(c, a);
    cand_update(c, d);
    return 0;
}

/* remove node b, which repeats the position of a = prev[b]: the edge a -> b has no length */
static void drop_zero_edge(tess_ctx *c, int b)
{
    cm_tri_ws *ws = c->ws;
    int a = ws->prev[b], d = ws->next[b];
    drop_state(ws, ws->side[a]);
    set_side(ws, a, ws->side[b]);
    ws->next[a] = d;
    ws->prev[d] = a;
    node_remove(c, b);
    cand_update(c, a);
    cand_update(c, d);
}

/* a spike a -> b -> d with a, d at one position: pair its two edges, keep a, drop b and d */
static void drop_spike(tess_ctx *c, int b)
{
    cm_tri_ws *ws = c->ws;
    int a = ws->prev[b], d = ws->next[b], e = ws->next[d];
    pair_states(ws, ws->side[a], ws->side[b]);
    node_remove(c, b);
    node_remove(c, d);
    if (e == a) { /* nothing but the spike was left; the edge d -> a has no length */
        drop_state(ws, ws->side[d]);
        ws->side[a] = -1;
        return;
    }
    set_side(ws, a, ws->side[d]);
    ws->next[a] = e;
    ws->prev[e] = a;
    cand_update(c, a);
    cand_update(c, e);
}

/* remove a zero-length edge into k or a spike at k; the node to look at next, or -1 if none */
static int fix_at(tess_ctx *c, int k, int *rem)
{
    cm_tri_ws *ws = c->ws;
    int a = ws->prev[k];
    if (same_pos(npos(ws, a), npos(ws, k))) {
        drop_zero_edge(c, k);
        *rem -= 1;
        return a;
    }
    if (same_pos(npos(ws, a), npos(ws, ws->next[k]))) {
        drop_spike(c, k);
        *rem -= 2;
        return a;
    }
    return -1;
}

/*
 * Clean the ring around node k: zero-length edges and spikes (two edges
 * folding back onto each other, left when a cut runs along a boundary
 * segment that touches another loop) are removed as soon as they appear, so
 * no ear is ever cut across them.  Returns a live node near k.
 */
static int settle(tess_ctx *c, int k, int *rem, int len)
{
    cm_tri_ws *ws = c->ws;
    for (int g = 0; g < len && *rem >= 3; g++) {
        int r = fix_at(c, k, rem);
        if (r < 0 && *rem >= 3) {
            r = fix_at(c, ws->next[k], rem);
            if (r >= 0 && (ws->nflag[k] & NF_DEAD))
                k = r;
        } else if (r >= 0) {
            k = r;
        }
        if (r < 0)
            break;
    }
    return k;
}

/* the least-bad tip when no ear exists: largest sine of the turn among unblocked nodes */
static int least_bad(const tess_ctx *c, int start, int len, double *score)
{
    const cm_tri_ws *ws = c->ws;
    int best = -1, k = start;
    double bs = 0.0;
    for (int g = 0; g < len; g++, k = ws->next[k]) {
        if (!is_ear(c, k, 1, 0))
            continue;
        cm_vec2 A = npos(ws, ws->prev[k]), B = npos(ws, k), C = npos(ws, ws->next[k]);
        double l = sqrt(dist2(A, B) * dist2(B, C));
        double s = l > 0.0 ? cross3(A, B, C) / l : 0.0;
        if (best < 0 || s > bs) {
            best = k;
            bs = s;
        }
    }
    *score = bs;
    return best;
}

/*
 * A fallback ear that turns the wrong way (sine `sc` below -SIN_TOL) means loops that cross.  When
 * the caller allows folds, such a triangle is still cut if its height over its longest side is at
 * most c->fold: two boundary runs closer than the tessellation tolerance that cross by rounding
 * (a sliver of the region) come out as a triangle folded over by less than that.
 */
static int fold_ok(const tess_ctx *c, cm_vec2 A, cm_vec2 B, cm_vec2 C, double sc)
{
    if (sc >= -SIN_TOL)
        return 1;
    if (!(c->fold > 0.0))
        return 0;
    double l = dist2(A, B), m = dist2(B, C), n = dist2(C, A);
    double longest = sqrt(l > m ? (l > n ? l : n) : (m > n ? m : n));
    return longest > 0.0 && fabs(cross3(A, B, C)) <= c->fold * longest;
}

/*
 * A slit tip, when the caller allows folds: the ring turns back at b (by more than a right angle)
 * and the triangle (prev b, b, next b) is no higher over its longest side than c->fold.  Two
 * boundary runs that lie along each other closer than the tessellation tolerance (a zero-width
 * sliver of the region) cross each other by rounding; cutting their tips first closes the sliver
 * like a zip, with triangles between points that are near each other along both runs.  Left to
 * the general ear search, the crossing runs make it fall back to folded ears reaching far along a
 * nearly straight boundary, which no flip removes.
 */
static int slit_tip(const tess_ctx *c, int b)
{
    const cm_tri_ws *ws = c->ws;
    if (!(c->fold > 0.0))
        return 0;
    cm_vec2 A = npos(ws, ws->prev[b]), B = npos(ws, b), C = npos(ws, ws->next[b]);
    if (!((B.x - A.x) * (C.x - B.x) + (B.y - A.y) * (C.y - B.y) < 0.0))
        return 0;
    double l = dist2(A, B), m = dist2(B, C), n = dist2(C, A);
    double longest = sqrt(l > m ? (l > n ? l : n) : (m > n ? m : n));
    return longest > 0.0 && fabs(cross3(A, B, C)) <= c->fold * longest && is_ear(c, b, 1, 0);
}

/* cut ear b and clean the ring around it; the node to go on from */
static int cut(tess_ctx *c, int b, int *rem, int len)
{
    cm_tri_ws *ws = c->ws;
    int a = ws->prev[b], d = ws->next[b];
    if (clip(c, b) < 0)
        return -1;
    *rem -= 1;
    int k = settle(c, a, rem, len);
    if (!(ws->nflag[d] & NF_DEAD))
        k = settle(c, d, rem, len);
    return k;
}

/* Ear tests an ear clipping may spend: past them it gives up and the fallback (cdt_region)
 * triangulates the region.  On the corpus no ring needs more than 2.3 tests per node (2026-12-03,
 * every bench model decoded), but a hostile ring found by fuzz_decode (a loop of a few thousand
 * points whose candidate ears keep failing) took 676,000 tests, 2.1 G instructions, 5 s for one
 * face; with the budget the same file takes 0.3 s. */
#define EAR_TESTS_PER_NODE 16
#define EAR_TESTS_MIN 256
/* Steps the fallback (cdt_region) may spend, per boundary point: its segment recovery (Sloan's flips)
 * and the fan walks finding a side.  A triangulation the fallback finishes needs at most 1.2 steps per
 * point on the corpus and 38.9 on the triangulator's fuzz seeds (2026-12-03), but a folded ring found
 * by fuzz_decode, every segment crossing most others, took 4 G instructions (17 s) for one face.  Past
 * the budget the region is refused (CM_E_DEGENERATE), which leaves the face out. */
#define CDT_WORK_PER_POINT 256L
#define CDT_WORK_MIN 4096L
/* And a share quadratic in the points, up to a cap: a segment forced past a run of n boundary points
 * crosses up to n sides, and Sloan's flips take up to about n^2 / 2 steps for it.  Rings that
 * fuzz_tess found (2026-12-04: a straight run of 200 points, a spike at its end going out and back
 * over itself, and one long segment back beside the run) need 46 000 to 64 000 steps for 206 to 212
 * points, over the linear budget; they do not cross and are now taken.  The cap keeps a hostile
 * ring to 1 M steps more (about 60 ns a step under ASan, 0.06 s), reached at 724 points. */
#define CDT_WORK_QUAD_PER_POINT2 2L
#define CDT_WORK_QUAD_MAX (1L << 20)
/* Boundaries of this many points or more are triangulated by cdt_region first (coarse to fine).
 * Ear clipping cuts a long ring into fans, which the Lawson flips then turn into the Delaunay
 * triangulation one flip at a time, quadratic in the ring: a 4092-point rectangle (a face refined
 * at a hostile tolerance) took 1.4 M flips, 1.3 G instructions per triangulation, 2.6 s for a model
 * of 8 faces on the terminal build.  Every ring of the 24 corpus models at their files' tolerances
 * is below it (the largest 520 points, 2026-12-03), so their meshes are as before. */
#define CDT_FIRST_POINTS 1024
/* triangulate the ring through `start` (`len` nodes) */
static cm_err ear_clip(tess_ctx *c, int start, int len, cm_status *st)
{
    cm_tri_ws *ws = c->ws;
    double ext = c->box[2] - c->box[0] > c->box[3] - c->box[1] ? c->box[2] - c->box[0] : c->box[3] - c->box[1];
    c->zinv = 32767.0 / ext;
    int k = start, rem = len, *v = ws->stack;
    for (int g = 0; g < len; g++, k = ws->next[k]) {
        cand_update(c, k);
        cm_vec2 P = npos(ws, k);
        ws->zkey[k] = zcode(c, P.x, P.y);
        v[g] = k;
    }
    sort_nodes(ws, 1, v, len);
    for (int g = 0; g < len; g++) {
        ws->zprev[v[g]] = g > 0 ? v[g - 1] : -1;
        ws->znext[v[g]] = g + 1 < len ? v[g + 1] : -1;
    }
    for (int g = 0; g < len && rem >= 3; g++)
        k = ws->next[settle(c, k, &rem, len)];
    /* slits first (only when folds are allowed): one turn, each tip zipped up to the slit's mouth;
       after a tip is cut only its two neighbours can have become tips */
    for (int g = 0; c->fold > 0.0 && g < len && rem > 3; g++) {
        int b = k;
        k = ws->next[k];
        while (rem > 3 && slit_tip(c, b)) {
            int a = ws->prev[b], d = ws->next[b];
            int r = cut(c, b, &rem, len);
            if (r < 0)
                return cm_fail(st, CM_E_RANGE, __func__);
            k = r;
            if (rem <= 3)
                break;
            if (!(ws->nflag[a] & NF_DEAD) && slit_tip(c, a))
                b = a;
            else if (!(ws->nflag[d] & NF_DEAD))
                b = d;
            else
                break;
            k = ws->next[b];
        }
    }
    int ear = k, stop = k, skipped = 0;
    /* each turn of at most rem tests either cuts a node, or clears the cache (then the next
       turn tests everything), or falls back (which cuts or fails) */
    uint64_t cap = 2 * (uint64_t)len * (uint64_t)(len + 2) + 16;
    long budget = EAR_TESTS_PER_NODE * (long)len + EAR_TESTS_MIN; /* len < 2^24: no overflow */
    for (uint64_t it = 0; it < cap && rem > 2; it++) {
        if (ws->ear_tests > budget)
            return cm_fail(st, CM_E_DEGENERATE, "ear_clip: too many ear tests (the fallback triangulates)");
        int a = ws->prev[ear], d = ws->next[ear];
        if (rem == 3) {
            cm_vec2 A = npos(ws, a), B = npos(ws, ear), C = npos(ws, d);
            double l = sqrt(dist2(A, B) * dist2(B, C)), sc = l > 0.0 ? cross3(A, B, C) / l : -1.0;
            if (!fold_ok(c, A, B, C, sc))
                return cm_fail(st, CM_E_DEGENERATE, __func__);
            int t = new_tri(c, ws->node_pt[a], ws->node_pt[ear], ws->node_pt[d]);
            if (t < 0)
                break;
            attach(ws, t, 0, a);
            attach(ws, t, 1, ear);
            attach(ws, t, 2, d);
            rem = 0;
            break;
        }
        /* a node that failed keeps failing until its neighbours change (cand_update clears the
           flag) or a node blocking it goes: the cache is cleared after a turn without an ear */
        if (ws->nflag[ear] & NF_NOEAR) {
            skipped++;
        } else if (ws->ear_tests++, is_ear(c, ear, 0, 1)) {
            k = cut(c, ear, &rem, len);
            if (k < 0)
                break;
            /* go on after the next node: fewer slivers (earcut) */
            ear = stop = (ws->nflag[d] & NF_DEAD) ? ws->next[k] : ws->next[d];
            skipped = 0;
            continue;
        } else {
            ws->nflag[ear] = (unsigned char)(ws->nflag[ear] | NF_NOEAR);
        }
        ear = d;
        if (ear != stop)
            continue;
        if (skipped) { /* a whole turn without an ear, some nodes not tested: test them all */
            k = ear;
            for (int g = 0; g < rem; g++, k = ws->next[k])
                ws->nflag[k] = (unsigned char)(ws->nflag[k] & ~NF_NOEAR);
            skipped = 0;
            continue;
        }
        /* a whole turn without an ear */
        int b = -1;
        k = ear;
        for (int g = 0; g < rem && b < 0; g++, k = ws->next[k], ws->ear_tests++)
            if (is_ear(c, k, 1, 1))
                b = k;
        if (b < 0) {
            double sc;
            b = least_bad(c, ear, rem, &sc);
            if (b < 0 || !fold_ok(c, npos(ws, ws->prev[b]), npos(ws, b), npos(ws, ws->next[b]), sc))
                return cm_fail(st, CM_E_DEGENERATE, __func__);
        }
        k = cut(c, b, &rem, len);
        if (k < 0)
            break;
        ear = stop = k;
        skipped = 0;
    }
    if (c->overflow)
        return cm_fail(st, CM_E_RANGE, __func__);
    if (rem == 2) /* two nodes left: their edges are one segment both ways */
        pair_states(ws, ws->side[ear], ws->side[ws->next[ear]]);
    else if (rem > 2)
        return cm_fail(st, CM_E_DEGENERATE, __func__);
    /* a side whose partner never came (only after a fallback) counts as boundary */
    for (int t = 0; t < c->ntri; t++)
        for (int s = 0; s < 3; s++)
            if (ws->adj[t][s] < 0)
                set_fixed(ws, t, s, 1);
    return CM_OK;
}

/* -------------------------------------------------------- Lawson flipping */

static void push_side(tess_ctx *c, int t, int s)
{
    cm_tri_ws *ws = c->ws;
    if ((ws->flag[t] & QUEUED(s)) || c->sp >= 3 * CM_MAX_TESS_TRIS)
        return;
    ws->flag[t] = (unsigned char)(ws->flag[t] | QUEUED(s));
    ws->stack[c->sp++] = 3 * t + s;
}

static void link_side(cm_tri_ws *ws, int t, int s, int S, unsigned fixed)
{
    ws->adj[t][s] = S;
    if (S >= 0)
        ws->adj[S / 3][S % 3] = 3 * t + s;
    set_fixed(ws, t, s, (int)fixed);
}

/* flip side s of t if the pair is not locally Delaunay; 1 if flipped */
/* flip side s of t (its quadrilateral strictly convex): t = (c, a, d), u = (d, b, c); try_flip asks first */
static void force_flip(cm_tri_ws *ws, int t, int s)
{
    int S = ws->adj[t][s], u = S / 3, j = S % 3, s1 = n3(s), s2 = p3(s), j1 = n3(j), j2 = p3(j);
    int a = ws->tri[t][s], b = ws->tri[t][s1], cc = ws->tri[t][s2], d = ws->tri[u][j2];
    int Xbc = ws->adj[t][s1], Xca = ws->adj[t][s2], Xad = ws->adj[u][j1], Xdb = ws->adj[u][j2];
    unsigned fbc = ws->flag[t] & FIX(s1), fca = ws->flag[t] & FIX(s2);
    unsigned fad = ws->flag[u] & FIX(j1), fdb = ws->flag[u] & FIX(j2);
    /* t = (c, a, d), u = (d, b, c), as try_flip leaves them */
    ws->tri[t][0] = cc;
    ws->tri[t][1] = a;
    ws->tri[t][2] = d;
    ws->tri[u][0] = d;
    ws->tri[u][1] = b;
    ws->tri[u][2] = cc;
    link_side(ws, t, 0, Xca, fca != 0);
    link_side(ws, t, 1, Xad, fad != 0);
    link_side(ws, u, 0, Xdb, fdb != 0);
    link_side(ws, u, 1, Xbc, fbc != 0);
    ws->adj[t][2] = 3 * u + 2;
    ws->adj[u][2] = 3 * t + 2;
    set_fixed(ws, t, 2, 0);
    set_fixed(ws, u, 2, 0);
}

static int try_flip(tess_ctx *c, int t, int s)
{
    cm_tri_ws *ws = c->ws;
    int S = ws->adj[t][s];
    if (S < 0 || (ws->flag[t] & FIX(s)))
        return 0;
    int u = S / 3, j = S % 3, s1 = n3(s), s2 = p3(s), j1 = n3(j), j2 = p3(j);
    int a = ws->tri[t][s], b = ws->tri[t][s1], cc = ws->tri[t][s2], d = ws->tri[u][j2];
    if (u == t || cc == d || ws->tri[u][j] != b || ws->tri[u][j1] != a)
        return 0;
    cm_vec2 A = ws->p[a], B = ws->p[b], C = ws->p[cc], D = ws->p[d];
    /* (the tests are pure, so their order changes only the cost: most sides a Lawson pass pops are
       Delaunay already and end at the circle test, so it comes before the convexity test, which
       only a flip needs; the second circle only where the first is not certain) */
    if (orient_sign(A, B, C) > 0 && orient_sign(B, A, D) > 0) {
        /* d in the circle of abc, or equivalently c in the circle of bad: the two evaluations
           round differently (a sliver's own circle is ill-conditioned); either one certain is enough */
        double e1, ic1 = incircle(A, B, C, D, &e1);
        if (!(ic1 > e1)) {
            double e2, ic2 = incircle(B, A, D, C, &e2);
            if (!(ic2 > e2))
                return 0;
        }
    }
    if (orient_sign(A, D, C) <= 0 || orient_sign(D, B, C) <= 0)
        return 0; /* the quadrilateral is not strictly convex */
    force_flip(ws, t, s); /* t = (c, a, d), u = (d, b, c) */
    ws->flips++;
    push_side(c, t, 0);
    push_side(c, t, 1);
    push_side(c, u, 0);
    push_side(c, u, 1);
    return 1;
}

/* flip until the queue is empty (Lawson); the pop budget only guards against a numerical cycle */
static void run_flips(tess_ctx *c)
{
    cm_tri_ws *ws = c->ws;
    uint64_t cap = 64 + 16 * (uint64_t)c->ntri * (uint64_t)c->ntri;
    for (uint64_t it = 0; it < cap && c->sp > 0; it++) {
        int e = ws->stack[--c->sp], t = e / 3, s = e % 3;
        ws->flag[t] = (unsigned char)(ws->flag[t] & ~QUEUED(s));
        (void)try_flip(c, t, s);
    }
    for (; c->sp > 0;) { /* budget exhausted: leave the queue clean */
        int e = ws->stack[--c->sp];
        ws->flag[e / 3] = (unsigned char)(ws->flag[e / 3] & ~QUEUED(e % 3));
    }
}

static void flip_all(tess_ctx *c)
{
    cm_tri_ws *ws = c->ws;
    for (int t = 0; t < c->ntri; t++)
        for (int s = 0; s < 3; s++)
            if (ws->adj[t][s] > 3 * t + s && !(ws->flag[t] & FIX(s)))
                push_side(c, t, s);
    run_flips(c);
}

/* ------------------------------------------------------ interior points */

/* visibility walk from t towards q; -1 if it meets the boundary or does not settle */
static int walk(const tess_ctx *c, int t, cm_vec2 q)
{
    const cm_tri_ws *ws = c->ws;
    for (int step = 0; step < c->ntri + 3; step++) {
        int moved = 0;
        for (int r = 0; r < 3 && !moved; r++) {
            int i = (r + step) % 3; /* rotate the first side tried: no cycling on ties */
            /* q beyond side i (orient's o < -e: orient_sign decides it alike, mostly without the pivot) */
            if (orient_sign(ws->p[ws->tri[t][i]], ws->p[ws->tri[t][n3(i)]], q) < 0) {
                int S = ws->adj[t][i];
                if (S < 0)
                    return -1;
                t = S / 3;
                moved = 1;
            }
        }
        if (!moved)
            return t;
    }
    return -1;
}

static int scan(const tess_ctx *c, cm_vec2 q)
{
    const cm_tri_ws *ws = c->ws;
    for (int t = 0; t < c->ntri; t++) {
        cm_vec2 A = ws->p[ws->tri[t][0]], B = ws->p[ws->tri[t][1]], C = ws->p[ws->tri[t][2]];
        if ((q.x < A.x && q.x < B.x && q.x < C.x) || (q.x > A.x && q.x > B.x && q.x > C.x) ||
            (q.y < A.y && q.y < B.y && q.y < C.y) || (q.y > A.y && q.y > B.y && q.y > C.y))
            continue; /* outside its box (a point on the box still gets the exact test) */
        int in = 1;
        for (int i = 0; i < 3 && in; i++)
            in = orient_sign(ws->p[ws->tri[t][i]], ws->p[ws->tri[t][n3(i)]], q) >= 0;
        if (in)
            return t;
    }
    return -1;
}

/*
 * Is a vertex or a fixed side within sqrt(r2) of q (in triangle t0)?
 * Breadth-first over the triangles that meet the disc, entered through
 * non-fixed sides that meet it: every vertex and boundary segment in the
 * disc is on a triangle of that set, or behind a boundary segment that is.
 */
static int near_used(tess_ctx *c, int t0, cm_vec2 q, double r2, int stamp)
{
    cm_tri_ws *ws = c->ws;
    int tail = 0;
    ws->stack[tail++] = t0;
    ws->mark[t0] = stamp;
    for (int head = 0; head < tail; head++) {
        int t = ws->stack[head];
        for (int i = 0; i < 3; i++)
            if (dist2(q, ws->p[ws->tri[t][i]]) < r2)
                return 1;
        for (int i = 0; i < 3; i++) {
            double d2 = seg_dist2(q, ws->p[ws->tri[t][i]], ws->p[ws->tri[t][n3(i)]]);
            if (!(d2 < r2))
                continue;
            if (ws->flag[t] & FIX(i))
                return 1;
            int S = ws->adj[t][i];
            if (S >= 0 && ws->mark[S / 3] != stamp && tail < 3 * CM_MAX_TESS_TRIS) {
                ws->mark[S / 3] = stamp;
                ws->stack[tail++] = S / 3;
            }
        }
    }
    return 0;
}

/* split t = (a, b, c) at point q inside it */
static int split_tri(tess_ctx *c, int t, int q)
{
    cm_tri_ws *ws = c->ws;
    int a = ws->tri[t][0], b = ws->tri[t][1], d = ws->tri[t][2];
    int X1 = ws->adj[t][1], X2 = ws->adj[t][2];
    unsigned f = ws->flag[t] & FIX_ALL;
    int t1 = new_tri(c, b, d, q), t2 = new_tri(c, d, a, q);
    if (t1 < 0 || t2 < 0)
        return -1;
    ws->tri[t][2] = q;
    link_side(ws, t, 0, ws->adj[t][0], f & 1u);
    link_side(ws, t, 1, 3 * t1 + 2, 0);
    link_side(ws, t, 2, 3 * t2 + 1, 0);
    link_side(ws, t1, 0, X1, (f >> 1) & 1u);
    link_side(ws, t1, 1, 3 * t2 + 2, 0);
    link_side(ws, t2, 0, X2, (f >> 2) & 1u);
    push_side(c, t, 0);
    push_side(c, t1, 0);
    push_side(c, t2, 0);
    return t;
}

/* split side i of t (and the triangle across it) at point q on it */
static int split_side(tess_ctx *c, int t, int i, int q)
{
    cm_tri_ws *ws = c->ws;
    int S = ws->adj[t][i];
    if (S < 0 || (ws->flag[t] & FIX(i)))
        return -2;
    int u = S / 3, j = S % 3, i1 = n3(i), i2 = p3(i), j1 = n3(j), j2 = p3(j);
    int a = ws->tri[t][i], b = ws->tri[t][i1], cc = ws->tri[t][i2], d = ws->tri[u][j2];
    if (u == t || cc == d || ws->tri[u][j] != b || ws->tri[u][j1] != a)
        return -2;
    int Xbc = ws->adj[t][i1], Xca = ws->adj[t][i2], Xad = ws->adj[u][j1], Xdb = ws->adj[u][j2];
    unsigned fbc = ws->flag[t] & FIX(i1), fca = ws->flag[t] & FIX(i2);
    unsigned fad = ws->flag[u] & FIX(j1), fdb = ws->flag[u] & FIX(j2);
    int t1 = new_tri(c, cc, q, b), u1 = new_tri(c, d, q, a);
    if (t1 < 0 || u1 < 0)
        return -1;
    /* t = (c, a, q), t1 = (c, q, b), u = (d, b, q), u1 = (d, q, a) */
    ws->tri[t][0] = cc;
    ws->tri[t][1] = a;
    ws->tri[t][2] = q;
    ws->tri[u][0] = d;
    ws->tri[u][1] = b;
    ws->tri[u][2] = q;
    link_side(ws, t, 0, Xca, fca != 0);
    link_side(ws, t1, 2, Xbc, fbc != 0);
    link_side(ws, u, 0, Xdb, fdb != 0);
    link_side(ws, u1, 2, Xad, fad != 0);
    link_side(ws, t, 1, 3 * u1 + 1, 0);
    link_side(ws, t, 2, 3 * t1 + 0, 0);
    link_side(ws, t1, 1, 3 * u + 1, 0);
    link_side(ws, u, 2, 3 * u1 + 0, 0);
    set_fixed(ws, u, 1, 0);
    push_side(c, t, 0);
    push_side(c, t1, 2);
    push_side(c, u, 0);
    push_side(c, u1, 2);
    return t;
}

/* cell of the location grid holding q (clamped to the grid) */
/* the cell index along one axis of x cells from the box's corner: floor(x) clamped to [0, g - 1],
   without floor (a libm call on x86-64 without SSE4.1, twice per located point): for 0 <= x < g - 1
   the truncation is the floor, and x >= g - 1 and x < 0 clamp alike (NaN too, which made the cast
   undefined) */
static int cell_axis(double x, int g)
{
    if (!(x >= 0.0))
        return 0;
    return x >= (double)(g - 1) ? g - 1 : (int)x;
}

static int cell_of(const tess_ctx *c, cm_vec2 q)
{
    int ix = cell_axis((q.x - c->box[0]) / c->ghx, c->grid), iy = cell_axis((q.y - c->box[1]) / c->ghy, c->grid);
    return iy * c->grid + ix;
}

/*
 * Location grid: G x G cells over the boundary's box (G^2 about half the
 * triangle count, at most CM_MAX_TESS_POINTS), each remembering a triangle
 * that meets it, or -1 if none does: a point in such a cell is outside the
 * region and is skipped without a search (the caller's interior grid covers
 * the box of the face, and every point outside would otherwise cost a scan
 * of all triangles).  Each triangle is rasterised row by row (its x range
 * in each row's strip, widened by GRID_PAD so that rounding never leaves a
 * cell it touches empty), so a sliver costs the cells it crosses, not its
 * box.  Walks start from the cell's triangle, which stays near because the
 * cell takes every triangle a point is inserted into.
 */
#define GRID_PAD 1e-9
static void build_grid(tess_ctx *c)
{
    cm_tri_ws *ws = c->ws;
    int g = (int)sqrt(0.5 * (double)c->ntri); /* ntri < 2 CM_MAX_TESS_POINTS: g^2 fits the cells */
    g = g < 1 ? 1 : g;
    c->grid = g;
    c->grid_ntri = c->ntri;
    c->ghx = (c->box[2] - c->box[0]) / g;
    c->ghy = (c->box[3] - c->box[1]) / g;
    if (!(c->ghx > 0.0 && c->ghy > 0.0)) {
        c->grid = 0;
        return;
    }
    for (int i = 0; i < g * g; i++)
        ws->cell[i] = -1;
    for (int t = 0; t < c->ntri; t++) {
        cm_vec2 V[3] = {ws->p[ws->tri[t][0]], ws->p[ws->tri[t][1]], ws->p[ws->tri[t][2]]};
        double ylo = V[0].y, yhi = V[0].y;
        for (int i = 1; i < 3; i++) {
            ylo = V[i].y < ylo ? V[i].y : ylo;
            yhi = V[i].y > yhi ? V[i].y : yhi;
        }
        int r0 = cell_of(c, cm_v2(c->box[0], ylo - GRID_PAD)) / g, r1 = cell_of(c, cm_v2(c->box[0], yhi + GRID_PAD)) / g;
        for (int r = r0; r <= r1; r++) {
            double y0 = c->box[1] + r * c->ghy - GRID_PAD, y1 = c->box[1] + (r + 1) * c->ghy + GRID_PAD;
            double xlo = 0.0, xhi = 0.0;
            int have = 0;
            for (int i = 0; i < 3; i++) {
                cm_vec2 P = V[i], Q = V[n3(i)];
                double xs[3];
                int n = 0;
                if (P.y >= y0 && P.y <= y1)
                    xs[n++] = P.x;
                for (int k = 0; k < 2; k++) {
                    double yc = k ? y1 : y0;
                    if ((P.y < yc && Q.y > yc) || (P.y > yc && Q.y < yc))
                        xs[n++] = P.x + (yc - P.y) * (Q.x - P.x) / (Q.y - P.y);
                }
                for (int k = 0; k < n; k++) {
                    xlo = !have || xs[k] < xlo ? xs[k] : xlo;
                    xhi = !have || xs[k] > xhi ? xs[k] : xhi;
                    have = 1;
                }
            }
            if (!have)
                continue;
            int c0 = cell_of(c, cm_v2(xlo - GRID_PAD, c->box[1])), c1 = cell_of(c, cm_v2(xhi + GRID_PAD, c->box[1]));
            for (int k = c0; k <= c1; k++)
                ws->cell[r * g + k] = t;
        }
    }
}

/* insert interior point q; returns the triangle to walk from next, -2 if q was skipped, -1 on overflow */
static int insert_point(tess_ctx *c, int q, int last, double r2, int stamp)
{
    cm_tri_ws *ws = c->ws;
    cm_vec2 Q = ws->p[q];
    const double *box = c->box;
    if (!(Q.x >= box[0] - EPS_SNAP && Q.x <= box[2] + EPS_SNAP && Q.y >= box[1] - EPS_SNAP &&
          Q.y <= box[3] + EPS_SNAP))
        return -2; /* outside the boundary's box */
    int cell = c->grid > 0 ? cell_of(c, Q) : -1, t = -1;
    if (cell >= 0) {
        if (ws->cell[cell] < 0)
            return -2; /* no triangle meets the cell: outside the region */
        t = walk(c, ws->cell[cell], Q);
    }
    if (t < 0)
        t = walk(c, last, Q);
    if (t < 0)
        t = scan(c, Q);
    if (t < 0 || near_used(c, t, Q, r2, stamp))
        return -2;
    /* a flat triangle (forced by a vertex on a boundary segment) "contains" every point of its line:
       q is on that boundary line, not in the region */
    if (orient_sign(ws->p[ws->tri[t][0]], ws->p[ws->tri[t][1]], ws->p[ws->tri[t][2]]) <= 0)
        return -2;
    int on = -1;
    double dmin = EPS_ON * EPS_ON;
    for (int i = 0; i < 3; i++) {
        cm_vec2 A = ws->p[ws->tri[t][i]], B = ws->p[ws->tri[t][n3(i)]];
        double e, o = orient(A, B, Q, &e), l2 = dist2(A, B);
        double d2 = l2 > 0.0 ? o * o / l2 : 0.0;
        if (d2 <= dmin) {
            dmin = d2;
            on = i;
        } else if (o < 0.0) {
            return -2; /* not in t after all */
        }
    }
    int r = on >= 0 ? split_side(c, t, on, q) : split_tri(c, t, q);
    if (r < 0)
        return r;
    run_flips(c);
    if (cell >= 0)
        ws->cell[cell] = r;
    return r;
}

/* ---------------------------------------- fallback: constrained triangulation of the loops */

/*
 * When ear clipping cannot finish, or leaves a flat triangle that the input
 * does not force, the region is triangulated again another way, one that
 * needs no simple ring: the boundary points are inserted into a Delaunay
 * triangulation inside an enclosing triangle (points at one position become
 * one vertex), every boundary segment is then forced in as a fixed side
 * (the sides it crosses are flipped away, Sloan's method; a vertex lying on
 * the segment splits it there), and the triangles are kept whose winding
 * number with respect to the loops (outer loop counter-clockwise, holes
 * clockwise, as the ear clipping orients them) is positive: counted from
 * the enclosing triangle, across each fixed side by the pieces of boundary
 * segments along it.  Touching loops, vertices on other loops'
 * segments, holes sharing a vertex or a run of segments with the outer
 * loop, spikes, slits and repeated points need nothing special there; only
 * segments that cross (loops crossing each other or themselves) cannot be
 * forced in: CM_E_DEGENERATE.  A boundary segment a -> b split at vertices
 * v1 .. vk on it gets the flat triangles (a, v(i+1), v(i)) and (a, b, vk),
 * so that it is still a side of a triangle, as the ear clipping leaves it:
 * those are the only flat triangles, and the input forces them.  Nothing of
 * this runs for an input the ear clipping triangulates.
 */
#define SUPER_V CM_MAX_TESS_POINTS /* ids of the enclosing triangle's corners: SUPER_V .. SUPER_V + 2 */
#define CDT_CROSS (-2)             /* a segment crosses a fixed side: the loops cross */
#define CDT_FAIL (-3)              /* the predicates contradict each other (rounding) */
#define TF_SEEN 64u                /* triangle flag: its winding number is known */
#define TF_KEEP 128u               /* triangle flag: in the region */

/* corner of triangle t at vertex v, or -1 */
static int corner_of(const cm_tri_ws *ws, int t, int v)
{
    for (int i = 0; i < 3; i++)
        if (ws->tri[t][i] == v)
            return i;
    return -1;
}

/*
 * Loop [s, e) as make_ring sees it: its distinct points (a point repeating
 * its predecessor, or the first, dropped) into kept[]; returns their count,
 * *a2 twice the signed area (summed as make_ring sums it), *ext the larger
 * extent.
 */
static int loop_shape(const cm_tri_ws *ws, int s, int e, int *kept, double *a2, double *ext)
{
    int cnt = 0;
    for (int k = s; k < e; k++)
        if (cnt == 0 || !same_pos(ws->p[k], ws->p[kept[cnt - 1]]))
            kept[cnt++] = k;
    while (cnt > 1 && same_pos(ws->p[kept[cnt - 1]], ws->p[kept[0]]))
        cnt--;
    cm_vec2 f = ws->p[kept[0]];
    double sum = 0.0, xmin = f.x, xmax = f.x, ymin = f.y, ymax = f.y;
    for (int g = 0; g < cnt; g++) {
        cm_vec2 q = ws->p[kept[g]];
        sum += cross3(f, q, ws->p[kept[g + 1 < cnt ? g + 1 : 0]]);
        xmin = q.x < xmin ? q.x : xmin;
        xmax = q.x > xmax ? q.x : xmax;
        ymin = q.y < ymin ? q.y : ymin;
        ymax = q.y > ymax ? q.y : ymax;
    }
    *a2 = sum;
    *ext = xmax - xmin > ymax - ymin ? xmax - xmin : ymax - ymin;
    return cnt;
}

/*
 * Insert boundary point q into the Delaunay triangulation: returns the
 * vertex standing for it (q, or a vertex already at its position), -1 on
 * overflow, CDT_FAIL if it cannot be located.
 */
static int cdt_insert(tess_ctx *c, int q, int *last)
{
    cm_tri_ws *ws = c->ws;
    cm_vec2 Q = ws->p[q];
    int t = walk(c, *last, Q);
    if (t < 0)
        t = scan(c, Q);
    if (t < 0)
        return CDT_FAIL;
    int on = -1;
    double dmin = EPS_ON * EPS_ON;
    for (int i = 0; i < 3; i++) {
        int v = ws->tri[t][i];
        if (same_pos(ws->p[v], Q))
            return v;
    }
    if (orient_sign(ws->p[ws->tri[t][0]], ws->p[ws->tri[t][1]], ws->p[ws->tri[t][2]]) <= 0)
        return CDT_FAIL; /* only rounding makes a flat triangle here */
    for (int i = 0; i < 3; i++) {
        cm_vec2 A = ws->p[ws->tri[t][i]], B = ws->p[ws->tri[t][n3(i)]];
        double e, o = orient(A, B, Q, &e), l2 = dist2(A, B);
        double d2 = l2 > 0.0 ? o * o / l2 : 0.0;
        if (d2 <= dmin) {
            dmin = d2;
            on = i;
        }
    }
    int r = on >= 0 ? split_side(c, t, on, q) : split_tri(c, t, q);
    if (r == -2)
        r = split_tri(c, t, q);
    if (r < 0)
        return -1;
    run_flips(c);
    *last = r;
    return q;
}

/* set both sides of the edge at side s of t fixed */
static void fix_edge(cm_tri_ws *ws, int t, int s)
{
    set_fixed(ws, t, s, 1);
    int S = ws->adj[t][s];
    if (S >= 0)
        set_fixed(ws, S / 3, S % 3, 1);
}


/* one step of the walk round u (from t0) looking for the side u -> w: 3 t + s when found, -1 not
   yet (*t moved on), -2 the walk is over (round, or off the triangulation) */
static int walk_step(const tess_ctx *c, int *t, int t0, int u, int w)
{
    const cm_tri_ws *ws = c->ws;
    c->ws->cdt_work++;
    int i = corner_of(ws, *t, u);
    if (i < 0)
        return -2;
    if (ws->tri[*t][n3(i)] == w)
        return 3 * *t + i;
    int S = ws->adj[*t][p3(i)];
    *t = S >= 0 ? S / 3 : -1;
    return *t < 0 || *t == t0 ? -2 : -1;
}

/*
 * The side u -> w (3 t + s), or -1: walked round u and round w (as the twin
 * w -> u) a step each in turn, from vt[] (which knows no corner of the
 * enclosing triangle), so that the cost is the smaller degree of the two:
 * a segment forced past a long run of points (a fan: one end of each side
 * crossed has them all) would otherwise pay the fan's degree per side, the
 * fallback's whole budget on a ring of 200 points.  A directed side is
 * unique, so the side found is the one either walk alone would find.
 */
static int find_side(const tess_ctx *c, const int *vt, int u, int w)
{
    int tu = u < SUPER_V ? vt[u] : -1, tw = w < SUPER_V ? vt[w] : -1, u0 = tu, w0 = tw;
    for (int g = 0; g <= c->ntri && (tu >= 0 || tw >= 0); g++) {
        if (tu >= 0) {
            int r = walk_step(c, &tu, u0, u, w);
            if (r >= 0)
                return r;
            if (r == -2)
                tu = -1;
        }
        if (tw >= 0) {
            int r = walk_step(c, &tw, w0, w, u);
            if (r >= 0)
                return c->ws->adj[r / 3][r % 3]; /* its twin, u -> w (-1 on the hull) */
            if (r == -2)
                tw = -1;
        }
    }
    return -1;
}

/*
 * Vertex p lies on the segment from a to b, strictly between: collinear to
 * rounding, or within tol of it and of the whole boundary segment a0 -> b
 * that a -> b is the rest of: tol is EPS_TOUCH (a vertex of a loop touching
 * the segment, a run of segments overlapping another, both only to
 * rounding), or with folds allowed half the fold tolerance (loops crossing
 * by less: the segment is bent through p; its flat triangles, between
 * points within tol of the segment, are folded by less than the tolerance).
 */
static int on_the_way(cm_vec2 a0, cm_vec2 a, cm_vec2 b, cm_vec2 p, double tol)
{
    double l2 = dist2(a, b), o = cross3(a, b, p), o0 = cross3(a0, b, p);
    if (orient_sign(a, b, p) != 0 && !(o * o <= tol * tol * l2 && o0 * o0 <= tol * tol * dist2(a0, b)))
        return 0;
    double along = (p.x - a.x) * (b.x - a.x) + (p.y - a.y) * (b.y - a.y);
    return along > 0.0 && dist2(a, p) < l2;
}

/*
 * Force the segment a -> b (the rest of boundary segment a0 -> b) in, as far
 * as its first vertex: returns the vertex reached (b, or a vertex lying on
 * the segment), CDT_CROSS, CDT_FAIL.  The segment a -> reached is then a
 * fixed side: the sides it crosses are flipped away (Sloan 1993), vt (a
 * triangle at each boundary vertex) kept up to date.
 */
static int cdt_segment(tess_ctx *c, int a0, int a, int b, int *vt)
{
    cm_tri_ws *ws = c->ws;
    cm_vec2 A0 = ws->p[a0], A = ws->p[a], B = ws->p[b];
    double tol = 0.5 * c->fold > EPS_TOUCH ? 0.5 * c->fold : EPS_TOUCH;
    int t = vt[a], i = t >= 0 && t < c->ntri ? corner_of(ws, t, a) : -1;
    if (i < 0)
        for (t = 0; t < c->ntri && (i = corner_of(ws, t, a)) < 0; t++) {
        }
    if (i < 0)
        return CDT_FAIL;
    /* an edge from a to b, else to the nearest vertex on the way (a whole turn round a, so that
       next_piece finds the same), else the triangle at a that the segment leaves a through */
    int t0 = t, bt = -1, bs = -1, bv = -1, wt = -1, wi = -1;
    double bd = 0.0;
    for (int g = 0; g <= c->ntri; g++) {
        int x = ws->tri[t][n3(i)], y = ws->tri[t][p3(i)];
        if (x == b) {
            fix_edge(ws, t, i);
            return b;
        }
        if (on_the_way(A0, A, B, ws->p[x], tol) && (bv < 0 || dist2(A, ws->p[x]) < bd)) {
            bt = t;
            bs = i;
            bv = x;
            bd = dist2(A, ws->p[x]);
        }
        if (wt < 0 && orient_sign(A, B, ws->p[x]) < 0 && orient_sign(A, B, ws->p[y]) > 0) {
            wt = t;
            wi = i;
        }
        int S = ws->adj[t][p3(i)];
        if (S < 0)
            return CDT_FAIL;
        t = S / 3;
        i = corner_of(ws, t, a);
        if (i < 0)
            return CDT_FAIL;
        if (t == t0)
            break;
    }
    if (bv >= 0) {
        fix_edge(ws, bt, bs);
        return bv;
    }
    if (wt < 0)
        return CDT_FAIL;
    t = wt;
    i = wi;
    /* walk along the segment to b or the first vertex on it: the sides it crosses, as vertex pairs
       (right end, left end) in a ring buffer (ex, ey); none of them fixed */
    int *ex = ws->znext, *ey = ws->zprev, cap = CM_TESS_MAX_NODES, nq = 0;
    int s = n3(i), x = ws->tri[t][n3(i)], y = ws->tri[t][p3(i)], tgt = -1;
    for (int g = 0; g <= c->ntri && tgt < 0; g++) {
        if (ws->flag[t] & FIX(s))
            return CDT_CROSS;
        int S = ws->adj[t][s];
        if (S < 0 || nq >= cap)
            return CDT_FAIL;
        ex[nq] = x;
        ey[nq++] = y;
        t = S / 3;
        s = S % 3; /* side s of t: y -> x */
        int d = ws->tri[t][p3(s)];
        if (d == b) {
            tgt = b;
            break;
        }
        cm_vec2 D = ws->p[d];
        int od = orient_sign(A, B, D);
        if (on_the_way(A0, A, B, D, tol)) {
            tgt = d;
        } else if (od == 0) {
            return CDT_FAIL;
        } else if (od > 0) {
            y = d;
            s = n3(s); /* x -> d */
        } else {
            x = d;
            s = p3(s); /* d -> y */
        }
    }
    if (tgt < 0)
        return CDT_FAIL;
    /* Sloan's flips: take a crossing side from the ring; where its quadrilateral is strictly convex
       flip it, and if the new side still crosses put that back; else put it back for later */
    int head = 0, n = nq;
    uint64_t budget = 16 + 8 * (uint64_t)nq * (uint64_t)nq;
    for (uint64_t it = 0; n > 0; it++) {
        if (it > budget || ws->cdt_work > c->cdt_budget)
            return CDT_FAIL;
        ws->cdt_work++;
        int u = ex[head], w = ey[head];
        head = head + 1 < cap ? head + 1 : 0;
        n--;
        int S = find_side(c, vt, u, w);
        if (S < 0)
            return CDT_FAIL;
        int ts = S / 3, ss = S % 3, T2 = ws->adj[ts][ss];
        if (T2 < 0 || (ws->flag[ts] & FIX(ss)))
            return CDT_FAIL;
        int cc = ws->tri[ts][p3(ss)], d = ws->tri[T2 / 3][p3(T2 % 3)];
        cm_vec2 Pu = ws->p[u], Pw = ws->p[w], C = ws->p[cc], D = ws->p[d];
        int slot = head + n < cap ? head + n : head + n - cap;
        if (orient_sign(Pu, D, C) > 0 && orient_sign(D, Pw, C) > 0) {
            force_flip(ws, ts, ss); /* ts = (cc, u, d), T2 / 3 = (d, w, cc) */
            int t2 = T2 / 3;
            if (u < SUPER_V)
                vt[u] = ts;
            if (cc < SUPER_V)
                vt[cc] = ts;
            if (d < SUPER_V)
                vt[d] = ts;
            if (w < SUPER_V)
                vt[w] = t2;
            int oc = orient_sign(A, B, C), odd = orient_sign(A, B, D);
            if ((oc < 0 && odd > 0) || (oc > 0 && odd < 0)) { /* still across: right end first */
                ex[slot] = oc < 0 ? cc : d;
                ey[slot] = oc < 0 ? d : cc;
                n++;
            }
        } else {
            ex[slot] = u;
            ey[slot] = w;
            n++;
        }
    }
    int S = find_side(c, vt, a, tgt);
    if (S < 0)
        return CDT_FAIL;
    fix_edge(ws, S / 3, S % 3);
    return tgt;
}

/*
 * The fixed side from -> r that segment a -> b (forced in) continues along
 * from vertex `from`: r = b, else the nearest vertex on the way (as
 * cdt_segment chose it); *t, *j: the side (from -> r) of the triangle on its
 * left.  0 if there is none (rounding).
 */
static int next_piece(const tess_ctx *c, int a, int from, int b, const int *vt, int *t, int *j)
{
    const cm_tri_ws *ws = c->ws;
    cm_vec2 A0 = ws->p[a], A = ws->p[from], B = ws->p[b];
    double tol = 0.5 * c->fold > EPS_TOUCH ? 0.5 * c->fold : EPS_TOUCH, best = 0.0;
    int tt = vt[from], found = 0;
    for (int g = 0; g <= c->ntri && tt >= 0; g++) {
        int iu = corner_of(ws, tt, from);
        if (iu < 0)
            return 0;
        int x = ws->tri[tt][n3(iu)];
        if ((ws->flag[tt] & FIX(iu)) && x < SUPER_V) {
            double d = dist2(A, ws->p[x]);
            int ok = x == b ? 2 : on_the_way(A0, A, B, ws->p[x], tol);
            if (ok == 2 || (ok && (!found || d < best))) {
                *t = tt;
                *j = iu;
                best = d;
                found = 1;
                if (ok == 2)
                    return 1;
            }
        }
        int S = ws->adj[tt][p3(iu)];
        tt = S >= 0 ? S / 3 : -1;
        if (tt == vt[from])
            break;
    }
    return found;
}

/*
 * The fallback (see above): triangulate the region of the loops in ws->p
 * (scaled, touching points snapped) into c's triangles, with adjacency and
 * fixed sides as ear_clip leaves them.  `coarse`: insert the boundary coarse
 * to fine (every top-th point, top the largest power of two below nb / 2,
 * then the odd multiples of top / 2, of top / 4, ... of 1) instead of in
 * loop order.  Each point then lands beside points already in, at every
 * scale, and the Delaunay triangulation of the ring is rebuilt as it grows
 * with a few flips per point: in loop order a 4092-point rectangle took
 * 859 000 flips, coarse to fine 2 600.  (Only the long rings of
 * CDT_FIRST_POINTS take that order, so the fallback's ties between
 * cocircular points fall as before on every other ring.)
 */
static cm_err cdt_region(tess_ctx *c, const int *loop_start, int nloops, int nb, int coarse, cm_status *st)
{
    cm_tri_ws *ws = c->ws;
    unsigned char *lsign = ws->nflag; /* per loop: 0 left out, 1 as given, 2 reversed */
    int *rep = ws->node_pt, *vt = ws->cell;
    c->ntri = 0;
    c->sp = 0;
    c->overflow = 0;
    for (int l = 0; l < nloops; l++) {
        double a2 = 0.0, ext = 0.0;
        int cnt = loop_shape(ws, loop_start[l], loop_start[l + 1], ws->next, &a2, &ext);
        int ok = cnt >= 3 && fabs(a2) > EPS_AREA * ext * ext;
        if (!ok && l == 0)
            return cm_fail(st, CM_E_DEGENERATE, "cm_triangulate: the outer loop has no area");
        lsign[l] = (unsigned char)(!ok ? 0 : ((l == 0) == (a2 > 0.0) ? 1 : 2));
    }
    /* the enclosing triangle (the boundary's box is within 1 of its centre) and the boundary points */
    double cx = 0.5 * (c->box[0] + c->box[2]), cy = 0.5 * (c->box[1] + c->box[3]);
    ws->p[SUPER_V] = cm_v2(cx - 16.0, cy - 8.0);
    ws->p[SUPER_V + 1] = cm_v2(cx + 16.0, cy - 8.0);
    ws->p[SUPER_V + 2] = cm_v2(cx, cy + 16.0);
    if (new_tri(c, SUPER_V, SUPER_V + 1, SUPER_V + 2) < 0)
        return cm_fail(st, CM_E_RANGE, __func__);
    int last = 0, top = 1;
    while (coarse && top < nb / 2)
        top *= 2;
    /* step 1 (top = 1): every point in loop order */
    for (int step = top; step >= 1; step /= 2)
        for (int i = step == top ? 0 : step, l = 0; i < nb; i += step == top ? step : 2 * step) {
            while (i >= loop_start[l + 1])
                l++;
            if (!lsign[l])
                continue;
            int r = cdt_insert(c, i, &last);
            if (r < 0 || c->overflow)
                return cm_fail(st, r == -1 || c->overflow ? CM_E_RANGE : CM_E_DEGENERATE, __func__);
            rep[i] = r;
        }
    for (int i = 0; i < nb; i++)
        vt[i] = -1;
    for (int t = 0; t < c->ntri; t++)
        for (int i = 0; i < 3; i++)
            if (ws->tri[t][i] < SUPER_V)
                vt[ws->tri[t][i]] = t;
    /* the boundary segments, as fixed sides */
    for (int t = 0; t < c->ntri; t++)
        ws->flag[t] = (unsigned char)(ws->flag[t] & ~(TF_SEEN | TF_KEEP));
    for (int l = 0; l < nloops; l++) {
        int s = loop_start[l], e = loop_start[l + 1];
        for (int i = s; lsign[l] && i < e; i++) {
            int a = rep[i], b = rep[i + 1 < e ? i + 1 : s], from = a;
            if (lsign[l] == 2) {
                a = b;
                b = from;
                from = a;
            }
            for (int g = 0; from != b && g <= nb; g++) {
                int r = cdt_segment(c, a, from, b, vt);
                if (r < 0 && ws->cdt_work > c->cdt_budget)
                    return cm_fail(st, CM_E_DEGENERATE, "cm_triangulate: the fallback's step budget is spent "
                                                        "(boundary segments crossing most others)");
                if (r < 0)
                    return cm_fail(st, CM_E_DEGENERATE,
                                   r == CDT_CROSS ? "cm_triangulate: loops cross" : "cm_triangulate: rounding");
                from = r;
            }
            if (from != b)
                return cm_fail(st, CM_E_DEGENERATE, "cm_triangulate: rounding");
        }
    }
    /* each segment again, along its fixed pieces: the net count of pieces along each side (left
       minus right; twins opposite) into ws->stack; a segment a -> b split at v1 .. vk gets the flat
       triangles (a, v(i+1), v(i)), (a, b, vk), kept aside in next/prev/side */
    int *cnt = ws->stack, nfan = 0;
    for (int k = 0; k < 3 * c->ntri; k++)
        cnt[k] = 0;
    for (int l = 0; l < nloops; l++) {
        int s = loop_start[l], e = loop_start[l + 1];
        for (int i = s; lsign[l] && i < e; i++) {
            int a = rep[i], b = rep[i + 1 < e ? i + 1 : s], from = a;
            if (lsign[l] == 2) {
                a = b;
                b = from;
                from = a;
            }
            for (int g = 0; from != b && g <= nb; g++) {
                int t = -1, j = -1;
                if (!next_piece(c, a, from, b, vt, &t, &j))
                    return cm_fail(st, CM_E_DEGENERATE, "cm_triangulate: rounding");
                int r = ws->tri[t][n3(j)];
                cnt[3 * t + j]++;
                if (ws->adj[t][j] >= 0)
                    cnt[ws->adj[t][j]]--;
                if (from != a) {
                    if (nfan >= CM_TESS_MAX_NODES)
                        return cm_fail(st, CM_E_RANGE, __func__);
                    ws->next[nfan] = a;
                    ws->prev[nfan] = r;
                    ws->side[nfan++] = from;
                }
                from = r;
            }
            if (from != b)
                return cm_fail(st, CM_E_DEGENERATE, "cm_triangulate: rounding");
        }
    }
    /* the winding number of every triangle: 0 at the enclosing triangle's corners, stepping across
       each side by its count; keep those of winding number >= 1 */
    int *wn = ws->mark, *q = ws->znext, nq = 0;
    for (int t = 0; t < c->ntri && nq == 0; t++)
        if (ws->tri[t][0] >= SUPER_V || ws->tri[t][1] >= SUPER_V || ws->tri[t][2] >= SUPER_V) {
            q[nq++] = t;
            wn[t] = 0;
            ws->flag[t] = (unsigned char)(ws->flag[t] | TF_SEEN);
        }
    for (int h = 0; h < nq; h++) {
        int t = q[h];
        for (int j = 0; j < 3; j++) {
            int S = ws->adj[t][j];
            if (S < 0)
                continue;
            int w = wn[t] - cnt[3 * t + j];
            if (ws->flag[S / 3] & TF_SEEN) {
                if (wn[S / 3] != w) /* the pieces do not close up: only rounding in forcing them in */
                    return cm_fail(st, CM_E_DEGENERATE, "cm_triangulate: rounding");
                continue;
            }
            wn[S / 3] = w;
            ws->flag[S / 3] = (unsigned char)(ws->flag[S / 3] | TF_SEEN);
            q[nq++] = S / 3;
        }
    }
    for (int t = 0; t < c->ntri; t++) {
        int inner = ws->tri[t][0] < SUPER_V && ws->tri[t][1] < SUPER_V && ws->tri[t][2] < SUPER_V;
        if (inner && (ws->flag[t] & TF_SEEN) && wn[t] >= 1)
            ws->flag[t] = (unsigned char)(ws->flag[t] | TF_KEEP);
    }
    /* compact the kept triangles (in order); sides towards the others become boundary */
    int *map = ws->mark, nk = 0;
    for (int t = 0; t < c->ntri; t++)
        map[t] = (ws->flag[t] & TF_KEEP) ? nk++ : -1;
    for (int t = 0; t < c->ntri; t++) {
        int u = map[t];
        if (u < 0)
            continue;
        unsigned f = 0;
        int adj[3];
        for (int j = 0; j < 3; j++) {
            int S = ws->adj[t][j];
            adj[j] = S >= 0 && map[S / 3] >= 0 ? 3 * map[S / 3] + S % 3 : -1;
            if ((ws->flag[t] & FIX(j)) || adj[j] < 0)
                f |= FIX(j);
        }
        for (int j = 0; j < 3; j++) {
            ws->tri[u][j] = ws->tri[t][j];
            ws->adj[u][j] = adj[j];
        }
        ws->flag[u] = (unsigned char)f;
    }
    if (nk == 0)
        return cm_fail(st, CM_E_DEGENERATE, "cm_triangulate: no region inside the loops");
    /* the flat triangles of split segments */
    if (nk + nfan > CM_MAX_TESS_TRIS)
        return cm_fail(st, CM_E_RANGE, __func__);
    for (int f = 0; f < nfan; f++) {
        int t = nk + f;
        ws->tri[t][0] = ws->next[f];
        ws->tri[t][1] = ws->prev[f];
        ws->tri[t][2] = ws->side[f];
        for (int j = 0; j < 3; j++)
            ws->adj[t][j] = -1;
        ws->flag[t] = (unsigned char)FIX_ALL;
    }
    c->ntri = nk + nfan;
    /* what bending segments through vertices near them made: nothing folded beyond the tolerance
       (with folds allowed) or beyond the touch distance */
    double lim = c->fold > EPS_TOUCH ? c->fold : EPS_TOUCH;
    for (int t = 0; t < c->ntri; t++) {
        cm_vec2 A = ws->p[ws->tri[t][0]], B = ws->p[ws->tri[t][1]], C = ws->p[ws->tri[t][2]];
        double l = dist2(A, B), m = dist2(B, C), n = dist2(C, A), a2 = cross3(A, B, C);
        double longest = l > m ? (l > n ? l : n) : (m > n ? m : n);
        if (a2 < 0.0 && a2 * a2 > lim * lim * longest && orient_sign(A, B, C) < 0)
            return cm_fail(st, CM_E_DEGENERATE, "cm_triangulate: loops cross");
        ws->mark[t] = 0;
    }
    return CM_OK;
}

/*
 * Is cdt_region's result a plain triangulation of the loops: every loop
 * kept, no point merged with another, every triangle strictly positive and
 * not flat, exactly n + 2 h - 2 of them (n points, h holes), and every side
 * without a neighbour a boundary segment, in the loop's direction (so each
 * of the n segments is one side, and the triangles tile the region once)?
 * Only such a result is taken for a long ring without ear clipping; where
 * the loops do anything else (a loop running back along itself within
 * rounding, a vertex on a segment, touching loops: on occt__bug22869_Spring
 * cdt_region split such segments where ear clipping zips the slit), the ear
 * clipping decides as it does for every shorter ring.
 */
static int flat(cm_vec2 a, cm_vec2 b, cm_vec2 c);
static int cdt_plain(const tess_ctx *c, const int *loop_start, int nloops, int nb)
{
    const cm_tri_ws *ws = c->ws;
    if (c->ntri != nb + 2 * (nloops - 1) - 2)
        return 0;
    for (int l = 0; l < nloops; l++)
        if (ws->nflag[l] == 0)
            return 0;
    for (int i = 0; i < nb; i++)
        if (ws->node_pt[i] != i)
            return 0;
    int open = 0;
    for (int t = 0; t < c->ntri; t++) {
        const int *v = ws->tri[t];
        cm_vec2 A = ws->p[v[0]], B = ws->p[v[1]], C = ws->p[v[2]];
        if (orient_sign(A, B, C) <= 0 || flat(A, B, C))
            return 0;
        for (int j = 0; j < 3; j++) {
            if (ws->adj[t][j] >= 0)
                continue;
            int u = v[j], w = v[n3(j)], lo = 0, hi = nloops - 1;
            while (lo < hi) { /* the loop of u */
                int mid = (lo + hi + 1) / 2;
                if (loop_start[mid] <= u)
                    lo = mid;
                else
                    hi = mid - 1;
            }
            int s = loop_start[lo], e = loop_start[lo + 1];
            int succ = ws->nflag[lo] == 1 ? (u + 1 < e ? u + 1 : s) : (u > s ? u - 1 : e - 1);
            if (w != succ)
                return 0;
            open++;
        }
    }
    return open == nb;
}

/* p on the closed segment ab: within EPS_TOUCH of it (where loops touch), between its ends */
static int on_segment(cm_vec2 a, cm_vec2 b, cm_vec2 p)
{
    double l2 = dist2(a, b), o = cross3(a, b, p);
    if (!(o * o <= EPS_TOUCH * EPS_TOUCH * l2) && orient_sign(a, b, p) != 0)
        return 0;
    double along = (p.x - a.x) * (b.x - a.x) + (p.y - a.y) * (b.y - a.y);
    return along >= 0.0 && along <= l2;
}

/*
 * abc is flat: its largest angle within EPS_FLAT (sine) of a straight one.
 * Points that were collinear before the caller rotated them into the
 * parameter domain (a sampled straight edge, a grid line) are collinear to
 * rounding only, further than orient's bound; this catches them, and not a
 * sliver next to a short segment (its largest angle is far from straight).
 */
static int flat(cm_vec2 a, cm_vec2 b, cm_vec2 c)
{
    double lab = dist2(a, b), lbc = dist2(b, c), lca = dist2(c, a);
    double s1 = lab, s2 = lca; /* the two sides at the largest angle (opposite the longest side) */
    if (lab >= lbc && lab >= lca)
        s1 = lbc;
    else if (lca >= lbc)
        s2 = lbc;
    double a2 = cross3(a, b, c);
    return a2 * a2 <= EPS_FLAT * EPS_FLAT * s1 * s2;
}

/*
 * Is the ear clipping's result one to redo by the fallback: a flat triangle
 * (orientation within its rounding bound) that the input does not force,
 * i.e. whose corners do not all lie on one boundary segment (a vertex on a
 * boundary segment forces a flat triangle for the segment to stay a side)?
 */
static int flat_unforced(const tess_ctx *c, const int *loop_start, int nloops)
{
    const cm_tri_ws *ws = c->ws;
    for (int t = 0; t < c->ntri; t++) {
        cm_vec2 A = ws->p[ws->tri[t][0]], B = ws->p[ws->tri[t][1]], C = ws->p[ws->tri[t][2]];
        if (!flat(A, B, C))
            continue;
        int forced = 0;
        for (int l = 0; l < nloops && !forced; l++)
            for (int i = loop_start[l]; i < loop_start[l + 1] && !forced; i++) {
                cm_vec2 U = ws->p[i], V = ws->p[i + 1 < loop_start[l + 1] ? i + 1 : loop_start[l]];
                forced = !same_pos(U, V) && on_segment(U, V, A) && on_segment(U, V, B) && on_segment(U, V, C);
            }
        if (!forced)
            return 1;
    }
    return 0;
}

/* ------------------------------------------------------------------ driver */

static cm_err check_args(const cm_vec2 *pts, int npts, const int *loop_start, int nloops, double min_dist,
                         int (*tris)[3], int cap, const int *ntris, const cm_tri_ws *ws, cm_status *st)
{
    if (!pts || !loop_start || !ntris || !ws || nloops < 1 || npts < 0 || cap < 0 || (cap > 0 && !tris) ||
        !(min_dist >= 0.0))
        return cm_fail(st, CM_E_ARG, __func__);
    if (npts > CM_MAX_TESS_POINTS)
        return cm_fail_limit(st, CM_LIMIT_MAX_TESS_POINTS, (uint64_t)npts, CM_MAX_TESS_POINTS, __func__);
    if (loop_start[0] != 0 || loop_start[nloops] > npts)
        return cm_fail(st, CM_E_ARG, __func__);
    for (int l = 0; l < nloops; l++)
        if (loop_start[l + 1] <= loop_start[l])
            return cm_fail(st, CM_E_ARG, __func__);
    for (int i = 0; i < npts; i++)
        if (!(fabs(pts[i].x) <= DBL_MAX && fabs(pts[i].y) <= DBL_MAX))
            return cm_fail(st, CM_E_NONFINITE, __func__);
    return CM_OK;
}

/*
 * Scale every point by the power of two k that brings the boundary's
 * larger extent into (1/2, 1]; the box of the boundary goes to c->box.
 * Scaling by a power of two is exact, so every predicate decides as it
 * would on the caller's coordinates (no translation: it would round, and
 * change the answer for nearly degenerate configurations); the tolerances
 * are relative to the extent.  Only if that would overflow (coordinates
 * 1e300 times the extent) the box corner is subtracted first.  Returns k,
 * or 0 if the boundary points all coincide.
 */
static double normalise(const cm_vec2 *pts, int npts, int nb, cm_tri_ws *ws, double box[4])
{
    double xmin = pts[0].x, xmax = xmin, ymin = pts[0].y, ymax = ymin;
    for (int i = 1; i < nb; i++) {
        xmin = pts[i].x < xmin ? pts[i].x : xmin;
        xmax = pts[i].x > xmax ? pts[i].x : xmax;
        ymin = pts[i].y < ymin ? pts[i].y : ymin;
        ymax = pts[i].y > ymax ? pts[i].y : ymax;
    }
    double s = xmax - xmin > ymax - ymin ? xmax - xmin : ymax - ymin;
    if (!(s > 0.0 && s <= DBL_MAX))
        return 0.0;
    double k = 1.0;
    for (int g = 0; g < 2200 && s * k > 1.0; g++)
        k *= 0.5;
    for (int g = 0; g < 2200 && s * k <= 0.5; g++)
        k *= 2.0;
    double big = fabs(xmin) > fabs(xmax) ? fabs(xmin) : fabs(xmax);
    big = fabs(ymin) > big ? fabs(ymin) : big;
    big = fabs(ymax) > big ? fabs(ymax) : big;
    double ox = 0.0, oy = 0.0;
    if (!(big * k <= 1e300)) {
        ox = xmin;
        oy = ymin;
    }
    for (int i = 0; i < npts; i++)
        ws->p[i] = cm_v2((pts[i].x - ox) * k, (pts[i].y - oy) * k);
    ws->done.scale = k;
    ws->done.ox = ox;
    ws->done.oy = oy;
    box[0] = (xmin - ox) * k;
    box[1] = (ymin - oy) * k;
    box[2] = (xmax - ox) * k;
    box[3] = (ymax - oy) * k;
    return k;
}

/* the boundary points i and j are neighbours on one loop (then never snapped together) */
static int loop_neighbours(const int *loop_of, const int *loop_start, int i, int j)
{
    if (loop_of[i] != loop_of[j])
        return 0;
    int s = loop_start[loop_of[i]], e = loop_start[loop_of[i] + 1] - 1;
    return i - j == 1 || j - i == 1 || (i == s && j == e) || (i == e && j == s);
}

/*
 * Loops that touch: boundary points within EPS_TOUCH of each other (and not
 * neighbours on one loop) are given one position, the first's in (x, y)
 * order, so that the rest of the algorithm sees touching loops exactly
 * touching even when the caller mapped the shared vertex into the
 * parameter domain twice with different rounding.  Only the internal copy
 * moves; the output refers to the caller's points.  The forward scan in
 * sorted order is capped at SNAP_WINDOW points, which only matters for
 * pathological inputs with many points within EPS_TOUCH in x.
 */
#define SNAP_WINDOW 64
static void snap_touching(cm_tri_ws *ws, const int *loop_start, int nloops, int nb)
{
    int *loop_of = ws->mark, *v = ws->stack;
    unsigned char *snapped = ws->nflag;
    for (int l = 0; l < nloops; l++)
        for (int i = loop_start[l]; i < loop_start[l + 1]; i++)
            loop_of[i] = l;
    for (int i = 0; i < nb; i++) {
        ws->node_pt[i] = i;
        snapped[i] = 0;
        v[i] = i;
    }
    sort_nodes(ws, 0, v, nb);
    for (int a = 0; a < nb; a++) {
        int i = v[a];
        for (int b = a + 1; b < nb && b <= a + SNAP_WINDOW; b++) {
            int j = v[b];
            if (ws->p[j].x - ws->p[i].x > EPS_TOUCH)
                break;
            if (snapped[j] || fabs(ws->p[j].y - ws->p[i].y) > EPS_TOUCH ||
                loop_neighbours(loop_of, loop_start, i, j))
                continue;
            ws->p[j] = ws->p[i];
            snapped[j] = 1;
        }
    }
}

/* build the single ring: outer loop with every hole bridged in; its start node and length */
static cm_err build_ring(tess_ctx *c, const int *loop_start, int nloops, int *start, int *len, cm_status *st)
{
    cm_tri_ws *ws = c->ws;
    snap_touching(ws, loop_start, nloops, loop_start[nloops]);
    int outer = make_ring(ws, 0, loop_start[1], 1);
    if (outer < 0)
        return cm_fail(st, CM_E_DEGENERATE, __func__);
    int nh = 0, *hole = ws->stack;
    for (int l = 1; l < nloops; l++) {
        int h = make_ring(ws, loop_start[l], loop_start[l + 1], -1);
        if (h < 0)
            continue; /* a hole without area (collapsed by rounding) takes nothing away: left out */
        int k = h, left = h, cnt = loop_start[l + 1] - loop_start[l];
        for (int g = 0; g < cnt; g++, k = ws->next[k]) {
            cm_vec2 P = npos(ws, k), L = npos(ws, left);
            if (P.x < L.x || (P.x == L.x && P.y < L.y))
                left = k;
            if (ws->next[k] == h)
                break;
        }
        hole[nh++] = left;
    }
    sort_nodes(ws, 0, hole, nh);
    int ring_len = 0, k = outer;
    for (int g = 0; g < loop_start[1]; g++, k = ws->next[k]) {
        ring_len++;
        if (ws->next[k] == outer)
            break;
    }
    for (int i = 0; i < nh; i++) {
        int h = hole[i], hl = 0;
        k = h;
        for (int g = 0; g < c->nn; g++, k = ws->next[k]) {
            hl++;
            if (ws->next[k] == h)
                break;
        }
        int m = find_bridge(ws, h, outer, ring_len);
        if (m < 0)
            return cm_fail(st, CM_E_DEGENERATE, __func__); /* the hole is not inside the outer loop */
        int merged = same_pos(npos(ws, m), npos(ws, h));
        if (splice_hole(c, m, h, merged) < 0)
            return cm_fail(st, CM_E_RANGE, __func__);
        ring_len += merged ? hl : hl + 2;
    }
    *start = outer;
    *len = ring_len;
    /* mark nodes that share a position with another node (sorted neighbours) */
    int *v = ws->stack;
    k = outer;
    for (int g = 0; g < ring_len; g++, k = ws->next[k])
        v[g] = k;
    sort_nodes(ws, 0, v, ring_len);
    for (int g = 0; g + 1 < ring_len; g++)
        if (same_pos(npos(ws, v[g]), npos(ws, v[g + 1]))) {
            ws->nflag[v[g]] = (unsigned char)(ws->nflag[v[g]] | NF_DUP);
            ws->nflag[v[g + 1]] = (unsigned char)(ws->nflag[v[g + 1]] | NF_DUP);
        }
    return CM_OK;
}

/*
 * Step 7 and 8: the interior points [from, npts) in order, the final Lawson pass (`final_pass`:
 * after the flips around each point it changes nothing but what rounding left; a continuation
 * skips it, as it costs a test of every side, round after round), the triangles copied out; what
 * cm_triangulate_more continues from is recorded in ws->done.  Stamps of the near-point search
 * are q - nb + 1: they grow with q, so marks left by earlier insertions (and earlier calls
 * continued) never equal one.
 */
static cm_err insert_and_copy(tess_ctx *c, int from, int npts, double min_dist, int final_pass, int (*tris)[3],
                              int cap, int *ntris, int *nused, cm_status *st)
{
    cm_tri_ws *ws = c->ws;
    int nb = ws->done.nb;
    double md = min_dist * ws->done.scale, r = md > EPS_SNAP ? md : EPS_SNAP, r2 = r * r;
    int last = ws->done.last < c->ntri ? ws->done.last : 0, used = 0;
    for (int q = from; q < npts; q++) {
        int t = insert_point(c, q, last, r2, q - nb + 1);
        if (t == -1 || c->overflow)
            return cm_fail(st, CM_E_RANGE, __func__);
        if (t >= 0) {
            last = t;
            used++;
        }
    }
    if (final_pass)
        flip_all(c);

    if (c->ntri > cap)
        return cm_fail_nospace(st, (uint64_t)c->ntri, (uint64_t)cap, __func__);
    for (int t = 0; t < c->ntri; t++)
        for (int i = 0; i < 3; i++)
            tris[t][i] = ws->tri[t][i];
    *ntris = c->ntri;
    if (nused)
        *nused = used;
    ws->done.npts = npts;
    ws->done.ntri = c->ntri;
    ws->done.last = last;
    ws->done.valid = 1;
    ws->done.grid = c->grid;
    ws->done.grid_ntri = c->grid_ntri;
    ws->done.ghx = c->ghx;
    ws->done.ghy = c->ghy;
    return CM_OK;
}

cm_err cm_triangulate(const cm_vec2 *pts, int npts, const int *loop_start, int nloops, double min_dist,
                      int (*tris)[3], int cap, int *ntris, int *nused, cm_tri_ws *ws, cm_status *st)
{
    return cm_triangulate_folds(pts, npts, loop_start, nloops, min_dist, 0.0, tris, cap, ntris, nused, ws, st);
}

cm_err cm_triangulate_folds(const cm_vec2 *pts, int npts, const int *loop_start, int nloops, double min_dist,
                            double fold_tol, int (*tris)[3], int cap, int *ntris, int *nused, cm_tri_ws *ws,
                            cm_status *st)
{
    return cm_triangulate_cdt(pts, npts, loop_start, nloops, min_dist, fold_tol, CDT_FIRST_POINTS, tris, cap, ntris,
                              nused, ws, st);
}

cm_err cm_triangulate_cdt(const cm_vec2 *pts, int npts, const int *loop_start, int nloops, double min_dist,
                          double fold_tol, int cdt_first, int (*tris)[3], int cap, int *ntris, int *nused,
                          cm_tri_ws *ws, cm_status *st)
{
    if (ntris)
        *ntris = 0;
    if (nused)
        *nused = 0;
    if (ws)
        ws->done.valid = 0;
    cm_err err = check_args(pts, npts, loop_start, nloops, min_dist, tris, cap, ntris, ws, st);
    if (err != CM_OK)
        return err;
    int nb = loop_start[nloops];
    tess_ctx c;
    memset(&c, 0, sizeof c);
    ws->ear_tests = 0;
    ws->cdt_work = 0;
    ws->flips = 0;
    long quad = nb > 1024 ? CDT_WORK_QUAD_MAX : CDT_WORK_QUAD_PER_POINT2 * (long)nb * (long)nb; /* no 32-bit overflow */
    c.cdt_budget = CDT_WORK_PER_POINT * (long)nb + CDT_WORK_MIN + (quad < CDT_WORK_QUAD_MAX ? quad : CDT_WORK_QUAD_MAX);
    double scale = normalise(pts, npts, nb, ws, c.box);
    if (!(scale > 0.0))
        return cm_fail(st, CM_E_DEGENERATE, __func__);
    c.ws = ws;
    c.nn = nb;
    c.fold = fold_tol > 0.0 ? fold_tol * scale : 0.0;
    /* ear clipping; where it cannot finish, or leaves a flat triangle the input does not force, the
       fallback (cdt_region); its failure is the one reported.  A boundary of CDT_FIRST_POINTS or
       more is first inserted coarse to fine by cdt_region, and taken when that gives a plain
       triangulation (cdt_plain) */
    int start = 0, len = 0;
    cm_status first;
    cm_status_init(&first);
    err = CM_E_DEGENERATE;
    if (nb >= (cdt_first > 0 ? cdt_first : CDT_FIRST_POINTS)) {
        snap_touching(ws, loop_start, nloops, nb); /* as build_ring does (it is idempotent) */
        if (cdt_region(&c, loop_start, nloops, nb, 1, &first) == CM_OK && cdt_plain(&c, loop_start, nloops, nb)) {
            flip_all(&c);
            err = CM_OK;
        } else { /* as if never tried */
            c.ntri = c.sp = c.overflow = 0;
            c.nn = nb;
            ws->cdt_work = 0;
            cm_status_init(&first);
        }
    }
    if (err != CM_OK) {
        err = build_ring(&c, loop_start, nloops, &start, &len, &first);
        if (err == CM_OK)
            err = ear_clip(&c, start, len, &first);
        if (err == CM_OK && c.ntri > 0) {
            flip_all(&c);
            if (flat_unforced(&c, loop_start, nloops))
                err = CM_E_DEGENERATE;
        } else if (err == CM_OK) {
            err = CM_E_DEGENERATE;
        }
    }
    if (err == CM_E_DEGENERATE) {
        cm_status_init(&first);
        err = cdt_region(&c, loop_start, nloops, nb, 0, &first);
        if (err == CM_OK)
            flip_all(&c);
    }
    if (err != CM_OK) {
        if (st && st->code == CM_OK)
            *st = first;
        return err;
    }

    if (npts > nb)
        build_grid(&c);
    ws->done.nb = nb;
    ws->done.last = 0;
    for (int i = 0; i < 4; i++)
        ws->done.box[i] = c.box[i];
    /* the final pass only after interior points: the region was flipped after its boundary */
    return insert_and_copy(&c, nb, npts, min_dist, npts > nb, tris, cap, ntris, nused, st);
}

cm_err cm_triangulate_more(const cm_vec2 *pts, int npts, double min_dist, int (*tris)[3], int cap, int *ntris,
                           cm_tri_ws *ws, cm_status *st)
{
    if (ntris)
        *ntris = 0;
    if (!pts || !ntris || !ws || cap < 0 || (cap > 0 && !tris) || !(min_dist >= 0.0) || !ws->done.valid ||
        npts < ws->done.npts) {
        if (ws)
            ws->done.valid = 0;
        return cm_fail(st, CM_E_ARG, __func__);
    }
    ws->done.valid = 0;
    if (npts > CM_MAX_TESS_POINTS)
        return cm_fail_limit(st, CM_LIMIT_MAX_TESS_POINTS, (uint64_t)npts, CM_MAX_TESS_POINTS, __func__);
    double k = ws->done.scale;
    for (int i = ws->done.npts; i < npts; i++) {
        if (!(fabs(pts[i].x) <= DBL_MAX && fabs(pts[i].y) <= DBL_MAX))
            return cm_fail(st, CM_E_NONFINITE, __func__);
        ws->p[i] = cm_v2((pts[i].x - ws->done.ox) * k, (pts[i].y - ws->done.oy) * k);
    }
    tess_ctx c;
    memset(&c, 0, sizeof c);
    c.ws = ws;
    c.ntri = ws->done.ntri;
    for (int i = 0; i < 4; i++)
        c.box[i] = ws->done.box[i];
    ws->flips = 0;
    /* the location grid stays right as points go in (the region does not change, and a cell's
       triangle is still a triangle, near it); it is built again, to the triangles there are now,
       when they have grown fourfold, so that walks stay short (a build each call cost 7 % of a
       decode, one each doubling 4 %) */
    c.grid = ws->done.grid;
    c.grid_ntri = ws->done.grid_ntri;
    c.ghx = ws->done.ghx;
    c.ghy = ws->done.ghy;
    if (npts > ws->done.npts && (c.grid == 0 || c.ntri >= 4 * c.grid_ntri))
        build_grid(&c);
    return insert_and_copy(&c, ws->done.npts, npts, min_dist, 0, tris, cap, ntris, NULL, st);
}
