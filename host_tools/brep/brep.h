/*
 * brep.h - the workstation's boundary representation: faces, each an exact
 * NURBS surface with an outer loop and holes made of 3D boundary curves.
 *
 * Every input form lands here the same way: IGES 144 trimmed surfaces,
 * 143 bounded surfaces, 186/514/510 B-rep solids and untrimmed surfaces
 * (a face bounded by its parameter rectangle).  Topology (shared edges) is
 * not part of this layer: IGES 144 files share nothing, so the curve mesh
 * (mesh/cmesh.h) derives it for all inputs alike.
 *
 * A loop is a sequence of segments, each an owned curve traversed over its
 * whole domain in loop direction (importers cut and reverse as needed).
 * Orientation (spec §1): walking along a loop with the face normal towards
 * the viewer, the material is on the left; the outer loop runs
 * counter-clockwise, holes clockwise.  The face normal is Su x Sv, negated
 * when `flip` is set.  brep_orient_loops (face_domain.c) enforces this.
 */
#ifndef BREP_H
#define BREP_H

#include <stddef.h>
#include <stdint.h>

#include "geom/hbox.h"
#include "geom/hnurbs.h"

typedef struct brep_loop {
    int first, n; /* segments [first, first + n) */
} brep_loop;

/* brep_face.src_type of a face read from STEP (src_de is then its #n) */
#define BREP_SRC_STEP_FACE (-1)

typedef struct brep_face {
    int surf;             /* index into surfs */
    int first_loop, nloops; /* loops[first_loop] is the outer loop */
    int natural;          /* the outer loop is the surface's parameter rectangle */
    int flip;             /* face normal = -(Su x Sv) */
    int has_color;
    uint32_t rgb;         /* 0xRRGGBB when has_color */
    int src_de, src_type; /* the IGES entity that made the face (144, 143, 510, or a surface; its DE),
                             or BREP_SRC_STEP_FACE and the STEP face's #n */
    int surf_type;        /* IGES type of its base surface (128, 120, 190, ...) */
    int shell;            /* index of its shell (186/514), -1 if none */
    int instance;         /* outermost subfigure instance (408) placing it, 0 for none */
    /* its part, for the terminal's assembly steps (host_tools/encode/parts.c): */
    int top;              /* the import's ordinal of the top-level entity that placed it (parts in
                             file order) */
    int owner;            /* the entity that names its part: IGES the outermost 408 instance, else
                             the 186 solid or 514 shell, else a 402 group listing the face (DEs);
                             STEP the solid's or shell's #n; 0: none (a loose face) */
    int product;          /* STEP: the #n of the PRODUCT its representation shapes (its part's name,
                             the solid's own usually being empty); 0: none, and for IGES */
    /* a band cut open along its seam (brep_seam.h): its loops before the cut, and whether it may be
       cut (again) */
    int cut_from_loop, cut_from_nloops; /* cut_from_nloops 0: not cut */
    int no_cut;
} brep_face;

/* an outermost subfigure instance (IGES 408) as imported: its faces carry its id */
typedef struct brep_instance {
    int id;      /* brep_face.instance of the faces it places */
    int def_de;  /* the DE of its subfigure definition (308) */
    haffine xf;  /* definition -> model (millimetres) */
} brep_instance;

/* a copy of an instance's faces folded out of the model (brep_fold_instances): the faces of instance
   `proto`, placed by xf (model -> model), are the copy */
typedef struct brep_placement {
    int proto;   /* the instance id (brep_face.instance) of the faces placed */
    int nfaces;  /* how many faces the copy had */
    haffine xf;
    int top, owner, product; /* its own instance's (brep_face.top, .owner, .product of the faces it had) */
} brep_placement;

typedef struct brep_model {
    hsurf *surfs;
    int nsurfs, capsurfs;
    brep_face *faces;
    int nfaces, capfaces;
    brep_loop *loops;
    int nloops, caploops;
    hcurve *segs;
    int nsegs, capsegs;
    int nshells;
    hbox box;             /* of all boundary curves (millimetres) */
    double resolution_mm; /* the file's minimum resolution, converted; 0 if none */
    int faces_failed;     /* faces skipped because they could not be built (warned) */
    brep_instance *instances; /* outermost subfigure instances, in import order */
    int ninstances, capinstances;
    brep_placement *placements; /* copies folded out (brep_fold_instances) */
    int nplacements;
    int placed_faces;     /* faces those copies had */
    hbox placed_box;      /* the box of the model before folding (its diagonal stays the model's) */
    int entities_failed;  /* solids, shells and instances left out because they could not be read (warned) */
} brep_model;

void brep_free(brep_model *m);

/**
 * What made face f, for messages: "entity 144 (DE 57)" for IGES, "ADVANCED_FACE #57" for STEP.
 * Returns buf.
 */
const char *brep_face_source(const brep_face *f, char *buf, size_t cap);

/** Diagonal of the model box (0 for an empty model). */
double brep_diag(const brep_model *m);

/**
 * The model's geometric tolerance (vertex merging, projection acceptance):
 * 1e-6 of the diagonal (spec 5.1), or the file's declared resolution when
 * that is coarser, capped at 1e-4 of the diagonal.  Never absolute.
 */
double brep_tolerance(const brep_model *m);

/* building blocks for importers (all return CM_OK or an allocation error) */
CM_NODISCARD cm_err brep_add_surf(brep_model *m, hsurf *s, int *index, cm_status *st); /* moves s */
CM_NODISCARD cm_err brep_add_seg(brep_model *m, hcurve *c, cm_status *st);             /* moves c */
CM_NODISCARD cm_err brep_add_loop(brep_model *m, int first_seg, int nseg, cm_status *st);
CM_NODISCARD cm_err brep_add_face(brep_model *m, const brep_face *f, cm_status *st);

/**
 * The loop of a face bounded by its surface's parameter rectangle (an untrimmed surface): the four
 * iso-curves counter-clockwise in (u, v), collapsed sides (poles) left out; box grows by them.
 */
CM_NODISCARD cm_err brep_add_rect_loop(brep_model *m, int surf, hbox *box, cm_status *st);
/** Length of a curve by 64 chords (for "is this boundary piece degenerate"). */
double brep_curve_length(const hcurve *c);

CM_NODISCARD cm_err brep_add_instance(brep_model *m, const brep_instance *in, cm_status *st);

/**
 * Fold placed copies out of m: of the outermost instances of one subfigure definition, the first
 * stays (the prototype) and every other whose faces are the prototype's moved by one affine map
 * (the same entities in the same order, surfaces and boundary curves within the model's tolerance,
 * the same colours and sides) is removed and listed in m->placements.  Instances whose faces differ
 * (one failed to import, a member's own colour) stay as they are.  The model's box stays the
 * whole's (m->placed_box).  Returns the copies folded in *folded (may be NULL).
 */
CM_NODISCARD cm_err brep_fold_instances(brep_model *m, int *folded, cm_status *st);

/** Roll the model back to the given counts (drops a half-built face). */
void brep_truncate(brep_model *m, int nsurfs, int nfaces, int nloops, int nsegs);

/**
 * Remove the faces with drop[f] != 0 (drop has m->nfaces entries) with their surfaces, loops and
 * segments, keeping the order of the rest; m->box is left to the caller.  CM_E_NOMEM (model
 * unchanged) if the bookkeeping cannot be allocated.
 */
CM_NODISCARD cm_err brep_remove_faces(brep_model *m, const unsigned char *drop, cm_status *st);

#endif /* BREP_H */
