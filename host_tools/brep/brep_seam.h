/*
 * brep_seam.h - a face whose two loops wind round a closed surface (a band of a full cylinder, cone,
 * torus or surface of revolution between two circles, with no seam edge: common in STEP files),
 * cut open along a curve of its surface so that it has one outer loop, as the same band has where
 * the file gives it a seam edge (issue 13, spec §11's periodic splitting, in its simplest form).
 *
 * No rebuilding method takes a face with a hole on a curved surface, nor a loop of one edge: such a
 * band was always sent with its surface.  Cut open, its loop is the two circles and the cut twice
 * (a seam, as cmesh classifies it), a four-sided face the GREGORY-EXACT patches rebuild as they do
 * the bands the file itself gives a seam (IGES exporters mostly do).  The face stays one face: the
 * same entity, the same number, the same surface; only its boundary gains the cut.
 *
 * The cut runs along the surface's parameter line through the start of the first winding loop's
 * first curve (no new vertex there), up to where that line meets the other loop (which is cut
 * there in two).  Only a band of exactly those two loops (a cap: the one) is cut: no method rebuilds
 * a further hole on a curved surface, and a cut could cross it.  The face's loops before the cut are kept in brep_face.cut_from_loop, so that the encoder
 * can undo a cut that did not let the face's surface go (brep_uncut_seam).
 */
#ifndef BREP_SEAM_H
#define BREP_SEAM_H

#include "brep/brep.h"
#include "brep/face_domain.h"

/**
 * Cut face f open if its domain fd joined two loops winding round its surface (fd->joined_seam with
 * fd->wind_loop[1] >= 0): the face gets one outer loop (its other holes follow) and fd is built
 * again.  *cut = 1 when done; 0 when the face is not such a band or the cut could not be made (the
 * loops' crossing not found, the cut not on the loops' ends within the domain's acceptance, the new
 * domain failed): the face and fd are then as they were.  CM_E_NOMEM only for memory.
 */
CM_NODISCARD cm_err brep_cut_seam(brep_model *m, int f, face_domain *fd, double tol, int *cut, cm_status *st);

/**
 * Undo brep_cut_seam on face f (its loops as imported again; cut_from_nloops cleared, so the face
 * is never cut again) and build fd again.  A face not cut is left alone.
 */
CM_NODISCARD cm_err brep_uncut_seam(brep_model *m, int f, face_domain *fd, double tol, cm_status *st);

#endif /* BREP_SEAM_H */
