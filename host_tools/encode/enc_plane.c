/* enc_plane.c - the encoder's half of PLANE (spec 5A; decoder/methods/plane.c). */
#include "enc_method.h"

#include <math.h>

#include "cm/cm_method.h"

/* spec 5A applicability and §12 verification of PLANE for face f of the decoded model */
static int try_plane(tx *t, const loaded_model *lm, int f, const encode_opts *o, face_report *rep, face_surface *fs)
{
    enc_work *w = t->w;
    cm_model *m = &w->dec.model;
    cm_rebuilt rb;
    if (enc_trial_rebuild(w, f, CM_METHOD_PLANE, 0, 0, NULL, &rb) != CM_OK)
        return 0;
    double tol = encode_face_tol(o->rel_tol, o->rel_set, o->abs_tol, rb.bbox);
    int n, n_outer;
    if (cm_face_samples(m, (uint32_t)f, w->rbws.samples, CM_MAX_FACE_SAMPLES, &n, &n_outer, NULL) != CM_OK)
        return 0;
    double dev = 0;
    for (int i = 0; i < n; i++)
        dev = fmax(dev, fabs(cm_frame_local(&rb.frame, w->rbws.samples[i]).z));
    rep->plane_dev = dev;
    rep->bbox = rb.bbox;
    if (dev > 0.25 * tol)
        return 0; /* spec 5A: the boundary is not flat enough */
    face_error fe;
    if (!verify_face(lm, m, f, &rb, tol, &fe))
        return 0;
    rep->rebuild_max = fe.max;
    rep->rebuild_avg = fe.avg;
    rep->ratio = fe.ratio;
    if (!(fe.max < tol))
        return 0;
    return face_surface_set(&fs[f], &rb);
}

const enc_method enc_method_plane = {CM_METHOD_PLANE, try_plane, NULL};
