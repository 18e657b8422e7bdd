/*
 * cm_glb.c - binary glTF 2.0 (.glb) writer.
 *
 * Layout: 12-byte header; JSON chunk (padded with spaces to 4 bytes); BIN
 * chunk holding, in this order, all positions (float32 VEC3), all normals
 * (float32 VEC3) and the indices of every face with triangles (uint32,
 * rebased to the face's first vertex), face after face.
 *
 * JSON: one buffer; three buffer views (positions and normals with
 * byteStride 12, target ARRAY_BUFFER, shared by the faces' accessors;
 * indices, target ELEMENT_ARRAY_BUFFER); per face with triangles three
 * accessors (POSITION with its exact min/max, NORMAL, indices as
 * UNSIGNED_INT) at the face's byte offsets, so each primitive only sees its
 * own vertices; one mesh "model" with one primitive per face (mode 4,
 * extras {"face": source_face} for picking); one material per distinct
 * face colour (first-use order, at most CM_OUT_MAX_MATERIALS) plus a
 * default light grey for faces without colour or beyond the limit; one
 * root node whose matrix turns CAD millimetres, Z up, into glTF metres, +Y
 * up: glTF (x, y, z) = 0.001 * (x, z, -y) in CAD terms, i.e. a rotation of
 * -90 degrees about X and a scale of 0.001.
 *
 * A mesh with placed copies (format 4.3, cm_mesh.nplace): the buffers hold
 * the model's own faces only; the root node gets a child per copy, whose
 * matrix is the copy's placement (CAD millimetres, under the root's turn),
 * and whose mesh lists the primitives of its part's faces (the same
 * accessors: nothing is stored twice); consecutive copies of one face range
 * share one mesh.  A copy with a negative determinant turns the triangles'
 * winding by glTF's own rule.
 *
 * The GLB header needs the total length before the first byte is written:
 * cm_glb_begin runs the JSON stages once on a copy of the state only to
 * count their bytes (the same functions write them later).
 */
#include <string.h>

#include "cm/cm_format.h"
#include "cm_out_priv.h"

enum {
    GLB_HEADER,      /* file header + JSON chunk header */
    GLB_JSON_HEAD,   /* asset, scene, root node */
    GLB_JSON_CHILD,  /* item = copy: the root's children */
    GLB_JSON_NODE,   /* item = copy: its node; count = part meshes so far */
    GLB_JSON_MESH,   /* start of the meshes */
    GLB_JSON_PRIM,   /* item = face; count = primitives so far */
    GLB_JSON_PART_HEAD, /* item = the first copy of a run of one face range: its mesh */
    GLB_JSON_PART,   /* item as above, sub = mesh face, ibase = its primitive's number */
    GLB_JSON_MAT_HEAD,
    GLB_JSON_MAT,    /* item = material (the default grey last) */
    GLB_JSON_ACC_HEAD,
    GLB_JSON_ACC,    /* item = face, sub = 0 POSITION / 1 NORMAL / 2 indices; count = accessors so far */
    GLB_JSON_TAIL,   /* buffer views, buffer */
    GLB_JSON_PAD,    /* spaces up to 4-byte alignment */
    GLB_BIN_HEAD,
    GLB_BIN_POS,     /* item = vertex */
    GLB_BIN_NRM,     /* item = vertex */
    GLB_BIN_IDX      /* item = face, sub = index inside the face */
};

#define GLB_MAGIC 0x46546C67u      /* "glTF" */
#define GLB_CHUNK_JSON 0x4E4F534Au /* "JSON" */
#define GLB_CHUNK_BIN 0x004E4942u  /* "BIN\0" */
#define GLB_VERTS_PER_PIECE 32u    /* 384 bytes */
#define GLB_INDICES_PER_PIECE 96u  /* 384 bytes */
_Static_assert(GLB_VERTS_PER_PIECE * 12u <= 512u && GLB_INDICES_PER_PIECE * 4u <= 512u, "binary pieces fit pending");

/* n 32-bit words, little-endian (a piece at a time: a call per float was a tenth of the writing) */
static void put_words(cm_buf *b, uint32_t *w, uint32_t n)
{
#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
    for (uint32_t j = 0; j < n; j++) {
        uint8_t *p = (uint8_t *)&w[j];
        uint32_t v = w[j];
        p[0] = (uint8_t)(v & 0xFFu);
        p[1] = (uint8_t)((v >> 8) & 0xFFu);
        p[2] = (uint8_t)((v >> 16) & 0xFFu);
        p[3] = (uint8_t)(v >> 24);
    }
#endif
    cm_buf_bytes(b, w, 4u * n);
}

static uint32_t pad4(uint32_t n)
{
    return (n + 3u) & ~3u;
}

static void set_stage(cm_out *w, uint32_t stage)
{
    w->stage = stage;
    w->item = 0;
    w->sub = 0;
    w->count = 0;
    w->ibase = 0;
}

/* first face at or after w->item with triangles; 0 (and item = nfaces) when none is left */
static int skip_empty_faces(cm_out *w)
{
    const cm_mesh *m = w->m;
    while (w->item < m->nfaces && m->faces[w->item].nindex == 0) /* bounded by nfaces */
        w->item++;
    return w->item < m->nfaces;
}

static uint32_t face_rgb(const cm_mesh_face *fc)
{
    return fc->rgb & 0xFFFFFFu;
}

/* material of a face: its colour's, else the default grey (index nmaterials) */
static uint32_t face_material(const cm_out *w, const cm_mesh_face *fc)
{
    if (fc->has_color) {
        uint32_t rgb = face_rgb(fc);
        for (uint32_t i = 0; i < w->nmaterials; i++)
            if (w->material_rgb[i] == rgb)
                return i;
    }
    return w->nmaterials;
}

/* ---- JSON pieces ---- */

static void json_head(cm_out *w, cm_buf *b)
{
    cm_buf_str(b, "{\"asset\":{\"version\":\"2.0\",\"generator\":\"curvemesh\"},"
                  "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
                  /* column-major: columns are the images of CAD x, y, z in glTF: (s,0,0), (0,0,-s), (0,s,0) */
                  "\"nodes\":[{\"name\":\"model\",\"mesh\":0,"
                  "\"matrix\":[0.001,0,0,0,0,0,-0.001,0,0,0.001,0,0,0,0,0,1]");
    if (w->whole) {
        cm_buf_str(b, ",\"children\":[");
        set_stage(w, GLB_JSON_CHILD);
    } else {
        cm_buf_str(b, "}");
        set_stage(w, GLB_JSON_MESH);
    }
}

/* copy k's part has a triangle (else its node has no mesh: a glTF mesh needs a primitive) */
static int part_has_tris(const cm_out *w, uint32_t k)
{
    const cm_placement *P = &w->whole->place[k];
    const cm_mesh *m = w->m;
    for (uint32_t i = cm_mesh_face_from(m, m->nfaces, P->first); i < m->nfaces && m->faces[i].source_face - P->first < P->count; i++)
        if (m->faces[i].nindex > 0)
            return 1;
    return 0;
}

/* copy k starts a run (its face range differs from copy k-1's) */
static int starts_run(const cm_out *w, uint32_t k)
{
    const cm_placement *P = w->whole->place;
    return k == 0 || P[k].first != P[k - 1].first || P[k].count != P[k - 1].count;
}

static void json_child(cm_out *w, cm_buf *b)
{
    if (w->item >= w->whole->nplace) {
        cm_buf_str(b, "]}");
        set_stage(w, GLB_JSON_NODE);
        return;
    }
    if (w->item > 0)
        cm_buf_str(b, ",");
    cm_buf_u64(b, 1u + (uint64_t)w->item);
    w->item++;
}

/* copy k's node: its part's mesh (1 + the runs with triangles before its own) and its placement */
static void json_node(cm_out *w, cm_buf *b)
{
    uint32_t k = w->item;
    if (k >= w->whole->nplace) {
        set_stage(w, GLB_JSON_MESH);
        return;
    }
    /* count = runs with triangles so far; sub = 1 while the current run has them */
    if (starts_run(w, k)) {
        w->sub = (uint32_t)part_has_tris(w, k);
        w->count += w->sub;
    }
    const double *a = w->whole->place[k].m;
    cm_buf_str(b, ",{\"name\":\"copy\"");
    if (w->sub) {
        cm_buf_str(b, ",\"mesh\":");
        cm_buf_u64(b, w->count);
    }
    cm_buf_str(b, ",\"matrix\":[");
    for (int c = 0; c < 4; c++)
        for (int r = 0; r < 4; r++) {
            if (c + r > 0)
                cm_buf_str(b, ",");
            double v = r == 3 ? (c == 3 ? 1.0 : 0.0) : a[4 * r + c];
            cm_buf_f32(b, (float)v);
        }
    cm_buf_str(b, "]}");
    w->item++;
}

/* a face's primitive: accessors 3a, 3a+1, 3a+2 */
static void prim_json(const cm_out *w, cm_buf *b, const cm_mesh_face *fc, uint64_t a, int first)
{
    a *= 3u;
    if (!first)
        cm_buf_str(b, ",");
    cm_buf_str(b, "{\"attributes\":{\"POSITION\":");
    cm_buf_u64(b, a);
    cm_buf_str(b, ",\"NORMAL\":");
    cm_buf_u64(b, a + 1u);
    cm_buf_str(b, "},\"indices\":");
    cm_buf_u64(b, a + 2u);
    cm_buf_str(b, ",\"material\":");
    cm_buf_u64(b, face_material(w, fc));
    cm_buf_str(b, ",\"mode\":4,\"extras\":{\"face\":");
    cm_buf_u64(b, fc->source_face);
    cm_buf_str(b, "}}");
}

static void json_prim(cm_out *w, cm_buf *b)
{
    if (!skip_empty_faces(w)) {
        set_stage(w, w->whole ? GLB_JSON_PART_HEAD : GLB_JSON_MAT_HEAD);
        return;
    }
    prim_json(w, b, &w->m->faces[w->item], w->count, w->count == 0);
    w->count++;
    w->item++;
}

/* the next run of copies at or after item that has triangles; 0 when none is left */
static int next_run(cm_out *w)
{
    while (w->item < w->whole->nplace && (!starts_run(w, w->item) || !part_has_tris(w, w->item)))
        w->item++;
    return w->item < w->whole->nplace;
}

static void json_part_head(cm_out *w, cm_buf *b)
{
    if (!next_run(w)) {
        set_stage(w, GLB_JSON_MAT_HEAD);
        return;
    }
    const cm_mesh *m = w->m;
    w->sub = cm_mesh_face_from(m, m->nfaces, w->whole->place[w->item].first);
    /* the primitive number of face sub: the faces with triangles before it, counted on from the
       last run's (the ranges only go forwards: glb_nodes_fit) */
    if (w->sub < w->ord_face)
        w->ord_face = w->ord = 0;
    for (; w->ord_face < w->sub; w->ord_face++)
        w->ord += m->faces[w->ord_face].nindex > 0;
    w->ibase = w->ord;
    w->count = 0;
    cm_buf_str(b, "]},{\"name\":\"part\",\"primitives\":[");
    w->stage = GLB_JSON_PART;
}

static void json_part(cm_out *w, cm_buf *b)
{
    const cm_mesh *m = w->m;
    const cm_placement *P = &w->whole->place[w->item];
    while (w->sub < m->nfaces && m->faces[w->sub].source_face - P->first < P->count && m->faces[w->sub].nindex == 0)
        w->sub++;
    if (w->sub >= m->nfaces || m->faces[w->sub].source_face - P->first >= P->count) {
        w->item++;
        w->stage = GLB_JSON_PART_HEAD;
        return;
    }
    prim_json(w, b, &m->faces[w->sub], w->ibase, w->count == 0);
    w->count++;
    w->ibase++;
    w->sub++;
}

static void json_material(cm_out *w, cm_buf *b)
{
    uint32_t nm = w->nmaterials + (w->default_material ? 1u : 0u);
    if (w->item >= nm) {
        set_stage(w, GLB_JSON_ACC_HEAD);
        return;
    }
    if (w->item > 0)
        cm_buf_str(b, ",");
    if (w->item == w->nmaterials) { /* the default grey */
        cm_buf_str(b, "{\"name\":\"default\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.8,0.8,0.8,1]");
    } else {
        static const char hex[] = "0123456789abcdef";
        uint32_t rgb = w->material_rgb[w->item];
        char name[7];
        for (int i = 0; i < 6; i++)
            name[i] = hex[(rgb >> (20 - 4 * i)) & 0xFu];
        name[6] = '\0';
        cm_buf_str(b, "{\"name\":\"rgb_");
        cm_buf_str(b, name);
        cm_buf_str(b, "\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[");
        for (int c = 0; c < 3; c++) {
            uint32_t v = (rgb >> (16 - 8 * c)) & 0xFFu;
            cm_buf_f32(b, (float)((double)v / 255.0));
            cm_buf_str(b, ",");
        }
        cm_buf_str(b, "1]");
    }
    cm_buf_str(b, ",\"metallicFactor\":0,\"roughnessFactor\":0.6},\"doubleSided\":false}");
    w->item++;
}

static void json_vec3(cm_buf *b, const float v[3])
{
    cm_buf_str(b, "[");
    for (int k = 0; k < 3; k++) {
        if (k > 0)
            cm_buf_str(b, ",");
        cm_buf_f32(b, v[k]);
    }
    cm_buf_str(b, "]");
}

static void json_accessor(cm_out *w, cm_buf *b)
{
    if (w->sub == 0 && !skip_empty_faces(w)) {
        set_stage(w, GLB_JSON_TAIL);
        return;
    }
    const cm_mesh *m = w->m;
    const cm_mesh_face *fc = &m->faces[w->item];
    if (w->count > 0)
        cm_buf_str(b, ",");
    if (w->sub < 2) {
        cm_buf_str(b, w->sub == 0 ? "{\"bufferView\":0,\"byteOffset\":" : "{\"bufferView\":1,\"byteOffset\":");
        cm_buf_u64(b, 12u * (uint64_t)fc->first_vert);
        cm_buf_str(b, ",\"componentType\":5126,\"count\":");
        cm_buf_u64(b, fc->nverts);
        cm_buf_str(b, ",\"type\":\"VEC3\"");
        if (w->sub == 0) { /* exact bounds of the vertices this accessor covers */
            float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
            (void)cm_mesh_range_bounds(m, fc->first_vert, fc->nverts, lo, hi); /* (a face with triangles has vertices) */
            cm_buf_str(b, ",\"min\":");
            json_vec3(b, lo);
            cm_buf_str(b, ",\"max\":");
            json_vec3(b, hi);
        }
        cm_buf_str(b, "}");
        w->sub++;
    } else {
        cm_buf_str(b, "{\"bufferView\":2,\"byteOffset\":");
        cm_buf_u64(b, 4u * w->ibase);
        cm_buf_str(b, ",\"componentType\":5125,\"count\":");
        cm_buf_u64(b, fc->nindex);
        cm_buf_str(b, ",\"type\":\"SCALAR\"}");
        w->ibase += fc->nindex;
        w->sub = 0;
        w->item++;
    }
    w->count++;
}

static void json_tail(const cm_out *w, cm_buf *b)
{
    uint64_t pv = 12u * (uint64_t)w->m->nverts, iv = 12u * w->ntris;
    cm_buf_str(b, "],\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":");
    cm_buf_u64(b, pv);
    cm_buf_str(b, ",\"byteStride\":12,\"target\":34962},{\"buffer\":0,\"byteOffset\":");
    cm_buf_u64(b, pv);
    cm_buf_str(b, ",\"byteLength\":");
    cm_buf_u64(b, pv);
    cm_buf_str(b, ",\"byteStride\":12,\"target\":34962},{\"buffer\":0,\"byteOffset\":");
    cm_buf_u64(b, 2u * pv);
    cm_buf_str(b, ",\"byteLength\":");
    cm_buf_u64(b, iv);
    cm_buf_str(b, ",\"target\":34963}],\"buffers\":[{\"byteLength\":");
    cm_buf_u64(b, 2u * pv + iv);
    cm_buf_str(b, "}]}");
}

/* ---- binary pieces ---- */

static void bin_vec3(cm_out *w, cm_buf *b, int normals, uint32_t next)
{
    uint32_t nv = w->m->nverts, i = w->item;
    if (i >= nv) {
        set_stage(w, next);
        return;
    }
    uint32_t n = nv - i > GLB_VERTS_PER_PIECE ? GLB_VERTS_PER_PIECE : nv - i;
    union {
        float f[GLB_VERTS_PER_PIECE][3];
        uint32_t u[3 * GLB_VERTS_PER_PIECE];
    } v;
    cm_mesh_vecs(w->m, normals ? CM_SPILL_NRM : CM_SPILL_POS, i, n, v.f);
    put_words(b, v.u, 3u * n);
    w->item = i + n;
}

static void bin_indices(cm_out *w, cm_buf *b)
{
    if (!skip_empty_faces(w)) {
        w->stage = CM_OUT_DONE;
        return;
    }
    const cm_mesh *m = w->m;
    const cm_mesh_face *fc = &m->faces[w->item];
    uint32_t k = w->sub;
    uint32_t n = fc->nindex - k > GLB_INDICES_PER_PIECE ? GLB_INDICES_PER_PIECE : fc->nindex - k;
    uint32_t idx[GLB_INDICES_PER_PIECE];
    cm_mesh_idxs(m, fc->first_index + k, n, idx);
    for (uint32_t j = 0; j < n; j++)
        idx[j] -= fc->first_vert; /* validated: inside the face */
    put_words(b, idx, n);
    w->sub = k + n;
    if (w->sub == fc->nindex) {
        w->sub = 0;
        w->item++;
    }
}

/* one step: append a piece, or move to the next stage */
void cm_glb_fill(cm_out *w, cm_buf *b)
{
    switch (w->stage) {
    case GLB_HEADER:
        cm_buf_le32(b, GLB_MAGIC);
        cm_buf_le32(b, 2u);
        cm_buf_le32(b, (uint32_t)w->total);
        cm_buf_le32(b, pad4(w->json_len));
        cm_buf_le32(b, GLB_CHUNK_JSON);
        set_stage(w, GLB_JSON_HEAD);
        break;
    case GLB_JSON_HEAD:
        json_head(w, b);
        break;
    case GLB_JSON_CHILD:
        json_child(w, b);
        break;
    case GLB_JSON_NODE:
        json_node(w, b);
        break;
    case GLB_JSON_MESH:
        cm_buf_str(b, "],\"meshes\":[{\"name\":\"model\",\"primitives\":[");
        set_stage(w, GLB_JSON_PRIM);
        break;
    case GLB_JSON_PRIM:
        json_prim(w, b);
        break;
    case GLB_JSON_PART_HEAD:
        json_part_head(w, b);
        break;
    case GLB_JSON_PART:
        json_part(w, b);
        break;
    case GLB_JSON_MAT_HEAD:
        cm_buf_str(b, "]}],\"materials\":[");
        set_stage(w, GLB_JSON_MAT);
        break;
    case GLB_JSON_MAT:
        json_material(w, b);
        break;
    case GLB_JSON_ACC_HEAD:
        cm_buf_str(b, "],\"accessors\":[");
        set_stage(w, GLB_JSON_ACC);
        break;
    case GLB_JSON_ACC:
        json_accessor(w, b);
        break;
    case GLB_JSON_TAIL:
        json_tail(w, b);
        set_stage(w, GLB_JSON_PAD);
        break;
    case GLB_JSON_PAD:
        cm_buf_bytes(b, "   ", pad4(w->json_len) - w->json_len);
        set_stage(w, GLB_BIN_HEAD);
        break;
    case GLB_BIN_HEAD:
        cm_buf_le32(b, w->bin_len);
        cm_buf_le32(b, GLB_CHUNK_BIN);
        set_stage(w, GLB_BIN_POS);
        break;
    case GLB_BIN_POS:
        bin_vec3(w, b, 0, GLB_BIN_NRM);
        break;
    case GLB_BIN_NRM:
        bin_vec3(w, b, 1, GLB_BIN_IDX);
        break;
    case GLB_BIN_IDX:
        bin_indices(w, b);
        break;
    default:
        w->stage = CM_OUT_DONE;
        break;
    }
}

/* materials in first-use order over the faces with triangles */
static void collect_materials(cm_out *w)
{
    const cm_mesh *m = w->m;
    w->nmaterials = 0;
    w->default_material = 0;
    for (uint32_t f = 0; f < m->nfaces; f++) {
        const cm_mesh_face *fc = &m->faces[f];
        if (fc->nindex == 0)
            continue;
        if (face_material(w, fc) < w->nmaterials)
            continue; /* colour already has its material */
        if (fc->has_color && w->nmaterials < CM_OUT_MAX_MATERIALS)
            w->material_rgb[w->nmaterials++] = face_rgb(fc);
        else
            w->default_material = 1;
    }
}

cm_err cm_glb_begin(cm_out *w, cm_status *st)
{
    collect_materials(w);

    /* JSON length: run its stages on a copy, counting bytes */
    cm_out t = *w;
    set_stage(&t, GLB_JSON_HEAD);
    uint64_t json = 0;
    uint64_t max_steps = 4u * (uint64_t)w->m->nfaces + 2u * CM_OUT_MAX_MATERIALS + 16u;
    if (w->whole) /* children, nodes, and per run a head and its faces */
        max_steps += 4u * (uint64_t)w->whole->nplace + 2u * (uint64_t)w->whole->nplace * ((uint64_t)w->m->nfaces + 2u);
    for (uint64_t k = 0; k < max_steps && t.stage != GLB_JSON_PAD; k++) {
        cm_buf b;
        cm_buf_init(&b, t.pending, CM_OUT_PENDING);
        cm_glb_fill(&t, &b);
        if (b.overflow)
            return cm_fail(st, CM_E_FORMAT, "cm_glb_begin: internal piece overflow");
        json += b.n;
    }
    if (t.stage != GLB_JSON_PAD)
        return cm_fail(st, CM_E_FORMAT, "cm_glb_begin: JSON stages did not finish");

    uint64_t bin = 24u * (uint64_t)w->m->nverts + 12u * w->ntris;
    uint64_t total = 12u + 8u + ((json + 3u) & ~(uint64_t)3u) + 8u + bin;
    if (total > UINT32_MAX)
        return cm_fail(st, CM_E_RANGE, "cm_glb_begin: model too large for GLB's 32-bit length");
    w->json_len = (uint32_t)json;
    w->bin_len = (uint32_t)bin;
    w->total = total;
    set_stage(w, GLB_HEADER);
    return CM_OK;
}
