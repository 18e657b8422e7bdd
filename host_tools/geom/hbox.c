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
