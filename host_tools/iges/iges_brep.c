/*
 * iges_brep.c - IGES faces into the workstation B-rep (see iges_brep.h, brep/brep.h).
 *
 * Which entities are faces: every 144 trimmed surface, 143 bounded
 * surface, 510 face (through 186 solids and 514 shells), and every
 * surface entity that nothing references (an untrimmed patch).  Entities
 * inside a 308 subfigure definition are faces only through the 408
 * instances that place them.  "Referenced" means structurally (a 144's
 * base surface, a shell's faces, a definition's members...), not through
 * 402 groups or 406 properties, which annotate but do not own.
 */
#include "iges_brep.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brep/brep.h"
#include "cm/cm_project.h"
#include "iges/iges_file.h"
#include "iges/iges_geom.h"

#define MAX_INSTANCE_DEPTH 16

/* a saturating count of faces: more than any budget, still far from overflowing a sum of two */
#define FACE_COUNT_CAP (1LL << 60)

typedef struct importer {
    iges_file *f;
    brep_model *m;
    brep_import_stats *stats;
    cm_status *st;
    unsigned char *ref;   /* per entity index: structurally referenced */
    int instance;         /* current 408 instance counter (0 = top level) */
    long long *nfaces_of; /* per entity index: faces it places when imported (memo; -1 = not counted) */
    long long faces_tried; /* faces attempted so far (placed or skipped) */
    const iges_entity *face; /* the face being imported, and the curve pieces of its loops so far */
    int face_pieces;
    long long model_pieces; /* curve pieces built for every face placed so far */
    hbox *fbox;           /* per face (index into m->faces): box of its boundary */
    int *ford;            /* per face: its ordinal among the faces attempted (for messages) */
    int capf;
    int first_fail_line;  /* the first skipped face's warning, for the error when none is left */
    char first_fail[400];
    int include_blanked;  /* import blanked (hidden) entities too (--include-blanked) */
    long long placed_faces; /* faces the top-level entities place (check_face_budget) */
    int top;              /* the top-level entity being imported (its index): brep_face.top */
    int owner;            /* the entity naming the faces' part (brep_face.owner), 0 while none does */
} importer;

/*
 * Blanked entities (status blank = 01) are hidden: a CAD system does not show them, so they are
 * not part of the model a terminal is to show (ovt__asmo carries 6 blanked planes 3.6 m off the
 * part; Shelt_channel_5's 30 blanked subfigure instances place 24 000 of its 27 734 faces).  The
 * rule applies to what the import places as such: top-level entities and the members and nested
 * instances of a subfigure definition; a trimmed surface's base surface or a curve it uses is
 * reached through its owner and is routinely blanked by exporters, so its status is not read.
 */
static int hidden(const importer *im, const iges_entity *e)
{
    return !im->include_blanked && e->blank == 1;
}

static int ent_index(const iges_file *f, const iges_entity *e)
{
    return (int)(e - f->ents);
}

/*
 * Every loop below runs over parameters that exist: counts come from iges_count_or0 (clamped to
 * the entity's parameter count) and indices are compared with nparams before they are formed, so
 * a count of 2147483647 costs nothing and overflows nothing.
 */
static void mark_ref(importer *im, const iges_entity *e, int i)
{
    if (i < 0 || i >= e->nparams || e->params[i].kind != IGES_P_NUM)
        return;
    double v = e->params[i].num;
    if (!(fabs(v) < 1e9))
        return;
    const iges_entity *t = iges_by_de(im->f, (int)fabs(v));
    if (t)
        im->ref[ent_index(im->f, t)] = 1;
}

/* Mark every entity that another entity owns through its parameters. */
static void mark_references(importer *im)
{
    const iges_file *f = im->f;
    for (int k = 0; k < f->nents; k++) {
        const iges_entity *e = &f->ents[k];
        if (e->bad)
            continue;
        int n = e->nparams;
        switch (e->type) {
        case 102: { /* N, DE... */
            int cnt = iges_count_or0(e, 0);
            for (int i = 1; i < n && i <= cnt; i++)
                mark_ref(im, e, i);
            break;
        }
        case 118:
            mark_ref(im, e, 0);
            mark_ref(im, e, 1);
            break;
        case 120:
            mark_ref(im, e, 0);
            mark_ref(im, e, 1);
            break;
        case 122:
            mark_ref(im, e, 0);
            break;
        case 141: { /* TYPE PREF SPTR N (CRV SENSE K PS...)... */
            mark_ref(im, e, 2);
            int pos = 4, cnt = iges_count_or0(e, 3);
            for (int c = 0; c < cnt && pos + 2 < n; c++) {
                mark_ref(im, e, pos);
                int kk = iges_count_or0(e, pos + 2);
                for (int j = 0; j < kk && pos + 3 + j < n; j++)
                    mark_ref(im, e, pos + 3 + j);
                if (kk > n - pos - 3)
                    break;
                pos += 3 + kk;
            }
            break;
        }
        case 142:
            mark_ref(im, e, 1);
            mark_ref(im, e, 2);
            mark_ref(im, e, 3);
            break;
        case 143: {
            mark_ref(im, e, 1);
            int cnt = iges_count_or0(e, 2);
            for (int i = 0; i < cnt && i < n - 3; i++)
                mark_ref(im, e, 3 + i);
            break;
        }
        case 144: {
            mark_ref(im, e, 0);
            mark_ref(im, e, 3);
            int cnt = iges_count_or0(e, 2);
            for (int i = 0; i < cnt && i < n - 4; i++)
                mark_ref(im, e, 4 + i);
            break;
        }
        case 186: {
            mark_ref(im, e, 0);
            int cnt = iges_count_or0(e, 2);
            for (int i = 0; i < cnt && 3 + 2L * i < n; i++)
                mark_ref(im, e, 3 + 2 * i);
            break;
        }
        case 190: case 192: case 194: case 196: case 198:
            for (int i = 0; i < n && i < 5; i++) {
                int de = e->params[i].kind == IGES_P_NUM ? iges_to_int(e->params[i].num, 1, 99999999, 0) : 0;
                const iges_entity *t = iges_by_de(f, de);
                if (t && (t->type == 116 || t->type == 123))
                    im->ref[ent_index(f, t)] = 1;
            }
            break;
        case 308: {
            int cnt = iges_count_or0(e, 2);
            for (int i = 0; i < cnt && i < n - 3; i++)
                mark_ref(im, e, 3 + i);
            break;
        }
        case 408:
            mark_ref(im, e, 0);
            break;
        case 504: {
            int cnt = iges_count_or0(e, 0);
            for (int i = 0; i < cnt && 1 + 5L * i < n; i++) {
                mark_ref(im, e, 1 + 5 * i);
                mark_ref(im, e, 2 + 5 * i);
                mark_ref(im, e, 4 + 5 * i);
            }
            break;
        }
        case 508: {
            int pos = 1, cnt = iges_count_or0(e, 0);
            for (int c = 0; c < cnt && pos + 4 < n; c++) {
                mark_ref(im, e, pos + 1);
                int kk = iges_count_or0(e, pos + 4);
                for (int j = 0; j < kk && pos + 6 + 2L * j < n; j++)
                    mark_ref(im, e, pos + 6 + 2 * j);
                if (kk > (n - pos - 5) / 2)
                    break;
                pos += 5 + 2 * kk;
            }
            break;
        }
        case 510: {
            mark_ref(im, e, 0);
            int cnt = iges_count_or0(e, 1);
            for (int i = 0; i < cnt && i < n - 3; i++)
                mark_ref(im, e, 3 + i);
            break;
        }
        case 514: {
            int cnt = iges_count_or0(e, 0);
            for (int i = 0; i < cnt && 1 + 2L * i < n; i++)
                mark_ref(im, e, 1 + 2 * i);
            break;
        }
        default:
            break;
        }
    }
}

/* ---- colours ---- */

static int face_color(importer *im, const iges_entity *e, uint32_t *rgb)
{
    static const uint32_t palette[9] = {0, 0x000000, 0xff0000, 0x00ff00, 0x0000ff,
                                        0xffff00, 0xff00ff, 0x00ffff, 0xffffff};
    if (e->color > 0 && e->color <= 8) {
        *rgb = palette[e->color];
        return 1;
    }
    if (e->color < 0) {
        const iges_entity *c = iges_by_de(im->f, -e->color);
        if (c && c->type == 314 && !c->bad) {
            uint32_t v = 0;
            for (int i = 0; i < 3; i++) {
                double pc = iges_num_or(c, i, 0.0);
                pc = pc < 0 ? 0 : pc > 100 ? 100 : pc;
                v = (v << 8) | (uint32_t)lround(pc * 2.55);
            }
            im->f->ents[ent_index(im->f, c)].used = 1;
            *rgb = v;
            return 1;
        }
    }
    return 0;
}

/* ---- faces ---- */

/* warn that face number `ordinal` (entity e) is skipped, why; the first such warning is kept for
 * the error when no face is left.  model_load.c recognises the "face N (TYPE, DE d) skipped: " form. */
static void warn_skipped(importer *im, const iges_entity *e, int ordinal, const char *why)
{
    iges_warn(im->f, e->pd_line, "face %d (%s, DE %d) skipped: %s", ordinal, iges_type_name(e->type), e->de, why);
    if (im->first_fail[0] == 0) {
        snprintf(im->first_fail, sizeof im->first_fail, "face %d (%s, DE %d): %s", ordinal, iges_type_name(e->type),
                 e->de, why);
        im->first_fail_line = e->pd_line;
    }
    im->m->faces_failed++;
}

/* f->err without its "line N: entity T (name, DE d): " prefix when it is about entity e (a warning
   that names e already says so) */
static const char *bare_error(const iges_file *f, const iges_entity *e)
{
    char prefix[160];
    snprintf(prefix, sizeof prefix, "line %d: entity %d (%s, DE %d): ", e->pd_line, e->type, iges_type_name(e->type),
             e->de);
    size_t n = strlen(prefix);
    return strncmp(f->err, prefix, n) == 0 ? f->err + n : f->err;
}

/* forget an error already reported as a warning (the import goes on without what it concerned) */
static void forget_error(importer *im)
{
    im->f->err[0] = 0;
    im->f->err_line = 0;
    if (im->st)
        cm_status_init(im->st);
}

/* skip a face: warn with the reason already in f->err (every failure path names its entity; the
 * status is the fallback) and forget the error */
static void face_failed(importer *im, const iges_entity *e, int nsurfs, int nfaces, int nloops, int nsegs)
{
    brep_truncate(im->m, nsurfs, nfaces, nloops, nsegs);
    char why[512];
    if (im->f->err[0])
        snprintf(why, sizeof why, "%s", im->f->err);
    else
        snprintf(why, sizeof why, "line %d: %s (%s)", e->pd_line,
                 cm_strerror(im->st ? im->st->code : CM_E_IGES), im->st && im->st->where ? im->st->where : "?");
    warn_skipped(im, e, im->m->nfaces + im->m->faces_failed + 1, why);
    im->f->err[0] = 0;
    im->f->err_line = 0;
    if (im->st)
        cm_status_init(im->st);
}

static cm_vec3 curve_end(const hcurve *c, int at_end)
{
    double t0, t1;
    hcurve_domain(c, &t0, &t1);
    cm_curve v = hcurve_view(c);
    cm_vec3 d[1] = {{0, 0, 0}};
    if (cm_curve_eval(&v, at_end ? t1 : t0, 0, d, NULL) != CM_OK)
        return cm_v3(0, 0, 0);
    return d[0];
}

/*
 * Some exporters (ICEM among them) write a loop's curves out of order and
 * some of them backwards: the 102 composite of a trimmed surface lists the
 * outer boundary, then the pieces of a notch in any order.  When consecutive
 * curves do not meet (gap above tol) the loop is chained again by its end
 * points, greedily from its first curve, reversing curves as needed, and
 * kept only if that narrows the widest gap; returns 1 if it was reordered.
 */
static int chain_loop(hcurve_list *L, double tol)
{
    int n = L->n;
    if (n < 2)
        return 0;
    cm_vec3 *ends = malloc((size_t)n * 2 * sizeof *ends);
    int *order = malloc((size_t)n * sizeof *order);
    unsigned char *rev = calloc((size_t)n, 1);
    hcurve *tmp = malloc((size_t)n * sizeof *tmp);
    int changed = 0;
    if (!ends || !order || !rev || !tmp)
        goto done;
    for (int k = 0; k < n; k++) {
        ends[2 * k] = curve_end(&L->c[k], 0);
        ends[2 * k + 1] = curve_end(&L->c[k], 1);
        order[k] = k;
    }
    /* gap after position i: end of order[i] (start if reversed) to start of order[i+1] */
#define CHAIN_END(i) ends[2 * order[i] + (rev[i] ? 0 : 1)]
#define CHAIN_START(i) ends[2 * order[i] + (rev[i] ? 1 : 0)]
    double before = 0;
    for (int i = 0; i < n; i++) {
        double d = cm_dist(ends[2 * i + 1], ends[2 * ((i + 1) % n)]);
        before = d > before ? d : before;
    }
    if (before <= tol)
        goto done;
    for (int i = 0; i + 1 < n; i++) {
        cm_vec3 end = CHAIN_END(i);
        int best = i + 1, best_rev = 0;
        double best_d = HUGE_VAL;
        for (int j = i + 1; j < n; j++)
            for (int r = 0; r < 2; r++) {
                double d = cm_dist(end, ends[2 * order[j] + r]);
                if (d < best_d) {
                    best_d = d;
                    best = j;
                    best_rev = r; /* matched its end point: run it backwards */
                }
            }
        int t = order[i + 1];
        order[i + 1] = order[best];
        order[best] = t;
        rev[i + 1] = (unsigned char)best_rev;
    }
    double after = 0;
    for (int i = 0; i < n; i++) {
        double d = cm_dist(CHAIN_END(i), CHAIN_START((i + 1) % n));
        after = d > after ? d : after;
    }
#undef CHAIN_END
#undef CHAIN_START
    if (!(after < before))
        goto done;
    for (int i = 0; i < n; i++) {
        tmp[i] = L->c[order[i]];
        if (rev[i])
            hcurve_reverse(&tmp[i]);
    }
    memcpy(L->c, tmp, (size_t)n * sizeof *tmp);
    changed = 1;
done:
    free(ends);
    free(order);
    free(rev);
    free(tmp);
    return changed;
}

/*
 * Add a face from its loops (lists of model-space curves in loop order;
 * loops[0] outer unless `natural`), building the surface over their extent.
 * Moves the curves out of the lists.
 */
static cm_err add_face(importer *im, const iges_entity *fe, int surf_de, const haffine *surf_parent,
                       hcurve_list *loops, int nloops, int natural, int flip, int shell)
{
    brep_model *m = im->m;
    hbox box = hbox_empty();
    for (int l = 0; l < nloops; l++)
        for (int i = 0; i < loops[l].n; i++)
            hbox_add_curve(&box, &loops[l].c[i]);
    hsurf s = {0};
    cm_err e = iges_surface(im->f, surf_de, surf_parent, &box, &s, im->st);
    if (e != CM_OK)
        return e;
    brep_face face;
    memset(&face, 0, sizeof face);
    face.src_de = fe->de;
    face.src_type = fe->type;
    face.surf_type = iges_by_de(im->f, surf_de) ? iges_by_de(im->f, surf_de)->type : 0;
    face.flip = flip;
    face.shell = shell;
    face.instance = im->instance;
    face.top = im->top;
    face.owner = im->owner;
    face.natural = natural;
    face.first_loop = m->nloops;
    uint32_t rgb;
    if (face_color(im, fe, &rgb) || face_color(im, iges_by_de(im->f, surf_de), &rgb)) {
        face.has_color = 1;
        face.rgb = rgb;
    }
    if ((e = brep_add_surf(m, &s, &face.surf, im->st)) != CM_OK)
        return e;
    if (natural) {
        if ((e = brep_add_rect_loop(m, face.surf, &box, im->st)) != CM_OK)
            return e;
        face.nloops = 1;
    }
    double diag = box.empty ? 0 : cm_dist(box.lo, box.hi);
    for (int l = 0; l < nloops; l++) {
        if (chain_loop(&loops[l], 1e-5 * diag))
            iges_warn(im->f, fe->pd_line, "DE %d: loop %d lists its curves out of order; chained by their end points",
                      fe->de, l + 1);
        int first = m->nsegs;
        for (int i = 0; i < loops[l].n; i++) {
            if (brep_curve_length(&loops[l].c[i]) <= 1e-9 * diag)
                continue; /* degenerate boundary piece (exporters write them at poles) */
            if ((e = brep_add_seg(m, &loops[l].c[i], im->st)) != CM_OK)
                return e;
        }
        if (m->nsegs == first) {
            iges_warn(im->f, fe->pd_line, "DE %d: loop %d has no non-degenerate curve; dropped", fe->de, l + 1);
            continue;
        }
        if ((e = brep_add_loop(m, first, m->nsegs - first, im->st)) != CM_OK)
            return e;
        face.nloops++;
    }
    if (face.nloops == 0)
        return iges_entity_error(im->f, fe, "no usable boundary"), cm_fail(im->st, CM_E_IGES, "face");
    /* per-face box and ordinal, for the far-away check at the end (index = the face's) */
    if (m->nfaces >= im->capf) {
        int cap = im->capf ? 2 * im->capf : 256;
        hbox *nb = realloc(im->fbox, (size_t)cap * sizeof *nb);
        if (nb)
            im->fbox = nb;
        int *no = realloc(im->ford, (size_t)cap * sizeof *no);
        if (no)
            im->ford = no;
        if (!nb || !no)
            return iges_nomem(im->f, fe->pd_line, "importing face DE %d", fe->de),
                   cm_fail(im->st, CM_E_NOMEM, "out of memory");
        im->capf = cap;
    }
    im->fbox[m->nfaces] = box;
    im->ford[m->nfaces] = m->nfaces + m->faces_failed + 1;
    if (!box.empty) {
        hbox_add(&m->box, box.lo);
        hbox_add(&m->box, box.hi);
    }
    return brep_add_face(m, &face, im->st);
}

long long iges_max_placed_faces = IGES_MAX_PLACED_FACES_DEFAULT;

/*
 * Budgets of one face (chaining a loop is quadratic in its pieces, and each piece built costs):
 * room for `n` more pieces in a loop that holds `have`, and for `built` more pieces built for the
 * face (a B-rep edge builds its whole curve to use one piece); else an error naming the face.
 * `n` or `built` < 0: the count could not be allocated.
 */
static cm_err piece_room(importer *im, int have, int n, int built)
{
    if (n < 0 || built < 0)
        return iges_nomem(im->f, im->face->pd_line, "counting the curve pieces of face DE %d", im->face->de),
               cm_fail(im->st, CM_E_NOMEM, "out of memory");
    if (n > IGES_MAX_CURVE_PIECES || built > IGES_MAX_CURVE_PIECES)
        return CM_OK; /* one curve past its own budget: iges_curve refuses it, naming the curve */
    if ((long long)have + n > IGES_MAX_CURVE_PIECES)
        return iges_entity_error(im->f, im->face, "a loop has more than %d curve pieces (limit %d per loop)",
                                 IGES_MAX_CURVE_PIECES, IGES_MAX_CURVE_PIECES),
               cm_fail(im->st, CM_E_LIMIT, "loop pieces");
    if ((long long)im->face_pieces + built > IGES_MAX_FACE_PIECES)
        return iges_entity_error(im->f, im->face, "its loops have more than %d curve pieces (limit %d per face)",
                                 IGES_MAX_FACE_PIECES, IGES_MAX_FACE_PIECES),
               cm_fail(im->st, CM_E_LIMIT, "face pieces");
    /* the whole model's: placed faces times their pieces is what the import's time grows with (a
       35 KB subfigure DAG placing 2^18 faces of 10^4 pieces each ran for minutes) */
    if (im->model_pieces + built > IGES_MAX_MODEL_PIECES) {
        im->f->over_budget = 1;
        return iges_entity_error(im->f, im->face,
                                 "the model's faces have more than %lld curve pieces (limit %lld per model)",
                                 IGES_MAX_MODEL_PIECES, IGES_MAX_MODEL_PIECES),
               cm_fail(im->st, CM_E_LIMIT, "model pieces");
    }
    im->face_pieces += built;
    im->model_pieces += built;
    return CM_OK;
}

/* model-space curves of one boundary entity into a list; reversed when `reverse` */
static cm_err boundary_curves(importer *im, int de, const haffine *map, int reverse, hcurve_list *out)
{
    int n = iges_curve_pieces(im->f, de);
    cm_err room = piece_room(im, out->n, n, n);
    if (room != CM_OK)
        return room;
    hcurve_list tmp = {0};
    cm_err e = iges_curve(im->f, de, map, &tmp, im->st);
    if (e == CM_OK && reverse) {
        for (int i = 0; i < tmp.n / 2; i++) {
            hcurve t = tmp.c[i];
            tmp.c[i] = tmp.c[tmp.n - 1 - i];
            tmp.c[tmp.n - 1 - i] = t;
        }
        for (int i = 0; i < tmp.n; i++)
            hcurve_reverse(&tmp.c[i]);
    }
    for (int i = 0; i < tmp.n && e == CM_OK; i++)
        e = hcurve_list_push(out, &tmp.c[i], im->st);
    hcurve_list_free(&tmp);
    return e;
}

static cm_err face_144(importer *im, const iges_entity *e, const haffine *parent)
{
    iges_file *f = im->f;
    haffine map;
    int pts, n1, n2, pto;
    if (iges_entity_xform(f, e, &map) || iges_ptr(f, e, 0, 0, &pts) || iges_int(f, e, 1, &n1) ||
        iges_int(f, e, 2, &n2))
        return cm_fail(im->st, CM_E_IGES, "144");
    map = haffine_compose(parent, &map);
    if (n2 < 0 || n2 > 100000 || 4 + n2 > e->nparams)
        return iges_entity_error(f, e, "%d inner boundaries do not fit its %d parameters", n2, e->nparams),
               cm_fail(im->st, CM_E_IGES, "144");
    int nl = 1 + n2;
    hcurve_list *loops = calloc((size_t)nl, sizeof *loops);
    if (!loops)
        return cm_fail(im->st, CM_E_NOMEM, "out of memory");
    cm_err err = CM_OK;
    if (n1 != 0) {
        if (iges_ptr(f, e, 3, 0, &pto))
            err = cm_fail(im->st, CM_E_IGES, "144");
        else
            err = boundary_curves(im, pto, &map, 0, &loops[0]);
    }
    for (int i = 0; i < n2 && err == CM_OK; i++) {
        int pti;
        if (iges_ptr(f, e, 4 + i, 0, &pti))
            err = cm_fail(im->st, CM_E_IGES, "144");
        else
            err = boundary_curves(im, pti, &map, 0, &loops[1 + i]);
    }
    if (err == CM_OK)
        err = add_face(im, e, pts, &map, n1 != 0 ? loops : loops + 1, n1 != 0 ? nl : n2, n1 == 0, 0, -1);
    for (int i = 0; i < nl; i++)
        hcurve_list_free(&loops[i]);
    free(loops);
    if (err == CM_OK)
        im->stats->faces_144++;
    return err;
}

static cm_err face_143(importer *im, const iges_entity *e, const haffine *parent)
{
    iges_file *f = im->f;
    haffine map;
    int sptr, n;
    if (iges_entity_xform(f, e, &map) || iges_ptr(f, e, 1, 0, &sptr) || iges_int(f, e, 2, &n))
        return cm_fail(im->st, CM_E_IGES, "143");
    map = haffine_compose(parent, &map);
    if (n < 1 || n > 100000 || 3 + n > e->nparams)
        return iges_entity_error(f, e, "%d boundaries do not fit its %d parameters", n, e->nparams),
               cm_fail(im->st, CM_E_IGES, "143");
    hcurve_list *loops = calloc((size_t)n, sizeof *loops);
    if (!loops)
        return cm_fail(im->st, CM_E_NOMEM, "out of memory");
    cm_err err = CM_OK;
    for (int b = 0; b < n && err == CM_OK; b++) {
        int bde;
        if (iges_ptr(f, e, 3 + b, 0, &bde)) {
            err = cm_fail(im->st, CM_E_IGES, "143");
            break;
        }
        const iges_entity *bd = iges_by_de(f, bde);
        haffine bmap;
        int nc;
        if (bd->type != 141 || bd->bad || iges_entity_xform(f, bd, &bmap) || iges_int(f, bd, 3, &nc)) {
            err = iges_entity_error(f, e, "boundary %d (DE %d) is not a readable 141 boundary", b + 1, bde);
            break;
        }
        bmap = haffine_compose(&map, &bmap);
        int pos = 4;
        for (int c = 0; c < nc && err == CM_OK; c++) {
            int crv, sense, kk;
            if (iges_ptr(f, bd, pos, 0, &crv) || iges_int(f, bd, pos + 1, &sense) || iges_int(f, bd, pos + 2, &kk)) {
                err = cm_fail(im->st, CM_E_IGES, "141");
                break;
            }
            if (kk < 0 || kk > bd->nparams - pos - 3) { /* before pos + 3 + kk can overflow */
                err = iges_entity_error(f, bd, "curve %d: %d parameter-space curves do not fit its %d parameters",
                                        c + 1, kk, bd->nparams);
                break;
            }
            err = boundary_curves(im, crv, &bmap, sense == 2, &loops[b]);
            pos += 3 + kk;
        }
        if (err == CM_OK)
            f->ents[ent_index(f, bd)].used = 1;
    }
    if (err == CM_OK)
        err = add_face(im, e, sptr, &map, loops, n, 0, 0, -1);
    for (int i = 0; i < n; i++)
        hcurve_list_free(&loops[i]);
    free(loops);
    if (err == CM_OK)
        im->stats->faces_143++;
    return err;
}

/* vertex `idx` (1-based) of a 502 vertex list, in model space */
static int vertex_502(importer *im, const iges_entity *host, int de, int idx, const haffine *map, cm_vec3 *out)
{
    const iges_entity *v = iges_by_de(im->f, de);
    haffine vm;
    if (!v || v->type != 502 || v->bad || iges_entity_xform(im->f, v, &vm)) {
        iges_entity_error(im->f, host, "vertex list DE %d is not a readable 502", de);
        return -1;
    }
    int n = iges_int_or(v, 0, 0);
    if (idx < 1 || idx > n || n > (v->nparams - 1) / 3) { /* not 1 + 3 * n > nparams: n may be 2147483647 */
        iges_entity_error(im->f, host, "vertex %d of list DE %d does not exist", idx, de);
        return -1;
    }
    vm = haffine_compose(map, &vm);
    cm_vec3 p = cm_v3(iges_num_or(v, 1 + 3 * (idx - 1), (double)NAN), iges_num_or(v, 2 + 3 * (idx - 1), (double)NAN),
                      iges_num_or(v, 3 + 3 * (idx - 1), (double)NAN));
    if (!cm_finite3(p)) {
        iges_entity_error(im->f, v, "vertex %d is not numeric", idx);
        return -1;
    }
    im->f->ents[ent_index(im->f, v)].used = 1;
    *out = haffine_apply(&vm, p);
    return 0;
}

/*
 * Edge `ndx` of a 504 edge list: its curve cut between its two vertices
 * (the curve may extend beyond them), oriented start -> terminate vertex.
 * `have`: the curves already in its loop (for the loop's budget).
 */
static cm_err edge_504(importer *im, const iges_entity *loop, int list_de, int ndx, const haffine *map, int have,
                       hcurve *out)
{
    iges_file *f = im->f;
    const iges_entity *el = iges_by_de(f, list_de);
    haffine em;
    if (!el || el->type != 504 || el->bad || iges_entity_xform(f, el, &em))
        return iges_entity_error(f, loop, "edge list DE %d is not a readable 504", list_de),
               cm_fail(im->st, CM_E_IGES, "504");
    em = haffine_compose(map, &em);
    int n = iges_int_or(el, 0, 0);
    if (ndx < 1 || ndx > n || n > (el->nparams - 1) / 5) /* not 1 + 5 * n > nparams: no overflow */
        return iges_entity_error(f, loop, "edge %d of list DE %d does not exist", ndx, list_de),
               cm_fail(im->st, CM_E_IGES, "504");
    int o = 1 + 5 * (ndx - 1), crv, svp, sv, tvp, tv;
    if (iges_ptr(f, el, o, 0, &crv) || iges_ptr(f, el, o + 1, 0, &svp) || iges_int(f, el, o + 2, &sv) ||
        iges_ptr(f, el, o + 3, 0, &tvp) || iges_int(f, el, o + 4, &tv))
        return cm_fail(im->st, CM_E_IGES, "504");
    cm_vec3 A, B;
    if (vertex_502(im, el, svp, sv, &em, &A) || vertex_502(im, el, tvp, tv, &em, &B))
        return cm_fail(im->st, CM_E_IGES, "504");
    cm_err room = piece_room(im, have, 1, iges_curve_pieces(f, crv)); /* one piece of it goes into the loop */
    if (room != CM_OK)
        return room;
    hcurve_list pieces = {0};
    hcurve whole = {0};
    cm_err e = iges_curve(f, crv, &em, &pieces, im->st);
    if (e == CM_OK && pieces.n == 1) {
        whole = pieces.c[0];
        memset(&pieces.c[0], 0, sizeof whole);
    } else if (e == CM_OK) {
        /* several pieces: keep them as one curve by cutting each end piece; rare in practice */
        e = hcurve_copy(&pieces.c[0], &whole, im->st);
        if (e == CM_OK && pieces.n > 1)
            iges_warn(f, loop->pd_line, "edge %d of list DE %d is a %d-piece composite: only its first piece is used",
                      ndx, list_de, pieces.n);
    }
    hcurve_list_free(&pieces);
    if (e != CM_OK) {
        hcurve_free(&whole);
        return e;
    }
    f->ents[ent_index(f, el)].used = 1;
    cm_curve v = hcurve_view(&whole);
    double t0, t1, ta, tb, da, db;
    hcurve_domain(&whole, &t0, &t1);
    if (cm_curve_project(&v, t0, t1, A, &ta, &da, im->st) != CM_OK ||
        cm_curve_project(&v, t0, t1, B, &tb, &db, im->st) != CM_OK) {
        hcurve_free(&whole);
        return iges_entity_error(f, loop, "cannot place the vertices of edge %d on its curve", ndx),
               cm_fail(im->st, CM_E_IGES, "504");
    }
    double span = t1 - t0, eps = 1e-9 * span;
    int closed_edge = cm_dist(A, B) <= 1e-9 * (1.0 + cm_norm(A));
    if (closed_edge || (fabs(ta - t0) <= eps && fabs(tb - t1) <= eps)) {
        *out = whole; /* the whole curve (a closed edge runs all the way round) */
        return CM_OK;
    }
    if (fabs(ta - t1) <= eps && fabs(tb - t0) <= eps) {
        hcurve_reverse(&whole);
        *out = whole;
        return CM_OK;
    }
    int rev = ta > tb;
    double lo = rev ? tb : ta, hi = rev ? ta : tb;
    if (!(hi - lo > eps)) {
        hcurve_free(&whole);
        return iges_entity_error(f, loop, "edge %d: both vertices project to the same point of its curve", ndx),
               cm_fail(im->st, CM_E_IGES, "504");
    }
    if (lo - t0 <= eps && t1 - hi <= eps) {
        *out = whole;
    } else {
        e = hcurve_subrange(&whole, lo, hi, out, im->st);
        hcurve_free(&whole);
        if (e != CM_OK)
            return e;
    }
    if (rev)
        hcurve_reverse(out);
    return CM_OK;
}

static cm_err face_510(importer *im, const iges_entity *e, const haffine *parent, int shell, int flip)
{
    iges_file *f = im->f;
    haffine map;
    int surf, n, of;
    if (iges_entity_xform(f, e, &map) || iges_ptr(f, e, 0, 0, &surf) || iges_int(f, e, 1, &n))
        return cm_fail(im->st, CM_E_IGES, "510");
    of = iges_int_or(e, 2, 1);
    map = haffine_compose(parent, &map);
    if (n < 1 || n > 100000 || 3 + n > e->nparams)
        return iges_entity_error(f, e, "%d loops do not fit its %d parameters", n, e->nparams),
               cm_fail(im->st, CM_E_IGES, "510");
    if (of != 1)
        iges_warn(f, e->pd_line, "face DE %d does not mark its first loop as outer; the outer loop is decided "
                                 "from the geometry", e->de);
    hcurve_list *loops = calloc((size_t)n, sizeof *loops);
    if (!loops)
        return cm_fail(im->st, CM_E_NOMEM, "out of memory");
    cm_err err = CM_OK;
    for (int l = 0; l < n && err == CM_OK; l++) {
        int lde;
        if (iges_ptr(f, e, 3 + l, 0, &lde)) {
            err = cm_fail(im->st, CM_E_IGES, "510");
            break;
        }
        const iges_entity *lp = iges_by_de(f, lde);
        haffine lmap;
        int ne;
        if (lp->type != 508 || lp->bad || iges_entity_xform(f, lp, &lmap) || iges_int(f, lp, 0, &ne) || ne < 1) {
            err = iges_entity_error(f, e, "loop %d (DE %d) is not a readable 508 loop", l + 1, lde);
            break;
        }
        lmap = haffine_compose(&map, &lmap);
        int pos = 1;
        for (int k = 0; k < ne && err == CM_OK; k++) {
            int type, list, ndx, ok_flag, kk;
            if (iges_int(f, lp, pos, &type) || iges_int(f, lp, pos + 2, &ndx) || iges_int(f, lp, pos + 3, &ok_flag) ||
                iges_int(f, lp, pos + 4, &kk)) {
                err = cm_fail(im->st, CM_E_IGES, "508");
                break;
            }
            if (kk < 0 || kk > (lp->nparams - pos - 5) / 2) { /* before pos + 5 + 2 * kk can overflow */
                err = iges_entity_error(f, lp, "edge %d: %d parameter-space curves do not fit its %d parameters",
                                        k + 1, kk, lp->nparams);
                break;
            }
            list = iges_int_or(lp, pos + 1, 0);
            pos += 5 + 2 * kk;
            if (type == 1)
                continue; /* a vertex in a loop: no curve */
            hcurve c = {0};
            err = edge_504(im, lp, list, ndx, &lmap, loops[l].n, &c);
            if (err == CM_OK) {
                if (ok_flag == 0)
                    hcurve_reverse(&c);
                err = hcurve_list_push(&loops[l], &c, im->st);
            }
            hcurve_free(&c);
        }
        if (err == CM_OK)
            f->ents[ent_index(f, lp)].used = 1;
    }
    if (err == CM_OK)
        err = add_face(im, e, surf, &map, loops, n, 0, flip, shell);
    for (int i = 0; i < n; i++)
        hcurve_list_free(&loops[i]);
    free(loops);
    if (err == CM_OK)
        im->stats->faces_510++;
    return err;
}

static cm_err import_face(importer *im, const iges_entity *e, const haffine *parent, int shell, int flip)
{
    brep_model *m = im->m;
    int ns = m->nsurfs, nf = m->nfaces, nl = m->nloops, nsg = m->nsegs;
    cm_err err;
    im->face = e;
    im->face_pieces = 0;
    /* the count made before the import (count_faces) already refused a model over the budget;
     * this keeps the bound true whatever path placed the face */
    if (++im->faces_tried > IGES_MAX_PLACED_FACES) {
        im->f->over_budget = 1;
        return iges_entity_error(im->f, e, "the model places more than %lld faces (limit %lld per model)",
                                 IGES_MAX_PLACED_FACES, IGES_MAX_PLACED_FACES),
               cm_fail(im->st, CM_E_LIMIT, "placed faces");
    }
    switch (e->type) {
    case 144: err = face_144(im, e, parent); break;
    case 143: err = face_143(im, e, parent); break;
    case 510: err = face_510(im, e, parent, shell, flip); break;
    default: {
        /* an untrimmed surface: a face bounded by its parameter rectangle */
        err = add_face(im, e, e->de, parent, NULL, 0, 1, 0, -1);
        if (err == CM_OK)
            im->stats->faces_untrimmed++;
    }
    }
    if (err != CM_OK) {
        if (err == CM_E_NOMEM || im->f->over_budget)
            return err; /* out of memory, or a model-wide budget: nothing sensible to continue with */
        face_failed(im, e, ns, nf, nl, nsg);
        return CM_OK;
    }
    im->f->ents[ent_index(im->f, e)].used = 1;
    return CM_OK;
}

static cm_err shell_514(importer *im, const iges_entity *e, const haffine *parent, int reversed)
{
    iges_file *f = im->f;
    haffine map;
    int n;
    if (iges_entity_xform(f, e, &map) || iges_int(f, e, 0, &n))
        return cm_fail(im->st, CM_E_IGES, "514");
    if (n < 0 || n > (e->nparams - 1) / 2) /* not 1 + 2 * n > nparams: n may be 2147483647 */
        return iges_entity_error(f, e, "%d faces do not fit its %d parameters", n, e->nparams),
               cm_fail(im->st, CM_E_IGES, "514");
    map = haffine_compose(parent, &map);
    int shell = im->m->nshells++;
    int saved_owner = im->owner;
    im->owner = saved_owner ? saved_owner : e->de; /* a shell of its own is a part; a solid's is the solid's */
    for (int i = 0; i < n; i++) {
        int fde, of;
        if (iges_ptr(f, e, 1 + 2 * i, 0, &fde)) {
            /* one bad member pointer loses that face, not the shell */
            /* (no face is lost: the pointer names none; a face it was meant to name, now owned by
               nothing, is imported on its own) */
            iges_warn(f, e->pd_line, "shell DE %d: member %d skipped: %s", e->de, i + 1, bare_error(f, e));
            forget_error(im);
            continue;
        }
        of = iges_int_or(e, 2 + 2 * i, 1);
        const iges_entity *fe = iges_by_de(f, fde);
        if (fe->type != 510 || fe->bad) {
            iges_warn(f, e->pd_line, "shell DE %d: member %d (DE %d) is not a readable face (510); skipped", e->de,
                      i + 1, fde);
            im->m->faces_failed++;
            continue;
        }
        /* face normal = surface normal when OF = 1; a reversed shell flips every face */
        cm_err err = import_face(im, fe, &map, shell, (of == 0) != (reversed != 0));
        if (err != CM_OK) {
            im->owner = saved_owner;
            return err;
        }
    }
    im->owner = saved_owner;
    f->ents[ent_index(f, e)].used = 1;
    return CM_OK;
}

static cm_err solid_186(importer *im, const iges_entity *e, const haffine *parent)
{
    iges_file *f = im->f;
    haffine map;
    int shell, nv;
    if (iges_entity_xform(f, e, &map) || iges_ptr(f, e, 0, 0, &shell) || iges_int(f, e, 2, &nv))
        return cm_fail(im->st, CM_E_IGES, "186");
    if (nv < 0 || nv > (e->nparams - 3) / 2)
        return iges_entity_error(f, e, "%d void shells do not fit its %d parameters", nv, e->nparams),
               cm_fail(im->st, CM_E_IGES, "186");
    map = haffine_compose(parent, &map);
    int sof = iges_int_or(e, 1, 1);
    const iges_entity *s = iges_by_de(f, shell);
    if (s->type != 514 || s->bad)
        return iges_entity_error(f, e, "its shell DE %d is not a readable 514", shell), cm_fail(im->st, CM_E_IGES, "186");
    int saved_owner = im->owner;
    im->owner = saved_owner ? saved_owner : e->de; /* the solid is the part (inside an instance, the instance) */
    cm_err err = shell_514(im, s, &map, sof == 0);
    for (int i = 0; i < nv && err == CM_OK; i++) {
        int vde;
        if (iges_ptr(f, e, 3 + 2 * i, 0, &vde)) {
            /* a bad void shell pointer loses that void, not the solid */
            iges_warn(f, e->pd_line, "solid DE %d: void shell %d skipped: %s", e->de, i + 1, bare_error(f, e));
            forget_error(im);
            continue;
        }
        const iges_entity *vs = iges_by_de(f, vde);
        if (vs->type == 514 && !vs->bad)
            err = shell_514(im, vs, &map, iges_int_or(e, 4 + 2 * i, 1) == 0);
    }
    im->owner = saved_owner;
    if (err == CM_OK)
        f->ents[ent_index(f, e)].used = 1;
    return err;
}

static cm_err import_entity(importer *im, const iges_entity *e, const haffine *parent, int depth);

static cm_err instance_408(importer *im, const iges_entity *e, const haffine *parent, int depth)
{
    iges_file *f = im->f;
    int def;
    haffine own;
    if (depth >= MAX_INSTANCE_DEPTH)
        return iges_entity_error(f, e, "subfigures nested deeper than %d (a cycle?)", MAX_INSTANCE_DEPTH),
               cm_fail(im->st, CM_E_IGES, "408");
    if (iges_entity_xform(f, e, &own) || iges_ptr(f, e, 0, 0, &def))
        return cm_fail(im->st, CM_E_IGES, "408");
    const iges_entity *d = iges_by_de(f, def);
    if (d->type != 308 || d->bad)
        return iges_entity_error(f, e, "DE %d is not a subfigure definition (308)", def), cm_fail(im->st, CM_E_IGES, "408");
    double s = iges_num_or(e, 4, 1.0);
    if (!(s > 0))
        s = 1.0;
    /* x -> own(s * def(x) + t) */
    haffine place = haffine_identity();
    for (int i = 0; i < 3; i++)
        place.R[i][i] = s;
    place.t = cm_v3(iges_num_or(e, 1, 0.0), iges_num_or(e, 2, 0.0), iges_num_or(e, 3, 0.0));
    haffine defmap;
    if (iges_entity_xform(f, d, &defmap))
        return cm_fail(im->st, CM_E_IGES, "308");
    haffine m = haffine_compose(&own, &place);
    m = haffine_compose(&m, &defmap);
    m = haffine_compose(parent, &m);
    int n = iges_int_or(d, 2, 0);
    if (n < 0 || n > d->nparams - 3) /* not 3 + n > nparams: n may be 2147483647 */
        return iges_entity_error(f, d, "%d members do not fit its %d parameters", n, d->nparams),
               cm_fail(im->st, CM_E_IGES, "308");
    /* faces remember the outermost placement: a part may be assembled from nested
     * subfigures (and even one shell per face), which together form one body */
    int saved = im->instance, saved_owner = im->owner;
    im->stats->instances++;
    cm_err err = CM_OK;
    if (depth == 0) {
        im->instance = im->stats->instances;
        im->owner = e->de; /* an outermost instance is one part, whatever solids it holds */
        /* what brep_fold_instances needs to send a part placed several times once */
        brep_instance bi = {im->instance, def, m};
        err = brep_add_instance(im->m, &bi, im->st);
    }
    for (int i = 0; i < n && err == CM_OK; i++) {
        int mde;
        if (iges_ptr(f, d, 3 + i, 0, &mde)) {
            err = cm_fail(im->st, CM_E_IGES, "308");
            break;
        }
        err = import_entity(im, iges_by_de(f, mde), &m, depth + 1);
    }
    im->instance = saved;
    im->owner = saved_owner;
    if (err == CM_OK) {
        f->ents[ent_index(f, e)].used = 1;
        f->ents[ent_index(f, d)].used = 1;
    }
    return err;
}

static int makes_face(const iges_entity *e)
{
    switch (e->type) {
    case 144: case 143: case 510:
        return 1;
    default: /* bounded surface kinds only: planes etc. need a trim */
        return iges_is_surface(e->type) && e->type != 108 && e->type != 190 && e->type != 192 && e->type != 194;
    }
}

static long long add_sat(long long a, long long b)
{
    return a + b > FACE_COUNT_CAP ? FACE_COUNT_CAP : a + b;
}

/*
 * Faces entity e places when import_entity imports it, subfigures expanded (saturating at
 * FACE_COUNT_CAP), memoised per entity: a DAG of 308/408 nested 15 levels deep, 8 instances per
 * level, is counted in a few hundred steps instead of expanded into 8^15 instances.  Structures
 * the import refuses (cycles, nesting deeper than MAX_INSTANCE_DEPTH) count as far as they go.
 */
static long long own_faces(importer *im, const iges_entity *e, int depth);
static long long count_faces(importer *im, const iges_entity *e, int depth)
{
    if (!e || e->bad || depth > MAX_INSTANCE_DEPTH + 1 || hidden(im, e))
        return 0;
    return own_faces(im, e, depth);
}

/* ... and those it would place if it were not blanked itself (its members' blanking counts) */
static long long own_faces(importer *im, const iges_entity *e, int depth)
{
    if (!e || e->bad || depth > MAX_INSTANCE_DEPTH + 1)
        return 0;
    if (makes_face(e))
        return 1;
    long long *memo = &im->nfaces_of[ent_index(im->f, e)];
    if (*memo >= 0)
        return *memo;
    iges_file *f = im->f;
    long long n = 0;
    switch (e->type) {
    case 186: { /* its shell, then its void shells */
        int nv = iges_count_or0(e, 2);
        n = count_faces(im, iges_by_de(f, iges_int_or(e, 0, 0)), depth + 1);
        for (int i = 0; i < nv && 3 + 2L * i < e->nparams; i++)
            n = add_sat(n, count_faces(im, iges_by_de(f, iges_int_or(e, 3 + 2 * i, 0)), depth + 1));
        break;
    }
    case 514: { /* its faces */
        int nf = iges_count_or0(e, 0);
        for (int i = 0; i < nf && 1 + 2L * i < e->nparams; i++) {
            const iges_entity *fe = iges_by_de(f, iges_int_or(e, 1 + 2 * i, 0));
            n += fe && fe->type == 510;
        }
        break;
    }
    case 408: { /* the members of its definition */
        const iges_entity *d = iges_by_de(f, iges_int_or(e, 0, 0));
        if (!d || d->type != 308 || d->bad)
            break;
        *memo = 0; /* a cycle counts 0 here; the import reports it */
        int nm = iges_count_or0(d, 2);
        for (int i = 0; i < nm && 3 + i < d->nparams; i++)
            n = add_sat(n, count_faces(im, iges_by_de(f, iges_int_or(d, 3 + i, 0)), depth + 1));
        break;
    }
    default:
        break;
    }
    *memo = n;
    return n;
}

/*
 * The budget of placed faces, checked before anything is built: the faces every top-level entity
 * places, summed.  Past IGES_MAX_PLACED_FACES the import is refused, naming the entity at which
 * the sum went over (for a subfigure instance, with what its definition expands to).
 */
static cm_err check_face_budget(importer *im)
{
    iges_file *f = im->f;
    if (!im->nfaces_of)
        im->nfaces_of = malloc((size_t)(f->nents > 0 ? f->nents : 1) * sizeof *im->nfaces_of);
    if (!im->nfaces_of)
        return iges_nomem(f, f->nents > 0 ? f->ents[0].line : 0, "counting the faces of %d entities", f->nents),
               cm_fail(im->st, CM_E_NOMEM, "out of memory");
    for (int k = 0; k < f->nents; k++)
        im->nfaces_of[k] = -1; /* (again when include_blanked changes: members' blanking counts) */
    long long total = 0;
    for (int k = 0; k < f->nents; k++) {
        if (im->ref[k])
            continue; /* imported through its owner */
        const iges_entity *e = &f->ents[k];
        long long n = count_faces(im, e, 0);
        total = add_sat(total, n);
        if (total <= IGES_MAX_PLACED_FACES)
            continue;
        f->over_budget = 1;
        if (e->type == 408) {
            int d = iges_int_or(e, 0, 0);
            return iges_entity_error(f, e,
                                     "subfigure instances expand to more than %lld faces (limit %lld per model): "
                                     "this instance of definition DE %d places %s%lld faces",
                                     IGES_MAX_PLACED_FACES, IGES_MAX_PLACED_FACES, d,
                                     n >= FACE_COUNT_CAP ? "more than " : "", n),
                   cm_fail(im->st, CM_E_LIMIT, "subfigure instances");
        }
        return iges_entity_error(f, e, "the model places more than %lld faces (limit %lld per model)",
                                 IGES_MAX_PLACED_FACES, IGES_MAX_PLACED_FACES),
               cm_fail(im->st, CM_E_LIMIT, "placed faces");
    }
    im->placed_faces = total;
    return CM_OK;
}

/* faces of one entity, if it makes any; everything else is left for `cmz info` to count */
static cm_err import_entity(importer *im, const iges_entity *e, const haffine *parent, int depth)
{
    if (e->bad)
        return CM_OK;
    if (hidden(im, e)) {
        long long n = own_faces(im, e, depth);
        if (n > 0) {
            im->stats->blanked_entities++;
            im->stats->blanked_faces = add_sat(im->stats->blanked_faces, n);
            iges_warn(im->f, e->pd_line,
                      "entity %d (%s, DE %d) not imported: blanked (hidden in the CAD system), %lld face%s; "
                      "--include-blanked imports it", e->type, iges_type_name(e->type), e->de, n, n == 1 ? "" : "s");
        }
        return CM_OK;
    }
    switch (e->type) {
    case 144: case 143: case 510:
        return import_face(im, e, parent, -1, 0);
    case 186:
        return solid_186(im, e, parent);
    case 514:
        return shell_514(im, e, parent, 0);
    case 408:
        return instance_408(im, e, parent, depth);
    default:
        if (makes_face(e))
            return import_face(im, e, parent, -1, 0);
        return CM_OK;
    }
}

/* median of n values (sorted in place; the lower one of the middle two) */
static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y ? 1 : 0;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return v[(n - 1) / 2];
}

/*
 * Drop faces lying absurdly far from the rest of the model: farther (max-norm, whole box) from the
 * median of the face centres than 10^6 times the median face's such distance.  One corrupted
 * matrix entry or coordinate (still below IGES_MAX_COORD_MM) would otherwise make the model's
 * diagonal, and with it every relative tolerance, meaningless: the real faces' vertices would all
 * merge.  Needs three faces to tell which ones are the outliers.  Each is warned, naming its DE.
 */
#define FAR_FACTOR 1e6
static cm_err drop_far_faces(importer *im)
{
    brep_model *m = im->m;
    int n = m->nfaces;
    if (n < 3)
        return CM_OK;
    double *v = malloc((size_t)n * sizeof *v), *dist = malloc((size_t)n * sizeof *dist);
    unsigned char *drop = calloc((size_t)n, 1);
    if (!v || !dist || !drop) {
        free(v);
        free(dist);
        free(drop);
        return iges_nomem(im->f, 0, "checking the extent of %d faces", n), cm_fail(im->st, CM_E_NOMEM, "out of memory");
    }
    double c[3];
    for (int k = 0; k < 3; k++) {
        for (int i = 0; i < n; i++) {
            const hbox *b = &im->fbox[i];
            double lo = k == 0 ? b->lo.x : k == 1 ? b->lo.y : b->lo.z, hi = k == 0 ? b->hi.x : k == 1 ? b->hi.y : b->hi.z;
            v[i] = b->empty ? 0.0 : 0.5 * (lo + hi);
        }
        c[k] = median(v, n);
    }
    for (int i = 0; i < n; i++) {
        const hbox *b = &im->fbox[i];
        double d = 0;
        if (!b->empty)
            d = fmax(fmax(fmax(fabs(b->lo.x - c[0]), fabs(b->hi.x - c[0])), fmax(fabs(b->lo.y - c[1]), fabs(b->hi.y - c[1]))),
                     fmax(fabs(b->lo.z - c[2]), fabs(b->hi.z - c[2])));
        dist[i] = v[i] = d;
    }
    double typical = median(v, n), limit = FAR_FACTOR * typical;
    int ndrop = 0;
    for (int i = 0; i < n && typical > 0; i++)
        if (dist[i] > limit) {
            const brep_face *F = &m->faces[i];
            const iges_entity *e = iges_by_de(im->f, F->src_de);
            char why[400];
            snprintf(why, sizeof why,
                     "line %d: its geometry lies %g mm from the middle of the model, more than %g times the typical "
                     "face's %g mm (a corrupted coordinate, scale or transformation?)",
                     e ? e->pd_line : 0, dist[i], FAR_FACTOR, typical);
            if (e)
                warn_skipped(im, e, im->ford[i], why);
            drop[i] = 1;
            ndrop++;
        }
    cm_err err = CM_OK;
    if (ndrop > 0) {
        err = brep_remove_faces(m, drop, im->st);
        if (err == CM_OK) {
            m->box = hbox_empty();
            for (int i = 0; i < n; i++)
                if (!drop[i] && !im->fbox[i].empty) {
                    hbox_add(&m->box, im->fbox[i].lo);
                    hbox_add(&m->box, im->fbox[i].hi);
                }
        } else {
            iges_nomem(im->f, 0, "removing %d far-away faces", ndrop);
        }
    }
    free(v);
    free(dist);
    free(drop);
    return err;
}

/*
 * Faces that no solid, shell or instance placed (trimmed surfaces at the top level) take as their
 * part's owner the first associativity group (402 forms 1, 7, 14, 15: an exporter's solids, OCCT's
 * among them, written as a group of their faces) that lists them directly.  Groups only annotate:
 * a face in none stays loose (the encoder joins loose faces by their edges, parts.c).
 */
static cm_err group_loose_faces(importer *im)
{
    iges_file *f = im->f;
    int *group = calloc((size_t)(f->nents ? f->nents : 1), sizeof *group);
    if (!group)
        return iges_nomem(f, 0, "grouping %d entities", f->nents), cm_fail(im->st, CM_E_NOMEM, "out of memory");
    for (int k = 0; k < f->nents; k++) {
        const iges_entity *e = &f->ents[k];
        if (e->type != 402 || e->bad || !(e->form == 1 || e->form == 7 || e->form == 14 || e->form == 15))
            continue;
        int n = iges_count_or0(e, 0);
        for (int i = 0; i < n && 1 + i < e->nparams; i++) {
            const iges_param *p = &e->params[1 + i];
            int de = p->kind == IGES_P_NUM ? iges_to_int(p->num, 1, 99999999, 0) : 0;
            const iges_entity *t = de > 0 ? iges_by_de(f, de) : NULL;
            if (t && group[ent_index(f, t)] == 0)
                group[ent_index(f, t)] = e->de;
        }
    }
    for (int i = 0; i < im->m->nfaces; i++) {
        brep_face *F = &im->m->faces[i];
        const iges_entity *t = F->owner == 0 && F->instance == 0 ? iges_by_de(f, F->src_de) : NULL;
        if (t)
            F->owner = group[ent_index(f, t)];
    }
    free(group);
    return CM_OK;
}

cm_err iges_to_brep(iges_file *f, brep_model *m, brep_import_stats *stats, int include_blanked, cm_status *st)
{
    importer im;
    memset(&im, 0, sizeof im);
    memset(m, 0, sizeof *m);
    memset(stats, 0, sizeof *stats);
    m->box = hbox_empty();
    m->resolution_mm = f->g.resolution * f->to_mm;
    im.f = f;
    im.m = m;
    im.stats = stats;
    im.st = st;
    im.ref = calloc((size_t)(f->nents ? f->nents : 1), 1);
    if (!im.ref)
        return iges_nomem(f, 0, "importing %d entities", f->nents), cm_fail(st, CM_E_NOMEM, "out of memory");
    mark_references(&im);
    im.include_blanked = include_blanked;
    cm_err err = check_face_budget(&im);
    if (err == CM_OK && im.placed_faces == 0 && !im.include_blanked) {
        /* nothing visible: a file whose every face is blanked is still a model someone wants */
        im.include_blanked = 1;
        err = check_face_budget(&im);
        if (err == CM_OK && im.placed_faces > 0)
            iges_warn(f, 0, "every face of the file is blanked (hidden in the CAD system): imported anyway");
        else
            im.include_blanked = 0;
    }
    haffine to_mm = haffine_identity();
    for (int i = 0; i < 3; i++)
        to_mm.R[i][i] = f->to_mm;
    int k = 0;
    for (; k < f->nents && err == CM_OK; k++) {
        const iges_entity *e = &f->ents[k];
        if (im.ref[k])
            continue; /* owned by another entity: imported through it */
        int nsurfs = m->nsurfs, nfaces = m->nfaces, nloops = m->nloops, nsegs = m->nsegs, nshells = m->nshells;
        im.top = k;
        im.owner = 0;
        err = import_entity(&im, e, &to_mm, 0);
        if (err != CM_OK && err != CM_E_NOMEM && err != CM_E_LIMIT && err != CM_E_IO) {
            /* one malformed solid, shell or instance never sinks the model: what it had added is
               taken back, it is left out by name, and the other entities are imported (faces
               fail one by one inside; what reaches here is the structure around them) */
            brep_truncate(m, nsurfs, nfaces, nloops, nsegs);
            m->nshells = nshells;
            char why[512];
            if (f->err[0])
                snprintf(why, sizeof why, "%s", bare_error(f, e));
            else
                snprintf(why, sizeof why, "%s (%s)", cm_strerror(err), st && st->where ? st->where : "?");
            iges_warn(f, e->pd_line, "entity %d (%s, DE %d) left out: %s", e->type, iges_type_name(e->type), e->de,
                      why);
            forget_error(&im);
            m->entities_failed++;
            err = CM_OK;
        }
    }
    if (err == CM_OK)
        err = group_loose_faces(&im);
    if (err == CM_OK)
        err = drop_far_faces(&im);
    if (err == CM_E_NOMEM && k > 0 && k <= f->nents) /* say where the import was (the input is not to blame) */
        iges_nomem(f, f->ents[k - 1].pd_line, "importing entity %d, DE %d", f->ents[k - 1].type, f->ents[k - 1].de);
    else if (err != CM_OK && f->err[0] == 0 && k > 0 && k <= f->nents)
        iges_entity_error(f, &f->ents[k - 1], "import failed: %s (%s)", cm_strerror(err),
                          st && st->where ? st->where : "?");
    free(im.ref);
    free(im.nfaces_of);
    free(im.fbox);
    free(im.ford);
    if (err != CM_OK)
        return err;
    for (int i = 0; i < f->nents; i++) {
        int t = f->ents[i].type;
        stats->face_entities += (t == 144 || t == 143 || t == 510) && f->ents[i].used;
    }
    if (m->nfaces == 0) {
        if (m->faces_failed)
            iges_error(f, im.first_fail_line, "none of the file's %d faces could be read; the first, %s",
                       m->faces_failed, im.first_fail);
        else
            iges_error(f, f->nents > 0 ? f->ents[0].line : 0,
                       "the file's %d entities hold no faces (no trimmed, bounded or B-rep surfaces)", f->nents);
        return cm_fail(st, CM_E_IGES, "iges_to_brep");
    }
    return CM_OK;
}
