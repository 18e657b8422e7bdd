/* verify.c - spec §12 error evaluation and §13 G1 verification (see verify.h). */
#include "verify.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_const.h"
#include "cm/cm_geom.h"
#include "cm/cm_param.h"
#include "cm/cm_project.h"

/* fs->nurbs: a copy of s over arrays of its own (fs->nurbs_ctrl, fs->nurbs_num); 0 on out of memory
   or a surface of no size */
static int nurbs_copy(face_surface *fs, const cm_surf *s)
{
    if (s->p < 1 || s->q < 1 || s->nu < 1 || s->nv < 1 || !s->ctrl || !s->U || !s->V)
        return 0;
    size_t nc = (size_t)s->nu * (size_t)s->nv;
    size_t nU = (size_t)s->nu + (size_t)s->p + 1, nV = (size_t)s->nv + (size_t)s->q + 1;
    size_t nn = nU + nV + (s->w ? nc : 0);
    fs->nurbs_ctrl = malloc(nc * sizeof *fs->nurbs_ctrl);
    fs->nurbs_num = malloc(nn * sizeof *fs->nurbs_num);
    if (!fs->nurbs_ctrl || !fs->nurbs_num) {
        free(fs->nurbs_ctrl);
        free(fs->nurbs_num);
        fs->nurbs_ctrl = NULL;
        fs->nurbs_num = NULL;
        return 0;
    }
    memcpy(fs->nurbs_ctrl, s->ctrl, nc * sizeof *fs->nurbs_ctrl);
    memcpy(fs->nurbs_num, s->U, nU * sizeof *fs->nurbs_num);
    memcpy(fs->nurbs_num + nU, s->V, nV * sizeof *fs->nurbs_num);
    if (s->w)
        memcpy(fs->nurbs_num + nU + nV, s->w, nc * sizeof *fs->nurbs_num);
    fs->nurbs = *s;
    fs->nurbs.ctrl = fs->nurbs_ctrl;
    fs->nurbs.U = fs->nurbs_num;
    fs->nurbs.V = fs->nurbs_num + nU;
    fs->nurbs.w = s->w ? fs->nurbs_num + nU + nV : NULL;
    return 1;
}

int face_surface_set(face_surface *fs, const cm_rebuilt *rb)
{
    face_surface_free(fs);
    fs->rebuilt = 1;
    fs->repr = rb->repr;
    fs->bbox = rb->bbox;
    fs->frame = rb->frame;
    if (rb->repr == CM_REPR_PATCHES && rb->greg) {
        fs->greg = malloc(sizeof *fs->greg);
        if (!fs->greg)
            return 0;
        *fs->greg = *rb->greg;
    }
    /* NURBS: rb->surf's arrays are in the rebuild's workspace, which the next rebuild overwrites */
    if (rb->repr == CM_REPR_NURBS) {
        fs->sign = rb->sign;
        return nurbs_copy(fs, &rb->surf);
    }
    return 1;
}

void face_surface_free(face_surface *fs)
{
    free(fs->greg);
    fs->greg = NULL;
    free(fs->nurbs_ctrl);
    free(fs->nurbs_num);
    fs->nurbs_ctrl = NULL;
    fs->nurbs_num = NULL;
    memset(&fs->nurbs, 0, sizeof fs->nurbs);
    fs->sign = 0;
    fs->rebuilt = 0;
}

/* A PLANE face is the plane trimmed by its own boundary curves (the terminal tessellates it in the
   frame, cm_tessellate.c CHART_FRAME), not the method's bilinear rectangle: the distance is the
   height over the plane.  Clamped to the rectangle (the rectangle of the boundary samples, 1 %
   larger), a curved boundary bulging past it between samples counted its in-plane gap: exactly flat
   faces with arcs measured 0.8-0.9 % and were kept at --tol 0.001 (issue 14.7) */
static double dist_to_plane(const cm_frame *fr, cm_vec3 p)
{
    return fabs(cm_frame_local(fr, p).z);
}

static double clamp01(double t) { return t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t); }

/* Gauss-Newton on patch k from (u,v), clamped to the patch, step halved when it does not improve */
static double greg_local(const cm_greg_surface *s, int k, cm_vec3 p, double *u, double *v)
{
    cm_vec3 S, Su, Sv;
    cm_greg_surface_eval(s, k, *u, *v, &S, &Su, &Sv);
    double best = cm_dist(S, p);
    for (int it = 0; it < 30; it++) {
        cm_vec3 r = cm_sub(p, S);
        double a = cm_dot(Su, Su), b = cm_dot(Su, Sv), c = cm_dot(Sv, Sv);
        double gu = cm_dot(Su, r), gv = cm_dot(Sv, r), det = a * c - b * b;
        if (!(det > 1e-24 * a * c))
            break;
        double du = (c * gu - b * gv) / det, dv = (a * gv - b * gu) / det;
        int moved = 0;
        for (int h = 0; h < 8 && !moved; h++, du *= 0.5, dv *= 0.5) {
            double nu = clamp01(*u + du), nv = clamp01(*v + dv);
            cm_vec3 T, Tu, Tv;
            cm_greg_surface_eval(s, k, nu, nv, &T, &Tu, &Tv);
            double d = cm_dist(T, p);
            if (d < best) {
                moved = fabs(nu - *u) > 1e-13 || fabs(nv - *v) > 1e-13 ? 1 : 2;
                *u = nu;
                *v = nv;
                best = d;
                S = T;
                Su = Tu;
                Sv = Tv;
            }
        }
        if (moved != 1)
            break;
    }
    return best;
}

/* a search that remembers its last foot point: neighbouring queries start there */
typedef struct greg_walk {
    const cm_greg_surface *s;
    double accept;   /* a local answer at most this far is taken without a global search */
    int have, patch;
    double u, v;
    double again;    /* an answer farther than this is confirmed: a foot at rest inside a patch asks the
                        global search, and the global search's answer a dense one (0: never) */
} greg_walk;

/* samples per direction of each patch in the dense search that confirms a large distance */
#define CONFIRM_SAMPLES 48

/*
 * The nearest point of the patches to p from a 49 x 49 grid on each and a local walk from the best:
 * the global search (cm_greg_surface_project, 17 x 17) can settle in a local minimum.  On Pieza1's
 * GREGORY-FIT face 111 it answered 0.45 mm for a source point the encoder's walk had put 0.18 mm
 * from the face (a point 0.3 mm beside it is 0.009 mm from it), and `cmz eval` failed the file.
 */
static double greg_dense(const cm_greg_surface *s, cm_vec3 p, int *k, double *u, double *v)
{
    double best = HUGE_VAL;
    for (int q = 0; q < s->npatch; q++)
        for (int i = 0; i <= CONFIRM_SAMPLES; i++)
            for (int j = 0; j <= CONFIRM_SAMPLES; j++) {
                cm_vec3 S;
                double a = (double)i / CONFIRM_SAMPLES, b = (double)j / CONFIRM_SAMPLES;
                if (cm_greg_surface_eval(s, q, a, b, &S, NULL, NULL) != CM_OK)
                    continue;
                double d = cm_dist(S, p);
                if (d < best) {
                    best = d;
                    *k = q;
                    *u = a;
                    *v = b;
                }
            }
    if (best < HUGE_VAL) {
        double d = greg_local(s, *k, p, u, v);
        best = d < best ? d : best;
    }
    return best;
}

/*
 * greg_local, and across the internal curves of an N-split: patch k's side u = 1 is I_k, which is
 * patch k+1's side v = 1 (patch k at (1,t) is patch k+1 at (t,1)); a foot stopped there goes on in
 * the neighbour (cm_gregface.h gives the layout).  *inner: the foot came to rest strictly inside
 * a patch (a minimum of the distance there, not a stop against a side).
 */
static double greg_local_hop(const cm_greg_surface *s, int *k, cm_vec3 p, double *u, double *v, int *inner)
{
    double d = greg_local(s, *k, p, u, v);
    int split = s->layout == CM_GREG_LAYOUT_SPLIT && s->npatch > 1;
    for (int hop = 0; split && hop < 4; hop++) {
        int nk;
        double nu, nv;
        if (*u >= 1.0) {
            nk = (*k + 1) % s->npatch;
            nu = *v;
            nv = 1.0;
        } else if (*v >= 1.0) {
            nk = (*k + s->npatch - 1) % s->npatch;
            nu = 1.0;
            nv = *u;
        } else {
            break;
        }
        double d2 = greg_local(s, nk, p, &nu, &nv);
        if (!(d2 < d))
            break;
        d = d2;
        *k = nk;
        *u = nu;
        *v = nv;
    }
    /* at rest inside: away from the sides, and the residual orthogonal to both tangents (a walk
       stalled against a corner is neither) */
    cm_vec3 S, Su, Sv;
    cm_greg_surface_eval(s, *k, *u, *v, &S, &Su, &Sv);
    cm_vec3 r = cm_sub(p, S);
    double lr = cm_norm(r);
    *inner = *u > 1e-6 && *u < 1.0 - 1e-6 && *v > 1e-6 && *v < 1.0 - 1e-6 &&
             fabs(cm_dot(r, Su)) <= 1e-6 * lr * cm_norm(Su) && fabs(cm_dot(r, Sv)) <= 1e-6 * lr * cm_norm(Sv);
    return d;
}

static double greg_dist(greg_walk *w, cm_vec3 p)
{
    double d = HUGE_VAL;
    if (w->have) {
        double u = w->u, v = w->v;
        int k = w->patch, inner;
        d = greg_local_hop(w->s, &k, p, &u, &v, &inner);
        /* a local foot is a point of the surface, so its distance is never below the true one: it
           is taken when small, or when it came to rest inside a patch (a minimum there) unless it
           is far enough to matter (a local minimum is not the nearest point: Pieza1's face 111 read
           0.45 mm so where the global search finds 0.18 mm); a foot stopped against a side with a
           large distance asks the global search */
        if (d <= w->accept || (inner && !(w->again > 0 && d > w->again))) {
            w->patch = k;
            w->u = u;
            w->v = v;
            return d;
        }
    }
    int k;
    double u, v, g = cm_greg_surface_project(w->s, p, &k, &u, &v);
    if (g < d) {
        d = g;
        w->patch = k;
        w->u = u;
        w->v = v;
        w->have = 1;
    }
    if (w->again > 0 && d > w->again && (g = greg_dense(w->s, p, &k, &u, &v)) < d) {
        d = g;
        w->patch = k;
        w->u = u;
        w->v = v;
        w->have = 1;
    }
    return d;
}

double verify_patch_foot(const cm_greg_surface *s, double accept, cm_vec3 p, int *have, int *k, double *u, double *v)
{
    greg_walk w = {s, accept, *have, *k, *u, *v, 0};
    double d = greg_dist(&w, p);
    *have = w.have;
    *k = w.patch;
    *u = w.u;
    *v = w.v;
    return d;
}

/*
 * The NURBS counterpart of greg_walk: the foot of a point walked from the previous point's by
 * cm_psurf_project_from over the surface's whole domain (parameters clamped), taken when within
 * `accept` or at rest inside the domain (a minimum there); else the K9 projection cm_patch_project,
 * and the nearer of the two.
 */
typedef struct surf_walk {
    cm_psurf ps;    /* the surface over its domain, neither direction closed */
    cm_patch patch; /* the same for the K9 search (points at the caller's cm_surf) */
    double accept;
    int have;
    double u, v;
} surf_walk;

static void surf_walk_init(surf_walk *w, const cm_surf *s, double accept)
{
    memset(w, 0, sizeof *w);
    w->ps.s = *s;
    w->ps.u0 = s->U[s->p];
    w->ps.u1 = s->U[s->nu];
    w->ps.v0 = s->V[s->q];
    w->ps.v1 = s->V[s->nv];
    w->patch = cm_patch_of_surf(s);
    w->accept = accept;
}

static double surf_dist(surf_walk *w, cm_vec3 p)
{
    double d = HUGE_VAL;
    if (w->have) {
        double u = w->u, v = w->v, dl;
        cm_vec3 S[3];
        if (cm_psurf_project_from(&w->ps, p, &u, &v, &dl, NULL) == CM_OK &&
            cm_psurf_eval(&w->ps, u, v, S, NULL) == CM_OK) {
            /* at rest inside: away from the domain's sides, the residual orthogonal to both tangents */
            const cm_psurf *ps = &w->ps;
            double eu = 1e-6 * (ps->u1 - ps->u0), ev = 1e-6 * (ps->v1 - ps->v0);
            cm_vec3 r = cm_sub(p, S[0]);
            double lr = cm_norm(r);
            int inner = u > ps->u0 + eu && u < ps->u1 - eu && v > ps->v0 + ev && v < ps->v1 - ev &&
                        fabs(cm_dot(r, S[1])) <= 1e-6 * lr * cm_norm(S[1]) &&
                        fabs(cm_dot(r, S[2])) <= 1e-6 * lr * cm_norm(S[2]);
            w->u = u;
            w->v = v;
            if (dl <= w->accept || inner)
                return dl;
            d = dl;
        }
    }
    double u, v, g;
    if (cm_patch_project(&w->patch, p, &u, &v, &g, NULL) == CM_OK && g < d) {
        d = g;
        w->u = u;
        w->v = v;
        w->have = 1;
    }
    return d;
}

double verify_surf_foot(const cm_surf *s, double accept, cm_vec3 p, int *have, double *u, double *v)
{
    surf_walk w;
    surf_walk_init(&w, s, accept);
    w.have = *have;
    w.u = *u;
    w.v = *v;
    double d = surf_dist(&w, p);
    *have = w.have;
    *u = w.u;
    *v = w.v;
    return d;
}

static double face_dist(const cm_rebuilt *rb, greg_walk *w, surf_walk *sw, cm_vec3 p)
{
    if (rb->repr == CM_REPR_NURBS)
        return surf_dist(sw, p);
    return rb->repr == CM_REPR_PATCHES ? greg_dist(w, p) : dist_to_plane(&rb->frame, p);
}

/* points of the source grid kept for the other direction (spec §12 grid: 21 x 21 at most) */
typedef struct grid_pts {
    cm_vec2 uv[21 * 21];
    cm_vec3 xyz[21 * 21];
    int n;
} grid_pts;

void verify_nearest_boundary(const face_domain *fd, cm_vec3 p, double *best2, cm_vec2 *uv)
{
    for (int q = 0; q < fd->npts; q++) {
        double dq = cm_finite3(fd->xyz[q]) ? cm_norm2(cm_sub(fd->xyz[q], p)) : HUGE_VAL;
        if (dq < *best2) {
            *best2 = dq;
            *uv = fd->uv[q];
        }
    }
}

/*
 * The other direction, past spec §12 (which measures the source against the rebuilt surface only):
 * each patch at the 5 x 5 points (i/6, j/6), i, j = 1..5, projected on the source surface from the
 * nearest source point seen (grid or boundary).  A patch that bulges or folds where no source point
 * is near it passes §12 and shows wrongly; it fails here.  Returns the largest distance.
 */
/* the distance of S from the source surface, the foot started from the nearest grid or boundary
   point (HUGE_VAL where it cannot be had) */
/* S's distance to the boundary curves of face fd (the nearest point of a trimmed face to a point
   whose foot lies outside it is on its boundary) */
static double boundary_dist(const brep_model *m, const face_domain *fd, cm_vec3 S)
{
    const brep_face *F = &m->faces[fd->face];
    double best = HUGE_VAL;
    for (int l = 0; l < F->nloops; l++) {
        const brep_loop *L = &m->loops[F->first_loop + l];
        for (int k = 0; k < L->n; k++) {
            const hcurve *c = &m->segs[L->first + k];
            cm_curve cv = hcurve_view(c);
            double t0, t1, t, d;
            hcurve_domain(c, &t0, &t1);
            if (cm_curve_project(&cv, t0, t1, S, &t, &d, NULL) == CM_OK && d < best)
                best = d;
        }
    }
    return best;
}

/* 1 if (u, v) or its copy a period away lies in the face */
static int foot_inside(const face_domain *fd, double u, double v)
{
    double pu = fd->ps.u1 - fd->ps.u0, pv = fd->ps.v1 - fd->ps.v0;
    for (int i = -1; i <= 1; i++)
        for (int j = -1; j <= 1; j++) {
            if ((i && !fd->ps.closed_u) || (j && !fd->ps.closed_v))
                continue;
            if (face_domain_inside(fd, cm_v2(u + i * pu, v + j * pv)))
                return 1;
        }
    return 0;
}

static double point_to_source(const brep_model *m, const face_domain *fd, const grid_pts *g, cm_vec3 S, double again,
                              int trimmed)
{
    double best = HUGE_VAL, u = 0, v = 0, d;
    for (int q = 0; q < g->n; q++) {
        double dq = cm_norm2(cm_sub(g->xyz[q], S));
        if (dq < best) {
            best = dq;
            u = g->uv[q].x;
            v = g->uv[q].y;
        }
    }
    cm_vec2 uv = cm_v2(u, v);
    verify_nearest_boundary(fd, S, &best, &uv);
    u = uv.x;
    v = uv.y;
    if (!(best < HUGE_VAL) || cm_psurf_project_from(&fd->ps, S, &u, &v, &d, NULL) != CM_OK)
        return HUGE_VAL;
    double dg, ug, vg;
    /* a foot stuck in a local minimum only overstates the distance: search again */
    if (!(d < again) && face_domain_project_global(fd, S, &ug, &vg, &dg) == CM_OK && dg < d) {
        d = dg;
        u = ug;
        v = vg;
    }
    /* `trimmed` (a point that is shown: a mesh vertex, a Gregory patch's point, the patches being
       bounded by the face's own edges): the face, not its whole surface.  A point off the face's
       region (a patch hanging past a short side, gmsh__Block's seven-sided cylinder face: 0.02 mm off
       the cylinder, 0.27 mm off the face) is as far as the face's boundary.  (A G1FIT net is cut by
       the face's loop when shown: for its points the surface.) */
    if (trimmed && !foot_inside(fd, u, v)) {
        double db = boundary_dist(m, fd, S);
        d = db < HUGE_VAL && db > d ? db : d;
    }
    return d;
}

static double patches_to_source(const brep_model *m, const face_domain *fd, const cm_greg_surface *gs,
                                const grid_pts *g, double again)
{
    double worst = 0;
    for (int k = 0; k < gs->npatch; k++)
        for (int i = 1; i <= 5; i++)
            for (int j = 1; j <= 5; j++) {
                cm_vec3 S;
                if (cm_greg_surface_eval(gs, k, i / 6.0, j / 6.0, &S, NULL, NULL) != CM_OK)
                    return HUGE_VAL;
                double d = point_to_source(m, fd, g, S, again, 1); /* all of a patch is shown */
                worst = d > worst ? d : worst;
            }
    return worst;
}

/*
 * The exact patches beside each joint of a side made of several edges (layout 3's CHAIN sides).  A
 * patch blends its sides' cross derivatives straight across it, and a chain's derivative is each
 * edge's own, so where two edges meet at an angle (layout 3 takes such sides where the N-split
 * failed) or with different cross bases, the patch jumps along the line through the joint: a tear
 * in the surface whose size steps 4's grid and the 21 x 21 grid see only where a point happens to
 * fall beside it.  gmsh__Block's seven-sided faces (a notch of two arcs meeting the cylinder's
 * straight side at 38 degrees) jumped 0.28 mm there and measured 0.0965 mm off the cylinder just
 * before the joint, past the 0.084 mm tolerance, where the grids found 0.081 (with format 4.13's
 * hints and a GREGORY-FIT correction, since taken out); tail_section_asm's face 19, 0.079 mm on the
 * grids, runs 1.16 mm past its boundary beside its joint (tolerance 0.83).  Measured here on
 * both sides of each joint's line (a hair from it: the side evaluates the edge before or after),
 * CREASE_N + 1 points along each.
 */
#define CREASE_N 40
#define CREASE_HAIR 1e-9
static double creases_to_source(const brep_model *m, const face_domain *fd, const cm_greg_surface *gs,
                                const grid_pts *g, double again, double tol)
{
    double worst = 0;
    for (int k = 0; gs->exact && k < gs->npatch; k++)
        for (int sd = 0; sd < 4; sd++) {
            const cm_egreg_side *side = &gs->e[k].side[sd];
            for (int p = 0; side->kind == CM_EGREG_SIDE_CHAIN && p + 1 < side->npiece; p++)
                for (int h = -1; h <= 1; h += 2) {
                    /* sides 0 and 2 run with u, 1 and 3 with v; 2 and 3 backwards (cm_egreg_eval) */
                    double s = side->piece[p].s1 + h * CREASE_HAIR, across = sd >= 2 ? 1.0 - s : s;
                    for (int i = 0; i <= CREASE_N; i++) {
                        double t = (double)i / CREASE_N;
                        cm_vec3 S;
                        if (cm_greg_surface_eval(gs, k, sd % 2 ? t : across, sd % 2 ? across : t, &S, NULL, NULL) !=
                            CM_OK)
                            return HUGE_VAL;
                        double d = point_to_source(m, fd, g, S, again, 1);
                        worst = d > worst ? d : worst;
                        if (!(worst < tol))
                            return worst; /* failed: the rest cannot save it */
                    }
                }
        }
    return worst;
}

/* a G1FIT net against the source surface: the whole net is the face (its loop is the border), so
   every point of it must lie near the source (the grid of step 2 only measures the other way).
   On a 41 x 41 grid of its parameters: at 11 x 11 (and at 21 x 21) a 150 mm G1FIT face of
   geo_example measured 0.178 mm where Open CASCADE found the decoded face 0.325 mm off its B-rep,
   past the 0.199 mm tolerance (1e-3 of the diagonal): a narrow ridge between the samples */
#define NET_SAMPLES 40
static double net_to_source(const brep_model *m, const face_domain *fd, const cm_surf *s, const grid_pts *g,
                            double again, double tol)
{
    double worst = 0;
    for (int i = 0; i <= NET_SAMPLES; i++)
        for (int j = 0; j <= NET_SAMPLES; j++) {
            cm_vec3 D[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
            if (cm_surf_eval(s, (double)i / NET_SAMPLES, (double)j / NET_SAMPLES, 0, D, NULL) != CM_OK)
                return HUGE_VAL;
            double d = point_to_source(m, fd, g, D[0][0], again, 0);
            worst = d > worst ? d : worst;
            if (!(worst < tol))
                return worst; /* failed: the rest cannot save it */
        }
    return worst;
}

int verify_face(const loaded_model *lm, const cm_model *m, int f, const cm_rebuilt *rb, double tol, face_error *out)
{
    memset(out, 0, sizeof *out);
    const face_domain *fd = &lm->fds[lm->mesh.faces[f].brep_face];
    if (!fd->uv || (rb->repr == CM_REPR_PATCHES && !rb->greg) ||
        (rb->repr == CM_REPR_NURBS && !(rb->surf.ctrl && rb->surf.U && rb->surf.V)))
        return 0;
    /* a walk's local answer is a distance to a point of the surface, so never below the true one:
       one within a tenth of the tolerance cannot change the verdict and needs no global search */
    greg_walk w = {rb->greg, tol < HUGE_VAL ? 0.1 * tol : 1e-4 * rb->bbox, 0, 0, 0, 0,
                   tol < HUGE_VAL ? tol : 1e-3 * rb->bbox};
    surf_walk sw;
    if (rb->repr == CM_REPR_NURBS)
        surf_walk_init(&sw, &rb->surf, w.accept);
    else
        memset(&sw, 0, sizeof sw);
    double sum = 0, worst = 0;
    int n = 0;
    grid_pts *grid = malloc(sizeof *grid); /* (encodes may run in parallel threads: not static) */
    if (!grid)
        return 0;
    grid->n = 0;
    /* 1-2: the source surface on the 21 x 21 grid, points inside the outer loop, row by row in a
       serpentine so that each point starts from its neighbour's foot */
    for (int i = 0; i <= 20; i++) {
        for (int jj = 0; jj <= 20; jj++) {
            int j = i % 2 ? 20 - jj : jj;
            cm_vec2 uv = cm_v2(fd->umin + (fd->umax - fd->umin) * i / 20.0, fd->vmin + (fd->vmax - fd->vmin) * j / 20.0);
            if (!cm_point_in_polygon(fd->uv + fd->loops[0].first, fd->loops[0].n, uv))
                continue;
            cm_vec3 P;
            if (face_domain_eval(&lm->brep, fd, uv.x, uv.y, &P, NULL, NULL) != CM_OK) {
                free(grid);
                return 0;
            }
            double d = face_dist(rb, &w, &sw, P);
            grid->uv[grid->n] = uv;
            grid->xyz[grid->n++] = P;
            sum += d;
            worst = d > worst ? d : worst;
            n++;
            if (!(worst < tol))
                goto done; /* failed: the rest cannot save it */
        }
    }
    out->grid_points = n;
    /* 3: the boundary, every edge use of every loop at t = k/20 */
    const cm_face *F = &m->faces[f];
    for (uint32_t l = 0; l < F->nloops; l++) {
        const cm_loop *L = &m->loops[F->loop0 + l];
        w.have = 0; /* a loop starts with a global search, then walks along it */
        sw.have = 0;
        for (uint32_t u = 0; u < L->nuse; u++) {
            const cm_use *U = &m->uses[L->use0 + u];
            cm_curve c;
            cm_model_edge_curve(m, U->edge, &c);
            for (int k = 0; k <= 20; k++) {
                cm_vec3 d3[1];
                if (cm_curve_eval(&c, U->rev ? 1.0 - k / 20.0 : k / 20.0, 0, d3, NULL) != CM_OK) {
                    free(grid);
                    return 0;
                }
                double d = face_dist(rb, &w, &sw, d3[0]);
                sum += d;
                worst = d > worst ? d : worst;
                n++;
                out->boundary_points++;
                if (!(worst < tol))
                    goto done;
            }
        }
    }
    /* 4: the patches against the source surface (see patches_to_source).  Not a NURBS surface: it
       extends past the face (NFILL's rectangle contains it), so only its points inside the face's
       trimmed region would mean anything, and telling those apart needs the loops projected on it */
    if (rb->repr == CM_REPR_PATCHES) {
        double again = tol < HUGE_VAL ? 0.5 * tol : 5e-3 * rb->bbox;
        double back = patches_to_source(&lm->brep, fd, rb->greg, grid, again);
        double crease = creases_to_source(&lm->brep, fd, rb->greg, grid, again, tol);
        back = crease > back ? crease : back;
        out->back = back;
        worst = back > worst ? back : worst;
    } else if (rb->method == CM_METHOD_G1FIT) {
        double back = net_to_source(&lm->brep, fd, &rb->surf, grid, tol < HUGE_VAL ? 0.5 * tol : 5e-3 * rb->bbox, tol);
        out->back = back;
        worst = back > worst ? back : worst;
    }
done:
    out->complete = worst < tol;
    out->max = worst;
    out->avg = n > 0 ? sum / n : 0;
    out->ratio = rb->bbox > 0 ? worst / rb->bbox : 0;
    out->bbox = rb->bbox;
    free(grid);
    return 1;
}

/* ---- the decoded mesh against the source (issue 14.6) ---- */

/* distance from p to the triangle abc: the nearest point by the region of the triangle's plane that
   p falls in (a corner, a side or the inside) */
static double point_triangle_dist(cm_vec3 p, cm_vec3 a, cm_vec3 b, cm_vec3 c)
{
    cm_vec3 ab = cm_sub(b, a), ac = cm_sub(c, a), ap = cm_sub(p, a);
    double d1 = cm_dot(ab, ap), d2 = cm_dot(ac, ap);
    if (d1 <= 0 && d2 <= 0)
        return cm_norm(ap); /* corner a */
    cm_vec3 bp = cm_sub(p, b);
    double d3 = cm_dot(ab, bp), d4 = cm_dot(ac, bp);
    if (d3 >= 0 && d4 <= d3)
        return cm_norm(bp); /* corner b */
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) /* side ab */
        return cm_norm(cm_sub(p, cm_add(a, cm_scale(ab, d1 / (d1 - d3)))));
    cm_vec3 cp = cm_sub(p, c);
    double d5 = cm_dot(ab, cp), d6 = cm_dot(ac, cp);
    if (d6 >= 0 && d5 <= d6)
        return cm_norm(cp); /* corner c */
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) /* side ac */
        return cm_norm(cm_sub(p, cm_add(a, cm_scale(ac, d2 / (d2 - d6)))));
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) /* side bc */
        return cm_norm(cm_sub(p, cm_add(b, cm_scale(cm_sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))))));
    double den = va + vb + vc;
    if (!(fabs(den) > 0)) /* a flat triangle: its sides decide */
        return fmin(fmin(cm_norm(ap), cm_norm(bp)), cm_norm(cp));
    double v = vb / den, w = vc / den; /* inside */
    return cm_norm(cm_sub(p, cm_add(a, cm_add(cm_scale(ab, v), cm_scale(ac, w)))));
}

static cm_vec3 mesh_pt(const float (*pos)[3], uint32_t i)
{
    return cm_v3((double)pos[i][0], (double)pos[i][1], (double)pos[i][2]);
}

/* the distance from p to the nearest triangle */
static double point_mesh_dist(cm_vec3 p, const float (*pos)[3], const uint32_t *idx, uint32_t nindex)
{
    double best = HUGE_VAL;
    for (uint32_t t = 0; t + 2 < nindex; t += 3) {
        double d = point_triangle_dist(p, mesh_pt(pos, idx[t]), mesh_pt(pos, idx[t + 1]), mesh_pt(pos, idx[t + 2]));
        best = d < best ? d : best;
    }
    return best;
}

double verify_mesh_face(const loaded_model *lm, int f, const float (*pos)[3], uint32_t nverts, const uint32_t *idx,
                        uint32_t nindex, double expect)
{
    const face_domain *fd = &lm->fds[lm->mesh.faces[f].brep_face];
    if (!fd->uv || nindex < 3)
        return -1.0;
    for (uint32_t k = 0; k < nindex; k++)
        if (idx[k] >= nverts)
            return -1.0;
    grid_pts *grid = malloc(sizeof *grid);
    if (!grid)
        return -1.0;
    grid->n = 0;
    double worst = 0;
    /* the source to the mesh: the grid inside the face, then the boundary samples */
    for (int i = 0; i <= 20; i++)
        for (int j = 0; j <= 20; j++) {
            cm_vec2 uv = cm_v2(fd->umin + (fd->umax - fd->umin) * i / 20.0, fd->vmin + (fd->vmax - fd->vmin) * j / 20.0);
            cm_vec3 P;
            if (!face_domain_inside(fd, uv) || face_domain_eval(&lm->brep, fd, uv.x, uv.y, &P, NULL, NULL) != CM_OK)
                continue;
            grid->uv[grid->n] = uv;
            grid->xyz[grid->n++] = P;
            double d = point_mesh_dist(P, pos, idx, nindex);
            worst = d > worst ? d : worst;
        }
    for (int q = 0; q < fd->npts; q++) {
        if (!cm_finite3(fd->xyz[q]))
            continue; /* (a joined winding polygon's points along the seam or a pole: no boundary
                         point; measured, the report said "inf" for every such face) */
        double d = point_mesh_dist(fd->xyz[q], pos, idx, nindex);
        worst = d > worst ? d : worst;
    }
    /* the mesh to the source: its vertices (a piece of mesh where the face is not, or off it; the
       chords' sag between them is what the other way sees) */
    /* a local foot farther than twice what is expected is searched for again over the whole
       surface (a foot stuck in a local minimum only overstates) */
    double again = 2.0 * expect;
    for (uint32_t k = 0; k < nverts; k++) {
        double d = point_to_source(&lm->brep, fd, grid, mesh_pt(pos, k), again, 1);
        if (d < HUGE_VAL) /* a foot that cannot be had is not a distance */
            worst = d > worst ? d : worst;
    }
    free(grid);
    return worst;
}

/* unit normal of face f's source surface near P, projected from the nearest boundary sample */
static int source_normal_at(const loaded_model *lm, int f, cm_vec3 P, cm_vec3 *n)
{
    const face_domain *D = &lm->fds[lm->mesh.faces[f].brep_face];
    if (!D->uv)
        return 0;
    int best = 0;
    double bd = HUGE_VAL;
    for (int i = 0; i < D->npts; i++) {
        double d = cm_finite3(D->xyz[i]) ? cm_norm2(cm_sub(D->xyz[i], P)) : HUGE_VAL;
        if (d < bd) {
            bd = d;
            best = i;
        }
    }
    double u = D->uv[best].x, v = D->uv[best].y, dist;
    cm_vec3 d3[3];
    if (cm_psurf_project_from(&D->ps, P, &u, &v, &dist, NULL) != CM_OK || cm_psurf_eval(&D->ps, u, v, d3, NULL) != CM_OK)
        return 0;
    cm_vec3 c = cm_cross(d3[1], d3[2]);
    if (!(cm_norm(c) > CM_EPS_CROSS_REL * cm_norm(d3[1]) * cm_norm(d3[2])) || !(cm_norm(c) > 0))
        return 0;
    *n = cm_unit(c);
    return 1;
}

int verify_source_normal(const loaded_model *lm, int f, cm_vec3 P, cm_vec3 *n)
{
    return source_normal_at(lm, f, P, n);
}

/* unit normal of face f's final surface near P (0 where it cannot be had); a Gregory face's foot
 * point is walked along from the previous point of the same edge (w), a NURBS face's too (sw) */
static int normal_at(const loaded_model *lm, int f, const face_surface *fs, greg_walk *w, surf_walk *sw, cm_vec3 P,
                     cm_vec3 *n)
{
    const face_surface *S = &fs[f];
    if (S->rebuilt && S->repr == CM_REPR_FRAME) {
        *n = S->frame.ez;
        return 1;
    }
    if (S->rebuilt && S->repr == CM_REPR_NURBS && S->nurbs_ctrl) {
        cm_vec3 d[3];
        if (!(surf_dist(sw, P) < HUGE_VAL) || cm_psurf_eval(&sw->ps, sw->u, sw->v, d, NULL) != CM_OK)
            return 0;
        cm_vec3 c = cm_cross(d[1], d[2]);
        if (!(cm_norm(c) > CM_EPS_CROSS_REL * cm_norm(d[1]) * cm_norm(d[2])) || !(cm_norm(c) > 0))
            return 0;
        *n = cm_scale(cm_unit(c), S->sign < 0 ? -1.0 : 1.0); /* the face normal is sign * (Su x Sv) */
        return 1;
    }
    if (!S->rebuilt || S->repr != CM_REPR_PATCHES || !S->greg)
        return source_normal_at(lm, f, P, n); /* a kept surface: the surface as it was */
    cm_vec3 Su, Sv, X;
    w->s = S->greg;
    greg_dist(w, P);
    cm_greg_surface_eval(S->greg, w->patch, w->u, w->v, &X, &Su, &Sv);
    cm_vec3 c = cm_cross(Su, Sv);
    if (!(cm_norm(c) > CM_EPS_CROSS_REL * cm_norm(Su) * cm_norm(Sv)) || !(cm_norm(c) > 0))
        return 0;
    *n = cm_unit(c);
    return 1;
}

int verify_face_normal(const loaded_model *lm, int f, const face_surface *fs, cm_vec3 P, cm_vec3 *n)
{
    greg_walk w = {NULL, 0, 0, 0, 0, 0, 0};
    surf_walk sw;
    if (fs[f].rebuilt && fs[f].repr == CM_REPR_NURBS && fs[f].nurbs_ctrl)
        surf_walk_init(&sw, &fs[f].nurbs, 0);
    else
        memset(&sw, 0, sizeof sw);
    return normal_at(lm, f, fs, &w, &sw, P, n);
}

double verify_g1_self(const loaded_model *lm, const cm_model *m, int f, const face_surface *fs,
                      const unsigned char *kept, double *worst_kept, double *use_worst)
{
    double worst = 1.0, worst_k = 1.0;
    const cm_face *F = &m->faces[f];
    const face_surface *S = &fs[f];
    uint32_t nth = 0; /* the use's place in use_worst */
    for (uint32_t l = 0; use_worst && l < F->nloops; l++)
        for (uint32_t k = 0; k < m->loops[F->loop0 + l].nuse; k++)
            use_worst[nth++] = 1.0;
    nth = 0;
    for (uint32_t l = 0; l < F->nloops; l++) {
        const cm_loop *L = &m->loops[F->loop0 + l];
        for (uint32_t k = 0; k < L->nuse; k++, nth++) {
            uint32_t e = m->uses[L->use0 + k].edge;
            int32_t a = m->edge_face[e][0], b = m->edge_face[e][1];
            if (!m->edges[e].g1 || a < 0 || b < 0 || a == b)
                continue;
            int to_kept = kept && kept[a == f ? b : a];
            cm_curve c;
            cm_model_edge_curve(m, e, &c);
            greg_walk walk = {NULL, S->greg ? 1e-3 * S->bbox : 0, 0, 0, 0, 0, 0};
            surf_walk swalk;
            if (S->rebuilt && S->repr == CM_REPR_NURBS && S->nurbs_ctrl)
                surf_walk_init(&swalk, &S->nurbs, 1e-3 * S->bbox);
            else
                memset(&swalk, 0, sizeof swalk);
            for (int j = 1; j <= 9; j++) {
                cm_vec3 d3[1], n, ns;
                if (cm_curve_eval(&c, j / 10.0, 0, d3, NULL) != CM_OK) {
                    if (worst_kept)
                        *worst_kept = 0.0;
                    return 0.0;
                }
                if (!normal_at(lm, f, fs, &walk, &swalk, d3[0], &n) || !source_normal_at(lm, f, d3[0], &ns))
                    continue; /* a pole or collapsed corner: verify_g1_edge decides */
                double cs = fabs(cm_dot(n, ns));
                if (use_worst && cs < use_worst[nth])
                    use_worst[nth] = cs;
                if (to_kept)
                    worst_k = cs < worst_k ? cs : worst_k;
                else
                    worst = cs < worst ? cs : worst;
            }
        }
    }
    if (worst_kept)
        *worst_kept = worst_k;
    return worst;
}

double verify_g1_edge(const loaded_model *lm, const cm_model *m, uint32_t e, const face_surface *fs, int *worse)
{
    int32_t a = m->edge_face[e][0], b = m->edge_face[e][1];
    if (worse)
        *worse = 0;
    if (a < 0 || b < 0 || a == b)
        return 1.0;
    cm_curve c;
    cm_model_edge_curve(m, e, &c);
    double worst = 1.0;
    /* the edge lies on both surfaces (within the §12 tolerance): a local foot within 1e-3 of the
       face's size is the right one */
    greg_walk walk[2] = {{NULL, 0, 0, 0, 0, 0, 0}, {NULL, 0, 0, 0, 0, 0, 0}};
    for (int side = 0; side < 2; side++)
        walk[side].accept = fs[side ? b : a].greg ? 1e-3 * fs[side ? b : a].bbox : 0;
    surf_walk swalk[2];
    for (int side = 0; side < 2; side++) {
        const face_surface *S = &fs[side ? b : a];
        if (S->rebuilt && S->repr == CM_REPR_NURBS && S->nurbs_ctrl)
            surf_walk_init(&swalk[side], &S->nurbs, 1e-3 * S->bbox);
        else
            memset(&swalk[side], 0, sizeof swalk[side]);
    }
    for (int k = 1; k <= 9; k++) {
        cm_vec3 n[2], P[2];
        int ok = 1;
        for (int side = 0; side < 2 && ok; side++) {
            int f = side ? b : a;
            ok = 0;
            /* a degenerate normal (a collapsed corner, a pole): 1e-3 along the edge instead (spec §13) */
            for (int tries = 0; tries < 3 && !ok; tries++) {
                double t = k / 10.0 + (tries == 0 ? 0.0 : (tries == 1 ? 1e-3 : -1e-3));
                cm_vec3 d3[1];
                if (cm_curve_eval(&c, t, 0, d3, NULL) != CM_OK)
                    break;
                P[side] = d3[0];
                ok = normal_at(lm, f, fs, &walk[side], &swalk[side], d3[0], &n[side]);
            }
        }
        if (!ok)
            return 0.0;
        double cs = fabs(cm_dot(n[0], n[1]));
        if (cs < worst) {
            worst = cs;
            /* the face whose final normal strays farther from its own source surface's is to blame */
            if (worse) {
                double dev[2];
                for (int side = 0; side < 2; side++) {
                    cm_vec3 ns;
                    dev[side] = source_normal_at(lm, side ? b : a, P[side], &ns) ? fabs(cm_dot(ns, n[side])) : 0.0;
                }
                *worse = dev[1] < dev[0];
            }
        }
    }
    return worst;
}
