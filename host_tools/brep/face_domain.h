/*
 * face_domain.h - a face's trimmed region in its surface's parameter
 * space: the loops as (u,v) polygons, oriented per spec §1, with an
 * inside test and a sampler.
 *
 * The polygons come from projecting samples of the 3D boundary curves onto
 * the surface (spec §12 allows this when no pcurves are used), following
 * each loop by continuation so that a loop crossing the seam of a closed
 * surface stays continuous ("unwrapped": u may leave [u0,u1] by a period).
 * The face's surface is evaluated at wrapped parameters.
 *
 * A face whose loops wind around a closed surface (a band of a full
 * cylinder bounded by two circles, no seam edge) has no closed polygon in
 * (u,v); its two winding loops are joined along the seam into one polygon.
 */
#ifndef FACE_DOMAIN_H
#define FACE_DOMAIN_H

#include "brep/brep.h"
#include "cm/cm_param.h"

typedef struct fd_loop {
    int first, n;   /* polygon vertices [first, first+n); closed implicitly */
    double area;    /* signed (u,v) area after orientation */
    int winds;      /* net turns around a closed direction (0 for an ordinary loop) */
} fd_loop;

/* the face's surface on verify.c's global-search grid, made on first need and kept: the encoder
   projects thousands of points onto one face, and each search evaluated the whole grid again */
typedef struct fd_grid {
    int state;    /* 0 not made yet, 1 made, -1 an evaluation failed (search as before) */
    cm_vec3 *pts; /* FD_GRID_N x FD_GRID_N points (cm_psurf_grid_points) */
} fd_grid;

#define FD_GRID_N 33

typedef struct face_domain {
    int face;
    cm_psurf ps;      /* the face's surface, with its domain and closedness */
    cm_vec2 *uv;      /* polygon vertices of all loops (unwrapped) */
    cm_vec3 *xyz;     /* the boundary point each vertex came from */
    int npts, cap;
    fd_loop *loops;   /* loops[0] the outer region polygon, then holes */
    int nloops;
    double umin, umax, vmin, vmax; /* box of the outer polygon */
    double max_gap;   /* largest distance from a boundary sample to the surface */
    int reversed;     /* loops were reversed to match the face normal */
    int reordered;    /* the outer loop was not the file's first loop */
    int joined_seam;  /* winding loops were joined along the seam */
    int wind_loop[2]; /* then the face's loops (numbered from its first) that wound, -1 for none */
    int wind_along_u; /* and whether they wound round u (else v) */
    int wind_turns[2];/* and their net turns round it (signed: the loops' own directions) */
    fd_grid *grid;    /* (its pointee changes under a const face_domain: a cache of what ps gives) */
} face_domain;

/**
 * Build the parameter domain of face `face`, and fix the model's loops in
 * place (spec §1): reverse loops that run the wrong way for the face
 * normal, move the outer loop first.  `tol` is the model's geometric
 * tolerance (closedness of surfaces, projection acceptance).
 */
CM_NODISCARD cm_err face_domain_build(brep_model *m, int face, double tol, face_domain *fd, cm_status *st);

void face_domain_free(face_domain *fd);

/**
 * A global projection of S onto the face's surface: cm_psurf_project_grid at FD_GRID_N, over the
 * grid kept in fd->grid (made on first need), so the same answer without evaluating the grid again.
 */
CM_NODISCARD cm_err face_domain_project_global(const face_domain *fd, cm_vec3 S, double *u, double *v, double *d);

/** 1 if (u,v) is inside the outer polygon and outside every hole. */
int face_domain_inside(const face_domain *fd, cm_vec2 uv);

/** Distance in (u,v) from a point to the nearest polygon edge. */
double face_domain_edge_dist(const face_domain *fd, cm_vec2 uv);

/** Surface point and unit normal (face orientation: flipped with the face) at (u,v). */
CM_NODISCARD cm_err face_domain_eval(const brep_model *m, const face_domain *fd, double u, double v, cm_vec3 *P,
                                     cm_vec3 *N, cm_status *st);

/**
 * Up to `n` points well inside the face (away from its boundary),
 * deterministic for a given `seed`.  Returns the number written (>= 1 for
 * any face with a non-empty region).
 */
int face_domain_sample(const face_domain *fd, int n, uint32_t seed, cm_vec2 *out);

#endif /* FACE_DOMAIN_H */
