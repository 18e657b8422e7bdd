/*
 * cm_view.h - the terminal's software viewer (issue 17): a decoded mesh drawn
 * into a z-buffered RGB frame, with the curve mesh's exact edges on top.
 *
 * The frame is the caller's (static on the terminal, sized by fixedcfg's
 * CM_VIEW_MAX_W x CM_VIEW_MAX_H); nothing is allocated.  The camera looks
 * at the mesh's box from a named direction (CAD axes, Z up), orthographic
 * or perspective, and is fitted so that the whole box shows.  Triangles
 * are filled with the decoder's own normals (Gouraud shading: a head light
 * and a fill light, both sides lit), in the face's colour from the model or
 * a default grey-blue; the edges are each edge curve of the model sampled
 * and drawn as lines in front of the faces they bound (a small depth bias),
 * so they stay crisp at any zoom.  Placed copies (format 4.3) get their
 * placement's edges too.
 *
 * Triangles are rasterised with exact integer edge functions on corners
 * rounded to 1/256 pixel (the top-left rule: a pixel centre on a side two
 * triangles share is filled once); a closed part's triangles facing away
 * are skipped (cm_view_parts).
 *
 * Deterministic: integers, and only + - * / sqrt in double, in a fixed
 * order, with -ffp-contract=off: the same model and view give the same
 * pixels on x86-64, aarch64 and armhf (check-view-cross compares).
 *
 * Contract: no heap, no recursion; work bounded by the mesh, the model and
 * the frame's size.
 */
#ifndef CM_VIEW_H
#define CM_VIEW_H

#include <stdint.h>

#include "cm/cm_error.h"
#include "cm/cm_format.h"
#include "cm/cm_mesh.h"
#include "cm_limits.h"

/** Where the camera looks from (CAD axes: Z up; front looks along +Y). */
typedef enum cm_view_dir {
    CM_VIEW_ISO = 0, /* from the front, right and top: along (-1, 1, -1) */
    CM_VIEW_FRONT,   /* from -Y */
    CM_VIEW_BACK,    /* from +Y */
    CM_VIEW_LEFT,    /* from -X */
    CM_VIEW_RIGHT,   /* from +X */
    CM_VIEW_TOP,     /* from +Z, +Y up on the screen */
    CM_VIEW_BOTTOM,  /* from -Z, -Y up on the screen */
    CM_VIEW_DIR_COUNT
} cm_view_dir;

/** The name of a direction ("iso", "front", ...), and back (-1: no such name). */
const char *cm_view_dir_name(cm_view_dir d);
int cm_view_dir_parse(const char *name);

typedef struct cm_view_opts {
    int width, height;     /* pixels, 1..CM_VIEW_MAX_W x 1..CM_VIEW_MAX_H */
    cm_view_dir dir;
    int perspective;       /* 0: orthographic; 1: a 30 degree field of view */
    uint32_t background;   /* 0xRRGGBB */
    int edges;             /* 1: draw the curve mesh's edges and the silhouettes of curved faces */
    uint32_t step;         /* assembly step k >= 1: parts 1..k shown, part k highlighted, the others
                              dimmed (cm_view_parts numbers them); 0: the whole model as it is */
    int turn;              /* the model turned about its vertical (Z) axis by turn x CM_VIEW_TURN_DEG
                              degrees, counter-clockwise seen from above (a turntable; any integer) */
} cm_view_opts;

/** One turn step of cm_view_opts.turn (a rotate button press, a turntable tick), in degrees. */
#define CM_VIEW_TURN_DEG 15
#define CM_VIEW_TURNS (360 / CM_VIEW_TURN_DEG)

/** Defaults: 800 x 480 (within the build's frame), iso, unturned, orthographic, white, edges on. */
void cm_view_opts_default(cm_view_opts *o);

/** The coarse depth's tiles (cm_view_mesh): pixels a side, and how many the largest frame has. */
#define CM_VIEW_TILE 8
#define CM_VIEW_TILES (((CM_VIEW_MAX_W + CM_VIEW_TILE - 1) / CM_VIEW_TILE) * ((CM_VIEW_MAX_H + CM_VIEW_TILE - 1) / CM_VIEW_TILE))

/** Vertices (and triangles) read back from the mesh at a time by cm_view_mesh. */
#define CM_VIEW_READ_RUN 256

/** A mesh vertex on the screen (cm_view.c's): view-space depth, its brightness, its normal along
    the line of sight (the silhouette where it is 0, positive facing away), the position in the
    rasteriser's fixed point (pixels x right, y down, times 256), and flags: whether it can be
    drawn at all (in front of the eye, within the fixed point's reach), whether it faces away. */
typedef struct cm_view_vert {
    double z, light, facing;
    int32_t X, Y;
    uint8_t flags;
} cm_view_vert;

/* two doubles handled as one (gcc's and clang's vector extension: one SSE2 or NEON operation where
   the target has it, two otherwise; each lane rounds as a double alone) */
typedef double view_pair __attribute__((vector_size(16)));

typedef struct cm_view {
    cm_view_opts o;
    /* the camera: a point of view space is ((p - c).r, (p - c).u, (p - c).f), f into the screen */
    double c[3], r[3], u[3], f[3];
    double scale;          /* orthographic: pixels per mm; perspective: the focal length in pixels */
    double diag;           /* the model's box's diagonal (mm) */
    double eye;            /* perspective: the eye's depth in view space (negative) */
    /* orthographic, set by cm_view_mesh from the above: a point's screen x, y and depth and a
       normal's component along the view and along the fill light, each a dot product with a
       model-space row (and a constant) */
    double ortho[5][4];
    /* the same rows' coefficients in pairs, x with y and depth with facing (vertex_screen_in) */
    view_pair ortho_xy[4], ortho_zf[4];
    uint64_t triangles, edge_segments, silhouette_segments; /* drawn (for tests and --verbose) */
    uint64_t hidden_faces, hidden_triangles;                /* skipped behind what was drawn */
    /* the model's parts (cm_view_parts): those the file names (format 4.11: cm_face.part,
       cm_placement.part), else a face's part among its own faces' connected components (faces joined
       by their edges, see there), numbered from 1 in face order, and placement k's copies part
       nbase_parts + 1 + k */
    uint32_t nparts, nbase_parts;
    int named_parts;                       /* the parts are the file's */
    uint32_t part_of_face[CM_MAX_FACES];
    uint32_t place_part[CM_MAX_PLACEMENTS > 0 ? CM_MAX_PLACEMENTS : 1]; /* (named parts) */
    uint8_t part_closed[CM_MAX_FACES + 1]; /* (scratch: connected component p's faces close it) */
    uint8_t face_closed[CM_MAX_FACES];     /* face f's connected component is closed (see cm_view_parts;
                                              VIEW_CLOSED_SHARED: to be measured by cm_view_mesh) */
    uint32_t piece_of_face[CM_MAX_FACES];  /* face f's connected component (from 1) */
    uint8_t face_away[CM_MAX_FACES];       /* (cm_view_mesh, for cm_view_edges: face f is closed and
                                              all its vertices face away: its edges are behind it;
                                              a face skipped as hidden keeps its edges) */
    /* (scratch, cm_view_mesh: a component's signed volume, about its area, and a face's vertices in
       model space, to tell whether its normals face outwards) */
    double piece_volume[CM_MAX_FACES + 1], piece_area[CM_MAX_FACES + 1];
    float face_pos[CM_VIEW_FACE_VERTS][3], face_nrm[CM_VIEW_FACE_VERTS][3];
    uint32_t parts_nfaces;                 /* the faces cm_view_parts numbered */
    int32_t edge_head[CM_MAX_EDGES];       /* (scratch: each edge's uses in a list, ... */
    int32_t use_next[CM_MAX_MODEL_USES];   /* ... the next use of the same edge, -1 at the end, */
    uint32_t use_face[CM_MAX_MODEL_USES];  /* ... and the face of each use) */
    /* a face's vertices on the screen, lit: a vertex is in about six triangles; a face of more
       (GREGORY faces are meshed patch by patch) keeps its vertex j in fv[j % CM_VIEW_FACE_VERTS],
       fv_tag saying which j is there */
    cm_view_vert fv[CM_VIEW_FACE_VERTS];
    /* front to back (orthographic): cm_view_fit keeps each mesh face's box (view units across and
       up, before the fit's centring, which it keeps in fit_x, fit_y) and nearest depth; cm_view_mesh
       draws the faces nearest first, and skips a face whose box is behind the farthest pixel of
       every tile it touches (tile_far: an upper bound, made the farthest again where written since,
       tile_writer), and a triangle of a face drawn likewise */
    uint32_t boxes_nfaces;                 /* the faces boxed (0: none, draw in file order) */
    int tiles_w;                           /* tiles across the frame */
    int tiles_live;                        /* (cm_view_mesh drawing front to back: tile_far holds) */
    double fit_x, fit_y;
    float face_box[CM_MAX_FACES][4];       /* x low, x high, y low, y high */
    double face_near[CM_MAX_FACES];
    uint32_t face_order[CM_MAX_FACES];
    int32_t face_place[CM_MAX_FACES];      /* a face's placement (-1: the model's own) */
    float tile_far[CM_VIEW_TILES];
    uint32_t tile_writer[CM_VIEW_TILES];   /* (the face that wrote a tile since its tile_far was
                                              found, plus 1; 0: none) */
    uint32_t writer;                       /* (the face being drawn, plus 1) */
    uint32_t tri_visible, tri_wait;        /* (its triangles found visible in a row; to skip testing) */
    uint32_t fv_tag[CM_VIEW_FACE_VERTS];
    /* a run of the mesh's positions, normals and indices, read back together */
    float run_pos[CM_VIEW_READ_RUN][3], run_nrm[CM_VIEW_READ_RUN][3];
    uint32_t run_idx[3 * CM_VIEW_READ_RUN];
    /* an edge curve's points (model space), for its next copy wanting as many (cm_view_edges) */
    uint32_t edge_cache_e;
    int edge_cache_n, edge_cache_len;
    cm_vec3 edge_cache_pts[CM_VIEW_EDGE_SEGMENTS + 1];
    uint8_t rgb[CM_VIEW_MAX_W * CM_VIEW_MAX_H * 3]; /* row by row from the top, width * 3 bytes a row */
    float depth[CM_VIEW_MAX_W * CM_VIEW_MAX_H];     /* view-space depth of what the pixel shows */
} cm_view;

/**
 * Start a frame: camera fitted to the box [lo, hi] (mm), the frame cleared.
 * @return CM_E_LIMIT (VIEW_SIZE) when the size is beyond the build's frame, CM_E_ARG for a size
 *         below 1 pixel, a direction out of range or a box that is not finite
 */
CM_NODISCARD cm_err cm_view_begin(cm_view *v, const cm_view_opts *o, const float lo[3], const float hi[3],
                                  cm_status *st);

/**
 * Orthographic frames: centre and scale the camera on the mesh's own outline (its vertices seen
 * from the camera) instead of its box's, which from an oblique direction is larger.  Call after
 * cm_view_begin, before drawing; perspective frames keep the box's fit.  With the faces' model-space
 * boxes (box[f] from cm_mesh_face_boxes, nboxed of them: once a model) only the faces that may
 * reach the outline have their vertices projected, the same outline; else (box NULL) every vertex.
 */
void cm_view_fit(cm_view *v, const cm_mesh *mesh, const float (*box)[6], uint32_t nboxed);

/**
 * Number the model's parts for assembly steps (opts.step): those the file names (format 4.11, the
 * workstation's parts in the order of its steps), else the connected components of its own faces
 * (an edge used by two faces joins them; where three or more meet, touching parts of a flattened
 * assembly, each face is joined to the nearest one in file order that runs the edge the other
 * way), in the order of their first face, then each placement's
 * copies (format 4.3: an IGES subfigure instance, a STEP occurrence) one part each, in file order.
 * Until it is called every face is part 1.  Also marks the connected pieces that are closed (each
 * edge of their faces used twice, in opposite directions: the encoder faced them outwards; or, at an
 * edge of three or more uses, the piece's own uses of it as often one way as the other, and then
 * cm_view_mesh measures the piece's volume to see it faces outwards), whose back faces cm_view_mesh
 * skips.  Returns the number of parts.
 */
uint32_t cm_view_parts(cm_view *v, const cm_model *m);

/**
 * Fill every triangle of the mesh (faces coloured by their rgb when they have one; of a closed part,
 * cm_view_parts', only those with a corner facing the viewer: the rest are behind), and with
 * opts.edges the silhouettes of curved faces: where the mesh's normals turn from facing the viewer
 * to facing away, the line on which their component along the line of sight, interpolated across
 * each triangle, is zero (drawn like an edge: depth-tested, a little in front).  Orthographic, after
 * cm_view_fit: the faces nearest first, a face behind what is drawn (by more than a line's bias)
 * skipped.  A face is judged by its own vertices: its indices must name them (as the decoder and
 * cm_glb_read make them; an index beyond its face is drawn, but the face's box does not hold it).
 */
void cm_view_mesh(cm_view *v, const cm_mesh *mesh);

/**
 * Draw the model's edges (each edge curve sampled into CM_VIEW_EDGE_SEGMENTS lines) for its own
 * faces and each placement's copies.  An edge the evaluator refuses is skipped.
 */
void cm_view_edges(cm_view *v, const cm_model *m);

/**
 * The status line (transfer progress, refusals, errors: issue 17): a dark bar across the bottom of
 * the frame, cm_view_status_height() pixels high, with text in a built-in 5 x 7 bitmap font (scaled
 * twice on frames 300 pixels high or more); characters outside ASCII show as '?', what does not fit
 * is cut.  Drawn over whatever the frame holds.
 */
void cm_view_status(cm_view *v, const char *text);
int cm_view_status_height(const cm_view *v);

#endif /* CM_VIEW_H */
