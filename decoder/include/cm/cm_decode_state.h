/*
 * cm_decode_state.h - the static storage of one decode: the decoder (which
 * holds the whole .cmz file and the model's pools), the triangulator's
 * workspace and the output mesh, each at this build's limits.  A heap-free
 * program declares one `static cm_decode_state` (cmz-decode, cmz-terminal,
 * the decode fuzz target) and takes the mesh over it with
 * cm_decode_state_mesh().
 *
 * Its size per profile is printed by `--limits` (cm-limits, cmz-decode,
 * cmz-terminal) and held at compile time to CM_DECODE_STATE_BUDGET
 * (fixedcfg/cm_limits.h and the profiles), so that it grows only on purpose.
 *
 * The host profile's state (about 3.1 GiB) is larger than a 32-bit address
 * space: there the struct is not declared and CM_DECODE_STATE_FITS is 0 (the
 * workstation decodes into arrays it sizes itself).
 */
#ifndef CM_DECODE_STATE_H
#define CM_DECODE_STATE_H

#include <stddef.h>
#include <stdint.h>

#include "cm/cm_decode.h"
#include "cm/cm_mesh.h"
#include "cm/cm_tessellate.h"

/* vertices of the decoded mesh at this build's limits: a face of T triangles has at most T + 2 */
#define CM_DECODE_MESH_VERTS ((size_t)CM_MAX_TRIS + 2u * (size_t)CM_MAX_FACES)
/* vertex indices of the decoded mesh: 3 a triangle */
#define CM_DECODE_MESH_INDEX (3u * (size_t)CM_MAX_TRIS)

/* The output mesh's window (issue 15: stream, don't hold): the vertices and indices a program keeps
 * in memory, the rest spilled beside the output (cm_mesh.h, cm_decode_file.h).  At least one call
 * of the tessellation's output: the points of one face's triangulation (MAX_TESS_POINTS) and its
 * triangles (fewer than two a point).  Not a limit of a model: a bigger window only spills less
 * often. */
#ifndef CM_MESH_WINDOW_VERTS
#  define CM_MESH_WINDOW_VERTS ((size_t)CM_MAX_TESS_POINTS)
#endif
#ifndef CM_MESH_WINDOW_INDEX
#  define CM_MESH_WINDOW_INDEX (3u * (size_t)CM_MAX_TESS_TRIS)
#endif
_Static_assert(CM_MESH_WINDOW_VERTS >= CM_MAX_TESS_POINTS && CM_MESH_WINDOW_INDEX >= 3u * (size_t)CM_MAX_TESS_TRIS,
               "the mesh window must hold one face's tessellation");

#if CM_DECODE_STATE_BUDGET <= PTRDIFF_MAX
#define CM_DECODE_STATE_FITS 1

typedef struct cm_decode_state {
    cm_decoder dec;
    cm_tess_ws tess;
    float pos[CM_MESH_WINDOW_VERTS][3], nrm[CM_MESH_WINDOW_VERTS][3]; /* the mesh's window */
    uint32_t idx[CM_MESH_WINDOW_INDEX];
    cm_mesh_face faces[CM_MAX_FACES];
    cm_mesh_spill spill; /* its page cache; the platform sets io and ctx (cm_decode_file.h) */
} cm_decode_state;

_Static_assert(sizeof(cm_decode_state) <= CM_DECODE_STATE_BUDGET,
               "cm_decode_state is larger than CM_DECODE_STATE_BUDGET: raise the budget in the profile "
               "(fixedcfg/) if the growth is meant, and say so");

/** An empty mesh over s's arrays.  With io (the platform's, cm_decode_file.h) the arrays are a
    window and the mesh may hold CM_MAX_TRIS triangles, spilled through io; with io NULL, only what
    the window holds (a decode fuzz target, whose inputs are small). */
static inline cm_mesh cm_decode_state_mesh(cm_decode_state *s, cm_mesh_spill_io *io, void *ctx)
{
    cm_mesh m = {.pos = s->pos,
                 .nrm = s->nrm,
                 .idx = s->idx,
                 .faces = s->faces,
                 .cap_verts = (uint32_t)CM_MESH_WINDOW_VERTS,
                 .cap_index = (uint32_t)CM_MESH_WINDOW_INDEX,
                 .cap_faces = (uint32_t)CM_MAX_FACES};
    if (io) {
        s->spill.io = io;
        s->spill.ctx = ctx;
        cm_mesh_set_spill(&m, &s->spill, (uint32_t)CM_MESH_WINDOW_VERTS, (uint32_t)CM_MESH_WINDOW_INDEX,
                          (uint32_t)CM_DECODE_MESH_VERTS, (uint32_t)CM_DECODE_MESH_INDEX);
    }
    return m;
}
#else
#define CM_DECODE_STATE_FITS 0
#endif

#endif /* CM_DECODE_STATE_H */
