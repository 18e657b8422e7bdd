/*
 * plane.c - PLANE (spec 5A, docs/METHODS.md): a flat face rebuilt from its
 * boundary alone.  The record holds nothing; the K11 frame of the
 * boundary samples gives the plane, and the rectangle of their (x, y)
 * enlarged by 1 % per side a bilinear patch that covers the face.
 */
#include "cm_method_impl.h"

#include "cm/cm_const.h"
cm_err cm_plane_rebuild(const cm_model *m, uint32_t f, int check, int n, int n_outer, cm_rebuilt *out,
                        cm_rebuild_ws *ws, cm_status *st)
{
    (void)m;
    (void)f;
    (void)check;
    /* the frame only needs "zero" relative to the loop it is built from */
    cm_err e = cm_face_frame(ws->samples, n_outer, ws->samples, n, CM_EPS_LEN_REL * out->bbox, &out->frame, st);
    if (e != CM_OK)
        return e;
    double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
    for (int i = 0; i < n; i++) {
        cm_vec3 l = cm_frame_local(&out->frame, ws->samples[i]);
        if (i == 0 || l.x < x0)
            x0 = l.x;
        if (i == 0 || l.x > x1)
            x1 = l.x;
        if (i == 0 || l.y < y0)
            y0 = l.y;
        if (i == 0 || l.y > y1)
            y1 = l.y;
    }
    double ex = 0.01 * (x1 - x0), ey = 0.01 * (y1 - y0);
    out->rect[0] = x0 - ex;
    out->rect[1] = x1 + ex;
    out->rect[2] = y0 - ey;
    out->rect[3] = y1 + ey;
    /* bilinear patch, degree 1 x 1, row-major in u (= x) */
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++)
            out->plane_ctrl[i * 2 + j] = cm_frame_world(&out->frame, cm_v3(out->rect[i], out->rect[2 + j], 0.0));
    out->plane_knots[0] = out->plane_knots[1] = 0.0;
    out->plane_knots[2] = out->plane_knots[3] = 1.0;
    out->surf.p = out->surf.q = 1;
    out->surf.nu = out->surf.nv = 2;
    out->surf.U = out->surf.V = out->plane_knots;
    out->surf.ctrl = out->plane_ctrl;
    out->surf.w = NULL;
    out->repr = CM_REPR_FRAME; /* ez is the face normal: the frame is built from the oriented loop */
    return CM_OK;
}

const cm_method cm_method_plane = {
    .name = "plane",
    .counted = "plane",
    .id = CM_METHOD_PLANE,
    .since_major = 1,
};
