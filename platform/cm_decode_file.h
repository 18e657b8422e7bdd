/*
 * cm_decode_file.h - .cmz file -> triangle mesh -> .glb/.stl/.obj file,
 * the decode path of both the workstation (`cmz decode`) and the terminal
 * (`cmz-decode`, cmz-terminal).  Plain POSIX I/O (open/read/write), no
 * stdio streams and no heap: the caller owns the decoder, the tessellation
 * workspace and the mesh arrays (static on the terminal).  The output is
 * written to a temporary file beside the target, synced and renamed into
 * place, so a viewer never sees half a model and an error never destroys
 * the previous one.
 */
#ifndef CM_DECODE_FILE_H
#define CM_DECODE_FILE_H

#include "cm/cm_decode.h"
#include "cm/cm_out.h"
#include "cm/cm_tessellate.h"

/** Faces left out whose reasons a summary keeps (the count goes on beyond). */
#define CM_DECODE_LEFT_OUT_LIST 8

typedef struct cm_decode_summary {
    uint32_t faces, triangles, vertices;       /* faces: of the model; triangles, vertices: of the mesh */
    uint32_t faces_plane, faces_gregory, faces_keep; /* faces in the mesh, by method */
    uint32_t faces_left_out;                   /* faces whose tessellation failed: not in the mesh */
    cm_status left_out[CM_DECODE_LEFT_OUT_LIST]; /* why, for the first of them: code, face, byte offset */
    double tess_tol;
    uint64_t out_bytes;
    double max_gap;
} cm_decode_summary;

/** Output format from a file name's extension (.glb, .stl, .obj); -1 if none matches. */
int cm_out_format_of(const char *path);

/**
 * Read and decode `in_path` into dec (fed in chunks), check it.
 * @return the decoder's errors; CM_E_IO (with errno) for the file
 */
CM_NODISCARD cm_err cm_decode_read(const char *in_path, cm_decoder *dec, cm_status *st);

/**
 * Tessellate every face of dec's model into mesh (tol <= 0: the file's
 * recommended chordal tolerance).
 *
 * One bad face never sinks a model: a face whose tessellation fails is left
 * out (the mesh is rolled back to where it was before that face), counted
 * in sum->faces_left_out, and the first CM_DECODE_LEFT_OUT_LIST of them are
 * kept in sum->left_out (each status names the face, its record's byte
 * offset and the cause) for the caller to report as warnings.  Only these
 * end the decode: CM_E_LIMIT (the mesh is full, or the face exceeds this
 * build), CM_E_NOMEM and CM_E_IO, with the face named in the status; and a
 * model with faces left out and no triangle left fails with its first left-
 * out face's error (there is nothing to show).
 */
CM_NODISCARD cm_err cm_decode_mesh(const cm_decoder *dec, double tol, cm_mesh *mesh, cm_tess_ws *ws,
                                   cm_decode_summary *sum, cm_status *st);

/** Write mesh to out_path atomically (temporary file, fsync, rename) in `fmt`. */
CM_NODISCARD cm_err cm_write_mesh(const cm_mesh *mesh, cm_out_format fmt, const char *out_path, uint64_t *bytes,
                                  cm_status *st);

#endif /* CM_DECODE_FILE_H */
