/*
 * step_brep.h - a STEP file's faces into the format-neutral B-rep (brep.h),
 * as exactly as the IGES import: every ADVANCED_FACE (and FACE_SURFACE) of
 * the solids and shells the file's shape representations hold, each
 * representation placed where its assembly puts it, in millimetres.
 *
 * What is read (AP203, AP214, AP242 exporters):
 *   geometry   CARTESIAN_POINT, DIRECTION, VECTOR, AXIS1/AXIS2_PLACEMENT_3D;
 *              LINE, CIRCLE, ELLIPSE, POLYLINE, B_SPLINE_CURVE_WITH_KNOTS
 *              (and rational), TRIMMED_CURVE, SURFACE_CURVE, SEAM_CURVE;
 *              PLANE, CYLINDRICAL_, CONICAL_, SPHERICAL_, TOROIDAL_SURFACE,
 *              SURFACE_OF_REVOLUTION, SURFACE_OF_LINEAR_EXTRUSION,
 *              B_SPLINE_SURFACE_WITH_KNOTS (and rational)
 *   topology   VERTEX_POINT, EDGE_CURVE, ORIENTED_EDGE, EDGE_LOOP,
 *              VERTEX_LOOP, POLY_LOOP, FACE_BOUND, FACE_OUTER_BOUND,
 *              ADVANCED_FACE, FACE_SURFACE, CLOSED_SHELL, OPEN_SHELL,
 *              ORIENTED_CLOSED_SHELL, MANIFOLD_SOLID_BREP, BREP_WITH_VOIDS,
 *              FACETED_BREP, SHELL_BASED_SURFACE_MODEL
 *   structure  every representation (ADVANCED_BREP_SHAPE_REPRESENTATION,
 *              SHAPE_REPRESENTATION, ...) with its context's length and
 *              angle units (SI_UNIT with prefixes, CONVERSION_BASED_UNIT)
 *              and uncertainty; SHAPE_REPRESENTATION_RELATIONSHIP (with
 *              ITEM_DEFINED_TRANSFORMATION: assembly placements, the child
 *              told from the parent by NEXT_ASSEMBLY_USAGE_OCCURRENCE) and
 *              MAPPED_ITEM; every placement of a part is an instance
 *              (brep_instance), so MODEL_LOAD_FOLD sends it once
 *   colours    STYLED_ITEM / OVER_RIDING_STYLED_ITEM through their
 *              presentation styles to COLOUR_RGB or a pre-defined colour,
 *              on a face, a shell or a solid
 * Edges are cut from their curves between their vertices (the 3D curve of
 * a SURFACE_CURVE; parameter-space curves are not needed).  A face that
 * cannot be built is skipped with a warning naming its #n and line
 * ("face #n (ADVANCED_FACE) skipped: ..."); the import fails only when no
 * face of the file can be read.  Anything else is counted, not read.
 */
#ifndef STEP_BREP_H
#define STEP_BREP_H

#include "brep/brep.h"
#include "step/step_file.h"

/** Counts of what a STEP import read, for `cmz info`. */
typedef struct step_import_stats {
    int faces;          /* faces placed in the model (placements expanded) */
    int face_entities;  /* distinct face instances imported */
    int solids;         /* MANIFOLD_SOLID_BREP, BREP_WITH_VOIDS, FACETED_BREP read */
    int shells;         /* shells of SHELL_BASED_SURFACE_MODELs read */
    int placements;     /* representations placed by an assembly or a MAPPED_ITEM */
    int colored_faces;  /* faces that got a colour */
    double unit_mm;     /* the first representation's length unit, in millimetres */
} step_import_stats;

/**
 * Import every face of a STEP file into m (model space, millimetres).  Warnings
 * (faces skipped, entities not understood) go to f->warn; on failure f->err says
 * why, naming the line and #n.
 */
CM_NODISCARD cm_err step_to_brep(step_file *f, brep_model *m, step_import_stats *stats, cm_status *st);

#endif /* STEP_BREP_H */
