/*
 * cm_rebuild.h - rebuilding a face's surface from the curve mesh and its
 * record: the one entry point the encoder's verification and the
 * terminal's decoder share (spec §2 rule 1).  The methods themselves are
 * modules (cm_method.h).
 */
#ifndef CM_REBUILD_H
#define CM_REBUILD_H

#include "cm/cm_bspline.h"
#include "cm/cm_corner.h"
#include "cm/cm_face_samples.h"
#include "cm/cm_format.h"
#include "cm/cm_geom.h"
#include "cm/cm_gregface.h"
#include "cm/cm_g1fit.h"
#include "cm/cm_nfill.h"

typedef struct cm_rebuild_ws {
    cm_vec3 samples[CM_MAX_FACE_SAMPLES];
    cm_corner_ws corner;
    cm_greg_input gin;
    union {                 /* a face is rebuilt by one method at a time */
        cm_greg_surface greg; /* GREGORY: the rebuilt patches (cm_rebuilt.greg points here) */
        struct {
            cm_nfill_surface nfill; /* NFILL, G1FIT: the rebuilt net (cm_rebuilt.surf views it) */
            union {
                struct {
                    cm_nfill_holes nfill_holes;
                    cm_nfill_ws nfill_ws;
                };
                cm_g1fit_ws g1fit_ws;
            };
        };
    };
} cm_rebuild_ws;

/**
 * What a rebuilt surface is, for the code that evaluates it (tessellation, verification): methods
 * differ in how they build a surface, far less in what they build.
 */
typedef enum cm_repr {
    CM_REPR_FRAME = 0,    /* flat: the face frame's (x, y) (rect, and surf as a bilinear patch) */
    CM_REPR_NURBS = 1,    /* a NURBS surface (surf) the face's loops are projected onto */
    CM_REPR_PATCHES = 2   /* Gregory patches bounded by the loop itself (greg), one region each */
} cm_repr;

/** A rebuilt face surface. */
typedef struct cm_rebuilt {
    int method;
    cm_repr repr;
    double sign;          /* the face normal is sign * (Su x Sv): -1 where the face is flipped */
    cm_frame frame;       /* FRAME: the K11 frame (ez = face normal) */
    double rect[4];       /* FRAME: x0, x1, y0, y1 of the patch in the frame */
    double bbox;          /* diagonal of the face's boundary samples (spec §1 bbox_F) */
    cm_surf surf;         /* FRAME, NURBS: the surface (FRAME: bilinear patch in `plane_ctrl`) */
    cm_vec3 plane_ctrl[4];
    double plane_knots[4];
    const cm_greg_surface *greg; /* PATCHES: the patches (in the workspace); surf is unset */
    uint32_t checksum;    /* PATCHES: FNV-1a of the patches, as computed here */
} cm_rebuilt;

/**
 * Rebuild face f's surface (spec §2 rule 1: the same code on both sides)
 * by its method's module (cm_method.h, decoder/methods/).  A checksum in
 * the record is compared with what was rebuilt (CM_E_CHECKSUM on a
 * mismatch, unless `check` is 0: the encoder's trial rebuilds have no
 * record yet).  `out` points into the model, into itself or into ws.
 */
CM_NODISCARD cm_err cm_rebuild_face(const cm_model *m, uint32_t f, cm_rebuilt *out, cm_rebuild_ws *ws,
                                    cm_status *st);
/** cm_rebuild_face() with the GREGORY checksum check chosen (the encoder's trials pass 0). */
CM_NODISCARD cm_err cm_rebuild_face_ex(const cm_model *m, uint32_t f, int check, cm_rebuilt *out, cm_rebuild_ws *ws,
                                       cm_status *st);

#endif /* CM_REBUILD_H */
