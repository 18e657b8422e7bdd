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

#include "geom/hnurbs.h"
#include "iges/iges_file.h"

/** A growable list of owned curves (the pieces of a composite curve). */
typedef struct hcurve_list {
    hcurve *c;
    int n, cap;
} hcurve_list;

void hcurve_list_free(hcurve_list *l);
/** Move `c` into the list (c is left empty). */
CM_NODISCARD cm_err hcurve_list_push(hcurve_list *l, hcurve *c, cm_status *st);

/**
 * The affine map from entity `de`'s definition space to the space of its
 * parent: its 124 chain (the matrix, then the matrix that one points to,
 * ...).  Returns 0 on success, else an error is in f->err.
 */
int iges_entity_xform(iges_file *f, const iges_entity *e, haffine *out);

/**
 * Append the pieces of model-space curve `de` to `out`, each mapped by
 * `parent` (the map from the curve's parent space to millimetre model
 * space) after the curve's own transformation.  Returns CM_OK, or
 * CM_E_IGES with f->err set (unsupported type, malformed parameters).
 */
CM_NODISCARD cm_err iges_curve(iges_file *f, int de, const haffine *parent, hcurve_list *out, cm_status *st);

/** An axis-aligned box (millimetre model space), for sizing unbounded surfaces. */
typedef struct hbox {
    cm_vec3 lo, hi;
    int empty;
} hbox;

hbox hbox_empty(void);
void hbox_add(hbox *b, cm_vec3 p);
/** Box of sample points of a curve (33 per span). */
void hbox_add_curve(hbox *b, const hcurve *c);

/**
 * Surface `de` as a NURBS in millimetre model space.  `extent` bounds the
 * face that uses it (its boundary curves, already in model space); planes,
 * cylinders and cones are built over that extent plus a 10 % margin.
 */
CM_NODISCARD cm_err iges_surface(iges_file *f, int de, const haffine *parent, const hbox *extent, hsurf *out,
                                 cm_status *st);

/** 1 if `type` is a curve entity iges_curve understands. */
int iges_is_curve(int type);
/** 1 if `type` is a surface entity iges_surface understands. */
int iges_is_surface(int type);

#endif /* IGES_GEOM_H */
