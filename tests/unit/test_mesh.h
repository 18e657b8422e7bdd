/*
 * test_mesh.h - a cm_mesh over a test's own static arrays (the viewer's and the writers' tests).
 */
#ifndef TEST_MESH_H
#define TEST_MESH_H

#include <string.h>

#include "cm/cm_mesh.h"

/* an empty mesh whose vertices, indices and faces go into the arrays given, of the sizes given */
static inline cm_mesh test_mesh_on(float (*pos)[3], float (*nrm)[3], uint32_t *idx, cm_mesh_face *faces,
                                   uint32_t cap_verts, uint32_t cap_index, uint32_t cap_faces)
{
    cm_mesh m;
    memset(&m, 0, sizeof m);
    m.pos = pos;
    m.nrm = nrm;
    m.idx = idx;
    m.faces = faces;
    m.cap_verts = cap_verts;
    m.cap_index = cap_index;
    m.cap_faces = cap_faces;
    return m;
}

#endif
