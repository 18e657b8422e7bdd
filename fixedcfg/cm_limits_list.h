/*
 * cm_limits_list.h - the one list that yields the run-time limits table.
 *
 * X(id, value, hard_max, unit, doc): `id` names the limit in messages
 * ("model needs MAX_FACES=20000, this build has 16384"), `value` is the
 * macro from cm_limits.h, `hard_max` its format or type ceiling.
 * cm_limit_info[] (decoder/src/cm_limits.c), `--limits`, `make
 * print-limits`, the file header's `need` table and the link protocol's
 * HELLO all iterate this list, so adding a limit here adds it everywhere.
 * Append new limits at the end: the position is the limit id on the wire.
 */
#ifndef CM_LIMITS_LIST_H
#define CM_LIMITS_LIST_H

#include "cm_limits.h"

#define CM_LIMITS(X)                                                                          \
    X(MAX_DEGREE, CM_MAX_DEGREE, CM_HARD_MAX_DEGREE, "degree",                                 \
      "polynomial degree of a curve or of a surface in one direction")                       \
    X(MAX_EDGE_CTRL, CM_MAX_EDGE_CTRL, CM_HARD_MAX_COUNT16, "points",                          \
      "control points of one edge curve")                                                     \
    X(MAX_SURF_CTRL_DIR, CM_MAX_SURF_CTRL_DIR, CM_HARD_MAX_COUNT16, "points",                  \
      "control points of one surface in one direction")                                       \
    X(MAX_SURF_CTRL, CM_MAX_SURF_CTRL, CM_HARD_MAX_COUNT24, "points",                          \
      "control points of one surface in total")                                               \
    X(MAX_FIT_CTRL, CM_MAX_FIT_CTRL, CM_HARD_MAX_FIT_CTRL, "points",                           \
      "control points per direction of a fitted (NFILL/G1FIT) surface")                       \
    X(MAX_LOOPS, CM_MAX_LOOPS, CM_HARD_MAX_COUNT16, "loops",                                   \
      "loops of one face (outer loop + holes)")                                               \
    X(MAX_LOOP_EDGES, CM_MAX_LOOP_EDGES, CM_HARD_MAX_COUNT16, "edges",                         \
      "edge uses in one loop")                                                                \
    X(MAX_FACE_EDGES, CM_MAX_FACE_EDGES, CM_HARD_MAX_COUNT16, "edges",                         \
      "edge uses in one face, all loops")                                                     \
    X(MAX_SIDES, CM_MAX_SIDES, CM_HARD_MAX_SIDES, "sides",                                     \
      "sides of a face rebuilt by Gregory N-split")                                           \
    X(MAX_GREG, CM_MAX_GREG, CM_HARD_MAX_GREG, "patches",                                      \
      "Gregory patches of one rebuilt face")                                                  \
    X(MAX_LSQ_UNKNOWNS, CM_MAX_LSQ_UNKNOWNS, CM_HARD_MAX_LSQ_UNKNOWNS, "unknowns",             \
      "unknown control points of a least-squares surface")                                    \
    X(MAX_LSQ_BAND, CM_MAX_LSQ_BAND, CM_HARD_MAX_LSQ_BAND, "columns",                          \
      "half bandwidth of the surface normal equations")                                       \
    X(MAX_FACES, CM_MAX_FACES, CM_HARD_MAX_COUNT24, "faces", "faces of one model")             \
    X(MAX_EDGES, CM_MAX_EDGES, CM_HARD_MAX_COUNT24, "edges", "edges of one model's curve mesh") \
    X(MAX_VERTICES, CM_MAX_VERTICES, CM_HARD_MAX_COUNT24, "vertices",                          \
      "vertices of one model's curve mesh")                                                   \
    X(MAX_TRIS, CM_MAX_TRIS, CM_HARD_MAX_TRIS, "triangles", "triangles of the decoded mesh")   \
    X(STACK_FN_MAX, CM_STACK_FN_MAX, CM_HARD_MAX_STACK, "bytes",                               \
      "stack frame of one decoder or kernel function")                                        \
    X(STACK_BUDGET, CM_STACK_BUDGET, CM_HARD_MAX_STACK, "bytes",                               \
      "deepest decoder/kernel call path, summed frames")                                      \
    X(MAX_TESS_POINTS, CM_MAX_TESS_POINTS, CM_HARD_MAX_COUNT24, "points",                      \
      "points triangulated for one face (boundary and interior)")                             \
    X(MAX_FILE_BYTES, CM_MAX_FILE_BYTES, 2147483647u, "bytes", "size of one .cmz file")       \
    X(MAX_MODEL_CTRL, CM_MAX_MODEL_CTRL, CM_HARD_MAX_COUNT24, "points",                        \
      "control points of all curves and kept surfaces of a model")                            \
    X(MAX_MODEL_KNOTS, CM_MAX_MODEL_KNOTS, CM_HARD_MAX_COUNT24, "knots",                       \
      "knots of all curves and kept surfaces of a model")                                     \
    X(MAX_MODEL_LOOPS, CM_MAX_MODEL_LOOPS, CM_HARD_MAX_COUNT24, "loops", "loops of all faces of a model") \
    X(MAX_MODEL_USES, CM_MAX_MODEL_USES, CM_HARD_MAX_COUNT24, "uses",                          \
      "edge uses of all loops of a model")                                                    \
    X(MAX_EDGE_SAMPLES, CM_MAX_EDGE_SAMPLES, CM_HARD_MAX_COUNT16, "points",                    \
      "points sampled on one edge for tessellation")                                          \
    X(MAX_PLACEMENTS, CM_MAX_PLACEMENTS, CM_HARD_MAX_COUNT24, "copies",                        \
      "placed copies of a model's parts (instances, format 4.3)")

#endif /* CM_LIMITS_LIST_H */
