/* enc_net_fit.c - a fitted net (NFILL, G1FIT) with format 4.2's interior correction, tried (see
   enc_method.h, enc_net_corrected; the fit itself: fit_net.c). */
#include "enc_method.h"
#include "fit_correction.h"

#include <stdlib.h>
#include <string.h>

#include "cm/cm_patchfit.h"

/* G1FIT's twists (base, or none) in a correction's record */
static void with_twists(fit_record *fr, const fit_record *base)
{
    fr->ntwist = base ? base->ntwist : 0;
    fr->hint_mask = 0; /* (the GREGORY family's alone) */
    if (base)
        memcpy(fr->twist, base->twist, sizeof fr->twist);
}

/*
 * The functions of a smaller m are combinations of those of the largest (Bernstein degree
 * elevation), so the largest the net's interior takes is fitted first and the net given up when it
 * fails (most trials fail: this is the encoder's time); then m = 1, 2, ... for a smaller record.
 */
int enc_net_corrected(enc_work *w, const loaded_model *lm, int f, int method, int layout, int corner, double tol,
                      const fit_record *base, fit_record *fr, face_error *fe, cm_rebuilt *rb)
{
    const cm_model *m = &w->dec.model;
    int bface = lm->mesh.faces[f].brep_face;
    face_surface net = {0}; /* the plain net (the next rebuild reuses the workspace) */
    fit_record *best = malloc(sizeof *best);
    cm_fit_q bview;
    if (base)
        bview = fit_record_view(base);
    int ok = best && enc_trial_rebuild(w, f, method, layout, corner, base ? &bview : NULL, rb) == CM_OK &&
             rb->repr == CM_REPR_NURBS && face_surface_set(&net, rb);
    int top = ok ? net.nurbs.nu - 4 : 0;
    if (ok && net.nurbs.nv - 4 < top)
        top = net.nurbs.nv - 4;
    if (top > CM_FIT_MAX_M)
        top = CM_FIT_MAX_M;
    ok = ok && top >= 1 && fit_net_correction(lm, bface, &net.nurbs, top, tol, m->q, best);
    if (ok)
        with_twists(best, base);
    cm_fit_q view;
    if (ok) {
        view = fit_record_view(best);
        ok = enc_trial_rebuild(w, f, method, layout, corner, &view, rb) == CM_OK &&
             verify_face(lm, m, f, rb, tol, fe) && fe->max < tol;
    }
    int smaller = 0;
    for (int k = 1; ok && k < top && !smaller; k++) {
        if (!fit_net_correction(lm, bface, &net.nurbs, k, tol, m->q, fr))
            continue;
        with_twists(fr, base);
        view = fit_record_view(fr);
        face_error e;
        smaller = enc_trial_rebuild(w, f, method, layout, corner, &view, rb) == CM_OK &&
                  verify_face(lm, m, f, rb, tol, &e) && e.max < tol;
        if (smaller)
            *fe = e;
    }
    if (ok && !smaller) {
        /* the largest after all: rebuilt again (the tries since reused the workspace) */
        *fr = *best;
        view = fit_record_view(fr);
        ok = enc_trial_rebuild(w, f, method, layout, corner, &view, rb) == CM_OK;
    }
    face_surface_free(&net);
    free(best);
    return ok;
}

void enc_net_near_sort(enc_net_near *near, int n)
{
    for (int i = 1; i < n; i++)
        for (int k = i; k > 0 && near[k].err < near[k - 1].err; k--) {
            enc_net_near x = near[k];
            near[k] = near[k - 1];
            near[k - 1] = x;
        }
}

int enc_net_take(tx *t, int f, fit_record *fr, int layout, int corner, int shown, const cm_rebuilt *rb,
                 const face_error *fe, face_report *rep)
{
    if (enc_fit_record_bits(fr) >= enc_kept_surface_bits(&t->surfs[f], t->o->predicted)) {
        free(fr);
        rep->why = "record larger than the surface";
        return 0;
    }
    free(t->fit[f]);
    t->fit[f] = fr;
    enc_fit_accept(t, f, layout, corner, shown, rb, fe, rep);
    rep->fit_m = fr->m;
    return 1;
}
