/* cm_rebuild.c - PLANE, GREGORY and KEEP reconstruction of a face (see cm_rebuild.h). */
#include "cm/cm_rebuild.h"

#include <stddef.h>

#include "cm/cm_limits_info.h"

cm_err cm_face_samples(const cm_model *m, uint32_t f, cm_vec3 *out, int cap, int *n, int *n_outer, cm_status *st)
{
    const cm_face *F = &m->faces[f];
    int k = 0;
    *n_outer = 0;
    for (uint32_t l = 0; l < F->nloops; l++) {
        const cm_loop *L = &m->loops[F->loop0 + l];
        for (uint32_t u = 0; u < L->nuse; u++) {
            const cm_use *U = &m->uses[L->use0 + u];
            cm_curve c;
            cm_model_edge_curve(m, U->edge, &c);
            if (k + CM_FMT_SEG_PER_EDGE > cap)
                return cm_fail_limit(st, CM_LIMIT_MAX_FACE_EDGES, (uint64_t)(k / CM_FMT_SEG_PER_EDGE + 1),
                                     CM_MAX_FACE_EDGES, __func__);
            for (int s = 0; s < CM_FMT_SEG_PER_EDGE; s++) {
                double t = (double)s / (double)CM_FMT_SEG_PER_EDGE;
                cm_vec3 d[1];
                cm_err e = cm_curve_eval(&c, U->rev ? 1.0 - t : t, 0, d, st);
                if (e != CM_OK)
                    return e;
                out[k++] = d[0];
            }
        }
        if (l == 0)
            *n_outer = k;
    }
    *n = k;
    return CM_OK;
}

double cm_points_diag(const cm_vec3 *p, int n)
{
    cm_vec3 lo = p[0], hi = p[0];
    for (int i = 1; i < n; i++) {
        lo = cm_v3(p[i].x < lo.x ? p[i].x : lo.x, p[i].y < lo.y ? p[i].y : lo.y, p[i].z < lo.z ? p[i].z : lo.z);
        hi = cm_v3(p[i].x > hi.x ? p[i].x : hi.x, p[i].y > hi.y ? p[i].y : hi.y, p[i].z > hi.z ? p[i].z : hi.z);
    }
    return cm_dist(lo, hi);
}

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
    out->method = F->method;
    out->bbox = cm_points_diag(ws->samples, n);
    out->greg = NULL;
    out->checksum = 0;
    if (F->method == CM_METHOD_KEEP) {
        cm_model_surface(m, F->surf, &out->surf);
        return CM_OK;
    }
    if (F->method == CM_METHOD_GREGORY) {
        if ((e = cm_greg_input_build(m, f, &ws->gin, &ws->corner, st)) != CM_OK)
            return e;
        if ((e = cm_greg_build(&ws->gin, F->layout, F->corner, &ws->greg, st)) != CM_OK)
            return e;
        out->greg = &ws->greg;
        out->checksum = cm_greg_surface_checksum(&ws->greg);
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
        check = 0; /* as with the CRCs: mutated records must reach the tessellation */
#endif
        if (check && out->checksum != F->checksum)
            return cm_fail(st, CM_E_CHECKSUM, "GREGORY face rebuilt differently from the encoder");
        return CM_OK;
    }
    /* PLANE (spec 5A): EPS_LEN = 1e-12 of the model is approximated by the face here: the
     * frame only needs "zero" relative to the loop it is built from */
    if ((e = cm_face_frame(ws->samples, n_outer, ws->samples, n, 1e-12 * out->bbox, &out->frame, st)) != CM_OK)
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
    return CM_OK;
}
