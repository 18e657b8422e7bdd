/*
 * step_brep.c - STEP faces into the workstation B-rep (see step_brep.h, brep/brep.h).
 *
 * Data flow: colours are gathered first (styled item -> colour); then the
 * representations are grouped (an identity SHAPE_REPRESENTATION_RELATIONSHIP
 * puts two in one space), the placements between groups collected (assembly
 * transformations and mapped items), and every group reachable from a root
 * (a group no placement puts anywhere) is visited with its accumulated
 * placement; each visit imports the solids and shells of the group's
 * representations, face by face.  A face is built in its representation's
 * space and units (millimetres), then moved by the placement.
 *
 * Nothing here recurses: references are followed through fixed-depth chains
 * (a SURFACE_CURVE's 3D curve, a TRIMMED_CURVE's basis: at most
 * STEP_MAX_CHAIN links) and the assembly is walked with an explicit stack.
 */
#include "step_brep.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cm/cm_project.h"
#include "geom/hbox.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* links of a curve chain (SURFACE_CURVE -> TRIMMED_CURVE -> basis ...) followed before giving up */
#define STEP_MAX_CHAIN 8
/* depth of an assembly (placements within placements) */
#define STEP_MAX_ASSEMBLY_DEPTH 16
/* faces placed in all (the IGES import's budget: IGES_MAX_PLACED_FACES_DEFAULT) */
#define STEP_MAX_PLACED_FACES 262144
/* representation visits (an assembly DAG placing a part 2^16 times is refused, by name) */
#define STEP_MAX_VISITS 65536
/* curves in one loop and in one face (the host profile's CM_MAX_LOOP_EDGES, CM_MAX_FACE_EDGES) */
#define STEP_MAX_LOOP_EDGES 4096
#define STEP_MAX_FACE_EDGES 16384
/* boundary curves built for the whole model (the host profile's CM_MAX_MODEL_USES, as
   IGES_MAX_MODEL_PIECES): a shell listing one 16384-edge face 262144 times is refused, not built */
#define STEP_MAX_MODEL_PIECES 4194304
/* control points built for the whole model, curves and surfaces (1.5 GB of points): a file that
   lists one face with a 10^7-point surface a thousand times is refused by name, not built */
#define STEP_MAX_MODEL_CTRL (1LL << 26)
/* largest coordinate magnitude accepted, in millimetres (as IGES_MAX_COORD_MM) */
#define STEP_MAX_COORD_MM 1e12

/* the surface kinds, numbered as the IGES entities of the same surface (brep_face.surf_type) */
enum { SURF_PLANE = 190, SURF_CYLINDER = 192, SURF_CONE = 194, SURF_SPHERE = 196, SURF_TORUS = 198,
       SURF_REVOLUTION = 120, SURF_EXTRUSION = 122, SURF_BSPLINE = 128 };

typedef struct colour_of {
    int id;       /* the styled item (a face, shell or solid) */
    int order;    /* file order of the style (an over-riding style comes later and wins) */
    uint32_t rgb;
} colour_of;

/* a placement of one group of representations into another */
typedef struct placement_link {
    int parent, child; /* group indices */
    haffine xf;        /* child space -> parent space */
} placement_link;

typedef struct importer {
    step_file *f;
    brep_model *m;
    step_import_stats *stats;
    cm_status *st;
    double mm, rad;     /* units of the representation being read: millimetres, radians per unit */
    haffine xf;         /* its placement: representation (millimetres) -> model */
    int instance;       /* outermost placement being imported (brep_face.instance), 0 at the top */
    int shell;          /* brep shell index of the faces being imported */
    int shell_id, solid_id; /* their shell's and solid's #n (for colours styled onto them), 0 if none */
    int product;        /* the PRODUCT the representations being read shape (brep_face.product), 0 if none */
    char why[400];      /* why the current face cannot be built */
    colour_of *colours;
    int ncolours;
    unsigned char *done; /* per entity index: 1 face imported once, 2 solid reached */
    int *placed_head;   /* per entity index: its latest entry in placed_at, -1 none */
    struct placed_item {
        haffine xf;
        int next;       /* the entity's previous entry, -1 none */
    } *placed_at;       /* every placement a solid or shell model was imported with */
    int nplaced, capplaced;
    long long ctrl_built; /* control points of the curves and surfaces built so far (STEP_MAX_MODEL_CTRL) */
    int face_ordinal;
    int top;            /* solids and shell models reached so far (brep_face.top of their faces) */
    int first_fail_line;
    char first_fail[480];
} importer;

static int ent_index(const step_file *f, const step_entity *e)
{
    return (int)(e - f->ents);
}

static const char *tname(const importer *im, const step_entity *e, char *buf, size_t cap)
{
    return step_type(im->f, e, buf, cap);
}

/* record why the face at hand cannot be built (the first reason wins); returns CM_E_STEP */
__attribute__((format(printf, 3, 4))) static cm_err why(importer *im, const step_entity *e, const char *fmt, ...)
{
    if (im->why[0])
        return CM_E_STEP;
    char msg[300], t[64];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (e)
        snprintf(im->why, sizeof im->why, "#%d %s (line %d): %s", e->id, tname(im, e, t, sizeof t), e->line, msg);
    else
        snprintf(im->why, sizeof im->why, "%s", msg);
    return CM_E_STEP;
}

/* the instance a parameter names, which must be of `type` (NULL: any); else why() */
static const step_entity *ref_of(importer *im, const step_entity *host, const step_val *v, const char *type,
                                 const char *what)
{
    const step_entity *e = step_ref(im->f, v);
    if (!e) {
        if (v && v->kind == STEP_REF)
            why(im, host, "%s #%d is not in the file", what, v->ref);
        else
            why(im, host, "%s is not a reference", what);
        return NULL;
    }
    if (type && !step_is(im->f, e, type)) {
        char t[64];
        why(im, host, "%s #%d is a %s, not a %s", what, e->id, tname(im, e, t, sizeof t), type);
        return NULL;
    }
    return e;
}

static int bool_of(const importer *im, const step_val *v, int dflt)
{
    if (step_val_is(im->f, v, "T"))
        return 1;
    if (step_val_is(im->f, v, "F"))
        return 0;
    return dflt;
}

/* ---- points, directions, placements (in the representation's units, as millimetres) ---- */

static int coords_sane(cm_vec3 p)
{
    return fabs(p.x) <= STEP_MAX_COORD_MM && fabs(p.y) <= STEP_MAX_COORD_MM && fabs(p.z) <= STEP_MAX_COORD_MM;
}

static cm_err triple(importer *im, const step_entity *e, const step_val *list, double scale, cm_vec3 *out)
{
    double x[3] = {0, 0, 0};
    int n = list && list->kind == STEP_LIST ? list->n : 0;
    if (n < 1 || n > 3)
        return why(im, e, "%d coordinates (1 to 3 expected)", n);
    for (int i = 0; i < n; i++)
        if (step_num(step_item(list, i), &x[i]))
            return why(im, e, "coordinate %d is not a number", i + 1);
    *out = cm_v3(x[0] * scale, x[1] * scale, x[2] * scale);
    if (!coords_sane(*out))
        return why(im, e, "coordinates beyond +-%g mm", STEP_MAX_COORD_MM);
    return CM_OK;
}

static cm_err point_at(importer *im, const step_entity *host, const step_val *v, cm_vec3 *out)
{
    const step_entity *e = ref_of(im, host, v, "CARTESIAN_POINT", "the point");
    if (!e)
        return CM_E_STEP;
    return triple(im, e, step_item(step_params(im->f, e, "CARTESIAN_POINT"), 1), im->mm, out);
}

static cm_err direction_at(importer *im, const step_entity *host, const step_val *v, cm_vec3 *out)
{
    const step_entity *e = ref_of(im, host, v, "DIRECTION", "the direction");
    if (!e)
        return CM_E_STEP;
    cm_err err = triple(im, e, step_item(step_params(im->f, e, "DIRECTION"), 1), 1.0, out);
    if (err != CM_OK)
        return err;
    if (!(cm_norm(*out) > 1e-300))
        return why(im, e, "zero direction");
    *out = cm_unit(*out);
    return CM_OK;
}

/* VECTOR(name, direction, magnitude): a length in the representation's units */
static cm_err vector_at(importer *im, const step_entity *host, const step_val *v, cm_vec3 *out)
{
    const step_entity *e = ref_of(im, host, v, "VECTOR", "the vector");
    if (!e)
        return CM_E_STEP;
    const step_val *p = step_params(im->f, e, "VECTOR");
    double mag;
    cm_vec3 d;
    cm_err err = direction_at(im, e, step_item(p, 1), &d);
    if (err != CM_OK)
        return err;
    if (step_num(step_item(p, 2), &mag) || !(fabs(mag * im->mm) <= STEP_MAX_COORD_MM))
        return why(im, e, "its magnitude is not a number in range");
    *out = cm_scale(d, mag * im->mm);
    return CM_OK;
}

/* a frame: origin and orthonormal right-handed axes */
typedef struct frame {
    cm_vec3 o, X, Y, Z;
} frame;

/* AXIS2_PLACEMENT_3D(name, location, axis, ref_direction); axis and ref_direction may be $ */
static cm_err axis2_at(importer *im, const step_entity *host, const step_val *v, frame *fr)
{
    const step_entity *e = ref_of(im, host, v, "AXIS2_PLACEMENT_3D", "the placement");
    if (!e)
        return CM_E_STEP;
    const step_val *p = step_params(im->f, e, "AXIS2_PLACEMENT_3D");
    cm_vec3 Z = cm_v3(0, 0, 1), ref = cm_v3(1, 0, 0);
    cm_err err = point_at(im, e, step_item(p, 1), &fr->o);
    const step_val *a = step_item(p, 2), *r = step_item(p, 3);
    if (err == CM_OK && a && a->kind == STEP_REF)
        err = direction_at(im, e, a, &Z);
    if (err == CM_OK && r && r->kind == STEP_REF)
        err = direction_at(im, e, r, &ref);
    if (err != CM_OK)
        return err;
    fr->Z = Z;
    /* no reference direction: ISO 10303-42's first_proj_axis, the x axis projected, or the y axis
       when the placement's axis is the x axis */
    if (!(r && r->kind == STEP_REF) && fabs(fabs(Z.x) - 1.0) <= 1e-12)
        ref = cm_v3(0, 1, 0);
    hbox_frame(Z, &ref, &fr->X, &fr->Y);
    return CM_OK;
}

/* the map taking frame coordinates to the frame's space */
static haffine frame_map(const frame *fr)
{
    haffine m;
    cm_vec3 c[3] = {fr->X, fr->Y, fr->Z};
    for (int i = 0; i < 3; i++) {
        m.R[0][i] = c[i].x;
        m.R[1][i] = c[i].y;
        m.R[2][i] = c[i].z;
    }
    m.t = fr->o;
    return m;
}

/* ---- curves ---- */

static int clamped(const double *k, int n, int p)
{
    for (int i = 1; i <= p; i++)
        if (k[i] != k[0] || k[n + p - i] != k[n + p])
            return 0;
    return 1;
}

/* a full knot vector of `total` values from STEP's distinct knots and multiplicities */
static cm_err expand_knots(importer *im, const step_entity *e, const step_val *mults, const step_val *knots, int total,
                           double *out)
{
    int nk = knots && knots->kind == STEP_LIST ? knots->n : -1;
    if (nk < 1 || !mults || mults->kind != STEP_LIST || mults->n != nk)
        return why(im, e, "the knots and their multiplicities do not pair up");
    int k = 0;
    for (int i = 0; i < nk; i++) {
        double kv, mv;
        if (step_num(step_item(knots, i), &kv) || step_num(step_item(mults, i), &mv) || !(mv >= 1 && mv <= total) ||
            mv != floor(mv))
            return why(im, e, "knot %d or its multiplicity is not a number in range", i + 1);
        for (int j = 0; j < (int)mv; j++) {
            if (k >= total)
                return why(im, e, "the multiplicities add up to more than the %d knots its points need", total);
            out[k++] = kv;
        }
    }
    if (k != total)
        return why(im, e, "the multiplicities add up to %d knots, its points and degree need %d", k, total);
    return CM_OK;
}

/* B_SPLINE_CURVE_WITH_KNOTS, simple or complex (with B_SPLINE_CURVE and RATIONAL_B_SPLINE_CURVE) */
static cm_err bspline_curve(importer *im, const step_entity *e, hcurve *out)
{
    const step_file *f = im->f;
    const step_val *bc = step_params(f, e, "B_SPLINE_CURVE"), *bk = step_params(f, e, "B_SPLINE_CURVE_WITH_KNOTS");
    const step_val *deg, *pts, *mults, *knots;
    if (bc && bk) { /* complex: B_SPLINE_CURVE(degree, points, form, closed, self) ..._WITH_KNOTS(mults, knots, spec) */
        deg = step_item(bc, 0), pts = step_item(bc, 1), mults = step_item(bk, 0), knots = step_item(bk, 1);
    } else if (bk && bk->n >= 8) {
        deg = step_item(bk, 1), pts = step_item(bk, 2), mults = step_item(bk, 6), knots = step_item(bk, 7);
    } else {
        return why(im, e, "a B-spline curve without knots (uniform, Bezier) is not supported");
    }
    const step_val *rw = step_params(f, e, "RATIONAL_B_SPLINE_CURVE");
    const step_val *wl = rw ? step_item(rw, 0) : NULL;
    double dp;
    int n = pts && pts->kind == STEP_LIST ? pts->n : 0;
    if (step_num(deg, &dp) || !(dp >= 1 && dp <= CM_MAX_DEGREE) || dp != floor(dp))
        return why(im, e, "degree is not a whole number from 1 to %d", CM_MAX_DEGREE);
    int p = (int)dp;
    if (n < p + 1 || n > 100000)
        return why(im, e, "%d control points for degree %d (at least %d, at most 100000)", n, p, p + 1);
    if (rw && (!wl || wl->kind != STEP_LIST || wl->n != n))
        return why(im, e, "its weights do not match its %d control points", n);
    cm_err err = hcurve_alloc(out, p, n, rw != NULL, im->st);
    if (err != CM_OK)
        return err;
    err = expand_knots(im, e, mults, knots, n + p + 1, out->knots);
    for (int i = 0; i < n && err == CM_OK; i++) {
        err = point_at(im, e, step_item(pts, i), &out->ctrl[i]);
        if (err == CM_OK && rw && (step_num(step_item(wl, i), &out->w[i]) || !(out->w[i] > 0)))
            err = why(im, e, "weight %d is not a positive number", i + 1);
    }
    if (err == CM_OK) {
        cm_curve v = hcurve_view(out);
        cm_status cst;
        cm_status_init(&cst);
        if (cm_curve_check(&v, &cst) != CM_OK)
            err = why(im, e, "invalid B-spline curve: %s", cm_strerror(cst.code));
    }
    if (err == CM_OK && !clamped(out->knots, n, p)) {
        hcurve c = {0};
        err = hcurve_clamp(out, &c, im->st);
        hcurve_free(out);
        *out = c;
    }
    if (err != CM_OK)
        hcurve_free(out);
    return err;
}

/* CIRCLE(name, placement, r) or ELLIPSE(name, placement, a, b) */
static cm_err conic_of(importer *im, const step_entity *e, frame *fr, double *a, double *b)
{
    int circle = step_is(im->f, e, "CIRCLE");
    const step_val *p = step_params(im->f, e, circle ? "CIRCLE" : "ELLIPSE");
    cm_err err = axis2_at(im, e, step_item(p, 1), fr);
    if (err != CM_OK)
        return err;
    if (step_num(step_item(p, 2), a) || (!circle && step_num(step_item(p, 3), b)))
        return why(im, e, "its radius is not a number");
    if (circle)
        *b = *a;
    *a *= im->mm;
    *b *= im->mm;
    if (!(*a > 0 && *b > 0 && *a <= STEP_MAX_COORD_MM && *b <= STEP_MAX_COORD_MM))
        return why(im, e, "radius %g mm out of range", fmin(*a, *b));
    return CM_OK;
}

/* the angle of point P on the conic (its parameter) */
static double conic_angle(const frame *fr, double a, double b, cm_vec3 P)
{
    cm_vec3 d = cm_sub(P, fr->o);
    return atan2(cm_dot(d, fr->Y) / b, cm_dot(d, fr->X) / a);
}

/* the arc from angle t0 forwards (sense) or backwards to t1; closed: the whole conic from t0 */
static cm_err conic_arc(importer *im, const frame *fr, double a, double b, double t0, double t1, int sense,
                        int closed, hcurve *out)
{
    if (!isfinite(t0) || !isfinite(t1) || fabs(t0) > 1e6 || fabs(t1) > 1e6)
        return why(im, NULL, "an arc's angles (%g, %g rad) are not finite numbers of turns", t0, t1);
    /* angles reduced to one turn first: a file's 1e20 would never move by 2 pi steps */
    t0 = remainder(t0, 2 * M_PI);
    t1 = remainder(t1, 2 * M_PI);
    double lo, hi;
    if (closed) {
        lo = t0;
        hi = t0 + 2 * M_PI;
    } else {
        lo = sense ? t0 : t1;
        hi = sense ? t1 : t0;
        if (hi <= lo + 1e-12)
            hi += 2 * M_PI; /* once: both within a turn of zero */
        if (hi <= lo + 1e-12)
            hi += 2 * M_PI;
    }
    if (hi - lo > 2 * M_PI)
        hi = lo + 2 * M_PI;
    cm_err err = hcurve_ellipse_arc(fr->o, fr->X, fr->Y, a, b, lo, hi, out, im->st);
    if (err == CM_OK && !sense)
        hcurve_reverse(out);
    return err;
}

/*
 * Two clamped pieces of one closed curve, a ending where b starts (its seam), as one curve: b's knots
 * moved on to follow a's, the seam point once, a's degree and rationality (b's weights scaled to
 * meet a's at the seam: the same curve).
 */
static cm_err join_at_seam(const hcurve *a, const hcurve *b, hcurve *out, cm_status *st)
{
    if (a->p != b->p || (a->w == NULL) != (b->w == NULL))
        return cm_fail(st, CM_E_ARG, "join_at_seam");
    int p = a->p, n = a->n + b->n - 1;
    cm_err err = hcurve_alloc(out, p, n, a->w != NULL, st);
    if (err != CM_OK)
        return err;
    double shift = a->knots[a->n + p] - b->knots[0];
    int k = 0;
    for (int i = 0; i < a->n + p; i++) /* a's knots but the last one */
        out->knots[k++] = a->knots[i];
    for (int i = p + 1; i < b->n + p + 1; i++) /* b's after its first p + 1 (the seam, p-fold now) */
        out->knots[k++] = b->knots[i] + shift;
    double scale = a->w ? a->w[a->n - 1] / b->w[0] : 1.0;
    for (int i = 0; i < a->n; i++) {
        out->ctrl[i] = a->ctrl[i];
        if (a->w)
            out->w[i] = a->w[i];
    }
    for (int i = 1; i < b->n; i++) {
        out->ctrl[a->n - 1 + i] = b->ctrl[i];
        if (a->w)
            out->w[a->n - 1 + i] = b->w[i] * scale;
    }
    return CM_OK;
}

/*
 * The piece of `whole` from A to B: along its direction when sense, against it otherwise; closed:
 * the whole (closed) curve.  `whole` is consumed.
 */
static cm_err cut_between(importer *im, const step_entity *e, hcurve *whole, cm_vec3 A, cm_vec3 B, int sense,
                          int closed, hcurve *out)
{
    double t0, t1, ta, tb, da, db;
    hcurve_domain(whole, &t0, &t1);
    cm_curve v = hcurve_view(whole);
    cm_err err = CM_OK;
    if (closed) {
        *out = *whole;
        memset(whole, 0, sizeof *whole);
        if (!sense)
            hcurve_reverse(out);
        return CM_OK;
    }
    if (cm_curve_project(&v, t0, t1, A, &ta, &da, NULL) != CM_OK || cm_curve_project(&v, t0, t1, B, &tb, &db, NULL) != CM_OK) {
        hcurve_free(whole);
        return why(im, e, "cannot place the edge's vertices on it");
    }
    double eps = 1e-9 * (t1 - t0);
    cm_vec3 s = cm_v3(0, 0, 0), en = s;
    cm_vec3 d[1];
    if (cm_curve_eval(&v, t0, 0, d, NULL) == CM_OK)
        s = d[0];
    if (cm_curve_eval(&v, t1, 0, d, NULL) == CM_OK)
        en = d[0];
    int closed_curve = cm_dist(s, en) <= 1e-9 * (1 + cm_norm(s));
    if (closed_curve) { /* a closed curve: the seam belongs to either end */
        if (sense) {
            if (ta >= t1 - eps)
                ta = t0;
            if (tb <= t0 + eps)
                tb = t1;
        } else {
            if (tb >= t1 - eps)
                tb = t0;
            if (ta <= t0 + eps)
                ta = t1;
        }
    }
    double lo = sense ? ta : tb, hi = sense ? tb : ta;
    if (!(hi > lo + eps) && closed_curve && lo < t1 - eps && hi > t0 + eps) {
        /* the edge runs over the closed curve's seam: from lo to the end, then from the start to hi */
        hcurve a = {0}, b = {0};
        err = hcurve_subrange(whole, lo, t1, &a, im->st);
        if (err == CM_OK)
            err = hcurve_subrange(whole, t0, hi, &b, im->st);
        if (err == CM_OK)
            err = join_at_seam(&a, &b, out, im->st);
        hcurve_free(&a);
        hcurve_free(&b);
        hcurve_free(whole);
        if (err == CM_OK && !sense)
            hcurve_reverse(out);
        return err;
    }
    if (!(hi > lo + eps)) {
        hcurve_free(whole);
        return why(im, e, "the edge's vertices come in the wrong order on it");
    }
    if (lo <= t0 + eps && hi >= t1 - eps) {
        *out = *whole;
        memset(whole, 0, sizeof *whole);
    } else {
        err = hcurve_subrange(whole, fmax(lo, t0), fmin(hi, t1), out, im->st);
        hcurve_free(whole);
    }
    if (err == CM_OK && !sense)
        hcurve_reverse(out);
    return err;
}

/* POLYLINE(name, points) */
static cm_err polyline_of(importer *im, const step_entity *e, hcurve *out)
{
    const step_val *pts = step_item(step_params(im->f, e, "POLYLINE"), 1);
    int n = pts && pts->kind == STEP_LIST ? pts->n : 0;
    if (n < 2 || n > 100000)
        return why(im, e, "%d points (2 to 100000 expected)", n);
    cm_vec3 *p = malloc((size_t)n * sizeof *p);
    if (!p)
        return cm_fail(im->st, CM_E_NOMEM, "out of memory");
    cm_err err = CM_OK;
    for (int i = 0; i < n && err == CM_OK; i++)
        err = point_at(im, e, step_item(pts, i), &p[i]);
    if (err == CM_OK)
        err = hcurve_polyline(p, n, out, im->st);
    free(p);
    return err;
}

/* a curve given by its points (a B-spline or a polyline) whole; `what` names its use in the error */
static cm_err curve_of_points(importer *im, const step_entity *g, const char *what, hcurve *out)
{
    if (step_is(im->f, g, "B_SPLINE_CURVE_WITH_KNOTS"))
        return bspline_curve(im, g, out);
    if (step_is(im->f, g, "POLYLINE"))
        return polyline_of(im, g, out);
    char t[64];
    return why(im, g, "a %s %s is not supported", tname(im, g, t, sizeof t), what);
}

/* follow SURFACE_CURVE / SEAM_CURVE to the 3D curve and TRIMMED_CURVE to its basis (sense flips) */
static const step_entity *curve_basis(importer *im, const step_entity *g, int *sense, const step_val **trims)
{
    const step_file *f = im->f;
    for (int k = 0; k < STEP_MAX_CHAIN && g; k++) {
        const step_val *p;
        if ((p = step_params(f, g, "SURFACE_CURVE")) || (p = step_params(f, g, "SEAM_CURVE")) ||
            (p = step_params(f, g, "INTERSECTION_CURVE"))) {
            g = ref_of(im, g, step_item(p, 1), NULL, "its 3D curve");
        } else if ((p = step_params(f, g, "TRIMMED_CURVE"))) {
            if (!bool_of(im, step_item(p, 4), 1))
                *sense = !*sense;
            if (trims)
                *trims = p;
            g = ref_of(im, g, step_item(p, 1), NULL, "its basis curve");
        } else {
            return g;
        }
    }
    if (g)
        why(im, g, "curve references nest deeper than %d", STEP_MAX_CHAIN);
    return NULL;
}

/*
 * An edge's curve, running from its start vertex A to its end vertex B: `g` is the EDGE_CURVE's
 * geometry, `sense` its same_sense, `closed` when both vertices are one (the edge runs all round).
 */
static cm_err edge_curve(importer *im, const step_entity *edge, const step_entity *g, cm_vec3 A, cm_vec3 B, int sense,
                         int closed, hcurve *out)
{
    const step_file *f = im->f;
    g = curve_basis(im, g, &sense, NULL);
    if (!g)
        return CM_E_STEP;
    if (step_is(f, g, "LINE")) {
        if (closed || !(cm_dist(A, B) > 0))
            return why(im, edge, "a straight edge whose two ends are one point");
        return hcurve_line(A, B, out, im->st);
    }
    if (step_is(f, g, "CIRCLE") || step_is(f, g, "ELLIPSE")) {
        frame fr;
        double a, b;
        cm_err err = conic_of(im, g, &fr, &a, &b);
        if (err != CM_OK)
            return err;
        return conic_arc(im, &fr, a, b, conic_angle(&fr, a, b, A), conic_angle(&fr, a, b, B), sense, closed, out);
    }
    hcurve whole = {0};
    cm_err err = curve_of_points(im, g, "edge curve", &whole);
    if (err != CM_OK)
        return err;
    return cut_between(im, g, &whole, A, B, sense, closed, out);
}

/* a trimming value of a TRIMMED_CURVE: a PARAMETER_VALUE(t) or a point, the one its master
   representation names first (.CARTESIAN.: the point; exporters' parameters are the less reliable) */
static int trim_value(importer *im, const step_val *sel, int cartesian_first, double *t, cm_vec3 *P, int *is_point)
{
    char saved[sizeof im->why];
    memcpy(saved, im->why, sizeof saved); /* a select item that is no point is no error */
    for (int pass = 0; pass < 2; pass++) {
        int want_point = pass == 0 ? cartesian_first : !cartesian_first;
        for (int i = 0; sel && i < sel->n; i++) {
            const step_val *v = step_item(sel, i);
            if (!want_point && step_val_is(im->f, v, "PARAMETER_VALUE") && step_num(v, t) == 0) {
                *is_point = 0;
                memcpy(im->why, saved, sizeof saved);
                return 0;
            }
            if (want_point && v && v->kind == STEP_REF && step_is(im->f, step_ref(im->f, v), "CARTESIAN_POINT") &&
                point_at(im, NULL, v, P) == CM_OK) {
                *is_point = 1;
                memcpy(im->why, saved, sizeof saved);
                return 0;
            }
        }
    }
    memcpy(im->why, saved, sizeof saved);
    return -1;
}

/*
 * A curve with ends (a surface's generatrix or swept curve): a B-spline or polyline whole, a full
 * circle or ellipse, or a TRIMMED_CURVE of a line, conic or B-spline cut at its trims.
 */
static cm_err bounded_curve(importer *im, const step_entity *host, const step_val *v, hcurve *out)
{
    const step_file *f = im->f;
    const step_entity *g = ref_of(im, host, v, NULL, "the curve");
    int sense = 1;
    const step_val *tr = NULL;
    if (g)
        g = curve_basis(im, g, &sense, &tr);
    if (!g)
        return CM_E_STEP;
    cm_vec3 PA = cm_v3(0, 0, 0), PB = PA;
    double ta = 0, tb = 0;
    int pa = 0, pb = 0;
    int cartesian = tr && step_val_is(f, step_item(tr, 5), "CARTESIAN");
    if (tr && (trim_value(im, step_item(tr, 2), cartesian, &ta, &PA, &pa) ||
               trim_value(im, step_item(tr, 3), cartesian, &tb, &PB, &pb)))
        return why(im, host, "its trimmed curve has no usable trims");
    if (step_is(f, g, "LINE")) {
        if (!tr)
            return why(im, g, "an unbounded line cannot make a surface");
        const step_val *p = step_params(f, g, "LINE");
        cm_vec3 P, V;
        cm_err err = point_at(im, g, step_item(p, 1), &P);
        if (err == CM_OK)
            err = vector_at(im, g, step_item(p, 2), &V);
        if (err != CM_OK)
            return err;
        cm_vec3 A = pa ? PA : cm_add(P, cm_scale(V, ta)), B = pb ? PB : cm_add(P, cm_scale(V, tb));
        if (!(cm_dist(A, B) > 0))
            return why(im, g, "its trimmed piece has no length");
        return hcurve_line(A, B, out, im->st); /* trim 1 to trim 2, whichever way the line runs */
    }
    if (step_is(f, g, "CIRCLE") || step_is(f, g, "ELLIPSE")) {
        frame fr;
        double a, b;
        cm_err err = conic_of(im, g, &fr, &a, &b);
        if (err != CM_OK)
            return err;
        if (!tr)
            return conic_arc(im, &fr, a, b, 0, 0, 1, 1, out);
        double t0 = pa ? conic_angle(&fr, a, b, PA) : ta * im->rad, t1 = pb ? conic_angle(&fr, a, b, PB) : tb * im->rad;
        return conic_arc(im, &fr, a, b, t0, t1, sense, 0, out);
    }
    hcurve whole = {0};
    cm_err err = curve_of_points(im, g, "curve", &whole);
    if (err != CM_OK || !tr) {
        if (err == CM_OK)
            *out = whole;
        return err;
    }
    cm_curve cv = hcurve_view(&whole);
    double t0, t1, d;
    hcurve_domain(&whole, &t0, &t1);
    if ((pa && cm_curve_project(&cv, t0, t1, PA, &ta, &d, NULL) != CM_OK) ||
        (pb && cm_curve_project(&cv, t0, t1, PB, &tb, &d, NULL) != CM_OK)) {
        hcurve_free(&whole);
        return why(im, g, "cannot place its trims on it");
    }
    double lo = fmax(t0, fmin(ta, tb)), hi = fmin(t1, fmax(ta, tb));
    if (!(hi > lo)) {
        hcurve_free(&whole);
        return why(im, g, "its trimmed piece is empty");
    }
    err = hcurve_subrange(&whole, lo, hi, out, im->st);
    hcurve_free(&whole);
    if (err == CM_OK && ta > tb) /* from trim 1 to trim 2 */
        hcurve_reverse(out);
    return err;
}

/* ---- surfaces (over `ext`, the face's boundary box in the representation's space) ---- */

static cm_err bspline_surface(importer *im, const step_entity *e, hsurf *out)
{
    const step_file *f = im->f;
    const step_val *bs = step_params(f, e, "B_SPLINE_SURFACE"), *bk = step_params(f, e, "B_SPLINE_SURFACE_WITH_KNOTS");
    const step_val *du, *dv, *net, *um, *vm, *uk, *vk;
    if (bs && bk) { /* complex: (u_deg, v_deg, points, form, uc, vc, self) (um, vm, uk, vk, spec) */
        du = step_item(bs, 0), dv = step_item(bs, 1), net = step_item(bs, 2);
        um = step_item(bk, 0), vm = step_item(bk, 1), uk = step_item(bk, 2), vk = step_item(bk, 3);
    } else if (bk && bk->n >= 12) {
        du = step_item(bk, 1), dv = step_item(bk, 2), net = step_item(bk, 3);
        um = step_item(bk, 8), vm = step_item(bk, 9), uk = step_item(bk, 10), vk = step_item(bk, 11);
    } else {
        return why(im, e, "a B-spline surface without knots (uniform, Bezier) is not supported");
    }
    const step_val *rw = step_params(f, e, "RATIONAL_B_SPLINE_SURFACE");
    const step_val *wn = rw ? step_item(rw, 0) : NULL;
    double pd, qd;
    if (step_num(du, &pd) || step_num(dv, &qd) || !(pd >= 1 && pd <= CM_MAX_DEGREE && qd >= 1 && qd <= CM_MAX_DEGREE) ||
        pd != floor(pd) || qd != floor(qd))
        return why(im, e, "degrees are not whole numbers from 1 to %d", CM_MAX_DEGREE);
    int p = (int)pd, q = (int)qd;
    int nu = net && net->kind == STEP_LIST ? net->n : 0;
    const step_val *row0 = step_item(net, 0);
    int nv = row0 && row0->kind == STEP_LIST ? row0->n : 0;
    if (nu < p + 1 || nv < q + 1 || nu > 100000 || nv > 100000 || (long)nu * nv > 10000000)
        return why(im, e, "a %d x %d control net for degrees %d x %d", nu, nv, p, q);
    hsurf s = {0};
    cm_err err = hsurf_alloc(&s, p, q, nu, nv, rw != NULL, im->st);
    if (err != CM_OK)
        return err;
    err = expand_knots(im, e, um, uk, nu + p + 1, s.U);
    if (err == CM_OK)
        err = expand_knots(im, e, vm, vk, nv + q + 1, s.V);
    for (int i = 0; i < nu && err == CM_OK; i++) {
        const step_val *row = step_item(net, i), *wrow = wn ? step_item(wn, i) : NULL;
        if (!row || row->kind != STEP_LIST || row->n != nv || (rw && (!wrow || wrow->kind != STEP_LIST || wrow->n != nv))) {
            err = why(im, e, "row %d of its control net (or weights) is not %d long", i + 1, nv);
            break;
        }
        for (int j = 0; j < nv && err == CM_OK; j++) {
            err = point_at(im, e, step_item(row, j), &s.ctrl[(long)i * nv + j]);
            if (err == CM_OK && rw && (step_num(step_item(wrow, j), &s.w[(long)i * nv + j]) || !(s.w[(long)i * nv + j] > 0)))
                err = why(im, e, "weight (%d, %d) is not a positive number", i + 1, j + 1);
        }
    }
    if (err == CM_OK) {
        cm_surf view = hsurf_view(&s);
        cm_status cst;
        cm_status_init(&cst);
        if (cm_surf_check(&view, &cst) != CM_OK)
            err = why(im, e, "invalid B-spline surface: %s", cm_strerror(cst.code));
    }
    if (err == CM_OK && (!clamped(s.U, nu, p) || !clamped(s.V, nv, q))) {
        double u0, u1, v0, v1;
        hsurf c = {0};
        hsurf_domain(&s, &u0, &u1, &v0, &v1);
        err = hsurf_subrange(&s, u0, u1, v0, v1, &c, im->st);
        hsurf_free(&s);
        s = c;
    }
    if (err != CM_OK) {
        hsurf_free(&s);
        return err;
    }
    *out = s;
    return CM_OK;
}

/* how many of a face's loops wind round the axis through o along Z (their points' angle about it
   turning a whole turn): a cone's face of one such loop reaches the apex (its other side is
   unbounded), whether or not the file gives the apex a VERTEX_LOOP */
static int loops_winding(const hcurve_list *loops, int nloops, const frame *fr)
{
    int winding = 0;
    for (int l = 0; l < nloops; l++) {
        double turned = 0.0, last = 0.0;
        int have = 0;
        for (int i = 0; i < loops[l].n; i++) {
            cm_curve cv = hcurve_view(&loops[l].c[i]);
            double t0, t1;
            hcurve_domain(&loops[l].c[i], &t0, &t1);
            for (int j = 0; j <= 16; j++) {
                cm_vec3 d[1];
                if (cm_curve_eval(&cv, t0 + (t1 - t0) * j / 16.0, 0, d, NULL) != CM_OK)
                    return 0;
                cm_vec3 r = cm_sub(d[0], fr->o);
                double a = atan2(cm_dot(r, fr->Y), cm_dot(r, fr->X));
                if (have) {
                    double da = a - last;
                    da -= da > M_PI ? 2 * M_PI : (da < -M_PI ? -2 * M_PI : 0.0);
                    turned += da;
                }
                last = a;
                have = 1;
            }
        }
        winding += fabs(turned) > M_PI;
    }
    return winding;
}

static cm_err surface_of(importer *im, const step_entity *face, const step_val *v, const hbox *ext,
                         const hcurve_list *loops, int nloops, hsurf *out, int *kind)
{
    const step_file *f = im->f;
    const step_entity *e = ref_of(im, face, v, NULL, "its surface");
    if (!e)
        return CM_E_STEP;
    const step_val *p;
    frame fr;
    cm_err err;
    if (step_is(f, e, "B_SPLINE_SURFACE_WITH_KNOTS")) {
        *kind = SURF_BSPLINE;
        return bspline_surface(im, e, out);
    }
    if ((p = step_params(f, e, "PLANE"))) {
        *kind = SURF_PLANE;
        if ((err = axis2_at(im, e, step_item(p, 1), &fr)) != CM_OK)
            return err;
        double x0, x1, y0, y1;
        hbox_axis_range(ext, fr.o, fr.X, &x0, &x1);
        hbox_axis_range(ext, fr.o, fr.Y, &y0, &y1);
        return hsurf_plane(fr.o, fr.X, fr.Y, x0, x1, y0, y1, out, im->st);
    }
    int cyl = (p = step_params(f, e, "CYLINDRICAL_SURFACE")) != NULL;
    if (cyl || (p = step_params(f, e, "CONICAL_SURFACE"))) {
        *kind = cyl ? SURF_CYLINDER : SURF_CONE;
        double r, semi = 0;
        if ((err = axis2_at(im, e, step_item(p, 1), &fr)) != CM_OK)
            return err;
        if (step_num(step_item(p, 2), &r) || (!cyl && step_num(step_item(p, 3), &semi)))
            return why(im, e, "its radius or angle is not a number");
        r *= im->mm;
        semi *= im->rad;
        if (!(r >= 0 && r <= STEP_MAX_COORD_MM) || (cyl && !(r > 0)) || !(fabs(semi) < M_PI / 2))
            return why(im, e, "radius %g mm or semi-angle %g rad out of range", r, semi);
        double v0, v1;
        hbox_axis_range(ext, fr.o, fr.Z, &v0, &v1);
        if (cyl)
            return hsurf_cylinder(fr.o, fr.X, fr.Y, fr.Z, r, 0, 2 * M_PI, v0, v1, out, im->st);
        double ta = tan(semi), apex = ta != 0 ? -r / ta : -HUGE_VAL;
        if (ta != 0 && loops_winding(loops, nloops, &fr) == 1) { /* (the apex in it: a cap) */
            v0 = apex < v0 ? apex : v0;
            v1 = apex > v1 ? apex : v1;
        }
        if (ta > 0 && v0 < apex)
            v0 = apex;
        if (ta < 0 && v1 > apex)
            v1 = apex;
        return hsurf_cone(fr.o, fr.X, fr.Y, fr.Z, r, semi, 0, 2 * M_PI, v0, v1, out, im->st);
    }
    int sph = (p = step_params(f, e, "SPHERICAL_SURFACE")) != NULL;
    if (sph || (p = step_params(f, e, "TOROIDAL_SURFACE")) || (p = step_params(f, e, "DEGENERATE_TOROIDAL_SURFACE"))) {
        *kind = sph ? SURF_SPHERE : SURF_TORUS;
        double R, r = 0;
        if ((err = axis2_at(im, e, step_item(p, 1), &fr)) != CM_OK)
            return err;
        if (step_num(step_item(p, 2), &R) || (!sph && step_num(step_item(p, 3), &r)))
            return why(im, e, "its radii are not numbers");
        R *= im->mm;
        r *= im->mm;
        if (!(R > 0 && R <= STEP_MAX_COORD_MM) || (!sph && !(r > 0 && r <= STEP_MAX_COORD_MM)))
            return why(im, e, "radius out of range");
        if (sph)
            return hsurf_sphere(fr.o, fr.X, fr.Y, fr.Z, R, 0, 2 * M_PI, -M_PI / 2, M_PI / 2, out, im->st);
        return hsurf_torus(fr.o, fr.X, fr.Y, fr.Z, R, r, 0, 2 * M_PI, -M_PI, M_PI, out, im->st);
    }
    if ((p = step_params(f, e, "SURFACE_OF_REVOLUTION"))) {
        *kind = SURF_REVOLUTION;
        const step_entity *ax = ref_of(im, e, step_item(p, 2), "AXIS1_PLACEMENT", "its axis");
        if (!ax)
            return CM_E_STEP;
        const step_val *ap = step_params(f, ax, "AXIS1_PLACEMENT");
        cm_vec3 o, d = cm_v3(0, 0, 1);
        err = point_at(im, ax, step_item(ap, 1), &o);
        if (err == CM_OK && step_item(ap, 2) && step_item(ap, 2)->kind == STEP_REF)
            err = direction_at(im, ax, step_item(ap, 2), &d);
        hcurve g = {0};
        if (err == CM_OK)
            err = bounded_curve(im, e, step_item(p, 1), &g);
        if (err == CM_OK)
            err = hsurf_revolve(&g, o, d, 0, 2 * M_PI, out, im->st);
        hcurve_free(&g);
        return err;
    }
    if ((p = step_params(f, e, "SURFACE_OF_LINEAR_EXTRUSION"))) {
        *kind = SURF_EXTRUSION;
        cm_vec3 V;
        hcurve c = {0};
        err = vector_at(im, e, step_item(p, 2), &V);
        if (err == CM_OK && !(cm_norm(V) > 0))
            err = why(im, e, "its extrusion vector has no length");
        if (err == CM_OK)
            err = bounded_curve(im, e, step_item(p, 1), &c);
        if (err == CM_OK) {
            /* the surface reaches as far along the direction as the face does: the box's extent
               past the curve's own (its control points bound it) */
            cm_vec3 d = cm_unit(V);
            double lo, hi, cmin = HUGE_VAL, cmax = -HUGE_VAL;
            hbox_axis_range(ext, cm_v3(0, 0, 0), d, &lo, &hi);
            for (int i = 0; i < c.n; i++) {
                double t = cm_dot(c.ctrl[i], d);
                cmin = fmin(cmin, t);
                cmax = fmax(cmax, t);
            }
            double v0 = lo - cmax, v1 = hi - cmin;
            haffine sh = haffine_identity();
            sh.t = cm_scale(d, v0);
            hcurve_transform(&c, &sh);
            err = hsurf_extrude(&c, cm_scale(d, v1 - v0), out, im->st);
        }
        hcurve_free(&c);
        return err;
    }
    char t[64];
    return why(im, e, "a %s surface is not supported", tname(im, e, t, sizeof t));
}

/* ---- faces ---- */

/* the colour styled onto instance id, if any (binary search; the last style of an id wins) */
static int colour_for(const importer *im, int id, uint32_t *rgb)
{
    int lo = 0, hi = im->ncolours - 1, found = -1;
    while (lo <= hi) {
        int mid = lo + (hi - lo) / 2;
        if (im->colours[mid].id < id)
            lo = mid + 1;
        else if (im->colours[mid].id > id)
            hi = mid - 1;
        else {
            found = mid;
            lo = mid + 1;
        }
    }
    if (found < 0)
        return 0;
    *rgb = im->colours[found].rgb;
    return 1;
}

/* the curves of one bound, in loop order: EDGE_LOOP, POLY_LOOP; a VERTEX_LOOP gives none */
static cm_err loop_curves(importer *im, const step_entity *face, const step_entity *loop, hcurve_list *out,
                          int *face_edges, hbox *points)
{
    const step_file *f = im->f;
    const step_val *p;
    if ((p = step_params(f, loop, "VERTEX_LOOP"))) {
        /* a loop shrunk to a point (a cone's apex, a sphere's pole): no boundary, but the surface
           must reach it (an unbounded cone is built over the face's extent, the apex in it) */
        const step_entity *v = ref_of(im, loop, step_item(p, 1), "VERTEX_POINT", "its vertex");
        cm_vec3 P;
        if (!v || point_at(im, v, step_item(step_params(f, v, "VERTEX_POINT"), 1), &P) != CM_OK)
            return CM_E_STEP;
        hbox_add(points, P);
        return CM_OK;
    }
    if ((p = step_params(f, loop, "POLY_LOOP"))) {
        const step_val *pts = step_item(p, 1);
        int n = pts && pts->kind == STEP_LIST ? pts->n : 0;
        if (n < 3 || n > STEP_MAX_LOOP_EDGES)
            return why(im, loop, "%d corners (3 to %d expected)", n, STEP_MAX_LOOP_EDGES);
        if ((*face_edges += n) > STEP_MAX_FACE_EDGES)
            return why(im, face, "its loops have more than %d edges", STEP_MAX_FACE_EDGES);
        cm_vec3 first, prev, P;
        cm_err err = point_at(im, loop, step_item(pts, 0), &first);
        prev = first;
        for (int i = 1; i <= n && err == CM_OK; i++) {
            if (i < n)
                err = point_at(im, loop, step_item(pts, i), &P);
            else
                P = first;
            if (err != CM_OK)
                break;
            hcurve c = {0};
            if (cm_dist(prev, P) > 0) {
                err = hcurve_line(prev, P, &c, im->st);
                if (err == CM_OK)
                    err = hcurve_list_push(out, &c, im->st);
                hcurve_free(&c);
            }
            prev = P;
        }
        return err;
    }
    if (!(p = step_params(f, loop, "EDGE_LOOP"))) {
        char t[64];
        return why(im, face, "a bound's loop #%d is a %s", loop->id, tname(im, loop, t, sizeof t));
    }
    const step_val *edges = step_item(p, 1);
    int n = edges && edges->kind == STEP_LIST ? edges->n : 0;
    if (n < 1 || n > STEP_MAX_LOOP_EDGES)
        return why(im, loop, "%d edges (1 to %d expected)", n, STEP_MAX_LOOP_EDGES);
    if ((*face_edges += n) > STEP_MAX_FACE_EDGES)
        return why(im, face, "its loops have more than %d edges", STEP_MAX_FACE_EDGES);
    for (int i = 0; i < n; i++) {
        const step_entity *oe = ref_of(im, loop, step_item(edges, i), "ORIENTED_EDGE", "an edge");
        if (!oe)
            return CM_E_STEP;
        const step_val *op = step_params(f, oe, "ORIENTED_EDGE");
        const step_entity *ec = ref_of(im, oe, step_item(op, 3), "EDGE_CURVE", "its edge");
        if (!ec)
            return CM_E_STEP;
        const step_val *ep = step_params(f, ec, "EDGE_CURVE");
        const step_entity *va = ref_of(im, ec, step_item(ep, 1), "VERTEX_POINT", "its start vertex");
        const step_entity *vb = va ? ref_of(im, ec, step_item(ep, 2), "VERTEX_POINT", "its end vertex") : NULL;
        const step_entity *g = vb ? ref_of(im, ec, step_item(ep, 3), NULL, "its curve") : NULL;
        if (!g)
            return CM_E_STEP;
        cm_vec3 A, B;
        cm_err err = point_at(im, va, step_item(step_params(f, va, "VERTEX_POINT"), 1), &A);
        if (err == CM_OK)
            err = point_at(im, vb, step_item(step_params(f, vb, "VERTEX_POINT"), 1), &B);
        if (err != CM_OK)
            return err;
        int closed = va == vb || cm_dist(A, B) <= 1e-12 * (1 + cm_norm(A));
        hcurve c = {0};
        err = edge_curve(im, ec, g, A, B, bool_of(im, step_item(ep, 4), 1), closed, &c);
        im->ctrl_built += c.n;
        if (err == CM_OK && !bool_of(im, step_item(op, 4), 1))
            hcurve_reverse(&c);
        if (err == CM_OK)
            err = hcurve_list_push(out, &c, im->st);
        hcurve_free(&c);
        if (err != CM_OK)
            return err;
    }
    return CM_OK;
}

/* build face `fe` (ADVANCED_FACE or FACE_SURFACE) into the model; `flip` from an oriented face or shell */
static cm_err build_face(importer *im, const step_entity *fe, int flip)
{
    const step_file *f = im->f;
    brep_model *m = im->m;
    const step_val *p = step_params(f, fe, "ADVANCED_FACE");
    if (!p)
        p = step_params(f, fe, "FACE_SURFACE");
    if (!p) {
        char t[64];
        return why(im, fe, "a %s is not a face with a surface", tname(im, fe, t, sizeof t));
    }
    const step_val *bounds = step_item(p, 1);
    int nb = bounds && bounds->kind == STEP_LIST ? bounds->n : 0;
    if (nb > 100000)
        return why(im, fe, "%d bounds", nb);
    hcurve_list *loops = calloc((size_t)nb + 1, sizeof *loops);
    if (!loops)
        return cm_fail(im->st, CM_E_NOMEM, "out of memory");
    cm_err err = CM_OK;
    int nloops = 0, face_edges = 0, outer = -1;
    hbox vertex_loops = hbox_empty(); /* the points of its VERTEX_LOOPs */
    for (int b = 0; b < nb && err == CM_OK; b++) {
        const step_entity *be = ref_of(im, fe, step_item(bounds, b), "FACE_BOUND", "a bound");
        if (!be) { /* FACE_OUTER_BOUND is a FACE_BOUND subtype: its own name */
            const step_entity *ob = step_ref(f, step_item(bounds, b));
            if (ob && step_is(f, ob, "FACE_OUTER_BOUND")) {
                im->why[0] = 0;
                be = ob;
            }
        }
        if (!be) {
            err = CM_E_STEP;
            break;
        }
        int is_outer = step_is(f, be, "FACE_OUTER_BOUND");
        const step_val *bp = step_params(f, be, is_outer ? "FACE_OUTER_BOUND" : "FACE_BOUND");
        const step_entity *le = ref_of(im, be, step_item(bp, 1), NULL, "its loop");
        if (!le) {
            err = CM_E_STEP;
            break;
        }
        err = loop_curves(im, fe, le, &loops[nloops], &face_edges, &vertex_loops);
        if (err != CM_OK || loops[nloops].n == 0)
            continue;
        if (!bool_of(im, step_item(bp, 2), 1)) { /* the bound runs against its loop */
            hcurve_list *l = &loops[nloops];
            for (int i = 0; i < l->n / 2; i++) {
                hcurve t = l->c[i];
                l->c[i] = l->c[l->n - 1 - i];
                l->c[l->n - 1 - i] = t;
            }
            for (int i = 0; i < l->n; i++)
                hcurve_reverse(&l->c[i]);
        }
        if (is_outer && outer < 0)
            outer = nloops;
        nloops++;
    }
    if (err == CM_OK && outer > 0) { /* the outer loop first (brep.h) */
        hcurve_list t = loops[0];
        loops[0] = loops[outer];
        loops[outer] = t;
    }
    hbox box = hbox_empty();
    for (int l = 0; l < nloops; l++)
        for (int i = 0; i < loops[l].n; i++)
            hbox_add_curve(&box, &loops[l].c[i]);
    if (!vertex_loops.empty && nloops > 0) {
        hbox_add(&box, vertex_loops.lo);
        hbox_add(&box, vertex_loops.hi);
    }
    hsurf s = {0};
    int kind = 0;
    if (err == CM_OK && nloops > 0)
        err = surface_of(im, fe, step_item(p, 2), &box, loops, nloops, &s, &kind);
    else if (err == CM_OK) { /* no edge: the whole surface (a sphere, a torus), which must be closed */
        hbox none = hbox_empty();
        err = surface_of(im, fe, step_item(p, 2), &none, loops, nloops, &s, &kind);
        if (err == CM_OK && kind != SURF_SPHERE && kind != SURF_TORUS && kind != SURF_BSPLINE && kind != SURF_REVOLUTION)
            err = why(im, fe, "an unbounded surface without any edge");
    }
    im->ctrl_built += (long long)s.nu * s.nv;
    if (err == CM_OK && !im->why[0]) {
        double worst = 0;
        for (long i = 0; i < (long)s.nu * s.nv; i++)
            worst = fmax(worst, fmax(fabs(s.ctrl[i].x), fmax(fabs(s.ctrl[i].y), fabs(s.ctrl[i].z))));
        if (!(worst <= STEP_MAX_COORD_MM))
            err = why(im, fe, "its surface reaches %g mm, beyond +-%g mm", worst, STEP_MAX_COORD_MM);
    }
    brep_face face;
    memset(&face, 0, sizeof face);
    if (err == CM_OK) {
        /* into model space */
        hsurf_transform(&s, &im->xf);
        box = hbox_empty();
        for (int l = 0; l < nloops; l++)
            for (int i = 0; i < loops[l].n; i++) {
                hcurve_transform(&loops[l].c[i], &im->xf);
                hbox_add_curve(&box, &loops[l].c[i]);
            }
        face.src_de = fe->id;
        face.src_type = BREP_SRC_STEP_FACE;
        face.surf_type = kind;
        /* the face's normal is its surface's unless same_sense says otherwise; a SURFACE_OF_REVOLUTION
           is built with the curve along u and the angle along v (hsurf_revolve), ISO 10303-42 the
           other way round: its Su x Sv points against the standard's normal */
        face.flip = ((!bool_of(im, step_item(p, 3), 1)) != (flip != 0)) != (kind == SURF_REVOLUTION);
        face.shell = im->shell;
        face.instance = im->instance;
        face.top = im->top;
        /* the part (assembly steps): the solid or shell model; a face placed on its own is loose */
        face.owner = im->solid_id != fe->id ? im->solid_id : 0;
        face.product = im->product;
        face.first_loop = m->nloops;
        uint32_t rgb;
        if (colour_for(im, fe->id, &rgb) || (im->shell_id && colour_for(im, im->shell_id, &rgb)) ||
            (im->solid_id && colour_for(im, im->solid_id, &rgb))) {
            face.has_color = 1;
            face.rgb = rgb;
        }
        err = brep_add_surf(m, &s, &face.surf, im->st);
    }
    hsurf_free(&s);
    if (err == CM_OK && nloops == 0) {
        face.natural = 1;
        err = brep_add_rect_loop(m, face.surf, &box, im->st);
        face.nloops = err == CM_OK ? 1 : 0;
    }
    double diag = box.empty ? 0 : cm_dist(box.lo, box.hi);
    for (int l = 0; l < nloops && err == CM_OK; l++) {
        int first = m->nsegs;
        for (int i = 0; i < loops[l].n && err == CM_OK; i++) {
            if (brep_curve_length(&loops[l].c[i]) <= 1e-9 * diag)
                continue; /* a degenerate edge (exporters write them at poles) */
            err = brep_add_seg(m, &loops[l].c[i], im->st);
        }
        if (err == CM_OK && m->nsegs > first) {
            err = brep_add_loop(m, first, m->nsegs - first, im->st);
            face.nloops++;
        }
    }
    for (int l = 0; l <= nb; l++) /* all nb + 1 lists (calloc'd) */
        hcurve_list_free(&loops[l]);
    free(loops);
    if (err == CM_OK && face.nloops == 0)
        err = why(im, fe, "no usable boundary");
    if (err == CM_OK) {
        if (!box.empty) {
            hbox_add(&m->box, box.lo);
            hbox_add(&m->box, box.hi);
        }
        err = brep_add_face(m, &face, im->st);
    }
    return err;
}

static int same_map(const haffine *a, const haffine *b)
{
    double scale = 1 + cm_norm(a->t) + cm_norm(b->t);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (fabs(a->R[i][j] - b->R[i][j]) > 1e-9)
                return 0;
    return cm_dist(a->t, b->t) <= 1e-9 * scale;
}

/*
 * 1 if item k was already imported with the placement im->xf, else remembers it: exporters reach
 * one solid through several representations (a part's shape and a copy for validation properties,
 * a mapped item and the representation it maps) and it is one solid all the same.
 */
static int placed_before(importer *im, int k, cm_err *err)
{
    for (int i = im->placed_head[k]; i >= 0; i = im->placed_at[i].next)
        if (same_map(&im->placed_at[i].xf, &im->xf))
            return 1;
    if (im->nplaced == im->capplaced) {
        int cap = im->capplaced ? 2 * im->capplaced : 64;
        struct placed_item *q = realloc(im->placed_at, (size_t)cap * sizeof *q);
        if (!q) {
            *err = cm_fail(im->st, CM_E_NOMEM, "out of memory");
            return 1;
        }
        im->placed_at = q;
        im->capplaced = cap;
    }
    im->placed_at[im->nplaced].xf = im->xf;
    im->placed_at[im->nplaced].next = im->placed_head[k];
    im->placed_head[k] = im->nplaced++;
    return 0;
}

/* one face: built, or skipped with a warning naming it (the rest of the model goes on) */
static cm_err import_face(importer *im, const step_entity *fe, int flip)
{
    brep_model *m = im->m;
    if (m->nfaces >= STEP_MAX_PLACED_FACES)
        return step_error(im->f, fe->line, "the model places more than %d faces (limit %d)", STEP_MAX_PLACED_FACES,
                          STEP_MAX_PLACED_FACES);
    if (im->ctrl_built >= STEP_MAX_MODEL_CTRL)
        return step_error(im->f, fe->line, "the model's curves and surfaces have more than %lld control points "
                          "(limit %lld)", STEP_MAX_MODEL_CTRL, STEP_MAX_MODEL_CTRL);
    if (m->nsegs >= STEP_MAX_MODEL_PIECES)
        return step_error(im->f, fe->line, "the model's faces have more than %lld boundary curves (limit %lld)",
                          (long long)STEP_MAX_MODEL_PIECES, (long long)STEP_MAX_MODEL_PIECES);
    cm_err dup = CM_OK;
    if (placed_before(im, ent_index(im->f, fe), &dup)) {
        /* a shell listing one face twice (or two shells sharing it) at one placement: one face, not
           two on top of each other (nor a file that multiplies one big face by listing it) */
        if (dup != CM_OK)
            return dup;
        step_warn(im->f, fe->line, "face #%d is listed again at the same place; imported once", fe->id);
        return CM_OK;
    }
    int ns = m->nsurfs, nf = m->nfaces, nl = m->nloops, nsg = m->nsegs;
    hbox box = m->box;
    im->why[0] = 0;
    im->face_ordinal++;
    cm_err err = build_face(im, fe, flip);
    if (err == CM_OK) {
        im->stats->faces++;
        int k = ent_index(im->f, fe);
        if (!(im->done[k] & 1)) {
            im->done[k] |= 1;
            im->stats->face_entities++;
        }
        if (m->faces[m->nfaces - 1].has_color)
            im->stats->colored_faces++;
        im->f->ents[k].used = 1;
        return CM_OK;
    }
    brep_truncate(m, ns, nf, nl, nsg);
    m->box = box;
    if (err == CM_E_NOMEM)
        return step_error(im->f, fe->line, "out of memory importing face #%d", fe->id), err;
    char t[64];
    step_warn(im->f, fe->line, "face #%d (%s) skipped: %s", fe->id, tname(im, fe, t, sizeof t),
              im->why[0] ? im->why : cm_strerror(err));
    if (!im->first_fail[0]) {
        snprintf(im->first_fail, sizeof im->first_fail, "face #%d: %s", fe->id, im->why[0] ? im->why : cm_strerror(err));
        im->first_fail_line = fe->line;
    }
    m->faces_failed++;
    return CM_OK;
}

/* the faces of a shell (CLOSED_SHELL, OPEN_SHELL, or one of them oriented) */
static cm_err import_shell(importer *im, const step_entity *host, const step_val *v, int flip)
{
    step_file *f = im->f;
    const step_entity *sh = step_ref(f, v);
    const step_val *p = NULL;
    for (int k = 0; sh && k < STEP_MAX_CHAIN; k++) {
        if ((p = step_params(f, sh, "ORIENTED_CLOSED_SHELL")) || (p = step_params(f, sh, "ORIENTED_OPEN_SHELL"))) {
            if (!bool_of(im, step_item(p, 3), 1))
                flip = !flip;
            sh = step_ref(f, step_item(p, 2));
            continue;
        }
        break;
    }
    if (!sh || !((p = step_params(f, sh, "CLOSED_SHELL")) || (p = step_params(f, sh, "OPEN_SHELL")) ||
                 (p = step_params(f, sh, "CONNECTED_FACE_SET")))) {
        step_warn(f, host->line, "#%d: its shell is not a readable CLOSED_SHELL or OPEN_SHELL; left out", host->id);
        im->m->entities_failed++;
        return CM_OK;
    }
    f->ents[ent_index(f, sh)].used = 1;
    int saved = im->shell_id;
    im->shell_id = sh->id;
    im->shell = im->m->nshells++;
    const step_val *faces = step_item(p, 1);
    int n = faces && faces->kind == STEP_LIST ? faces->n : 0;
    cm_err err = CM_OK;
    for (int i = 0; i < n && err == CM_OK; i++) {
        const step_entity *fe = step_ref(f, step_item(faces, i));
        int fflip = flip;
        const step_val *op = fe ? step_params(f, fe, "ORIENTED_FACE") : NULL;
        if (op) {
            if (!bool_of(im, step_item(op, 3), 1))
                fflip = !fflip;
            fe = step_ref(f, step_item(op, 2));
        }
        if (!fe) {
            step_warn(f, sh->line, "#%d: face %d names no instance; left out", sh->id, i + 1);
            im->m->faces_failed++;
            continue;
        }
        err = import_face(im, fe, fflip);
    }
    im->shell_id = saved;
    return err;
}

/* a representation item that holds faces: a solid or a shell-based surface model (else nothing) */
static cm_err import_item(importer *im, const step_entity *it)
{
    const step_file *f = im->f;
    const step_val *p;
    cm_err err = CM_OK;
    int k = ent_index(f, it);
    if (!step_is(f, it, "MANIFOLD_SOLID_BREP") && !step_is(f, it, "FACETED_BREP") && !step_is(f, it, "BREP_WITH_VOIDS") &&
        !step_is(f, it, "SHELL_BASED_SURFACE_MODEL") && !step_is(f, it, "ADVANCED_FACE") && !step_is(f, it, "FACE_SURFACE"))
        return CM_OK;
    if (placed_before(im, k, &err))
        return err;
    im->solid_id = it->id;
    im->top++;
    if ((p = step_params(f, it, "MANIFOLD_SOLID_BREP")) || (p = step_params(f, it, "FACETED_BREP"))) {
        im->stats->solids += !(im->done[k] & 2);
        err = import_shell(im, it, step_item(p, 1), 0);
        const step_val *bv = step_params(f, it, "BREP_WITH_VOIDS");
        if (bv && err == CM_OK) { /* (complex form) voids after the outer shell */
            const step_val *voids = step_item(bv, bv->n - 1);
            for (int i = 0; voids && voids->kind == STEP_LIST && i < voids->n && err == CM_OK; i++)
                err = import_shell(im, it, step_item(voids, i), 0);
        }
    } else if ((p = step_params(f, it, "BREP_WITH_VOIDS"))) {
        im->stats->solids += !(im->done[k] & 2);
        err = import_shell(im, it, step_item(p, 1), 0);
        const step_val *voids = step_item(p, 2);
        for (int i = 0; voids && voids->kind == STEP_LIST && i < voids->n && err == CM_OK; i++)
            err = import_shell(im, it, step_item(voids, i), 0);
    } else if ((p = step_params(f, it, "SHELL_BASED_SURFACE_MODEL"))) {
        const step_val *shells = step_item(p, 1);
        for (int i = 0; shells && shells->kind == STEP_LIST && i < shells->n && err == CM_OK; i++) {
            im->stats->shells += !(im->done[k] & 2);
            err = import_shell(im, it, step_item(shells, i), 0);
        }
    } else if (step_is(f, it, "ADVANCED_FACE") || step_is(f, it, "FACE_SURFACE")) {
        im->shell = -1;
        err = import_face(im, it, 0);
    } else {
        im->solid_id = 0;
        return CM_OK;
    }
    im->done[k] |= 2;
    f->ents[k].used = 1;
    im->solid_id = 0;
    return err;
}

/* ---- units ---- */

static double si_prefix(const step_file *f, const step_val *v)
{
    static const struct {
        const char *name;
        double factor;
    } prefixes[] = {{"EXA", 1e18}, {"PETA", 1e15}, {"TERA", 1e12}, {"GIGA", 1e9}, {"MEGA", 1e6}, {"KILO", 1e3},
                    {"HECTO", 1e2}, {"DECA", 1e1}, {"DECI", 1e-1}, {"CENTI", 1e-2}, {"MILLI", 1e-3},
                    {"MICRO", 1e-6}, {"NANO", 1e-9}, {"PICO", 1e-12}, {"FEMTO", 1e-15}, {"ATTO", 1e-18}};
    for (size_t i = 0; i < sizeof prefixes / sizeof prefixes[0]; i++)
        if (step_val_is(f, v, prefixes[i].name))
            return prefixes[i].factor;
    return 1.0; /* $: no prefix */
}

/*
 * What one unit is worth: millimetres per length unit, or radians per angle unit (want_length 0);
 * 0 when it cannot be told.  SI units with their prefixes; conversion-based units (inch, foot,
 * degree) through their measure, a chain of at most STEP_MAX_CHAIN conversions.
 */
static double unit_factor(const step_file *f, const step_entity *u, int want_length)
{
    double scale = 1;
    for (int k = 0; u && k < STEP_MAX_CHAIN; k++) {
        const step_val *p;
        if ((p = step_params(f, u, "SI_UNIT"))) {
            /* complex form SI_UNIT(prefix, name); simple form SI_UNIT(dimensions, prefix, name) */
            const step_val *pre = p->n >= 3 ? step_item(p, 1) : step_item(p, 0);
            const step_val *name = p->n >= 3 ? step_item(p, 2) : step_item(p, 1);
            if (want_length && !step_val_is(f, name, "METRE"))
                return 0;
            if (!want_length && !step_val_is(f, name, "RADIAN"))
                return 0;
            return scale * si_prefix(f, pre) * (want_length ? 1000.0 : 1.0);
        }
        if ((p = step_params(f, u, "CONVERSION_BASED_UNIT"))) {
            const step_entity *mw = step_ref(f, step_item(p, 1));
            const step_val *mp = NULL;
            for (int i = 0; mw && i < mw->nparts && !mp; i++) { /* the part that holds (value, unit) */
                const step_val *q = &f->vals[f->parts[mw->first_part + i].params];
                if (q->n >= 2 && step_item(q, 1)->kind == STEP_REF)
                    mp = q;
            }
            double v;
            if (!mp || step_num(step_item(mp, 0), &v) || !(v > 0))
                return 0;
            scale *= v;
            u = step_ref(f, step_item(mp, 1));
            continue;
        }
        return 0;
    }
    return 0;
}

typedef struct rep_units {
    double mm, rad;   /* millimetres per length unit, radians per angle unit */
    double uncertainty_mm; /* the context's distance uncertainty, 0 if none */
    int has_length;
    int warned;       /* "no length unit" said once */
} rep_units;

static rep_units context_units(const step_file *f, const step_entity *ctx)
{
    rep_units u = {1.0, 1.0, 0.0, 0, 0};
    const step_val *ul = step_item(step_params(f, ctx, "GLOBAL_UNIT_ASSIGNED_CONTEXT"), 0);
    for (int i = 0; ul && ul->kind == STEP_LIST && i < ul->n; i++) {
        const step_entity *e = step_ref(f, step_item(ul, i));
        double v;
        if (step_is(f, e, "LENGTH_UNIT") && (v = unit_factor(f, e, 1)) > 0) {
            u.mm = v;
            u.has_length = 1;
        } else if (step_is(f, e, "PLANE_ANGLE_UNIT") && (v = unit_factor(f, e, 0)) > 0) {
            u.rad = v;
        }
    }
    const step_val *cl = step_item(step_params(f, ctx, "GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT"), 0);
    for (int i = 0; cl && cl->kind == STEP_LIST && i < cl->n; i++) {
        const step_entity *e = step_ref(f, step_item(cl, i));
        const step_val *p = step_params(f, e, "UNCERTAINTY_MEASURE_WITH_UNIT");
        double v, k;
        if (p && step_num(step_item(p, 0), &v) == 0 && v > 0 &&
            (k = unit_factor(f, step_ref(f, step_item(p, 1)), 1)) > 0 && u.uncertainty_mm == 0)
            u.uncertainty_mm = v * k;
    }
    return u;
}

/* ---- colours ---- */

/* the styles a colour is looked for through: surface styles (curve and point styles colour no face) */
static int style_path(const step_file *f, const step_entity *e)
{
    static const char *const kinds[] = {"PRESENTATION_STYLE_ASSIGNMENT", "PRESENTATION_STYLE_BY_CONTEXT",
                                        "SURFACE_STYLE_USAGE", "SURFACE_SIDE_STYLE", "SURFACE_STYLE_FILL_AREA",
                                        "FILL_AREA_STYLE", "FILL_AREA_STYLE_COLOUR", "SURFACE_STYLE_RENDERING",
                                        "SURFACE_STYLE_RENDERING_WITH_PROPERTIES"};
    for (size_t i = 0; i < sizeof kinds / sizeof kinds[0]; i++)
        if (step_is(f, e, kinds[i]))
            return 1;
    return 0;
}

static int colour_value(const step_file *f, const step_entity *e, uint32_t *rgb)
{
    const step_val *p = step_params(f, e, "COLOUR_RGB");
    if (p) {
        uint32_t v = 0;
        for (int i = 0; i < 3; i++) {
            double c;
            if (step_num(step_item(p, 1 + i), &c))
                return 0;
            c = c < 0 ? 0 : c > 1 ? 1 : c;
            v = (v << 8) | (uint32_t)lround(c * 255.0);
        }
        *rgb = v;
        return 1;
    }
    if ((p = step_params(f, e, "DRAUGHTING_PRE_DEFINED_COLOUR"))) {
        static const struct {
            const char *name;
            uint32_t rgb;
        } named[] = {{"red", 0xff0000}, {"green", 0x00ff00}, {"blue", 0x0000ff}, {"yellow", 0xffff00},
                     {"magenta", 0xff00ff}, {"cyan", 0x00ffff}, {"black", 0x000000}, {"white", 0xffffff}};
        char name[32];
        step_str(f, step_item(p, 0), name, sizeof name);
        for (size_t i = 0; i < sizeof named / sizeof named[0]; i++)
            if (strcasecmp(name, named[i].name) == 0) {
                *rgb = named[i].rgb;
                return 1;
            }
    }
    return 0;
}

/* push every instance the parameters of e name (walking the value arrays: no recursion) */
static int push_refs(const step_file *f, const step_entity *e, const step_entity **stack, int n, int cap)
{
    for (int i = 0; i < e->nparts; i++) {
        const step_val *p = &f->vals[f->parts[e->first_part + i].params];
        for (int k = 1; k < p->size && n < cap; k++)
            if (p[k].kind == STEP_REF) {
                const step_entity *t = step_by_id(f, p[k].ref);
                if (t)
                    stack[n++] = t;
            }
    }
    return n;
}

static int cmp_colour(const void *a, const void *b)
{
    const colour_of *x = a, *y = b;
    if (x->id != y->id)
        return x->id < y->id ? -1 : 1;
    return (x->order > y->order) - (x->order < y->order);
}

/* every styled item with a surface colour: (item #n, rgb), sorted by item then file order */
static cm_err gather_colours(importer *im)
{
    const step_file *f = im->f;
    int cap = 0;
    for (int i = 0; i < f->nents; i++) {
        const step_entity *e = &f->ents[i];
        const step_val *p = step_params(f, e, "STYLED_ITEM");
        if (!p)
            p = step_params(f, e, "OVER_RIDING_STYLED_ITEM");
        if (!p)
            continue;
        const step_val *item = step_item(p, 2);
        if (!item || item->kind != STEP_REF)
            continue;
        /* a bounded walk through the style tree */
        const step_entity *stack[64];
        int n = 0, visits = 0, found = 0;
        uint32_t rgb = 0;
        const step_val *styles = step_item(p, 1);
        for (int k = 0; styles && styles->kind == STEP_LIST && k < styles->n && n < 64; k++) {
            const step_entity *s = step_ref(f, step_item(styles, k));
            if (s)
                stack[n++] = s;
        }
        while (n > 0 && !found && visits++ < 256) {
            const step_entity *s = stack[--n];
            if (colour_value(f, s, &rgb))
                found = 1;
            else if (style_path(f, s))
                n = push_refs(f, s, stack, n, 64);
        }
        if (!found)
            continue;
        if (im->ncolours == cap) {
            cap = cap ? 2 * cap : 64;
            colour_of *q = realloc(im->colours, (size_t)cap * sizeof *q);
            if (!q)
                return cm_fail(im->st, CM_E_NOMEM, "out of memory");
            im->colours = q;
        }
        im->colours[im->ncolours++] = (colour_of){item->ref, i, rgb};
        f->ents[i].used = 1;
    }
    if (im->ncolours > 1)
        qsort(im->colours, (size_t)im->ncolours, sizeof *im->colours, cmp_colour);
    return CM_OK;
}

/* ---- the shape structure: representations, their spaces and placements ---- */

/* a representation's (name, items, context) when e is one (its part whose third parameter names a context) */
static const step_val *rep_params(const step_file *f, const step_entity *e, const step_entity **ctx)
{
    for (int i = 0; i < e->nparts; i++) {
        const step_part *pt = &f->parts[e->first_part + i];
        const step_val *p = &f->vals[pt->params];
        if (pt->name_len < 14 || strncasecmp(f->text + pt->name + pt->name_len - 14, "REPRESENTATION", 14) != 0 ||
            (pt->name_len == 28 && strncasecmp(f->text + pt->name, "DEFINITIONAL_REPRESENTATION", 28) == 0))
            continue;
        if (p->n < 3 || step_item(p, 1)->kind != STEP_LIST)
            continue;
        const step_entity *c = step_ref(f, step_item(p, 2));
        if (!c || !step_is(f, c, "GEOMETRIC_REPRESENTATION_CONTEXT"))
            continue; /* a parameter-space or presentation representation */
        if (ctx)
            *ctx = c;
        return p;
    }
    return NULL;
}

typedef struct structure {
    int *node_of;     /* per entity index: its representation node, -1 if not a representation */
    int *ent_of;      /* per node: entity index */
    int *up;          /* per node: union-find parent (identity relationships join spaces) */
    rep_units *units; /* per node */
    int *pd_of;       /* per node: #n of the PRODUCT_DEFINITION it represents (0 unknown) */
    int nnodes;
    placement_link *links;
    int nlinks, caplinks;
} structure;

static int find_group(structure *s, int n)
{
    while (s->up[n] != n) {
        s->up[n] = s->up[s->up[n]];
        n = s->up[n];
    }
    return n;
}

static int node_by_ref(const step_file *f, const structure *s, const step_val *v)
{
    const step_entity *e = step_ref(f, v);
    return e ? s->node_of[ent_index(f, e)] : -1;
}

/* the frame of placement v read in a node's units, as the map frame -> that node's space */
static cm_err placement_map(importer *im, const structure *s, int node, const step_entity *host, const step_val *v,
                            haffine *out)
{
    frame fr;
    im->mm = s->units[node].mm;
    im->rad = s->units[node].rad;
    cm_err err = axis2_at(im, host, v, &fr);
    if (err == CM_OK)
        *out = frame_map(&fr);
    return err;
}

static cm_err add_link(importer *im, structure *s, int parent, int child, const haffine *xf)
{
    if (s->nlinks == s->caplinks) {
        int cap = s->caplinks ? 2 * s->caplinks : 32;
        placement_link *q = realloc(s->links, (size_t)cap * sizeof *q);
        if (!q)
            return cm_fail(im->st, CM_E_NOMEM, "out of memory");
        s->links = q;
        s->caplinks = cap;
    }
    s->links[s->nlinks++] = (placement_link){parent, child, *xf};
    return CM_OK;
}

/* child -> parent map from two frames: the child's frame `a` lands on the parent's frame `b` */
static int frames_map(const haffine *a, const haffine *b, haffine *out)
{
    haffine ai;
    if (!haffine_invert(a, &ai))
        return -1;
    *out = haffine_compose(b, &ai);
    return 0;
}

/* a relationship between two representations: one space (no transformation) or a placement */
static cm_err relationship(importer *im, structure *s, const step_entity *e, const int *nauo_of)
{
    const step_file *f = im->f;
    const step_val *p = step_params(f, e, "REPRESENTATION_RELATIONSHIP");
    if (!p || p->n < 4)
        p = step_params(f, e, "SHAPE_REPRESENTATION_RELATIONSHIP");
    if (!p || p->n < 4)
        return CM_OK;
    int r1 = node_by_ref(f, s, step_item(p, 2)), r2 = node_by_ref(f, s, step_item(p, 3));
    if (r1 < 0 || r2 < 0)
        return CM_OK; /* between other kinds of representation */
    const step_val *tw = step_params(f, e, "REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION");
    f->ents[ent_index(f, e)].used = 1;
    if (!tw) {
        int a = find_group(s, r1), b = find_group(s, r2);
        if (a != b)
            s->up[a] = b;
        return CM_OK;
    }
    const step_entity *t = step_ref(f, step_item(tw, 0));
    const step_val *tp = t ? step_params(f, t, "ITEM_DEFINED_TRANSFORMATION") : NULL;
    haffine a, b, xf;
    im->why[0] = 0;
    if (!tp || placement_map(im, s, r1, t, step_item(tp, 2), &a) != CM_OK ||
        placement_map(im, s, r2, t, step_item(tp, 3), &b) != CM_OK || frames_map(&a, &b, &xf)) {
        step_warn(im->f, e->line, "#%d: its transformation cannot be read (%s); the part it places is left out",
                  e->id, im->why[0] ? im->why : "not an ITEM_DEFINED_TRANSFORMATION of two placements");
        im->m->entities_failed++;
        return CM_OK;
    }
    /*
     * rep_1 is the component placed into rep_2 (ISO 10303-21 assemblies, as Open CASCADE reads them)
     * unless the assembly usage it belongs to says rep_1 is the assembly: then the other way round.
     */
    int nauo = nauo_of[ent_index(f, e)];
    const step_entity *ne = nauo ? step_by_id(f, nauo) : NULL;
    const step_val *np = ne ? step_params(f, ne, "NEXT_ASSEMBLY_USAGE_OCCURRENCE") : NULL;
    const step_val *relating = np ? step_item(np, 3) : NULL;
    if (relating && relating->kind == STEP_REF && s->pd_of[r1] == relating->ref && s->pd_of[r2] != relating->ref) {
        haffine inv;
        if (!haffine_invert(&xf, &inv))
            return CM_OK;
        return add_link(im, s, r1, r2, &inv);
    }
    return add_link(im, s, r2, r1, &xf);
}

/* MAPPED_ITEM(name, REPRESENTATION_MAP(origin, representation), target) inside node's items */
static cm_err mapped_item(importer *im, structure *s, int node, const step_entity *it)
{
    step_file *f = im->f;
    const step_val *p = step_params(f, it, "MAPPED_ITEM");
    const step_entity *map = step_ref(f, step_item(p, 1));
    const step_val *mp = map ? step_params(f, map, "REPRESENTATION_MAP") : NULL;
    int child = mp ? node_by_ref(f, s, step_item(mp, 1)) : -1;
    haffine a, b, xf;
    im->why[0] = 0;
    if (child < 0 || placement_map(im, s, child, map, step_item(mp, 0), &a) != CM_OK ||
        placement_map(im, s, node, it, step_item(p, 2), &b) != CM_OK || frames_map(&a, &b, &xf)) {
        step_warn(f, it->line, "#%d MAPPED_ITEM: cannot be placed (%s); left out", it->id,
                  im->why[0] ? im->why : "its map is no REPRESENTATION_MAP of a shape representation");
        im->m->entities_failed++;
        return CM_OK;
    }
    f->ents[ent_index(f, it)].used = 1;
    return add_link(im, s, node, child, &xf);
}

static void structure_free(structure *s)
{
    free(s->node_of);
    free(s->ent_of);
    free(s->up);
    free(s->units);
    free(s->pd_of);
    free(s->links);
}

static cm_err build_structure(importer *im, structure *s)
{
    step_file *f = im->f;
    int n = f->nents;
    s->node_of = malloc((size_t)n * sizeof *s->node_of);
    s->ent_of = malloc((size_t)n * sizeof *s->ent_of);
    s->up = malloc((size_t)n * sizeof *s->up);
    s->units = malloc((size_t)n * sizeof *s->units);
    s->pd_of = calloc((size_t)n, sizeof *s->pd_of);
    int *nauo_of = calloc((size_t)n, sizeof *nauo_of);
    if (!s->node_of || !s->ent_of || !s->up || !s->units || !s->pd_of || !nauo_of) {
        free(nauo_of);
        return cm_fail(im->st, CM_E_NOMEM, "out of memory");
    }
    for (int i = 0; i < n; i++) {
        const step_entity *ctx = NULL;
        s->node_of[i] = -1;
        if (!rep_params(f, &f->ents[i], &ctx))
            continue;
        int k = s->nnodes++;
        s->node_of[i] = k;
        s->ent_of[k] = i;
        s->up[k] = k;
        s->units[k] = context_units(f, ctx);
    }
    /* which product each representation shapes, and which assembly usage each placement belongs to */
    for (int i = 0; i < n; i++) {
        const step_entity *e = &f->ents[i];
        const step_val *p;
        if ((p = step_params(f, e, "SHAPE_DEFINITION_REPRESENTATION"))) {
            const step_entity *pds = step_ref(f, step_item(p, 0));
            const step_val *pp = pds ? step_params(f, pds, "PRODUCT_DEFINITION_SHAPE") : NULL;
            int node = node_by_ref(f, s, step_item(p, 1));
            const step_val *def = pp ? step_item(pp, 2) : NULL;
            if (node >= 0 && def && def->kind == STEP_REF)
                s->pd_of[node] = def->ref;
        } else if ((p = step_params(f, e, "CONTEXT_DEPENDENT_SHAPE_REPRESENTATION"))) {
            const step_entity *rel = step_ref(f, step_item(p, 0));
            const step_entity *pds = step_ref(f, step_item(p, 1));
            const step_val *pp = pds ? step_params(f, pds, "PRODUCT_DEFINITION_SHAPE") : NULL;
            const step_val *def = pp ? step_item(pp, 2) : NULL;
            if (rel && def && def->kind == STEP_REF)
                nauo_of[ent_index(f, rel)] = def->ref;
        }
    }
    cm_err err = CM_OK;
    for (int i = 0; i < n && err == CM_OK; i++)
        err = relationship(im, s, &f->ents[i], nauo_of);
    free(nauo_of);
    for (int k = 0; k < s->nnodes && err == CM_OK; k++) {
        const step_val *items = step_item(rep_params(f, &f->ents[s->ent_of[k]], NULL), 1);
        for (int i = 0; i < items->n && err == CM_OK; i++) {
            const step_entity *it = step_ref(f, step_item(items, i));
            if (it && step_is(f, it, "MAPPED_ITEM"))
                err = mapped_item(im, s, k, it);
        }
    }
    return err;
}

typedef struct visit {
    int group;
    int depth;
    int instance;
    haffine xf;
    int product; /* the PRODUCT of the outermost occurrence being imported (its part's name: a
                    sub-assembly's, not its first part's), 0 at the top */
} visit;

/* the groups' members and the placements out of each group, by group (counting sorts: every
   visit touches its own members and links only) */
typedef struct group_index {
    int *member_start, *members; /* members[member_start[g] .. member_start[g + 1]) are group g's nodes */
    int *link_start, *links;     /* links[link_start[g] .. link_start[g + 1]) place children into group g */
} group_index;

static void group_index_free(group_index *gi)
{
    free(gi->member_start);
    free(gi->members);
    free(gi->link_start);
    free(gi->links);
}

static cm_err group_index_build(importer *im, structure *s, group_index *gi)
{
    int n = s->nnodes, nl = s->nlinks;
    gi->member_start = calloc((size_t)n + 2, sizeof *gi->member_start);
    gi->members = malloc(((size_t)n + 1) * sizeof *gi->members);
    gi->link_start = calloc((size_t)n + 2, sizeof *gi->link_start);
    gi->links = malloc(((size_t)nl + 1) * sizeof *gi->links);
    if (!gi->member_start || !gi->members || !gi->link_start || !gi->links)
        return cm_fail(im->st, CM_E_NOMEM, "out of memory");
    for (int k = 0; k < n; k++)
        gi->member_start[find_group(s, k) + 1]++;
    for (int l = 0; l < nl; l++)
        gi->link_start[find_group(s, s->links[l].parent) + 1]++;
    for (int g = 0; g < n; g++) {
        gi->member_start[g + 1] += gi->member_start[g];
        gi->link_start[g + 1] += gi->link_start[g];
    }
    int *fill = calloc((size_t)n + 1, sizeof *fill);
    if (!fill)
        return cm_fail(im->st, CM_E_NOMEM, "out of memory");
    for (int k = 0; k < n; k++) {
        int g = find_group(s, k);
        gi->members[gi->member_start[g] + fill[g]++] = k;
    }
    memset(fill, 0, ((size_t)n + 1) * sizeof *fill);
    for (int l = 0; l < nl; l++) {
        int g = find_group(s, s->links[l].parent);
        gi->links[gi->link_start[g] + fill[g]++] = l;
    }
    free(fill);
    return CM_OK;
}

/* import the faces of every representation in group v->group, placed by v */
/* the #n of the PRODUCT of PRODUCT_DEFINITION pd (through its PRODUCT_DEFINITION_FORMATION), 0 if
   there is none */
static int product_of(const step_file *f, int pd)
{
    const step_entity *e = pd ? step_by_id(f, pd) : NULL;
    const step_val *p = e ? step_params(f, e, "PRODUCT_DEFINITION") : NULL;
    const step_entity *pdf = p ? step_ref(f, step_item(p, 2)) : NULL;
    const step_val *q = pdf ? step_params(f, pdf, "PRODUCT_DEFINITION_FORMATION") : NULL;
    if (!q && pdf)
        q = step_params(f, pdf, "PRODUCT_DEFINITION_FORMATION_WITH_SPECIFIED_SOURCE");
    const step_entity *prod = q ? step_ref(f, step_item(q, 2)) : NULL;
    return prod && step_params(f, prod, "PRODUCT") ? prod->id : 0;
}

/* the product group g shapes: the first of its representations that says, 0 if none */
static int group_product(const step_file *f, const structure *s, const group_index *gi, int g)
{
    int product = 0;
    for (int q = gi->member_start[g]; q < gi->member_start[g + 1] && !product; q++)
        product = product_of(f, s->pd_of[gi->members[q]]);
    return product;
}

static cm_err import_group(importer *im, structure *s, const group_index *gi, const visit *v)
{
    step_file *f = im->f;
    cm_err err = CM_OK;
    /* the product that names its faces' part: the outermost occurrence's, else the one the group
       shapes */
    im->product = v->product ? v->product : group_product(f, s, gi, v->group);
    for (int q = gi->member_start[v->group]; q < gi->member_start[v->group + 1] && err == CM_OK; q++) {
        int k = gi->members[q];
        const step_entity *re = &f->ents[s->ent_of[k]];
        const step_val *items = step_item(rep_params(f, re, NULL), 1);
        im->mm = s->units[k].mm;
        im->rad = s->units[k].rad;
        if (im->m->resolution_mm == 0 && s->units[k].uncertainty_mm > 0)
            im->m->resolution_mm = s->units[k].uncertainty_mm;
        if (im->stats->unit_mm == 0)
            im->stats->unit_mm = s->units[k].mm;
        im->xf = v->xf;
        im->instance = v->instance;
        int faces = im->m->nfaces + im->m->faces_failed;
        for (int i = 0; i < items->n && err == CM_OK; i++) {
            const step_entity *it = step_ref(f, step_item(items, i));
            if (it)
                err = import_item(im, it);
        }
        if (im->m->nfaces + im->m->faces_failed > faces && !s->units[k].has_length && !s->units[k].warned) {
            step_warn(f, re->line, "#%d: its context declares no length unit; millimetres assumed", re->id);
            s->units[k].warned = 1;
        }
        f->ents[s->ent_of[k]].used = 1;
    }
    return err;
}

static cm_err push_visit(importer *im, visit **stack, int *n, int *cap, const visit *v)
{
    if (*n == *cap) {
        visit *q = realloc(*stack, (size_t)(*cap * 2) * sizeof *q);
        if (!q)
            return cm_fail(im->st, CM_E_NOMEM, "out of memory");
        *stack = q;
        *cap *= 2;
    }
    (*stack)[(*n)++] = *v;
    return CM_OK;
}

static cm_err walk(importer *im, structure *s)
{
    step_file *f = im->f;
    /* group indices: a group is named by its root node; groups placed by nothing are the roots */
    unsigned char *placed = calloc((size_t)s->nnodes + 1, 1);
    unsigned char *product = calloc((size_t)s->nnodes + 1, 1);
    int cap = 64, n = 0, next_instance = 0, pushed = 0;
    visit *stack = malloc((size_t)cap * sizeof *stack);
    group_index gi;
    memset(&gi, 0, sizeof gi);
    cm_err err = placed && product && stack ? group_index_build(im, s, &gi) : cm_fail(im->st, CM_E_NOMEM, "out of memory");
    for (int l = 0; err == CM_OK && l < s->nlinks; l++)
        placed[find_group(s, s->links[l].child)] = 1;
    /*
     * The roots: groups nothing places that shape a product (a SHAPE_DEFINITION_REPRESENTATION of
     * a product definition's shape).  A representation tied only to a property (a shape aspect's
     * "solid data", validation properties) repeats a part's solid where the part is not placed and
     * is no root.  A file that names no product at all (loose geometry) has every group as a root.
     */
    int any_product = 0;
    for (int k = 0; err == CM_OK && k < s->nnodes; k++)
        if (s->pd_of[k]) {
            product[find_group(s, k)] = 1;
            any_product = 1;
        }
    for (int k = s->nnodes - 1; k >= 0 && err == CM_OK; k--)
        if (find_group(s, k) == k && !placed[k] && (!any_product || product[k])) {
            visit root = {k, 0, 0, haffine_identity(), 0};
            err = push_visit(im, &stack, &n, &cap, &root);
        }
    /* every visit pushed counts against the budget (a representation mapping itself 800 times
       would otherwise be walked 800^16 ways, each looked at before it is refused) */
    while (n > 0 && err == CM_OK) {
        visit v = stack[--n];
        if (v.depth > 0)
            im->stats->placements++;
        err = import_group(im, s, &gi, &v);
        int first = gi.link_start[v.group], last = gi.link_start[v.group + 1];
        if (err == CM_OK && last > first && v.depth + 1 > STEP_MAX_ASSEMBLY_DEPTH) {
            const step_entity *re = &f->ents[s->ent_of[v.group]];
            step_warn(f, re->line, "#%d: places parts deeper than %d assembly levels (a cycle?); those left out",
                      re->id, STEP_MAX_ASSEMBLY_DEPTH);
            im->m->entities_failed++;
            continue;
        }
        for (int q = last - 1; q >= first && err == CM_OK; q--) {
            const placement_link *L = &s->links[gi.links[q]];
            if (++pushed > STEP_MAX_VISITS) {
                const step_entity *re = &f->ents[s->ent_of[v.group]];
                err = step_error(f, re->line, "the assembly places its parts more than %d times (limit %d; #%d "
                                 "places them again)", STEP_MAX_VISITS, STEP_MAX_VISITS, re->id);
                break;
            }
            visit c = {find_group(s, L->child), v.depth + 1, v.instance, haffine_compose(&v.xf, &L->xf), v.product};
            if (v.depth == 0) { /* an outermost placement: an instance the fold may send once */
                brep_instance in = {++next_instance, f->ents[s->ent_of[c.group]].id, c.xf};
                c.instance = in.id;
                c.product = group_product(f, s, &gi, c.group); /* (a sub-assembly: its own name) */
                err = brep_add_instance(im->m, &in, im->st);
            }
            if (err == CM_OK)
                err = push_visit(im, &stack, &n, &cap, &c);
        }
    }
    group_index_free(&gi);
    free(placed);
    free(product);
    free(stack);
    return err;
}

cm_err step_to_brep(step_file *f, brep_model *m, step_import_stats *stats, cm_status *st)
{
    memset(stats, 0, sizeof *stats);
    importer im;
    memset(&im, 0, sizeof im);
    im.f = f;
    im.m = m;
    im.stats = stats;
    im.st = st;
    im.mm = 1.0;
    im.rad = 1.0;
    im.xf = haffine_identity();
    im.shell = -1;
    m->box = hbox_empty();
    structure s;
    memset(&s, 0, sizeof s);
    im.done = calloc((size_t)f->nents + 1, 1);
    im.placed_head = malloc(((size_t)f->nents + 1) * sizeof *im.placed_head);
    if (im.placed_head)
        for (int i = 0; i < f->nents; i++)
            im.placed_head[i] = -1;
    cm_err err = im.done && im.placed_head ? gather_colours(&im) : cm_fail(st, CM_E_NOMEM, "out of memory");
    if (err == CM_OK)
        err = build_structure(&im, &s);
    if (err == CM_OK)
        err = walk(&im, &s);
    im.product = 0; /* (what follows no product shapes) */
    /* solids no product's shape reaches (a loose file): where they stand, in the units of the
       representation that holds them (else the first one's) */
    int *holder = err == CM_OK ? malloc(((size_t)f->nents + 1) * sizeof *holder) : NULL;
    if (err == CM_OK && !holder)
        err = cm_fail(st, CM_E_NOMEM, "out of memory");
    for (int i = 0; holder && i < f->nents; i++)
        holder[i] = -1;
    for (int k = 0; holder && k < s.nnodes; k++) {
        const step_val *items = step_item(rep_params(f, &f->ents[s.ent_of[k]], NULL), 1);
        for (int i = 0; i < items->n; i++) {
            const step_entity *it = step_ref(f, step_item(items, i));
            if (it && holder[ent_index(f, it)] < 0)
                holder[ent_index(f, it)] = k;
        }
    }
    for (int i = 0; i < f->nents && err == CM_OK; i++) {
        const step_entity *e = &f->ents[i];
        if (im.done[i] & 2)
            continue;
        if (!step_is(f, e, "MANIFOLD_SOLID_BREP") && !step_is(f, e, "BREP_WITH_VOIDS") &&
            !step_is(f, e, "SHELL_BASED_SURFACE_MODEL") && !step_is(f, e, "FACETED_BREP"))
            continue;
        step_warn(f, e->line, "#%d: a solid or shell model no product's shape places; imported where it stands",
                  e->id);
        im.xf = haffine_identity();
        im.instance = 0;
        int k = holder[i] >= 0 ? holder[i] : 0;
        im.mm = s.nnodes ? s.units[k].mm : 1.0;
        im.rad = s.nnodes ? s.units[k].rad : 1.0;
        err = import_item(&im, e);
    }
    free(holder);
    structure_free(&s);
    free(im.colours);
    free(im.done);
    free(im.placed_head);
    free(im.placed_at);
    if (err != CM_OK) {
        if (err == CM_E_NOMEM && !f->err[0])
            step_error(f, 0, "out of memory");
        return cm_fail(st, err, "step import");
    }
    if (stats->unit_mm == 0)
        stats->unit_mm = 1.0;
    if (m->nfaces == 0) {
        if (im.first_fail[0])
            return cm_fail(st, step_error(f, im.first_fail_line, "none of the file's %d faces could be read; the first: %s",
                                          m->faces_failed, im.first_fail),
                           "step import");
        return cm_fail(st, step_error(f, f->nlines, "no face found: no shape representation holds a solid, shell or face"),
                       "step import");
    }
    return CM_OK;
}
