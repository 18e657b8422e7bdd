/*
 * cm_rebuild.h - rebuilding a face's surface from the curve mesh and its
 * record: the one entry point the encoder's verification and the
 * terminal's decoder share (spec §2 rule 1).  This version knows PLANE
 * (spec 5A), GREGORY (spec §6: layouts 0, 1 and 2) and KEEP (the kept
 * surface, already in the model).
 */
#ifndef CM_REBUILD_H
#define CM_REBUILD_H

#include "cm/cm_bspline.h"
#include "cm/cm_corner.h"
#include "cm/cm_format.h"
#include "cm/cm_geom.h"
#include "cm/cm_gregface.h"

typedef struct cm_rebuild_ws {
    cm_vec3 samples[CM_MAX_FACE_SAMPLES];
    cm_corner_ws corner;
    cm_greg_input gin;
    cm_greg_surface greg;   /* GREGORY: the rebuilt patches (cm_rebuilt.greg points here) */
} cm_rebuild_ws;

/** A rebuilt face surface. */
typedef struct cm_rebuilt {
    int method;
    cm_frame frame;       /* PLANE: the K11 frame (ez = face normal) */
    double rect[4];       /* PLANE: x0, x1, y0, y1 of the patch in the frame */
    double bbox;          /* diagonal of the face's boundary samples (spec §1 bbox_F) */
    cm_surf surf;         /* the surface as a NURBS view (PLANE: bilinear patch in `plane_ctrl`) */
    cm_vec3 plane_ctrl[4];
    double plane_knots[4];
    const cm_greg_surface *greg; /* GREGORY: the patches (in the workspace); surf is unset */
    uint32_t checksum;    /* GREGORY: FNV-1a of the patches, as computed here */
} cm_rebuilt;

/**
 * Boundary samples of face f (all loops, loop order, use direction):
 * points at t = s/10, s = 0..9 of every edge use.
 * @param[out] n_outer  samples of the outer loop (the first ones)
 * @return CM_E_LIMIT if the face has more uses than CM_MAX_FACE_EDGES
 */
CM_NODISCARD cm_err cm_face_samples(const cm_model *m, uint32_t f, cm_vec3 *out, int cap, int *n, int *n_outer,
                                    cm_status *st);

/** Diagonal of the axis-aligned box of n > 0 points (spec §1 bbox_F of a face's samples). */
double cm_points_diag(const cm_vec3 *p, int n);

/**
 * Rebuild face f's surface (spec §2 rule 1: the same code on both sides).
 * PLANE: K11 frame of its boundary samples, rectangle of their (x, y)
 * enlarged by 1 % per side, a bilinear patch (spec 5A).  KEEP: the kept
 * surface.  GREGORY: cm_greg_build() on the outer loop (cm_corner.h) with
 * the face's layout, its checksum compared with the record's
 * (CM_E_CHECKSUM on a mismatch, unless `check` is 0: the encoder's trial
 * rebuilds have no record yet).  `out` points into the model, into itself
 * or into ws.
 */
CM_NODISCARD cm_err cm_rebuild_face(const cm_model *m, uint32_t f, cm_rebuilt *out, cm_rebuild_ws *ws,
                                    cm_status *st);
/** cm_rebuild_face() with the GREGORY checksum check chosen (the encoder's trials pass 0). */
CM_NODISCARD cm_err cm_rebuild_face_ex(const cm_model *m, uint32_t f, int check, cm_rebuilt *out, cm_rebuild_ws *ws,
                                       cm_status *st);

#endif /* CM_REBUILD_H */
