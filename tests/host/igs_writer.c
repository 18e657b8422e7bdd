/* igs_writer.c - a minimal IGES writer and the synthetic test shapes (see igs_writer.h). */
#define _POSIX_C_SOURCE 200809L
#include "igs_writer.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

void igw_init(igw *w)
{
    memset(w, 0, sizeof *w);
    w->units = 2;
    w->scale = 1.0;
    snprintf(w->exporter, sizeof w->exporter, "curvemesh test writer");
}

void igw_free(igw *w)
{
    for (int i = 0; i < w->n; i++)
        free(w->e[i].params);
    free(w->e);
    memset(w, 0, sizeof *w);
}

int igw_add(igw *w, int type, int form, const char *fmt, ...)
{
    if (w->n == w->cap) {
        w->cap = w->cap ? 2 * w->cap : 64;
        w->e = realloc(w->e, (size_t)w->cap * sizeof *w->e);
    }
    char buf[65536];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    struct igw_ent *e = &w->e[w->n];
    memset(e, 0, sizeof *e);
    e->type = type;
    e->form = form;
    e->params = strdup(buf);
    return 2 * w->n++ + 1;
}

void igw_blank(igw *w, int de)
{
    w->e[(de - 1) / 2].blank = 1;
}

void igw_set(igw *w, int de, int subord, int xform, int color)
{
    struct igw_ent *e = &w->e[(de - 1) / 2];
    e->subord = subord;
    e->xform = xform;
    e->color = color;
}

/* append one 80-column line: 72 (or 64 + 8) columns of text, section letter, sequence */
static void put_line(char **out, size_t *len, size_t *cap, const char *text, int width, const char *mid, char sec,
                     int seq)
{
    if (*len + 82 > *cap) {
        *cap = *cap ? 2 * *cap : 65536;
        *out = realloc(*out, *cap);
    }
    char line[81];
    memset(line, ' ', 80);
    line[80] = 0;
    size_t tl = strlen(text);
    memcpy(line, text, tl < (size_t)width ? tl : (size_t)width);
    if (mid)
        memcpy(line + 64, mid, 8);
    char tail[24];
    snprintf(tail, sizeof tail, "%c%7d", sec, seq % 10000000);
    memcpy(line + 72, tail, 8);
    memcpy(*out + *len, line, 80);
    (*out)[*len + 80] = '\n';
    *len += 81;
    (*out)[*len] = 0;
}

char *igw_text(const igw *w, size_t *len_out)
{
    char *out = NULL;
    size_t len = 0, cap = 0;
    put_line(&out, &len, &cap, "curvemesh synthetic IGES for tests", 72, NULL, 'S', 1);
    /* Global section, wrapped at 72 columns between parameters */
    char g[1024];
    snprintf(g, sizeof g,
             "1H,,1H;,4Htest,8Htest.igs,%zuH%s,3H0.1,32,38,6,308,15,4Htest,%.1f,%d,2H%s,1,0.01,15H20261122.120000,"
             "1e-06,1000.,6Htester,4Hcmz.,11,0,15H20261122.120000;",
             strlen(w->exporter), w->exporter, w->scale, w->units, w->units == 1 ? "IN" : "MM");
    int gseq = 0;
    for (size_t pos = 0; pos < strlen(g);) {
        size_t take = strlen(g) - pos > 72 ? 72 : strlen(g) - pos;
        char chunk[73];
        memcpy(chunk, g + pos, take);
        chunk[take] = 0;
        put_line(&out, &len, &cap, chunk, 72, NULL, 'G', ++gseq);
        pos += take;
    }
    /* Parameter lines per entity, first to know the pointers */
    int *pstart = malloc((size_t)(w->n + 1) * sizeof *pstart), *pcount = malloc((size_t)(w->n + 1) * sizeof *pcount);
    char *pbuf = NULL;
    size_t plen = 0, pcap = 0;
    int pseq = 0;
    for (int i = 0; i < w->n; i++) {
        const struct igw_ent *e = &w->e[i];
        size_t n = strlen(e->params) + 32;
        char *full = malloc(n);
        snprintf(full, n, "%d%s%s;", e->type, e->params[0] ? "," : "", e->params);
        pstart[i] = pseq + 1;
        char mid[24];
        snprintf(mid, sizeof mid, "%8d", (2 * i + 1) % 10000000);
        mid[0] = ' ';
        /* split between parameters, at most 64 columns per line */
        size_t pos = 0, fl = strlen(full);
        while (pos < fl) {
            size_t take = fl - pos;
            if (take > 64) {
                take = 64;
                while (take > 1 && full[pos + take - 1] != ',' && full[pos + take - 1] != ';')
                    take--;
            }
            char chunk[65];
            memcpy(chunk, full + pos, take);
            chunk[take] = 0;
            put_line(&pbuf, &plen, &pcap, chunk, 64, mid, 'P', ++pseq);
            pos += take;
        }
        pcount[i] = pseq + 1 - pstart[i];
        free(full);
    }
    for (int i = 0; i < w->n; i++) {
        const struct igw_ent *e = &w->e[i];
        char l1[160], l2[160];
        /* status: blank, subordinate switch, use flag, hierarchy (2 digits each) */
        snprintf(l1, sizeof l1, "%8d%8d%8d%8d%8d%8d%8d%8d%02d%02d0000", e->type, pstart[i], 0, 1, 0, 0, e->xform, 0,
                 e->blank, e->subord);
        snprintf(l2, sizeof l2, "%8d%8d%8d%8d%8d%8s%8s%8s%8d", e->type, 0, e->color, pcount[i], e->form, "", "", "", 0);
        put_line(&out, &len, &cap, l1, 72, NULL, 'D', 2 * i + 1);
        put_line(&out, &len, &cap, l2, 72, NULL, 'D', 2 * i + 2);
    }
    if (len + plen + 100 > cap) {
        cap = len + plen + 100;
        out = realloc(out, cap);
    }
    memcpy(out + len, pbuf, plen);
    len += plen;
    char t[96];
    snprintf(t, sizeof t, "S%7dG%7dD%7dP%7d", 1, gseq, 2 * w->n, pseq);
    put_line(&out, &len, &cap, t, 72, NULL, 'T', 1);
    free(pbuf);
    free(pstart);
    free(pcount);
    *len_out = len;
    return out;
}

int igw_save(const igw *w, const char *path)
{
    size_t len;
    char *t = igw_text(w, &len);
    FILE *f = fopen(path, "wb");
    int rc = -1;
    if (f) {
        rc = fwrite(t, 1, len, f) == len ? 0 : -1;
        if (fclose(f) != 0)
            rc = -1;
    }
    free(t);
    return rc;
}

/* ---- geometry helpers ---- */

typedef struct v3 {
    double x, y, z;
} v3;

static int line(igw *w, v3 a, v3 b)
{
    int de = igw_add(w, 110, 0, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", a.x, a.y, a.z, b.x, b.y, b.z);
    igw_set(w, de, 1, 0, 0);
    return de;
}

/* full counter-clockwise circle in the plane z, starting and ending at angle 0 */
static int circle_100(igw *w, double cx, double cy, double z, double r)
{
    int de = igw_add(w, 100, 0, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", z, cx, cy, cx + r, cy, cx + r, cy);
    igw_set(w, de, 1, 0, 0);
    return de;
}

/* `quarters` quarter arcs clockwise (seen from +z) as one rational 126, from the point `first` of
   the circle's eight (0: angle 0, 2: -90 degrees, 4: 180 degrees, ...) */
static int arc_cw_126(igw *w, double cx, double cy, double z, double r, int first, int quarters)
{
    const double s = sqrt(0.5);
    /* angles 0, -45(handle), -90, ... : clockwise */
    const double px[8] = {1, 1, 0, -1, -1, -1, 0, 1}, py[8] = {0, -1, -1, -1, 0, 1, 1, 1};
    int n = 2 * quarters + 1;
    char buf[4096];
    int k = snprintf(buf, sizeof buf, "%d,2,1,%d,0,0,0,0,0", n - 1, quarters == 4 ? 1 : 0);
    for (int q = 1; q < quarters; q++)
        k += snprintf(buf + k, sizeof buf - (size_t)k, ",%.17g,%.17g", (double)q / quarters, (double)q / quarters);
    k += snprintf(buf + k, sizeof buf - (size_t)k, ",1,1,1");
    for (int i = 0; i < n; i++)
        k += snprintf(buf + k, sizeof buf - (size_t)k, ",%.17g", i % 2 ? s : 1.0);
    for (int i = 0; i < n; i++)
        k += snprintf(buf + k, sizeof buf - (size_t)k, ",%.17g,%.17g,%.17g", cx + r * px[(first + i) % 8],
                      cy + r * py[(first + i) % 8], z);
    snprintf(buf + k, sizeof buf - (size_t)k, ",0,1,0,0,1");
    int de = igw_add(w, 126, 0, "%s", buf);
    igw_set(w, de, 1, 0, 0);
    return de;
}

/* full clockwise circle (seen from +z), starting at angle 0 */
static int circle_cw_126(igw *w, double cx, double cy, double z, double r)
{
    return arc_cw_126(w, cx, cy, z, r, 0, 4);
}

static int bilinear_128(igw *w, v3 p00, v3 p10, v3 p01, v3 p11)
{
    int de = igw_add(w, 128, 0,
                     "1,1,1,1,1,0,1,0,0,0,0,1,1,0,0,1,1,1,1,1,1,"
                     "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,0,1,0,1",
                     p00.x, p00.y, p00.z, p10.x, p10.y, p10.z, p01.x, p01.y, p01.z, p11.x, p11.y, p11.z);
    igw_set(w, de, 1, 0, 0);
    return de;
}

/* a 142 on `surf` whose model-space curve is `crv`, and return its DE */
static int on_surface(igw *w, int surf, int crv)
{
    int de = igw_add(w, 142, 0, "0,%d,0,%d,2", surf, crv);
    igw_set(w, de, 1, 0, 0);
    return de;
}

static int composite(igw *w, const int *members, int n)
{
    char buf[1024];
    int k = snprintf(buf, sizeof buf, "%d", n);
    for (int i = 0; i < n; i++)
        k += snprintf(buf + k, sizeof buf - (size_t)k, ",%d", members[i]);
    int de = igw_add(w, 102, 0, "%s", buf);
    igw_set(w, de, 1, 0, 0);
    return de;
}

/* rectangle loop a->b->c->d as a composite of 4 lines */
static int rect_loop(igw *w, v3 a, v3 b, v3 c, v3 d)
{
    int m[4] = {line(w, a, b), line(w, b, c), line(w, c, d), line(w, d, a)};
    return composite(w, m, 4);
}

static void plane_face_144(igw *w, v3 p00, v3 p10, v3 p11, v3 p01, int hole_curve)
{
    int s = bilinear_128(w, p00, p10, p01, p11);
    int outer = on_surface(w, s, rect_loop(w, p00, p10, p11, p01));
    if (hole_curve)
        igw_add(w, 144, 0, "%d,1,1,%d,%d", s, outer, on_surface(w, s, hole_curve));
    else
        igw_add(w, 144, 0, "%d,1,0,%d", s, outer);
}

void igw_pyramid_144(igw *w, int n, double r, double h)
{
    v3 apex = {0, 0, h}, b[128];
    if (n > 128)
        n = 128;
    for (int i = 0; i < n; i++)
        b[i] = (v3){r * cos(2 * M_PI * i / n), r * sin(2 * M_PI * i / n), 0};
    for (int i = 0; i < n; i++) { /* each side on the parallelogram that holds it */
        v3 p = b[i], q = b[(i + 1) % n];
        v3 far = {apex.x + q.x - p.x, apex.y + q.y - p.y, apex.z + q.z - p.z};
        int s = bilinear_128(w, p, q, apex, far);
        int m[3] = {line(w, p, q), line(w, q, apex), line(w, apex, p)};
        igw_add(w, 144, 0, "%d,1,0,%d", s, on_surface(w, s, composite(w, m, 3)));
    }
    int m[128];
    for (int i = 0; i < n; i++) /* the base, clockwise seen from above: outward down */
        m[i] = line(w, b[(n - i) % n], b[(n - i - 1 + n) % n]);
    int s = bilinear_128(w, (v3){-r, r, 0}, (v3){r, r, 0}, (v3){-r, -r, 0}, (v3){r, -r, 0});
    igw_add(w, 144, 0, "%d,1,0,%d", s, on_surface(w, s, composite(w, m, n)));
}

void igw_box_with_hole_144(igw *w, double a, double b, double c, double r)
{
    double cx = a / 2, cy = b / 2;
    v3 p[8];
    for (int i = 0; i < 8; i++)
        p[i] = (v3){i & 1 ? a : 0, i & 2 ? b : 0, i & 4 ? c : 0};
    plane_face_144(w, p[0], p[1], p[3], p[2], circle_100(w, cx, cy, 0, r)); /* bottom */
    plane_face_144(w, p[4], p[5], p[7], p[6], circle_100(w, cx, cy, c, r)); /* top */
    plane_face_144(w, p[0], p[1], p[5], p[4], 0);                            /* y = 0 */
    plane_face_144(w, p[1], p[3], p[7], p[5], 0);                            /* x = a */
    plane_face_144(w, p[3], p[2], p[6], p[7], 0);                            /* y = b */
    plane_face_144(w, p[2], p[0], p[4], p[6], 0);                            /* x = 0 */
    /* the hole: a 120 (line revolved 360 deg), loop = bottom circle, seam up, top circle backwards, seam down */
    int axis = line(w, (v3){cx, cy, 0}, (v3){cx, cy, 1});
    int gen = line(w, (v3){cx + r, cy, 0}, (v3){cx + r, cy, c});
    int surf = igw_add(w, 120, 0, "%d,%d,0,%.17g", axis, gen, 2 * M_PI);
    igw_set(w, surf, 1, 0, 0);
    int m[4] = {circle_100(w, cx, cy, 0, r), line(w, (v3){cx + r, cy, 0}, (v3){cx + r, cy, c}),
                circle_cw_126(w, cx, cy, c, r), line(w, (v3){cx + r, cy, c}, (v3){cx + r, cy, 0})};
    igw_add(w, 144, 0, "%d,1,0,%d", surf, on_surface(w, surf, composite(w, m, 4)));
}

void igw_box_144(igw *w, double a, double b, double c)
{
    v3 p[8];
    for (int i = 0; i < 8; i++)
        p[i] = (v3){i & 1 ? a : 0, i & 2 ? b : 0, i & 4 ? c : 0};
    plane_face_144(w, p[0], p[2], p[3], p[1], 0); /* z = 0, outward down */
    plane_face_144(w, p[4], p[5], p[7], p[6], 0); /* z = c */
    plane_face_144(w, p[0], p[1], p[5], p[4], 0); /* y = 0 */
    plane_face_144(w, p[1], p[3], p[7], p[5], 0); /* x = a */
    plane_face_144(w, p[3], p[2], p[6], p[7], 0); /* y = b */
    plane_face_144(w, p[2], p[0], p[4], p[6], 0); /* x = 0 */
}

void igw_square_scrambled_144(igw *w, double a)
{
    v3 p00 = {0, 0, 0}, p10 = {a, 0, 0}, p11 = {a, a, 0}, p01 = {0, a, 0};
    int s = bilinear_128(w, p00, p10, p01, p11);
    /* the loop p00 -> p10 -> p11 -> p01 -> p00, listed as: first side, third side backwards,
       second side, fourth side backwards (as ICEM writes a notch's pieces) */
    int m[4] = {line(w, p00, p10), line(w, p01, p11), line(w, p10, p11), line(w, p00, p01)};
    igw_add(w, 144, 0, "%d,1,0,%d", s, on_surface(w, s, composite(w, m, 4)));
}

void igw_half_cylinder_120_mirrored(igw *w, double r, double h)
{
    int axis = line(w, (v3){0, 0, 0}, (v3){0, 0, 1});
    int gen = line(w, (v3){r, 0, 0}, (v3){r, 0, h});
    int mirror = igw_add(w, 124, 1, "1,0,0,0,0,-1,0,0,0,0,1,0"); /* y -> -y, determinant -1 */
    int surf = igw_add(w, 120, 0, "%d,%d,0,%.17g", axis, gen, M_PI);
    igw_set(w, surf, 0, mirror, 0);
}

static int point_116(igw *w, v3 p)
{
    int de = igw_add(w, 116, 0, "%.17g,%.17g,%.17g,0", p.x, p.y, p.z);
    igw_set(w, de, 1, 0, 0);
    return de;
}

static int dir_123(igw *w, v3 d)
{
    int de = igw_add(w, 123, 0, "%.17g,%.17g,%.17g", d.x, d.y, d.z);
    igw_set(w, de, 1, 0, 0);
    return de;
}

void igw_box_with_hole_186_oriented(igw *w, double a, double b, double c, double r, int inside_out)
{
    double cx = a / 2, cy = b / 2;
    /* vertices 1..8 box corners (i & 1 -> x, i & 2 -> y, i & 4 -> z), 9, 10 seam points */
    char vb[2048];
    int k = snprintf(vb, sizeof vb, "10");
    for (int i = 0; i < 8; i++)
        k += snprintf(vb + k, sizeof vb - (size_t)k, ",%.17g,%.17g,%.17g", i & 1 ? a : 0.0, i & 2 ? b : 0.0,
                      i & 4 ? c : 0.0);
    k += snprintf(vb + k, sizeof vb - (size_t)k, ",%.17g,%.17g,0,%.17g,%.17g,%.17g", cx + r, cy, cx + r, cy, c);
    int vl = igw_add(w, 502, 1, "%s", vb);
    igw_set(w, vl, 1, 0, 0);
    v3 P[11];
    for (int i = 0; i < 8; i++)
        P[i + 1] = (v3){i & 1 ? a : 0, i & 2 ? b : 0, i & 4 ? c : 0};
    P[9] = (v3){cx + r, cy, 0};
    P[10] = (v3){cx + r, cy, c};
    /* edges: 12 box edges (vertex pairs), 2 circles, 1 seam */
    static const int ev[15][2] = {{1, 2}, {2, 4}, {4, 3}, {3, 1}, {5, 6}, {6, 8}, {8, 7}, {7, 5},
                                  {1, 5}, {2, 6}, {4, 8}, {3, 7}, {9, 9}, {10, 10}, {9, 10}};
    int crv[15];
    for (int i = 0; i < 12; i++)
        crv[i] = line(w, P[ev[i][0]], P[ev[i][1]]);
    crv[12] = circle_100(w, cx, cy, 0, r);
    crv[13] = circle_100(w, cx, cy, c, r);
    crv[14] = line(w, P[9], P[10]);
    char eb[4096];
    k = snprintf(eb, sizeof eb, "15");
    for (int i = 0; i < 15; i++)
        k += snprintf(eb + k, sizeof eb - (size_t)k, ",%d,%d,%d,%d,%d", crv[i], vl, ev[i][0], vl, ev[i][1]);
    int el = igw_add(w, 504, 1, "%s", eb);
    igw_set(w, el, 1, 0, 0);
    /* loops: lists of (edge index, orientation 1 = along the edge) */
    struct lp {
        int n;
        int e[4], of[4];
    };
    const struct lp loops[9] = {
        {4, {4, 3, 2, 1}, {0, 0, 0, 0}},  /* bottom outer (clockwise from above: outward normal -z) */
        {1, {13}, {1}},                   /* bottom hole */
        {4, {5, 6, 7, 8}, {1, 1, 1, 1}},  /* top outer */
        {1, {14}, {0}},                   /* top hole */
        {4, {1, 10, 5, 9}, {1, 1, 0, 0}}, /* y = 0 */
        {4, {2, 11, 6, 10}, {1, 1, 0, 0}}, /* x = a */
        {4, {3, 12, 7, 11}, {1, 1, 0, 0}}, /* y = b */
        {4, {4, 9, 8, 12}, {1, 1, 0, 0}},  /* x = 0 */
        {4, {13, 15, 14, 15}, {1, 1, 0, 0}}, /* hole cylinder with its seam */
    };
    int lde[9];
    for (int l = 0; l < 9; l++) {
        char lb[512];
        int q = snprintf(lb, sizeof lb, "%d", loops[l].n);
        for (int i = 0; i < loops[l].n; i++)
            q += snprintf(lb + q, sizeof lb - (size_t)q, ",0,%d,%d,%d,0", el, loops[l].e[i], loops[l].of[i]);
        lde[l] = igw_add(w, 508, 1, "%s", lb);
        igw_set(w, lde[l], 1, 0, 0);
    }
    /* surfaces: planes with outward normals, the cylinder (its normal points away from the axis) */
    const v3 origin[6] = {{0, 0, 0}, {0, 0, c}, {0, 0, 0}, {a, 0, 0}, {0, b, 0}, {0, 0, 0}};
    const v3 normal[6] = {{0, 0, -1}, {0, 0, 1}, {0, -1, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}};
    int surf[7];
    for (int i = 0; i < 6; i++) {
        surf[i] = igw_add(w, 190, 0, "%d,%d", point_116(w, origin[i]), dir_123(w, normal[i]));
        igw_set(w, surf[i], 1, 0, 0);
    }
    surf[6] = igw_add(w, 192, 1, "%d,%d,%.17g,%d", point_116(w, (v3){cx, cy, 0}), dir_123(w, (v3){0, 0, 1}), r,
                      dir_123(w, (v3){1, 0, 0}));
    igw_set(w, surf[6], 1, 0, 0);
    int face[7];
    face[0] = igw_add(w, 510, 1, "%d,2,1,%d,%d", surf[0], lde[0], lde[1]);
    face[1] = igw_add(w, 510, 1, "%d,2,1,%d,%d", surf[1], lde[2], lde[3]);
    for (int i = 2; i < 6; i++)
        face[i] = igw_add(w, 510, 1, "%d,1,1,%d", surf[i], lde[i + 2]);
    face[6] = igw_add(w, 510, 1, "%d,1,1,%d", surf[6], lde[8]);
    char sb[256];
    k = snprintf(sb, sizeof sb, "7");
    for (int i = 0; i < 7; i++) {
        igw_set(w, face[i], 1, 0, 0);
        /* the hole's outward normal points at the axis: opposite to the cylinder's */
        k += snprintf(sb + k, sizeof sb - (size_t)k, ",%d,%d", face[i], (i == 6 ? 0 : 1) ^ (inside_out != 0));
    }
    int shell = igw_add(w, 514, 1, "%s", sb);
    igw_set(w, shell, 1, 0, 0);
    igw_add(w, 186, 0, "%d,1,0", shell);
}

void igw_box_with_hole_186(igw *w, double a, double b, double c, double r)
{
    igw_box_with_hole_186_oriented(w, a, b, c, r, 0);
}

void igw_half_cylinder_120(igw *w, double r, double h)
{
    int axis = line(w, (v3){0, 0, 0}, (v3){0, 0, 1});
    int gen = line(w, (v3){r, 0, 0}, (v3){r, 0, h});
    igw_add(w, 120, 0, "%d,%d,0,%.17g", axis, gen, M_PI);
}

const double igw_bicubic_z[4][4] = {{0, 0.5, 0.2, 0}, {0.3, 1.0, 0.8, 0.1}, {0.1, 0.9, 1.2, 0.4}, {0, 0.2, 0.5, 0.3}};

/* one bicubic Bezier patch (a polynomial 128 on [0,1]^2) of control points p[j][i] (v index j, u
   index i); its DE */
static int bezier_128(igw *w, const v3 p[4][4])
{
    char buf[4096];
    int k = snprintf(buf, sizeof buf, "3,3,3,3,0,0,1,0,0,0,0,0,0,1,1,1,1,0,0,0,0,1,1,1,1");
    for (int i = 0; i < 16; i++)
        k += snprintf(buf + k, sizeof buf - (size_t)k, ",1");
    for (int j = 0; j < 4; j++)     /* v index outer */
        for (int i = 0; i < 4; i++) /* u index runs fastest in the file */
            k += snprintf(buf + k, sizeof buf - (size_t)k, ",%.17g,%.17g,%.17g", p[j][i].x, p[j][i].y, p[j][i].z);
    snprintf(buf + k, sizeof buf - (size_t)k, ",0,1,0,1");
    return igw_add(w, 128, 0, "%s", buf);
}

void igw_bicubic_128(igw *w)
{
    v3 p[4][4];
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++)
            p[j][i] = (v3){i, j, igw_bicubic_z[i][j]};
    bezier_128(w, p);
}

static double dense_knot(int i, int n)
{
    int c = i < 4 ? 0 : (i >= n ? n - 3 : i - 3);
    return pow((double)c / (double)(n - 3), 1.3); /* uneven, as exporters' knots are */
}

void igw_dense_128(igw *w, int n, double a, double h)
{
    size_t cap = 64 * (size_t)n * (size_t)n + 4096;
    char *buf = malloc(cap);
    if (!buf)
        return;
    int k = snprintf(buf, cap, "%d,%d,3,3,0,0,1,0,0", n - 1, n - 1);
    for (int dir = 0; dir < 2; dir++)
        for (int i = 0; i < n + 4; i++)
            k += snprintf(buf + k, cap - (size_t)k, ",%.10g", dense_knot(i, n));
    for (int i = 0; i < n * n; i++)
        k += snprintf(buf + k, cap - (size_t)k, ",1");
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            /* at the Greville abscissae: the net follows the wave */
            double gx = (dense_knot(i + 1, n) + dense_knot(i + 2, n) + dense_knot(i + 3, n)) / 3.0;
            double gy = (dense_knot(j + 1, n) + dense_knot(j + 2, n) + dense_knot(j + 3, n)) / 3.0;
            double x = a * gx, y = a * gy;
            double sx = 2.0 * x / a - 1.0, sy = 2.0 * y / a - 1.0;
            k += snprintf(buf + k, cap - (size_t)k, ",%.10g,%.10g,%.10g", x, y, h * (pow(sx, 8) + pow(sy, 8)));
        }
    snprintf(buf + k, cap - (size_t)k, ",0,1,0,1");
    igw_add(w, 128, 0, "%s", buf);
    free(buf);
}

/* counter-clockwise arc of the circle (cx, cy, r) in the plane z from angle a0 to a1 */
static int arc_100(igw *w, double cx, double cy, double z, double r, double a0, double a1)
{
    int de = igw_add(w, 100, 0, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", z, cx, cy, cx + r * cos(a0),
                     cy + r * sin(a0), cx + r * cos(a1), cy + r * sin(a1));
    igw_set(w, de, 1, 0, 0);
    return de;
}

/* arc (cx, cy, r) in the plane z from a0 to a1 as `pieces` arcs, cut at unequal angles; their DEs
   appended to m[*k] */
static void cut_arc(igw *w, double r, double z, double a0, double a1, int pieces, int *m, int *k)
{
    static const double f[4][5] = {{0, 1}, {0, 3.0 / 8.0, 1}, {0, 0.2, 0.55, 1}, {0, 0.15, 0.4, 0.7, 1}};
    for (int i = 0; i < pieces; i++)
        m[(*k)++] = arc_100(w, 0, 0, z, r, a0 + f[pieces - 1][i] * (a1 - a0), a0 + f[pieces - 1][i + 1] * (a1 - a0));
}

void igw_t_vertex_half_cylinder_144(igw *w, double r, double h, int pieces, int both)
{
    int axis = line(w, (v3){0, 0, 0}, (v3){0, 0, 1});
    int gen = line(w, (v3){r, 0, 0}, (v3){r, 0, h});
    for (int q = 0; q < 2; q++) {
        double a0 = q * M_PI / 2, a1 = (q + 1) * M_PI / 2;
        int surf = igw_add(w, 120, 0, "%d,%d,%.17g,%.17g", axis, gen, a0, a1);
        igw_set(w, surf, 1, 0, 0);
        v3 b0 = {r * cos(a0), r * sin(a0), 0}, b1 = {r * cos(a1), r * sin(a1), 0};
        v3 t0 = {b0.x, b0.y, h}, t1 = {b1.x, b1.y, h};
        /* quarter 0's bottom arc and quarter 1's top arc (with `both`, both arcs of quarter 0) cut */
        int m[12], k = 0;
        cut_arc(w, r, 0, a0, a1, q == 0 ? pieces : 1, m, &k);
        m[k++] = line(w, b1, t1);
        cut_arc(w, r, h, a0, a1, q == 1 || both ? pieces : 1, m, &k);
        m[k++] = line(w, t0, b0);
        igw_add(w, 144, 0, "%d,1,0,%d", surf, on_surface(w, surf, composite(w, m, k)));
    }
}

void igw_ruled_half_cylinder_144(igw *w, double r, double h, int pieces)
{
    int axis = line(w, (v3){0, 0, 0}, (v3){0, 0, 1});
    int gen = line(w, (v3){r, 0, 0}, (v3){r, 0, h});
    int surf = igw_add(w, 120, 0, "%d,%d,0,%.17g", axis, gen, M_PI);
    igw_set(w, surf, 1, 0, 0);
    int m[2 + 2 * 16], k = 0;
    pieces = pieces < 1 ? 1 : (pieces > 16 ? 16 : pieces);
    cut_arc(w, r, 0, 0, M_PI, 1, m, &k);
    for (int i = 0; i < pieces; i++) /* up the line at angle pi, in pieces of unequal length */
        m[k++] = line(w, (v3){-r, 0, h * (i * (i + 3.0)) / (pieces * (pieces + 3.0))},
                      (v3){-r, 0, h * ((i + 1) * (i + 4.0)) / (pieces * (pieces + 3.0))});
    cut_arc(w, r, h, 0, M_PI, 1, m, &k); /* written 0 -> pi, run backwards (as the t-vertex cylinder's) */
    for (int i = pieces; i > 0; i--) /* down the line at angle 0 */
        m[k++] = line(w, (v3){r, 0, h * (i * (i + 3.0)) / (pieces * (pieces + 3.0))},
                      (v3){r, 0, h * ((i - 1) * (i + 2.0)) / (pieces * (pieces + 3.0))});
    igw_add(w, 144, 0, "%d,1,0,%d", surf, on_surface(w, surf, composite(w, m, k)));
}

/* a cubic Bezier curve (polynomial 126) through control points p[4], in the plane x = p[0].x */
static int bezier_x_126(igw *w, const v3 p[4])
{
    char buf[2048];
    int k = snprintf(buf, sizeof buf, "3,3,1,0,1,0,0,0,0,0,1,1,1,1,1,1,1,1");
    for (int i = 0; i < 4; i++)
        k += snprintf(buf + k, sizeof buf - (size_t)k, ",%.17g,%.17g,%.17g", p[i].x, p[i].y, p[i].z);
    snprintf(buf + k, sizeof buf - (size_t)k, ",0,1,1,0,0");
    int de = igw_add(w, 126, 0, "%s", buf);
    igw_set(w, de, 1, 0, 0);
    return de;
}

void igw_trough_144(igw *w, double a, double b, double h, int pieces)
{
    /* z = 4 h t (1 - t), t = y / b: the cubic Bezier rows (0, 4h/3, 4h/3, 0) over y = 0, b/3, 2b/3, b
       (the quadratic's (0, 2h, 0) raised a degree), x running linearly over [0, a] */
    static const double zr[4] = {0, 4.0 / 3.0, 4.0 / 3.0, 0};
    v3 p[4][4];
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++)
            p[j][i] = (v3){a * i / 3.0, b * j / 3.0, h * zr[j]};
    int s = bezier_128(w, p);
    igw_set(w, s, 1, 0, 0);
    int m[2 + 2 * 16], n = 0;
    pieces = pieces < 1 ? 1 : (pieces > 16 ? 16 : pieces);
    for (int i = 0; i < pieces; i++) /* along y = 0, pieces of unequal length */
        m[n++] = line(w, (v3){a * (i * (i + 3.0)) / (pieces * (pieces + 3.0)), 0, 0},
                      (v3){a * ((i + 1) * (i + 4.0)) / (pieces * (pieces + 3.0)), 0, 0});
    const v3 e1[4] = {{a, 0, 0}, {a, b / 3, 4 * h / 3}, {a, 2 * b / 3, 4 * h / 3}, {a, b, 0}};
    m[n++] = bezier_x_126(w, e1);
    for (int i = pieces; i > 0; i--) /* back along y = b */
        m[n++] = line(w, (v3){a * (i * (i + 3.0)) / (pieces * (pieces + 3.0)), b, 0},
                      (v3){a * ((i - 1) * (i + 2.0)) / (pieces * (pieces + 3.0)), b, 0});
    const v3 e0[4] = {{0, b, 0}, {0, 2 * b / 3, 4 * h / 3}, {0, b / 3, 4 * h / 3}, {0, 0, 0}};
    m[n++] = bezier_x_126(w, e0);
    igw_add(w, 144, 0, "%d,1,0,%d", s, on_surface(w, s, composite(w, m, n)));
}

void igw_split_half_cylinder_144(igw *w, double r, double h)
{
    igw_t_vertex_half_cylinder_144(w, r, h, 1, 0);
}

void igw_bump_144(igw *w, double a, double h)
{
    /* bicubic, 5 x 5 control points on knots 0 0 0 0 .5 1 1 1 1, placed at their Greville abscissae
       (0, 1/6, 1/2, 5/6, 1) of the square so that the parameters run linearly; only the middle one
       raised: the surface and its cross slopes are flat on the whole boundary */
    static const double g[5] = {0.0, 1.0 / 6.0, 0.5, 5.0 / 6.0, 1.0};
    char buf[8192];
    int k = snprintf(buf, sizeof buf, "4,4,3,3,0,0,1,0,0,0,0,0,0,0.5,1,1,1,1,0,0,0,0,0.5,1,1,1,1");
    for (int i = 0; i < 25; i++)
        k += snprintf(buf + k, sizeof buf - (size_t)k, ",1");
    for (int j = 0; j < 5; j++)     /* v index outer */
        for (int i = 0; i < 5; i++) /* u index runs fastest in the file */
            k += snprintf(buf + k, sizeof buf - (size_t)k, ",%.17g,%.17g,%.17g", a * g[i], a * g[j],
                          i == 2 && j == 2 ? h : 0.0);
    snprintf(buf + k, sizeof buf - (size_t)k, ",0,1,0,1");
    int s = igw_add(w, 128, 0, "%s", buf);
    igw_set(w, s, 1, 0, 0);
    v3 p00 = {0, 0, 0}, p10 = {a, 0, 0}, p11 = {a, a, 0}, p01 = {0, a, 0};
    igw_add(w, 144, 0, "%d,1,0,%d", s, on_surface(w, s, rect_loop(w, p00, p10, p11, p01)));
}

void igw_tri_bump_144(igw *w, double a, double h)
{
    /* f(u, v) = 729 h u^2 v^2 (1-u-v)^2, whose largest value is h (at u = v = 1/3), expanded into
       monomials c[i][j] u^i v^j and written as one biquartic Bezier patch: the Bernstein coefficient
       (k, l) is sum c[i][j] C(k,i)/C(4,i) C(l,j)/C(4,j); x and y run linearly (a k/4, a l/4) */
    static const int C[5][5] = {{1}, {1, 1}, {1, 2, 1}, {1, 3, 3, 1}, {1, 4, 6, 4, 1}};
    double c[5][5] = {{0}};
    c[2][2] = 1, c[3][2] = -2, c[2][3] = -2, c[4][2] = 1, c[3][3] = 2, c[2][4] = 1;
    char buf[8192];
    int k = snprintf(buf, sizeof buf, "4,4,4,4,0,0,1,0,0,0,0,0,0,0,1,1,1,1,1,0,0,0,0,0,1,1,1,1,1");
    for (int i = 0; i < 25; i++)
        k += snprintf(buf + k, sizeof buf - (size_t)k, ",1");
    for (int l = 0; l < 5; l++)      /* v index outer */
        for (int kk = 0; kk < 5; kk++) { /* u index runs fastest in the file */
            double z = 0;
            for (int i = 0; i <= kk; i++)
                for (int j = 0; j <= l; j++)
                    z += c[i][j] * C[kk][i] / C[4][i] * C[l][j] / C[4][j];
            k += snprintf(buf + k, sizeof buf - (size_t)k, ",%.17g,%.17g,%.17g", a * kk / 4.0, a * l / 4.0,
                          729.0 * h * z);
        }
    snprintf(buf + k, sizeof buf - (size_t)k, ",0,1,0,1");
    int s = igw_add(w, 128, 0, "%s", buf);
    igw_set(w, s, 1, 0, 0);
    v3 p0 = {0, 0, 0}, p1 = {a, 0, 0}, p2 = {0, a, 0};
    int m[3] = {line(w, p0, p1), line(w, p1, p2), line(w, p2, p0)};
    igw_add(w, 144, 0, "%d,1,0,%d", s, on_surface(w, s, composite(w, m, 3)));
}

/* ---- a flat disc ---- */

int igw_disc_144(igw *w, double r, double z)
{
    v3 p00 = {-r, -r, z}, p10 = {r, -r, z}, p01 = {-r, r, z}, p11 = {r, r, z};
    int s = bilinear_128(w, p00, p10, p01, p11);
    return igw_add(w, 144, 0, "%d,1,0,%d", s, on_surface(w, s, circle_100(w, 0, 0, z, r)));
}

/* ---- building blocks for hostile inputs ---- */

int igw_square_144(igw *w, double a, double z, int subord)
{
    v3 p00 = {0, 0, z}, p10 = {a, 0, z}, p11 = {a, a, z}, p01 = {0, a, z};
    int s = bilinear_128(w, p00, p10, p01, p11);
    int de = igw_add(w, 144, 0, "%d,1,0,%d", s, on_surface(w, s, rect_loop(w, p00, p10, p11, p01)));
    igw_set(w, de, subord, 0, 0);
    return de;
}

int igw_transform_124(igw *w, const double m[12])
{
    char buf[1024];
    int k = 0;
    for (int i = 0; i < 12; i++)
        k += snprintf(buf + k, sizeof buf - (size_t)k, "%s%.17g", i ? "," : "", m[i]);
    int de = igw_add(w, 124, 0, "%s", buf);
    igw_set(w, de, 1, 0, 0);
    return de;
}

/* a list "n,de,de,..." of `fan` copies of `de` after `head` */
static void repeat_list(char *buf, size_t cap, const char *head, int fan, const int *des)
{
    int k = snprintf(buf, cap, "%s%d", head, fan);
    for (int i = 0; i < fan && (size_t)k < cap; i++)
        k += snprintf(buf + k, cap - (size_t)k, ",%d", des[i]);
}

int igw_subfigure_dag(igw *w, int levels, int fan)
{
    int face = igw_square_144(w, 10.0, 0.0, 1);
    int def = igw_add(w, 308, 0, "0,3HL00,1,%d", face);
    igw_set(w, def, 1, 0, 0);
    int *inst = malloc((size_t)(fan > 0 ? fan : 1) * sizeof *inst);
    char buf[4096], head[32];
    for (int k = 1; k <= levels; k++) {
        for (int i = 0; i < fan; i++) {
            /* each instance moved along x so the placed squares do not coincide */
            inst[i] = igw_add(w, 408, 0, "%d,%.17g,0,0,1", def, 20.0 * i);
            igw_set(w, inst[i], 1, 0, 0);
        }
        snprintf(head, sizeof head, "0,3HL%02d,", k % 100);
        repeat_list(buf, sizeof buf, head, fan, inst);
        def = igw_add(w, 308, 0, "%s", buf);
        igw_set(w, def, 1, 0, 0);
    }
    free(inst);
    return igw_add(w, 408, 0, "%d,0,0,0,1", def);
}

int igw_placed_boxes(igw *w, int copies, const double (*xform)[12])
{
    return igw_placed_boxes_named(w, copies, xform, "BOX");
}

int igw_placed_boxes_named(igw *w, int copies, const double (*xform)[12], const char *name)
{
    int from = w->n;
    igw_box_with_hole_144(w, 40, 30, 20, 5);
    int members[16], n = 0;
    for (int i = from; i < w->n && n < 16; i++)
        if (w->e[i].type == 144) {
            members[n++] = 2 * i + 1;
            w->e[i].subord = 1;
        }
    char buf[512], head[128];
    snprintf(head, sizeof head, "0,%dH%s,", (int)strlen(name), name);
    repeat_list(buf, sizeof buf, head, n, members);
    int def = igw_add(w, 308, 0, "%s", buf);
    igw_set(w, def, 1, 0, 0);
    for (int k = 0; k < copies; k++) {
        int x = igw_transform_124(w, xform[k]);
        int inst = igw_add(w, 408, 0, "%d,0,0,0,1", def);
        igw_set(w, inst, 0, x, 0);
    }
    return def;
}

int igw_composite_dag_144(igw *w, int levels, int fan)
{
    v3 p00 = {0, 0, 0}, p10 = {10, 0, 0}, p11 = {10, 10, 0}, p01 = {0, 10, 0};
    int s = bilinear_128(w, p00, p10, p01, p11);
    int c = circle_100(w, 5, 5, 0, 1);
    int *m = malloc((size_t)(fan > 0 ? fan : 1) * sizeof *m);
    for (int k = 1; k <= levels; k++) {
        for (int i = 0; i < fan; i++)
            m[i] = c;
        c = composite(w, m, fan);
    }
    free(m);
    return igw_add(w, 144, 0, "%d,1,1,%d,%d", s, on_surface(w, s, rect_loop(w, p00, p10, p11, p01)),
                   on_surface(w, s, c));
}

/* ---- spec §17 T8: an L-shaped face on a quadratic surface ---- */

/* z of the T8 surface at (x, y) */
static double t8_z(double x, double y)
{
    return 0.02 * (x * x - 0.5 * y * y) + 0.1 * x + 0.01 * x * y;
}

/* the straight segment a -> b of the plane lifted onto a surface z(x, y) of degree 2: z is quadratic
   along it, so the lift is one quadratic Bezier (126), exactly */
static int lift_126(igw *w, double (*z)(double, double), double ax, double ay, double bx, double by)
{
    double mx = 0.5 * (ax + bx), my = 0.5 * (ay + by);
    double za = z(ax, ay), zb = z(bx, by), z1 = 2.0 * z(mx, my) - 0.5 * (za + zb);
    int de = igw_add(w, 126, 0,
                     "2,2,0,0,1,0,0,0,0,1,1,1,1,1,1,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,0,1,0,0,1",
                     ax, ay, za, mx, my, z1, bx, by, zb);
    igw_set(w, de, 1, 0, 0);
    return de;
}

void igw_l_shape_144(igw *w)
{
    /* z(20u, 16v) = 2u + 8u^2 + 3.2uv - 2.56v^2: its biquadratic Bernstein coefficients are
       b_kl = sum c_ij C(k,i)/C(2,i) C(l,j)/C(2,j), with x and y linear (20 k/2, 16 l/2) */
    static const double c[3][3] = {{0.0, 0.0, -2.56}, {2.0, 3.2, 0.0}, {8.0, 0.0, 0.0}};
    static const double C[3][3] = {{1, 0, 0}, {1, 1, 0}, {1, 2, 1}};
    char buf[4096];
    int k = snprintf(buf, sizeof buf, "2,2,2,2,0,0,1,0,0,0,0,0,1,1,1,0,0,0,1,1,1,1,1,1,1,1,1,1,1,1");
    for (int l = 0; l < 3; l++)     /* v index outer */
        for (int kk = 0; kk < 3; kk++) { /* u index runs fastest in the file */
            double z = 0.0;
            for (int i = 0; i <= kk; i++)
                for (int j = 0; j <= l; j++)
                    z += c[i][j] * C[kk][i] / C[2][i] * C[l][j] / C[2][j];
            k += snprintf(buf + k, sizeof buf - (size_t)k, ",%.17g,%.17g,%.17g", 10.0 * kk, 8.0 * l, z);
        }
    snprintf(buf + k, sizeof buf - (size_t)k, ",0,1,0,1");
    int s = igw_add(w, 128, 0, "%s", buf);
    igw_set(w, s, 1, 0, 0);
    static const double px[6] = {0, 20, 20, 8, 8, 0}, py[6] = {0, 0, 8, 8, 16, 16};
    int m[6];
    for (int i = 0; i < 6; i++) {
        int j = (i + 1) % 6;
        m[i] = lift_126(w, t8_z, px[i], py[i], px[j], py[j]);
    }
    igw_add(w, 144, 0, "%d,1,0,%d", s, on_surface(w, s, composite(w, m, 6)));
}

/* a cubic Bezier (126) through control points p[0..3] */
static int cubic_126(igw *w, const v3 p[4])
{
    int de = igw_add(w, 126, 0,
                     "3,3,0,0,1,0,0,0,0,0,1,1,1,1,1,1,1,1,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,"
                     "%.17g,%.17g,0,1,0,0,1",
                     p[0].x, p[0].y, p[0].z, p[1].x, p[1].y, p[1].z, p[2].x, p[2].y, p[2].z, p[3].x, p[3].y, p[3].z);
    igw_set(w, de, 1, 0, 0);
    return de;
}

void igw_twisted_pair_144(igw *w, double a, double h)
{
    /* z = h (x/a) (y/a)^3: linear in x, so its Bernstein coefficients in u are its values at x_i;
       (y/a)^3 = (2v - 1)^3 has the coefficients -1, 1, -1, 1 (its blossom at 0s and 1s) */
    static const double c[4] = {-1.0, 1.0, -1.0, 1.0};
    for (int half = 0; half < 2; half++) {
        double x0 = half ? 0.0 : -a, x1 = half ? a : 0.0;
        char buf[4096];
        int k = snprintf(buf, sizeof buf, "3,3,3,3,0,0,1,0,0,0,0,0,0,1,1,1,1,0,0,0,0,1,1,1,1");
        for (int i = 0; i < 16; i++)
            k += snprintf(buf + k, sizeof buf - (size_t)k, ",1");
        for (int j = 0; j < 4; j++)     /* v index outer */
            for (int i = 0; i < 4; i++) { /* u index runs fastest in the file */
                double x = x0 + (x1 - x0) * i / 3.0;
                k += snprintf(buf + k, sizeof buf - (size_t)k, ",%.17g,%.17g,%.17g", x, -a + 2.0 * a * j / 3.0,
                              h * (x / a) * c[j]);
            }
        snprintf(buf + k, sizeof buf - (size_t)k, ",0,1,0,1");
        int surf = igw_add(w, 128, 0, "%s", buf);
        igw_set(w, surf, 1, 0, 0);
        /* the loop, counter-clockwise seen from +z: bottom, right, top, left; the edges along y are
           cubics (a line where x = 0: the shared edge) */
        v3 up[4], down[4];
        for (int j = 0; j < 4; j++) {
            up[j] = (v3){x1, -a + 2.0 * a * j / 3.0, h * (x1 / a) * c[j]};
            down[j] = (v3){x0, a - 2.0 * a * j / 3.0, h * (x0 / a) * c[3 - j]};
        }
        int m[4];
        m[0] = line(w, (v3){x0, -a, -h * x0 / a}, (v3){x1, -a, -h * x1 / a});
        m[1] = x1 == 0.0 ? line(w, up[0], up[3]) : cubic_126(w, up);
        m[2] = line(w, (v3){x1, a, h * x1 / a}, (v3){x0, a, h * x0 / a});
        m[3] = x0 == 0.0 ? line(w, down[0], down[3]) : cubic_126(w, down);
        igw_add(w, 144, 0, "%d,1,0,%d", surf, on_surface(w, surf, composite(w, m, 4)));
    }
}

cm_err igw_load(igw *w, const char *name, loaded_model *lm, cm_status *st)
{
    size_t len = 0;
    char *text = igw_text(w, &len);
    igw_free(w);
    cm_status_init(st);
    cm_err e = text ? model_load_data(name, text, len, lm, NULL, NULL, st) : cm_fail(st, CM_E_NOMEM, "igw_text");
    free(text);
    return e;
}

/* ---- a square on a paraboloid with a round hole ---- */

static double dome_z(double x, double y)
{
    return 5.0 * (1.0 - (x * x + y * y) / 400.0);
}

/* the dome z = 5 (1 - (x^2 + y^2) / 400) over [-20, 20]^2 as a biquadratic B-spline: with
   x = 20(2u-1), y = 20(2v-1), z = -5 + 20u - 20u^2 + 20v - 20v^2, in the Bernstein basis as
   igw_l_shape_144 */
static int dome_128(igw *w)
{
    static const double c[3][3] = {{-5.0, 20.0, -20.0}, {20.0, 0.0, 0.0}, {-20.0, 0.0, 0.0}};
    static const double C[3][3] = {{1, 0, 0}, {1, 1, 0}, {1, 2, 1}};
    char buf[4096];
    int k = snprintf(buf, sizeof buf, "2,2,2,2,0,0,1,0,0,0,0,0,1,1,1,0,0,0,1,1,1,1,1,1,1,1,1,1,1,1");
    for (int l = 0; l < 3; l++)
        for (int kk = 0; kk < 3; kk++) {
            double z = 0.0;
            for (int i = 0; i <= kk; i++)
                for (int j = 0; j <= l; j++)
                    z += c[i][j] * C[kk][i] / C[2][i] * C[l][j] / C[2][j];
            k += snprintf(buf + k, sizeof buf - (size_t)k, ",%.17g,%.17g,%.17g", 20.0 * (kk - 1), 20.0 * (l - 1), z);
        }
    snprintf(buf + k, sizeof buf - (size_t)k, ",0,1,0,1");
    int s = igw_add(w, 128, 0, "%s", buf);
    igw_set(w, s, 1, 0, 0);
    return s;
}

void igw_half_dome_band_144(igw *w, double r0, double r1)
{
    int s = dome_128(w);
    /* circles about the apex lie at one height: the outer half from (r1, 0) over (0, r1) to (-r1, 0),
       in along y = 0, the inner half back clockwise, out along y = 0 */
    int m[4] = {arc_100(w, 0, 0, dome_z(r1, 0.0), r1, 0.0, M_PI), lift_126(w, dome_z, -r1, 0.0, -r0, 0.0),
                arc_cw_126(w, 0, 0, dome_z(r0, 0.0), r0, 4, 2), lift_126(w, dome_z, r0, 0.0, r1, 0.0)};
    igw_add(w, 144, 0, "%d,1,0,%d", s, on_surface(w, s, composite(w, m, 4)));
}

void igw_dome_square_hole_144(igw *w, double a, double r0)
{
    int s = dome_128(w);
    static const double px[4] = {-1, 1, 1, -1}, py[4] = {-1, -1, 1, 1};
    int m[4];
    for (int i = 0; i < 4; i++) {
        int j = (i + 1) % 4;
        m[i] = lift_126(w, dome_z, a * px[i], a * py[i], a * px[j], a * py[j]);
    }
    int outer = on_surface(w, s, composite(w, m, 4));
    /* the circle of radius r0 about the apex lies at one height: two arcs */
    double z0 = dome_z(r0, 0.0);
    int h[2] = {arc_100(w, 0, 0, z0, r0, 0.0, M_PI), arc_100(w, 0, 0, z0, r0, M_PI, 2 * M_PI)};
    int inner = on_surface(w, s, composite(w, h, 2));
    igw_add(w, 144, 0, "%d,1,1,%d,%d", s, outer, inner);
}
