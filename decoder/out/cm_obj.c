/*
 * cm_obj.c - Wavefront OBJ writer (text, millimetres, CAD axes).
 *
 *   # curvemesh OBJ: millimetres, CAD axes (Z up)
 *   # V vertices, T triangles, F faces
 *   v x y z            all vertices, in mesh order
 *   vn x y z           their normals, same order
 *   g face_N           per face with triangles, N = the face's source_face
 *   f a//a b//b c//c   its triangles, 1-based vertex (= normal) numbers
 *
 * Numbers are cm_fmt_f32 text (read back bit-exact), lines end in "\n".
 * The size is known only at the end (cm_out_size gives 0).
 */
#include "cm_out_priv.h"

enum {
    OBJ_HEADER,
    OBJ_V,     /* item = vertex */
    OBJ_VN,    /* item = vertex */
    OBJ_FACES  /* item = face, sub = triangle inside the face */
};

/* longest lines: "vn " + 3 numbers of 15 + 2 spaces + "\n" = 51; "f " + 3 x (10+2+10) + 2 + 1 = 71 */
#define OBJ_VLINE_MAX 64u
#define OBJ_FLINE_MAX 80u

static void set_stage(cm_out *w, uint32_t stage)
{
    w->stage = stage;
    w->item = 0;
    w->sub = 0;
}

static void obj_header(const cm_out *w, cm_buf *b)
{
    cm_buf_str(b, "# curvemesh OBJ: millimetres, CAD axes (Z up)\n# ");
    cm_buf_u64(b, w->m->nverts);
    cm_buf_str(b, " vertices, ");
    cm_buf_u64(b, w->ntris);
    cm_buf_str(b, " triangles, ");
    cm_buf_u64(b, w->nprims);
    cm_buf_str(b, " faces\n");
}

/* lines "<tag> x y z" for vertices from w->item on, while they fit */
static void obj_vectors(cm_out *w, cm_buf *b, const char *tag, int normals, uint32_t next)
{
    uint32_t nv = w->m->nverts;
    if (w->item >= nv) {
        set_stage(w, next);
        return;
    }
    while (w->item < nv && cm_buf_room(b) >= OBJ_VLINE_MAX) { /* bounded by nverts */
        float p[3];
        if (normals)
            cm_mesh_nrm(w->m, w->item, p);
        else
            cm_mesh_pos(w->m, w->item, p);
        cm_buf_str(b, tag);
        for (int k = 0; k < 3; k++) {
            cm_buf_str(b, " ");
            cm_buf_f32(b, p[k]);
        }
        cm_buf_str(b, "\n");
        w->item++;
    }
}

static void obj_faces(cm_out *w, cm_buf *b)
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
    if (w->sub == 0) {
        cm_buf_str(b, "g face_");
        cm_buf_u64(b, fc->source_face);
        cm_buf_str(b, "\n");
    }
    while (w->sub < nt && cm_buf_room(b) >= OBJ_FLINE_MAX) { /* bounded by nt */
        const uint32_t t0 = fc->first_index + 3u * w->sub;
        cm_buf_str(b, "f");
        for (int k = 0; k < 3; k++) {
            uint64_t v = (uint64_t)cm_mesh_idx(m, t0 + (uint32_t)k) + 1u;
            cm_buf_str(b, " ");
            cm_buf_u64(b, v);
            cm_buf_str(b, "//");
            cm_buf_u64(b, v);
        }
        cm_buf_str(b, "\n");
        w->sub++;
    }
    if (w->sub == nt) {
        w->sub = 0;
        w->item++;
    }
}

void cm_obj_fill(cm_out *w, cm_buf *b)
{
    switch (w->stage) {
    case OBJ_HEADER:
        obj_header(w, b);
        set_stage(w, OBJ_V);
        break;
    case OBJ_V:
        obj_vectors(w, b, "v", 0, OBJ_VN);
        break;
    case OBJ_VN:
        obj_vectors(w, b, "vn", 1, OBJ_FACES);
        break;
    case OBJ_FACES:
        obj_faces(w, b);
        break;
    default:
        w->stage = CM_OUT_DONE;
        break;
    }
}

cm_err cm_obj_begin(cm_out *w, cm_status *st)
{
    (void)st;
    w->total = 0;
    set_stage(w, OBJ_HEADER);
    return CM_OK;
}
