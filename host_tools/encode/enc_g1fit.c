/* enc_g1fit.c - the encoder's half of G1FIT (cm_g1fit.h; decoder/methods/g1fit.c). */
#include "enc_method.h"

#include <math.h>

#include "cm/cm_const.h"
#include "cm/cm_g1fit.h"
#include "cm/cm_method.h"

/* nets tried, smallest first (NFILL's sizes, spec 8.9) ... */
static const int g1fit_ctrl[] = {4, 5, 6, 8, 10, 12, 16, 20, 24};
/* ... each with the Coons interior, then the faired one (the record's mode) */
static const int g1fit_modes[] = {0, 1};

/*
 * The first (c, mode) whose rebuild passes §12 and whose normals along the face's G1 edges are within
 * half the G1 limit of its source surface's (verify_g1_self): then it meets a kept neighbour, and any
 * rebuilt one that keeps the same promise, within the limit (§13), so the G1 fix-point does not turn
 * it back.  Its record (nu = nv = c, mode) goes to t.
 */
static int try_g1fit(tx *t, const loaded_model *lm, int f, const encode_opts *o, face_report *rep,
                     face_surface *fs)
{
    enc_work *w = t->w;
    const cm_model *m = &w->dec.model;
    const cm_face *F = &m->faces[f];
    uint32_t n = m->loops[F->loop0].nuse;
    /* four edges only, though the format takes 4..12: on faces of more edges the net passed §12
       folded over their extra corners, and the terminal's trimmed mesh strayed 2.5 to 3.7 % of the
       face's size off the model (asitus___C1G0B0O's ten-sided faces of revolution, ovt__asmo's
       twelve-sided one, whose joints are all within 20 degrees of flat: the Open CASCADE round trip
       of make check); the encoder's §12 does not see a trimmed mesh */
    if (!o->g1fit || n != 4)
        return 0;
    double tol = encode_face_tol(o->rel_tol, o->rel_set, o->abs_tol, rep->bbox);
    /* half the G1 limit: cos(acos(CM_COS_G1) / 2) */
    double cos_half = sqrt(0.5 * (1.0 + CM_COS_G1));
    const char *why = "G1FIT over the error at every net";
    for (size_t i = 0; i < sizeof g1fit_ctrl / sizeof g1fit_ctrl[0]; i++) {
        int c = g1fit_ctrl[i];
        if (c > CM_MAX_FIT_CTRL)
            break;
        for (size_t j = 0; j < sizeof g1fit_modes / sizeof g1fit_modes[0]; j++) {
            int mode = g1fit_modes[j], corner = c | mode << 8;
            cm_rebuilt rb;
            cm_err e = enc_trial_rebuild(w, f, CM_METHOD_G1FIT, c, corner, NULL, &rb);
            if (e == CM_E_DEGENERATE || e == CM_E_UNSUPPORTED || e == CM_E_RANGE) {
                if (!rep->why)
                    rep->why = "G1FIT: a side of no length";
                return 0;
            }
            if (e != CM_OK)
                continue;
            face_error fe;
            if (!verify_face(lm, m, f, &rb, tol, &fe))
                return 0;
            if (!(fe.max < tol))
                continue;
            if (!face_surface_set(&fs[f], &rb))
                return 0;
            if (!(verify_g1_self(lm, m, f, fs) >= cos_half)) {
                face_surface_free(&fs[f]);
                why = "G1FIT off its neighbours' tangent planes at every net";
                continue;
            }
            enc_fit_accept(t, f, c, corner, mode, &rb, &fe, rep);
            return 1;
        }
    }
    if (!rep->why)
        rep->why = why;
    return 0;
}

const enc_method enc_method_g1fit = {CM_METHOD_G1FIT, try_g1fit, NULL};
