/*
 * keep.c - KEEP: the face's own surface travels in the SURF section
 * (docs/METHODS.md).  The fallback of every other method: always
 * applicable, exact by construction, and the most bytes.
 */
#include "cm_method_impl.h"

/* the kept surface, already decoded into the model; the face's loops are projected onto it */
cm_err cm_keep_rebuild(const cm_model *m, uint32_t f, int check, int n, int n_outer, cm_rebuilt *out, cm_rebuild_ws *ws,
                       cm_status *st)
{
    (void)check;
    (void)n;
    (void)n_outer;
    (void)ws;
    (void)st;
    const cm_face *F = &m->faces[f];
    cm_model_surface(m, F->surf, &out->surf);
    out->repr = CM_REPR_NURBS;
    /* a kept surface's normal may point into the part: the record's flip turns the face */
    out->sign = F->flip ? -1.0 : 1.0;
    return CM_OK;
}

const cm_method cm_method_keep = {
    .name = "keep",
    .counted = "kept",
    .id = CM_METHOD_KEEP,
    .since_major = 1,
    .kept_surface = 1,
};
