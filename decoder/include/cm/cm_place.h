/*
 * cm_place.h - a model's placed copies in its mesh (format 4.3).
 *
 * An assembly that places one part several times (IGES 308/408 subfigure
 * instances) sends the part's faces once and, per further placement, the
 * range of faces and the transform (cm_placement, cm_format.h).  The
 * terminal rebuilds and tessellates the part once; this appends each
 * placement's triangles, transformed, after the model's own, so every
 * writer (GLB, STL, OBJ) and viewer sees the whole assembly.
 *
 * A copy's positions are M p + t computed in double from the part's float
 * positions; its normals are the cofactor matrix of M times the part's,
 * normalised (right for any invertible M, mirrors and scales included); a
 * mirroring M (det < 0) reverses each triangle so its front stays outside.
 * Only + - * / sqrt, in a fixed order: the same bits on every machine.
 *
 * Contract: no heap, no recursion; the mesh's capacities bound the work.
 */
#ifndef CM_PLACE_H
#define CM_PLACE_H

#include "cm/cm_format.h"
#include "cm/cm_mesh.h"

/**
 * Append the placed copies of model m to mesh (filled by the model's faces in face order, as
 * cm_decode_mesh does; a face left out of the mesh is left out of its copies too).  Copies keep
 * their face's source_face.
 * @return CM_E_LIMIT (MAX_TRIS, or MAX_FACES for the mesh's faces) when the copies do not fit the
 *         mesh's capacities (nothing appended is kept then), CM_E_NONFINITE when a copy's vertex
 *         leaves float range
 */
CM_NODISCARD cm_err cm_mesh_place(const cm_model *m, cm_mesh *mesh, cm_status *st);

/**
 * The triangles and mesh faces the copies add to a mesh of the model's faces whose face k has
 * tris[k] triangles (the encoder's needs: MAX_TRIS and MAX_FACES of the header); tris NULL: the
 * faces only (*add_tris 0).
 */
void cm_place_counts(const cm_model *m, const uint32_t *tris, uint64_t *add_tris, uint64_t *add_faces);

#endif /* CM_PLACE_H */
