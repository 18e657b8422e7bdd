/*
 * cm_out.c - the chunked writer shared by the GLB, STL and OBJ serialisers:
 * mesh validation, the pending-piece buffer and the copy loop.
 *
 * cm_out_begin validates everything the formats rely on (ranges, indices
 * inside their face, finite numbers), so the per-format fill functions
 * never fail on content; cm_out_next only copies pieces out.  A piece is
 * produced whole into cm_out.pending and handed out across as many calls
 * as the caller's buffer sizes need, so the bytes never depend on them.
 */
#include <string.h>

#include "cm/cm_numfmt.h"
#include "cm/cm_format.h"
#include "cm_out_priv.h"

/* ---- cm_buf ---- */

void cm_buf_init(cm_buf *b, uint8_t *p, uint32_t cap)
{
    b->p = p;
    b->n = 0;
    b->cap = cap;
    b->overflow = 0;
}

uint32_t cm_buf_room(const cm_buf *b)
{
    return b->cap - b->n;
}

void cm_buf_bytes(cm_buf *b, const void *src, uint32_t n)
{
    if (n > b->cap - b->n) {
        b->overflow = 1;
        return;
    }
    memcpy(b->p + b->n, src, n);
    b->n += n;
}

void cm_buf_str(cm_buf *b, const char *s)
{
    size_t n = strlen(s);
    if (n > b->cap - b->n) {
        b->overflow = 1;
        return;
    }
    cm_buf_bytes(b, s, (uint32_t)n);
}

void cm_buf_u64(cm_buf *b, uint64_t v)
{
    char t[CM_FMT_U64_MAX];
    size_t n = cm_fmt_u64(t, v);
    cm_buf_bytes(b, t, (uint32_t)n);
}

void cm_buf_f32(cm_buf *b, float f)
{
    char t[CM_FMT_F32_MAX];
    size_t n = cm_fmt_f32(t, f);
    cm_buf_bytes(b, t, (uint32_t)n);
}

void cm_buf_le16(cm_buf *b, uint16_t v)
{
    uint8_t t[2] = {(uint8_t)(v & 0xFFu), (uint8_t)(v >> 8)};
    cm_buf_bytes(b, t, 2);
}

void cm_buf_le32(cm_buf *b, uint32_t v)
{
    uint8_t t[4] = {(uint8_t)(v & 0xFFu), (uint8_t)((v >> 8) & 0xFFu), (uint8_t)((v >> 16) & 0xFFu),
                    (uint8_t)(v >> 24)};
    cm_buf_bytes(b, t, 4);
}

void cm_buf_lef32(cm_buf *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    cm_buf_le32(b, u);
}

/* ---- validation ---- */

uint32_t cm_out_face_tris(const cm_mesh *m, uint32_t f)
{
    return m->faces[f].nindex / 3u;
}

static int f32_finite(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return (u & 0x7F800000u) != 0x7F800000u;
}

/* NULL arrays, counts above capacities */
static cm_err check_storage(const cm_mesh *m, int need_normals, cm_status *st)
{
    if (m->nverts > m->cap_verts || m->nindex > m->cap_index || m->nfaces > m->cap_faces)
        return cm_fail(st, CM_E_ARG, "cm_out_begin: mesh count above its capacity");
    if ((m->nverts > 0 && m->pos == NULL) || (m->nverts > 0 && need_normals && m->nrm == NULL) ||
        (m->nindex > 0 && m->idx == NULL) || (m->nfaces > 0 && m->faces == NULL))
        return cm_fail(st, CM_E_ARG, "cm_out_begin: mesh array missing");
    return CM_OK;
}

/* face ranges, indices inside their face, triangle count */
static cm_err check_faces(const cm_mesh *m, uint64_t *ntris, uint32_t *nprims, cm_status *st)
{
    uint64_t nt = 0;
    uint32_t np = 0;
    for (uint32_t f = 0; f < m->nfaces; f++) {
        const cm_mesh_face *fc = &m->faces[f];
        if ((uint64_t)fc->first_vert + fc->nverts > m->nverts)
            return cm_fail_at(st, CM_E_RANGE, f, "cm_out_begin: face vertex range outside the mesh (offset = face)");
        if ((uint64_t)fc->first_index + fc->nindex > m->nindex || fc->nindex % 3u != 0)
            return cm_fail_at(st, CM_E_RANGE, f,
                              "cm_out_begin: face index range outside the mesh or not whole triangles (offset = face)");
        for (uint32_t k0 = 0; k0 < fc->nindex; k0 += CM_OUT_RUN) {
            uint32_t run[CM_OUT_RUN], n = fc->nindex - k0 < CM_OUT_RUN ? fc->nindex - k0 : CM_OUT_RUN;
            cm_mesh_idxs(m, fc->first_index + k0, n, run);
            for (uint32_t k = 0; k < n; k++)
                if (run[k] < fc->first_vert || run[k] - fc->first_vert >= fc->nverts)
                    return cm_fail_at(st, CM_E_RANGE, f, "cm_out_begin: index outside its face's vertices (offset = face)");
        }
        nt += fc->nindex / 3u;
        np += fc->nindex > 0;
    }
    if (nt == 0)
        return cm_fail(st, CM_E_RANGE, "cm_out_begin: empty mesh (no triangle)");
    *ntris = nt;
    *nprims = np;
    return CM_OK;
}

static cm_err check_finite(const cm_mesh *m, int check_normals, cm_status *st)
{
    float p[CM_OUT_RUN][3], n[CM_OUT_RUN][3];
    memset(n, 0, sizeof n);
    for (uint32_t i0 = 0; i0 < m->nverts; i0 += CM_OUT_RUN) {
        uint32_t len = m->nverts - i0 < CM_OUT_RUN ? m->nverts - i0 : CM_OUT_RUN;
        cm_mesh_vecs(m, CM_SPILL_POS, i0, len, p);
        if (check_normals)
            cm_mesh_vecs(m, CM_SPILL_NRM, i0, len, n);
        for (uint32_t i = 0; i < len; i++)
            for (int k = 0; k < 3; k++) {
                if (!f32_finite(p[i][k]))
                    return cm_fail_at(st, CM_E_NONFINITE, i0 + i, "cm_out_begin: position (offset = vertex)");
                if (!f32_finite(n[i][k]))
                    return cm_fail_at(st, CM_E_NONFINITE, i0 + i, "cm_out_begin: normal (offset = vertex)");
            }
    }
    return CM_OK;
}

/*
 * A GLB can show m's copies as nodes: their list is the decoder's (each transform one the format
 * says: finite, invertible), a glTF node matrix (translation, rotation, scale: its columns square to
 * each other), their face ranges in increasing order (the part meshes' primitives are counted
 * forwards).  Else the GLB holds every copy's triangles, as STL and OBJ do.
 */
static int glb_nodes_fit(const cm_mesh *m)
{
    if (m->nplace == 0 || m->place == NULL || m->nbase_faces > m->nfaces || m->nbase_verts > m->nverts ||
        m->nbase_index > m->nindex)
        return 0;
    for (uint32_t k = 0; k < m->nplace; k++) {
        const double *a = m->place[k].m;
        if (cm_fmt_placement_fault(a) || (k > 0 && m->place[k].first < m->place[k - 1].first))
            return 0;
        for (int i = 0; i < 3; i++)
            for (int j = i + 1; j < 3; j++) {
                double dot = a[i] * a[j] + a[4 + i] * a[4 + j] + a[8 + i] * a[8 + j];
                double ni = a[i] * a[i] + a[4 + i] * a[4 + i] + a[8 + i] * a[8 + i];
                double nj = a[j] * a[j] + a[4 + j] * a[4 + j] + a[8 + j] * a[8 + j];
                if (!(dot * dot <= 1e-18 * ni * nj))
                    return 0;
            }
    }
    return 1;
}

/* ---- public ---- */

cm_err cm_out_begin(cm_out *w, cm_out_format fmt, const cm_mesh *m, cm_status *st)
{
    if (w == NULL)
        return cm_fail(st, CM_E_ARG, "cm_out_begin: no writer");
    memset(w, 0, sizeof *w); /* w->m stays NULL until the mesh is accepted: cm_out_next refuses */
    if (m == NULL)
        return cm_fail(st, CM_E_ARG, "cm_out_begin: no mesh");
    if (fmt != CM_OUT_GLB && fmt != CM_OUT_STL && fmt != CM_OUT_OBJ)
        return cm_fail(st, CM_E_ARG, "cm_out_begin: unknown format");
    int normals = fmt != CM_OUT_STL; /* STL computes facet normals */
    cm_err e = check_storage(m, normals, st);
    if (e == CM_OK)
        e = check_faces(m, &w->ntris, &w->nprims, st);
    if (e == CM_OK)
        e = check_finite(m, normals, st);
    if (cm_mesh_spill_failed(m)) { /* what the checks read is moot: zeros stood for it */
        if (st)
            cm_status_init(st);
        e = cm_fail(st, CM_E_IO, "cm_out_begin: reading the mesh back from its spill");
    }
    if (e != CM_OK)
        return e;
    w->fmt = fmt;
    w->m = m;
    if (fmt == CM_OUT_GLB && glb_nodes_fit(m)) {
        /* the copies as nodes: the model's own faces are the file's triangles (validated above) */
        w->whole = m;
        w->base = *m;
        w->base.nfaces = m->nbase_faces;
        w->base.nverts = m->nbase_verts;
        w->base.nindex = m->nbase_index;
        if ((e = check_faces(&w->base, &w->ntris, &w->nprims, st)) != CM_OK)
            return e;
        w->m = &w->base;
    }
    switch (fmt) {
    case CM_OUT_GLB:
        e = cm_glb_begin(w, st);
        break;
    case CM_OUT_STL:
        e = cm_stl_begin(w, st);
        break;
    default:
        e = cm_obj_begin(w, st);
        break;
    }
    if (e != CM_OK)
        w->m = NULL;
    return e;
}

/* next piece into w->pending; empty only when the file is complete */
static cm_err refill(cm_out *w, cm_status *st)
{
    cm_buf b;
    cm_buf_init(&b, w->pending, CM_OUT_PENDING);
    /* a step either appends bytes or moves to the next stage: a few stages at most in a row */
    for (int k = 0; k < 32 && b.n == 0 && !b.overflow && w->stage != CM_OUT_DONE; k++) {
        switch (w->fmt) {
        case CM_OUT_GLB:
            cm_glb_fill(w, &b);
            break;
        case CM_OUT_STL:
            cm_stl_fill(w, &b);
            break;
        default:
            cm_obj_fill(w, &b);
            break;
        }
    }
    w->pending_pos = 0;
    w->npending = b.overflow ? 0 : b.n;
    if (cm_mesh_spill_failed(w->m)) { /* the piece holds zeros for what could not be read back */
        w->stage = CM_OUT_DONE;
        w->npending = 0;
        return cm_fail(st, CM_E_IO, "cm_out_next: reading the mesh back from its spill");
    }
    if (b.overflow || (b.n == 0 && w->stage != CM_OUT_DONE)) {
        w->stage = CM_OUT_DONE;
        return cm_fail(st, CM_E_FORMAT, "cm_out_next: internal piece overflow");
    }
    return CM_OK;
}

cm_err cm_out_next(cm_out *w, uint8_t *buf, size_t cap, size_t *n, int *done, cm_status *st)
{
    if (n != NULL)
        *n = 0;
    if (done != NULL)
        *done = 0;
    if (w == NULL || buf == NULL || n == NULL || done == NULL || cap == 0)
        return cm_fail(st, CM_E_ARG, "cm_out_next: bad argument");
    if (w->m == NULL)
        return cm_fail(st, CM_E_ARG, "cm_out_next: writer not begun (or cm_out_begin failed)");
    size_t pos = 0;
    cm_err e = CM_OK;
    /* every pass copies at least one byte or stops */
    for (size_t iter = 0; iter < cap && pos < cap; iter++) {
        if (w->pending_pos == w->npending) {
            if (w->stage == CM_OUT_DONE)
                break;
            e = refill(w, st);
            if (e != CM_OK || w->npending == 0)
                break;
        }
        size_t k = w->npending - w->pending_pos;
        if (k > cap - pos)
            k = cap - pos;
        memcpy(buf + pos, w->pending + w->pending_pos, k);
        pos += k;
        w->pending_pos += (uint32_t)k;
    }
    /* look ahead so that *done comes with the last bytes when they fit */
    if (e == CM_OK && w->pending_pos == w->npending && w->stage != CM_OUT_DONE)
        e = refill(w, st);
    *n = pos;
    w->written += pos;
    if (e != CM_OK)
        return e;
    if (w->total != 0 && w->written > w->total)
        return cm_fail(st, CM_E_FORMAT, "cm_out_next: output longer than announced (mesh changed?)");
    if (w->stage == CM_OUT_DONE && w->pending_pos == w->npending) {
        if (w->total != 0 && w->written != w->total)
            return cm_fail(st, CM_E_FORMAT, "cm_out_next: output shorter than announced (mesh changed?)");
        *done = 1;
    }
    return CM_OK;
}

uint64_t cm_out_size(const cm_out *w)
{
    return w != NULL && w->m != NULL ? w->total : 0;
}
