/* cm_mesh.c - the decoded triangle mesh: clearing, rolling back a failed face, bounds. */
#include "cm/cm_mesh.h"

#include <stddef.h>

void cm_mesh_clear(cm_mesh *m)
{
    if (m == NULL)
        return;
    m->nverts = 0;
    m->nindex = 0;
    m->nfaces = 0;
    m->nplace = 0;
    m->place = NULL;
}

cm_mesh_mark cm_mesh_save(const cm_mesh *m)
{
    cm_mesh_mark k = {m->nverts, m->nindex, m->nfaces};
    return k;
}

void cm_mesh_rollback(cm_mesh *m, const cm_mesh_mark *mark)
{
    /* only ever back: a mark from another mesh, or a later one, leaves nothing beyond the fill */
    if (mark->nverts < m->nverts)
        m->nverts = mark->nverts;
    if (mark->nindex < m->nindex)
        m->nindex = mark->nindex;
    if (mark->nfaces < m->nfaces)
        m->nfaces = mark->nfaces;
    if (m->nplace && (m->nfaces < m->nbase_faces || m->nverts < m->nbase_verts || m->nindex < m->nbase_index)) {
        m->nplace = 0; /* the copies went with the faces they place */
        m->place = NULL;
    }
}

uint32_t cm_mesh_face_from(const cm_mesh *m, uint32_t n, uint32_t f)
{
    uint32_t lo = 0, hi = n;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (m->faces[mid].source_face < f)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/*
 * Bounds of positions [0, nverts).  NaN coordinates never win a comparison,
 * so they are ignored unless the first vertex holds one (the writers reject
 * non-finite meshes before they need bounds).
 */
int cm_mesh_bounds(const cm_mesh *m, float lo[3], float hi[3])
{
    if (m == NULL || m->nverts == 0 || m->pos == NULL || lo == NULL || hi == NULL)
        return 0;
    float l[3], h[3];
    for (int k = 0; k < 3; k++)
        l[k] = h[k] = m->pos[0][k];
    for (uint32_t i = 1; i < m->nverts; i++) {
        for (int k = 0; k < 3; k++) {
            float v = m->pos[i][k];
            if (v < l[k])
                l[k] = v;
            if (v > h[k])
                h[k] = v;
        }
    }
    for (int k = 0; k < 3; k++) {
        lo[k] = l[k];
        hi[k] = h[k];
    }
    return 1;
}
