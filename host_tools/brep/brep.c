/* brep.c - storage of the workstation B-rep (see brep.h). */
#include "brep.h"

#include <stdio.h>
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
    free(m->instances);
    free(m->placements);
    memset(m, 0, sizeof *m);
}

double brep_diag(const brep_model *m)
{
    hbox b = m->box;
    if (m->nplacements > 0 && !m->placed_box.empty) {
        hbox_add(&b, m->placed_box.lo);
        hbox_add(&b, m->placed_box.hi);
    }
    return b.empty ? 0.0 : cm_dist(b.lo, b.hi);
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
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    m->surfs[m->nsurfs] = *s;
    memset(s, 0, sizeof *s);
    *index = m->nsurfs++;
    return CM_OK;
}

cm_err brep_add_seg(brep_model *m, hcurve *c, cm_status *st)
{
    if (grow((void **)&m->segs, &m->capsegs, m->nsegs, sizeof *m->segs))
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    m->segs[m->nsegs++] = *c;
    memset(c, 0, sizeof *c);
    return CM_OK;
}

cm_err brep_add_loop(brep_model *m, int first_seg, int nseg, cm_status *st)
{
    if (grow((void **)&m->loops, &m->caploops, m->nloops, sizeof *m->loops))
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    m->loops[m->nloops].first = first_seg;
    m->loops[m->nloops].n = nseg;
    m->nloops++;
    return CM_OK;
}

cm_err brep_add_instance(brep_model *m, const brep_instance *in, cm_status *st)
{
    if (grow((void **)&m->instances, &m->capinstances, m->ninstances, sizeof *m->instances))
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    m->instances[m->ninstances++] = *in;
    return CM_OK;
}

cm_err brep_add_face(brep_model *m, const brep_face *f, cm_status *st)
{
    if (grow((void **)&m->faces, &m->capfaces, m->nfaces, sizeof *m->faces))
        return cm_fail(st, CM_E_NOMEM, "out of memory");
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

cm_err brep_remove_faces(brep_model *m, const unsigned char *drop, cm_status *st)
{
    /* what the kept faces use; everything else is freed, the rest moved down in order */
    unsigned char *usurf = calloc((size_t)m->nsurfs + 1, 1), *uloop = calloc((size_t)m->nloops + 1, 1),
                  *useg = calloc((size_t)m->nsegs + 1, 1);
    int *nsurf = malloc(((size_t)m->nsurfs + 1) * sizeof *nsurf), *nloop = malloc(((size_t)m->nloops + 1) * sizeof *nloop),
        *nseg = malloc(((size_t)m->nsegs + 1) * sizeof *nseg);
    cm_err e = CM_OK;
    if (!usurf || !uloop || !useg || !nsurf || !nloop || !nseg) {
        e = cm_fail(st, CM_E_NOMEM, "out of memory");
        goto done;
    }
    for (int f = 0; f < m->nfaces; f++) {
        if (drop[f])
            continue;
        const brep_face *F = &m->faces[f];
        usurf[F->surf] = 1;
        for (int l = F->first_loop; l < F->first_loop + F->nloops; l++) {
            uloop[l] = 1;
            for (int i = 0; i < m->loops[l].n; i++)
                useg[m->loops[l].first + i] = 1;
        }
        /* (a face cut open keeps the loops it had, for the encoder's undo: brep_seam.h) */
        for (int l = F->cut_from_loop; F->cut_from_nloops > 0 && l < F->cut_from_loop + F->cut_from_nloops; l++) {
            uloop[l] = 1;
            for (int i = 0; i < m->loops[l].n; i++)
                useg[m->loops[l].first + i] = 1;
        }
    }
    int k = 0;
    for (int i = 0; i < m->nsurfs; i++) {
        nsurf[i] = k;
        if (usurf[i])
            m->surfs[k++] = m->surfs[i];
        else
            hsurf_free(&m->surfs[i]);
    }
    m->nsurfs = k;
    k = 0;
    for (int i = 0; i < m->nsegs; i++) {
        nseg[i] = k;
        if (useg[i])
            m->segs[k++] = m->segs[i];
        else
            hcurve_free(&m->segs[i]);
    }
    nseg[m->nsegs] = k;
    m->nsegs = k;
    k = 0;
    for (int i = 0; i < m->nloops; i++) {
        nloop[i] = k;
        if (uloop[i]) {
            m->loops[k] = m->loops[i];
            m->loops[k].first = nseg[m->loops[i].first];
            k++;
        }
    }
    nloop[m->nloops] = k;
    m->nloops = k;
    k = 0;
    for (int f = 0; f < m->nfaces; f++) {
        if (drop[f])
            continue;
        m->faces[k] = m->faces[f];
        m->faces[k].surf = nsurf[m->faces[f].surf];
        m->faces[k].first_loop = nloop[m->faces[f].first_loop];
        if (m->faces[f].cut_from_nloops > 0)
            m->faces[k].cut_from_loop = nloop[m->faces[f].cut_from_loop];
        k++;
    }
    m->nfaces = k;
done:
    free(usurf);
    free(uloop);
    free(useg);
    free(nsurf);
    free(nloop);
    free(nseg);
    return e;
}

double brep_curve_length(const hcurve *c)
{
    cm_curve v = hcurve_view(c);
    double t0, t1, len = 0;
    hcurve_domain(c, &t0, &t1);
    cm_vec3 prev = cm_v3(0, 0, 0);
    for (int k = 0; k <= 64; k++) {
        cm_vec3 d[1];
        if (cm_curve_eval(&v, t0 + (t1 - t0) * k / 64.0, 0, d, NULL) != CM_OK)
            return 0;
        if (k)
            len += cm_dist(d[0], prev);
        prev = d[0];
    }
    return len;
}

cm_err brep_add_rect_loop(brep_model *m, int surf, hbox *box, cm_status *st)
{
    /* counter-clockwise in (u,v): v=v0, u=u1, v=v1 back, u=u0 back */
    const hsurf *sf = &m->surfs[surf];
    double u0, u1, v0, v1;
    cm_err e;
    hsurf_domain(sf, &u0, &u1, &v0, &v1);
    hcurve side[4] = {{0}, {0}, {0}, {0}};
    if ((e = hsurf_iso_v(sf, v0, &side[0], st)) != CM_OK || (e = hsurf_iso_u(sf, u1, &side[1], st)) != CM_OK ||
        (e = hsurf_iso_v(sf, v1, &side[2], st)) != CM_OK || (e = hsurf_iso_u(sf, u0, &side[3], st)) != CM_OK) {
        for (int i = 0; i < 4; i++)
            hcurve_free(&side[i]);
        return e;
    }
    hcurve_reverse(&side[2]);
    hcurve_reverse(&side[3]);
    for (int i = 0; i < 4; i++)
        hbox_add_curve(box, &side[i]);
    double diag = box->empty ? 0 : cm_dist(box->lo, box->hi);
    int first = m->nsegs;
    for (int i = 0; i < 4 && e == CM_OK; i++) {
        if (brep_curve_length(&side[i]) <= 1e-9 * diag) { /* a collapsed side (a pole) */
            hcurve_free(&side[i]);
            continue;
        }
        e = brep_add_seg(m, &side[i], st);
    }
    for (int i = 0; i < 4; i++)
        hcurve_free(&side[i]);
    if (e == CM_OK)
        e = brep_add_loop(m, first, m->nsegs - first, st);
    return e;
}

const char *brep_face_source(const brep_face *f, char *buf, size_t cap)
{
    if (f->src_type == BREP_SRC_STEP_FACE)
        snprintf(buf, cap, "STEP face #%d", f->src_de);
    else
        snprintf(buf, cap, "entity %d (DE %d)", f->src_type, f->src_de);
    return buf;
}
