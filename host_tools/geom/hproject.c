/* hproject.c - projection onto host surfaces with continuation and periodic parameters. */
#include "hproject.h"

#include <math.h>
#include <stddef.h>

#include "cm/cm_lsq.h"

hsurf_param hsurf_param_of(const hsurf *s, double tol)
{
    hsurf_param sp;
    sp.s = s;
    hsurf_domain(s, &sp.u0, &sp.u1, &sp.v0, &sp.v1);
    sp.closed_u = hsurf_closed_u(s, tol);
    sp.closed_v = hsurf_closed_v(s, tol);
    return sp;
}

static double wrap(double x, double a, double b, int periodic)
{
    if (periodic) {
        double p = b - a;
        double k = floor((x - a) / p);
        x -= k * p;
        if (x > b) /* rounding at the seam */
            x = b;
        return x;
    }
    return x < a ? a : (x > b ? b : x);
}

cm_err hsurf_param_eval(const hsurf_param *sp, double u, double v, cm_vec3 d[3], cm_status *st)
{
    cm_surf view = hsurf_view(sp->s);
    cm_vec3 S[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
    cm_err e = cm_surf_eval(&view, wrap(u, sp->u0, sp->u1, sp->closed_u), wrap(v, sp->v0, sp->v1, sp->closed_v), 1, S, st);
    if (e != CM_OK)
        return e;
    d[0] = S[0][0];
    d[1] = S[1][0];
    d[2] = S[0][1];
    return CM_OK;
}

cm_err hsurf_project_from(const hsurf_param *sp, cm_vec3 P, double *u, double *v, double *dist, cm_status *st)
{
    double uu = *u, vv = *v;
    if (!sp->closed_u)
        uu = wrap(uu, sp->u0, sp->u1, 0);
    if (!sp->closed_v)
        vv = wrap(vv, sp->v0, sp->v1, 0);
    cm_vec3 d[3];
    cm_err e = hsurf_param_eval(sp, uu, vv, d, st);
    if (e != CM_OK)
        return e;
    double f = cm_norm2(cm_sub(d[0], P)), mu = 1e-3;
    double du = sp->u1 - sp->u0, dv = sp->v1 - sp->v0;
    for (int it = 0; it < 60; it++) {
        cm_vec3 r = cm_sub(d[0], P);
        double J[4] = {cm_dot(d[1], d[1]), cm_dot(d[1], d[2]), cm_dot(d[1], d[2]), cm_dot(d[2], d[2])};
        double g[2] = {-cm_dot(d[1], r), -cm_dot(d[2], r)};
        double tr = J[0] + J[3];
        if (!(tr > 0))
            break;
        double A[4] = {J[0] + mu * tr, J[1], J[2], J[3] + mu * tr}, x[2];
        if (cm_solve2(A, g, 0.0, x, NULL) != CM_OK)
            break;
        double un = uu + x[0], vn = vv + x[1];
        if (!sp->closed_u)
            un = wrap(un, sp->u0, sp->u1, 0);
        if (!sp->closed_v)
            vn = wrap(vn, sp->v0, sp->v1, 0);
        double step = fabs(un - uu) / du + fabs(vn - vv) / dv;
        cm_vec3 dn[3];
        if ((e = hsurf_param_eval(sp, un, vn, dn, st)) != CM_OK)
            return e;
        double fn = cm_norm2(cm_sub(dn[0], P));
        if (fn <= f) {
            uu = un;
            vv = vn;
            f = fn;
            d[0] = dn[0];
            d[1] = dn[1];
            d[2] = dn[2];
            mu = fmax(mu / 10, 1e-12);
        } else {
            mu *= 10;
            if (mu > 1e8)
                break;
        }
        if (step < 1e-14)
            break;
    }
    *u = uu;
    *v = vv;
    if (dist)
        *dist = sqrt(f);
    return CM_OK;
}

cm_err hsurf_project_grid(const hsurf_param *sp, cm_vec3 P, int n, double *u, double *v, double *dist, cm_status *st)
{
    double bu = sp->u0, bv = sp->v0, bf = HUGE_VAL;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double ui = sp->u0 + (sp->u1 - sp->u0) * i / (n - 1), vj = sp->v0 + (sp->v1 - sp->v0) * j / (n - 1);
            cm_vec3 d[3];
            cm_err e = hsurf_param_eval(sp, ui, vj, d, st);
            if (e != CM_OK)
                return e;
            double fi = cm_norm2(cm_sub(d[0], P));
            if (fi < bf) {
                bf = fi;
                bu = ui;
                bv = vj;
            }
        }
    *u = bu;
    *v = bv;
    return hsurf_project_from(sp, P, u, v, dist, st);
}
