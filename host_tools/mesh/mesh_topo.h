/*
 * mesh_topo.h - what a viewer sees of a decoded mesh once vertices are
 * welded by position: is it closed, is it consistently oriented, where are
 * its open boundaries.  Used by the encoder's fold check on kept faces
 * (host_tools/encode/needs.c), the round-trip tests and the corpus check
 * (tests/tools/mesh_check.c); plain C, results reported, nothing asserted
 * here.
 */
#ifndef MESH_TOPO_H
#define MESH_TOPO_H

#include <stddef.h>

#include "cm/cm_mesh.h"
#include "cm/cm_vec.h"

typedef struct mesh_topo {
    size_t triangles;
    size_t welded_vertices;  /* distinct positions */
    size_t degenerate;       /* triangles with two corners at one position */
    size_t duplicate;        /* directed edges used more than once: overlap or misorientation */
    size_t lens_chords;      /* ... but for chords through a thin lens between two faces (each used
                                twice both ways by triangles facing apart: the model's shape) */
    size_t unpaired;         /* directed edges without their reverse: open boundary */
    cm_vec3 *bnd;            /* 2 * unpaired end points of the unpaired edges (malloc'd) */
    double volume;           /* signed volume (meaningful when closed) */
} mesh_topo;

/** Weld m by bit-identical positions and count; 0, or -1 when out of memory. */
int mesh_topo_analyse(const cm_mesh *m, mesh_topo *out);
void mesh_topo_free(mesh_topo *t);

#endif /* MESH_TOPO_H */
