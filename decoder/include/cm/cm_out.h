/*
 * cm_out.h - serialisers of a decoded mesh: binary glTF 2.0 (.glb), binary
 * STL and Wavefront OBJ, written into caller buffers a chunk at a time.
 *
 * Heap-free and I/O-free (the platform layer moves the chunks to a file or
 * a socket): cm_out_begin() chooses the format, then cm_out_next() is called
 * with any buffer size until *done.  The bytes produced do not depend on
 * the buffer sizes used.  All multi-byte values are written little-endian
 * byte by byte (no struct dumps, no host-endianness assumptions).
 *
 * glTF: one mesh, one primitive per face (so faces stay pickable; the
 * face's source_face in the primitive's extras {"face": N}), each with
 * POSITION, NORMAL (float32 VEC3, min/max set on POSITION) and uint32
 * indices rebased to the face's own vertices; a material per distinct face
 * colour (up to CM_OUT_MAX_MATERIALS; a default grey otherwise); the root
 * node's matrix converts CAD millimetres, Z up, to glTF metres, +Y up.
 * Numbers in JSON and OBJ text are cm_fmt_f32's (cm_numfmt.h): 9
 * significant digits that read back as the same float.
 * STL: 80-byte header, facet normals from the triangle, positions in
 * millimetres.  OBJ: `v`/`vn` and `f v//vn` lines, one `g face_N` group per
 * face, millimetres.
 */
#ifndef CM_OUT_H
#define CM_OUT_H

#include <stddef.h>
#include <stdint.h>

#include "cm/cm_error.h"
#include "cm/cm_mesh.h"

typedef enum cm_out_format { CM_OUT_GLB = 0, CM_OUT_STL = 1, CM_OUT_OBJ = 2 } cm_out_format;

#define CM_OUT_MAX_MATERIALS 64 /* GLB: colour materials; faces with further colours get the default grey */

/* serialiser state: a position in the output, no pointers into caller buffers */
typedef struct cm_out {
    cm_out_format fmt;
    const cm_mesh *m;
    uint32_t stage;     /* which part of the file is being written */
    uint32_t item;      /* index inside that part (face, vertex, material, ...) */
    uint32_t sub;       /* position inside the current item (accessor of a face, index or triangle in a face) */
    uint32_t count;     /* elements of the current JSON array written so far (GLB) */
    uint64_t ibase;     /* GLB: indices of the faces before the current one (index buffer view offset / 4) */
    uint64_t written;   /* bytes produced so far */
    uint64_t total;     /* file size when known in advance (GLB, STL), else 0 */
    uint64_t ntris;     /* triangles of all faces */
    uint32_t nprims;    /* faces with triangles (GLB primitives, OBJ groups) */
    uint8_t pending[512]; /* bytes of the current piece not yet copied out */
    uint32_t npending, pending_pos;
    uint32_t json_len, bin_len; /* GLB chunk sizes (JSON without its padding) */
    uint32_t nmaterials;        /* GLB colour materials; the default grey, if used, follows them */
    uint32_t material_rgb[CM_OUT_MAX_MATERIALS];
    uint8_t default_material;   /* GLB: some face uses the default grey */
    /* GLB of a mesh with placed copies (cm_mesh.nplace): the model's own faces as the view `base`
       (w->m points at it: a cm_out is not moved once begun), each copy a node sharing its part's
       primitives; consecutive copies of one part share one mesh (the encoder writes them so) */
    const cm_mesh *whole;
    cm_mesh base;
    uint32_t ord_face, ord;     /* GLB part meshes: face ord_face is primitive ord (counted forwards) */
} cm_out;

/**
 * Start writing mesh m in format fmt.  Validates the whole mesh first, so
 * cm_out_next cannot fail on its content.  Faces without triangles are
 * skipped (no glTF primitive, no OBJ group).  The mesh must not change
 * until the file is complete.
 * @return CM_E_RANGE if the mesh is empty (no triangle) or too large for the
 *         format (e.g. STL's 32-bit triangle count, GLB's 32-bit length), or
 *         a face's vertex/index range or an index lies outside the mesh or
 *         outside the face's own vertices, or a face's index count is not a
 *         multiple of 3;
 *         CM_E_NONFINITE if a position (or, for GLB and OBJ, a normal) is
 *         NaN or infinite;
 *         CM_E_ARG on a bad format, NULL pointers or counts above capacities
 */
CM_NODISCARD cm_err cm_out_begin(cm_out *w, cm_out_format fmt, const cm_mesh *m, cm_status *st);

/**
 * Write the next bytes into buf (cap > 0): *n bytes written, *done = 1
 * when the file is complete (then *n may be 0).  Fills buf completely
 * unless the file ends.
 * @return CM_E_ARG on NULL pointers, cap == 0 or a writer not begun;
 *         CM_E_FORMAT if the output disagrees with the size announced at
 *         cm_out_begin (the mesh changed while writing)
 */
CM_NODISCARD cm_err cm_out_next(cm_out *w, uint8_t *buf, size_t cap, size_t *n, int *done, cm_status *st);

/** Exact size of the file for GLB and STL (0 for OBJ, whose size is known only at the end). */
uint64_t cm_out_size(const cm_out *w);

#endif /* CM_OUT_H */
