/* cm_mesh.c - the decoded triangle mesh: clearing, rolling back a failed face, the spill, bounds. */
#include "cm/cm_mesh.h"
#include "cm/cm_limits_info.h"

#include <stddef.h>
#include <string.h>

/* the window at the mesh's start, the spill's pages dropped and its failure forgotten */
static void restart_window(cm_mesh *m)
{
    m->win_vert = m->win_index = 0;
    if (m->spill) {
        m->spill->failed = 0;
        memset(m->spill->page_n, 0, sizeof m->spill->page_n);
    }
}

void cm_mesh_clear(cm_mesh *m)
{
    if (m == NULL)
        return;
    m->nverts = 0;
    m->nindex = 0;
    m->nfaces = 0;
    m->nplace = 0;
    m->place = NULL;
    restart_window(m);
}

void cm_mesh_set_spill(cm_mesh *m, cm_mesh_spill *s, uint32_t win_verts, uint32_t win_index, uint32_t cap_verts,
                       uint32_t cap_index)
{
    m->spill = s;
    restart_window(m);
    m->win_cap_verts = win_verts;
    m->win_cap_index = win_index;
    m->cap_verts = cap_verts;
    m->cap_index = cap_index;
}

/* the one call through the spill's io (noinline: the stack gates' tables name this function) */
__attribute__((noinline)) static int spill_io(cm_mesh_spill *s, int write, unsigned stream, uint64_t off, void *buf,
                                              size_t n)
{
    if (n > 0 && !s->failed && s->io(s->ctx, write, stream, off, buf, n) != 0)
        s->failed = 1;
    return !s->failed;
}

cm_err cm_mesh_make_room(cm_mesh *m, uint32_t nv, uint32_t ni, cm_status *st)
{
    cm_mesh_spill *s = m->spill;
    if (s == NULL)
        return CM_OK; /* the arrays are the whole mesh: the callers' capacity checks decide */
    if (s->failed)
        return cm_fail(st, CM_E_IO, "mesh spill");
    if (nv <= m->win_cap_verts - (m->nverts - m->win_vert) && ni <= m->win_cap_index - (m->nindex - m->win_index))
        return CM_OK;
    uint32_t rv = m->nverts - m->win_vert, ri = m->nindex - m->win_index;
    if (!spill_io(s, 1, CM_SPILL_POS, 12u * (uint64_t)m->win_vert, m->pos, 12u * (size_t)rv) ||
        !spill_io(s, 1, CM_SPILL_NRM, 12u * (uint64_t)m->win_vert, m->nrm, 12u * (size_t)rv) ||
        !spill_io(s, 1, CM_SPILL_IDX, 4u * (uint64_t)m->win_index, m->idx, 4u * (size_t)ri))
        return cm_fail(st, CM_E_IO, "mesh spill");
    m->win_vert = m->nverts;
    m->win_index = m->nindex;
    /* the window holds one call of the tessellation's output: MAX_TESS_POINTS points and fewer
       than two triangles a point (cm_decode_state.h); said in points */
    if (nv > m->win_cap_verts)
        return cm_fail_limit(st, CM_LIMIT_MAX_TESS_POINTS, nv, m->win_cap_verts, "mesh window (one face)");
    if (ni > m->win_cap_index)
        return cm_fail_limit(st, CM_LIMIT_MAX_TESS_POINTS, ni / 6u + 1u, m->win_cap_index / 6u,
                             "mesh window (one face's triangles)");
    return CM_OK;
}

/* the page of stream s holding spilled element i (es bytes each), loaded when not cached.  Inlined
   with es a constant at each caller, so that the page arithmetic needs no division: the writers
   call this for every vertex and index they read back (4 % of a 35 000-triangle decode when it
   divided by a variable).  *avail (if not NULL) gets how many elements from i on the returned
   memory holds: the rest of the page, or 1 (the zeros of a failed read) */
static inline const uint8_t *spilled(const cm_mesh *m, unsigned s, uint32_t i, uint32_t es, uint32_t *avail)
{
    static const uint8_t zeros[12];
    cm_mesh_spill *sp = m->spill;
    if (avail)
        *avail = 1;
    if (sp == NULL)
        return zeros;
    const uint32_t per = CM_SPILL_PAGE_BYTES / es, end = s == CM_SPILL_IDX ? m->win_index : m->win_vert;
    const uint32_t first = i - i % per, k = (first / per) % CM_SPILL_PAGES;
    /* (a page loaded when fewer elements were spilled holds fewer than `per`: loaded again) */
    if (sp->page_first[s][k] != first || i - first >= sp->page_n[s][k]) {
        uint32_t n = end - first < per ? end - first : per;
        sp->page_n[s][k] = 0;
        if (!spill_io(sp, 0, s, (uint64_t)first * es, sp->page[s][k].b, (size_t)n * es))
            return zeros;
        sp->page_first[s][k] = first;
        sp->page_n[s][k] = n;
    }
    if (avail)
        *avail = sp->page_n[s][k] - (i - first);
    return sp->page[s][k].b + (size_t)(i - first) * es;
}

/* (not inlined into cm_mesh_pos and cm_mesh_nrm: two copies of the page logic cost the board's
   cmz-terminal 256 bytes of its text budget) */
__attribute__((noinline)) void cm_mesh_vec(const cm_mesh *m, unsigned s, uint32_t i, float out[3])
{
    if (i >= m->win_vert)
        memcpy(out, (s == CM_SPILL_NRM ? m->nrm : m->pos)[i - m->win_vert], 12u);
    else
        memcpy(out, spilled(m, s, i, 12u, NULL), 12u);
}

void cm_mesh_pos(const cm_mesh *m, uint32_t i, float out[3]) { cm_mesh_vec(m, CM_SPILL_POS, i, out); }

void cm_mesh_nrm(const cm_mesh *m, uint32_t i, float out[3]) { cm_mesh_vec(m, CM_SPILL_NRM, i, out); }

uint32_t cm_mesh_idx(const cm_mesh *m, uint32_t k)
{
    uint32_t v;
    if (k >= m->win_index)
        return m->idx[k - m->win_index];
    memcpy(&v, spilled(m, CM_SPILL_IDX, k, 4u, NULL), 4u);
    return v;
}

/* n elements of stream s (es bytes each) from element i into out: the spilled ones a cached page at
   a time, then the window's (win_first on, in win) in one copy */
static void read_run(const cm_mesh *m, unsigned s, uint32_t i, uint32_t n, uint32_t es, uint32_t win_first,
                     const uint8_t *win, uint8_t *out)
{
    while (n > 0 && i < win_first) {
        uint32_t run;
        const uint8_t *p = spilled(m, s, i, es, &run);
        run = run < n ? run : n;
        run = run < win_first - i ? run : win_first - i;
        memcpy(out, p, (size_t)run * es);
        out += (size_t)run * es;
        i += run;
        n -= run;
    }
    if (n > 0)
        memcpy(out, win + (size_t)(i - win_first) * es, (size_t)n * es);
}

void cm_mesh_vecs(const cm_mesh *m, unsigned s, uint32_t first, uint32_t n, float (*out)[3])
{
    read_run(m, s, first, n, 12u, m->win_vert, (const uint8_t *)(s == CM_SPILL_NRM ? m->nrm : m->pos),
             (uint8_t *)out);
}

void cm_mesh_idxs(const cm_mesh *m, uint32_t k, uint32_t n, uint32_t *out)
{
    read_run(m, CM_SPILL_IDX, k, n, 4u, m->win_index, (const uint8_t *)m->idx, (uint8_t *)out);
}

const float (*cm_mesh_vecs_at(const cm_mesh *m, unsigned s, uint32_t first, uint32_t n, float (*out)[3]))[3]
{
    uint32_t avail;
    if (first >= m->win_vert)
        return (const float(*)[3])((s == CM_SPILL_NRM ? m->nrm : m->pos) + (first - m->win_vert));
    const uint8_t *p = spilled(m, s, first, 12u, &avail);
    if (avail >= n) /* (within one cached page: valid until the stream's next page is read) */
        return (const float(*)[3])(const void *)p;
    cm_mesh_vecs(m, s, first, n, out);
    return (const float(*)[3])out;
}

const uint32_t *cm_mesh_idxs_at(const cm_mesh *m, uint32_t k, uint32_t n, uint32_t *out)
{
    uint32_t avail;
    if (k >= m->win_index)
        return m->idx + (k - m->win_index);
    const uint8_t *p = spilled(m, CM_SPILL_IDX, k, 4u, &avail);
    if (avail >= n)
        return (const uint32_t *)(const void *)p;
    cm_mesh_idxs(m, k, n, out);
    return out;
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
    if (m->win_vert > m->nverts || m->win_index > m->nindex) {
        /* back past the window's start (placed copies that failed): the window restarts there, the
           spill's bytes beyond it are rewritten by the next flush, its cached pages dropped */
        if (m->win_vert > m->nverts)
            m->win_vert = m->nverts;
        if (m->win_index > m->nindex)
            m->win_index = m->nindex;
        if (m->spill)
            memset(m->spill->page_n, 0, sizeof m->spill->page_n);
    }
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
 * Bounds of positions [first, first + n), read a run at a time (once a face: built for size, as the
 * GLB writer that calls it is).  NaN coordinates never win a
 * comparison, so they are ignored unless the first vertex holds one (the writers reject non-finite
 * meshes before they need bounds).
 */
CM_ONCE_PER_FACE int cm_mesh_range_bounds(const cm_mesh *m, uint32_t first, uint32_t n, float lo[3], float hi[3])
{
    if (m == NULL || n == 0 || m->pos == NULL || lo == NULL || hi == NULL)
        return 0;
    float l[3], h[3], p[CM_MESH_BOUNDS_RUN][3];
    cm_mesh_pos(m, first, p[0]);
    for (int k = 0; k < 3; k++)
        l[k] = h[k] = p[0][k];
    for (uint32_t i0 = 1; i0 < n; i0 += CM_MESH_BOUNDS_RUN) {
        uint32_t len = n - i0 < CM_MESH_BOUNDS_RUN ? n - i0 : CM_MESH_BOUNDS_RUN;
        cm_mesh_vecs(m, CM_SPILL_POS, first + i0, len, p);
        for (uint32_t i = 0; i < len; i++)
            for (int k = 0; k < 3; k++) {
                if (p[i][k] < l[k])
                    l[k] = p[i][k];
                if (p[i][k] > h[k])
                    h[k] = p[i][k];
            }
    }
    for (int k = 0; k < 3; k++) {
        lo[k] = l[k];
        hi[k] = h[k];
    }
    return 1;
}

int cm_mesh_bounds(const cm_mesh *m, float lo[3], float hi[3])
{
    return m != NULL && cm_mesh_range_bounds(m, 0, m->nverts, lo, hi);
}

uint32_t cm_mesh_faces_in_order(const cm_mesh *m, uint32_t cap)
{
    if (m == NULL || m->nfaces == 0 || m->nfaces > cap)
        return 0;
    uint64_t next = 0; /* (64 bits: a hostile GLB's counts do not wrap round to a match) */
    for (uint32_t f = 0; f < m->nfaces; f++) {
        if (m->faces[f].first_vert != next)
            return 0;
        next += m->faces[f].nverts;
    }
    return next == m->nverts ? m->nfaces : 0;
}

/*
 * Each face's bounds and the whole mesh's, in one pass: once a model, so that the viewer's frames
 * need not read every vertex to fit the camera (cm_view_fit).  The faces must hold the vertices one
 * after another from 0, each once (as the decoder, cm_mesh_place and cm_glb_read make them);
 * otherwise, or with more faces than cap, none is boxed and the whole mesh's bounds are
 * cm_mesh_bounds'.  The union of the faces' is the same as cm_mesh_bounds' (a NaN likewise ignored
 * unless the first vertex holds one); where a face's first vertex holds one, its box ignores the
 * rest of its vertices (found by the fuzzing of the viewer's glTF input): then cm_mesh_bounds'.
 */
CM_ONCE_PER_FACE int cm_mesh_face_boxes(const cm_mesh *m, float (*box)[6], uint32_t cap, uint32_t *nboxed, float lo[3],
                                        float hi[3])
{
    *nboxed = 0;
    if (box == NULL || cm_mesh_faces_in_order(m, cap) == 0)
        return cm_mesh_bounds(m, lo, hi);
    int any = 0, nan = 0;
    float l[3] = {0, 0, 0}, h[3] = {0, 0, 0};
    for (uint32_t f = 0; f < m->nfaces; f++) {
        float *b = box[f];
        if (!cm_mesh_range_bounds(m, m->faces[f].first_vert, m->faces[f].nverts, b, b + 3)) {
            b[0] = b[1] = b[2] = 3.0e38f; /* (no vertices: an empty box, lower above upper) */
            b[3] = b[4] = b[5] = -3.0e38f;
            continue;
        }
        for (int k = 0; k < 3; k++) {
            nan = nan || b[k] != b[k] || b[3 + k] != b[3 + k];
            if (!any || b[k] < l[k])
                l[k] = b[k];
            if (!any || b[3 + k] > h[k])
                h[k] = b[3 + k];
        }
        any = 1;
    }
    *nboxed = m->nfaces;
    if (nan) /* (a face's first vertex held one: its box ignores the rest, the whole mesh's do not) */
        return cm_mesh_bounds(m, lo, hi);
    for (int k = 0; any && k < 3; k++) {
        lo[k] = l[k];
        hi[k] = h[k];
    }
    return any;
}
