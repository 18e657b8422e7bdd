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

#include <stdint.h>

#include "cm/cm_error.h"

typedef struct cm_mesh_face {
    uint32_t first_vert, nverts;   /* vertices [first_vert, first_vert + nverts) */
    uint32_t first_index, nindex;  /* indices [first_index, first_index + nindex), 3 per triangle, global vertex ids */
    uint32_t rgb;                  /* 0xRRGGBB when has_color */
    uint8_t has_color;
    uint32_t source_face;          /* face number in the model (the .cmz face order) */
} cm_mesh_face;

typedef struct cm_mesh {
    float (*pos)[3];               /* cap_verts positions (mm) */
    float (*nrm)[3];               /* cap_verts unit normals */
    uint32_t *idx;                 /* cap_index vertex indices */
    cm_mesh_face *faces;           /* cap_faces faces */
    uint32_t nverts, cap_verts;
    uint32_t nindex, cap_index;
    uint32_t nfaces, cap_faces;
    /* format 4.3 (cm_mesh_place, cm_place.h): faces [0, nbase_faces), vertices [0, nbase_verts) and
       indices [0, nbase_index) are the model's own, the rest its nplace placed copies, copy k placed
       by place[k] (the GLB writer writes the model's own and shares them between nodes instead) */
    uint32_t nbase_faces, nbase_verts, nbase_index, nplace;
    const struct cm_placement *place;
} cm_mesh;

/** Set the mesh empty (keeps the caller's arrays and capacities). */
void cm_mesh_clear(cm_mesh *m);

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

#endif /* CM_MESH_H */
