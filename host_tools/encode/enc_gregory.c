/* enc_gregory.c - the encoder's half of GREGORY (spec §6; decoder/methods/gregory.c) and of
   GREGORY-EXACT (the same layouts over the exact edges; decoder/methods/gregory_exact.c). */
#include "enc_method.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_const.h"
#include "cm/cm_corner.h"
#include "cm/cm_cubic_convert.h"
#include "cm/cm_method.h"
#include "fit_correction.h"

/* the K7 acceptance of spec 6 */
#define K7_ACCEPT 0.25

#define NO_SIDE_AREA 1e-6 /* of the square of the loop's size: a loop's Newell vector below this is noise */

/*
 * Spec §6 applicability of GREGORY for face f: an outer loop of 3..CM_MAX_SIDES edges, each
 * cubic-convertible within a quarter of the tolerance (K7; not asked by GREGORY-EXACT, whose
 * patches take the edges as they are), no reflex corner.  This version also
 * asks for no holes: the rebuilt patches cover the outer loop, and a terminal would have to trim
 * them by the holes' projections (left to the fitting methods).  Fills the corner angles' cosines
 * for the layout-2 order.  Returns 0 (and why, in rep->why) when not applicable.
 */
static int gregory_applicable(enc_work *w, int f, double tol, int exact, double *corner_cos, face_report *rep)
{
    const cm_model *m = &w->dec.model;
    const cm_face *F = &m->faces[f];
    const cm_loop *L = &m->loops[F->loop0];
    int n = (int)L->nuse;
    if (F->nloops != 1) {
        rep->why = "holes";
        return 0;
    }
    /* GREGORY-EXACT's layout 3 takes loops of up to 12 edges (four of them corners) */
    if (n < 3 || n > (exact ? CM_GREG_MAX_INPUT : CM_MAX_SIDES)) {
        rep->why = n < 3 ? "fewer than 3 sides" : "too many sides";
        return 0;
    }
    cm_cubic cub[CM_GREG_MAX_INPUT];
    cm_vec3 t_in[CM_GREG_MAX_INPUT], t_out[CM_GREG_MAX_INPUT]; /* unit tangents at the end and start of side k */
    for (int k = 0; k < n && exact; k++) {
        const cm_use *U = &m->uses[L->use0 + (uint32_t)k];
        if (!cm_use_tangent(m, U, 1, 0.0, &t_in[k]) || !cm_use_tangent(m, U, 0, 0.0, &t_out[k])) {
            rep->why = "degenerate edge";
            return 0;
        }
    }
    for (int k = 0; k < n && !exact; k++) {
        const cm_use *U = &m->uses[L->use0 + (uint32_t)k];
        cm_curve c;
        cm_model_edge_curve(m, U->edge, &c);
        double delta = 0;
        if (cm_edge_cubic(&c, m->conic_cubic, &cub[k], NULL) != CM_OK ||
            cm_edge_cubic_delta(&c, &cub[k], &delta, NULL) != CM_OK || !(delta <= K7_ACCEPT * tol)) {
            rep->why = "edge not cubic-convertible";
            return 0;
        }
        if (U->rev)
            cub[k] = cm_cubic_reverse(&cub[k]);
    }
    double bbox;
    cm_vec3 nF;
    if (cm_face_normal(m, (uint32_t)f, w->rbws.samples, &bbox, &nF, NULL) != CM_OK) {
        rep->why = "no face normal";
        return 0;
    }
    /* a loop with no mean direction (a full cylinder's band: its two circles run opposite ways, their
       Newell vectors cancel) has no side to be reflex against: its normal is rounding noise, which
       made the same band reflex or not as its circles' parameters fell (occt__OCC8842_cylinder_Ideas
       with its circles as format 4.4 arcs); the rebuild's error and G1 checks judge it instead */
    cm_vec3 area = cm_v3(0, 0, 0);
    const cm_vec3 *smp = w->rbws.samples;
    int ns = n * CM_FMT_SEG_PER_EDGE;
    for (int i = 0; i < ns; i++)
        area = cm_add(area, cm_cross(cm_sub(smp[i], smp[0]), cm_sub(smp[(i + 1) % ns], smp[0])));
    int no_side = exact && !(cm_norm(area) >= NO_SIDE_AREA * bbox * bbox);
    for (int k = 0; k < n; k++) {
        const cm_cubic *in = &cub[(k + n - 1) % n], *out = &cub[k];
        cm_vec3 ta = exact ? t_in[(k + n - 1) % n] : cm_sub(in->c[3], in->c[2]);
        cm_vec3 tb = exact ? t_out[k] : cm_sub(out->c[1], out->c[0]);
        if (!(cm_norm(ta) > 0) || !(cm_norm(tb) > 0)) {
            rep->why = "degenerate edge";
            return 0;
        }
        cm_vec3 a = cm_neg(cm_unit(ta)), b = cm_unit(tb), x = cm_cross(b, a);
        corner_cos[k] = cm_dot(a, b);
        /* GREGORY-EXACT: a corner square to n_F (a half cylinder's) is not reflex; only one clearly
           turned against it (its patch would face inwards there; corner normals are not turned) */
        if (!no_side && cm_norm(x) >= CM_SIN_FLAT &&
            (exact ? cm_dot(cm_unit(x), nF) < -0.5 : cm_dot(x, nF) <= 0)) {
            rep->why = "reflex corner";
            return 0;
        }
    }
    return 1;
}

/* "straight" for layout 3's order: a corner whose cosine between the edges leaving it is below
   minus this (within about 10 degrees of a straight line) */
#define CM_JOINED_STRAIGHT_COS 0.985

/* layout 3's corner bits: the four corners whose edges turn the most (largest cosine between the
   edges leaving the corner; the lower index first among equals) */
static int joined_corners(const double *ccos, int n)
{
    int bits = 0;
    for (int c = 0; c < CM_GREG_JOINED_CORNERS; c++) {
        int best = -1;
        for (int k = 0; k < n; k++)
            if (!((bits >> k) & 1) && (best < 0 || ccos[k] > ccos[best]))
                best = k;
        bits |= 1 << best;
    }
    return bits;
}

/* one correction of m per direction fitted, rebuilt by the decoder's code from the quantised record
   and measured: 1 when it passes (record in *fr, surface in rb, numbers in fe) */
static int fit_once(enc_work *w, const loaded_model *lm, int f, int layout, int corner, double tol,
                    const cm_greg_surface *base, int m, fit_record *fr, cm_rebuilt *rb, face_error *fe,
                    double *best_ratio)
{
    if (!fit_correction(lm, lm->mesh.faces[f].brep_face, base, m, tol, w->dec.model.q, fr))
        return 0;
    cm_fit_q view = fit_record_view(fr);
    if (enc_trial_rebuild(w, f, CM_METHOD_GREGORY_FIT, layout, corner, &view, rb) != CM_OK ||
        !verify_face(lm, &w->dec.model, f, rb, tol, fe))
        return 0;
    if (fe->ratio < *best_ratio)
        *best_ratio = fe->ratio;
    return fe->max < tol;
}

/*
 * GREGORY-FIT on one layout: the exact patches plus a correction.  The functions of a smaller m are
 * combinations of those of the largest (Bernstein degree elevation), so the largest fits at least
 * as closely: it is tried first, and when it fails the face is given up at once (most trials fail:
 * this is the encoder's time); when it passes, m = 1, 2, ... are tried for a smaller record.
 * Returns 1 with the winner's record, surface and numbers.
 */
static int fit_layout(tx *t, const loaded_model *lm, int f, int layout, int corner, double tol, fit_record *fr,
                      cm_rebuilt *rb, face_error *fe, double *best_ratio)
{
    enc_work *w = t->w;
    cm_rebuilt base;
    if (enc_trial_rebuild(w, f, CM_METHOD_GREGORY_EXACT, layout, corner, NULL, &base) != CM_OK)
        return 0;
    cm_greg_surface *gs = malloc(sizeof *gs); /* the base patches: the next rebuild reuses the workspace */
    fit_record *best = malloc(sizeof *best);
    if (!gs || !best) {
        free(gs);
        free(best);
        return 0;
    }
    *gs = *base.greg;
    int ok = fit_sides_within(lm, lm->mesh.faces[f].brep_face, gs, tol) &&
             fit_once(w, lm, f, layout, corner, tol, gs, CM_FIT_MAX_M, best, rb, fe, best_ratio);
    if (ok) {
        face_error best_fe = *fe;
        int smaller = 0;
        for (int m = 1; m < CM_FIT_MAX_M && !smaller; m++)
            smaller = fit_once(w, lm, f, layout, corner, tol, gs, m, fr, rb, fe, best_ratio);
        if (!smaller) {
            /* the largest m after all: rebuilt again (the tries since reused the workspace) */
            *fr = *best;
            *fe = best_fe;
            cm_fit_q view = fit_record_view(fr);
            ok = enc_trial_rebuild(w, f, CM_METHOD_GREGORY_FIT, layout, corner, &view, rb) == CM_OK;
        }
    }
    free(gs);
    free(best);
    return ok;
}

/* spec 15.3: a hint when the normal a flat corner falls back to (n_F) is more than 2 degrees off the
   source surface's */
#define HINT_COS 0.9993908270190958
/* a hint's bits in the record, about (a mask's, two octahedral coordinates' of 15 bits and signs) */
#define HINT_BITS 36

/*
 * Spec §14 step 3's last resort for face f (method: GREGORY or GREGORY-EXACT): its flat corners with
 * no G1 edge, where the rebuild takes n_F (spec 5.3 (iii)), each hinted with the source surface's
 * normal there where that is more than 2 degrees off n_F.  The hints into h (a record without a
 * correction); 0 when there are none.
 */
static int corner_hints(enc_work *w, const loaded_model *lm, int f, int method, fit_record *h)
{
    cm_model *m = &w->dec.model;
    cm_face saved = m->faces[f];
    enc_record_fields(&m->faces[f], method, 0, 0); /* (no hints of an earlier trial) */
    cm_greg_input *in = malloc(sizeof *in);
    cm_corner_ws *cw = malloc(sizeof *cw);
    memset(h, 0, sizeof *h);
    int n = 0;
    if (cw)
        cm_corner_cache_end(cw); /* (no cache: malloc's garbage otherwise) */
    if (in && cw && cm_greg_input_build(m, (uint32_t)f, method != CM_METHOD_GREGORY, in, cw, NULL) == CM_OK) {
        const cm_loop *L = &m->loops[m->faces[f].loop0];
        for (int k = 0; k < in->n && k < CM_GREG_JOINED_MAX_EDGES; k++) {
            const cm_use *uin = &m->uses[L->use0 + (uint32_t)((k + in->n - 1) % in->n)];
            const cm_use *uout = &m->uses[L->use0 + (uint32_t)k];
            cm_vec3 ns;
            if (cw->has_geo[k] || m->edges[uin->edge].g1 || m->edges[uout->edge].g1 || cw->vert[k] < 0 ||
                !verify_source_normal(lm, f, m->verts[cw->vert[k]], &ns))
                continue;
            /* (the source's Su x Sv, turned to the face's side: the loops run about that) */
            if (lm->brep.faces[lm->mesh.faces[f].brep_face].flip)
                ns = cm_neg(ns);
            if (!(cm_dot(ns, in->nF) < HINT_COS))
                continue;
            h->hint_mask |= 1u << k;
            cm_hint_encode(ns, h->hint[n++]);
        }
    }
    free(in);
    free(cw);
    m->faces[f] = saved;
    return n;
}

/* GREGORY's or GREGORY-EXACT's candidate layouts (cand_layout, cand_j: nc of them), with the record's
   corner hints (NULL: none): the first that passes §12 is accepted (1); -1 when its surface cannot
   be kept (out of memory), 0 when none passes (rep->why, *best_ratio the closest) */
static int try_layouts(tx *t, const loaded_model *lm, int f, int method, const int *cand_layout, const int *cand_j,
                       int nc, double tol, const cm_fit_q *hints, face_report *rep, face_surface *fs, double *best_ratio)
{
    enc_work *w = t->w;
    for (int c = 0; c < nc; c++) {
        cm_rebuilt rb;
        if (enc_trial_rebuild(w, f, method, cand_layout[c], cand_j[c], hints, &rb) != CM_OK) {
            rep->why = "construction failed";
            continue;
        }
        face_error fe;
        if (!verify_face(lm, &w->dec.model, f, &rb, tol, &fe)) {
            rep->why = "no source domain";
            continue;
        }
        if (fe.ratio < *best_ratio)
            *best_ratio = fe.ratio;
        if (rep->greg_ratio == 0 || fe.ratio < rep->greg_ratio)
            rep->greg_ratio = fe.ratio; /* over both methods of the family */
        if (!(fe.max < tol)) {
            rep->why = "error";
            continue;
        }
        if (!face_surface_set(&fs[f], &rb))
            return -1;
        enc_fit_accept(t, f, cand_layout[c], cand_j[c], cand_j[c], &rb, &fe, rep);
        return 1;
    }
    return 0;
}

/* spec §14 candidate list of the GREGORY family (method: GREGORY, GREGORY-EXACT or GREGORY-FIT); the
   first that passes §12 wins */
static int try_family(tx *t, const loaded_model *lm, int f, const encode_opts *o, face_report *rep,
                      face_surface *fs, int method)
{
    enc_work *w = t->w;
    double ccos[CM_GREG_MAX_INPUT];
    int fit = method == CM_METHOD_GREGORY_FIT;
    int exact = method == CM_METHOD_GREGORY_EXACT || fit;
    double tol = encode_face_tol(o->rel_tol, o->rel_set, o->abs_tol, rep->bbox);
    if (!gregory_applicable(w, f, tol, exact, ccos, rep))
        return 0;
    int n = (int)w->dec.model.loops[w->dec.model.faces[f].loop0].nuse;
    int cand_layout[4], cand_j[4], nc = 0;
    if (n == 4) {
        cand_layout[nc] = CM_GREG_LAYOUT_QUAD;
        cand_j[nc++] = 0;
        if (exact) {
            /* four quads around a centre follow a surface that bends between the sides (a fillet's
               corner, a saddle) where one patch cannot: tried second, it costs nothing in the record */
            cand_layout[nc] = CM_GREG_LAYOUT_SPLIT;
            cand_j[nc++] = 0;
        }
    } else if (n <= CM_MAX_SIDES) {
        cand_layout[nc] = CM_GREG_LAYOUT_SPLIT;
        cand_j[nc++] = 0;
    }
    if (exact && n >= 5 && cm_greg_joined_ok((unsigned)joined_corners(ccos, n), n)) {
        /* layout 3: the four sharpest corners are the patch's, the edges between them its sides.
           A quad whose side an exporter cut at a T-vertex (a flat corner, where a neighbour's edge
           ends) is a pentagon to the N-split, whose centre and five patches follow it badly (24 of
           as1_pe_203's faces at --tol 0.001).  Tried first where every other corner is within
           about 10 degrees of straight, else after the N-split. */
        int joined = joined_corners(ccos, n);
        int straight = 1;
        for (int k = 0; k < n; k++)
            if (!((joined >> k) & 1) && !(ccos[k] < -CM_JOINED_STRAIGHT_COS))
                straight = 0;
        cand_layout[nc] = CM_GREG_LAYOUT_JOINED;
        cand_j[nc] = joined;
        if (straight && nc > 0) {
            cand_layout[nc] = cand_layout[0];
            cand_j[nc] = cand_j[0];
            cand_layout[0] = CM_GREG_LAYOUT_JOINED;
            cand_j[0] = joined;
        }
        nc++;
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
    if (nc == 0) {
        rep->why = "too many sides"; /* more than CM_MAX_SIDES edges, and not a quad with T-vertices */
        return 0;
    }
    double best_ratio = HUGE_VAL;
    int too_large = 0; /* a correction passed but cost more than the surface */
    for (int c = 0; c < nc && fit; c++) {
        /* every layout: the correction vanishes with its slopes on every side of every patch, so a
           rebuilt face still meets its neighbours and its own patches G1.  A fit cannot move a side,
           so fit_layout first checks that the sides, the N-split's inner curves included, are within
           the tolerance, and spares the fits that cannot pass (none of 3819 N-split fits passed on
           Shelt_channel_5's bands of revolution).  At --tol 0.001 the three-sided chamfers of hex nuts
           (degenerate quad) and six-sided faces of revolution (as1_pe_203, N-split) pass. */
        cm_rebuilt rb;
        face_error fe;
        fit_record *fr = malloc(sizeof *fr);
        if (!fr)
            return 0;
        if (!fit_layout(t, lm, f, cand_layout[c], cand_j[c], tol, fr, &rb, &fe, &best_ratio)) {
            free(fr);
            continue;
        }
        /* spec §14 step 6: a correction that costs more than the surface it replaces is not worth
           sending (the N-split's several patches on a small B-spline face) */
        if (enc_fit_record_bits(fr) >= enc_kept_surface_bits(&t->surfs[f], t->o->predicted)) {
            too_large = 1;
            free(fr);
            continue;
        }
        if (!face_surface_set(&fs[f], &rb)) {
            free(fr);
            continue;
        }
        free(t->fit[f]);
        t->fit[f] = fr;
        enc_fit_accept(t, f, cand_layout[c], cand_j[c], cand_j[c], &rb, &fe, rep);
        rep->fit_m = fr->m;
        return 1;
    }
    /* the candidates, then (format 4.13) once more with hints at the flat corners that fell back to
       n_F, where there are any (spec §14 step 3) and they cost less than the surface (step 6) */
    int passed = fit ? 0 : try_layouts(t, lm, f, method, cand_layout, cand_j, nc, tol, NULL, rep, fs, &best_ratio);
    fit_record *hints = passed || fit || !enc_hints(o) ? NULL : malloc(sizeof *hints);
    int nh = hints ? corner_hints(w, lm, f, method, hints) : 0;
    if (nh > 0 && (double)(nh * HINT_BITS) < enc_kept_surface_bits(&t->surfs[f], t->o->predicted)) {
        cm_fit_q hview = fit_record_view(hints);
        passed = try_layouts(t, lm, f, method, cand_layout, cand_j, nc, tol, &hview, rep, fs, &best_ratio);
        if (passed > 0) {
            free(t->fit[f]);
            t->fit[f] = hints; /* (the hints travel in the record: a correction of m = 0) */
            hints = NULL;
        }
    }
    free(hints);
    if (passed)
        return passed > 0;
    /* the reason of the candidate that came closest: one built and measured over the tolerance says
       more than a later layout that could not be built */
    if (best_ratio < HUGE_VAL)
        rep->why = too_large ? "record larger than the surface" : "error";
    return 0;
}

static int try_gregory(tx *t, const loaded_model *lm, int f, const encode_opts *o, face_report *rep,
                       face_surface *fs)
{
    return o->gregory && try_family(t, lm, f, o, rep, fs, CM_METHOD_GREGORY);
}

static int try_gregory_exact(tx *t, const loaded_model *lm, int f, const encode_opts *o, face_report *rep,
                             face_surface *fs)
{
    return o->gregory && o->gregory_exact && try_family(t, lm, f, o, rep, fs, CM_METHOD_GREGORY_EXACT);
}

const enc_method enc_method_gregory = {CM_METHOD_GREGORY, try_gregory, NULL};
static int try_gregory_fit(tx *t, const loaded_model *lm, int f, const encode_opts *o, face_report *rep,
                           face_surface *fs)
{
    return o->gregory && o->gregory_exact && o->gregory_fit && try_family(t, lm, f, o, rep, fs, CM_METHOD_GREGORY_FIT);
}

const enc_method enc_method_gregory_exact = {CM_METHOD_GREGORY_EXACT, try_gregory_exact, NULL};
const enc_method enc_method_gregory_fit = {CM_METHOD_GREGORY_FIT, try_gregory_fit, NULL};
