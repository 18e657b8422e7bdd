/* cm_rebuild.c - a face's surface rebuilt by its method's module (see cm_rebuild.h, cm_method.h). */
#include "cm/cm_rebuild.h"

#include "cm/cm_method.h"

cm_err cm_rebuild_face(const cm_model *m, uint32_t f, cm_rebuilt *out, cm_rebuild_ws *ws, cm_status *st)
{
    return cm_rebuild_face_ex(m, f, 1, out, ws, st);
}

cm_err cm_rebuild_face_ex(const cm_model *m, uint32_t f, int check, cm_rebuilt *out, cm_rebuild_ws *ws,
                          cm_status *st)
{
    const cm_face *F = &m->faces[f];
    int n, n_outer;
    cm_err e = cm_face_samples(m, f, ws->samples, CM_MAX_FACE_SAMPLES, &n, &n_outer, st);
    if (e != CM_OK)
        return e;
    const cm_method *meth = cm_method_of(F->method);
    if (!meth)
        return cm_fail(st, CM_E_UNSUPPORTED, "face method");
    out->method = F->method;
    out->repr = CM_REPR_FRAME;
    out->sign = 1.0;
    out->bbox = cm_points_diag(ws->samples, n);
    out->greg = NULL;
    out->checksum = 0;
    return cm_method_rebuild(meth, m, f, check, n, n_outer, out, ws, st);
}
