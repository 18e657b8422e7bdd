/* cm_frame.c - face frame from boundary samples (spec K11). */
#include "cm/cm_geom.h"

cm_err cm_face_frame(const cm_vec3 *outer, int n_outer, const cm_vec3 *all, int n_all, double eps_len, cm_frame *f,
                     cm_status *st)
{
    if (n_outer < 3 || n_all < n_outer)
        return cm_fail(st, CM_E_DEGENERATE, __func__);
    cm_vec3 o = cm_v3(0, 0, 0);
    for (int k = 0; k < n_all; k++)
        o = cm_add(o, all[k]);
    o = cm_scale(o, 1.0 / (double)n_all);

    /* Newell normal of the outer loop, relative to o */
    cm_vec3 n = cm_v3(0, 0, 0);
    for (int k = 0; k < n_outer; k++) {
        cm_vec3 a = cm_sub(outer[k], o), b = cm_sub(outer[(k + 1) % n_outer], o);
        n = cm_add(n, cm_cross(a, b));
    }
    double nl = cm_norm(n);
    if (!(nl > eps_len * eps_len))
        return cm_fail(st, CM_E_DEGENERATE, __func__);
    cm_vec3 ez = cm_scale(n, 1.0 / nl);

    /* provisional in-plane basis (t1, t2) for the 2x2 covariance */
    cm_vec3 t1 = cm_cross(ez, cm_v3(1, 0, 0));
    if (cm_norm2(t1) < 1e-2)
        t1 = cm_cross(ez, cm_v3(0, 1, 0));
    t1 = cm_unit(t1);
    cm_vec3 t2 = cm_cross(ez, t1);
    double a = 0.0, b = 0.0, c = 0.0;
    for (int k = 0; k < n_all; k++) {
        cm_vec3 r = cm_sub(all[k], o);
        double x = cm_dot(r, t1), y = cm_dot(r, t2);
        a += x * x;
        b += x * y;
        c += y * y;
    }
    /* major eigenvector of [[a,b],[b,c]]: (b, lam-a) or (lam-c, b), the longer */
    double h = (a - c) / 2.0;
    double lam = (a + c) / 2.0 + sqrt(h * h + b * b);
    double v1x = b, v1y = lam - a, v2x = lam - c, v2y = b;
    double l1 = v1x * v1x + v1y * v1y, l2 = v2x * v2x + v2y * v2y;
    double vx = l1 >= l2 ? v1x : v2x, vy = l1 >= l2 ? v1y : v2y;
    double lmax = l1 >= l2 ? l1 : l2;
    cm_vec3 ex;
    double scale = a + c;
    if (!(lmax > 1e-20 * scale * scale)) {
        /* isotropic samples (circle, square): any in-plane axis; spec's fixed choice */
        ex = t1;
    } else {
        ex = cm_unit(cm_add(cm_scale(t1, vx), cm_scale(t2, vy)));
    }
    if (cm_dot(cm_sub(outer[0], o), ex) > 0.0)
        ex = cm_neg(ex);
    f->o = o;
    f->ez = ez;
    f->ex = ex;
    f->ey = cm_cross(ez, ex);
    return CM_OK;
}

cm_vec3 cm_frame_local(const cm_frame *f, cm_vec3 p)
{
    cm_vec3 r = cm_sub(p, f->o);
    return cm_v3(cm_dot(r, f->ex), cm_dot(r, f->ey), cm_dot(r, f->ez));
}

cm_vec3 cm_frame_world(const cm_frame *f, cm_vec3 l)
{
    return cm_add(cm_add(cm_add(f->o, cm_scale(f->ex, l.x)), cm_scale(f->ey, l.y)), cm_scale(f->ez, l.z));
}
