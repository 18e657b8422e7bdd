/*
 * cm_stl.c - binary STL writer.
 *
 * 80-byte header ("curvemesh binary STL", padded with spaces: never
 * "solid", which readers take for ASCII STL), uint32 triangle count, then
 * per triangle of every face in face order: facet normal (float32 x3, unit,
 * computed from the triangle's vertices in double; the zero vector for a
 * degenerate triangle), three vertices (float32 x3, millimetres as is) and
 * a uint16 attribute 0.  50 bytes a triangle, all little-endian.
 */
#include <math.h>
#include <string.h>

#include "cm_out_priv.h"

enum {
    STL_HEADER, /* header + triangle count */
    STL_TRIS    /* item = face, sub = triangle inside the face */
};

#define STL_HEADER_TEXT "curvemesh binary STL"
#define STL_TRIS_PER_PIECE 8u /* 400 bytes */
_Static_assert(STL_TRIS_PER_PIECE * 50u <= 512u, "STL piece fits pending");

static void stl_header(const cm_out *w, cm_buf *b)
{
    uint8_t h[80];
    memset(h, ' ', sizeof h);
    memcpy(h, STL_HEADER_TEXT, sizeof STL_HEADER_TEXT - 1);
    cm_buf_bytes(b, h, sizeof h);
    cm_buf_le32(b, (uint32_t)w->ntris);
}

/* unit normal of triangle (a, b, c), counter-clockwise; zero if degenerate */
static void facet_normal(const float *a, const float *b, const float *c, float n[3])
{
    double u[3], v[3];
    for (int k = 0; k < 3; k++) {
        u[k] = (double)b[k] - (double)a[k];
        v[k] = (double)c[k] - (double)a[k];
    }
    double x = u[1] * v[2] - u[2] * v[1];
    double y = u[2] * v[0] - u[0] * v[2];
    double z = u[0] * v[1] - u[1] * v[0];
    double len = sqrt(x * x + y * y + z * z); /* finite: float inputs cannot overflow a double here */
    if (!(len > 0.0)) {
        n[0] = n[1] = n[2] = 0.0f;
        return;
    }
    n[0] = (float)(x / len);
    n[1] = (float)(y / len);
    n[2] = (float)(z / len);
}

static void stl_tris(cm_out *w, cm_buf *b)
{
    const cm_mesh *m = w->m;
    while (w->item < m->nfaces && m->faces[w->item].nindex == 0) /* bounded by nfaces */
        w->item++;
    if (w->item >= m->nfaces) {
        w->stage = CM_OUT_DONE;
        return;
    }
    const cm_mesh_face *fc = &m->faces[w->item];
    uint32_t nt = cm_out_face_tris(m, w->item);
    uint32_t t = w->sub;
    uint32_t end = nt - t > STL_TRIS_PER_PIECE ? t + STL_TRIS_PER_PIECE : nt;
    for (; t < end; t++) {
        const uint32_t t0 = fc->first_index + 3u * t;
        float p0[3], p1[3], p2[3];
        cm_mesh_pos(m, cm_mesh_idx(m, t0), p0);
        cm_mesh_pos(m, cm_mesh_idx(m, t0 + 1u), p1);
        cm_mesh_pos(m, cm_mesh_idx(m, t0 + 2u), p2);
        float n[3];
        facet_normal(p0, p1, p2, n);
        for (int k = 0; k < 3; k++)
            cm_buf_lef32(b, n[k]);
        for (int k = 0; k < 3; k++)
            cm_buf_lef32(b, p0[k]);
        for (int k = 0; k < 3; k++)
            cm_buf_lef32(b, p1[k]);
        for (int k = 0; k < 3; k++)
            cm_buf_lef32(b, p2[k]);
        cm_buf_le16(b, 0);
    }
    w->sub = end;
    if (w->sub == nt) {
        w->sub = 0;
        w->item++;
    }
}

void cm_stl_fill(cm_out *w, cm_buf *b)
{
    switch (w->stage) {
    case STL_HEADER:
        stl_header(w, b);
        w->stage = STL_TRIS;
        w->item = 0;
        w->sub = 0;
        break;
    case STL_TRIS:
        stl_tris(w, b);
        break;
    default:
        w->stage = CM_OUT_DONE;
        break;
    }
}

cm_err cm_stl_begin(cm_out *w, cm_status *st)
{
    if (w->ntris > UINT32_MAX)
        return cm_fail(st, CM_E_RANGE, "cm_stl_begin: more triangles than STL's 32-bit count");
    w->total = 84u + 50u * w->ntris;
    w->stage = STL_HEADER;
    return CM_OK;
}
