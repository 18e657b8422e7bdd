/*
 * tx_arc.c - curves sent as the arcs they are (issue 14.4; format 4.4, docs/FORMAT.md, EDGE).
 *
 * A fifth of the corpus's bytes were circles: holes, the ends of fillets, bosses, each a rational
 * quadratic of 3 to 9 control points with its weights and double knots (asitus__Shelt_channel_5:
 * 8.7 of its 13.2 KB).  Its ends are the edge's vertices, which the terminal has; one point more, the
 * arc's middle, fixes it, and that point is sent as its offset from the chord's midpoint (the
 * arc's sagitta: one or two coordinates on an axis-aligned part).  The terminal builds the NURBS
 * (cm_arc_nurbs); the encoder builds the same one from the same grid numbers and sends the arc
 * only where it lies within the curves' share of the tolerance of the source curve, both ways,
 * and costs fewer bits.  Whatever the curve's source form: a polynomial approximation of a
 * circle becomes its arc as well.
 *
 * The middle point is the source curve's point as far from one end as from the other (found by
 * bisection: along an arc the two distances' difference changes sign once, where the arc crosses
 * the plane that bisects its chord), put on the largest step
 * the budget allows: the curves' share of the tolerance, and 4.4e-3 of the leg from an end to it,
 * so that the end tangents turn by at most half a degree (tx_coarsen.c's rule for a control
 * polygon's legs); on the grid itself when that step fails the check.
 *
 * A closed edge that is a full circle (a hole's rim, a boss) goes the same way with two points: the
 * one across from its vertex (the curve's farthest from it) and the one halfway to it (as far from
 * both, on the way), the terminal building both halves (cm_circle_nurbs): a few bytes where its
 * NURBS of 9 points took 30 to 45 (asitus__IAD_v3's 84 holes: 20 130 -> 18 455 bytes).
 *
 * An edge that stays on the grid (it bounds a kept face, whose surface meets it only as closely as
 * the source file made them: tx_coarsen.c, enc_keep_fine_edges) is sent as an arc only where the
 * arc through its middle point on the grid lies within FINE_STEPS grid steps of it: what its
 * control points on the grid would move it by, about.
 */
#include "encode_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_arc.h"

#define SHOULDER_ITERATIONS 60 /* bisection halvings of the parameter interval */
#define CHECK_SAMPLES 64       /* points of each curve tested against the other, at least */
#define SAMPLES_PER_SPAN 8     /* ... and in each knot span of a spline */
#define POLY_SEGMENTS 256      /* chords of the curve they are tested against, at least */
#define POLY_PER_SPAN 32       /* ... and in each knot span */
#define PROJECT_ITERATIONS 40  /* golden-section steps onto the curve about its nearest chord */
#define FINE_STEPS 2.0         /* grid steps: how far an edge that stays on the grid may move as an arc */
#define CHORD_BLOCK 16         /* chords boxed together, so that the nearest-chord scan skips far blocks */

static cm_vec3 grid_mm(const tx *t, const int64_t k[3])
{
    /* as the terminal's grid_point (cm_decode.c) */
    return cm_v3(t->origin[0] + t->q * (double)k[0], t->origin[1] + t->q * (double)k[1],
                 t->origin[2] + t->q * (double)k[2]);
}

static int eval_at(const cm_curve *c, double u, cm_vec3 *p)
{
    cm_status st;
    cm_status_init(&st);
    double a = c->knots[c->p], b = c->knots[c->n_ctrl];
    return cm_curve_eval(c, a + (b - a) * u, 0, p, &st) == CM_OK;
}

/* the parameter (on [0, hi] of the domain's [0,1]) of c's point as far from p0 as from p2 */
static int shoulder(const cm_curve *c, cm_vec3 p0, cm_vec3 p2, double hi, double *u)
{
    double lo = 0;
    for (int i = 0; i < SHOULDER_ITERATIONS; i++) {
        double mid = 0.5 * (lo + hi);
        cm_vec3 x;
        if (!eval_at(c, mid, &x))
            return 0;
        if (cm_norm2(cm_sub(x, p0)) < cm_norm2(cm_sub(x, p2)))
            lo = mid;
        else
            hi = mid;
    }
    *u = 0.5 * (lo + hi);
    return 1;
}

/* the knot spans of c that are not empty */
static int spans(const cm_curve *c)
{
    int k = 0;
    for (int i = c->p; i < c->n_ctrl; i++)
        k += c->knots[i + 1] > c->knots[i];
    return k;
}

/* the parameter (on [0,1] of the domain) of sample k of m, spread evenly over each non-empty knot
   span of c in turn (so that a short span, where a spline may hold a narrow feature, is looked at as
   closely as a long one) */
static double span_sample(const cm_curve *c, int k, int m)
{
    int ns = spans(c), seen = 0;
    double x = (double)k * ns / m, a = c->knots[c->p], b = c->knots[c->n_ctrl];
    int span = (int)x < ns ? (int)x : ns - 1;
    for (int i = c->p; i < c->n_ctrl; i++)
        if (c->knots[i + 1] > c->knots[i] && seen++ == span) {
            double f = x - span;
            return (c->knots[i] + (c->knots[i + 1] - c->knots[i]) * (f > 1 ? 1 : f) - a) / (b - a);
        }
    return 1.0;
}

/* the distance from x to chord i, poly[i] -> poly[i + 1] */
static double chord_dist(const cm_vec3 *poly, int i, cm_vec3 x)
{
    cm_vec3 s = cm_sub(poly[i + 1], poly[i]);
    double L = cm_norm2(s), f = L > 0 ? cm_dot(cm_sub(x, poly[i]), s) / L : 0.0;
    f = f < 0 ? 0 : (f > 1 ? 1 : f);
    return cm_dist(x, cm_add(poly[i], cm_scale(s, f)));
}

/* the largest distance from the samples of a (SAMPLES_PER_SPAN in each of its knot spans, at least
   CHECK_SAMPLES) to curve b, found about b's nearest chord (of POLY_PER_SPAN a span, at least
   POLY_SEGMENTS) by golden-section search; HUGE_VAL when either does not evaluate.  The caller asks
   only whether it is within `limit`, so it stops at the first sample farther than that, and a
   sample's search as soon as the sample is within it: the value is within `limit` exactly when the
   full searches' would be (a search's best only falls), and says no more */
static double one_way(const cm_curve *a, const cm_curve *b, double limit)
{
    int na = spans(a) * SAMPLES_PER_SPAN, nb = spans(b) * POLY_PER_SPAN;
    na = na < CHECK_SAMPLES ? CHECK_SAMPLES : na;
    nb = nb < POLY_SEGMENTS ? POLY_SEGMENTS : nb;
    int nblk = (nb + CHORD_BLOCK - 1) / CHORD_BLOCK;
    cm_vec3 *poly = malloc((size_t)(nb + 1) * sizeof *poly), *box = malloc((size_t)nblk * 2 * sizeof *box);
    double *up = malloc((size_t)(nb + 1) * sizeof *up), worst = 0;
    int prev_near = 0;
    if (!poly || !up || !box)
        worst = HUGE_VAL;
    for (int i = 0; i <= nb && worst == 0; i++) {
        up[i] = i == nb ? 1.0 : span_sample(b, i, nb);
        if (!eval_at(b, up[i], &poly[i]))
            worst = HUGE_VAL;
    }
    /* each block's box: its chords' ends */
    for (int g = 0; g < nblk && worst == 0; g++) {
        cm_vec3 lo = poly[g * CHORD_BLOCK], hi = lo;
        for (int i = g * CHORD_BLOCK + 1; i <= (g + 1) * CHORD_BLOCK && i <= nb; i++) {
            lo = cm_v3(fmin(lo.x, poly[i].x), fmin(lo.y, poly[i].y), fmin(lo.z, poly[i].z));
            hi = cm_v3(fmax(hi.x, poly[i].x), fmax(hi.y, poly[i].y), fmax(hi.z, poly[i].z));
        }
        box[2 * g] = lo;
        box[2 * g + 1] = hi;
    }
    for (int k = 0; k <= na && worst < HUGE_VAL; k++) {
        cm_vec3 x;
        if (!eval_at(a, k == na ? 1.0 : span_sample(a, k, na), &x)) {
            worst = HUGE_VAL;
            break;
        }
        /* the chord nearest the last sample first (the samples run along the curve), so that far
           blocks are skipped from the start; the first of equals still wins, as in a plain scan */
        double nearest = chord_dist(poly, prev_near, x);
        int near = prev_near;
        if (!(nearest <= HUGE_VAL)) { /* (a NaN: as a plain scan starts) */
            nearest = HUGE_VAL;
            near = 0;
        }
        for (int i = 0; i < nb; i++) {
            if (i % CHORD_BLOCK == 0) {
                /* a block whose box is farther than the nearest chord so far (with room for the
                   roundings) holds no chord nearer: skipped, the same chord found */
                cm_vec3 lo = box[2 * (i / CHORD_BLOCK)], hi = box[2 * (i / CHORD_BLOCK) + 1];
                double dx = fmax(0.0, fmax(lo.x - x.x, x.x - hi.x)), dy = fmax(0.0, fmax(lo.y - x.y, x.y - hi.y)),
                       dz = fmax(0.0, fmax(lo.z - x.z, x.z - hi.z));
                if (dx * dx + dy * dy + dz * dz > nearest * nearest * (1.0 + 1e-9)) {
                    i += CHORD_BLOCK - 1;
                    continue;
                }
            }
            double d = chord_dist(poly, i, x);
            if (d < nearest || (d == nearest && i < near)) {
                nearest = d;
                near = i;
            }
        }
        prev_near = near;
        /* the chords only say where: the distance is to the curve itself, about the nearest chord
           (chords cut corners, so a chord's distance may be less than the curve's) */
        double lo = up[near > 0 ? near - 1 : 0], hi = up[near + 2 < nb ? near + 2 : nb];
        double best = fmin(cm_dist(x, poly[near]), cm_dist(x, poly[near + 1]));
        /* best only falls: once it is within the limit this sample passes, and the search stops
           (where an arc fits its curve, the nearest chord's ends are within it already: the
           searches took a sixth of Shelt_channel_5's encode when they stopped only within the
           worst so far, a fifth before that) */
        for (int it = 0; it < PROJECT_ITERATIONS && !(best <= limit); it++) {
            double m1 = hi - 0.6180339887498949 * (hi - lo), m2 = lo + 0.6180339887498949 * (hi - lo);
            cm_vec3 y1, y2;
            if (!eval_at(b, m1, &y1) || !eval_at(b, m2, &y2)) {
                best = HUGE_VAL;
                break;
            }
            double d1 = cm_dist(x, y1), d2 = cm_dist(x, y2);
            best = fmin(best, fmin(d1, d2));
            if (d1 < d2)
                hi = m2;
            else
                lo = m1;
        }
        worst = fmax(worst, best);
        if (worst > limit)
            break; /* the caller asks only whether it is within limit */
    }
    free(poly);
    free(box);
    free(up);
    return worst;
}

/* the parameter (on [0,1]) of c's point farthest from p (`far`) or nearest to it: the best of 257
   samples, then refined about it by golden-section search */
static int extreme(const cm_curve *c, cm_vec3 p, int far, double *u)
{
    double best = HUGE_VAL, at = 0, sign = far ? -1.0 : 1.0;
    for (int i = 0; i <= POLY_SEGMENTS; i++) {
        cm_vec3 x;
        if (!eval_at(c, (double)i / POLY_SEGMENTS, &x))
            return 0;
        if (sign * cm_norm2(cm_sub(x, p)) < best) {
            best = sign * cm_norm2(cm_sub(x, p));
            at = (double)i / POLY_SEGMENTS;
        }
    }
    double lo = fmax(0.0, at - 1.0 / POLY_SEGMENTS), hi = fmin(1.0, at + 1.0 / POLY_SEGMENTS);
    for (int it = 0; it < PROJECT_ITERATIONS; it++) {
        double m1 = hi - 0.6180339887498949 * (hi - lo), m2 = lo + 0.6180339887498949 * (hi - lo);
        cm_vec3 y1, y2;
        if (!eval_at(c, m1, &y1) || !eval_at(c, m2, &y2))
            return 0;
        if (sign * cm_norm2(cm_sub(y1, p)) < sign * cm_norm2(cm_sub(y2, p)))
            hi = m2;
        else
            lo = m1;
    }
    *u = 0.5 * (lo + hi);
    return 1;
}

/* g as its prediction plus a multiple of 2^s, nearest to g; 0 when beyond what the terminal takes */
static int on_step(const int64_t g[3], const int64_t pred[3], int s, int64_t out[3])
{
    int inside = 1;
    for (int k = 0; k < 3; k++) {
        out[k] = pred[k] + tx_div_step(g[k] - pred[k], s) * ((int64_t)1 << s);
        inside &= out[k] <= CM_FMT_COORD_MAX && out[k] >= -CM_FMT_COORD_MAX;
    }
    return inside;
}

/* the points that fix the arc of src from p0 to p2 (closed: round to p0), in mm: an arc's middle
   point q; a circle's far point q and the point r halfway to it (r = p0 for an arc) */
static int arc_points(const cm_curve *src, cm_vec3 p0, cm_vec3 p2, int closed, cm_vec3 *q, cm_vec3 *r)
{
    double uq;
    *r = p0;
    if (!closed)
        return shoulder(src, p0, p2, 1.0, &uq) && eval_at(src, uq, q);
    if (!extreme(src, p0, 1, &uq) || !eval_at(src, uq, q))
        return 0;
    /* the point as far from the vertex as from q, on the way to q */
    double ur;
    return shoulder(src, p0, *q, uq, &ur) && eval_at(src, ur, r);
}

#define KINK_COS 0.99996192306417131 /* cos 0.5 deg */

/* the cosine of the turn at control point b between legs a-b and b-c (the curve's tangents there) */
static double joint_cos(cm_vec3 a, cm_vec3 b, cm_vec3 c)
{
    cm_vec3 u = cm_sub(b, a), v = cm_sub(c, b);
    double d = cm_norm(u) * cm_norm(v);
    return d > 0 ? cm_dot(u, v) / d : -1.0;
}

/* an arc as the terminal builds it */
typedef struct built_arc {
    cm_vec3 P[CM_ARC_MAX_CTRL];
    double W[CM_ARC_MAX_CTRL], K[CM_ARC_MAX_KNOTS];
    int n;
} built_arc;

/* the arc of src through the grid points k0, k2 (closed: k0 round to k0) and the points q, r (mm)
   on step s about their predictions (the chord's midpoint; a circle's vertex, then the midpoint of
   it and the far point): 1 when the terminal builds it (in *b; qk, rk its points) with at most
   max_ctrl points, within tol of src both ways */
static int fit_arc(const tx *t, const cm_curve *src, const int64_t k0[3], const int64_t k2[3], int closed, cm_vec3 q,
                   cm_vec3 r, int s, double tol, int max_ctrl, int64_t qk[3], int64_t rk[3], built_arc *b)
{
    int64_t qg[3], rg[3], qpred[3], rpred[3];
    if (!tx_quantise(t, q, qg) || !tx_quantise(t, r, rg))
        return 0;
    for (int k = 0; k < 3; k++)
        qpred[k] = closed ? k0[k] : cm_pred_arc_mid(k0[k], k2[k]);
    int inside = on_step(qg, qpred, s, qk);
    for (int k = 0; k < 3; k++) {
        rpred[k] = cm_pred_arc_mid(k0[k], qk[k]);
        rk[k] = 0;
    }
    inside &= !closed || on_step(rg, rpred, s, rk);
    cm_status st;
    cm_status_init(&st);
    cm_vec3 p0 = grid_mm(t, k0), p2 = grid_mm(t, k2);
    if (!inside ||
        cm_arc_record(closed, p0, grid_mm(t, closed ? rk : qk), closed ? grid_mm(t, qk) : p2, b->P, b->W, b->K, &b->n,
                      &st) != CM_OK ||
        b->n > max_ctrl)
        return 0;
    /* a circle's halves are two conics: with the middle point a step off the circle they meet at an
       angle (about twice the step over the radius), held to the half degree a control polygon's
       legs are (tx_coarsen.c) */
    if (closed && !(joint_cos(b->P[3], b->P[4], b->P[5]) >= KINK_COS && joint_cos(b->P[7], b->P[0], b->P[1]) >= KINK_COS))
        return 0;
    cm_curve arc = {2, b->n, b->K, b->P, b->W};
    return one_way(src, &arc, tol) <= tol && one_way(&arc, src, tol) <= tol;
}

int tx_arc_edge(const tx *t, const hcurve *c, int fine, tx_edge *A)
{
    if (!t->o || !enc_arcs(t->o) || !t->o->budget_steps || c->n < 3)
        return 0;
    int closed = A->v0 == A->v1;
    const int64_t *k0 = t->vq[A->v0], *k2 = t->vq[A->v1];
    cm_curve src = hcurve_view(c);
    double tol = fine ? FINE_STEPS * t->q : ENC_CURVE_SHARE * curve_face_tol(t, c);
    cm_vec3 p0 = grid_mm(t, k0), p2 = grid_mm(t, k2), q, r;
    if (!arc_points(&src, p0, p2, closed, &q, &r))
        return 0;
    /* a target board takes the curve the arc builds, or the arc is not sent (fit_board.c) */
    const cm_limit_info *L = t->o->target;
    int max_ctrl = !L ? CM_ARC_MAX_CTRL : (2 <= (int)L[CM_LIMIT_MAX_DEGREE].value ? (int)L[CM_LIMIT_MAX_EDGE_CTRL].value : 0);
    double leg = closed ? fmin(cm_dist(r, p0), cm_dist(r, q)) : fmin(cm_dist(q, p0), cm_dist(q, p2));
    for (int s = fine ? 0 : tx_choose_step(t, curve_face_tol(t, c), leg);; s = 0) {
        int64_t qk[3], rk[3];
        built_arc b;
        if (fit_arc(t, &src, k0, k2, closed, q, r, s, tol, max_ctrl, qk, rk, &b)) {
            A->kind = CM_EDGE_CURVE;
            A->arc = 1;
            A->p = 2;
            A->n = b.n;
            A->rational = 1;
            A->step = s;
            A->linear = 0;
            memcpy(A->qa, qk, sizeof A->qa);
            memcpy(A->ra, rk, sizeof A->ra);
            return 1;
        }
        if (s == 0)
            return 0;
    }
}

/*
 * Kept surfaces in their own terms (issue 14.4; format 4.4, docs/FORMAT.md, SURF, "Ruled"): half of
 * the corpus's kept faces are cylinders and cones (IGES 192, 194, 120 of a line; STEP's cylindrical
 * and conical surfaces), each sent as a rational net of 9 x 2 points and their weights (gmsh__Block's
 * 45: 85 bytes each).  A surface linear in v whose two rows are arcs (or full circles), or linear in
 * u whose two columns are (o3dv__as1_pe_203's twelve half cylinders of revolution), is sent as
 * those two arcs, their points on the grid: the terminal builds each as an arc edge and rules the
 * surface between them.  Taken where both rows are arcs within two grid steps (kept nets stay on
 * the grid: tx_coarsen.c), of as many pieces, corresponding as the source's do (the second row's
 * point at each parameter within four grid steps of the source's at the parameter of the first
 * row's nearest point), and where it codes in fewer bits.
 */
#define RULED_CHECKS 32 /* parameters along the first row where the rows' correspondence is checked */

int tx_ruled_surface(const tx *t, const hsurf *s, tx_surf *S)
{
    /* the arcs along u (the net's rows are 2 points: linear in v) or along v */
    int along_v = s->p == 1 && s->nu == 2 && s->nv >= 3;
    if (!t->o || !enc_arcs(t->o) || !t->o->budget_steps || !(along_v || (s->q == 1 && s->nv == 2 && s->nu >= 3)))
        return 0;
    int na = along_v ? s->nv : s->nu; /* points along the arcs */
    cm_vec3 *rc = malloc((size_t)na * 2 * sizeof *rc);
    double *rw = malloc((size_t)na * 2 * sizeof *rw);
    int ok = rc && rw;
    cm_curve row[2];
    built_arc b[2];
    int64_t pt[2][3][3];
    int closed[2] = {0, 0};
    double tol = FINE_STEPS * t->q;
    const cm_limit_info *L = t->o->target;
    int max_ctrl = CM_ARC_MAX_CTRL;
    if (L)
        max_ctrl = 2 > (int)L[CM_LIMIT_MAX_DEGREE].value ? 0
                   : (int)fmin((double)L[CM_LIMIT_MAX_SURF_CTRL_DIR].value, (double)L[CM_LIMIT_MAX_SURF_CTRL].value / 2);
    for (int j = 0; j < 2 && ok; j++) {
        for (int i = 0; i < na; i++) {
            int at = along_v ? j * s->nv + i : i * 2 + j;
            rc[j * na + i] = s->ctrl[at];
            rw[j * na + i] = s->w ? s->w[at] : 1.0;
        }
        row[j] = along_v ? (cm_curve){s->q, na, s->V, rc + j * na, s->w ? rw + j * na : NULL}
                         : (cm_curve){s->p, na, s->U, rc + j * na, s->w ? rw + j * na : NULL};
        cm_vec3 e0, e1, q, r;
        int64_t qk[3], rk[3];
        ok = eval_at(&row[j], 0.0, &e0) && eval_at(&row[j], 1.0, &e1) && tx_quantise(t, e0, pt[j][0]) &&
             tx_quantise(t, e1, pt[j][1]);
        closed[j] = ok && memcmp(pt[j][0], pt[j][1], sizeof pt[j][0]) == 0;
        cm_vec3 p0 = grid_mm(t, pt[j][0]), p2 = grid_mm(t, pt[j][1]);
        ok = ok && arc_points(&row[j], p0, p2, closed[j], &q, &r) &&
             fit_arc(t, &row[j], pt[j][0], pt[j][1], closed[j], q, r, 0, tol, max_ctrl, qk, rk, &b[j]);
        if (ok && closed[j]) { /* a circle sends its far point, then the point halfway to it */
            memcpy(pt[j][1], qk, sizeof qk);
            memcpy(pt[j][2], rk, sizeof rk);
        } else if (ok) {
            memcpy(pt[j][2], qk, sizeof qk);
        }
    }
    ok = ok && closed[0] == closed[1] && b[0].n == b[1].n;
    /* the rows correspond as the source's do: the surface is the source's, not a twisted one */
    for (int k = 0; k <= RULED_CHECKS && ok; k++) {
        cm_curve a0 = {2, b[0].n, b[0].K, b[0].P, b[0].W}, a1 = {2, b[1].n, b[1].K, b[1].P, b[1].W};
        cm_vec3 x0, x1, y1;
        double u;
        ok = eval_at(&a0, (double)k / RULED_CHECKS, &x0) && eval_at(&a1, (double)k / RULED_CHECKS, &x1) &&
             extreme(&row[0], x0, 0, &u) && eval_at(&row[1], u, &y1) && cm_dist(x1, y1) <= 2.0 * tol;
    }
    free(rc);
    free(rw);
    if (!ok)
        return 0;
    S->ruled = 1;
    S->ruled_closed = closed[0];
    S->ruled_along_v = along_v;
    memcpy(S->rp, pt, sizeof S->rp);
    return 1;
}
