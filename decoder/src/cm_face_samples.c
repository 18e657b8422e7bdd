/* cm_face_samples.c - a face's fixed boundary samples and its size (see cm_face_samples.h). */
#include "cm/cm_face_samples.h"

#include "cm/cm_bspline.h"
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
