/*
 * cm_glb_read.h - a binary glTF 2.0 file (.glb) as the viewer's mesh (issue 17: `cmz-view MODEL.glb`),
 * so that a person with the GLB `cmz decode` wrote, or one from another tool, sees it as the
 * terminal draws a .cmz.
 *
 * Read: the JSON chunk (streamed through a window, parsed without recursion: accessors, buffer views,
 * meshes and their primitives, materials, nodes, scenes) and the BIN chunk (each primitive's
 * POSITION, NORMAL and indices, read where its accessors say).  Each node of the scene that holds a
 * mesh places its primitives (its matrix, or translation, rotation and scale, times its parents')
 * as faces of the mesh, in the scene's order (breadth first: `cmz decode`'s model, then its placed
 * copies), turned from glTF's metres with Y up into CAD millimetres with Z up (x, -z, y) x 1000, the
 * viewer's axes; each such node is a part of the model (the assembly steps).  A face's colour is its
 * material's baseColorFactor (times 255, rounded); none without a material, or with the material
 * `cmz decode` names "default" for faces without colour.  A primitive without NORMAL gets the
 * normals of its triangles summed at each vertex.  The model filled alongside has the faces and
 * their parts only: no edges (a GLB has no curve mesh; the viewer draws the silhouettes), nothing
 * closed (its back faces are drawn).
 *
 * Not read (refused by name, CM_E_FORMAT): a buffer other than the BIN chunk (a uri), sparse
 * accessors, POSITION or NORMAL that is not float VEC3, indices that are not unsigned SCALAR, a node
 * with two parents.  Primitives that are not triangles (points, lines, strips, fans) are left out
 * and counted.  Over fixedcfg's CM_GLB_MAX_* or the mesh's capacity: CM_E_LIMIT with what the file
 * needs and what the build has.
 *
 * Contract: no heap, no recursion, no libc number parsing (glibc's strtod may allocate); work
 * bounded by the file's length and the build's limits.
 */
#ifndef CM_GLB_READ_H
#define CM_GLB_READ_H

#include <stdint.h>

#include "cm/cm_error.h"
#include "cm/cm_format.h"
#include "cm/cm_mesh.h"
#include "cm_limits.h"

/** Read n bytes at byte off of the file into buf: 0, or -1 (an I/O error). */
typedef int cm_glb_src_fn(void *ctx, uint64_t off, void *buf, size_t n);

#define CM_GLB_WINDOW 8192 /* bytes of the file held at a time */
#define CM_GLB_MAX_DEPTH 12 /* JSON levels tracked (deeper ones are skipped: nothing glTF's core puts there) */

typedef struct cm_glb_accessor {
    uint32_t view, offset, count; /* view: UINT32_MAX when it has none */
    uint16_t ctype;               /* componentType (5121 ubyte, 5123 ushort, 5125 uint, 5126 float) */
    uint8_t ncomp;                /* 1 SCALAR, 3 VEC3, ... (0: another type) */
    uint8_t sparse;
} cm_glb_accessor;

typedef struct cm_glb_view {
    uint32_t buffer, offset, length, stride; /* stride 0: tightly packed */
} cm_glb_view;

typedef struct cm_glb_prim {
    int32_t pos, nrm, idx, material; /* accessors and material, -1 when absent */
    uint32_t mesh;
    uint8_t mode;
} cm_glb_prim;

typedef struct cm_glb_node {
    int32_t mesh, parent;
    double m[16];           /* glTF's local matrix, column-major; else from t, r, s */
    double t[3], r[4], s[3];
    uint8_t has_matrix;
} cm_glb_node;

typedef struct cm_glb_jframe {
    uint8_t object;  /* 1: an object (key is its current key), 0: an array (index is its element) */
    uint8_t key;
    uint32_t index;
} cm_glb_jframe;

typedef struct cm_glb_reader {
    cm_glb_src_fn *src;
    void *ctx;
    uint64_t file_len, bin_off, bin_len;
    uint64_t win_off;
    uint32_t win_n;
    uint8_t win[CM_GLB_WINDOW];
    uint32_t naccessors, nviews, nprims, nnodes, nmaterials, nroots, nmeshes;
    int32_t scene;                    /* the "scene" field, -1 when none */
    uint32_t buffer0_uri;             /* the first buffer names a uri (not the BIN chunk) */
    cm_glb_accessor accessors[CM_GLB_MAX_ACCESSORS];
    cm_glb_view views[CM_GLB_MAX_VIEWS];
    cm_glb_prim prims[CM_GLB_MAX_PRIMS];
    cm_glb_node nodes[CM_GLB_MAX_NODES];
    uint32_t material_rgb[CM_GLB_MAX_MATERIALS];
    uint8_t material_color[CM_GLB_MAX_MATERIALS]; /* 0: no colour (the "default" material) */
    uint32_t root_scene[CM_GLB_MAX_NODES], root_node[CM_GLB_MAX_NODES]; /* scenes[s].nodes, flat */
    /* the scene's traversal: nodes in breadth-first order, each one's matrix to the model */
    uint32_t order[CM_GLB_MAX_NODES];
    double world[CM_GLB_MAX_NODES][16];
    uint32_t first_child[CM_GLB_MAX_NODES + 1], child[CM_GLB_MAX_NODES];
    uint8_t seen[CM_GLB_MAX_NODES];
    uint32_t mesh_first[CM_GLB_MAX_PRIMS + 1]; /* mesh i's primitives: [mesh_first[i], mesh_first[i + 1]) */
    cm_glb_jframe frame[CM_GLB_MAX_DEPTH];
    uint32_t skipped_prims;           /* primitives that are not triangles, left out */
} cm_glb_reader;

/** 1 when the first 4 bytes are a GLB's magic "glTF". */
int cm_glb_sniff(const uint8_t head[4]);

/**
 * Read the .glb of file_len bytes that src reads into mesh (cleared first; its spill, if any, takes
 * what does not fit its arrays) and model (the faces' parts: cm_view_parts steps through the nodes).
 * @return CM_OK; CM_E_FORMAT / CM_E_TRUNCATED / CM_E_RANGE for a malformed file, CM_E_LIMIT over
 *         the build's limits, CM_E_IO when src fails; st says where
 */
CM_NODISCARD cm_err cm_glb_read(cm_glb_reader *g, cm_glb_src_fn *src, void *ctx, uint64_t file_len, cm_mesh *mesh,
                                cm_model *model, cm_status *st);

#endif /* CM_GLB_READ_H */
