/* brep.c - storage of the workstation B-rep (see brep.h). */
#include "brep.h"

#include <stdlib.h>
#include <string.h>

void brep_free(brep_model *m)
{
    for (int i = 0; i < m->nsurfs; i++)
        hsurf_free(&m->surfs[i]);
    for (int i = 0; i < m->nsegs; i++)
        hcurve_free(&m->segs[i]);
    free(m->surfs);
    free(m->segs);
    free(m->faces);
    free(m->loops);
    memset(m, 0, sizeof *m);
}

double brep_diag(const brep_model *m)
{
    return m->box.empty ? 0.0 : cm_dist(m->box.lo, m->box.hi);
}

double brep_tolerance(const brep_model *m)
{
    double diag = brep_diag(m), t = 1e-6 * diag;
    if (m->resolution_mm > t)
        t = m->resolution_mm < 1e-4 * diag ? m->resolution_mm : 1e-4 * diag;
    return t;
}

/* grow an array of `size`-byte elements to hold n+1 */
static int grow(void **arr, int *cap, int n, size_t size)
{
    if (n < *cap)
        return 0;
    int c = *cap ? 2 * *cap : 64;
    void *q = realloc(*arr, (size_t)c * size);
    if (!q)
        return -1;
    *arr = q;
    *cap = c;
    return 0;
}

cm_err brep_add_surf(brep_model *m, hsurf *s, int *index, cm_status *st)
{
    if (grow((void **)&m->surfs, &m->capsurfs, m->nsurfs, sizeof *m->surfs))
        return cm_fail(st, CM_E_IO, "out of memory");
    m->surfs[m->nsurfs] = *s;
    memset(s, 0, sizeof *s);
    *index = m->nsurfs++;
    return CM_OK;
}

cm_err brep_add_seg(brep_model *m, hcurve *c, cm_status *st)
{
    if (grow((void **)&m->segs, &m->capsegs, m->nsegs, sizeof *m->segs))
        return cm_fail(st, CM_E_IO, "out of memory");
    m->segs[m->nsegs++] = *c;
    memset(c, 0, sizeof *c);
    return CM_OK;
}

cm_err brep_add_loop(brep_model *m, int first_seg, int nseg, cm_status *st)
{
    if (grow((void **)&m->loops, &m->caploops, m->nloops, sizeof *m->loops))
        return cm_fail(st, CM_E_IO, "out of memory");
    m->loops[m->nloops].first = first_seg;
    m->loops[m->nloops].n = nseg;
    m->nloops++;
    return CM_OK;
}

cm_err brep_add_face(brep_model *m, const brep_face *f, cm_status *st)
{
    if (grow((void **)&m->faces, &m->capfaces, m->nfaces, sizeof *m->faces))
        return cm_fail(st, CM_E_IO, "out of memory");
    m->faces[m->nfaces++] = *f;
    return CM_OK;
}

void brep_truncate(brep_model *m, int nsurfs, int nfaces, int nloops, int nsegs)
{
    while (m->nsurfs > nsurfs)
        hsurf_free(&m->surfs[--m->nsurfs]);
    while (m->nsegs > nsegs)
        hcurve_free(&m->segs[--m->nsegs]);
    if (m->nfaces > nfaces)
        m->nfaces = nfaces;
    if (m->nloops > nloops)
        m->nloops = nloops;
}
