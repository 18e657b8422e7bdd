/*
 * cm_tessellate.h - a decoded model's faces as triangles:
 * every edge sampled once (the same points for both faces that share it),
 * the samples mapped into each face's parameter domain, the trimmed region
 * triangulated with its holes (cm_tess.h), interior points added where the
 * surface curves, so that no triangle is farther than the chordal
 * tolerance from the surface.  Watertight along shared edges by
 * construction: a boundary vertex is the edge's own point, bit for bit.
 *
 * Heap-free: the caller owns the workspace (static on the terminal) and
 * the mesh arrays; faces are appended to the mesh one by one.
 */
#ifndef CM_TESSELLATE_H
#define CM_TESSELLATE_H

#include "cm/cm_format.h"
#include "cm/cm_mesh.h"
#include "cm/cm_param.h"
#include "cm/cm_rebuild.h"
#include "cm/cm_tess.h"

typedef struct cm_tess_ws {
    cm_rebuild_ws rb;
    cm_param_ws pw;
    cm_tri_ws tri;
    cm_vec3 bpts[CM_MAX_TESS_POINTS];      /* boundary points in 3D, all loops */
    cm_vec2 uv[CM_MAX_TESS_POINTS];        /* points to triangulate: boundary, then interior */
    int src[CM_MAX_TESS_POINTS];           /* boundary uv point -> bpts index */
    int loop_start[CM_MAX_LOOPS + 2];
    int loop_bstart[CM_MAX_LOOPS + 2];     /* loops' first bpts index */
    int wind_u[CM_MAX_LOOPS], wind_v[CM_MAX_LOOPS];
    cm_vec2 tmp[CM_MAX_TESS_POINTS];       /* polygon joins; scaled (u,v) for the triangulator */
    int src2[CM_MAX_TESS_POINTS];          /* polygon joins: sources of the joined points */
    int ssrc[CM_MAX_TESS_POINTS];          /* polygon joins: sources of the winding loops' copies */
    cm_vec3 xyz[CM_MAX_TESS_POINTS];       /* refinement: 3D position of each triangulation point */
    cm_vec3 nrm[CM_MAX_TESS_POINTS];       /* ... and its unit normal, where has_nrm (the evaluation
                                              that gave xyz gave it: not evaluated again) */
    unsigned char has_nrm[CM_MAX_TESS_POINTS];
    int use_first[CM_MAX_LOOP_EDGES];      /* outer loop: each use's first bpts index and sample count */
    int use_n[CM_MAX_LOOP_EDGES];
    int tris[CM_MAX_TESS_TRIS][3];
    uint32_t vmap[CM_MAX_TESS_POINTS];     /* triangulation point -> mesh vertex (or UINT32_MAX) */
    double ts[CM_MAX_EDGE_SAMPLES];
    cm_vec3 epts[CM_MAX_EDGE_SAMPLES];     /* an edge's points at ts (cm_edge_params) */
    uint64_t passed[2][CM_TESS_PASS_SLOTS]; /* refinement: pieces that passed, last round and this */
    uint32_t pass_slots;                   /* slots of each used at most: 0 = all; 1 = none (tests
                                              compare the output with and without) */
    long tested, skipped;                  /* refinement's deviation tests this face: run, and spared
                                              because the piece passed the round before */
    long predicted;                        /* ... and spared because its corners' normals predict it
                                              flat (format 4.8) */
    int point_cap;                         /* the face's budget of points (cm_tess_point_cap), set by
                                              cm_tessellate_face */
    int folded;                            /* the region's last triangulation needed the fold
                                              fallback (its boundary crosses itself by rounding) */
    int refine_47;                         /* the refinement of format 4.7 (cm_model.refine_47), set
                                              likewise */
    int refine_48;                         /* ... and of format 4.8 (cm_model.refine_48) */
    int refine_49;                         /* ... and of format 4.9 (cm_model.refine_49) */
    int refine_410;                        /* ... and of format 4.10 (cm_model.refine_410) */
    int test_every_piece;                  /* tests: 1 turns format 4.8's predicted passes off (on
                                              smooth models the mesh must not change) */
    cm_egreg_memo egreg_memo;              /* the exact patch being meshed: its side evaluations
                                              (cm_egreg.h; the same bits, fewer evaluations) */
} cm_tess_ws;

/** Statistics of one face's tessellation (for the encoder's needs and for tests). */
typedef struct cm_tess_info {
    int points;       /* points handed to the triangulator */
    int triangles;
    int max_edge_samples;
    double max_gap;   /* largest distance of a boundary point to a kept surface */
    long tested;      /* refinement: pieces (triangles, inner sides) tested against the surface */
    long skipped;     /* ... and passed again untested: they passed in the round before */
    long predicted;   /* ... and passed untested: their corners' normals predict them flat (4.8) */
} cm_tess_info;

/**
 * The work on one face is bounded by what the file's header declares (the
 * encoder measured it with this code at the file's tolerance), not only by
 * this build's limits: at most cm_tess_point_cap() points per face (per
 * patch of a GREGORY face) and cm_tess_edge_sample_cap() samples per edge.
 * Both are twice the declared need plus a margin (times 4 r^2 when `tol`
 * is r times finer than the file's), at most the build's limit (the limit
 * itself when the need is 0, i.e. not declared).  A valid file never comes
 * near them, so its output does not depend on them; a damaged face stops
 * there: its refinement ends, or it fails with CM_E_RANGE (CM_E_LIMIT when
 * the cap is the build's limit).
 */
int cm_tess_point_cap(const cm_model *m, double tol);
int cm_tess_edge_sample_cap(const cm_model *m, double tol);
/** The same bound on the triangles of the whole model (the declared MAX_TRIS, a
    margin of 1024): cm_decode_mesh() stops the model there (CM_E_RANGE). */
int cm_tess_triangle_cap(const cm_model *m, double tol);

/**
 * Parameters t in [0,1] sampling edge e so that every chord is within
 * `tol` of the curve (uniform in t, doubled until it holds).
 * @param[out] ts  n + 1 values, ts[0] = 0, ts[n] = 1 (cap entries available)
 * @param[out] pts NULL, or the curve's n + 1 points at ts, in the curve's direction: the bits
 *                 cm_curve_eval gives there (the last round's own evaluations, where it tested
 *                 its chords: a caller that wants the points need not evaluate them again)
 * At most min(cap, CM_MAX_EDGE_SAMPLES, cm_tess_edge_sample_cap(m, tol))
 * values: where the chords would need more, the densest allowed sampling is
 * returned (the same for every face that uses the edge).
 * @return CM_OK, or the curve's evaluation errors
 */
CM_NODISCARD cm_err cm_edge_params(const cm_model *m, uint32_t e, double tol, double *ts, cm_vec3 *pts, int cap,
                                   int *n, cm_status *st);

/**
 * Rebuild face f and append its triangles to `mesh` (one cm_mesh_face).
 * @param tol  chordal tolerance in mm (the file's tess_tol, or the viewer's)
 * @return CM_E_LIMIT when the face needs more than CM_MAX_TESS_POINTS or
 *         the mesh more than its capacity (CM_MAX_TRIS); CM_E_RANGE when it
 *         needs more points than the header declares (cm_tess_point_cap);
 *         errors of the rebuild, the projection or the triangulation
 *         otherwise.  On failure the status names the face (st->face = f)
 *         and, unless a more precise one is known, its record's byte offset
 *         (st->offset = faces[f].rec_off).  The mesh may then hold part of
 *         the face's vertices and indices (no face record): cm_mesh_rollback()
 *         removes them.
 */
CM_NODISCARD cm_err cm_tessellate_face(const cm_model *m, uint32_t f, double tol, cm_mesh *mesh, cm_tess_ws *ws,
                                       cm_tess_info *info, cm_status *st);

#endif /* CM_TESSELLATE_H */
