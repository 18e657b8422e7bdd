/* cm_view.c - the software viewer: z-buffered triangles and the curve mesh's edges (see cm_view.h). */
#include "cm/cm_view.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "cm/cm_bspline.h"

/* the default face colour (no colour in the model): a light steel grey-blue */
#define VIEW_DEFAULT_RGB 0x9fb0c2u
/* the status line: light text on a dark bar */
#define VIEW_STATUS_BG_RGB 0x262a30u
#define VIEW_STATUS_RGB 0xf2f2f2u
/* assembly steps: the part of the step */
#define VIEW_HIGHLIGHT_RGB 0xe8742au
/* the rasteriser's fixed point (see fill_triangle): 1/VIEW_SUBPIX of a pixel; a triangle with a
   corner VIEW_COORD_MAX pixels or more off the frame's corner is not filled, so that its edge
   functions fit 64 bits (2^28 units each way; a fitted camera keeps every corner near the frame) */
#define VIEW_SUBPIX 256
/* a triangle whose box holds at most this many pixel centres has each tested on its own */
#define VIEW_SMALL_BOX 16
/* a pixel's depth is a mix of its triangle's corners' in double, then a float: within this share of
   the model's diagonal of them (the coarse depth's tests, face_hidden and triangle_hidden) */
#define VIEW_DEPTH_ROUND 1e-5
/* at most this many triangles drawn untested after a visible one (triangle_hidden) */
#define VIEW_TEST_WAIT 32
/* cm_view.face_closed: closed at edges it shares with other parts, outwards still to be measured */
#define VIEW_CLOSED_SHARED 2
/* cm_view_vert.flags */
#define VIEW_VERT_OK 1u
#define VIEW_VERT_AWAY 2u
#define VIEW_COORD_MAX 1048576.0
/* brightness across a row in 8.24 fixed point (at most 1: ambient, head and fill light add to 1) */
#define VIEW_LIGHT_ONE 16777216.0
/* the brightest a pixel gets: 1 (the lights' sum, full colour), and room for a slope's rounding
   along a row (2^-9: 255 x it still rounds to 255, so a channel needs no clamp; put_lit) */
#define VIEW_LIGHT_MAX 16809984
/* a curved edge is drawn in straight pieces of about this many pixels */
#define VIEW_EDGE_PIECE_PX 6.0
/* edges are drawn this many pixels' worth of depth in front of the faces */
#define VIEW_EDGE_BIAS_PX 2.0
/* the edges' colour: near black */
#define VIEW_EDGE_RGB 0x1a1a1au
/* light: ambient share, the head light's and the fill light's */
#define VIEW_AMBIENT 0.22
#define VIEW_HEAD 0.62
#define VIEW_FILL 0.16
/* margin left round the fitted box, as a share of the frame's smaller side */
#define VIEW_MARGIN 0.06
/* perspective: tan of half the 30 degree field of view, as a constant (no libm tan: the same bits
   everywhere) */
#define VIEW_TAN_HALF_FOV 0.2679491924311227

static const char *const dir_names[CM_VIEW_DIR_COUNT] = {"iso", "front", "back", "left", "right", "top", "bottom"};

const char *cm_view_dir_name(cm_view_dir d)
{
    return (unsigned)d < CM_VIEW_DIR_COUNT ? dir_names[d] : "?";
}

/* the same string (the decoder library calls no strcmp: check-noheap's allowlist) */
static int same_name(const char *a, const char *b)
{
    while (*a && *a == *b)
        a++, b++;
    return *a == *b;
}

int cm_view_dir_parse(const char *name)
{
    for (int d = 0; d < CM_VIEW_DIR_COUNT; d++)
        if (same_name(name, dir_names[d]))
            return d;
    return -1;
}

void cm_view_opts_default(cm_view_opts *o)
{
    o->width = CM_VIEW_MAX_W < 800 ? CM_VIEW_MAX_W : 800;
    o->height = CM_VIEW_MAX_H < 480 ? CM_VIEW_MAX_H : 480;
    o->dir = CM_VIEW_ISO;
    o->perspective = 0;
    o->background = 0xffffffu;
    o->edges = 1;
    o->step = 0;
    o->turn = 0;
}

static void set3(double *a, double x, double y, double z)
{
    a[0] = x;
    a[1] = y;
    a[2] = z;
}

static double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* the camera's right, up and forward (into the screen) for a direction */
static void camera_axes(cm_view *v, cm_view_dir d)
{
    switch (d) {
    case CM_VIEW_FRONT:
        set3(v->r, 1, 0, 0), set3(v->u, 0, 0, 1), set3(v->f, 0, 1, 0);
        break;
    case CM_VIEW_BACK:
        set3(v->r, -1, 0, 0), set3(v->u, 0, 0, 1), set3(v->f, 0, -1, 0);
        break;
    case CM_VIEW_LEFT:
        set3(v->r, 0, -1, 0), set3(v->u, 0, 0, 1), set3(v->f, 1, 0, 0);
        break;
    case CM_VIEW_RIGHT:
        set3(v->r, 0, 1, 0), set3(v->u, 0, 0, 1), set3(v->f, -1, 0, 0);
        break;
    case CM_VIEW_TOP:
        set3(v->r, 1, 0, 0), set3(v->u, 0, 1, 0), set3(v->f, 0, 0, -1);
        break;
    case CM_VIEW_BOTTOM:
        set3(v->r, 1, 0, 0), set3(v->u, 0, -1, 0), set3(v->f, 0, 0, 1);
        break;
    default: { /* iso: f = (-1, 1, -1)/sqrt 3, r = f x z = (1, 1, 0)/sqrt 2, u = r x f = (-1, 1, 2)/sqrt 6 */
        double s2 = sqrt(2.0), s3 = sqrt(3.0), s6 = sqrt(6.0);
        set3(v->r, 1.0 / s2, 1.0 / s2, 0.0);
        set3(v->u, -1.0 / s6, 1.0 / s6, 2.0 / s6);
        set3(v->f, -1.0 / s3, 1.0 / s3, -1.0 / s3);
        break;
    }
    }
}

/* cos and sin of k x 15 degrees, k = 0..6 (a quarter turn), as constants: no libm trig, the same bits
   everywhere */
_Static_assert(CM_VIEW_TURN_DEG == 15, "turn_cos holds steps of 15 degrees");
static const double turn_cos[7] = {1.0,
                                   0.96592582628906829,
                                   0.86602540378443865,
                                   0.70710678118654752,
                                   0.5,
                                   0.25881904510252076,
                                   0.0};

/* the camera's axes turned about Z by -turn steps: the model seems turned by +turn (counter-clockwise
   from above) */
static void camera_turn(cm_view *v, int turn)
{
    int k = turn % CM_VIEW_TURNS;
    if (k < 0)
        k += CM_VIEW_TURNS;
    if (k == 0)
        return;
    /* the angle -k x 15 degrees: its cos and sin from the quarter-turn table by symmetry */
    int q = k / 6, m = k % 6;
    double c = turn_cos[m], s = turn_cos[6 - m]; /* of +m x 15 degrees */
    for (int i = 0; i < q; i++) { /* + a quarter turn each: (c, s) -> (-s, c) */
        double t = c;
        c = -s;
        s = t;
    }
    s = -s; /* the camera turns the other way */
    double *ax[3] = {v->r, v->u, v->f};
    for (int a = 0; a < 3; a++) {
        double x = ax[a][0], y = ax[a][1];
        ax[a][0] = c * x - s * y;
        ax[a][1] = s * x + c * y;
    }
}

/* view space of a point: x right, y up, z depth (into the screen) */
static void to_view(const cm_view *v, double x, double y, double z, double out[3])
{
    double d[3] = {x - v->c[0], y - v->c[1], z - v->c[2]};
    out[0] = dot3(d, v->r);
    out[1] = dot3(d, v->u);
    out[2] = dot3(d, v->f);
}

/* screen position (pixel units, y down, pixel centres at + 0.5) and depth of a view-space point;
   0 when it is behind the eye (perspective) */
static int to_screen(const cm_view *v, const double p[3], double s[3])
{
    double k = v->scale;
    if (v->o.perspective) {
        double ze = p[2] - v->eye;
        if (!(ze > 1e-9 * (-v->eye)))
            return 0;
        k = v->scale / ze;
    }
    s[0] = 0.5 * (double)v->o.width + p[0] * k;
    s[1] = 0.5 * (double)v->o.height - p[1] * k;
    s[2] = p[2];
    return 1;
}

/* half the frame across and down, less the margin: where the fitted model may reach from the centre */
static void frame_room(const cm_view *v, double *room_x, double *room_y)
{
    double w = (double)v->o.width, h = (double)v->o.height, side = w < h ? w : h;
    double rx = 0.5 * w - VIEW_MARGIN * side, ry = 0.5 * h - VIEW_MARGIN * side;
    *room_x = rx > 0.5 ? rx : 0.5;
    *room_y = ry > 0.5 ? ry : 0.5;
}

cm_err cm_view_begin(cm_view *v, const cm_view_opts *o, const float lo[3], const float hi[3], cm_status *st)
{
    if (o->width > CM_VIEW_MAX_W || o->height > CM_VIEW_MAX_H) {
        if (st && st->code == CM_OK) {
            st->need = (uint64_t)o->width * (uint64_t)o->height;
            st->have = (uint64_t)CM_VIEW_MAX_W * (uint64_t)CM_VIEW_MAX_H;
        }
        return cm_fail(st, CM_E_LIMIT, "view: a frame larger than this build's (CM_VIEW_MAX_W x CM_VIEW_MAX_H)");
    }
    if (o->width < 1 || o->height < 1 || (unsigned)o->dir >= CM_VIEW_DIR_COUNT)
        return cm_fail(st, CM_E_ARG, "view: size or direction");
    for (int i = 0; i < 3; i++)
        if (!isfinite(lo[i]) || !isfinite(hi[i]) || !(lo[i] <= hi[i]))
            return cm_fail(st, CM_E_ARG, "view: the model's box");
    v->o = *o;
    v->triangles = v->edge_segments = v->silhouette_segments = v->hidden_faces = v->hidden_triangles = 0;
    v->tiles_live = 0;
    v->nparts = v->nbase_parts = 0;
    v->boxes_nfaces = 0; /* (until cm_view_fit boxes this frame's faces) */
    v->named_parts = 0;
    camera_axes(v, o->dir);
    camera_turn(v, o->turn);
    for (int i = 0; i < 3; i++)
        v->c[i] = 0.5 * ((double)lo[i] + (double)hi[i]);
    /* the box's corners in view space: their extent across the screen and in depth */
    double ex = 0.0, ey = 0.0, diag2 = 0.0;
    for (int k = 0; k < 8; k++) {
        double p[3];
        to_view(v, (double)((k & 1) ? hi[0] : lo[0]), (double)((k & 2) ? hi[1] : lo[1]),
                (double)((k & 4) ? hi[2] : lo[2]), p);
        ex = fabs(p[0]) > ex ? fabs(p[0]) : ex;
        ey = fabs(p[1]) > ey ? fabs(p[1]) : ey;
        diag2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] > diag2 ? p[0] * p[0] + p[1] * p[1] + p[2] * p[2] : diag2;
    }
    double room_x, room_y;
    frame_room(v, &room_x, &room_y);
    double radius = sqrt(diag2);
    v->diag = 2.0 * radius;
    if (!(radius > 0.0))
        radius = 1.0; /* a point: any scale shows it */
    if (!o->perspective) {
        double sx = ex > 0.0 ? room_x / ex : 1e300, sy = ey > 0.0 ? room_y / ey : 1e300;
        v->scale = sx < sy ? sx : sy;
        if (!(v->scale < 1e300))
            v->scale = (room_x < room_y ? room_x : room_y) / radius;
        v->eye = 0.0;
    } else {
        /* the eye on the axis, far enough that the box's bounding sphere fits the field of view */
        double room = room_x < room_y ? room_x : room_y;
        double dist = radius / VIEW_TAN_HALF_FOV * 1.05 + radius;
        v->eye = -dist;
        v->scale = room / VIEW_TAN_HALF_FOV; /* a point at x = tan(fov/2) z lands on the room's edge */
    }
    /* the first row pixel by pixel, the others copies of it (a fill of the whole frame was a
       thirtieth of a large model's frame); the depth as far as a float goes */
    size_t w = (size_t)o->width;
    for (size_t i = 0; i < w; i++) {
        v->rgb[3 * i] = (uint8_t)(o->background >> 16);
        v->rgb[3 * i + 1] = (uint8_t)(o->background >> 8);
        v->rgb[3 * i + 2] = (uint8_t)o->background;
        v->depth[i] = 3.0e38f;
    }
    for (size_t y = 1; y < (size_t)o->height; y++) {
        memcpy(&v->rgb[3 * w * y], v->rgb, 3 * w);
        memcpy(&v->depth[w * y], v->depth, w * sizeof v->depth[0]);
    }
    return CM_OK;
}

/* a box's coordinate as a float, within the floats' range (beyond it the conversion is undefined;
   an empty face's 1e300 stays as far) */
static float box_float(double x)
{
    return x < 3.0e38 ? (x > -3.0e38 ? (float)x : -3.0e38f) : 3.0e38f;
}

/* the outline (across and up, before the fit's centring) and nearest depth of vertices
   [v0, v0 + nv) seen from the camera: out = {x low, x high, y low, y high, depth low} (1e300 and
   -1e300: none); the vertices read back a run at a time (one at a time was a twentieth of a large
   model's frame) */
static void outline_of(cm_view *v, const cm_mesh *mesh, uint32_t v0, uint32_t nv, double out[5])
{
    double fxlo = 1e300, fxhi = -1e300, fylo = 1e300, fyhi = -1e300, fz = 1e300;
    /* (x and y as a pair, as vertex_screen_in: the same bits as dot3's) */
    const view_pair r_u[3] = {{v->r[0], v->u[0]}, {v->r[1], v->u[1]}, {v->r[2], v->u[2]}};
    for (uint32_t i0 = 0; i0 < nv; i0 += CM_VIEW_READ_RUN) {
        uint32_t n = nv - i0 < CM_VIEW_READ_RUN ? nv - i0 : CM_VIEW_READ_RUN;
        const float(*pos)[3] = cm_mesh_vecs_at(mesh, CM_SPILL_POS, v0 + i0, n, v->run_pos);
        for (uint32_t i = 0; i < n; i++) {
            double d[3] = {(double)pos[i][0] - v->c[0], (double)pos[i][1] - v->c[1], (double)pos[i][2] - v->c[2]};
            const view_pair XY =
                (view_pair){d[0], d[0]} * r_u[0] + (view_pair){d[1], d[1]} * r_u[1] + (view_pair){d[2], d[2]} * r_u[2];
            double x = XY[0], y = XY[1], z = dot3(d, v->f);
            fxlo = x < fxlo ? x : fxlo;
            fxhi = x > fxhi ? x : fxhi;
            fylo = y < fylo ? y : fylo;
            fyhi = y > fyhi ? y : fyhi;
            fz = z < fz ? z : fz;
        }
    }
    out[0] = fxlo, out[1] = fxhi, out[2] = fylo, out[3] = fyhi, out[4] = fz;
}

/* the same bounds for every vertex within a model-space box b (cm_mesh_face_boxes): its centre
   seen from the camera, plus and minus its half sides' reach along each axis, widened by far more
   than the roundings of outline_of's sums (a billionth of the sizes: a box of a few vertices must
   hold theirs); an empty box gives none, one holding a NaN not-a-numbers (its face is measured).
   (This and measure out of line: each called from two loops, inlined they cost 1.5 KB of the
   budgeted aarch64 text, loops unswitched and copied) */
static __attribute__((noinline)) void outline_within(const cm_view *v, const float b[6], double out[5])
{
    if (b[0] > b[3] || b[1] > b[4] || b[2] > b[5]) {
        out[0] = out[2] = out[4] = 1e300, out[1] = out[3] = -1e300;
        return;
    }
    double d[3], h[3], size = 0.0;
    for (int k = 0; k < 3; k++) {
        d[k] = 0.5 * ((double)b[k] + (double)b[3 + k]) - v->c[k];
        h[k] = 0.5 * ((double)b[3 + k] - (double)b[k]);
        size += fabs(d[k]) + h[k];
    }
    const double *axis[3] = {v->r, v->u, v->f};
    for (int a = 0; a < 3; a++) {
        const double *x = axis[a], at = dot3(d, x);
        const double reach = fabs(x[0]) * h[0] + fabs(x[1]) * h[1] + fabs(x[2]) * h[2] + 1e-9 * size;
        out[2 * a] = at - reach;
        if (a < 2)
            out[2 * a + 1] = at + reach;
    }
}

/* face f's outline kept for cm_view_mesh's order and skipping */
static void keep_face_box(cm_view *v, uint32_t f, const double o[5])
{
    for (int k = 0; k < 4; k++)
        v->face_box[f][k] = box_float(o[k]);
    v->face_near[f] = o[4];
}

/* face f's vertices (UINT32_MAX: the whole mesh's) projected: its outline kept, and added to all (x
   low, high, y low, high: 1e300 and -1e300 before any) */
static __attribute__((noinline)) void measure(cm_view *v, const cm_mesh *mesh, uint32_t f, double all[4])
{
    double o[5];
    const int whole = f == UINT32_MAX;
    outline_of(v, mesh, whole ? 0 : mesh->faces[f].first_vert, whole ? mesh->nverts : mesh->faces[f].nverts, o);
    if (!whole)
        keep_face_box(v, f, o);
    if (!(o[0] <= o[1])) /* (no vertices) */
        return;
    all[0] = o[0] < all[0] ? o[0] : all[0];
    all[1] = o[1] > all[1] ? o[1] : all[1];
    all[2] = o[2] < all[2] ? o[2] : all[2];
    all[3] = o[3] > all[3] ? o[3] : all[3];
}

void cm_view_fit(cm_view *v, const cm_mesh *mesh, const float (*box)[6], uint32_t nboxed)
{
    v->boxes_nfaces = 0;
    if (v->o.perspective || mesh->nverts == 0)
        return;
    /* the outline across and up the screen, face by face (each face's box and nearest depth kept
       for cm_view_mesh's order), where the faces hold every vertex once; else vertex by vertex */
    const uint32_t nf = cm_mesh_faces_in_order(mesh, CM_MAX_FACES);
    /* with the faces' model-space boxes: each one's bound on the screen kept for the order and the
       skipping, and only the faces whose bound reaches past the outline of those measured so far
       (the four reaching farthest first) have their vertices projected: the same outline as from
       every vertex, in a large model's frame a few faces' vertices (each vertex projected twice
       was a twentieth of asmo's frame) */
    double all[4] = {1e300, -1e300, 1e300, -1e300};
    if (nf && box && nboxed == nf) {
        uint32_t reach[4] = {0, 0, 0, 0};
        double best[4] = {1e300, -1e300, 1e300, -1e300}, o[5];
        for (uint32_t f = 0; f < nf; f++) {
            outline_within(v, box[f], o);
            keep_face_box(v, f, o);
            for (int k = 0; k < 4; k++)
                if ((k & 1) ? o[k] > best[k] : o[k] < best[k])
                    best[k] = o[k], reach[k] = f;
        }
        for (int k = 0; k < 4; k++)
            if ((k < 1 || reach[k] != reach[0]) && (k < 2 || reach[k] != reach[1]) && (k < 3 || reach[k] != reach[2]))
                measure(v, mesh, reach[k], all);
        for (uint32_t f = 0; f < nf; f++) {
            if (f == reach[0] || f == reach[1] || f == reach[2] || f == reach[3] || mesh->faces[f].nverts == 0)
                continue;
            outline_within(v, box[f], o);
            if (!(o[0] >= all[0] && o[1] <= all[1] && o[2] >= all[2] && o[3] <= all[3])) /* (not a number: measured) */
                measure(v, mesh, f, all);
        }
    } else {
        for (uint32_t f = 0; f < (nf ? nf : 1); f++)
            measure(v, mesh, nf ? f : UINT32_MAX, all);
    }
    if (!(all[0] <= all[1])) /* (no vertices) */
        all[0] = all[1] = all[2] = all[3] = 0.0;
    v->boxes_nfaces = nf;
    double xlo = all[0], xhi = all[1], ylo = all[2], yhi = all[3];
    double mx = 0.5 * (xlo + xhi), my = 0.5 * (ylo + yhi);
    for (int k = 0; k < 3; k++)
        v->c[k] += mx * v->r[k] + my * v->u[k];
    v->fit_x = mx, v->fit_y = my;
    double room_x, room_y;
    frame_room(v, &room_x, &room_y);
    double ex = 0.5 * (xhi - xlo), ey = 0.5 * (yhi - ylo);
    double sx = ex > 0.0 ? room_x / ex : 1e300, sy = ey > 0.0 ? room_y / ey : 1e300;
    double s = sx < sy ? sx : sy;
    if (s < 1e300 && s > 0.0)
        v->scale = s;
}

/* the root of face f's set (path halving: no recursion) */
static uint32_t find_root(uint32_t *up, uint32_t f)
{
    while (up[f] != f) {
        up[f] = up[up[f]];
        f = up[f];
    }
    return f;
}

/* uses of one edge beyond which the viewer pairs none of them (a hostile file's edge of thousands of
   uses would cost their square) */
#define VIEW_MAX_PAIRED_USES 64

/* the use of edge e nearest to use u in file order (by face, then the lower face) that runs the edge
   the other way; -1 if none does */
static int32_t nearest_other(const cm_view *v, const cm_model *m, uint32_t e, int32_t u)
{
    uint32_t fu = v->use_face[u], bd = UINT32_MAX, bf = 0;
    int32_t best = -1;
    for (int32_t w = v->edge_head[e]; w >= 0; w = v->use_next[w]) {
        uint32_t fw = v->use_face[w];
        if (w == u || m->uses[w].rev == m->uses[u].rev)
            continue;
        uint32_t d = fw > fu ? fw - fu : fu - fw;
        if (d < bd || (d == bd && fw < bf)) {
            bd = d;
            bf = fw;
            best = w;
        }
    }
    return best;
}

/* (once a frame, not per triangle: built for size, as the status line is; 608 bytes of cmz-view's
   aarch64 text for 12 k more instructions in asmo's frame of 51 M.  Not cm_view_begin: its clearing
   of the frame, cold, cost 2.4 M) */
CM_ONCE_PER_FACE uint32_t cm_view_parts(cm_view *v, const cm_model *m)
{
    uint32_t *up = v->part_of_face, nf = m->nfaces < CM_MAX_FACES ? m->nfaces : CM_MAX_FACES;
    uint32_t ne = m->nedges < CM_MAX_EDGES ? m->nedges : CM_MAX_EDGES;
    for (uint32_t f = 0; f < nf; f++)
        up[f] = f;
    for (uint32_t e = 0; e < ne; e++)
        v->edge_head[e] = -1;
    /* each edge's uses in a list (face of each use) */
    int skipped = 0;
    for (uint32_t f = 0; f < nf; f++) {
        const cm_face *F = &m->faces[f];
        for (uint32_t l = 0; l < F->nloops; l++) {
            const cm_loop *L = &m->loops[F->loop0 + l];
            for (uint32_t k = 0; k < L->nuse; k++) {
                uint32_t u = L->use0 + k, e = m->uses[u].edge;
                if (u >= CM_MAX_MODEL_USES || e >= ne) {
                    skipped = 1;
                    continue;
                }
                v->use_face[u] = f;
                v->use_next[u] = v->edge_head[e];
                v->edge_head[e] = (int32_t)u;
            }
        }
    }
    /* an edge of two uses joins its two faces.  Where three or more faces meet (touching parts of a
       flattened assembly: as1_pe_203's 88 such edges would hold its 24 solids together as 3), the
       file does not say which belong together: two uses are joined when each is the other's nearest
       in file order among those running the edge the other way (a solid's faces come one after
       another, and its two faces at an edge run it in opposite directions) */
    for (uint32_t e = 0; e < ne; e++) {
        int n = 0;
        for (int32_t u = v->edge_head[e]; u >= 0 && n <= VIEW_MAX_PAIRED_USES; u = v->use_next[u])
            n++;
        if (n < 2 || n > VIEW_MAX_PAIRED_USES)
            continue;
        for (int32_t u = v->edge_head[e]; u >= 0; u = v->use_next[u]) {
            int32_t w = n == 2 ? (u == v->edge_head[e] ? v->use_next[u] : v->edge_head[e]) : nearest_other(v, m, e, u);
            if (w < 0 || (n > 2 && nearest_other(v, m, e, w) != u))
                continue; /* three or more: only uses that are each other's nearest */
            uint32_t a = find_root(up, v->use_face[u]), b = find_root(up, v->use_face[w]);
            if (a != b) /* the smaller face stays the root: a part is named by its first face */
                up[a > b ? a : b] = a < b ? a : b;
        }
    }
    /* every face to its root first (numbering as it goes would break the sets' paths), then the
       roots in face order get 1, 2, ... and every other face its root's number (a root is its set's
       smallest face: numbered before its faces ask) */
    for (uint32_t f = 0; f < nf; f++)
        up[f] = find_root(up, f);
    uint32_t n = 0;
    for (uint32_t f = 0; f < nf; f++)
        up[f] = up[f] == f ? ++n : up[up[f]];
    v->nbase_parts = n;
    v->nparts = n + m->nplacements;
    /* a part is closed when each edge of its faces is used twice, the two uses running it opposite
       ways: the encoder turned such a part's faces outwards (host_tools/encode/orient.c, by its
       signed volume), so none of its back faces can show (cm_view_mesh skips them); one edge used
       once, or twice the same way, and the part is drawn whole.  At an edge of three or more uses
       (solids touching) each part's own uses must run it as often one way as the other: then each
       is closed, but the encoder measured the touching solids together, and cm_view_mesh measures
       each part (VIEW_CLOSED_SHARED).  (as1_pe_203's 24 solids, drawn whole, were two thirds of its frame.) */
    /* (a piece without edge uses, a mesh's faces without their curve mesh (a GLB), closes nothing) */
    for (uint32_t p = 0; p <= n; p++)
        v->part_closed[p] = 0;
    for (uint32_t f = 0; f < nf; f++)
        if (m->faces[f].nloops > 0)
            v->part_closed[up[f]] = (uint8_t)!skipped;
    for (uint32_t e = 0; e < ne; e++) {
        int32_t first = v->edge_head[e], second = first >= 0 ? v->use_next[first] : -1;
        if (first < 0 || (second >= 0 && v->use_next[second] < 0 && m->uses[first].rev != m->uses[second].rev))
            continue;
        int many = second >= 0 && v->use_next[second] >= 0, n_uses = 0;
        for (int32_t u = first; u >= 0; u = v->use_next[u]) {
            /* (three or more: the part's own uses of the edge run it as often one way as the other) */
            int balance = 0;
            for (int32_t w = first; w >= 0 && many && ++n_uses <= VIEW_MAX_PAIRED_USES * VIEW_MAX_PAIRED_USES;
                 w = v->use_next[w])
                if (up[v->use_face[w]] == up[v->use_face[u]])
                    balance += m->uses[w].rev ? -1 : 1;
            uint8_t *c = &v->part_closed[up[v->use_face[u]]];
            *c = many && n_uses <= VIEW_MAX_PAIRED_USES * VIEW_MAX_PAIRED_USES && balance == 0 && *c ? VIEW_CLOSED_SHARED : 0;
        }
    }
    for (uint32_t f = 0; f < nf; f++) {
        v->face_closed[f] = v->part_closed[up[f]];
        v->piece_of_face[f] = up[f];
        v->face_away[f] = 0; /* (until cm_view_mesh has looked) */
    }
    /* the parts the workstation named (format 4.11: what the CAD system made one, in the order of
       its steps) replace the connected pieces as steps; what is closed stays the pieces' */
    v->named_parts = m->nparts > 0 && nf > 0;
    if (v->named_parts) {
        for (uint32_t f = 0; f < nf; f++)
            up[f] = m->faces[f].part;
        for (uint32_t k = 0; k < m->nplacements && k < CM_MAX_PLACEMENTS; k++)
            v->place_part[k] = m->placements[k].part;
        v->nparts = m->nparts;
    }
    v->parts_nfaces = nf;
    return v->nparts;
}

/* part of placement k's copies */
static uint32_t place_part(const cm_view *v, uint32_t k)
{
    return v->named_parts && k < CM_MAX_PLACEMENTS ? v->place_part[k] : v->nbase_parts + 1u + k;
}

/* part of model face f (1 when the parts were not numbered) */
static uint32_t face_part(const cm_view *v, uint32_t f)
{
    return v->nbase_parts > 0 && f < CM_MAX_FACES ? v->part_of_face[f] : 1;
}

/* how a part shows at the current step: 0 not at all, 1 as it is, 2 highlighted, 3 dimmed */
static int part_look(const cm_view *v, uint32_t part)
{
    if (v->o.step == 0)
        return 1;
    return part > v->o.step ? 0 : (part == v->o.step ? 2 : 3);
}

/* the colour a face is drawn in, for its look */
static uint32_t look_rgb(const cm_view *v, uint32_t rgb, int look)
{
    if (look == 2)
        return VIEW_HIGHLIGHT_RGB;
    if (look != 3)
        return rgb;
    /* dimmed: two thirds of the way to the background */
    uint32_t out = 0;
    for (int sh = 16; sh >= 0; sh -= 8) {
        uint32_t c = (rgb >> sh) & 0xffu, bgc = (v->o.background >> sh) & 0xffu;
        out |= ((c + 2u * bgc) / 3u) << sh;
    }
    return out;
}

/* the head light along the view (towards the viewer: -z), the fill light from the upper left */
static const double view_fill[3] = {-0.40824829046386302, 0.81649658092772603, -0.40824829046386302};

/* brightness of a surface from its unit normal's components along the view (head) and the fill
   light (fill), lit from both sides: within [0, 1] (not a number: 0) */
static double shade(double head, double fill)
{
    double light = VIEW_AMBIENT + VIEW_HEAD * fabs(head) + VIEW_FILL * fabs(fill);
    return light > 0.0 ? (light < 1.0 ? light : 1.0) : 0.0;
}

/* an orthographic camera as five model-space rows (cm_view.ortho): screen x and y in pixels,
   depth, a normal along the view and along the fill light */
static void ortho_rows(cm_view *v)
{
    const double k = v->scale;
    for (int i = 0; i < 3; i++) {
        v->ortho[0][i] = k * v->r[i];
        v->ortho[1][i] = -k * v->u[i];
        v->ortho[2][i] = v->f[i];
        v->ortho[3][i] = v->f[i];
        v->ortho[4][i] = view_fill[0] * v->r[i] + view_fill[1] * v->u[i] + view_fill[2] * v->f[i];
    }
    v->ortho[0][3] = 0.5 * (double)v->o.width - k * dot3(v->c, v->r);
    v->ortho[1][3] = 0.5 * (double)v->o.height + k * dot3(v->c, v->u);
    v->ortho[2][3] = -dot3(v->c, v->f);
    v->ortho[3][3] = v->ortho[4][3] = 0.0;
    for (int i = 0; i < 4; i++) {
        v->ortho_xy[i] = (view_pair){v->ortho[0][i], v->ortho[1][i]};
        v->ortho_zf[i] = (view_pair){v->ortho[2][i], i < 3 ? v->ortho[3][i] : -0.0};
    }
}

/* floor(a / VIEW_SUBPIX) for a > -2^30 (a corner within VIEW_COORD_MAX is 2^28 units off at most):
   a shift of an unsigned value (C leaves >> of a negative one to the compiler), the offset a whole
   number of pixels (and small: the sums' constants fit an instruction) */
#define VIEW_FLOOR_OFFSET ((int64_t)1 << 30)
static int64_t floor_px(int64_t a)
{
    return (int64_t)((uint64_t)(a + VIEW_FLOOR_OFFSET) / VIEW_SUBPIX) - VIEW_FLOOR_OFFSET / VIEW_SUBPIX;
}

/* one side p -> q of a triangle as an edge function E(P) = A (Px - Xp) + B (Py - Yp), in the fixed
   point's units, >= 0 inside (the corners ordered so); bias -1 on all but top and left sides: a
   pixel centre exactly on a side shared by two triangles is filled by one of them, once */
typedef struct view_side {
    int64_t A, B, bias;
} view_side;

static view_side side_fn(int64_t Xp, int64_t Yp, int64_t Xq, int64_t Yq)
{
    view_side e = {Yp - Yq, Xq - Xp, 0};
    /* the inside lies towards (A, B): a left side has it to its right, a top side (level) below */
    e.bias = -(int64_t)(e.A < 0 || (e.A == 0 && e.B <= 0));
    return e;
}

/* brightness in 8.24 fixed point, clamped to [0, VIEW_LIGHT_MAX] (not a number: 0) */
static int64_t light_fx(double l)
{
    double f = l * VIEW_LIGHT_ONE;
    return f > 0.0 ? (f < (double)VIEW_LIGHT_MAX ? (int64_t)(f + 0.5) : VIEW_LIGHT_MAX) : 0;
}

/* a colour 0xRRGGBB as three 21-bit lanes of one integer: each times a brightness in 4.12 fixed
   point (at most VIEW_LIGHT_MAX: below 2^9 x 2^12 / 2^8) stays within its lane */
static uint64_t lanes(uint32_t rgb)
{
    return ((uint64_t)((rgb >> 16) & 0xffu) << 42) | ((uint64_t)((rgb >> 8) & 0xffu) << 21) | (uint64_t)(rgb & 0xffu);
}

/* a pixel in colour base (lanes()) at brightness light (8.24, 0..VIEW_LIGHT_MAX): the three
   channels in one multiplication, each rounded, at most 255 (the brightness at most 1 and a hair) */
static void put_lit(uint8_t *px, uint64_t base, int64_t light)
{
    const uint64_t half = ((uint64_t)1 << 11) * (((uint64_t)1 << 42) | ((uint64_t)1 << 21) | 1u);
    uint64_t c = base * (uint64_t)(light >> 12) + half;
    px[0] = (uint8_t)(c >> 54);
    px[1] = (uint8_t)(c >> 33);
    px[2] = (uint8_t)(c >> 12);
}

/* the coarse depth: pixel (x, y) was written (its tile's farthest may be nearer now) */
static void tile_mark(cm_view *v, int64_t x, int64_t y)
{
    v->tile_writer[(y / CM_VIEW_TILE) * v->tiles_w + x / CM_VIEW_TILE] = v->writer;
}

/* is the triangle of screen corners t, whose pixel centres lie in the box x0..x1, y0..y1, behind
   the farthest pixel of every tile the box touches (cm_view_mesh drawing front to back)?  Then none
   of its pixels would pass the depth test and it is not set up at all: most triangles of an
   assembly's hidden parts and of an open sheet's far side.  A tile written by another face since it
   was last looked at has its farthest found again; one written by this face keeps its bound, loose
   now, never wrong (found again after each of its triangles, it cost more than it saved).
   VIEW_DEPTH_ROUND covers a pixel's depth, a mix of the corners' in double rounded to a float.  Its
   silhouette is still drawn (by the caller). */
static void tile_refresh(cm_view *v, int t);
static int triangle_hidden(cm_view *v, const cm_view_vert *t0, const cm_view_vert *t1, const cm_view_vert *t2, int64_t x0,
                           int64_t y0, int64_t x1, int64_t y1)
{
    double z = t0->z < t1->z ? t0->z : t1->z;
    z = (t2->z < z ? t2->z : z) - VIEW_DEPTH_ROUND * v->diag;
    /* (the box within the frame: not negative) */
    const uint32_t tx0 = (uint32_t)x0 / CM_VIEW_TILE, tx1 = (uint32_t)x1 / CM_VIEW_TILE, ty1 = (uint32_t)y1 / CM_VIEW_TILE;
    for (uint32_t ty = (uint32_t)y0 / CM_VIEW_TILE; ty <= ty1; ty++)
        for (uint32_t tx = tx0; tx <= tx1; tx++) {
            const int tile = (int)(ty * (uint32_t)v->tiles_w + tx);
            if (v->tile_writer[tile] && v->tile_writer[tile] != v->writer)
                tile_refresh(v, tile);
            if (!(z > (double)v->tile_far[tile])) /* (not a number: drawn) */
                return 0;
        }
    return 1;
}

/*
 * Fill the triangle of screen vertices t[3] (their fixed-point corners, depths and brightnesses)
 * in colour rgb.  The corners were rounded to 1/VIEW_SUBPIX of a pixel (vertex_screen_at) and the
 * three edge functions are exact 64-bit integers at the pixel centres, with the top-left rule:
 * shared sides neither crack nor fill twice, and a pixel's coverage is the same on every machine.
 * A triangle covering no pixel centre costs its box.  One whose box holds a few pixel centres
 * (VIEW_SMALL_BOX: most triangles of a finely meshed model) has each tested, and a covered one's
 * depth and brightness made from its weights.  A larger one is drawn in lines along its box's
 * longer side (rows, or columns: a sliver costs its few lines, not its many pixels' worth), each
 * line's span where all three edge functions are >= 0, found exactly by a division per side, depth
 * and brightness stepped along it (doubles, then the brightness in fixed point).
 * (Until 2026-12-07 each pixel's three barycentric weights were doubles with a hair's tolerance,
 * each row's span found by three divisions, and each channel rounded from a double: 3.1 k
 * instructions a triangle on C1G0B0O's frame; that day's first integer filling sent small
 * triangles through the spans' set-up and slivers row by row, and made a pixel's three channels
 * by three multiplications and clamps: 1.5 k.)
 */
static void fill_triangle(cm_view *v, const cm_view_vert *t0, const cm_view_vert *t1, const cm_view_vert *t2, int64_t wmax,
                          int64_t hmax, uint32_t rgb)
{
    /* (the corners in scalars, not arrays indexed by a variable: they stay in registers) */
    int64_t X0 = t0->X, X1 = t1->X, X2 = t2->X, Y0 = t0->Y, Y1 = t1->Y, Y2 = t2->Y;
    /* the pixels whose centres (256 x + 128 in the fixed point) lie in the box, within the frame:
       none, for most triangles of a finely meshed model */
    int64_t xmin = X1 < X0 ? X1 : X0, xmax = X1 > X0 ? X1 : X0, ymin = Y1 < Y0 ? Y1 : Y0, ymax = Y1 > Y0 ? Y1 : Y0;
    xmin = X2 < xmin ? X2 : xmin;
    xmax = X2 > xmax ? X2 : xmax;
    ymin = Y2 < ymin ? Y2 : ymin;
    ymax = Y2 > ymax ? Y2 : ymax;
    const int64_t half = VIEW_SUBPIX / 2;
    int64_t x0 = floor_px(xmin - half + VIEW_SUBPIX - 1), x1 = floor_px(xmax - half);
    int64_t y0 = floor_px(ymin - half + VIEW_SUBPIX - 1), y1 = floor_px(ymax - half);
    x0 = x0 < 0 ? 0 : x0;
    y0 = y0 < 0 ? 0 : y0;
    x1 = x1 > wmax ? wmax : x1;
    y1 = y1 > hmax ? hmax : y1;
    if (x0 > x1 || y0 > y1)
        return;
    if (v->tiles_live) {
        /* (tested again after a visible one only once as many triangles have passed as there were
           visible ones in a row, up to VIEW_TEST_WAIT: a face in plain sight costs a few tests) */
        if (v->tri_wait > 0) {
            v->tri_wait--;
        } else if (triangle_hidden(v, t0, t1, t2, x0, y0, x1, y1)) {
            v->tri_visible = 0;
            v->hidden_triangles++;
            return;
        } else {
            v->tri_visible = v->tri_visible < VIEW_TEST_WAIT ? v->tri_visible + 1 : VIEW_TEST_WAIT;
            v->tri_wait = v->tri_visible;
        }
    }
    int64_t area = (X1 - X0) * (Y2 - Y0) - (Y1 - Y0) * (X2 - X0);
    if (area == 0)
        return; /* edge-on or a point: nothing covered */
    if (area < 0) { /* (corners 1 and 2 swapped: counter-clockwise on the screen) */
        const cm_view_vert *tt = t1;
        int64_t q = X1;
        t1 = t2, t2 = tt;
        X1 = X2, X2 = q;
        q = Y1, Y1 = Y2, Y2 = q;
        area = -area;
    }
    /* e[0] is corner 0's weight (the side 1 -> 2) times the area, e[1] 1's, e[2] 2's */
    view_side e[3] = {side_fn(X1, Y1, X2, Y2), side_fn(X2, Y2, X0, Y0), side_fn(X0, Y0, X1, Y1)};
    /* each side's value at (x0, y0) */
    const int64_t px = x0 * VIEW_SUBPIX + half, py = y0 * VIEW_SUBPIX + half;
    int64_t w0[3];
    w0[0] = e[0].A * (px - X1) + e[0].B * (py - Y1) + e[0].bias;
    w0[1] = e[1].A * (px - X2) + e[1].B * (py - Y2) + e[1].bias;
    w0[2] = e[2].A * (px - X0) + e[2].B * (py - Y0) + e[2].bias;
    /* depth and brightness: the corner 0's plus the other two weights' shares of the differences */
    const double za = t0->z, la = t0->light;
    double inv = 1.0 / (double)area;
    double dzb = t1->z - za, dzc = t2->z - za, dlb = t1->light - la, dlc = t2->light - la;
    if ((x1 - x0 + 1) * (y1 - y0 + 1) <= VIEW_SMALL_BOX) {
        /* a few pixel centres in the box (a small triangle's usual case): each tested, and where
           covered its depth and brightness from the weights, without the slopes' set-up */
        const uint64_t base = lanes(rgb);
        const int64_t s0 = e[0].A * VIEW_SUBPIX, s1 = e[1].A * VIEW_SUBPIX, s2 = e[2].A * VIEW_SUBPIX;
        int drawn = 0;
        for (int64_t y = y0; y <= y1; y++) {
            int64_t dy = (y - y0) * VIEW_SUBPIX;
            int64_t q0 = w0[0] + e[0].B * dy, q1 = w0[1] + e[1].B * dy, q2 = w0[2] + e[2].B * dy;
            for (int64_t x = x0; x <= x1; x++, q0 += s0, q1 += s1, q2 += s2) {
                if ((q0 | q1 | q2) < 0)
                    continue;
                size_t at = (size_t)y * (size_t)v->o.width + (size_t)x;
                double wb = (double)(q1 - e[1].bias), wc = (double)(q2 - e[2].bias);
                float zf = (float)(za + (wb * dzb + wc * dzc) * inv);
                if (!(zf < v->depth[at]))
                    continue;
                v->depth[at] = zf;
                put_lit(&v->rgb[3 * at], base, light_fx(la + (wb * dlb + wc * dlc) * inv));
                drawn = 1;
            }
        }
        if (drawn) /* (the tile of the box's first corner: a mark makes the tile's bound tight again, a
                      mark missed leaves it loose, never wrong) */
            tile_mark(v, x0, y0);
        v->triangles += (uint64_t)drawn;
        return;
    }
    /* the box in lines along its longer side, rows or columns (a sliver costs its few lines, not
       its many): along a line the side values step by s, the depth by zs, the brightness by ls and
       the frame by stride pixels; a line on, the side values by d and the frame by dstride */
    const int cols = y1 - y0 > x1 - x0;
    const int64_t n = cols ? y1 - y0 : x1 - x0, nlines = cols ? x1 - x0 : y1 - y0;
    const size_t W = (size_t)v->o.width, stride = cols ? W : 1, dstride = cols ? 1 : W;
    const int64_t s0 = (cols ? e[0].B : e[0].A) * VIEW_SUBPIX, s1 = (cols ? e[1].B : e[1].A) * VIEW_SUBPIX,
                  s2 = (cols ? e[2].B : e[2].A) * VIEW_SUBPIX;
    const int64_t d0 = (cols ? e[0].A : e[0].B) * VIEW_SUBPIX, d1 = (cols ? e[1].A : e[1].B) * VIEW_SUBPIX,
                  d2 = (cols ? e[2].A : e[2].B) * VIEW_SUBPIX;
    const double zs = ((double)s1 * dzb + (double)s2 * dzc) * inv, ls = ((double)s1 * dlb + (double)s2 * dlc) * inv;
    /* (two pixel centres a line apart in the triangle differ by ls, within the corners' [0, 1]: a
       steeper slope is a sliver's, one pixel a line, and is cut where it cannot overflow; rounded
       half up, floor() written out) */
    double lsc = (ls > 4.0 ? 4.0 : (ls < -4.0 ? -4.0 : ls)) * VIEW_LIGHT_ONE + 0.5;
    int64_t ls_fx = (int64_t)lsc;
    ls_fx -= (double)ls_fx > lsc;
    const uint64_t base = lanes(rgb);
    int drawn = 0;
    /* each side bounds a line's span from its start (a positive step along it: the first pixel at
       or past its zero, a rounded-up quotient) or its end (the last, a rounded-down one), two of
       each kind, a side missing one that never binds; a side along the lines (no step) passes or
       stops whole lines, from the first line or up to a last (jlo, jhi) */
    const int64_t st[3] = {s0, s1, s2}, dn[3] = {d0, d1, d2}, far = INT64_MAX / 4;
    int64_t sr[2] = {far, far}, ss[2] = {1, 1}, sd[2] = {0, 0}, er[2] = {far, far}, em[2] = {1, 1}, ed[2] = {0, 0};
    int64_t jlo = 0, jhi = nlines;
    for (int i = 0, ns = 0, ne = 0; i < 3; i++) {
        if (st[i] > 0) {
            sr[ns] = w0[i], ss[ns] = st[i], sd[ns] = dn[i], ns++;
        } else if (st[i] < 0) {
            er[ne] = w0[i], em[ne] = -st[i], ed[ne] = dn[i], ne++;
        } else if (dn[i] > 0) { /* (not both 0: the corners are apart) */
            jlo = w0[i] < 0 ? (-w0[i] + dn[i] - 1) / dn[i] : 0;
        } else if (w0[i] < 0) {
            return;
        } else {
            int64_t last = w0[i] / -dn[i];
            jhi = last < jhi ? last : jhi;
        }
    }
    size_t line_at = (size_t)y0 * W + (size_t)x0;
    int64_t wl1 = w0[1] - e[1].bias, wl2 = w0[2] - e[2].bias; /* (the weights at each line's start) */
    for (int64_t j = 0; j <= jhi; j++, line_at += dstride, wl1 += d1, wl2 += d2) {
        /* the line's span [lo, hi] (pixels from its start), where all three are >= 0 */
        int64_t lo0 = (-sr[0] + ss[0] - 1) / ss[0], lo1 = (-sr[1] + ss[1] - 1) / ss[1];
        /* (floor: a negative value less its divisor's rounding) */
        int64_t e0 = er[0] < 0 ? er[0] - em[0] + 1 : er[0], e1 = er[1] < 0 ? er[1] - em[1] + 1 : er[1];
        int64_t hi0 = e0 / em[0], hi1 = e1 / em[1];
        int64_t lo = lo0 > lo1 ? lo0 : lo1, hi = hi0 < hi1 ? hi0 : hi1;
        lo = lo > 0 ? lo : 0;
        hi = hi < n ? hi : n;
        sr[0] += sd[0], sr[1] += sd[1], er[0] += ed[0], er[1] += ed[1];
        if (lo > hi || j < jlo)
            continue;
        /* the span from its first pixel, its depth and brightness from that pixel's exact weights
           (from the box's corner, a sliver's extrapolation lost more than face_hidden's margin),
           then stepped (depth in double, brightness in fixed point) */
        const double wb = (double)(wl1 + lo * s1), wc = (double)(wl2 + lo * s2);
        double zp = za + (wb * dzb + wc * dzc) * inv;
        int64_t lfx = light_fx(la + (wb * dlb + wc * dlc) * inv), lend = lfx + (hi - lo) * ls_fx;
        size_t at = line_at + (size_t)lo * stride;
        float *d = &v->depth[at];
        uint8_t *pix = &v->rgb[3 * at];
        const int clamp = !(lend >= 0 && lend <= VIEW_LIGHT_MAX); /* (both ends within: all between) */
        int wrote = 0;
        for (int64_t k = lo; k <= hi; k++, d += stride, pix += 3 * stride, zp += zs, lfx += ls_fx) {
            float zf = (float)zp;
            if (!(zf < *d))
                continue;
            *d = zf;
            put_lit(pix, base, clamp ? (lfx <= 0 ? 0 : (lfx >= VIEW_LIGHT_MAX ? VIEW_LIGHT_MAX : lfx)) : lfx);
            wrote = 1;
        }
        drawn |= wrote;
    }
    if (drawn) /* (every tile of the box: one not written is measured again for nothing, never wrong) */
        for (int64_t ty = y0 / CM_VIEW_TILE; ty <= y1 / CM_VIEW_TILE; ty++)
            for (int64_t tx = x0 / CM_VIEW_TILE; tx <= x1 / CM_VIEW_TILE; tx++)
                v->tile_writer[ty * v->tiles_w + tx] = v->writer;
    v->triangles += (uint64_t)drawn;
}

static void draw_line(cm_view *v, const double a[3], const double b[3]);

/* vertex vi of the mesh on the screen (x, y, depth), its brightness and its normal's component
   along the line of sight (positive: facing away); flags: VIEW_VERT_OK where it can be drawn (in
   front of the eye, within the fixed point's reach), VIEW_VERT_AWAY where it faces away.  (The
   camera's arithmetic written out, orthographic as five dot products: through to_view and
   to_screen it was a tenth of a large model's frame) */
/* (written out where a face's vertices are projected, the hot loop; a call elsewhere) */
__attribute__((always_inline)) static inline void vertex_screen_in(const cm_view *v, const float p[3], const float n[3],
                                                                   cm_view_vert *t)
{
    int ok = 1;
    double x, y;
    if (!v->o.perspective) {
        /* five dot products (ortho_rows), two at a time: x with y, the depth with the facing (its
           constant -0.0, which adds nothing to any value); each lane's sums in the order written
           out, so the same bits as one at a time */
        const double P0 = (double)p[0], P1 = (double)p[1], P2 = (double)p[2];
        const double N0 = (double)n[0], N1 = (double)n[1], N2 = (double)n[2];
        const view_pair *xy = v->ortho_xy, *zf = v->ortho_zf;
        const view_pair XY = (view_pair){P0, P0} * xy[0] + (view_pair){P1, P1} * xy[1] +
                             (view_pair){P2, P2} * xy[2] + xy[3];
        const view_pair ZF = (view_pair){P0, N0} * zf[0] + (view_pair){P1, N1} * zf[1] +
                             (view_pair){P2, N2} * zf[2] + zf[3];
        const double *o4 = v->ortho[4];
        x = XY[0], y = XY[1], t->z = ZF[0], t->facing = ZF[1];
        t->light = shade(t->facing, N0 * o4[0] + N1 * o4[1] + N2 * o4[2]);
    } else {
        double q[3], s[3] = {0, 0, 0};
        to_view(v, (double)p[0], (double)p[1], (double)p[2], q);
        const double nv[3] = {(double)n[0] * v->r[0] + (double)n[1] * v->r[1] + (double)n[2] * v->r[2],
                              (double)n[0] * v->u[0] + (double)n[1] * v->u[1] + (double)n[2] * v->u[2],
                              (double)n[0] * v->f[0] + (double)n[1] * v->f[1] + (double)n[2] * v->f[2]};
        t->light = shade(nv[2], dot3(nv, view_fill));
        /* the line of sight from the eye at (0, 0, eye) */
        t->facing = nv[0] * q[0] + nv[1] * q[1] + nv[2] * (q[2] - v->eye);
        ok = to_screen(v, q, s);
        x = s[0], y = s[1], t->z = q[2];
    }
    ok = ok && fabs(x) < VIEW_COORD_MAX && fabs(y) < VIEW_COORD_MAX;
    t->flags = (uint8_t)((ok ? VIEW_VERT_OK : 0) | (t->facing > 0.0 ? VIEW_VERT_AWAY : 0));
    /* the fixed point, rounded half away from zero (within VIEW_COORD_MAX: 2^28 units) */
    double fx = x * VIEW_SUBPIX, fy = y * VIEW_SUBPIX;
    t->X = ok ? (int32_t)(fx >= 0.0 ? fx + 0.5 : fx - 0.5) : 0;
    t->Y = ok ? (int32_t)(fy >= 0.0 ? fy + 0.5 : fy - 0.5) : 0;
}

__attribute__((noinline)) static void vertex_screen_at(const cm_view *v, const float p[3], const float n[3], cm_view_vert *t)
{
    vertex_screen_in(v, p, n, t);
}

/* the same for vertex vi of the mesh, read on its own */
static void vertex_screen(const cm_view *v, const cm_mesh *mesh, uint32_t vi, cm_view_vert *t)
{
    float p[3], n[3];
    cm_mesh_pos(mesh, vi, p);
    cm_mesh_nrm(mesh, vi, n);
    vertex_screen_at(v, p, n, t);
}

/* orthographic: do all of face F's vertex normals face away from the viewer (n . f > 0, as
   vertex_screen_at has it)?  The normals alone, a run at a time */
static int face_turned_away(cm_view *v, const cm_mesh *mesh, const cm_mesh_face *F)
{
    const double *f = v->ortho[3];
    for (uint32_t i0 = 0; i0 < F->nverts; i0 += CM_VIEW_READ_RUN) {
        uint32_t n = F->nverts - i0 < CM_VIEW_READ_RUN ? F->nverts - i0 : CM_VIEW_READ_RUN;
        const float(*nrm)[3] = cm_mesh_vecs_at(mesh, CM_SPILL_NRM, F->first_vert + i0, n, v->run_nrm);
        for (uint32_t i = 0; i < n; i++) {
            const float *N = nrm[i];
            if (!((double)N[0] * f[0] + (double)N[1] * f[1] + (double)N[2] * f[2] > 0.0))
                return 0;
        }
    }
    return F->nverts > 0;
}

/* vertex j (from the face's first) of face F, a face of more vertices than fv holds: from fv where
   it is still there, else read with the run that follows it (a patch's triangles use its own
   vertices, in order) and projected into the slots they map to */
static const cm_view_vert *window_vertex(cm_view *v, const cm_mesh *mesh, const cm_mesh_face *F, uint32_t j)
{
    uint32_t s = j % CM_VIEW_FACE_VERTS;
    if (v->fv_tag[s] != j) {
        /* (a run no longer than the window: it would replace its own first vertex) */
        const uint32_t run = CM_VIEW_READ_RUN < CM_VIEW_FACE_VERTS ? CM_VIEW_READ_RUN : CM_VIEW_FACE_VERTS;
        uint32_t n = F->nverts - j < run ? F->nverts - j : run;
        cm_mesh_vecs(mesh, CM_SPILL_POS, F->first_vert + j, n, v->run_pos);
        cm_mesh_vecs(mesh, CM_SPILL_NRM, F->first_vert + j, n, v->run_nrm);
        for (uint32_t i = 0; i < n; i++) {
            uint32_t si = (j + i) % CM_VIEW_FACE_VERTS;
            vertex_screen_at(v, v->run_pos[i], v->run_nrm[i], &v->fv[si]);
            v->fv_tag[si] = j + i;
        }
    }
    return &v->fv[s];
}

/*
 * The silhouette across one triangle (screen corners s, facing values d): where d, linear across
 * it, is zero, a segment between the two sides whose ends differ in sign (0 counts as facing the
 * viewer).  A side's crossing depends on its two corners alone, so the segments of neighbouring
 * triangles meet; a plane's corners share one normal and never cross.
 */
static void silhouette(cm_view *v, const cm_view_vert *c0, const cm_view_vert *c1, const cm_view_vert *c2)
{
    const cm_view_vert *const c[3] = {c0, c1, c2};
    /* (the corners where the rasteriser has them, to 1/VIEW_SUBPIX of a pixel) */
    const double px = 1.0 / VIEW_SUBPIX;
    const double s[3][3] = {{c[0]->X * px, c[0]->Y * px, c[0]->z},
                            {c[1]->X * px, c[1]->Y * px, c[1]->z},
                            {c[2]->X * px, c[2]->Y * px, c[2]->z}};
    const double d[3] = {c[0]->facing, c[1]->facing, c[2]->facing};
    double pt[2][3];
    int n = 0;
    for (int i = 0; i < 3 && n < 2; i++) {
        int j = (i + 1) % 3;
        if ((d[i] > 0.0) == (d[j] > 0.0))
            continue;
        double t = d[i] / (d[i] - d[j]);
        for (int k = 0; k < 3; k++)
            pt[n][k] = s[i][k] + t * (s[j][k] - s[i][k]);
        n++;
    }
    if (n == 2) {
        /* at the depth of the triangle's nearest corner: the surface beside a silhouette turns away
           within a pixel (a tube of radius r pixels spans sqrt(2 r) pixels of depth there), more
           than an edge's bias; what lies nearer than the whole triangle still hides it */
        double zmin = s[0][2] < s[1][2] ? s[0][2] : s[1][2];
        zmin = s[2][2] < zmin ? s[2][2] : zmin;
        pt[0][2] = pt[1][2] = zmin;
        draw_line(v, pt[0], pt[1]);
        v->silhouette_segments++;
    }
}

/* tile t's farthest pixel found again (tile_far), the tile clean */
static void tile_refresh(cm_view *v, int t)
{
    const int tx = t % v->tiles_w, ty = t / v->tiles_w;
    const int px1 = (tx + 1) * CM_VIEW_TILE < v->o.width ? (tx + 1) * CM_VIEW_TILE : v->o.width;
    const int py1 = (ty + 1) * CM_VIEW_TILE < v->o.height ? (ty + 1) * CM_VIEW_TILE : v->o.height;
    float far = -3.0e38f;
    for (int py = ty * CM_VIEW_TILE; py < py1; py++) {
        const float *d = &v->depth[(size_t)py * (size_t)v->o.width];
#pragma GCC unroll 8
        for (int px = tx * CM_VIEW_TILE; px < px1; px++)
            far = d[px] > far ? d[px] : far;
    }
    v->tile_far[t] = far;
    v->tile_writer[t] = 0;
}

/* is mesh face fi, by its box and nearest depth (cm_view_fit), behind the farthest pixel of every
   tile it touches, or off the frame?  A tile of its box written since it was last looked at has its
   farthest found again (else it stays an upper bound: a write only brings a pixel nearer) */
static int face_hidden(cm_view *v, uint32_t fi)
{
    const float *b = v->face_box[fi];
    const double k = v->scale, W = (double)v->o.width, H = (double)v->o.height;
    /* (a pixel's margin: the corners are rounded to 1/256 of one, the box to a float) */
    double x0 = 0.5 * W + k * ((double)b[0] - v->fit_x) - 1.0, x1 = 0.5 * W + k * ((double)b[1] - v->fit_x) + 1.0;
    double y0 = 0.5 * H - k * ((double)b[3] - v->fit_y) - 1.0, y1 = 0.5 * H - k * ((double)b[2] - v->fit_y) + 1.0;
    if (!(x1 >= 0.0 && y1 >= 0.0 && x0 < W && y0 < H))
        return 1;
    const int tw = v->tiles_w;
    int tx0 = x0 > 0.0 ? (int)x0 / CM_VIEW_TILE : 0, tx1 = x1 < W ? (int)x1 / CM_VIEW_TILE : (v->o.width - 1) / CM_VIEW_TILE;
    int ty0 = y0 > 0.0 ? (int)y0 / CM_VIEW_TILE : 0, ty1 = y1 < H ? (int)y1 / CM_VIEW_TILE : (v->o.height - 1) / CM_VIEW_TILE;
    /* behind by more than the lines' bias (a silhouette across the face, drawn that much nearer,
       would not show either) and room for the roundings (a pixel's depth is a mix of its triangle's
       corners' in double, then a float: a hundred-thousandth of the model across) */
    const double near = v->face_near[fi] - VIEW_EDGE_BIAS_PX / v->scale - VIEW_DEPTH_ROUND * v->diag;
    for (int ty = ty0; ty <= ty1; ty++)
        for (int tx = tx0; tx <= tx1; tx++) {
            int t = ty * tw + tx;
            if (v->tile_writer[t])
                tile_refresh(v, t);
            if (!(near > (double)v->tile_far[t]))
                return 0;
        }
    return 1;
}

/* the mesh's faces in order of their nearest depths (Shell's sort, Ciura's gaps and their usual
   extension by 2.25: no recursion, no scratch; equal depths in an order fixed by the input alone) */
static void order_faces(cm_view *v, uint32_t n)
{
    static const uint32_t gaps[] = {1149241, 510774, 227011, 100894, 44842, 19930, 8858, 3937,
                                    1750,    701,    301,    132,    57,    23,    10,   4, 1};
    for (uint32_t i = 0; i < n; i++)
        v->face_order[i] = i;
    for (size_t g = 0; g < sizeof gaps / sizeof gaps[0]; g++) {
        uint32_t gap = gaps[g];
        for (uint32_t i = gap; i < n; i++) {
            uint32_t f = v->face_order[i], j = i;
            for (; j >= gap && v->face_near[v->face_order[j - gap]] > v->face_near[f]; j -= gap)
                v->face_order[j] = v->face_order[j - gap];
            v->face_order[j] = f;
        }
    }
}

/*
 * The parts closed at edges they share with others (VIEW_CLOSED_SHARED): each one's volume, by the
 * divergence theorem over its triangles (each turned the way its vertex normals point, whatever its
 * winding), must be clearly positive: its normals face outwards and its back faces can be skipped
 * (face_closed 1); else, or where it cannot be measured (a face beyond face_pos), it is drawn whole
 * (0).  As the encoder judges a solid thinner than a millionth of its diagonal (orient.c).
 */
static void measure_shared_parts(cm_view *v, const cm_mesh *mesh)
{
    const float centre[3] = {(float)v->c[0], (float)v->c[1], (float)v->c[2]};
    uint32_t nf = v->parts_nfaces, nbase = mesh->nplace > 0 ? mesh->nbase_faces : mesh->nfaces;
    int any = 0;
    for (uint32_t f = 0; f < nf; f++)
        if (v->face_closed[f] == VIEW_CLOSED_SHARED) {
            v->piece_volume[v->piece_of_face[f]] = v->piece_area[v->piece_of_face[f]] = 0.0;
            any = 1;
        }
    for (uint32_t fi = 0; any && fi < nbase && fi < mesh->nfaces; fi++) {
        const cm_mesh_face *F = &mesh->faces[fi];
        if (F->source_face >= nf || v->face_closed[F->source_face] != VIEW_CLOSED_SHARED)
            continue;
        uint32_t p = v->piece_of_face[F->source_face];
        if (F->nverts > CM_VIEW_FACE_VERTS) {
            v->piece_area[p] = -1.0; /* (not measured: drawn whole) */
            continue;
        }
        for (uint32_t i0 = 0; i0 < F->nverts; i0 += CM_VIEW_READ_RUN) {
            uint32_t n = F->nverts - i0 < CM_VIEW_READ_RUN ? F->nverts - i0 : CM_VIEW_READ_RUN;
            cm_mesh_vecs(mesh, CM_SPILL_POS, F->first_vert + i0, n, &v->face_pos[i0]);
            cm_mesh_vecs(mesh, CM_SPILL_NRM, F->first_vert + i0, n, &v->face_nrm[i0]);
        }
        double vol = 0.0, area = 0.0;
        uint32_t ntri = F->nindex / 3;
        for (uint32_t k0 = 0; k0 < ntri; k0 += CM_VIEW_READ_RUN) {
            uint32_t n = ntri - k0 < CM_VIEW_READ_RUN ? ntri - k0 : CM_VIEW_READ_RUN;
            cm_mesh_idxs(mesh, F->first_index + 3u * k0, 3u * n, v->run_idx);
            for (const uint32_t *ix = v->run_idx, *const end = ix + 3u * n; ix < end; ix += 3) {
                const uint32_t j0 = ix[0] - F->first_vert, j1 = ix[1] - F->first_vert, j2 = ix[2] - F->first_vert;
                if (j0 >= F->nverts || j1 >= F->nverts || j2 >= F->nverts)
                    continue; /* (not the face's own vertices: not made so) */
                /* (in float, each triangle's share summed in double: its sign is what is asked, and
                   the threshold is a millionth; doubles throughout were a sixth of the frame) */
                const float *p0 = v->face_pos[j0], *p1 = v->face_pos[j1], *p2 = v->face_pos[j2];
                const float ax = p1[0] - p0[0], ay = p1[1] - p0[1], az = p1[2] - p0[2];
                const float bx = p2[0] - p0[0], by = p2[1] - p0[1], bz = p2[2] - p0[2];
                const float cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
                const float *n0 = v->face_nrm[j0], *n1 = v->face_nrm[j1], *n2 = v->face_nrm[j2];
                const float along = cx * (n0[0] + n1[0] + n2[0]) + cy * (n0[1] + n1[1] + n2[1]) + cz * (n0[2] + n1[2] + n2[2]);
                const float six_v = cx * (p0[0] - centre[0]) + cy * (p0[1] - centre[1]) + cz * (p0[2] - centre[2]);
                vol += (double)(along < 0.0f ? -six_v : six_v);
                area += (double)(fabsf(cx) + fabsf(cy) + fabsf(cz));
            }
        }
        if (v->piece_area[p] >= 0.0) {
            v->piece_volume[p] += vol;
            v->piece_area[p] += area;
        }
    }
    /* (vol is 6 V and area at most 2 sqrt(3) A: V / 3 > 1e-6 diag A / 2 asked with room) */
    for (uint32_t f = 0; f < nf; f++)
        if (v->face_closed[f] == VIEW_CLOSED_SHARED) {
            uint32_t p = v->piece_of_face[f];
            v->face_closed[f] = (uint8_t)(v->piece_area[p] > 0.0 && v->piece_volume[p] > 1e-6 * v->diag * v->piece_area[p]);
        }
}

/* the placement of mesh face fi, the one after faces up to fi - 1 were in placement (-1: the
   model's own) and face fi - 1 came from last_source: placed copies follow the model's own faces,
   placement by placement, each in source order (cm_mesh_place), so a copy whose source face does
   not come after the last one's, or lies beyond its placement's faces, starts the next placement
   that holds it */
static int64_t face_placement(const cm_mesh *mesh, uint32_t fi, int64_t placement, uint32_t last_source)
{
    const cm_mesh_face *F = &mesh->faces[fi];
    if (fi < mesh->nbase_faces || mesh->nplace == 0 || !mesh->place)
        return placement;
    const cm_placement *P = placement >= 0 ? &mesh->place[placement] : NULL;
    if (!P || F->source_face <= last_source || F->source_face >= P->first + P->count)
        placement++;
    while (placement + 1 < (int64_t)mesh->nplace &&
           !(F->source_face >= mesh->place[placement].first &&
             F->source_face < mesh->place[placement].first + mesh->place[placement].count))
        placement++;
    return placement < (int64_t)mesh->nplace ? placement : (int64_t)mesh->nplace - 1; /* (a mesh not
                                                                                      made by cm_mesh_place) */
}

/* draw mesh face fi, of placement (-1: the model's own); where the faces are drawn nearest first
   (tiles_live), a face behind what is drawn skipped */
static void draw_face(cm_view *v, const cm_mesh *mesh, uint32_t fi, int64_t placement)
{
    const cm_mesh_face *F = &mesh->faces[fi];
    const uint32_t nbase = mesh->nplace > 0 ? mesh->nbase_faces : mesh->nfaces;
    uint32_t part = placement < 0 ? face_part(v, F->source_face) : place_part(v, (uint32_t)placement);
    int look = part_look(v, part);
    if (look == 0)
        return;
    uint32_t rgb = look_rgb(v, F->has_color ? F->rgb : VIEW_DEFAULT_RGB, look);
    /* a closed part's triangles whose corners all face away are behind its front (a mesh whose
       faces are not all there, one the decoder left out, shows its back faces through the gap) */
    int closed = v->nbase_parts > 0 && nbase == v->parts_nfaces && F->source_face < v->parts_nfaces &&
                 v->face_closed[F->source_face];
    /* a face's vertices (each in about six triangles) projected and lit once, where they fit
       (else in a window, window_vertex: one at a time, a sixth of a large face's frame) */
    int cached = F->nverts <= CM_VIEW_FACE_VERTS;
    int away = closed && !v->o.perspective && face_turned_away(v, mesh, F);
    if (fi < nbase && F->source_face < v->parts_nfaces)
        v->face_away[F->source_face] = (uint8_t)away;
    if (away)
        return; /* (every triangle's corners face away: a third of a closed model's frame) */
    v->writer = fi + 1;
    v->tri_wait = v->tri_visible = 0;
    if (v->tiles_live && face_hidden(v, fi)) {
        v->hidden_faces++; /* (its edges still drawn: a curve may lie up to the tolerance off its
                              mesh, nearer than the face's nearest vertex) */
        return;
    }
    for (uint32_t s = 0; !cached && s < CM_VIEW_FACE_VERTS; s++)
        v->fv_tag[s] = UINT32_MAX;
    unsigned face_all = VIEW_VERT_OK | VIEW_VERT_AWAY, face_any = 0; /* (its vertices' flags) */
    for (uint32_t i0 = 0; cached && i0 < F->nverts; i0 += CM_VIEW_READ_RUN) {
        /* read back a run at a time (from the spill a page at a time): a call per value was a
           sixth of a large model's frame */
        uint32_t n = F->nverts - i0 < CM_VIEW_READ_RUN ? F->nverts - i0 : CM_VIEW_READ_RUN;
        const float(*pos)[3] = cm_mesh_vecs_at(mesh, CM_SPILL_POS, F->first_vert + i0, n, v->run_pos);
        const float(*nrm)[3] = cm_mesh_vecs_at(mesh, CM_SPILL_NRM, F->first_vert + i0, n, v->run_nrm);
        for (uint32_t i = 0; i < n; i++) {
            vertex_screen_in(v, pos[i], nrm[i], &v->fv[i0 + i]);
            face_all &= v->fv[i0 + i].flags;
            face_any |= v->fv[i0 + i].flags;
        }
    }
    /* a face whose vertices all face one way has no silhouette across it */
    const int mixed = !cached || ((face_all ^ face_any) & VIEW_VERT_AWAY);
    /* the triangles a run of indices at a time; the face's numbers held here (a pixel written
       through a byte pointer could be anything to the compiler: they would be read again) */
    const uint32_t first = F->first_vert, nverts = cached ? F->nverts : 0, ntri = F->nindex / 3;
    const unsigned silhouettes = v->o.edges && mixed ? VIEW_VERT_AWAY : 0u, cull = closed ? VIEW_VERT_AWAY : 0u;
    const int64_t wmax = v->o.width - 1, hmax = v->o.height - 1; /* (the frame's last pixel) */
    for (uint32_t k0 = 0; k0 < ntri; k0 += CM_VIEW_READ_RUN) {
        const uint32_t n = ntri - k0 < CM_VIEW_READ_RUN ? ntri - k0 : CM_VIEW_READ_RUN;
        const uint32_t *run = cm_mesh_idxs_at(mesh, F->first_index + 3u * k0, 3u * n, v->run_idx);
        for (const uint32_t *ix = run, *const end = ix + 3u * n; ix < end; ix += 3) {
            cm_view_vert own[3];
            /* (three pointers, not an array: they stay in registers) */
            const cm_view_vert *t0 = &own[0], *t1 = &own[1], *t2 = &own[2];
            /* (unsigned: an index below the face's wraps beyond it) */
            uint32_t j0 = ix[0] - first, j1 = ix[1] - first, j2 = ix[2] - first;
            if (j0 < nverts && j1 < nverts && j2 < nverts) {
                t0 = &v->fv[j0], t1 = &v->fv[j1], t2 = &v->fv[j2];
            } else {
                /* (a large face's corners copied out of the window: a later corner's run may
                   replace an earlier one's slot) */
                for (int i = 0; i < 3; i++) {
                    uint32_t j = ix[i] - first;
                    if (j < nverts)
                        own[i] = v->fv[j];
                    else if (j < F->nverts)
                        own[i] = *window_vertex(v, mesh, F, j);
                    else
                        vertex_screen(v, mesh, ix[i], &own[i]); /* (not the face's own: not made so) */
                }
            }
            const unsigned f0 = t0->flags, f1 = t1->flags, f2 = t2->flags, all = f0 & f1 & f2;
            if (!(all & VIEW_VERT_OK) || (all & cull))
                continue;
            /* a silhouette crosses it where its corners face different ways */
            const unsigned sil = ((f0 | f1 | f2) ^ all) & silhouettes;
            fill_triangle(v, t0, t1, t2, wmax, hmax, rgb);
            if (sil) {
                /* (the corners found again, not kept across the filling: a rare case's registers) */
                if (ix[0] - first < nverts && ix[1] - first < nverts && ix[2] - first < nverts)
                    silhouette(v, &v->fv[ix[0] - first], &v->fv[ix[1] - first], &v->fv[ix[2] - first]);
                else
                    silhouette(v, &own[0], &own[1], &own[2]);
            }
        }
    }
}

void cm_view_mesh(cm_view *v, const cm_mesh *mesh)
{
    ortho_rows(v);
    v->tiles_w = (v->o.width + CM_VIEW_TILE - 1) / CM_VIEW_TILE;
    for (uint32_t f = 0; f < v->parts_nfaces; f++)
        v->face_away[f] = 0;
    if (v->nbase_parts > 0 && (mesh->nplace > 0 ? mesh->nbase_faces : mesh->nfaces) == v->parts_nfaces)
        measure_shared_parts(v, mesh);
    /* orthographic, the faces boxed (cm_view_fit): nearest first, each behind what is drawn skipped
       (a third of an assembly's triangles lie behind its other parts); else in file order */
    const int front_to_back = !v->o.perspective && v->boxes_nfaces == mesh->nfaces && mesh->nfaces > 0 &&
                              mesh->nfaces <= CM_MAX_FACES;
    v->tiles_live = 0;
    if (front_to_back) {
        order_faces(v, mesh->nfaces);
        int ntiles = v->tiles_w * ((v->o.height + CM_VIEW_TILE - 1) / CM_VIEW_TILE);
        v->tiles_live = 1;
        for (int t = 0; t < ntiles; t++) {
            v->tile_far[t] = 3.0e38f; /* (the frame's clear depth) */
            v->tile_writer[t] = 0;
        }
    }
    /* each face's placement (face_placement: found in file order, so before the faces are drawn in
       another) */
    int64_t placement = -1;
    uint32_t last_source = 0;
    for (uint32_t fi = 0; fi < mesh->nfaces; fi++) {
        placement = face_placement(mesh, fi, placement, last_source);
        last_source = mesh->faces[fi].source_face;
        if (front_to_back)
            v->face_place[fi] = (int32_t)placement;
        else
            draw_face(v, mesh, fi, placement);
    }
    for (uint32_t k = 0; front_to_back && k < mesh->nfaces; k++)
        draw_face(v, mesh, v->face_order[k], v->face_place[v->face_order[k]]);
    v->tiles_live = 0;
}

/* ---------------------------------------------------------------- the status line */

/* ASCII 32..126 in 5 x 7 cells, drawn for curvemesh: row by row from the top, bit 4 the left column */
static const uint8_t font5x7[95][7] = {
    {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}, /* ' ' */
    {0x04, 0x04, 0x04, 0x04, 0x04, 0x00, 0x04}, /* '!' */
    {0x0a, 0x0a, 0x00, 0x00, 0x00, 0x00, 0x00}, /* '"' */
    {0x0a, 0x1f, 0x0a, 0x0a, 0x0a, 0x1f, 0x0a}, /* '#' */
    {0x04, 0x0f, 0x14, 0x0e, 0x05, 0x1e, 0x04}, /* '$' */
    {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}, /* '%' */
    {0x08, 0x14, 0x14, 0x08, 0x15, 0x12, 0x0d}, /* '&' */
    {0x04, 0x04, 0x00, 0x00, 0x00, 0x00, 0x00}, /* '\'' */
    {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}, /* '(' */
    {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}, /* ')' */
    {0x00, 0x04, 0x15, 0x0e, 0x15, 0x04, 0x00}, /* '*' */
    {0x00, 0x04, 0x04, 0x1f, 0x04, 0x04, 0x00}, /* '+' */
    {0x00, 0x00, 0x00, 0x00, 0x06, 0x02, 0x04}, /* ',' */
    {0x00, 0x00, 0x00, 0x1f, 0x00, 0x00, 0x00}, /* '-' */
    {0x00, 0x00, 0x00, 0x00, 0x00, 0x0c, 0x0c}, /* '.' */
    {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}, /* '/' */
    {0x0e, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0e}, /* '0' */
    {0x04, 0x0c, 0x04, 0x04, 0x04, 0x04, 0x0e}, /* '1' */
    {0x0e, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1f}, /* '2' */
    {0x1f, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0e}, /* '3' */
    {0x02, 0x06, 0x0a, 0x12, 0x1f, 0x02, 0x02}, /* '4' */
    {0x1f, 0x10, 0x1e, 0x01, 0x01, 0x11, 0x0e}, /* '5' */
    {0x06, 0x08, 0x10, 0x1e, 0x11, 0x11, 0x0e}, /* '6' */
    {0x1f, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}, /* '7' */
    {0x0e, 0x11, 0x11, 0x0e, 0x11, 0x11, 0x0e}, /* '8' */
    {0x0e, 0x11, 0x11, 0x0f, 0x01, 0x02, 0x0c}, /* '9' */
    {0x00, 0x0c, 0x0c, 0x00, 0x0c, 0x0c, 0x00}, /* ':' */
    {0x00, 0x0c, 0x0c, 0x00, 0x0c, 0x04, 0x08}, /* ';' */
    {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}, /* '<' */
    {0x00, 0x00, 0x1f, 0x00, 0x1f, 0x00, 0x00}, /* '=' */
    {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}, /* '>' */
    {0x0e, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04}, /* '?' */
    {0x0e, 0x11, 0x01, 0x0d, 0x15, 0x15, 0x0e}, /* '@' */
    {0x0e, 0x11, 0x11, 0x1f, 0x11, 0x11, 0x11}, /* 'A' */
    {0x1e, 0x11, 0x11, 0x1e, 0x11, 0x11, 0x1e}, /* 'B' */
    {0x0e, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0e}, /* 'C' */
    {0x1c, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1c}, /* 'D' */
    {0x1f, 0x10, 0x10, 0x1e, 0x10, 0x10, 0x1f}, /* 'E' */
    {0x1f, 0x10, 0x10, 0x1e, 0x10, 0x10, 0x10}, /* 'F' */
    {0x0e, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0f}, /* 'G' */
    {0x11, 0x11, 0x11, 0x1f, 0x11, 0x11, 0x11}, /* 'H' */
    {0x0e, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0e}, /* 'I' */
    {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0c}, /* 'J' */
    {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}, /* 'K' */
    {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1f}, /* 'L' */
    {0x11, 0x1b, 0x15, 0x15, 0x11, 0x11, 0x11}, /* 'M' */
    {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}, /* 'N' */
    {0x0e, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0e}, /* 'O' */
    {0x1e, 0x11, 0x11, 0x1e, 0x10, 0x10, 0x10}, /* 'P' */
    {0x0e, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0d}, /* 'Q' */
    {0x1e, 0x11, 0x11, 0x1e, 0x14, 0x12, 0x11}, /* 'R' */
    {0x0f, 0x10, 0x10, 0x0e, 0x01, 0x01, 0x1e}, /* 'S' */
    {0x1f, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}, /* 'T' */
    {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0e}, /* 'U' */
    {0x11, 0x11, 0x11, 0x11, 0x11, 0x0a, 0x04}, /* 'V' */
    {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0a}, /* 'W' */
    {0x11, 0x11, 0x0a, 0x04, 0x0a, 0x11, 0x11}, /* 'X' */
    {0x11, 0x11, 0x0a, 0x04, 0x04, 0x04, 0x04}, /* 'Y' */
    {0x1f, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1f}, /* 'Z' */
    {0x0e, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0e}, /* '[' */
    {0x00, 0x10, 0x08, 0x04, 0x02, 0x01, 0x00}, /* '\\' */
    {0x0e, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0e}, /* ']' */
    {0x04, 0x0a, 0x11, 0x00, 0x00, 0x00, 0x00}, /* '^' */
    {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1f}, /* '_' */
    {0x08, 0x04, 0x00, 0x00, 0x00, 0x00, 0x00}, /* '`' */
    {0x00, 0x00, 0x0e, 0x01, 0x0f, 0x11, 0x0f}, /* 'a' */
    {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x1e}, /* 'b' */
    {0x00, 0x00, 0x0e, 0x10, 0x10, 0x11, 0x0e}, /* 'c' */
    {0x01, 0x01, 0x0d, 0x13, 0x11, 0x11, 0x0f}, /* 'd' */
    {0x00, 0x00, 0x0e, 0x11, 0x1f, 0x10, 0x0e}, /* 'e' */
    {0x06, 0x09, 0x08, 0x1c, 0x08, 0x08, 0x08}, /* 'f' */
    {0x00, 0x0f, 0x11, 0x11, 0x0f, 0x01, 0x0e}, /* 'g' */
    {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x11}, /* 'h' */
    {0x04, 0x00, 0x0c, 0x04, 0x04, 0x04, 0x0e}, /* 'i' */
    {0x02, 0x00, 0x06, 0x02, 0x02, 0x12, 0x0c}, /* 'j' */
    {0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12}, /* 'k' */
    {0x0c, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0e}, /* 'l' */
    {0x00, 0x00, 0x1a, 0x15, 0x15, 0x11, 0x11}, /* 'm' */
    {0x00, 0x00, 0x16, 0x19, 0x11, 0x11, 0x11}, /* 'n' */
    {0x00, 0x00, 0x0e, 0x11, 0x11, 0x11, 0x0e}, /* 'o' */
    {0x00, 0x00, 0x1e, 0x11, 0x1e, 0x10, 0x10}, /* 'p' */
    {0x00, 0x00, 0x0d, 0x13, 0x0f, 0x01, 0x01}, /* 'q' */
    {0x00, 0x00, 0x16, 0x19, 0x10, 0x10, 0x10}, /* 'r' */
    {0x00, 0x00, 0x0f, 0x10, 0x0e, 0x01, 0x1e}, /* 's' */
    {0x08, 0x08, 0x1c, 0x08, 0x08, 0x09, 0x06}, /* 't' */
    {0x00, 0x00, 0x11, 0x11, 0x11, 0x13, 0x0d}, /* 'u' */
    {0x00, 0x00, 0x11, 0x11, 0x11, 0x0a, 0x04}, /* 'v' */
    {0x00, 0x00, 0x11, 0x11, 0x15, 0x15, 0x0a}, /* 'w' */
    {0x00, 0x00, 0x11, 0x0a, 0x04, 0x0a, 0x11}, /* 'x' */
    {0x00, 0x00, 0x11, 0x11, 0x0f, 0x01, 0x0e}, /* 'y' */
    {0x00, 0x00, 0x1f, 0x02, 0x04, 0x08, 0x1f}, /* 'z' */
    {0x02, 0x04, 0x04, 0x08, 0x04, 0x04, 0x02}, /* '{' */
    {0x04, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}, /* '|' */
    {0x08, 0x04, 0x04, 0x02, 0x04, 0x04, 0x08}, /* '}' */
    {0x00, 0x00, 0x08, 0x15, 0x02, 0x00, 0x00}, /* '~' */

};

static void put_rgb(cm_view *v, int x, int y, uint32_t rgb)
{
    if (x < 0 || y < 0 || x >= v->o.width || y >= v->o.height)
        return;
    size_t at = (size_t)y * (size_t)v->o.width + (size_t)x;
    v->rgb[3 * at] = (uint8_t)(rgb >> 16);
    v->rgb[3 * at + 1] = (uint8_t)(rgb >> 8);
    v->rgb[3 * at + 2] = (uint8_t)rgb;
}

int cm_view_status_height(const cm_view *v)
{
    int scale = v->o.height >= 300 ? 2 : 1;
    return 7 * scale + 4 * scale;
}

CM_ONCE_PER_FACE void cm_view_status(cm_view *v, const char *text)
{
    int scale = v->o.height >= 300 ? 2 : 1, h = cm_view_status_height(v), y0 = v->o.height - h;
    for (int y = y0 < 0 ? 0 : y0; y < v->o.height; y++)
        for (int x = 0; x < v->o.width; x++)
            put_rgb(v, x, y, VIEW_STATUS_BG_RGB);
    int x = 2 * scale;
    for (const char *c = text; *c && x + 5 * scale <= v->o.width; c++, x += 6 * scale) {
        unsigned ch = (unsigned char)*c;
        const uint8_t *g = font5x7[ch >= 32 && ch <= 126 ? ch - 32 : '?' - 32];
        for (int r = 0; r < 7; r++)
            for (int col = 0; col < 5; col++)
                if (g[r] & (0x10 >> col))
                    for (int dy = 0; dy < scale; dy++)
                        for (int dx = 0; dx < scale; dx++)
                            put_rgb(v, x + col * scale + dx, y0 + 2 * scale + r * scale + dy, VIEW_STATUS_RGB);
    }
}

/* a line from a to b (screen x, y, depth), depth-tested against the faces, drawn nearer by zbias */
static void draw_line(cm_view *v, const double a[3], const double b[3])
{
    double dx = b[0] - a[0], dy = b[1] - a[1];
    double len = fabs(dx) > fabs(dy) ? fabs(dx) : fabs(dy);
    if (!(len < 1e5))
        return; /* off in the distance (perspective near the eye): not a line worth drawing */
    int n = (int)len + 1;
    /* nearer by a few pixels' worth of depth: enough for the faces' own boundary (their triangles
       meet the edge at its samples, and may lie up to the tessellation's tolerance off between),
       not enough to see a back edge through a plate a few pixels thick.  The shift is linear in the
       depth (perspective: a pixel spans more depth farther away), so the ends are shifted and the
       points between interpolated, one multiplication a pixel where each took a division */
    double k = VIEW_EDGE_BIAS_PX / v->scale;
    double za = v->o.perspective ? a[2] - k * (a[2] - v->eye) : a[2] - k;
    double zb = v->o.perspective ? b[2] - k * (b[2] - v->eye) : b[2] - k;
    /* the points i = 0..n, each stepped from the last (the coordinates added to, not multiplied
       out), those off the frame left out */
    const double W = (double)v->o.width, H = (double)v->o.height, inv = 1.0 / (double)n;
    const double sx = dx * inv, sy = dy * inv, sz = (zb - za) * inv;
    double x = a[0], y = a[1], z = za;
    for (int i = 0; i <= n; i++, x += sx, y += sy, z += sz) {
        if (!(x >= 0.0 && y >= 0.0 && x < W && y < H))
            continue;
        size_t at = (size_t)(int)y * (size_t)v->o.width + (size_t)(int)x;
        float zf = (float)z;
        if (!(zf <= v->depth[at]))
            continue;
        v->depth[at] = zf;
        v->rgb[3 * at] = (uint8_t)(VIEW_EDGE_RGB >> 16);
        v->rgb[3 * at + 1] = (uint8_t)(VIEW_EDGE_RGB >> 8);
        v->rgb[3 * at + 2] = (uint8_t)VIEW_EDGE_RGB;
    }
    v->edge_segments++;
}

/* p placed by a (3 x 4, row by row; NULL: as it is), in view space */
static void placed_view(const cm_view *v, cm_vec3 p, const double *a, double q[3])
{
    double x = p.x, y = p.y, z = p.z;
    if (a) {
        double X = a[0] * x + a[1] * y + a[2] * z + a[3];
        double Y = a[4] * x + a[5] * y + a[6] * z + a[7];
        double Z = a[8] * x + a[9] * y + a[10] * z + a[11];
        x = X, y = Y, z = Z;
    }
    to_view(v, x, y, z, q);
}

/* is curve c one span with its knots clamped at both ends (p + 1 equal knots each): a Bezier curve
   (circular arcs, most exporters' simple edges, asmo's degree-7 edges)?  Then coef[i] = C(p, i) w_i
   (the binomials exact: integers) for bezier_point */
static __attribute__((noinline)) int one_span(const cm_curve *c, double coef[CM_MAX_ORDER])
{
    const int p = c->p;
    if (p < 2 || c->n_ctrl != p + 1 || !(c->knots[p] < c->knots[p + 1]))
        return 0;
    double binom = 1.0;
#pragma GCC unroll 1
    for (int i = 0; i <= p; i++) {
        if (i < p && (c->knots[i] != c->knots[p] || c->knots[p + 1 + i] != c->knots[2 * p + 1]))
            return 0;
        coef[i] = binom * (c->w ? c->w[i] : 1.0);
        binom = binom * (double)(p - i) / (double)(i + 1);
    }
    return 1;
}

/* such a curve's point at u (clamped to its domain, as cm_curve_eval's): its control points summed
   with the Bernstein polynomials' values, weighted where rational (coef: one_span's).  O(p) where
   the B-spline basis is O(p^2): a degree-7 point was 700 instructions.  (The viewer's alone: the
   lines between its points are drawn, not compared) */
static __attribute__((noinline)) void bezier_point(const cm_curve *c, const double coef[CM_MAX_ORDER], double u,
                                                   cm_vec3 *out)
{
    const int p = c->p;
    const double a = c->knots[p], b = c->knots[p + 1];
    u = u > a ? (u < b ? u : b) : a;
    const double s = (u - a) / (b - a), t = 1.0 - s;
    double pw[CM_MAX_ORDER], x = 0.0, y = 0.0, z = 0.0, w = 0.0, sp = 1.0, tp = 1.0;
    /* (loops, not peeled into one copy for each degree: the viewer's code is budgeted) */
#pragma GCC unroll 1
    for (int i = 0; i <= p; i++, sp *= s)
        pw[i] = sp; /* s^i */
#pragma GCC unroll 1
    for (int i = p; i >= 0; i--, tp *= t) { /* C(p, i) w_i s^i t^(p - i) */
        double bw = coef[i] * pw[i] * tp;
        x += bw * c->ctrl[i].x, y += bw * c->ctrl[i].y, z += bw * c->ctrl[i].z, w += bw;
    }
    out->x = x / w, out->y = y / w, out->z = z / w;
}

/* edge e of m, placed by a, sampled and drawn: a line (degree 1) at its control points, a curve in
   pieces of about VIEW_EDGE_PIECE_PX pixels of its control polygon on the screen (at least one a
   span, at most CM_VIEW_EDGE_SEGMENTS) */
static void draw_edge(cm_view *v, const cm_model *m, uint32_t e, const double *a)
{
    cm_curve c;
    cm_model_edge_curve(m, e, &c);
    int n = c.n_ctrl - 1;
    if (c.p > 1) {
        double len = 0.0, prevq[3] = {0, 0, 0};
        for (int i = 0; i < c.n_ctrl; i++) {
            double q[3];
            placed_view(v, c.ctrl[i], a, q);
            if (i > 0) {
                double dx = q[0] - prevq[0], dy = q[1] - prevq[1];
                len += sqrt(dx * dx + dy * dy);
            }
            prevq[0] = q[0], prevq[1] = q[1], prevq[2] = q[2];
        }
        double k = v->o.perspective ? v->scale / (v->scale > 0.0 ? -v->eye : 1.0) : v->scale; /* px per mm, about */
        double want = len * k / VIEW_EDGE_PIECE_PX;
        n = !(want < (double)CM_VIEW_EDGE_SEGMENTS) ? CM_VIEW_EDGE_SEGMENTS : (int)want + 1;
        n = n < c.n_ctrl - c.p ? c.n_ctrl - c.p : n;
    }
    n = n < 1 ? 1 : (n > CM_VIEW_EDGE_SEGMENTS && c.p > 1 ? CM_VIEW_EDGE_SEGMENTS : n);
    const int polyline = c.p == 1 && n == c.n_ctrl - 1;
    if (!polyline && !(v->edge_cache_e == e && v->edge_cache_n == n)) {
        /* the curve's points, kept for the next copy of the same edge that wants as many
           (cm_view_edges draws an edge's copies one after another: a copy's curve was evaluated
           again, a tenth of a large assembly's frame) */
        v->edge_cache_e = e, v->edge_cache_n = n, v->edge_cache_len = 0;
        double coef[CM_MAX_ORDER];
        const int bezier = one_span(&c, coef);
        for (int k = 0; k <= n; k++) {
            cm_vec3 d[CM_MAX_DERS + 1];
            if (bezier)
                bezier_point(&c, coef, (double)k / (double)n, d);
            else if (cm_curve_eval(&c, (double)k / (double)n, 0, d, NULL) != CM_OK)
                break; /* (the points before it are drawn) */
            v->edge_cache_pts[v->edge_cache_len++] = d[0];
        }
    }
    const int npts = polyline ? n + 1 : v->edge_cache_len;
    double prev[3] = {0, 0, 0};
    int have = 0;
    for (int k = 0; k < npts; k++) {
        double q[3], s[3];
        placed_view(v, polyline ? c.ctrl[k] : v->edge_cache_pts[k], a, q);
        if (!to_screen(v, q, s)) {
            have = 0;
            continue;
        }
        if (have)
            draw_line(v, prev, s);
        prev[0] = s[0], prev[1] = s[1], prev[2] = s[2];
        have = 1;
    }
}

/* does a face using edge e show (placement k's copy; -1: the model's own), and (range) lie in
   faces [first, first + count)?  Through the edge's uses where cm_view_parts listed them */
static int edge_shows(const cm_view *v, const cm_model *m, uint32_t e, int64_t k, uint32_t first, uint32_t count)
{
    uint32_t part = k < 0 ? 0 : place_part(v, (uint32_t)k);
    if (v->nbase_parts > 0 && e < CM_MAX_EDGES) {
        /* (the model's own edge between faces of closed parts all turned away is behind them:
           not worth its curve, cm_view_mesh's face_away) */
        int shows = 0, behind = k < 0;
        for (int32_t u = v->edge_head[e]; u >= 0; u = v->use_next[u]) {
            uint32_t f = v->use_face[u];
            if (f >= first && f - first < count && part_look(v, k < 0 ? face_part(v, f) : part) != 0)
                shows = 1;
            behind = behind && f < v->parts_nfaces && v->face_away[f];
        }
        return shows && !behind;
    }
    for (int i = 0; i < 2; i++) {
        int32_t f = m->edge_face[e][i];
        if (f >= 0 && (uint32_t)f >= first && (uint32_t)f - first < count && part_look(v, k < 0 ? 1 : part) != 0)
            return 1;
    }
    return 0;
}

void cm_view_edges(cm_view *v, const cm_model *m)
{
    if (!v->o.edges)
        return;
    /* each edge once (not once for each face that uses it), for the model and each placement; an
       edge's copies one after another (its points evaluated once: draw_edge).  (An edge pixel is
       the edges' colour whichever line reaches it first: the order shows nowhere) */
    v->edge_cache_n = -1;
    for (uint32_t e = 0; e < m->nedges; e++) {
        if (edge_shows(v, m, e, -1, 0, m->nfaces))
            draw_edge(v, m, e, NULL);
        for (uint32_t k = 0; k < m->nplacements; k++) {
            const cm_placement *P = &m->placements[k];
            if (edge_shows(v, m, e, k, P->first, P->count))
                draw_edge(v, m, e, P->m);
        }
    }
}
