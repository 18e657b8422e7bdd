/* cm_polygon.c - 2D point in polygon (spec K12). */
#include "cm/cm_geom.h"

/* p on the closed segment ab (exact arithmetic test: collinear and inside the box) */
static int on_segment(cm_vec2 a, cm_vec2 b, cm_vec2 p)
{
    if (cm_cross2(cm_sub2(b, a), cm_sub2(p, a)) != 0.0)
        return 0;
    double xmin = a.x < b.x ? a.x : b.x, xmax = a.x < b.x ? b.x : a.x;
    double ymin = a.y < b.y ? a.y : b.y, ymax = a.y < b.y ? b.y : a.y;
    return p.x >= xmin && p.x <= xmax && p.y >= ymin && p.y <= ymax;
}

int cm_point_in_polygon(const cm_vec2 *poly, int n, cm_vec2 p)
{
    int inside = 0;
    for (int i = 0, j = n - 1; i < n; j = i++) {
        cm_vec2 a = poly[j], b = poly[i];
        if (on_segment(a, b, p))
            return 1;
        if ((a.y > p.y) != (b.y > p.y)) {
            double x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if (p.x < x)
                inside = !inside;
        }
    }
    return inside;
}
