/*
 * verify.h - the workstation's measurements of a rebuilt face against the
 * original model: spec §12 (error evaluation) and §13 (G1 verification).
 * The encoder decides with them and `cmz eval` re-measures a finished file
 * with them, so neither has to trust the other's log.
 *
 * The rebuilt surfaces come from the decoder's own cm_rebuild_face(); the
 * originals from the import (loaded_model: the face's source surface and
 * its loops in parameter space).
 */
#ifndef VERIFY_H
#define VERIFY_H

#include "cm/cm_format.h"
#include "cm/cm_gregface.h"
#include "cm/cm_rebuild.h"
#include "model_load.h"

/** A face's surface as the terminal shows it, kept for the G1 check across its edges. */
typedef struct face_surface {
    int rebuilt;          /* 0: the face keeps its surface (measured on the source surface) */
    cm_repr repr;         /* rebuilt: what the rebuild made (cm_rebuilt.repr) */
    cm_frame frame;       /* FRAME */
    cm_greg_surface *greg; /* PATCHES: malloc'd copy (face_surface_free) */
    double bbox;           /* bbox_F */
    /* NURBS: a deep copy of cm_rebuilt.surf (whose arrays point into a workspace the next rebuild
       reuses): the view `nurbs` over the malloc'd nurbs_ctrl and nurbs_num (face_surface_free) */
    cm_surf nurbs;
    cm_vec3 *nurbs_ctrl;   /* nu * nv control points (NULL: no copy) */
    double *nurbs_num;     /* U (nu + p + 1), V (nv + q + 1), then the weights (nu * nv) if rational */
    double sign;           /* NURBS: the face normal is sign * (Su x Sv) (cm_rebuilt.sign) */
} face_surface;

/** spec §12 numbers of one face */
typedef struct face_error {
    double avg, max;      /* over the surface grid and the boundary points (mm) */
    double ratio;         /* max / bbox_F */
    double bbox;          /* bbox_F: diagonal of the box of the face's boundary samples (mm) */
    int grid_points;      /* 21 x 21 grid points inside the outer loop */
    int boundary_points;  /* 21 per edge use of every loop */
    int complete;         /* every point measured (0: stopped at the first one over the tolerance) */
    double back;          /* Gregory patches: their largest distance from the source surface (in max) */
} face_error;

/**
 * The boundary sample of fd nearest to p, if nearer than sqrt(*best2): *best2 becomes its squared
 * distance and *uv its parameters (a start for a foot search on the source surface).
 */
void verify_nearest_boundary(const face_domain *fd, cm_vec3 p, double *best2, cm_vec2 *uv);

/** Keep what cm_rebuild_face() gave for face f (copies the Gregory patches, or the NURBS surface with
 *  its control points, knots and weights). 0 on out of memory (or a NURBS surface of no size). */
int face_surface_set(face_surface *fs, const cm_rebuilt *rb);
void face_surface_free(face_surface *fs);

/**
 * Spec §12 for face f of the decoded model m, rebuilt as rb (a frame,
 * patches or a NURBS surface: each point's foot by the K9 projection
 * cm_patch_project, or walked from the previous point's foot when that is
 * near enough or a minimum inside the surface's domain): the source
 * surface on the 21 x 21 grid of its parameter box,
 * points inside the outer loop (holes included, as the papers say), and the
 * transmitted edges of every loop at t = k/20, each projected on the rebuilt
 * surface; and, past §12, for Gregory patches the other way: points of each
 * patch projected on the source surface (a bulge no source point is near; not
 * for a NURBS surface, which extends past the face).  Stops at the first point at or over `tol` mm (the face fails; HUGE_VAL measures all
 * points).  Returns 0 when the face's domain is unknown (no verdict).
 */
int verify_face(const loaded_model *lm, const cm_model *m, int f, const cm_rebuilt *rb, double tol,
                face_error *out);

/**
 * The foot of p on the patches of s: from patch *k at (*u,*v) when *have (a local walk, taken when
 * within `accept` mm or at rest inside a patch), else or when that fails a search over all patches
 * (*have then 1).  Returns the distance.
 */
double verify_patch_foot(const cm_greg_surface *s, double accept, cm_vec3 p, int *have, int *k, double *u, double *v);
/** The unit normal of face f's source surface at the foot of P (found from the nearest boundary
    sample: P near the face's loop), unit(Su x Sv) as the surface has it, not turned to the face's
    side (brep_face.flip): the G1 checks compare |cos|; 0 where it cannot be had. */
int verify_source_normal(const loaded_model *lm, int f, cm_vec3 P, cm_vec3 *n);
/** The same on a (non-periodic) B-spline surface over its whole domain: what verify_face measures
    a NURBS rebuild with. */
double verify_surf_foot(const cm_surf *s, double accept, cm_vec3 p, int *have, double *u, double *v);

/**
 * The unit normal of face f's final surface at the foot of P, as verify_g1_edge takes it (rebuilt
 * from fs[f]: a NURBS face's is fs[f].sign * unit(Su x Sv); a kept face's from its source surface),
 * found by a global search.  0 where it cannot be had.
 */
int verify_face_normal(const loaded_model *lm, int f, const face_surface *fs, cm_vec3 P, cm_vec3 *n);

/**
 * The worst |cos| between face f's final surface (fs[f]) and its own source surface, at the points of
 * verify_g1_edge along each of its G1 edges: a face within half the G1 limit of its source there meets
 * any neighbour that is too (the angles add).  1 without G1 edges.
 * kept: NULL, or per face 1 where that face keeps its surface for good; the G1 edges to those faces
 * are then left out and their worst |cos| goes to *worst_kept (1 without): there the source's normal
 * is the neighbour's own, and the whole G1 limit is the face's to use.
 * use_worst: NULL, or per use of the face (its loops' uses in order) the worst |cos| along it (1
 * where it is not a G1 edge to another face, or nothing was measured).
 */
double verify_g1_self(const loaded_model *lm, const cm_model *m, int f, const face_surface *fs,
                      const unsigned char *kept, double *worst_kept, double *use_worst);

/**
 * Spec §13 for edge e of m: at t = k/10, k = 1..9, the unit normals of the
 * final surfaces of its two faces (rebuilt from `fs`: a NURBS face's is
 * sign * unit(Su x Sv) at the edge point's foot on it; KEEP faces from the
 * source surface).  Returns min |nF . nG| (1 for an edge without two faces;
 * 0 where a normal cannot be had).  *worse (may be NULL): at the worst point,
 * 0 if face edge_face[e][0]'s final normal is farther from its source
 * surface's than the other face's is, else 1.
 */
double verify_g1_edge(const loaded_model *lm, const cm_model *m, uint32_t e, const face_surface *fs, int *worse);

/**
 * Face f as the terminal shows it - its triangles (positions pos, global vertex ids idx, the face
 * alone in the mesh) at the file's recommended chordal tolerance - against its source surface, both
 * ways: every vertex projected on the source surface (a piece of mesh off the face), and the
 * source's 21 x 21 grid points inside the face (holes left out) and its boundary samples to the
 * nearest triangle (the chords' sag, a part of the face not covered).  So it counts the rebuild's
 * error and the tessellation's chords together.  `expect` (mm; the rebuild error plus the
 * chordal tolerance): a vertex whose local foot is more than twice that off gets a search over the
 * whole surface.  Returns the larger distance (mm), or -1 where the face's domain is unknown.
 * (issue 14.6: --report's mesh_dev_mm)
 */
double verify_mesh_face(const loaded_model *lm, int f, const float (*pos)[3], uint32_t nverts, const uint32_t *idx,
                        uint32_t nindex, double expect);

#endif /* VERIFY_H */
