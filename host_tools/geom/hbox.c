/* hbox.c - axis-aligned boxes in model space (see hbox.h). */
#include "geom/hbox.h"

#include <math.h>
#include <stddef.h>

hbox hbox_empty(void)
{
    hbox b;
    b.lo = cm_v3(HUGE_VAL, HUGE_VAL, HUGE_VAL);
    b.hi = cm_v3(-HUGE_VAL, -HUGE_VAL, -HUGE_VAL);
    b.empty = 1;
    return b;
}

void hbox_add(hbox *b, cm_vec3 p)
{
    if (!cm_finite3(p))
        return;
    b->lo = cm_v3(fmin(b->lo.x, p.x), fmin(b->lo.y, p.y), fmin(b->lo.z, p.z));
    b->hi = cm_v3(fmax(b->hi.x, p.x), fmax(b->hi.y, p.y), fmax(b->hi.z, p.z));
    b->empty = 0;
}

void hbox_add_curve(hbox *b, const hcurve *c)
{
    cm_curve v = hcurve_view(c);
    double t0, t1;
    hcurve_domain(c, &t0, &t1);
    int spans = c->n - c->p;
    int ns = 33 * (spans > 0 ? spans : 1);
    if (ns > 2000)
        ns = 2000;
    for (int k = 0; k <= ns; k++) {
        cm_vec3 d[1];
        if (cm_curve_eval(&v, t0 + (t1 - t0) * k / ns, 0, d, NULL) == CM_OK)
            hbox_add(b, d[0]);
    }
}

/* X, Y completing Z to a right-handed frame; X along `ref` when given (not parallel to Z) */
void hbox_frame(cm_vec3 Z, const cm_vec3 *ref, cm_vec3 *X, cm_vec3 *Y)
{
    cm_vec3 x = ref ? cm_sub(*ref, cm_scale(Z, cm_dot(*ref, Z))) : cm_v3(0, 0, 0);
    if (!(cm_norm(x) > 1e-9)) {
        x = cm_cross(Z, cm_v3(1, 0, 0));
        if (cm_norm(x) < 0.1)
            x = cm_cross(Z, cm_v3(0, 1, 0));
    }
    *X = cm_unit(x);
    *Y = cm_cross(Z, *X);
}

/* extent of the face along an axis/in a plane: the 8 corners of its box, 10 % margin */
void hbox_axis_range(const hbox *b, cm_vec3 o, cm_vec3 dir, double *lo, double *hi)
{
    *lo = HUGE_VAL;
    *hi = -HUGE_VAL;
    for (int k = 0; k < 8; k++) {
        cm_vec3 c = cm_v3(k & 1 ? b->hi.x : b->lo.x, k & 2 ? b->hi.y : b->lo.y, k & 4 ? b->hi.z : b->lo.z);
        double t = cm_dot(cm_sub(c, o), dir);
        *lo = fmin(*lo, t);
        *hi = fmax(*hi, t);
    }
    double span = *hi - *lo, diag = cm_dist(b->lo, b->hi);
    double margin = 0.1 * (span > 0 ? span : diag) + 1e-9 * diag;
    *lo -= margin;
    *hi += margin;
}
