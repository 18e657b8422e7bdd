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
#include "cm/cm_decode_state.h"
#include "cm/cm_out.h"
#include "cm/cm_place.h"
#include "cm/cm_tessellate.h"

/** Faces left out whose reasons a summary keeps (the count goes on beyond). */
#define CM_DECODE_LEFT_OUT_LIST 8

typedef struct cm_decode_summary {
    uint32_t faces, triangles, vertices;       /* faces: of the model; triangles, vertices: of the mesh */
    uint32_t placed_faces;                     /* faces of the mesh: the model's and its placed copies' (4.3) */
    uint32_t faces_by_method[CM_METHOD_COUNT]; /* faces in the mesh, by method number */
    uint32_t faces_left_out;                   /* faces whose tessellation failed: not in the mesh */
    cm_status left_out[CM_DECODE_LEFT_OUT_LIST]; /* why, for the first of them: code, face, byte offset */
    double tess_tol;
    uint64_t out_bytes;
    double max_gap;
} cm_decode_summary;

/** Output format from a file name's extension (.glb, .stl, .obj); -1 if none matches. */
int cm_out_format_of(const char *path);

/**
 * s's mesh, streaming: its arrays a window, the rest spilled into unlinked files (created at the
 * first spill, gone when closed or when the program ends) in out_path's directory, or in out_path
 * when is_dir.  Closes the files of an earlier mesh.
 */
cm_mesh cm_decode_stream_mesh(cm_decode_state *s, const char *out_path, int is_dir);

/** Close the spill files (the mesh they held is gone). */
void cm_decode_spill_close(void);

/** cm_dec_read_fn over the file descriptor *(int *)ctx (pread). */
int cm_decode_pread(void *ctx, uint32_t off, uint8_t *buf, size_t n);

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

/**
 * Write mesh to out_path atomically in `fmt`: a temporary file beside it, renamed into place, so no
 * reader ever sees half a mesh and a failure leaves the previous file.  `sync`: fsync the file
 * before the rename, which a power cut then cannot undo (as gzip's --synchronous; 0.5 ms on this
 * VM's disk, 10-200 ms on an SD card, for a file the .cmz can make again).
 */
CM_NODISCARD cm_err cm_write_mesh(const cm_mesh *mesh, cm_out_format fmt, const char *out_path, int sync,
                                  uint64_t *bytes, cm_status *st);

/**
 * What cm_write_mesh_at has just done to its file: "created", "written" (its first chunk, up to
 * 64 KiB) or "closed" (all of it written, synced and closed).  cmz-terminal's fault injection
 * (cm_kill_point.h) stops there.
 */
typedef void cm_write_step(void *ctx, const char *step);

/**
 * Write mesh in `fmt` as the new file `name` in directory dirfd: created exclusively, written,
 * fsynced; no temporary file and no rename, for a directory that no viewer sees yet (cmz-terminal's
 * next generation, made visible as a whole).  On failure the file is removed.  step (may be NULL)
 * is called with ctx after each stage.
 */
CM_NODISCARD cm_err cm_write_mesh_at(const cm_mesh *mesh, cm_out_format fmt, int dirfd, const char *name,
                                     uint64_t *bytes, cm_write_step *step, void *ctx, cm_status *st);

/* cm_out_bytes_bound: the JSON of one glTF primitive and its three accessors (with min/max) takes
   about 440 bytes in the corpus, 768 leave room for the longest numbers; the fixed JSON and 64
   materials stay under 32 KiB */
#define CM_OUT_GLB_FACE_BYTES 768u
#define CM_OUT_GLB_FIXED_BYTES 32768u
#define CM_OUT_BYTES_PER_CMZ_BYTE 256u

/**
 * How large the GLB (or STL) that a .cmz of cmz_bytes decodes to on this build can be, for a
 * free-space check before the file has arrived (nothing but its size is known then): the smaller of
 *  - what this build's mesh holds (cm_decode_state's arrays): CM_MAX_TRIS triangles, CM_MAX_TRIS +
 *    2 CM_MAX_FACES vertices of 24 bytes, 12 bytes of indices a triangle and one primitive of
 *    CM_OUT_GLB_FACE_BYTES JSON per face (STL: 50 bytes a triangle); a true bound, 32 MB for the
 *    terminal profile, too much to ask of every small model;
 *  - CM_OUT_BYTES_PER_CMZ_BYTE (256) times the .cmz (STL twice that): the bundled and corpus models
 *    at their own tolerance make at most 140 GLB bytes per .cmz byte (bug22869 Spring; 60 among
 *    those the terminal profile loads) and STL 283.
 * The second is a measured factor, not a bound: a model that tessellates finer than any seen (or a
 * terminal run with a finer --tess) can exceed it.  Then the disk may fill while the model is
 * stored, and the store fails without touching the model on screen.
 */
static inline uint64_t cm_out_bytes_bound(cm_out_format fmt, uint64_t cmz_bytes)
{
    uint64_t tris = CM_MAX_TRIS, verts = CM_DECODE_MESH_VERTS;
    uint64_t cap = fmt == CM_OUT_STL ? 84u + 50u * tris
                                     : CM_OUT_GLB_FIXED_BYTES + 24u * verts + 12u * tris +
                                           (uint64_t)CM_OUT_GLB_FACE_BYTES * CM_MAX_FACES;
    uint64_t seen = (fmt == CM_OUT_STL ? 2u : 1u) * CM_OUT_BYTES_PER_CMZ_BYTE * cmz_bytes;
    return seen < cap ? seen : cap;
}

/** The static storage of this file's reader and writer (their I/O chunks), for `--limits`. */
size_t cm_decode_file_static_bytes(void);
/** ... of them, what a program that reads and decodes but writes no mesh links (cmz-view): the
 *  reader's chunk and the mesh spill's files. */
size_t cm_decode_file_read_static_bytes(void);

#endif /* CM_DECODE_FILE_H */
