/*
 * tx_coarsen.c - format 3's precision from the tolerance budget (issue 14.3; docs/FORMAT.md, EDGE).
 *
 * The grid (1e-6 of the model's diagonal) is what the smallest faces need.  Most of a model needs
 * much less: a point moved by e moves a B-spline or NURBS curve or surface by
 * at most e (its points are convex combinations of the control points), while the faces they bound
 * are held to a tolerance of up to 1e-3 of the diagonal.  So each curve takes a step of its own,
 * 2^s grid steps, and its points are sent as multiples of it (the vertices one step for all, from
 * the smallest face and the shortest edge of the model; the format gives each kept net a step too):
 *   - the budget: a sixteenth of the tolerance of the faces it bounds, so that the rebuild, which
 *     the encoder measures on the moved curves anyway, keeps the rest;
 *   - and the shape: no point moves by more than 4.4e-3 of the shortest leg of its polygon or net: a
 *     tangent (a difference of two points) then turns by at most tan(0.5 deg), so that two faces
 *     along a tangent edge stay within the 1 degree the G1 check holds rebuilt faces to (measured
 *     over the corpus: 2e-3 saved 4 % of the bytes, 4.4e-3 8 %, a tolerance share of 1/8 instead of
 *     1/16 under 1 % more: the legs, not the tolerance, bound the step on most curves);
 *   - a curve with two coincident successive points (a collapsed end) keeps the grid, since its
 *     predictions need not keep them coincident.
 * A curve's points are moved in closed loop: each is sent as its prediction from the points already
 * moved plus a multiple of the step, nearest to the original, so each coordinate moves by at most
 * half a step whatever came before.  The vertices go to the nearest multiple of their step instead,
 * so that equal vertices stay equal.  Kept nets stay on the grid (tx_net_predictor says why), and so
 * do the edges of kept faces and, when a face is kept, the vertices (enc_keep_fine_edges).
 * Everything after this (the methods' trials, the G1 check, the needs) runs on the moved points,
 * exactly as the terminal will decode them.
 */
#include "encode_internal.h"

#include <math.h>
#include <stdlib.h>


#define BUDGET_SHARE ENC_CURVE_SHARE
#define KEPT_SURFACE_SHARE 0.25  /* of its face's tolerance, for a kept surface re-approximated */
#define TURN_SHARE 4.4e-3         /* of the shortest leg: tan(0.5 deg) / 2, half a degree of turning */

/* the step exponent (encode_internal.h); 0 for coincident points (h_min 0) */
int tx_choose_step(const tx *t, double tol_mm, double h_min)
{
    if (!t->o->predicted || !t->o->budget_steps || !(tol_mm > 0) || !(h_min > 0))
        return 0;
    double allowed = fmin(BUDGET_SHARE * tol_mm, TURN_SHARE * h_min);
    int s = 0;
    /* a coordinate moves by at most half a step: the point by sqrt(3)/2 of it */
    while (s < CM_FMT_MAX_STEP && 0.8660254037844386 * ldexp(t->q, s + 1) <= allowed)
        s++;
    return s;
}

/* halves away from zero */
int64_t tx_div_step(int64_t v, int s)
{
    int64_t d = (int64_t)1 << s, h = d / 2;
    return v >= 0 ? (v + h) / d : -((-v + h) / d);
}

static double leg_mm(const tx *t, const int64_t a[3], const int64_t b[3])
{
    double s = 0;
    for (int k = 0; k < 3; k++) {
        double d = (double)(a[k] - b[k]) * t->q;
        s += d * d;
    }
    return sqrt(s);
}

void tx_coarsen_edge(const tx *t, tx_edge *X, int fine, double tol_mm)
{
    X->linear = X->step = 0;
    if (!t->o->predicted || X->kind == CM_EDGE_LINE || X->n < 3)
        return;
    int n = X->n;
    double h_min = HUGE_VAL;
    for (int j = 1; j < n; j++)
        h_min = fmin(h_min, leg_mm(t, X->cq[j], X->cq[j - 1]));
    int s = fine ? 0 : tx_choose_step(t, tol_mm, h_min);
    /* the predictor whose residuals, at this step, cost fewer bits (estimated open loop) */
    double bits[2] = {0, 0};
    for (int linear = 0; linear < 2; linear++)
        for (int j = 1; j < n - 1; j++)
            for (int k = 0; k < 3; k++)
                bits[linear] += enc_sint_bits(tx_div_step(X->cq[j][k] - tx_edge_pred(X, linear, j, k), s));
    X->linear = bits[1] < bits[0];
    X->step = s;
    for (int j = 1; j < n - 1; j++)
        for (int k = 0; k < 3; k++) {
            int64_t pred = tx_edge_pred(X, X->linear, j, k);
            X->cq[j][k] = pred + tx_div_step(X->cq[j][k] - pred, s) * ((int64_t)1 << s);
        }
}

/*
 * Curves in their own budget's terms (issue 14.4).  The exporters' curves carry what their systems
 * needed: ICEM's degree-7 Bezier boundaries (ovt__asmo), 36-point hull splines (ovt__ship_kvlcc2),
 * rational circles of 9 points and their weights and double knots (asitus__IAD_v3).  Within a
 * sixteenth of the tolerance of a face their size (the share the step above takes as well: the
 * rebuild, measured on what the terminal decodes, keeps the rest), most of them are a uniform cubic
 * B-spline of a few points, which costs no knots and no weights (a full circle: 9 points, 8 weights
 * and 3 double knots; at a loose tolerance a few cubic points and nothing else, at the default one
 * more cubic points than its rational form costs, so the caller keeps the circle).  The fit is
 * enc_edge_refit_ex's by length (end points kept, least squares over samples at equal steps of the
 * curve's length, checked at four times as many against the curve at the same fraction of its
 * length: by parameter, a conic's varying speed failed fits that were close); the counts tried grow
 * by a quarter, the first that holds wins.  A face the curve bounds that then fails or is kept takes
 * the curve back as it was (enc_keep_fine_edges).  Measured over the corpus with the budget steps:
 * 501 967 -> 436 465 bytes (asitus__IAD_v3 -24 %, occt__hammer -47 %, ovt__ship_kvlcc2 -18 %).
 */
double curve_face_tol(const tx *t, const hcurve *c)
{
    cm_vec3 lo = c->ctrl[0], hi = c->ctrl[0];
    for (int j = 1; j < c->n; j++) {
        lo = cm_v3(fmin(lo.x, c->ctrl[j].x), fmin(lo.y, c->ctrl[j].y), fmin(lo.z, c->ctrl[j].z));
        hi = cm_v3(fmax(hi.x, c->ctrl[j].x), fmax(hi.y, c->ctrl[j].y), fmax(hi.z, c->ctrl[j].z));
    }
    return encode_face_tol(t->o->rel_tol, t->o->rel_set, t->o->abs_tol, cm_dist(lo, hi));
}

double surf_face_tol(const tx *t, const hsurf *s)
{
    cm_vec3 lo = s->ctrl[0], hi = s->ctrl[0];
    for (long j = 1; j < (long)s->nu * s->nv; j++) {
        lo = cm_v3(fmin(lo.x, s->ctrl[j].x), fmin(lo.y, s->ctrl[j].y), fmin(lo.z, s->ctrl[j].z));
        hi = cm_v3(fmax(hi.x, s->ctrl[j].x), fmax(hi.y, s->ctrl[j].y), fmax(hi.z, s->ctrl[j].z));
    }
    return encode_face_tol(t->o->rel_tol, t->o->rel_set, t->o->abs_tol, cm_dist(lo, hi));
}

int tx_reapproximate_curve(const tx *t, hcurve *c)
{
    if (!t->o->predicted || !t->o->budget_steps || c->n <= 4)
        return 0;
    double tol = BUDGET_SHARE * curve_face_tol(t, c);
    /* fewer points; as many where the degree differs; half as many more where weights or uneven knots
       are saved (the caller sends the curve this way only where it costs fewer bits) */
    int most = c->w || enc_knots_uneven(c->knots, c->p, c->n) ? c->n + c->n / 2 : c->p != 3 ? c->n : c->n - 1;
    for (int n = 4; n <= most; n += 1 + n / 4) {
        hcurve f = {0};
        cm_status st;
        cm_status_init(&st);
        if (hcurve_copy(c, &f, &st) != CM_OK)
            return 0;
        if (enc_edge_refit_ex(&f, 3, n, tol, 1, &st)) {
            hcurve_free(c);
            *c = f;
            return 1;
        }
        hcurve_free(&f);
    }
    return 0;
}

/*
 * Kept surfaces likewise (issue 14.4): an exporter's net carries what its system needed
 * (asitus__Pieza1's rows of 178 points, IAD_v3's of 529, a ship hull of 99 x 68), where a uniform
 * cubic net of far fewer points stays within a quarter of the tolerance of a face its size: the
 * share the board fit takes (fit_board.c), since a kept face has no rebuild to leave room for; the
 * net stays on the grid (tx_net_predictor).  The rows are re-fitted first, within half of that,
 * then the columns, each to the fewest points that hold (counts growing by a quarter, as for
 * curves), measured against the original at the same parameters on a grid of four checks per
 * point each way, so the kept face's parameters (found by projecting its boundary) stay where
 * they were.
 * The boundary takes the same quarter: the face's edges, which the kept face's triangles meet,
 * then lie up to that off the surface, and format 4.1's tessellation tests a kept face's loop
 * against the surface's points (cm_tessellate.c, kept_off_edges; tested against the edges' own
 * points, the refinement crowded points where the loop runs off the surface, and eight of
 * asitus__IAD_v3's kept faces folded 78 to 228 triangles at a quarter of the recommended
 * tolerance).  Writing for an older terminal, whose tessellation still tests against the edges,
 * the boundary is held to the curves' share, a sixteenth, where the face's edges run along it
 * (face_meets_rim; nearly every kept face of the corpus).  Either way the encoder tessellates
 * every kept face with a re-approximated net as the terminal will, and a net that folds its face's
 * triangles is sent whole (needs.c, encode_model): occt__bug22869_Spring's coil, whose net a
 * quarter off folded 54 triangles where it meets its end cap.  The new net is taken only where it
 * codes in fewer bytes (enc_net_bytes): a smooth net on uniform knots, which the net's predictor
 * nearly foretells, may cost less whole.  Measured over the corpus: 421 664 -> 319 643 bytes with
 * the compact header of 4.1, median IGES/.cmz 79.7x -> 101.2x (asitus__Pieza1 77 413 -> 31 981,
 * asitus__IAD_v3 161 440 -> 124 947, ovt__ship_kvlcc2 16 507 -> 10 946, ovt__asmo 16 608 ->
 * 13 701); no face folds at the recommended tolerance, nor at a quarter or a tenth of it.  With
 * the boundary held to a sixteenth everywhere: 338 151 bytes, 88.2x (the hull's net kept whole).
 */
#define RIM_SAMPLES 256  /* points of each of the net's four boundary curves */
#define EDGE_SAMPLES 16  /* points of each edge of the face */
#define RIM_NEAR 2e-3    /* of the face's size: an edge point this close to a boundary curve is on it */

/* whether face f's boundary runs along a boundary curve of net s */
static int face_meets_rim(const cmesh *cm, int f, const hsurf *s)
{
    cm_surf sv = hsurf_view(s);
    double u0, u1, v0, v1;
    hsurf_domain(s, &u0, &u1, &v0, &v1);
    cm_vec3 *rim = malloc(4 * (RIM_SAMPLES + 1) * sizeof *rim);
    if (!rim)
        return 1;
    cm_vec3 lo = cm_v3(HUGE_VAL, HUGE_VAL, HUGE_VAL), hi = cm_v3(-HUGE_VAL, -HUGE_VAL, -HUGE_VAL);
    int n = 0;
    for (int side = 0; side < 4; side++)
        for (int i = 0; i <= RIM_SAMPLES; i++) {
            double a = (double)i / RIM_SAMPLES, u = side < 2 ? u0 + (u1 - u0) * a : (side == 2 ? u0 : u1),
                   v = side < 2 ? (side == 0 ? v0 : v1) : v0 + (v1 - v0) * a;
            cm_vec3 d[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
            cm_status st;
            cm_status_init(&st);
            if (cm_surf_eval(&sv, u, v, 0, d, &st) != CM_OK) {
                free(rim);
                return 1;
            }
            rim[n++] = d[0][0];
            lo = cm_v3(fmin(lo.x, d[0][0].x), fmin(lo.y, d[0][0].y), fmin(lo.z, d[0][0].z));
            hi = cm_v3(fmax(hi.x, d[0][0].x), fmax(hi.y, d[0][0].y), fmax(hi.z, d[0][0].z));
        }
    double near = RIM_NEAR * cm_dist(lo, hi);
    int meets = 0;
    const cmesh_face *cf = &cm->faces[f];
    for (int l = 0; l < cf->nloops && !meets; l++) {
        const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
        for (int k = 0; k < cl->n && !meets; k++) {
            const hcurve *c = &cm->edges[cm->uses[cl->first + k].edge].c;
            cm_curve cv = hcurve_view(c);
            double t0, t1;
            hcurve_domain(c, &t0, &t1);
            for (int i = 1; i < EDGE_SAMPLES && !meets; i++) { /* inner points: the ends are corners */
                cm_vec3 P;
                cm_status st;
                cm_status_init(&st);
                if (cm_curve_eval(&cv, t0 + (t1 - t0) * i / EDGE_SAMPLES, 0, &P, &st) != CM_OK) {
                    meets = 1;
                    break;
                }
                for (int j = 0; j < n && !meets; j++)
                    if (j % (RIM_SAMPLES + 1) != RIM_SAMPLES) {
                        /* the distance to the segment from rim[j] to rim[j + 1] */
                        cm_vec3 a = rim[j], ab = cm_sub(rim[j + 1], a);
                        double L = cm_dot(ab, ab), x = L > 0 ? cm_dot(cm_sub(P, a), ab) / L : 0;
                        x = x < 0 ? 0 : (x > 1 ? 1 : x);
                        meets = cm_dist(P, cm_add(a, cm_scale(ab, x))) <= near;
                    }
            }
        }
    }
    free(rim);
    return meets;
}

int tx_reapproximate_surface(const tx *t, hsurf *s, const cmesh *cm, int f)
{
    if (!t->o || !t->o->predicted || !t->o->budget_steps || (s->nu <= 4 && s->nv <= 4))
        return 0;
    cm_status st;
    cm_status_init(&st);
    double face_tol = surf_face_tol(t, s);
    /* a terminal older than 4.1 tests a kept face's loop against its edges */
    int held = !(enc_compact_header(t->o) && t->o->compact_minor >= (int)CM_FMT_KEPT_OFF_EDGES_MINOR) &&
               face_meets_rim(cm, f, s);
    double rim_tol = (held ? BUDGET_SHARE : KEPT_SURFACE_SHARE) * face_tol;
    hsurf r = {0};
    if (hsurf_copy(s, &r, &st) != CM_OK)
        return 0;
    if (enc_surf_reduce(&r, KEPT_SURFACE_SHARE * face_tol, rim_tol, &st) && (long)r.nu * r.nv < (long)s->nu * s->nv) {
        hsurf_free(s);
        *s = r;
        return 1;
    }
    hsurf_free(&r);
    return 0;
}

void tx_net_predictor(const tx *t, tx_surf *S)
{
    /* Kept nets stay on the grid (the format's step for them is sent as 0).  Moved by up to a
       sixteenth of their face's tolerance, in closed loop or to the nearest multiples of their step
       alike, the kept faces' boundaries came apart from their neighbours' in the decoded mesh
       (elif__Motor_case_back: 8 open sides; in closed loop also gmsh__model1, whose seams opened,
       and a projection 2.2 mm astray in asitus__IAD_v3): the tessellation of a kept face meets its
       edges through the surface, which then no longer passes through them closely enough.  Only
       the predictor is chosen here: the one whose residuals cost fewer bits. */
    S->quadratic = 0;
    if (!t->o->predicted)
        return;
    int nu = S->nu, nv = S->nv;
    double bits[2] = {0, 0};
    for (int quadratic = 0; quadratic < 2; quadratic++)
        for (int i = 0; i < nu * nv; i++)
            for (int k = 0; k < 3; k++)
                bits[quadratic] +=
                    enc_sint_bits(S->cq[i][k] - cm_pred_net(quadratic, (const int64_t(*)[3])S->cq, nv, i / nv, i % nv, k));
    S->quadratic = bits[1] < bits[0];
}

/* the tolerance (mm) of face f as the encoder will hold it, its size the box of its edges' control
   points (which holds its boundary) */
static double face_tol(const tx *t, const cmesh *cm, int f)
{
    const cmesh_face *cf = &cm->faces[f];
    cm_vec3 lo = cm_v3(HUGE_VAL, HUGE_VAL, HUGE_VAL), hi = cm_v3(-HUGE_VAL, -HUGE_VAL, -HUGE_VAL);
    for (int l = 0; l < cf->nloops; l++) {
        const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
        for (int i = 0; i < cl->n; i++) {
            const hcurve *c = &cm->edges[cm->uses[cl->first + i].edge].c;
            for (int j = 0; j < c->n; j++) {
                lo = cm_v3(fmin(lo.x, c->ctrl[j].x), fmin(lo.y, c->ctrl[j].y), fmin(lo.z, c->ctrl[j].z));
                hi = cm_v3(fmax(hi.x, c->ctrl[j].x), fmax(hi.y, c->ctrl[j].y), fmax(hi.z, c->ctrl[j].z));
            }
        }
    }
    double d = hi.x >= lo.x ? cm_dist(lo, hi) : 0.0;
    return encode_face_tol(t->o->rel_tol, t->o->rel_set, t->o->abs_tol, d);
}

void tx_coarsen_vertices(tx *t, const cmesh *cm)
{
    t->vstep = 0;
    if (!t->o->predicted || !t->o->budget_steps || t->nverts == 0 || t->no_vstep)
        return;
    /* one step for all: a vertex's own budget (its faces, its edges) would let the vertices of large
       faces move further, and measured over the corpus that turned more faces back (gmsh__model1:
       2 -> 4 kept) than the bits it saved */
    double tol = HUGE_VAL, h_min = HUGE_VAL;
    for (int f = 0; f < cm->nfaces; f++)
        tol = fmin(tol, face_tol(t, cm, f));
    for (int e = 0; e < cm->nedges; e++) {
        const cmesh_edge *E = &cm->edges[e];
        int a0 = t->vert_tx[E->v0], a1 = t->vert_tx[E->v1];
        if (a0 >= 0 && a1 >= 0 && a0 != a1)
            h_min = fmin(h_min, leg_mm(t, t->vq[a0], t->vq[a1]));
    }
    int s = tx_choose_step(t, tol, h_min);
    t->vstep = s;
    for (int v = 0; v < t->nverts; v++)
        for (int k = 0; k < 3; k++)
            t->vq[v][k] = tx_div_step(t->vq[v][k], s) * ((int64_t)1 << s);
}

/*
 * A kept face is tessellated on its own surface, which meets its edges only as closely as the file
 * it came from made them: moved by even a sixteenth of the tolerance, its edges and its net came
 * apart from each other (occt__bug22869_Spring: 100 overlapping triangles where a moved helix edge
 * met its kept coil; with moved nets, open sides in elif__Motor_case_back).  So the edges of kept
 * faces, and the vertices when any face is kept, stay on the grid: the encoder chooses the methods,
 * marks what a kept face touches, and chooses again on the edges made anew; a face newly kept in
 * that round marks its edges in the next.  The rounds are few (encode_pass stops after the fourth,
 * with every edge on the grid).
 */
int enc_keep_fine_edges(const loaded_model *lm, tx *t, int all)
{
    const cmesh *cm = &lm->mesh;
    if (!t->fine && !(t->fine = calloc((size_t)cm->nedges + 1, 1)))
        return 0; /* no memory: as it is (tx_free frees) */
    int changed = 0, kept = 0;
    for (int f = 0; f < cm->nfaces; f++) {
        if (!all && !enc_kept(t->method[f]))
            continue;
        kept = 1;
        const cmesh_face *cf = &cm->faces[f];
        for (int l = 0; l < cf->nloops; l++) {
            const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
            for (int i = 0; i < cl->n; i++) {
                int e = cm->uses[cl->first + i].edge;
                if (!t->fine[e] && t->edges[t->edge_tx[e]].step > 0) {
                    t->fine[e] = 1;
                    changed = 1;
                }
            }
        }
    }
    if (kept && t->vstep > 0 && !t->no_vstep) {
        t->no_vstep = 1;
        changed = 1;
    }
    return changed;
}
