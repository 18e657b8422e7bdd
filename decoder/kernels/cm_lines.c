/* cm_lines.c - closest points of two lines, ray/plane intersection (spec K10), a chord's S part. */
#include "cm/cm_geom.h"

int cm_lines_closest(cm_vec3 p, cm_vec3 d, cm_vec3 q, cm_vec3 e, double *lam, double *mu)
{
    double dd = cm_dot(d, d), ee = cm_dot(e, e), de = cm_dot(d, e);
    if (cm_norm2(cm_cross(d, e)) < 1e-12 * dd * ee)
        return 0;
    /* (p + lam d - q - mu e).d = 0 and .e = 0 */
    cm_vec3 w = cm_sub(p, q);
    double wd = cm_dot(w, d), we = cm_dot(w, e);
    double det = dd * ee - de * de;
    *lam = (de * we - ee * wd) / det;
    *mu = (dd * we - de * wd) / det;
    return 1;
}

int cm_ray_plane(cm_vec3 p, cm_vec3 d, cm_vec3 m, double c, double *lam)
{
    double dm = cm_dot(d, m);
    if (!(fabs(dm) >= CM_SIN_FLAT * cm_norm(d)))
        return 0;
    *lam = (c - cm_dot(p, m)) / dm;
    return 1;
}

/* the cubic with the ends' slopes m0 = -c.n0, m1 = -c.n1 (c the chord's unit direction) lies
   L s (1-s) [(m0 - m1)/2 + (m0 + m1)/2 (1 - 2s)] off the chord; the S part's peak, at
   s = 1/2 - 1/sqrt(12), is L |m0 + m1| / 2 * 0.0962 */
#define S_PART_PEAK 0.0481125224324688 /* (1/2) max s (1-s) (1-2s) = 1 / (12 sqrt 3) */

double cm_chord_s_part(cm_vec3 p0, cm_vec3 n0, cm_vec3 p1, cm_vec3 n1)
{
    cm_vec3 ch = cm_sub(p1, p0); /* L c: the slopes times L */
    return S_PART_PEAK * fabs(cm_dot(ch, n0) + cm_dot(ch, n1));
}

double cm_chord_c_part(cm_vec3 p0, cm_vec3 n0, cm_vec3 p1, cm_vec3 n1)
{
    /* L s (1-s) (m0 - m1) / 2 at s = 1/2, with L m = -(p1 - p0).n */
    return 0.125 * fabs(cm_dot(cm_sub(p1, p0), cm_sub(n0, n1)));
}
