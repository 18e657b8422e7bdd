/*
 * cm_mesh.h - the decoded triangle mesh handed to the viewer.
 *
 * Storage is the caller's (static arrays sized by fixedcfg limits on the
 * terminal); the decoder fills it face by face.  Each face keeps its own
 * vertices (so it stays pickable as its own glTF primitive, with its own
 * normals); positions along an edge shared by two faces are bit-identical
 * in both, so the mesh is watertight once vertices are welded by position.
 *
 * Units and axes: positions are the model's millimetres, CAD axes (Z up).
 * Writers convert to the output format's conventions (glTF: metres, +Y up,
 * through the root node's transform; STL/OBJ: millimetres as is).
 */
#ifndef CM_MESH_H
#define CM_MESH_H

#include <stddef.h>
#include <stdint.h>

#include "cm/cm_error.h"
#include "cm_limits.h" /* CM_SPILL_PAGE_BYTES */

typedef struct cm_mesh_face {
    uint32_t first_vert, nverts;   /* vertices [first_vert, first_vert + nverts) */
    uint32_t first_index, nindex;  /* indices [first_index, first_index + nindex), 3 per triangle, global vertex ids */
    uint32_t rgb;                  /* 0xRRGGBB when has_color */
    uint8_t has_color;
    uint32_t source_face;          /* face number in the model (the .cmz face order) */
} cm_mesh_face;

/*
 * Streaming (issue 15): a terminal does not hold the whole output mesh.  A mesh with a spill keeps
 * only its latest vertices and indices in its arrays (the resident window); when a face would not
 * fit there, cm_mesh_make_room writes the window out through the spill's io (the platform's: files
 * beside the output) and starts it again empty.  Everything reads vertices and indices through
 * cm_mesh_pos, cm_mesh_nrm and cm_mesh_idx, which take a flushed one back through a few cached pages
 * per array.  Without a spill (the workstation, tests) the arrays are the whole mesh, as before.
 */
enum { CM_SPILL_POS = 0, CM_SPILL_NRM = 1, CM_SPILL_IDX = 2, CM_SPILL_STREAMS = 3 };

/* read (write = 0) or write n bytes at byte offset off of stream s; 0 on success.  Writes only ever
   append or rewrite what a rolled-back face left; reads only what was written */
typedef int cm_mesh_spill_io(void *ctx, int write, unsigned s, uint64_t off, void *buf, size_t n);

/* a cached page of a spilled stream: its bytes as read, over storage of the type it holds (aligned
   for it, so that cm_mesh_vecs_at and cm_mesh_idxs_at can hand out pointers into it) */
typedef union cm_spill_page {
    uint8_t b[CM_SPILL_PAGE_BYTES];
    float vec[CM_SPILL_PAGE_BYTES / 12][3];
    uint32_t idx[CM_SPILL_PAGE_BYTES / 4];
} cm_spill_page;

typedef struct cm_mesh_spill {
    cm_mesh_spill_io *io;
    void *ctx;
    int failed;                    /* an io call failed: cm_mesh_spill_failed; the writers stop with CM_E_IO */
    /* CM_SPILL_PAGES cached pages per stream, page k of a stream in slot k % CM_SPILL_PAGES: the
       writers read in order, but STL takes a face's positions by its indices, which jump within
       the face (one page per stream re-read a page nearly every triangle) */
    uint32_t page_first[CM_SPILL_STREAMS][CM_SPILL_PAGES], page_n[CM_SPILL_STREAMS][CM_SPILL_PAGES];
    cm_spill_page page[CM_SPILL_STREAMS][CM_SPILL_PAGES];
} cm_mesh_spill;

typedef struct cm_mesh {
    float (*pos)[3];               /* cap_verts positions (mm); with a spill the window's win_cap_verts */
    float (*nrm)[3];               /* cap_verts unit normals (idem) */
    uint32_t *idx;                 /* cap_index vertex indices (idem, win_cap_index) */
    cm_mesh_face *faces;           /* cap_faces faces */
    uint32_t nverts, cap_verts;    /* with a spill, cap_* bound the whole mesh, win_cap_* the arrays */
    uint32_t nindex, cap_index;
    uint32_t nfaces, cap_faces;
    /* format 4.3 (cm_mesh_place, cm_place.h): faces [0, nbase_faces), vertices [0, nbase_verts) and
       indices [0, nbase_index) are the model's own, the rest its nplace placed copies, copy k placed
       by place[k] (the GLB writer writes the model's own and shares them between nodes instead) */
    uint32_t nbase_faces, nbase_verts, nbase_index, nplace;
    const struct cm_placement *place;
    cm_mesh_spill *spill;          /* NULL: the arrays hold the whole mesh (win_* stay 0) */
    uint32_t win_vert, win_index;  /* vertices [0, win_vert) and indices [0, win_index) are spilled */
    uint32_t win_cap_verts, win_cap_index;
} cm_mesh;

/** Set the mesh empty (keeps the caller's arrays, capacities and spill). */
void cm_mesh_clear(cm_mesh *m);

/** Give m a spill (s zeroed but for io and ctx): its arrays, of win_verts vertices and win_index
    indices, become a window; the whole mesh may then hold cap_verts and cap_index. */
void cm_mesh_set_spill(cm_mesh *m, cm_mesh_spill *s, uint32_t win_verts, uint32_t win_index, uint32_t cap_verts,
                       uint32_t cap_index);

/** Make the window hold nv more vertices and ni more indices, spilling it first when needed.
    @return CM_OK; CM_E_IO when the spill's io failed; CM_E_LIMIT (MAX_TESS_POINTS) when even an
    empty window is too small (the build's window below its one-face limits: cm_decode_state.h) */
CM_NODISCARD cm_err cm_mesh_make_room(cm_mesh *m, uint32_t nv, uint32_t ni, cm_status *st);

/* where in the arrays vertex i and index k are (valid for the resident ones only) */
static inline float *cm_mesh_wpos(cm_mesh *m, uint32_t i) { return m->pos[i - m->win_vert]; }
static inline float *cm_mesh_wnrm(cm_mesh *m, uint32_t i) { return m->nrm[i - m->win_vert]; }
static inline uint32_t *cm_mesh_widx(cm_mesh *m, uint32_t k) { return &m->idx[k - m->win_index]; }

/** Vertex i's position (s = CM_SPILL_POS) or normal (CM_SPILL_NRM), copied out, and index k: from
    the window, or read back from the spill (a failed read gives zeros and sets spill->failed).
    Functions, not inline: the board's code size is budgeted (CM_PROGRAM_TEXT_BUDGET) and the
    writers call them from many places. */
void cm_mesh_vec(const cm_mesh *m, unsigned s, uint32_t i, float out[3]);
void cm_mesh_pos(const cm_mesh *m, uint32_t i, float out[3]);
void cm_mesh_nrm(const cm_mesh *m, uint32_t i, float out[3]);
uint32_t cm_mesh_idx(const cm_mesh *m, uint32_t k);

/** n consecutive vectors of stream s from vertex `first`, and n indices from index k, copied out:
    the same values as one call each, a cached page or the window at a time (the viewer reads a
    face's vertices and triangles so, each frame). */
void cm_mesh_vecs(const cm_mesh *m, unsigned s, uint32_t first, uint32_t n, float (*out)[3]);
void cm_mesh_idxs(const cm_mesh *m, uint32_t k, uint32_t n, uint32_t *out);
/** The same values where the window or one cached page of the spill holds them all: a pointer to
    them, no copy (valid until the mesh changes or the stream's next page is read); else copied into
    out, which is returned. */
const float (*cm_mesh_vecs_at(const cm_mesh *m, unsigned s, uint32_t first, uint32_t n, float (*out)[3]))[3];
const uint32_t *cm_mesh_idxs_at(const cm_mesh *m, uint32_t k, uint32_t n, uint32_t *out);

/** 1 when a spill's io failed (the mesh, or what was written of it, is not to be trusted). */
static inline int cm_mesh_spill_failed(const cm_mesh *m) { return m->spill != NULL && m->spill->failed; }

/** How far a mesh is filled: taken before a face is added, it lets a failed face be removed. */
typedef struct cm_mesh_mark {
    uint32_t nverts, nindex, nfaces;
} cm_mesh_mark;

/** The mesh's current fill. */
cm_mesh_mark cm_mesh_save(const cm_mesh *m);

/** Back to a fill taken by cm_mesh_save (everything appended since is dropped). */
void cm_mesh_rollback(cm_mesh *m, const cm_mesh_mark *mark);

/** The first of faces [0, n) whose source face is at least f (the faces in source order: binary search). */
uint32_t cm_mesh_face_from(const cm_mesh *m, uint32_t n, uint32_t f);

/** Bounds of all positions (lo/hi untouched when the mesh is empty; returns 0 then, else 1). */
int cm_mesh_bounds(const cm_mesh *m, float lo[3], float hi[3]);

/** Vertices read at a time by cm_mesh_range_bounds (384 bytes of stack). */
#define CM_MESH_BOUNDS_RUN 32u

/** Bounds of positions [first, first + n) (the GLB's accessors: a face's); as cm_mesh_bounds. */
int cm_mesh_range_bounds(const cm_mesh *m, uint32_t first, uint32_t n, float lo[3], float hi[3]);

/** m->nfaces where its faces, at most cap of them, hold the vertices one after another from 0, each
    once (as the decoder, cm_mesh_place and cm_glb_read make them: a face's box is then its own
    vertices'), else 0. */
uint32_t cm_mesh_faces_in_order(const cm_mesh *m, uint32_t cap);

/** Each face's bounds into box[f] (low x, y, z, then high; an empty face's lower above its upper)
    and the whole mesh's into lo, hi, in one pass (once a model: the viewer's frames fit the camera
    from them, cm_view_fit).  Where the faces hold the vertices one after another from 0, each once,
    and are at most cap: *nboxed = m->nfaces; else 0 and lo, hi from cm_mesh_bounds.  Returns as
    cm_mesh_bounds (the same lo, hi). */
int cm_mesh_face_boxes(const cm_mesh *m, float (*box)[6], uint32_t cap, uint32_t *nboxed, float lo[3], float hi[3]);

#endif /* CM_MESH_H */
