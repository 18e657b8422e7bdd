/*
 * cmesh.h - the curve mesh (spec §5.1-§5.3): the model's boundary curves
 * with shared-edge topology, G1 flags and corner normals.
 *
 * Built from the B-rep the same way for every input (IGES 144 files share
 * nothing; B-rep files share by reference, and the geometry finds the same
 * answer):
 *   1. vertices: segment end points merged within tol_vertex; consecutive
 *      segments of a loop always share their joint;
 *   2. split: a segment is cut where another vertex lies on it (T-junction);
 *   3. pair: pieces with the same end vertices whose curves coincide (the
 *      midpoint of one projects onto the other within tol_pair) are one
 *      edge, stored once in the direction of its first use;
 *   4. loops: each face's loops as edge uses, in loop order;
 *   5. classify: free (1 use), shared (2 faces), seam (one face twice),
 *      non-manifold (3 or more uses);
 *   6. face normal per face (frame of its outer loop's samples);
 *   7. G1 flag per edge (spec 5.2): normals of both faces at 11 points agree
 *      within 1 degree;
 *   8. corner normals per face corner (spec 5.3).
 * cmesh_build (cmesh.c) runs these phases in this order, each in a function
 * of its own.
 * Tolerances are relative to the model (and to the file's resolution when
 * that is coarser), never absolute.
 */
#ifndef CMESH_H
#define CMESH_H

#include "brep/brep.h"
#include "brep/face_domain.h"

typedef enum cmesh_kind { CMESH_FREE = 0, CMESH_SHARED = 1, CMESH_SEAM = 2, CMESH_NONMANIFOLD = 3 } cmesh_kind;

typedef struct cmesh_edge {
    hcurve c;        /* owned; runs from v0 to v1 */
    int v0, v1;
    int nuse;
    int face[2];     /* the first two faces using it (-1 if fewer) */
    cmesh_kind kind;
    int g1;          /* spec 5.2 */
    double g1_min_cos; /* min |nF.nG| over the 11 test points (1 for free edges) */
} cmesh_edge;

typedef struct cmesh_use {
    int edge;
    int rev;         /* 1: the loop runs v1 -> v0 */
} cmesh_use;

typedef struct cmesh_corner {
    cm_vec3 n;       /* corner normal N(F,V) of spec 5.3 */
    int flat;        /* |a x b| < sin 5 deg: N_geo undefined, fallback used */
    int source;      /* 0 geometric, 1 from a G1 partner, 3 the face normal (fallback iii) */
} cmesh_corner;

typedef struct cmesh_loop {
    int first, n;    /* uses [first, first+n), corners likewise (corner i: into use i) */
} cmesh_loop;

typedef struct cmesh_face {
    int brep_face;
    int first_loop, nloops; /* loop 0 outer */
    cm_vec3 normal;  /* n_F: Newell normal of the sampled outer loop (K11) */
    int normal_ok;
} cmesh_face;

typedef struct cmesh {
    cm_vec3 *verts;
    int nverts;
    cmesh_edge *edges;
    int nedges;
    cmesh_use *uses;
    cmesh_corner *corners;
    int nuses;
    cmesh_loop *loops;
    int nloops;
    cmesh_face *faces;
    int nfaces;
    double tol_vertex, tol_pair;
    int nsplits;     /* pieces created at T-junctions */
    int nforced;     /* loop joints merged although farther apart than tol_vertex */
    double max_forced_gap;
    int inconsistent; /* shared edges both faces traverse the same way (normals disagree) */
} cmesh;

/**
 * Build the curve mesh of m.  `fds` are the faces' parameter domains
 * (face_domain_build, one per face, same order) used to start the normal
 * evaluations for G1 flags; pass NULL to skip G1 flags.
 */
CM_NODISCARD cm_err cmesh_build(const brep_model *m, const face_domain *fds, cmesh *out, cm_status *st);

void cmesh_free(cmesh *cm);

/** Counts by kind (any pointer may be NULL). */
void cmesh_counts(const cmesh *cm, int *free_e, int *shared, int *seam, int *nonmanifold, int *g1);

/**
 * Connected components of faces through shared edges.  comp[f] gets the
 * component of face f; returns the number of components.  `comp` has
 * cm->nfaces entries.
 */
int cmesh_components(const cmesh *cm, int *comp);

#endif /* CMESH_H */
