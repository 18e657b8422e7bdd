/* enc_g1fit.c - the encoder's half of G1FIT (cm_g1fit.h; decoder/methods/g1fit.c). */
#include "enc_method.h"
#include "fit_correction.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_const.h"
#include "cm/cm_corner.h"
#include "cm/cm_g1fit.h"
#include "cm/cm_gregface.h"
#include "cm/cm_method.h"
#include "cm/cm_patchfit.h"

/* nets tried, smallest first (NFILL's sizes, spec 8.9) ... */
static const int g1fit_ctrl[] = {4, 5, 6, 8, 10, 12, 16, 20, 24};
/* ... each with the Coons interior, then the faired one (the record's mode) */
static const int g1fit_modes[] = {0, 1};
#define G1FIT_TRIES (sizeof g1fit_ctrl / sizeof g1fit_ctrl[0] * sizeof g1fit_modes / sizeof g1fit_modes[0])

/* half the G1 limit: cos(acos(CM_COS_G1) / 2) */
#define G1FIT_COS_HALF sqrt(0.5 * (1.0 + CM_COS_G1))
/* along an edge to a face that keeps its surface: 0.9 of the G1 limit (the fix-point measures the
   kept face by its source's normal, the terminal has its net within a quarter of its tolerance) */
#define G1FIT_COS_KEPT cos(0.9 * acos(CM_COS_G1))

/*
 * Per face 1 where it keeps its surface for good: chosen (faces only move down the table, towards
 * KEEP) and kept.  A face not yet chosen counts as rebuilt.  NULL when out of memory.
 */
static unsigned char *g1fit_kept_neighbours(const tx *t)
{
    unsigned char *kept = calloc((size_t)t->nfaces + 1, 1);
    for (int g = 0; kept && g < t->nchosen && g < t->nfaces; g++)
        kept[g] = (unsigned char)enc_kept(t->method[g]);
    return kept;
}

/*
 * A G1 check of face f made with no face counted as kept (t->nchosen = 0: a worker's first choice,
 * choose_methods.c), recorded to be answered again once the faces before f are chosen: its answer
 * `ok`, and per face before f across a G1 edge the worst |cos| toward it (use_worst per use, `worst`
 * what verify_g1_self returned).  Where it cannot be recorded the face is chosen again whenever a
 * face before it keeps its surface.
 */
static void g1fit_record_check(tx *t, const cm_model *m, int f, int ok, double worst, const double *use_worst)
{
    if (!use_worst) {
        t->asked.all = 1;
        return;
    }
    const cm_face *F = &m->faces[f];
    tx_check c = {(unsigned char)ok, G1FIT_COS_HALF, G1FIT_COS_KEPT, 1.0, 0, {0}, {0}};
    double all = 1.0;
    uint32_t nth = 0;
    for (uint32_t l = 0; l < F->nloops; l++) {
        const cm_loop *L = &m->loops[F->loop0 + l];
        for (uint32_t k = 0; k < L->nuse; k++, nth++) {
            double w = use_worst[nth];
            uint32_t e = m->uses[L->use0 + k].edge;
            int32_t a = m->edge_face[e][0], b = m->edge_face[e][1], g = a == f ? b : a;
            all = w < all ? w : all;
            if (!(a >= 0 && b >= 0 && a != b && g < f)) {
                c.other = w < c.other ? w : c.other; /* never kept before f is chosen */
                continue;
            }
            int i = 0;
            while (i < c.n && c.face[i] != g)
                i++;
            if (i == TX_MAX_MATTER) {
                t->asked.all = 1;
                return;
            }
            if (i == c.n) {
                c.face[c.n] = g;
                c.worst[c.n++] = 1.0;
            }
            c.worst[i] = w < c.worst[i] ? w : c.worst[i];
        }
    }
    if (worst < all) /* a curve that did not evaluate: the check fails whatever the neighbours */
        c.other = worst;
    tx_note_check(t, &c);
}

/*
 * Face f's final surface (fs[f]) along its G1 edges: within half the G1 limit of its source's
 * normal where the neighbour may be rebuilt too (the angles add), within G1FIT_COS_KEPT where the
 * neighbour keeps its surface.  Before, every edge had half the limit, and on asitus__Pieza1 the
 * nets next to its kept caps missed it by 0.5 to 1 degree while the fix-point would have passed them.
 */
static int g1fit_g1_ok(tx *t, const loaded_model *lm, const cm_model *m, int f, const face_surface *fs,
                       const unsigned char *kept)
{
    const cm_face *F = &m->faces[f];
    uint32_t nuse = 0;
    for (uint32_t l = 0; l < F->nloops; l++)
        nuse += m->loops[F->loop0 + l].nuse;
    double worst_kept = 1.0, *use_worst = malloc(((size_t)nuse + 1) * sizeof *use_worst);
    double worst = verify_g1_self(lm, m, f, fs, kept, &worst_kept, use_worst);
    int ok = worst >= G1FIT_COS_HALF && worst_kept >= G1FIT_COS_KEPT;
    if (t->nchosen == 0)
        g1fit_record_check(t, m, f, ok, worst, use_worst);
    free(use_worst);
    return ok;
}

/*
 * What a rebuild that passed §12 must also keep (rb in fs[f] on success): its normals along the
 * face's G1 edges within half the G1 limit of its source surface's (verify_g1_self), and, on a face
 * of more than four edges, the terminal's trimmed mesh within the tolerance (enc_trial_mesh_dev: there
 * the net passed §12 folded over the extra corners, and the mesh strayed 2.5 to 3.7 % of the face's
 * size off the model: asitus___C1G0B0O's ten-sided faces of revolution, ovt__asmo's twelve-sided one,
 * the Open CASCADE round trip of make check).  fe->max becomes what the mesh shows where that is more.
 * fit: the net's correction (format 4.2), or NULL.
 */
static int g1fit_keeps(tx *t, const loaded_model *lm, int f, int corner, uint32_t n, double tol, const cm_rebuilt *rb,
                       const cm_fit_q *fit, const unsigned char *kept, face_error *fe, face_surface *fs,
                       const char **why)
{
    enc_work *w = t->w;
    const cm_model *m = &w->dec.model;
    if (!face_surface_set(&fs[f], rb))
        return 0;
    if (!g1fit_g1_ok(t, lm, m, f, fs, kept)) {
        face_surface_free(&fs[f]);
        *why = "G1FIT off its neighbours' tangent planes at every net";
        return 0;
    }
    if (n > 4) {
        double tess = m->tess_tol;
        double dev = enc_trial_mesh_dev(w, lm, f, CM_METHOD_G1FIT, rb->surf.nu, corner, fit, rb->checksum,
                                        fe->max + tess);
        if (!(dev <= tol + tess)) {
            face_surface_free(&fs[f]);
            *why = "G1FIT's trimmed mesh off the surface at every net";
            return 0;
        }
        if (dev - tess > fe->max)
            fe->max = dev - tess;
    }
    return 1;
}

/* a twist below this (1/4096 of a radian's sine each: about 0.1 degree) is not worth its bits */
#define TWIST_MIN 8

/*
 * Format 4.2: the twists along face f's edges (cm_g1fit.h, cm_g1fit_build).  Along an edge the
 * carried normals are rotation-minimising, but the surface's normal may twist about the edge: on
 * asitus__Pieza1's G1 faces the nets' normals were 10 to 80 degrees off the source's there at every
 * net, and with the source's normals at the edge samples 19 of its 61 G1FIT candidates pass where 6
 * did.  At each inner sample of every edge (the G1 ones alone: 149 faces kept over the corpus, every
 * edge: 139): the sine of the angle, about the edge's unit tangent,
 * from the carried normal N (cm_g1fit_edge_normals, as the terminal computes it) to the source's
 * normal (turned to N's side), quantised to 1/4096.  A record of m = 0 with the twists, or NULL
 * when no edge twists by TWIST_MIN or more (or out of memory).
 */
static fit_record *g1fit_twists(enc_work *w, const loaded_model *lm, int f)
{
    const cm_model *m = &w->dec.model;
    const cm_loop *L = &m->loops[m->faces[f].loop0];
    cm_greg_input *in = malloc(sizeof *in);
    cm_corner_ws *cw = malloc(sizeof *cw);
    fit_record *tw = calloc(1, sizeof *tw);
    int any = 0;
    if (cw)
        cm_corner_cache_end(cw); /* (no cache: its entries and model were malloc's garbage) */
    if (!in || !cw || !tw || cm_greg_input_build(m, (uint32_t)f, 1, in, cw, NULL) != CM_OK || in->n != (int)L->nuse)
        goto done;
    for (int k = 0; k < in->n; k++) {
        const cm_greg_side *gs = &in->side[k];
        cm_vec3 N[CM_FMT_SEG_PER_EDGE + 1];
        if (cm_g1fit_edge_normals(gs, N, NULL) != CM_OK)
            continue;
        for (int j = 1; j <= CM_TWIST_N; j++) {
            double u = (double)j / (double)CM_FMT_SEG_PER_EDGE;
            cm_vec3 q[CM_MAX_DERS + 1], ns;
            if (cm_curve_eval(&gs->curve, gs->rev ? 1.0 - u : u, 1, q, NULL) != CM_OK ||
                !verify_source_normal(lm, f, q[0], &ns))
                continue;
            cm_vec3 T = cm_unit(gs->rev ? cm_neg(q[1]) : q[1]), B = cm_cross(T, N[j]);
            if (!(cm_norm(B) > 0.5))
                continue;
            if (cm_dot(ns, N[j]) < 0)
                ns = cm_neg(ns);
            double s = nearbyint(cm_dot(cm_unit(B), ns) * CM_TWIST_ONE);
            s = s > CM_TWIST_MAX ? CM_TWIST_MAX : (s < -CM_TWIST_MAX ? -CM_TWIST_MAX : s);
            tw->twist[k][j - 1] = (int16_t)s;
        }
        int most = 0;
        for (int j = 0; j < CM_TWIST_N; j++)
            most = abs(tw->twist[k][j]) > most ? abs(tw->twist[k][j]) : most;
        if (most < TWIST_MIN)
            memset(tw->twist[k], 0, sizeof tw->twist[k]); /* untwisted: a bit */
        any |= most >= TWIST_MIN;
    }
    tw->ntwist = in->n;
done:
    free(in);
    free(cw);
    if (!any) {
        free(tw);
        return NULL;
    }
    return tw;
}

/*
 * The first (c, mode) whose rebuild passes §12 and g1fit_keeps: then it meets a kept neighbour, and
 * any rebuilt one that keeps the same promise, within the G1 limit (§13), so the G1 fix-point does
 * not turn it back.  Else, from format 4.2, the nets that came closest with a correction.  Its record
 * (nu = nv = c, mode, the correction) goes to t.
 */
static int g1fit_nets(tx *t, const loaded_model *lm, int f, const encode_opts *o, face_report *rep,
                      face_surface *fs, const unsigned char *kept)
{
    enc_work *w = t->w;
    const cm_model *m = &w->dec.model;
    const cm_face *F = &m->faces[f];
    uint32_t n = m->loops[F->loop0].nuse;
    if (!o->g1fit || n < CM_G1FIT_MIN_EDGES || n > CM_GREG_JOINED_MAX_EDGES)
        return 0;
    double tol = encode_face_tol(o->rel_tol, o->rel_set, o->abs_tol, rep->bbox);
    const char *why = "G1FIT over the error at every net";
    enc_net_near near[G1FIT_TRIES];
    int nnear = 0;
    /* format 4.2: the surface's twist along the edges, sent where the carried normals miss it */
    fit_record *tw = NULL;
    cm_fit_q tview;
    if (enc_net_fit(o) && (tw = g1fit_twists(w, lm, f)) != NULL)
        tview = fit_record_view(tw);
    for (size_t i = 0; i < sizeof g1fit_ctrl / sizeof g1fit_ctrl[0]; i++) {
        int c = g1fit_ctrl[i];
        if (c > CM_MAX_FIT_CTRL)
            break;
        for (size_t j = 0; j < sizeof g1fit_modes / sizeof g1fit_modes[0]; j++) {
            int mode = g1fit_modes[j], corner = c | mode << 8;
            cm_rebuilt rb;
            cm_err e = enc_trial_rebuild(w, f, CM_METHOD_G1FIT, c, corner, tw ? &tview : NULL, &rb);
            if (e == CM_E_DEGENERATE || e == CM_E_UNSUPPORTED || e == CM_E_RANGE) {
                if (!rep->why)
                    rep->why = "G1FIT: a side of no length";
                free(tw);
                return 0;
            }
            if (e != CM_OK)
                continue;
            face_error fe;
            if (!verify_face(lm, m, f, &rb, tol, &fe)) {
                free(tw);
                return 0;
            }
            if (!(fe.max < tol)) {
                /* a candidate for a correction, when the border keeps its promise (the correction
                   leaves the border rows: a net whose G1 fails here fails corrected) */
                if (enc_net_fit(o) && fe.max < ENC_NET_REACH * tol && c > 4 && face_surface_set(&fs[f], &rb)) {
                    if (g1fit_g1_ok(t, lm, m, f, fs, kept))
                        near[nnear++] = (enc_net_near){c, mode, fe.max};
                    face_surface_free(&fs[f]);
                }
                continue;
            }
            if (!g1fit_keeps(t, lm, f, corner, n, tol, &rb, tw ? &tview : NULL, kept, &fe, fs, &why))
                continue;
            enc_fit_accept(t, f, c, corner, mode, &rb, &fe, rep);
            free(t->fit[f]);
            t->fit[f] = tw; /* the twists travel in the record (a correction of m = 0) */
            return 1;
        }
    }
    enc_net_near_sort(near, nnear);
    for (int i = 0; i < nnear && i < ENC_NET_TRIED; i++) {
        fit_record *fr = malloc(sizeof *fr);
        face_error fe;
        if (!fr) {
            free(tw);
            return 0;
        }
        int corner = near[i].c | near[i].variant << 8;
        cm_rebuilt rb;
        cm_fit_q view;
        /* the correction leaves the border rows: the G1 check is the plain net's */
        if (!enc_net_corrected(w, lm, f, CM_METHOD_G1FIT, near[i].c, corner, tol, tw, fr, &fe, &rb) ||
            !(view = fit_record_view(fr), g1fit_keeps(t, lm, f, corner, n, tol, &rb, &view, kept, &fe, fs, &why))) {
            free(fr);
            continue;
        }
        const char *first = rep->why; /* the first reason stays (below) */
        if (enc_net_take(t, f, fr, near[i].c, corner, near[i].variant, &rb, &fe, rep)) {
            free(tw);
            return 1;
        }
        face_surface_free(&fs[f]);
        why = rep->why;
        rep->why = first;
    }
    free(tw);
    if (!rep->why)
        rep->why = why;
    return 0;
}

static int try_g1fit(tx *t, const loaded_model *lm, int f, const encode_opts *o, face_report *rep,
                     face_surface *fs)
{
    unsigned char *kept = g1fit_kept_neighbours(t);
    int ok = g1fit_nets(t, lm, f, o, rep, fs, kept);
    free(kept);
    return ok;
}

const enc_method enc_method_g1fit = {CM_METHOD_G1FIT, try_g1fit, NULL};
