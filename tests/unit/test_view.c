/*
 * test_view.c - the software viewer (cm_view.h) and its PNG writer
 * (cm_png.h): a box seen from the front fills the square the fitted camera
 * promises, with the head light's shade; the nearer of two triangles wins
 * whatever the order; a frame beyond the build's is refused by name; the
 * PNG's chunks, CRCs, stored deflate blocks and Adler-32 check out, its
 * pixels are the frame's, and its size is the one announced.
 */
#include "test_util.h"
#include "test_mesh.h"

#include <math.h>
#include <stdio.h>

#include "cm/cm_bspline.h"
#include "cm/cm_crc32.h"
#include "cm/cm_png.h"
#include "cm/cm_view.h"

static cm_view view;

#define MAXV 64
#define MAXI 192
static float g_pos[MAXV][3], g_nrm[MAXV][3];
static uint32_t g_idx[MAXI];
static cm_mesh_face g_faces[8];

static cm_mesh mesh_storage(void) { return test_mesh_on(g_pos, g_nrm, g_idx, g_faces, MAXV, MAXI, 8); }

/* a quad (a, b, c, d) with normal n as one face of two triangles */
static void add_quad(cm_mesh *m, const float q[4][3], const float n[3], uint32_t rgb, int has_color)
{
    cm_mesh_face *f = &m->faces[m->nfaces++];
    memset(f, 0, sizeof *f);
    f->first_vert = m->nverts;
    f->first_index = m->nindex;
    f->rgb = rgb;
    f->has_color = (uint8_t)has_color;
    for (int i = 0; i < 4; i++) {
        memcpy(m->pos[m->nverts + (uint32_t)i], q[i], sizeof(float[3]));
        memcpy(m->nrm[m->nverts + (uint32_t)i], n, sizeof(float[3]));
    }
    static const int tri[6] = {0, 1, 2, 0, 2, 3};
    for (int i = 0; i < 6; i++)
        m->idx[m->nindex + (uint32_t)i] = m->nverts + (uint32_t)tri[i];
    m->nverts += 4;
    m->nindex += 6;
    f->nverts = 4;
    f->nindex = 6;
}

/* the unit box's front face (y = 0, normal -y) in grey, one face of two triangles */
static cm_mesh front_square(void)
{
    cm_mesh m = mesh_storage();
    const float front[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}};
    const float ny[3] = {0, -1, 0};
    add_quad(&m, front, ny, 0x808080u, 1);
    return m;
}

/* options for a square frame of `size` pixels from `dir`, edges (and silhouettes) on or off */
static cm_view_opts square_opts(int size, cm_view_dir dir, int edges)
{
    cm_view_opts o;
    cm_view_opts_default(&o);
    o.width = o.height = size;
    o.dir = dir;
    o.edges = edges;
    return o;
}

static size_t count_not(const cm_view *v, uint32_t rgb)
{
    size_t n = 0, npix = (size_t)v->o.width * (size_t)v->o.height;
    for (size_t i = 0; i < npix; i++)
        if (v->rgb[3 * i] != (uint8_t)(rgb >> 16) || v->rgb[3 * i + 1] != (uint8_t)(rgb >> 8) ||
            v->rgb[3 * i + 2] != (uint8_t)rgb)
            n++;
    return n;
}

/* the unit box's front face (y = 0, normal -y) seen from the front, orthographic, 100 x 100: the
   camera leaves a margin of 6 px, so the box's 1 mm fills 88 px across and down */
static void test_front_box(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 100 || CM_VIEW_MAX_H < 100)
        skip(); /* the tiny profile's frame: test_refuses_large_frame covers it */
    cm_mesh m = front_square();
    cm_view_opts o = square_opts(100, CM_VIEW_FRONT, 0);
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_view_begin(&view, &o, lo, hi, &st));
    cm_view_mesh(&view, &m);
    assert_int_equal(view.triangles, 2);
    assert_int_equal(count_not(&view, o.background), 88 * 88);
    /* the middle pixel: grey 128 times ambient + head light + the fill light's |n . fill| */
    size_t mid = 50 * 100 + 50;
    double light = 0.22 + 0.62 * 1.0 + 0.16 * 0.40824829046386302;
    int want = (int)(128.0 * light + 0.5);
    assert_int_equal(view.rgb[3 * mid], want);
    assert_int_equal(view.rgb[3 * mid + 1], want);
    /* the corner pixel stays background */
    assert_int_equal(view.rgb[0], 0xff);
}

/* two overlapping squares at different depths: the nearer one shows, drawn first or last */
static void test_depth_order(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 64 || CM_VIEW_MAX_H < 64)
        skip();
    for (int order = 0; order < 2; order++) {
        cm_mesh m = mesh_storage();
        const float nearq[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}};
        const float farq[4][3] = {{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}};
        const float ny[3] = {0, -1, 0};
        add_quad(&m, order ? nearq : farq, ny, order ? 0xff0000u : 0x0000ffu, 1);
        add_quad(&m, order ? farq : nearq, ny, order ? 0x0000ffu : 0xff0000u, 1);
        cm_view_opts o = square_opts(64, CM_VIEW_FRONT, 0);
        const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
        assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
        cm_view_mesh(&view, &m);
        size_t mid = 32 * 64 + 32;
        assert_true(view.rgb[3 * mid] > 0); /* red: the near square */
        assert_int_equal(view.rgb[3 * mid + 2], 0);
    }
}

/* the turntable: the front view of a model turned a quarter (6 steps of 15 degrees counter-clockwise
   from above) is its left view, pixel for pixel; 24 steps are a whole turn, -18 the same as 6; the
   front face (red) and half of the left face (blue: the right view, its mirror, differs) tell the
   views apart */
static uint8_t g_frame[64 * 64 * 3];
static void turned_frame(cm_view_dir dir, int turn)
{
    cm_mesh m = mesh_storage();
    const float front[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}};
    const float left[4][3] = {{0, 0.5f, 0}, {0, 0, 0}, {0, 0, 1}, {0, 0.5f, 1}}; /* half: not its mirror */
    const float ny[3] = {0, -1, 0}, nx[3] = {-1, 0, 0};
    add_quad(&m, front, ny, 0xff0000u, 1);
    add_quad(&m, left, nx, 0x0000ffu, 1);
    cm_view_opts o = square_opts(64, dir, 0);
    o.turn = turn;
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
    cm_view_mesh(&view, &m);
}

static void test_turn(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 64 || CM_VIEW_MAX_H < 64)
        skip();
    size_t n = sizeof g_frame, mid = 3 * (32 * 64 + 32), right = 3 * (32 * 64 + 48);
    turned_frame(CM_VIEW_LEFT, 0);
    assert_true(view.rgb[right + 2] > 0 && view.rgb[right] == 0); /* the left view: blue on the right */
    memcpy(g_frame, view.rgb, n);
    turned_frame(CM_VIEW_RIGHT, 0);
    assert_memory_not_equal(view.rgb, g_frame, n);
    turned_frame(CM_VIEW_FRONT, 6);
    assert_memory_equal(view.rgb, g_frame, n);
    turned_frame(CM_VIEW_FRONT, -18);
    assert_memory_equal(view.rgb, g_frame, n);
    turned_frame(CM_VIEW_FRONT, 0);
    assert_true(view.rgb[mid] > 0 && view.rgb[mid + 2] == 0); /* unturned: red */
    memcpy(g_frame, view.rgb, n);
    turned_frame(CM_VIEW_FRONT, 24);
    assert_memory_equal(view.rgb, g_frame, n);
    turned_frame(CM_VIEW_FRONT, 1); /* 15 degrees: both faces, neither view */
    assert_memory_not_equal(view.rgb, g_frame, n);
}

/* a tube along x (radius 0.5, 24 sides, outward normals) seen from the front: its silhouettes are
   its top and bottom generators, drawn in the edge colour across its width; with edges off, none;
   a flat square has none either (one normal: no sign change) */
static size_t count_rgb(const cm_view *v, uint32_t rgb)
{
    size_t npix = (size_t)v->o.width * (size_t)v->o.height;
    return npix - count_not(v, rgb);
}

static void test_silhouette(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 100 || CM_VIEW_MAX_H < 100)
        skip();
    enum { SIDES = 24 };
    for (int edges = 0; edges < 2; edges++) {
        cm_mesh m = mesh_storage();
        cm_mesh_face *f = &m.faces[m.nfaces++];
        memset(f, 0, sizeof *f);
        for (int k = 0; k < SIDES; k++) {
            double a = 2.0 * 3.14159265358979323846 * (double)k / SIDES;
            for (int end = 0; end < 2; end++) {
                float *p = m.pos[2 * k + end], *n = m.nrm[2 * k + end];
                p[0] = (float)end, p[1] = (float)(0.5 + 0.5 * cos(a)), p[2] = (float)(0.5 + 0.5 * sin(a));
                n[0] = 0.0f, n[1] = (float)cos(a), n[2] = (float)sin(a);
            }
            uint32_t a0 = (uint32_t)(2 * k), b0 = (uint32_t)(2 * ((k + 1) % SIDES));
            const uint32_t tri[6] = {a0, a0 + 1, b0 + 1, a0, b0 + 1, b0};
            memcpy(&m.idx[m.nindex], tri, sizeof tri);
            m.nindex += 6;
        }
        m.nverts = 2 * SIDES;
        f->nverts = m.nverts;
        f->nindex = m.nindex;
        cm_view_opts o = square_opts(100, CM_VIEW_FRONT, edges);
        const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
        assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
        cm_view_mesh(&view, &m);
        size_t lines = count_rgb(&view, 0x1a1a1au);
        if (!edges) {
            assert_int_equal(view.silhouette_segments, 0);
            assert_int_equal(lines, 0);
            continue;
        }
        /* the two generators: each about the tube's 88 pixels across, in the top and bottom rows of
           its outline (rows 6 and 93 of the fitted frame, give or take one) */
        assert_true(view.silhouette_segments >= 2);
        size_t top = 0, bottom = 0;
        for (int y = 0; y < 100; y++)
            for (int x = 0; x < 100; x++) {
                const uint8_t *px = &view.rgb[3 * (y * 100 + x)];
                if (px[0] == 0x1a && px[1] == 0x1a && px[2] == 0x1a) {
                    assert_true(y <= 8 || y >= 91); /* nowhere in between */
                    top += y <= 8;
                    bottom += y >= 91;
                }
            }
        assert_true(top >= 80 && bottom >= 80);
    }
    /* a plane: no silhouette */
    cm_mesh m = front_square();
    cm_view_opts o = square_opts(100, CM_VIEW_ISO, 1);
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
    cm_view_mesh(&view, &m);
    assert_int_equal(view.silhouette_segments, 0);
}

/* the fill rule: the front square's two triangles drawn one at a time cover 88 x 88 pixels between
   them, each pixel once: the diagonal they share runs through 88 pixel centres (x + y = 100 at
   the centres of a square from 6 to 94), and the top-left rule gives each to one triangle (a
   tolerance on the weights gave them to both, a cut one to neither) */
static void test_fill_rule(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 100 || CM_VIEW_MAX_H < 100)
        skip();
    cm_view_opts o = square_opts(100, CM_VIEW_FRONT, 0);
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    size_t covered[2];
    for (int half = 0; half < 2; half++) {
        cm_mesh m = front_square();
        m.faces[0].first_index += half ? 3u : 0u;
        m.faces[0].nindex = 3;
        assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
        cm_view_mesh(&view, &m);
        covered[half] = count_not(&view, o.background);
        assert_true(covered[half] >= 88 * 87 / 2);
    }
    assert_int_equal(covered[0] + covered[1], 88 * 88);
}

/* a big mesh of its own: the unit square's front (y = 0, normal -y) in many triangles */
#define BIG_CELLS (CM_VIEW_FACE_VERTS / 2 + 8) /* a strip of these: more vertices than the cache */
#define GRID_CELLS 120                         /* a grid of these a side: cells of 0.73 px */
#define BIG_VERTS (2 * (BIG_CELLS + 1) > GRID_CELLS * 2 * (GRID_CELLS + 1) ? 2 * (BIG_CELLS + 1) : GRID_CELLS * 2 * (GRID_CELLS + 1))
#define BIG_INDEX (6 * (BIG_CELLS > GRID_CELLS * GRID_CELLS ? BIG_CELLS : GRID_CELLS * GRID_CELLS))
static float b_pos[2 * BIG_VERTS][3], b_nrm[2 * BIG_VERTS][3];
static uint32_t b_idx[BIG_INDEX];
static cm_mesh_face b_faces[BIG_CELLS + GRID_CELLS];
static uint8_t b_frame[3][100 * 100 * 3];

static cm_mesh big_storage(void)
{
    return test_mesh_on(b_pos, b_nrm, b_idx, b_faces, 2 * BIG_VERTS, BIG_INDEX, BIG_CELLS + GRID_CELLS);
}

/* a face of cells [c0, c1) of a row of `across` cells at height [z0, z1]: its own vertices, bottom
   and top by turns; its triangles each cell's lower-left (which & 1) and upper-right (which & 2),
   in reverse order where asked */
static void add_row(cm_mesh *m, int c0, int c1, int across, double z0, double z1, int which, int reverse)
{
    cm_mesh_face *f = &m->faces[m->nfaces++];
    memset(f, 0, sizeof *f);
    f->first_vert = m->nverts;
    f->first_index = m->nindex;
    f->rgb = 0x808080u;
    f->has_color = 1;
    for (int c = c0; c <= c1; c++)
        for (int k = 0; k < 2; k++) {
            float *p = m->pos[m->nverts], *n = m->nrm[m->nverts];
            p[0] = (float)((double)c / across), p[1] = 0.0f, p[2] = (float)(k ? z1 : z0);
            n[0] = 0.0f, n[1] = -1.0f, n[2] = 0.0f;
            m->nverts++;
        }
    for (int i = 0; i < c1 - c0; i++) {
        int c = reverse ? c1 - c0 - 1 - i : i;
        uint32_t b0 = f->first_vert + 2u * (uint32_t)c, t0 = b0 + 1, b1 = b0 + 2, t1 = b0 + 3;
        const uint32_t tri[2][3] = {{b0, b1, t0}, {b1, t1, t0}};
        for (int h = 0; h < 2; h++)
            if (which & (1 << h))
                for (int k = 0; k < 3; k++)
                    m->idx[m->nindex++] = tri[h][k];
    }
    f->nverts = m->nverts - f->first_vert;
    f->nindex = m->nindex - f->first_index;
}

/* a face of more vertices than the viewer's vertex cache (CM_VIEW_FACE_VERTS: a GREGORY face meshed
   patch by patch) is drawn through a window on it: the same pixels as the strip cut into faces that
   fit, its triangles in order or in reverse; the strip's slivers (a fifteenth of a pixel across)
   cover the square exactly */
static void test_large_face(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 100 || CM_VIEW_MAX_H < 100)
        skip();
    cm_view_opts o = square_opts(100, CM_VIEW_FRONT, 0);
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    for (int variant = 0; variant < 3; variant++) {
        cm_mesh m = big_storage();
        if (variant < 2) {
            add_row(&m, 0, BIG_CELLS, BIG_CELLS, 0.0, 1.0, 3, variant == 1);
            assert_true(m.faces[0].nverts > CM_VIEW_FACE_VERTS);
        } else {
            for (int c = 0; c < BIG_CELLS; c += CM_VIEW_FACE_VERTS / 4)
                add_row(&m, c, c + CM_VIEW_FACE_VERTS / 4 < BIG_CELLS ? c + CM_VIEW_FACE_VERTS / 4 : BIG_CELLS,
                        BIG_CELLS, 0.0, 1.0, 3, 0);
            assert_true(m.nfaces > 1 && m.faces[0].nverts <= CM_VIEW_FACE_VERTS);
        }
        assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
        cm_view_mesh(&view, &m);
        assert_int_equal(count_not(&view, o.background), 88 * 88);
        memcpy(b_frame[variant], view.rgb, sizeof b_frame[variant]);
    }
    assert_memory_equal(b_frame[0], b_frame[2], sizeof b_frame[0]);
    assert_memory_equal(b_frame[1], b_frame[2], sizeof b_frame[0]);
}

/* a square in triangles smaller than a pixel (each pixel centre tested on its own, no slopes):
   the lower-left halves of the cells and the upper-right halves drawn apart cover the square's
   88 x 88 pixels once between them, and together exactly the square the two large triangles cover */
static void test_small_triangles(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 100 || CM_VIEW_MAX_H < 100)
        skip();
    cm_view_opts o = square_opts(100, CM_VIEW_FRONT, 0);
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    size_t covered[3];
    for (int which = 1; which <= 3; which++) {
        cm_mesh m = big_storage();
        for (int r = 0; r < GRID_CELLS; r++)
            add_row(&m, 0, GRID_CELLS, GRID_CELLS, (double)r / GRID_CELLS, (double)(r + 1) / GRID_CELLS, which, 0);
        assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
        cm_view_mesh(&view, &m);
        covered[which - 1] = count_not(&view, o.background);
        memcpy(b_frame[0], view.rgb, sizeof b_frame[0]);
    }
    assert_true(covered[0] > 88 * 88 / 3 && covered[1] > 88 * 88 / 3);
    assert_int_equal(covered[0] + covered[1], 88 * 88);
    assert_int_equal(covered[2], 88 * 88);
    cm_mesh sq = front_square();
    assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
    cm_view_mesh(&view, &sq);
    for (size_t i = 0; i < 100 * 100; i++)
        assert_int_equal(view.rgb[3 * i] == (uint8_t)(o.background >> 16), b_frame[0][3 * i] == (uint8_t)(o.background >> 16));
}

/* a closed part's back faces: a tetrahedron whose four faces, one triangle each, face outwards and
   run each edge opposite ways (a closed part, cm_view_parts) is drawn to the same pixels with its two
   faces turned away from the iso view skipped; with one edge run the same way by both its faces the
   part is open and every triangle is drawn */
static cm_model g_tet;
/* `count` tetrahedra (the second the first turned half round the x axis: (x, y, z) -> (x, -y, -z),
   touching it along edge 0-1, its other edges its own, 6..10); `inward`: the second's normals turned
   inwards */
static void tetrahedra(cm_mesh *m, uint32_t count, int inward)
{
    static const float P[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    static const int tri[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    static const float N[4][3] = {{0, 0, -1}, {0, -1, 0}, {-1, 0, 0}, {0.57735027f, 0.57735027f, 0.57735027f}};
    /* edges 0-1, 0-2, 0-3, 1-2, 1-3, 2-3; each face's uses in its loop's order (rev: runs v1 -> v0) */
    static const uint32_t edge[4][3] = {{1, 3, 0}, {0, 4, 2}, {2, 5, 1}, {3, 5, 4}};
    static const uint8_t rev[4][3] = {{0, 1, 1}, {0, 0, 1}, {0, 1, 1}, {0, 0, 1}};
    memset(&g_tet, 0, sizeof g_tet);
    g_tet.nfaces = g_tet.nloops = 4 * count;
    g_tet.nedges = count > 1 ? 11 : 6;
    g_tet.nuses = 12 * count;
    *m = mesh_storage();
    for (uint32_t f = 0; f < 4 * count; f++) {
        uint32_t t = f % 4;
        int second = f >= 4;
        float flip = second && inward ? -1.0f : 1.0f, turn = second ? -1.0f : 1.0f;
        g_tet.faces[f].loop0 = f;
        g_tet.faces[f].nloops = 1;
        g_tet.loops[f].use0 = 3 * f;
        g_tet.loops[f].nuse = 3;
        cm_mesh_face *F = &m->faces[m->nfaces++];
        memset(F, 0, sizeof *F);
        F->source_face = f;
        F->first_vert = m->nverts;
        F->first_index = m->nindex;
        F->nverts = F->nindex = 3;
        for (int i = 0; i < 3; i++) {
            const float *q = P[tri[t][i]];
            const float pos[3] = {q[0], turn * q[1], turn * q[2]};
            const float nrm[3] = {flip * N[t][0], flip * turn * N[t][1], flip * turn * N[t][2]};
            g_tet.uses[3 * f + (uint32_t)i].edge = second && edge[t][i] != 0 ? edge[t][i] + 5 : edge[t][i];
            g_tet.uses[3 * f + (uint32_t)i].rev = rev[t][i];
            memcpy(m->pos[m->nverts], pos, sizeof pos);
            memcpy(m->nrm[m->nverts], nrm, sizeof nrm);
            m->idx[m->nindex++] = m->nverts++;
        }
    }
}

/* a closed tetrahedron, or an open one (edge 2-3 run 3 -> 2 by both its faces) */
static void tetrahedron(cm_mesh *m, int open)
{
    tetrahedra(m, 1, 0);
    if (open)
        g_tet.uses[3 * 3 + 1].rev = 1;
}

/* `count` tetrahedra (tetrahedra()) from iso: drawn as they are (k = 0, no parts: every triangle),
   then with their parts numbered (k = 1) and once more changed (k = 2: one open, or the second's
   normals inwards); the same pixels each time; the triangles drawn and (k > 0) the first and the
   second solid's faces closed each time */
static void draw_tetrahedra(uint32_t count, uint64_t drawn[3], uint8_t closed[3][2])
{
    cm_view_opts o = square_opts(64, CM_VIEW_ISO, 0);
    const float lo[3] = {0, count > 1 ? -1.0f : 0.0f, count > 1 ? -1.0f : 0.0f}, hi[3] = {1, 1, 1};
    for (int k = 0; k < 3; k++) {
        cm_mesh m;
        if (count > 1)
            tetrahedra(&m, count, k == 2);
        else
            tetrahedron(&m, k == 2);
        assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
        if (k > 0)
            assert_int_equal(cm_view_parts(&view, &g_tet), count);
        cm_view_mesh(&view, &m);
        drawn[k] = view.triangles;
        closed[k][0] = view.face_closed[0];
        closed[k][1] = count > 1 ? view.face_closed[4] : 0;
        if (k == 0)
            memcpy(g_frame, view.rgb, sizeof g_frame);
        else
            assert_memory_equal(view.rgb, g_frame, sizeof g_frame);
    }
}

static void test_back_faces(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 64 || CM_VIEW_MAX_H < 64 || CM_MAX_FACES < 4 || CM_MAX_MODEL_USES < 12)
        skip();
    uint64_t drawn[3];
    uint8_t closed[3][2];
    draw_tetrahedra(1, drawn, closed);
    assert_int_equal(closed[1][0], 1);
    assert_int_equal(closed[2][0], 0);
    assert_true(drawn[1] < drawn[0]); /* closed: the turned-away faces skipped */
    assert_int_equal(drawn[1], 2);
    assert_int_equal(drawn[2], drawn[0]); /* open: all drawn */
}

/* two closed tetrahedra touching along an edge (the second the first turned half round the x axis:
   edge 0-1 used four times, twice by each): each is closed by its own uses, and the viewer measures
   which way its normals face (the encoder measured the touching solids together).  Outwards: both
   drawn without their turned-away faces, the same pixels; the second's normals turned inwards: it
   is drawn whole (skipping its "turned-away" faces would lose its front), the same pixels again */
static void test_touching_solids(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 64 || CM_VIEW_MAX_H < 64 || CM_MAX_FACES < 8 || CM_MAX_EDGES < 11 || CM_MAX_MODEL_USES < 24)
        skip();
    uint64_t drawn[3];
    uint8_t closed[3][2];
    draw_tetrahedra(2, drawn, closed);
    assert_int_equal(closed[1][0], 1);
    assert_int_equal(closed[1][1], 1);
    assert_int_equal(closed[2][0], 1);
    assert_int_equal(closed[2][1], 0); /* (its normals inwards: measured so) */
    assert_true(drawn[1] < drawn[0]);
    assert_true(drawn[2] > drawn[1] && drawn[2] < drawn[0]);
}

/* the model's own edges, as lines: a closed tetrahedron seen from iso has two faces turned away,
   and the edge between them (0-2) is behind them: not drawn (nor a dashed line where the faces in
   front are nearer than its bias); open, all six are drawn */
static void test_back_edges(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 64 || CM_VIEW_MAX_H < 64 || CM_MAX_FACES < 4 || CM_MAX_MODEL_USES < 12 ||
        CM_MAX_MODEL_CTRL < 12 || CM_MAX_MODEL_KNOTS < 24)
        skip();
    static const int ends[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    static const float P[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    cm_view_opts o = square_opts(64, CM_VIEW_ISO, 1);
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    uint64_t lines[2];
    for (int open = 0; open < 2; open++) {
        cm_mesh m;
        tetrahedron(&m, open);
        for (uint32_t e = 0; e < 6; e++) {
            cm_edge *E = &g_tet.edges[e];
            E->v0 = ends[e][0], E->v1 = ends[e][1];
            E->p = 1, E->nctrl = 2, E->ctrl0 = 2 * e, E->knot0 = 4 * e;
            for (int i = 0; i < 2; i++)
                g_tet.ctrl[2 * e + (uint32_t)i] =
                    cm_v3((double)P[ends[e][i]][0], (double)P[ends[e][i]][1], (double)P[ends[e][i]][2]);
            for (int i = 0; i < 4; i++)
                g_tet.knots[4 * e + (uint32_t)i] = i < 2 ? 0.0 : 1.0;
        }
        assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
        assert_int_equal(cm_view_parts(&view, &g_tet), 1);
        cm_view_mesh(&view, &m);
        uint64_t before = view.edge_segments;
        cm_view_edges(&view, &g_tet);
        lines[open] = view.edge_segments - before;
        assert_int_equal(view.face_away[0], !open);
        assert_int_equal(view.face_away[2], !open);
    }
    assert_int_equal(lines[0], 5);
    assert_int_equal(lines[1], 6);
}

/* front to back: a square half the size behind the unit square's front (y = 0.5), first in the
   file, is drawn (two triangles) and then covered when the frame follows the file; with the fit's
   boxes (cm_view_fit) the front square goes first and the one behind is skipped whole, the same
   pixels; a square behind but larger shows round the front one and is drawn, and so is one whose
   upper half is in front of a tilted front square (nearer at its lower edge: drawn first) */
static void test_hidden_faces(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 100 || CM_VIEW_MAX_H < 100 || CM_MAX_FACES < 2)
        skip();
    cm_view_opts o = square_opts(100, CM_VIEW_FRONT, 0);
    const float ny[3] = {0, -1, 0};
    for (int larger = 0; larger < 3; larger++) {
        /* (2: the unit square tilted, its lower edge half a unit nearer and its upper half a unit
           farther, the small square upright at y = 0: after it in depth, half of it in front) */
        float lo_x = larger == 1 ? -0.25f : 0.25f, hi_x = larger == 1 ? 1.25f : 0.75f, yb = larger == 2 ? 0.0f : 0.5f;
        const float back[4][3] = {{lo_x, yb, lo_x}, {hi_x, yb, lo_x}, {hi_x, yb, hi_x}, {lo_x, yb, hi_x}};
        const float y0 = larger == 2 ? -0.5f : 0.0f, y1 = larger == 2 ? 0.5f : 0.0f;
        const float front[4][3] = {{0, y0, 0}, {1, y0, 0}, {1, y1, 1}, {0, y1, 1}};
        const float tilted[3] = {0, -0.7071068f, 0.7071068f};
        const float lo[3] = {lo_x < 0 ? lo_x : 0, y0, lo_x < 0 ? lo_x : 0}, hi[3] = {hi_x > 1 ? hi_x : 1, 0.5f, hi_x > 1 ? hi_x : 1};
        uint64_t drawn[2];
        for (int fit = 0; fit < 2; fit++) {
            cm_mesh m = mesh_storage();
            add_quad(&m, back, ny, 0x2060a0u, 1);
            add_quad(&m, front, larger == 2 ? tilted : ny, 0x808080u, 1);
            assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
            if (fit)
                cm_view_fit(&view, &m, NULL, 0);
            assert_int_equal(view.boxes_nfaces, fit ? 2 : 0);
            cm_view_mesh(&view, &m);
            drawn[fit] = view.triangles;
            if (!fit)
                memcpy(b_frame[0], view.rgb, sizeof b_frame[0]);
            else
                assert_memory_equal(view.rgb, b_frame[0], sizeof b_frame[0]);
        }
        assert_int_equal(drawn[0], 4);
        assert_int_equal(drawn[1], larger ? 4 : 2);
        assert_int_equal(view.hidden_faces, larger == 0);
    }
}

/* the fit from the faces' boxes (cm_mesh_face_boxes): six squares of a unit cube's faces, a small
   tilted one inside it and a sliver along its diagonal and a little beyond (whose box reaches
   farthest every way: measured first, it is not the outline), seen from iso and turned.  The camera is the
   same as from every vertex, bit for bit, and so is the frame; the boxes' union is cm_mesh_bounds';
   the small face is not measured (its kept box is its box's bound, wider than its vertices'); every
   kept box holds its face's vertices.  Faces that do not hold the vertices one after another, or
   more than the boxes: none boxed */
static void test_fit_from_boxes(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 120 || CM_VIEW_MAX_H < 90 || CM_MAX_FACES < 8)
        skip();
    static const float sq[8][4][3] = {
        {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}},         {{1, 1, 0}, {0, 1, 0}, {0, 1, 1}, {1, 1, 1}},
        {{0, 1, 0}, {0, 0, 0}, {0, 0, 1}, {0, 1, 1}},         {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}},
        {{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}},         {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
        {{0.3f, 0.3f, 0.3f}, {0.6f, 0.4f, 0.3f}, {0.6f, 0.5f, 0.6f}, {0.3f, 0.4f, 0.6f}},
        {{-0.1f, -0.1f, -0.1f}, {-0.08f, -0.1f, -0.1f}, {1.1f, 1.1f, 1.1f}, {1.08f, 1.1f, 1.1f}}};
    const float n[3] = {0, -1, 0};
    cm_mesh m = mesh_storage();
    for (int f = 0; f < 8; f++)
        add_quad(&m, sq[f], n, 0x808080u, 1);
    static float box[8][6];
    static uint8_t frame[120 * 90 * 3];
    uint32_t nboxed = 0;
    float lo[3], hi[3], blo[3], bhi[3];
    assert_int_equal(cm_mesh_bounds(&m, lo, hi), 1);
    assert_int_equal(cm_mesh_face_boxes(&m, box, 8, &nboxed, blo, bhi), 1);
    assert_int_equal(nboxed, 8);
    assert_memory_equal(lo, blo, sizeof lo);
    assert_memory_equal(hi, bhi, sizeof hi);
    assert_true(box[6][0] == 0.3f && box[6][4] == 0.5f && box[7][5] == 1.1f);
    cm_view_opts o = square_opts(120, CM_VIEW_ISO, 0);
    o.height = 90;
    for (int turn = 0; turn < 3; turn++) {
        o.turn = turn;
        double c[3], scale;
        float exact[8][4];
        for (int boxed = 0; boxed < 2; boxed++) {
            assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
            cm_view_fit(&view, &m, boxed ? (const float(*)[6])box : NULL, boxed ? nboxed : 0);
            assert_int_equal(view.boxes_nfaces, 8);
            cm_view_mesh(&view, &m);
            if (!boxed) {
                memcpy(c, view.c, sizeof c);
                scale = view.scale;
                memcpy(frame, view.rgb, sizeof frame);
                for (int f = 0; f < 8; f++)
                    for (int k = 0; k < 4; k++)
                        exact[f][k] = view.face_box[f][k];
                continue;
            }
            assert_memory_equal(view.c, c, sizeof c);
            assert_memory_equal(&view.scale, &scale, sizeof scale);
            assert_memory_equal(view.rgb, frame, sizeof frame);
            for (int f = 0; f < 8; f++)
                assert_true(view.face_box[f][0] <= exact[f][0] && view.face_box[f][1] >= exact[f][1] &&
                            view.face_box[f][2] <= exact[f][2] && view.face_box[f][3] >= exact[f][3]);
            assert_true(view.face_box[6][0] < exact[6][0] || view.face_box[6][1] > exact[6][1] ||
                        view.face_box[6][2] < exact[6][2] || view.face_box[6][3] > exact[6][3]);
        }
    }
    /* a NaN in a face's first vertex (a hostile GLB's): that face's box ignores the rest of its
       vertices, so the whole mesh's bounds are cm_mesh_bounds' all the same */
    m.pos[28][2] = NAN;
    m.pos[30][2] = 5.0f;
    assert_int_equal(cm_mesh_bounds(&m, lo, hi), 1);
    assert_int_equal(cm_mesh_face_boxes(&m, box, 8, &nboxed, blo, bhi), 1);
    assert_int_equal(nboxed, 8);
    assert_true(hi[2] == 5.0f && bhi[2] == 5.0f && blo[2] == lo[2]);
    /* (the last two faces' vertices swapped round: not one after another) */
    m.faces[6].first_vert = 28, m.faces[7].first_vert = 24;
    assert_int_equal(cm_mesh_face_boxes(&m, box, 8, &nboxed, blo, bhi), 1);
    assert_int_equal(nboxed, 0);
    assert_memory_equal(lo, blo, sizeof lo);
    assert_int_equal(cm_mesh_face_boxes(&m, box, 7, &nboxed, blo, bhi), 1);
    assert_int_equal(nboxed, 0);
}

/* front to back, triangle by triangle: a square tilted back (y = z - 0.5, nearest at its lower
   edge) and then one face of two squares upright at y = 0, one over the tilted square's lower half
   (behind it) and one over its upper half (in front of it).  The face is not behind every tile it
   touches, so it is drawn; its lower square's two triangles are skipped without being set up
   (triangle_hidden), its upper square drawn: the same pixels as drawing the file's order */
static void test_hidden_triangles(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 100 || CM_VIEW_MAX_H < 100 || CM_MAX_FACES < 2)
        skip();
    cm_view_opts o = square_opts(100, CM_VIEW_FRONT, 0);
    const float ny[3] = {0, -1, 0}, tilted[3] = {0, -0.7071068f, 0.7071068f}, lo[3] = {0, -0.5f, 0}, hi[3] = {1, 0.5f, 1};
    const float lower[4][3] = {{0.25f, 0, 0.1f}, {0.75f, 0, 0.1f}, {0.75f, 0, 0.4f}, {0.25f, 0, 0.4f}};
    const float upper[4][3] = {{0.25f, 0, 0.6f}, {0.75f, 0, 0.6f}, {0.75f, 0, 0.9f}, {0.25f, 0, 0.9f}};
    const float back[4][3] = {{0, -0.5f, 0}, {1, -0.5f, 0}, {1, 0.5f, 1}, {0, 0.5f, 1}};
    for (int fit = 0; fit < 2; fit++) {
        cm_mesh m = mesh_storage();
        add_quad(&m, lower, ny, 0x2060a0u, 1);
        add_quad(&m, upper, ny, 0x2060a0u, 1);
        m.nfaces--; /* (the two squares one face: their vertices and indices follow each other) */
        m.faces[0].nverts += 4, m.faces[0].nindex += 6;
        add_quad(&m, back, tilted, 0x808080u, 1);
        assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
        if (fit)
            cm_view_fit(&view, &m, NULL, 0);
        assert_int_equal(view.boxes_nfaces, fit ? 2 : 0);
        cm_view_mesh(&view, &m);
        assert_int_equal(view.hidden_faces, 0);
        assert_int_equal(view.hidden_triangles, fit ? 2 : 0);
        assert_int_equal(view.triangles, fit ? 4 : 6);
        if (!fit)
            memcpy(b_frame[0], view.rgb, sizeof b_frame[0]);
        else
            assert_memory_equal(view.rgb, b_frame[0], sizeof b_frame[0]);
    }
}

/* a sliver along the frame's diagonal, half a pixel across, its third corner behind the first
   two: every pixel it writes lies within its corners' depths (each span's depth is made from its
   first pixel's own weights: face_hidden counts on it) */
static void test_sliver_depth(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 100 || CM_VIEW_MAX_H < 100)
        skip();
    cm_view_opts o = square_opts(100, CM_VIEW_FRONT, 0);
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, ny[3] = {0, -1, 0};
    cm_mesh m = mesh_storage();
    cm_mesh_face *f = &m.faces[m.nfaces++];
    memset(f, 0, sizeof *f);
    const float p[3][3] = {{0.0f, 0.3f, 0.003f}, {1.0f, 0.3f, 1.003f}, {0.0057f, 0.9f, 0.003f}};
    for (int i = 0; i < 3; i++) {
        memcpy(m.pos[i], p[i], sizeof p[i]);
        memcpy(m.nrm[i], ny, sizeof ny);
        m.idx[i] = (uint32_t)i;
    }
    m.nverts = m.nindex = f->nverts = f->nindex = 3;
    assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
    cm_view_mesh(&view, &m);
    assert_true(view.triangles == 1);
    /* (view depth: the model's y less the box's centre, 0.5) */
    size_t written = 0;
    for (size_t i = 0; i < 100 * 100; i++)
        if (view.depth[i] < 1.0e30f) {
            written++;
            assert_true(view.depth[i] >= -0.2f - 1e-6f && view.depth[i] <= 0.4f + 1e-6f);
        }
    assert_true(written > 20);
}

/* a curved edge (a quadratic arc) placed three times: moved up, moved down (as many points as the
   first copy: its points reused, cm_view_edges) and three times the size (more points: evaluated
   again); the frame with all three is the union of three frames of one copy each (an edge pixel is
   the edges' colour, whichever copy draws it) */
static cm_model g_arc;
static void arc_model(int only)
{
    static const double P[3][3] = {{0, 0, 0}, {0.5, 0, 0.6}, {1, 0, 0}};
    static const double M[3][12] = {{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0.3},
                                    {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, -0.3},
                                    {3, 0, 0, -1, 0, 3, 0, 0, 0, 0, 3, -1}};
    memset(&g_arc, 0, sizeof g_arc);
    cm_edge *E = &g_arc.edges[0];
    E->p = 2, E->nctrl = 3, E->ctrl0 = 0, E->knot0 = 0, E->v0 = -1, E->v1 = -1;
    for (int i = 0; i < 3; i++)
        g_arc.ctrl[i] = cm_v3(P[i][0], P[i][1], P[i][2]);
    for (int i = 0; i < 6; i++)
        g_arc.knots[i] = i < 3 ? 0.0 : 1.0;
    /* (the edge's face is 1, beyond the model's own range [0, 1): only its copies are drawn) */
    g_arc.edge_face[0][0] = 1, g_arc.edge_face[0][1] = CM_NO_FACE;
    g_arc.nedges = 1;
    g_arc.nfaces = 1;
    for (int k = 0; k < 3; k++)
        if (only < 0 || only == k) {
            cm_placement *pl = &g_arc.placements[g_arc.nplacements++];
            pl->first = 1, pl->count = 1;
            memcpy(pl->m, M[k], sizeof M[k]);
        }
}

static void test_edge_copies(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 100 || CM_VIEW_MAX_H < 100 || CM_MAX_EDGES < 1 || CM_MAX_MODEL_CTRL < 3 ||
        CM_MAX_MODEL_KNOTS < 6 || CM_MAX_PLACEMENTS < 3)
        skip();
    cm_view_opts o = square_opts(100, CM_VIEW_FRONT, 1);
    const float lo[3] = {-1, 0, -1}, hi[3] = {2, 0, 2};
    static uint8_t one[3][100 * 100 * 3];
    uint64_t lines = 0;
    for (int only = 0; only < 3; only++) {
        arc_model(only);
        assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
        cm_view_edges(&view, &g_arc);
        assert_true(view.edge_segments >= 4); /* (a curve in several pieces) */
        lines += view.edge_segments;
        memcpy(one[only], view.rgb, sizeof one[only]);
    }
    arc_model(-1);
    assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
    cm_view_edges(&view, &g_arc);
    assert_int_equal(view.edge_segments, lines);
    for (size_t i = 0; i < 100 * 100 * 3; i++) {
        uint8_t bg = (uint8_t)(o.background >> (16 - 8 * (i % 3)));
        uint8_t want = one[0][i] != bg ? one[0][i] : (one[1][i] != bg ? one[1][i] : one[2][i]);
        assert_int_equal(view.rgb[i], want);
    }
}

/* edges of one span (Bezier curves: the viewer sums their Bernstein polynomials, not the B-spline
   basis): a rational quadratic quarter circle and a degree-7 curve, drawn from the front.  Every
   edge pixel lies within a pixel and a half of the curve (the kernels' cm_curve_eval, densely), and
   every point of the curve has an edge pixel that near: a wrong weight (a parabola for the circle)
   or a wrong binomial moves the lines by several pixels */
static cm_model g_bez;
static void test_bezier_edges(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 100 || CM_VIEW_MAX_H < 100 || CM_MAX_EDGES < 2 || CM_MAX_MODEL_CTRL < 11 ||
        CM_MAX_MODEL_KNOTS < 22 || CM_MAX_DEGREE < 7)
        skip();
    memset(&g_bez, 0, sizeof g_bez);
    static const double arc[3][3] = {{0.9, 0, 0.1}, {0.9, 0, 0.9}, {0.1, 0, 0.9}};
    static const double seven[8][3] = {{0.05, 0, 0.05}, {0.3, 0, 0.7}, {0.1, 0, 0.95}, {0.6, 0, 0.2},
                                       {0.9, 0, 0.5},   {0.5, 0, 0.9}, {0.95, 0, 0.9}, {0.7, 0, 0.05}};
    for (int i = 0; i < 3; i++) {
        g_bez.ctrl[i] = cm_v3(arc[i][0], arc[i][1], arc[i][2]);
        g_bez.w[i] = i == 1 ? sqrt(0.5) : 1.0;
    }
    for (int i = 0; i < 8; i++)
        g_bez.ctrl[3 + i] = cm_v3(seven[i][0], seven[i][1], seven[i][2]);
    for (int i = 0; i < 6; i++)
        g_bez.knots[i] = i < 3 ? 0.0 : 1.0;
    for (int i = 0; i < 16; i++)
        g_bez.knots[6 + i] = i < 8 ? 0.0 : 1.0;
    cm_edge *A = &g_bez.edges[0], *B = &g_bez.edges[1];
    A->p = 2, A->nctrl = 3, A->ctrl0 = 0, A->knot0 = 0, A->rational = 1, A->v0 = A->v1 = -1;
    B->p = 7, B->nctrl = 8, B->ctrl0 = 3, B->knot0 = 6, B->v0 = B->v1 = -1;
    for (int e = 0; e < 2; e++)
        g_bez.edge_face[e][0] = 0, g_bez.edge_face[e][1] = CM_NO_FACE;
    g_bez.nedges = 2;
    g_bez.nfaces = 1;
    cm_view_opts o = square_opts(100, CM_VIEW_FRONT, 1);
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 0, 1};
    assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
    cm_view_edges(&view, &g_bez);
    /* the curves densely on the screen (to_screen's orthographic arithmetic) */
    enum { DENSE = 2000 };
    static double sx[2][DENSE + 1], sy[2][DENSE + 1];
    for (int e = 0; e < 2; e++) {
        cm_curve c;
        cm_model_edge_curve(&g_bez, (uint32_t)e, &c);
        for (int k = 0; k <= DENSE; k++) {
            cm_vec3 d[CM_MAX_DERS + 1];
            assert_ok(cm_curve_eval(&c, (double)k / DENSE, 0, d, NULL));
            const double q[3] = {d[0].x - view.c[0], d[0].y - view.c[1], d[0].z - view.c[2]};
            sx[e][k] = 50.0 + view.scale * (q[0] * view.r[0] + q[1] * view.r[1] + q[2] * view.r[2]);
            sy[e][k] = 50.0 - view.scale * (q[0] * view.u[0] + q[1] * view.u[1] + q[2] * view.u[2]);
        }
    }
    int pixels = 0;
    for (int y = 0; y < 100; y++)
        for (int x = 0; x < 100; x++) {
            if (view.rgb[3 * (y * 100 + x)] == (uint8_t)(o.background >> 16))
                continue;
            pixels++;
            double best = 1e300;
            for (int e = 0; e < 2; e++)
                for (int k = 0; k <= DENSE; k++) {
                    double dx = sx[e][k] - (x + 0.5), dy = sy[e][k] - (y + 0.5);
                    best = dx * dx + dy * dy < best ? dx * dx + dy * dy : best;
                }
            assert_true(best <= 1.5 * 1.5);
        }
    assert_true(pixels > 100);
    for (int e = 0; e < 2; e++)
        for (int k = 0; k <= DENSE; k += 10) {
            int near = 0;
            for (int y = (int)sy[e][k] - 2; y <= (int)sy[e][k] + 2; y++)
                for (int x = (int)sx[e][k] - 2; x <= (int)sx[e][k] + 2; x++) {
                    double dx = sx[e][k] - (x + 0.5), dy = sy[e][k] - (y + 0.5);
                    near = near || (x >= 0 && y >= 0 && x < 100 && y < 100 && dx * dx + dy * dy <= 1.5 * 1.5 &&
                                    view.rgb[3 * (y * 100 + x)] != (uint8_t)(o.background >> 16));
                }
            assert_true(near);
        }
}

static void test_refuses_large_frame(void **state)
{
    (void)state;
    cm_view_opts o;
    cm_view_opts_default(&o);
    o.width = CM_VIEW_MAX_W + 1;
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    cm_status st;
    cm_status_init(&st);
    assert_int_equal(cm_view_begin(&view, &o, lo, hi, &st), CM_E_LIMIT);
    assert_non_null(strstr(st.where, "CM_VIEW_MAX_W"));
    assert_int_equal(st.have, (uint64_t)CM_VIEW_MAX_W * CM_VIEW_MAX_H);
    o.width = 10;
    o.height = 0;
    assert_int_equal(cm_view_begin(&view, &o, lo, hi, NULL), CM_E_ARG);
    const float bad[3] = {0, NAN, 0};
    o.height = 10;
    assert_int_equal(cm_view_begin(&view, &o, lo, bad, NULL), CM_E_ARG);
}

static void test_dir_names(void **state)
{
    (void)state;
    for (int d = 0; d < CM_VIEW_DIR_COUNT; d++)
        assert_int_equal(cm_view_dir_parse(cm_view_dir_name((cm_view_dir)d)), d);
    assert_int_equal(cm_view_dir_parse("sideways"), -1);
}

/* the status line: a dark bar over the frame's last 11 rows (scale 1 below 300 rows), the text's
   glyphs from the third column and row in it, the rows above untouched */
static void test_status_line(void **state)
{
    (void)state;
    if (CM_VIEW_MAX_W < 100 || CM_VIEW_MAX_H < 50)
        skip();
    cm_view_opts o;
    cm_view_opts_default(&o);
    o.width = 100;
    o.height = 50;
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
    cm_view_status(&view, "A\x01");
    assert_int_equal(cm_view_status_height(&view), 11);
    int y0 = 50 - 11;
    size_t above = (size_t)(y0 - 1) * 100 + 50, bar = (size_t)(y0 + 1) * 100 + 50;
    assert_int_equal(view.rgb[3 * above], 0xff); /* background */
    assert_int_equal(view.rgb[3 * bar], 0x26);   /* the bar */
    /* 'A''s first row " ### ": columns 1-3 of its cell at x = 2, row y0 + 2 */
    for (int x = 0; x < 8; x++) {
        size_t at = (size_t)(y0 + 2) * 100 + (size_t)x;
        int lit = x >= 3 && x <= 5;
        assert_int_equal(view.rgb[3 * at], lit ? 0xf2 : 0x26);
    }
    /* a character outside ASCII shows as '?' (its top row " ### " too, in the next cell, x = 8) */
    size_t q = (size_t)(y0 + 2) * 100 + 9;
    assert_int_equal(view.rgb[3 * q], 0xf2);
}

/* ---- PNG ---- */

static uint8_t g_png[1 << 18];
static size_t g_png_n;

static int put_mem(void *ctx, const uint8_t *p, size_t n)
{
    (void)ctx;
    if (g_png_n + n > sizeof g_png)
        return -1;
    memcpy(g_png + g_png_n, p, n);
    g_png_n += n;
    return 0;
}

static int put_fail(void *ctx, const uint8_t *p, size_t n)
{
    (void)ctx, (void)p, (void)n;
    return -1;
}

static uint32_t be32(const uint8_t *p) { return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]; }

/* walk the PNG: chunks and CRCs, IHDR, the zlib stream's stored blocks into raw[], Adler-32 */
static void check_png(const uint8_t *rgb, uint32_t w, uint32_t h)
{
    static uint8_t raw[1 << 18], z[1 << 18];
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    assert_int_equal(g_png_n, cm_png_size(w, h));
    assert_memory_equal(g_png, sig, 8);
    size_t at = 8, zn = 0;
    int saw_end = 0;
    while (at < g_png_n) {
        uint32_t len = be32(g_png + at);
        assert_true(at + 12 + len <= g_png_n);
        const uint8_t *type = g_png + at + 4, *data = type + 4;
        assert_int_equal(be32(data + len), cm_crc32(type, 4 + (size_t)len));
        if (memcmp(type, "IHDR", 4) == 0) {
            assert_int_equal(len, 13);
            assert_int_equal(be32(data), w);
            assert_int_equal(be32(data + 4), h);
            assert_int_equal(data[8], 8);
            assert_int_equal(data[9], 2);
        } else if (memcmp(type, "IDAT", 4) == 0) {
            memcpy(z + zn, data, len);
            zn += len;
        } else if (memcmp(type, "IEND", 4) == 0) {
            saw_end = 1;
        }
        at += 12 + len;
    }
    assert_true(saw_end);
    /* zlib: header, stored blocks, Adler-32 */
    assert_int_equal((z[0] * 256 + z[1]) % 31, 0);
    size_t zi = 2, rn = 0;
    for (int last = 0; !last;) {
        last = z[zi] & 1;
        assert_int_equal(z[zi] >> 1, 0); /* stored */
        uint32_t len = (uint32_t)z[zi + 1] | (uint32_t)z[zi + 2] << 8;
        uint32_t nlen = (uint32_t)z[zi + 3] | (uint32_t)z[zi + 4] << 8;
        assert_int_equal(len ^ 0xffffu, nlen);
        memcpy(raw + rn, z + zi + 5, len);
        rn += len;
        zi += 5 + len;
    }
    uint32_t a = 1, b = 0;
    for (size_t i = 0; i < rn; i++) {
        a = (a + raw[i]) % 65521u;
        b = (b + a) % 65521u;
    }
    assert_int_equal(be32(z + zi), (b << 16) | a);
    assert_int_equal(zi + 4, zn);
    assert_int_equal(rn, (size_t)h * (1 + 3 * (size_t)w));
    for (uint32_t y = 0; y < h; y++) {
        assert_int_equal(raw[y * (1 + 3 * w)], 0); /* filter: none */
        assert_memory_equal(raw + y * (1 + 3 * w) + 1, rgb + (size_t)y * 3 * w, 3 * (size_t)w);
    }
}

static void test_png(void **state)
{
    (void)state;
    static uint8_t rgb[3 * 200 * 120];
    uint32_t sizes[][2] = {{1, 1}, {3, 2}, {200, 120}}; /* the last: 72 120 raw bytes, two stored blocks */
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        uint32_t w = sizes[k][0], h = sizes[k][1];
        for (size_t i = 0; i < 3 * (size_t)w * h; i++)
            rgb[i] = (uint8_t)(i * 7 + k);
        g_png_n = 0;
        assert_ok(cm_png_write(rgb, w, h, put_mem, NULL, NULL));
        check_png(rgb, w, h);
    }
    cm_status st;
    cm_status_init(&st);
    assert_int_equal(cm_png_write(rgb, 4, 4, put_fail, NULL, &st), CM_E_IO);
    assert_int_equal(cm_png_write(rgb, 0, 4, put_mem, NULL, NULL), CM_E_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_front_box),   cmocka_unit_test(test_depth_order), cmocka_unit_test(test_refuses_large_frame),
        cmocka_unit_test(test_dir_names),   cmocka_unit_test(test_turn), cmocka_unit_test(test_silhouette),   cmocka_unit_test(test_png),         cmocka_unit_test(test_status_line),
        cmocka_unit_test(test_fill_rule),   cmocka_unit_test(test_back_faces), cmocka_unit_test(test_large_face),
        cmocka_unit_test(test_small_triangles), cmocka_unit_test(test_touching_solids),
        cmocka_unit_test(test_back_edges), cmocka_unit_test(test_hidden_faces), cmocka_unit_test(test_hidden_triangles),
        cmocka_unit_test(test_sliver_depth), cmocka_unit_test(test_edge_copies), cmocka_unit_test(test_bezier_edges), cmocka_unit_test(test_fit_from_boxes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
