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

#if CM_DECODE_STATE_BUDGET <= PTRDIFF_MAX
#define CM_DECODE_STATE_FITS 1

typedef struct cm_decode_state {
    cm_decoder dec;
    cm_tess_ws tess;
    float pos[CM_DECODE_MESH_VERTS][3], nrm[CM_DECODE_MESH_VERTS][3];
    uint32_t idx[CM_DECODE_MESH_INDEX];
    cm_mesh_face faces[CM_MAX_FACES];
} cm_decode_state;

_Static_assert(sizeof(cm_decode_state) <= CM_DECODE_STATE_BUDGET,
               "cm_decode_state is larger than CM_DECODE_STATE_BUDGET: raise the budget in the profile "
               "(fixedcfg/) if the growth is meant, and say so");

/** An empty mesh over s's arrays, with their capacities. */
static inline cm_mesh cm_decode_state_mesh(cm_decode_state *s)
{
    cm_mesh m = {.pos = s->pos,
                 .nrm = s->nrm,
                 .idx = s->idx,
                 .faces = s->faces,
                 .cap_verts = (uint32_t)CM_DECODE_MESH_VERTS,
                 .cap_index = (uint32_t)CM_DECODE_MESH_INDEX,
                 .cap_faces = (uint32_t)CM_MAX_FACES};
    return m;
}
#else
#define CM_DECODE_STATE_FITS 0
#endif

#endif /* CM_DECODE_STATE_H */
