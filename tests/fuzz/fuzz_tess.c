/*
 * fuzz_tess - libFuzzer target for the triangulator (cm_triangulate,
 * cm_triangulate_folds, cm_triangulate_cdt, cm_triangulate_more): bytes -> 1 to 4 loops of points on a coarse
 * integer grid (so repeated points, collinear runs, spikes, loops touching
 * at a vertex or along a run, zero-length segments and tiny loops are
 * frequent), plus interior points -> the triangulation, checked.
 *
 * Any input must end in CM_OK or CM_E_DEGENERATE with a reason, never a
 * crash, a hang, an out-of-bounds access or another error.  On CM_OK:
 *   - indices in range, the triangle count sane;
 *   - no triangle turns clockwise (with folds allowed: by no more than the
 *     fold tolerance), and a flat one only where the input forces it (its
 *     longest side a boundary segment with the third corner on it);
 *   - when no two boundary segments cross (and there are at most 400
 *     boundary points): the triangles cover exactly the region, checked
 *     exactly on the integer grid: every segment (boundary segments and
 *     triangle sides, split at every vertex on them) is a side of as many
 *     triangles on its left minus on its right as the region's indicator
 *     (winding number >= 1, loops oriented as the triangulator orients
 *     them, loops without area left out) steps across it.  That is the
 *     region's boundary, so the triangles tile the region: no gap, no
 *     overlap, nothing outside, every boundary segment kept.  (Where loops
 *     go round a part twice, touching but not crossing, the ear clipping
 *     covers it twice: the steps of the winding number itself are accepted
 *     too, for the whole input.)
 * A violation is __builtin_trap().  With FUZZ_TESS_STRICT set, a failure is
 * one too where no two boundary segments cross, there are no folds, the
 * outer loop has area and some region is left (the fuzzer hunts the inputs
 * the triangulator should take but refuses); with FUZZ_TESS_DUMP set, the
 * input and the result are printed (loop/pt/tri lines) and what failed.
 *
 * Layout of the input (missing bytes read as 0):
 *   byte 0: bits 0-1 loops - 1; bits 2-3 grid (8, 32, 256, 4096 cells);
 *           bits 4-5 fold tolerance (0, 0, 1/2, 3 cells); bits 6-7 placement
 *           (as is; scaled by 2^-7 and moved to (1000, -250): exact; scaled
 *           by 0.1: not on a binary grid; x and y swapped)
 *   byte 1: interior points (0..63); bit 6 of byte 1 doubles min_dist; bit 7 inserts the second
 *           half of them by cm_triangulate_more into the first call's triangulation, which
 *           takes the Delaunay path first for rings of 4 points or more (cm_triangulate_cdt;
 *           the decoder's refinement, format 4.7)
 *   per loop: a mode byte (bits 0-1: raw points, star around a centre,
 *           random walk, a run shared with loop 0 closed by a few points;
 *           bit 2: reversed), a count byte (outer loop: two), then its data.
 *   then the interior points, two bytes each.
 *
 * Built with clang -fsanitize=fuzzer,address,undefined (make fuzz-tess);
 * replayed without libFuzzer by replay_main.c (tests/fuzz/corpus_tess).
 */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_tess.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define FZ_PTS (CM_MAX_TESS_POINTS < 1024 ? CM_MAX_TESS_POINTS : 1024)
#define FZ_TRIS CM_MAX_TESS_TRIS
#define FZ_PI 3.14159265358979323846

static cm_tri_ws ws;
static cm_vec2 P[FZ_PTS];     /* what the triangulator gets */
static double GX[FZ_PTS], GY[FZ_PTS]; /* the same points on the integer grid (the oracle's) */
static int LS[6];
static int T[FZ_TRIS][3];

typedef struct rd {
    const uint8_t *d;
    size_t n, i;
} rd;
static unsigned get(rd *r) { return r->i < r->n ? r->d[r->i++] : 0u; }
/* two bytes, low first (one call per statement: the order of operands is unspecified in C) */
static unsigned get16(rd *r)
{
    unsigned lo = get(r);
    return lo | get(r) << 8;
}

/* ------------------------------------------------------------ the oracle */

static double cr(double ax, double ay, double bx, double by, double cx, double cy)
{
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}

static int np_, nb_, nl_;
static int rep[FZ_PTS], byx[FZ_PTS], nrep;
static signed char lsign[6];

static int cmp_xy(const void *a, const void *b)
{
    int i = *(const int *)a, j = *(const int *)b;
    if (GX[i] != GX[j])
        return GX[i] < GX[j] ? -1 : 1;
    if (GY[i] != GY[j])
        return GY[i] < GY[j] ? -1 : 1;
    return i - j;
}

/* winding number of (x, y) (never on a segment) with respect to the loops the triangulator keeps */
static int wind(double x, double y)
{
    int w = 0;
    for (int l = 0; l < nl_; l++) {
        if (!lsign[l])
            continue;
        int wl = 0;
        for (int i = LS[l]; i < LS[l + 1]; i++) {
            int j = i + 1 < LS[l + 1] ? i + 1 : LS[l];
            if (GY[i] <= y) {
                if (GY[j] > y && cr(GX[i], GY[i], GX[j], GY[j], x, y) > 0)
                    wl++;
            } else if (GY[j] <= y && cr(GX[i], GY[i], GX[j], GY[j], x, y) < 0) {
                wl--;
            }
        }
        w += lsign[l] * wl;
    }
    return w;
}

typedef struct sub {
    int a, b;   /* rep ids, a < b */
    int w;      /* +1 / -1 per triangle side a->b / b->a */
    int bnd;    /* a boundary sub-segment */
} sub;
#define FZ_SUBS (16 * FZ_TRIS)
static sub subs[FZ_SUBS];
static int nsub, sub_over;
static int nsplit; /* vertices found on boundary segments (each may cost a flat triangle) */
static int on_[FZ_PTS];
static double ont_[FZ_PTS];

/* segment p -> q (rep ids), split at every vertex on it, into subs */
static void add_seg(int p, int q, int w, int bnd)
{
    double ax = GX[p], ay = GY[p], bx = GX[q], by = GY[q], dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
    double x0 = ax < bx ? ax : bx, x1 = ax < bx ? bx : ax, y0 = ay < by ? ay : by, y1 = ay < by ? by : ay;
    int lo = 0, hi = nrep;
    while (lo < hi) { /* first rep with x >= x0 */
        int mid = (lo + hi) / 2;
        if (GX[byx[mid]] < x0)
            lo = mid + 1;
        else
            hi = mid;
    }
    int n = 0;
    for (int k = lo; k < nrep && GX[byx[k]] <= x1 && n < FZ_PTS; k++) {
        int v = byx[k];
        if (v == p || v == q || GY[v] < y0 || GY[v] > y1 || cr(ax, ay, bx, by, GX[v], GY[v]) != 0)
            continue;
        double t = (GX[v] - ax) * dx + (GY[v] - ay) * dy;
        if (t <= 0 || t >= l2)
            continue;
        int j = n++;
        while (j > 0 && ont_[j - 1] > t) {
            on_[j] = on_[j - 1];
            ont_[j] = ont_[j - 1];
            j--;
        }
        on_[j] = v;
        ont_[j] = t;
    }
    if (bnd)
        nsplit += n;
    int prev = p;
    for (int i = 0; i <= n; i++) {
        int cur = i < n ? on_[i] : q;
        if (nsub >= FZ_SUBS) {
            sub_over = 1;
            return;
        }
        sub *s = &subs[nsub++];
        s->a = prev < cur ? prev : cur;
        s->b = prev < cur ? cur : prev;
        s->w = prev < cur ? w : -w;
        s->bnd = bnd;
        prev = cur;
    }
}

static int cmp_sub(const void *x, const void *y)
{
    const sub *s = x, *t = y;
    if (s->a != t->a)
        return s->a < t->a ? -1 : 1;
    return s->b < t->b ? -1 : (s->b > t->b);
}

static int proper_cross(int i, int i2, int j, int j2)
{
    double d1 = cr(GX[i], GY[i], GX[i2], GY[i2], GX[j], GY[j]), d2 = cr(GX[i], GY[i], GX[i2], GY[i2], GX[j2], GY[j2]);
    double d3 = cr(GX[j], GY[j], GX[j2], GY[j2], GX[i], GY[i]), d4 = cr(GX[j], GY[j], GX[j2], GY[j2], GX[i2], GY[i2]);
    return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

static int next_in_loop(int i)
{
    int l = 0;
    while (LS[l + 1] <= i)
        l++;
    return i + 1 < LS[l + 1] ? i + 1 : LS[l];
}

/* do two boundary segments cross (interiors, at one point)?  Segments by their least x, swept */
static int seg_[FZ_PTS];
static int cmp_seg_x(const void *a, const void *b)
{
    int i = *(const int *)a, j = *(const int *)b;
    double xi = GX[i] < GX[next_in_loop(i)] ? GX[i] : GX[next_in_loop(i)];
    double xj = GX[j] < GX[next_in_loop(j)] ? GX[j] : GX[next_in_loop(j)];
    return xi < xj ? -1 : (xi > xj ? 1 : i - j);
}

static int any_crossing(void)
{
    for (int i = 0; i < nb_; i++)
        seg_[i] = i;
    qsort(seg_, (size_t)nb_, sizeof *seg_, cmp_seg_x);
    for (int a = 0; a < nb_; a++) {
        int i = seg_[a], i2 = next_in_loop(i);
        double xmax = GX[i] > GX[i2] ? GX[i] : GX[i2];
        for (int b = a + 1; b < nb_; b++) {
            int j = seg_[b], j2 = next_in_loop(j);
            if ((GX[j] < GX[j2] ? GX[j] : GX[j2]) > xmax)
                break;
            if (proper_cross(i, i2, j, j2))
                return 1;
        }
    }
    return 0;
}

/* a flat triangle is allowed where the input forces it: on one boundary segment (a vertex lying on
   that segment makes a flat triangle necessary for the segment to stay a triangle side) */
static int on_closed(int u, int v, int c)
{
    double along = (GX[c] - GX[u]) * (GX[v] - GX[u]) + (GY[c] - GY[u]) * (GY[v] - GY[u]);
    double l2 = (GX[v] - GX[u]) * (GX[v] - GX[u]) + (GY[v] - GY[u]) * (GY[v] - GY[u]);
    return cr(GX[u], GY[u], GX[v], GY[v], GX[c], GY[c]) == 0 && along >= 0 && along <= l2;
}

static int forced_flat(const int *t)
{
    for (int k = 0; k < nb_; k++) {
        int u = rep[k], v = rep[next_in_loop(k)];
        if (u != v && on_closed(u, v, rep[t[0]]) && on_closed(u, v, rep[t[1]]) && on_closed(u, v, rep[t[2]]))
            return 1;
    }
    return 0;
}

static void check(int nt, double fold_cells)
{
    if (nt < 1)
        __builtin_trap();
    for (int k = 0; k < nt; k++)
        for (int i = 0; i < 3; i++)
            if (T[k][i] < 0 || T[k][i] >= np_)
                __builtin_trap();
    /* positions: one rep per grid position */
    for (int i = 0; i < np_; i++)
        byx[i] = i;
    qsort(byx, (size_t)np_, sizeof *byx, cmp_xy);
    nrep = 0;
    for (int k = 0; k < np_; k++) {
        int i = byx[k];
        if (k > 0 && GX[byx[k - 1]] == GX[i] && GY[byx[k - 1]] == GY[i]) {
            rep[i] = rep[byx[k - 1]];
        } else {
            rep[i] = i;
            byx[nrep++] = i;
        }
    }
    /* orientation */
    for (int k = 0; k < nt; k++) {
        int a = T[k][0], b = T[k][1], c = T[k][2];
        double a2 = cr(GX[a], GY[a], GX[b], GY[b], GX[c], GY[c]);
        if (a2 > 0)
            continue;
        if (fold_cells > 0) {
            double l = hypot(GX[b] - GX[a], GY[b] - GY[a]), m = hypot(GX[c] - GX[b], GY[c] - GY[b]);
            double n = hypot(GX[a] - GX[c], GY[a] - GY[c]), L = l > m ? (l > n ? l : n) : (m > n ? m : n);
            if (-a2 <= fold_cells * L * (1 + 1e-9) + 1e-9)
                continue;
            if (getenv("FUZZ_TESS_DUMP"))
                printf("triangle %d (%d %d %d) folded by %g cells\n", k, a, b, c, -a2 / L);
            fflush(stdout);
            __builtin_trap(); /* folded by more than allowed */
        }
        if (a2 < 0 || !forced_flat(T[k])) {
            if (getenv("FUZZ_TESS_DUMP"))
                printf("triangle %d (%d %d %d) %s\n", k, a, b, c, a2 < 0 ? "clockwise" : "flat, not forced");
            fflush(stdout);
            __builtin_trap(); /* clockwise, or flat where nothing forces it */
        }
    }
    /* sane count: a triangulation of the points, plus a flat triangle per vertex on a boundary segment */
    nsub = 0;
    sub_over = 0;
    nsplit = 0;
    for (int i = 0; i < nb_; i++) {
        int a = rep[i], b = rep[next_in_loop(i)];
        if (a != b)
            add_seg(a, b, 0, 1);
    }
    if (fold_cells > 0) { /* with folds, a segment is bent through every vertex within half of them */
        nsplit = 0;
        for (int i = 0; i < nb_; i++) {
            int a = rep[i], b = rep[next_in_loop(i)];
            double dx = GX[b] - GX[a], dy = GY[b] - GY[a], l2 = dx * dx + dy * dy;
            for (int k = 0; k < nrep && l2 > 0; k++) {
                int v = byx[k];
                double o = cr(GX[a], GY[a], GX[b], GY[b], GX[v], GY[v]);
                double t = (GX[v] - GX[a]) * dx + (GY[v] - GY[a]) * dy;
                nsplit += v != a && v != b && t > 0 && t < l2 && o * o <= 0.25 * fold_cells * fold_cells * l2 * 1.01;
            }
        }
    }
    if (nt > 2 * np_ + 2 * nl_ + nsplit) {
        if (getenv("FUZZ_TESS_DUMP"))
            printf("%d triangles for %d points\n", nt, np_);
        fflush(stdout);
        __builtin_trap();
    }
    if (fold_cells > 0)
        return;
    /* the exact cover check, when no two boundary segments cross (up to 400 boundary points: the
       check is quadratic, and smaller inputs are where the fuzzer finds things) */
    if (nb_ > 400 || any_crossing())
        return;
    for (int k = 0; k < nt; k++)
        for (int i = 0; i < 3; i++) {
            int a = rep[T[k][i]], b = rep[T[k][(i + 1) % 3]];
            if (a != b)
                add_seg(a, b, 1, 0);
        }
    if (sub_over)
        return;
    qsort(subs, (size_t)nsub, sizeof *subs, cmp_sub);
    /* loops that cover a part twice (a loop around a part of itself, touching, not crossing): the
       ear clipping covers it twice (the triangles' sides are the loops' exactly), the fallback once;
       either way every segment must agree */
    int ok_once = 1, ok_wind = 1;
    for (int i = 0; i < nsub;) {
        int j = i, net = 0, bnd = 0;
        for (; j < nsub && subs[j].a == subs[i].a && subs[j].b == subs[i].b; j++) {
            net += subs[j].w;
            bnd |= subs[j].bnd;
        }
        int once = 0, step = 0;
        if (bnd) { /* the winding number just left and just right of the middle of a -> b */
            int a = subs[i].a, b = subs[i].b;
            double mx = 0.5 * (GX[a] + GX[b]), my = 0.5 * (GY[a] + GY[b]);
            double dx = GX[b] - GX[a], dy = GY[b] - GY[a], len = hypot(dx, dy), eps = 1e-7 / len;
            int wl = wind(mx - eps * dy, my + eps * dx), wr = wind(mx + eps * dy, my - eps * dx);
            once = (wl >= 1) - (wr >= 1);
            step = wl - wr;
        }
        ok_once &= net == once;
        ok_wind &= net == step;
        if (!ok_once && !ok_wind) {
            if (getenv("FUZZ_TESS_DUMP"))
                printf("segment (%g,%g)-(%g,%g): triangles %d, region steps %d (winding %d)\n", GX[subs[i].a],
                       GY[subs[i].a], GX[subs[i].b], GY[subs[i].b], net, once, step);
            fflush(stdout);
            __builtin_trap(); /* a gap, an overlap, a triangle outside or a boundary segment lost */
        }
        i = j;
    }
}

/* ------------------------------------------------------------ the input */

static void add_pt(double x, double y)
{
    if (np_ < FZ_PTS) {
        GX[np_] = x;
        GY[np_] = y;
        np_++;
    }
}

static double clampg(double v, double g) { return v < 0 ? 0 : (v > g ? g : v); }

static void gen_loop(rd *r, int l, double G)
{
    unsigned mode = get(r);
    int n = l == 0 ? 3 + (int)(get16(r) % 300u) : 3 + (int)(get(r) % 64u);
    int s = np_;
    unsigned kind = mode & 3u;
    if (kind == 3 && l == 0) /* nothing to share yet */
        kind = 1;
    switch (kind) {
    case 0: /* raw points */
        for (int i = 0; i < n; i++) {
            double x = (double)(get16(r) % ((unsigned)G + 1u));
            double y = (double)(get16(r) % ((unsigned)G + 1u));
            add_pt(x, y);
        }
        break;
    case 1: { /* star around a centre: simple before rounding to the grid */
        double cx = l == 0 ? G / 2 : G * get(r) / 255.0, cy = l == 0 ? G / 2 : G * get(r) / 255.0;
        double R = l == 0 ? G / 2 : G / 2 * get(r) / 255.0;
        for (int i = 0; i < n; i++) {
            double a = 2 * FZ_PI * i / n, rr = R * (0.1 + 0.9 * get(r) / 255.0);
            add_pt(clampg(floor(cx + rr * cos(a) + 0.5), G), clampg(floor(cy + rr * sin(a) + 0.5), G));
        }
        break;
    }
    case 2: { /* random walk: collinear runs, spikes, repeats */
        double x = G * get(r) / 255.0, y = G * get(r) / 255.0;
        x = floor(x);
        y = floor(y);
        for (int i = 0; i < n; i++) {
            unsigned b = get(r);
            x = clampg(x + (double)(b & 7u) - 3, G);
            y = clampg(y + (double)(b >> 3 & 7u) - 3, G);
            add_pt(x, y);
        }
        break;
    }
    default: { /* a run of loop 0, closed by a few points: shares vertices and segments with it */
        int n0 = LS[1] - LS[0], j = (int)(get(r) % (unsigned)n0), k = 2 + (int)(get(r) % 16u);
        for (int i = 0; i < k; i++)
            add_pt(GX[(j + i) % n0], GY[(j + i) % n0]);
        int extra = 1 + (int)(get(r) % 3u);
        double cx = 0, cy = 0;
        for (int i = 0; i < k; i++) {
            cx += GX[(j + i) % n0] / k;
            cy += GY[(j + i) % n0] / k;
        }
        for (int i = 0; i < extra; i++) {
            double dx = (double)(get(r) % 9u) - 4, dy = (double)(get(r) % 9u) - 4;
            add_pt(clampg(floor(cx + dx * G / 32 + 0.5), G), clampg(floor(cy + dy * G / 32 + 0.5), G));
        }
        break;
    }
    }
    if ((mode & 4u) && np_ > s + 1) /* reversed */
        for (int i = s, j = np_ - 1; i < j; i++, j--) {
            double tx = GX[i], ty = GY[i];
            GX[i] = GX[j];
            GY[i] = GY[j];
            GX[j] = tx;
            GY[j] = ty;
        }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    rd r = {data, size, 0};
    unsigned h0 = get(&r), h1 = get(&r);
    static const double grids[4] = {8, 32, 256, 4096}, folds[4] = {0, 0, 0.5, 3};
    double G = grids[h0 >> 2 & 3u], fold_cells = folds[h0 >> 4 & 3u];
    unsigned place = h0 >> 6 & 3u;
    np_ = 0;
    nl_ = 0;
    int want = 1 + (int)(h0 & 3u);
    for (int l = 0; l < want && np_ + 3 <= FZ_PTS; l++) {
        LS[nl_++] = np_;
        gen_loop(&r, l, G);
        if (np_ == LS[nl_ - 1]) /* no room left: no empty loop */
            nl_--;
    }
    LS[nl_] = np_;
    nb_ = np_;
    int ni = (int)(h1 % 64u);
    for (int i = 0; i < ni; i++) {
        double x = (double)(get16(&r) % ((unsigned)G + 1u));
        double y = (double)(get16(&r) % ((unsigned)G + 1u));
        add_pt(x, y);
    }
    if (place == 3)
        for (int i = 0; i < np_; i++) {
            double t = GX[i];
            GX[i] = GY[i];
            GY[i] = t;
        }
    for (int i = 0; i < np_; i++)
        P[i] = place == 1 ? cm_v2(1000.0 + GX[i] / 128.0, -250.0 + GY[i] / 128.0)
               : place == 2 ? cm_v2(GX[i] * 0.1, GY[i] * 0.1) : cm_v2(GX[i], GY[i]);
    double unit = place == 1 ? 1.0 / 128.0 : (place == 2 ? 0.1 : 1.0);
    double md = (h1 & 64u) ? 2.0 * unit : 0.0;
    /* the triangulator's loops: without area (exactly, on the grid) they are left out */
    for (int l = 0; l < nl_; l++) {
        double a2 = 0;
        for (int i = LS[l]; i < LS[l + 1]; i++) {
            int j = i + 1 < LS[l + 1] ? i + 1 : LS[l];
            a2 += cr(GX[LS[l]], GY[LS[l]], GX[i], GY[i], GX[j], GY[j]);
        }
        lsign[l] = (signed char)(a2 == 0 ? 0 : ((l == 0) == (a2 > 0) ? 1 : -1));
    }

    cm_status st;
    cm_status_init(&st);
    int nt = -1, nu = -1, split = (h1 & 128u) ? nb_ + (np_ - nb_) / 2 : np_;
    /* with the continuation, as format 4.7's refinement: rings of 4 points or more by the Delaunay
       path first (cm_triangulate_cdt) */
    cm_err e = cm_triangulate_cdt(P, split, LS, nl_, md, fold_cells * unit, split < np_ ? 4 : 0, T, FZ_TRIS, &nt,
                                  &nu, &ws, &st);
    if (e == CM_OK && split < np_) {
        /* the rest into that triangulation: its used points are not counted, so nu stays the first's */
        e = cm_triangulate_more(P, np_, md, T, FZ_TRIS, &nt, &ws, &st);
        if (e != CM_OK && nt != 0)
            __builtin_trap();
    }
    if (getenv("FUZZ_TESS_DUMP")) { /* the input and the result on the grid, for a look (not in fuzzing) */
        printf("# place %u fold %g md %g: %s %s\n", place, fold_cells, md, cm_err_name(e), st.where ? st.where : "");
        for (int l = 0; l < nl_; l++) {
            printf("loop %d:", l);
            for (int i = LS[l]; i < LS[l + 1]; i++)
                printf(" (%.17g,%.17g)", GX[i], GY[i]);
            printf("\n");
        }
        for (int i = nb_; i < np_; i++)
            printf("pt (%.17g,%.17g)\n", GX[i], GY[i]);
        for (int k = 0; e == CM_OK && k < nt; k++)
            printf("tri %d %d %d\n", T[k][0], T[k][1], T[k][2]);
        fflush(stdout);
    }
    if (e != CM_OK) {
        /* out of triangles only where the fallback's Delaunay triangulation of every boundary point and
           an enclosing triangle needs 2 nb + 1 > CM_MAX_TESS_TRIS (the tiny profile's 64 points) */
        int limit_ok = e == CM_E_RANGE && 2 * nb_ + 1 > CM_MAX_TESS_TRIS;
        if ((e != CM_E_DEGENERATE && !limit_ok) || st.code != e || st.where == NULL || nt != 0)
            __builtin_trap();
        int empty = st.where && strstr(st.where, "no region") != NULL; /* loops in the wrong order */
        if (e == CM_E_DEGENERATE && lsign[0] != 0 && fold_cells == 0 && !empty && getenv("FUZZ_TESS_STRICT")) {
            /* strict mode (for finding them): refuse a failure on loops that do not cross */
            if (!any_crossing())
                __builtin_trap();
        }
        return 0;
    }
    if (lsign[0] == 0 || nu < 0 || nu > np_ - nb_)
        __builtin_trap(); /* an outer loop without area must fail */
    check(nt, fold_cells);
    return 0;
}
