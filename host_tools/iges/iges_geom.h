/*
 * iges_geom.h - IGES curve and surface entities as exact NURBS, in
 * millimetres and model space (every 124 transformation chain applied).
 *
 * Curves: 100 circular arc, 102 composite (flattened into its pieces), 104
 * conic arc, 106 copious data (polyline forms 11, 12, 63; point forms give
 * polylines through the points), 110 line, 112 parametric spline, 126
 * rational B-spline, 142 curve on surface (its model-space curve).
 * Surfaces: 108 plane and 190 plane surface, 118 ruled, 120 revolution,
 * 122 tabulated cylinder, 128 rational B-spline, 192 cylinder, 194 cone,
 * 196 sphere, 198 torus.  Unbounded surfaces (planes, cylinders, cones)
 * get a finite patch covering a box the caller passes (the face's
 * boundary), enlarged by a margin.
 */
#ifndef IGES_GEOM_H
#define IGES_GEOM_H

#include "geom/hbox.h" /* hbox: the extent that sizes unbounded surfaces; hbox_* are defined in iges_geom.c */
#include "geom/hnurbs.h"
#include "iges/iges_file.h"

/*
 * Import budgets.  A few kilobytes of IGES can describe an astronomically large model: a 102
 * composite whose members are composites listed many times (a DAG, not a tree) flattens into
 * 8^12 pieces; subfigures (308/408) nest likewise (iges_brep.c).  The importer counts what an
 * entity expands to before building it and refuses, by name, past these budgets.  They are far
 * above the corpus (its longest composite flattens into 83 pieces; Shelt_channel_5, the largest
 * model, builds 124912 curve pieces for 27734 faces).  The curve budgets are host-profile limits
 * (a model past them could not be encoded anyway); the face budget is below the format's
 * MAX_FACES, chosen for memory and time.
 */
/** Pieces one curve entity (a composite, through every level) may flatten into: CM_MAX_LOOP_EDGES
 *  of the host profile, the edge uses of one loop (a boundary of more pieces cannot be encoded). */
#define IGES_MAX_CURVE_PIECES 4096
/** Curve pieces in the loops of one face: CM_MAX_FACE_EDGES of the host profile (one loop may hold
 *  IGES_MAX_CURVE_PIECES, CM_MAX_LOOP_EDGES). */
#define IGES_MAX_FACE_PIECES 16384
/** Curve pieces built for the whole model: CM_MAX_MODEL_USES of the host profile. */
#define IGES_MAX_MODEL_PIECES 4194304LL
/**
 * Faces placed in the model, subfigure instances expanded (iges_brep.c): 2^18, 9.5 times the
 * corpus's largest assembly (Shelt_channel_5, 27734 placed faces, 0.36 GB and 30 s to import), so
 * a model at the budget still imports in about 4 GB and a few minutes.
 */
#define IGES_MAX_PLACED_FACES_DEFAULT 262144
/** The placed-face budget in force: IGES_MAX_PLACED_FACES_DEFAULT, lowered only by the IGES fuzz
 *  target (a 35 KB subfigure DAG placing 2^18 faces imports, as designed, in minutes; the fuzzer's
 *  time is better spent on inputs that reach new code than on the 2^18th copy of one face). */
extern long long iges_max_placed_faces;
#define IGES_MAX_PLACED_FACES iges_max_placed_faces
/**
 * Largest coordinate magnitude (millimetres, after units and every transformation) a face's
 * geometry may reach: 1e12 mm is a million kilometres.  Beyond it (or not finite) the entity is
 * refused: such numbers come from a corrupted matrix or scale, and squared distances of them
 * overflow.
 */
#define IGES_MAX_COORD_MM 1e12

/**
 * 1 if all n points are finite and within IGES_MAX_COORD_MM on every axis; else 0 and *worst
 * (may be NULL) gets the first offending coordinate.
 */
int iges_coords_sane(const cm_vec3 *p, long n, double *worst);


/**
 * The affine map from entity `de`'s definition space to the space of its
 * parent: its 124 chain (the matrix, then the matrix that one points to,
 * ...).  Returns 0 on success, else an error is in f->err.
 */
int iges_entity_xform(iges_file *f, const iges_entity *e, haffine *out);

/**
 * Append the pieces of model-space curve `de` to `out`, each mapped by
 * `parent` (the map from the curve's parent space to millimetre model
 * space) after the curve's own transformation.  Returns CM_OK, or an error
 * with f->err naming the entity and its line: CM_E_IGES (malformed
 * parameters), CM_E_UNSUPPORTED, CM_E_LIMIT past IGES_MAX_CURVE_PIECES
 * (the face is skipped) or past IGES_MAX_MODEL_PIECES (then f->over_budget
 * is set: the whole import stops), CM_E_NOMEM.
 */
CM_NODISCARD cm_err iges_curve(iges_file *f, int de, const haffine *parent, hcurve_list *out, cm_status *st);

/**
 * The number of pieces iges_curve would append for curve `de` (composites flattened through every
 * level; counted without building anything, memoised), saturated at IGES_MAX_CURVE_PIECES + 1;
 * -1 if the count cannot be allocated.
 */
int iges_curve_pieces(iges_file *f, int de);

/**
 * Surface `de` as a NURBS in millimetre model space.  `extent` bounds the
 * face that uses it (its boundary curves, already in model space); planes,
 * cylinders and cones are built over that extent plus a 10 % margin.
 */
CM_NODISCARD cm_err iges_surface(iges_file *f, int de, const haffine *parent, const hbox *extent, hsurf *out,
                                 cm_status *st);

/** 1 if `type` is a surface entity iges_surface understands. */
int iges_is_surface(int type);

#endif /* IGES_GEOM_H */
