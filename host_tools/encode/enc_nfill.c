/* enc_nfill.c - the encoder's half of NFILL (spec §8.9; decoder/methods/nfill.c). */
#include "enc_method.h"
#include "fit_correction.h"

#include <stdlib.h>

#include "cm/cm_method.h"
#include "cm/cm_nfill.h"

/* spec 8.9: nets tried, smallest first (while the unknowns are at most half the data) ... */
static const int nfill_ctrl[] = {4, 5, 6, 8, 10, 12, 16, 20, 24};
/* ... and for each, the fairing weights in this order (indices into cm_nfill_phi: 1e-3, 1e-2, 1e-4,
   1e-1) */
static const int nfill_phi_order[] = {2, 3, 1, 4};
#define NFILL_TRIES (sizeof nfill_ctrl / sizeof nfill_ctrl[0] * sizeof nfill_phi_order / sizeof nfill_phi_order[0])

/*
 * Spec §8.9: the first (c, phi) in that order whose rebuild passes §12 wins; its record (nu = nv = c,
 * phi) goes to t.  A loop NFILL cannot take, or rays that leave a side of the rectangle with fewer
 * than 4 hits (no net fits it at all), ends the search at once.  From format 4.2, when none passes,
 * the nets that came closest with an interior correction.
 */
static int try_nfill(tx *t, const loaded_model *lm, int f, const encode_opts *o, face_report *rep,
                     face_surface *fs)
{
    enc_work *w = t->w;
    const cm_model *m = &w->dec.model;
    const cm_face *F = &m->faces[f];
    uint32_t n = m->loops[F->loop0].nuse, all = 0;
    for (uint32_t l = 0; l < F->nloops; l++)
        all += m->loops[F->loop0 + l].nuse;
    if (!o->nfill || n < 3 || n > CM_GREG_JOINED_MAX_EDGES || all > CM_NFILL_MAX_ALL_EDGES)
        return 0;
    double tol = encode_face_tol(o->rel_tol, o->rel_set, o->abs_tol, rep->bbox);
    /* boundary samples, and at most 3 ray samples for each of the outer loop's */
    int data = (int)(all + 3 * n) * CM_FMT_SEG_PER_EDGE;
    enc_net_near near[NFILL_TRIES];
    int nnear = 0;
    for (size_t i = 0; i < sizeof nfill_ctrl / sizeof nfill_ctrl[0]; i++) {
        int c = nfill_ctrl[i];
        if (c > CM_MAX_FIT_CTRL || 2 * (c - 2) * (c - 2) > data)
            break;
        for (size_t j = 0; j < sizeof nfill_phi_order / sizeof nfill_phi_order[0]; j++) {
            int phi = nfill_phi_order[j], corner = c | phi << 8;
            cm_rebuilt rb;
            cm_err e = enc_trial_rebuild(w, f, CM_METHOD_NFILL, c, corner, NULL, &rb);
            if (e == CM_E_DEGENERATE || e == CM_E_UNSUPPORTED || e == CM_E_LIMIT) {
                if (!rep->why)
                    rep->why = "NFILL: a side of its rectangle gets too few rays";
                return 0;
            }
            if (e != CM_OK)
                continue;
            face_error fe;
            if (!verify_face(lm, m, f, &rb, tol, &fe))
                return 0;
            if (!(fe.max < tol)) {
                if (enc_net_fit(o) && fe.max < ENC_NET_REACH * tol && c > 4)
                    near[nnear++] = (enc_net_near){c, phi, fe.max};
                continue;
            }
            enc_fit_accept(t, f, c, corner, phi, &rb, &fe, rep);
            return face_surface_set(&fs[f], &rb);
        }
    }
    enc_net_near_sort(near, nnear);
    rep->why = "NFILL over the error at every net";
    for (int i = 0; i < nnear && i < ENC_NET_TRIED; i++) {
        fit_record *fr = malloc(sizeof *fr);
        if (!fr)
            return 0;
        int corner = near[i].c | near[i].variant << 8;
        cm_rebuilt rb;
        face_error fe;
        if (!enc_net_corrected(w, lm, f, CM_METHOD_NFILL, near[i].c, corner, tol, NULL, fr, &fe, &rb)) {
            free(fr);
            continue;
        }
        if (!face_surface_set(&fs[f], &rb)) {
            free(fr);
            return 0;
        }
        if (enc_net_take(t, f, fr, near[i].c, corner, near[i].variant, &rb, &fe, rep))
            return 1;
        face_surface_free(&fs[f]);
    }
    return 0;
}

const enc_method enc_method_nfill = {CM_METHOD_NFILL, try_nfill, NULL};
