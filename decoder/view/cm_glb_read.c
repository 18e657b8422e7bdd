/*
 * cm_glb_read.c - a .glb into the viewer's mesh (see cm_glb_read.h).
 *
 * The JSON is read once, a byte at a time through the window, by a loop over an explicit stack of
 * open containers (no recursion); each value is judged by its path (the keys and indices of the
 * containers around it) against the few paths glTF's core puts geometry at.  Then the scene's nodes
 * are walked breadth first and each primitive's accessors are read from the BIN chunk.
 */
#include "cm/cm_glb_read.h"

#include <math.h>
#include <string.h>

#include "cm/cm_limits_info.h"

#define GLB_MAGIC 0x46546C67u /* "glTF" */
#define GLB_JSON 0x4E4F534Au  /* "JSON" */
#define GLB_BIN 0x004E4942u   /* "BIN\0" */

/* the keys a path is made of (K_OTHER: any other) */
enum {
    K_OTHER,
    K_ACCESSORS, K_BUFFERVIEW, K_BYTEOFFSET, K_COMPONENTTYPE, K_COUNT, K_TYPE, K_SPARSE,
    K_BUFFERVIEWS, K_BUFFER, K_BYTELENGTH, K_BYTESTRIDE, K_BUFFERS, K_URI,
    K_MESHES, K_PRIMITIVES, K_ATTRIBUTES, K_POSITION, K_NORMAL, K_INDICES, K_MATERIAL, K_MODE,
    K_MATERIALS, K_NAME, K_PBR, K_BASECOLOR,
    K_NODES, K_MESH, K_MATRIX, K_TRANSLATION, K_ROTATION, K_SCALE, K_CHILDREN, K_SCENE, K_SCENES,
    K_COUNT_OF_KEYS
};

static const char *const key_names[K_COUNT_OF_KEYS] = {
    "", "accessors", "bufferView", "byteOffset", "componentType", "count", "type", "sparse",
    "bufferViews", "buffer", "byteLength", "byteStride", "buffers", "uri",
    "meshes", "primitives", "attributes", "POSITION", "NORMAL", "indices", "material", "mode",
    "materials", "name", "pbrMetallicRoughness", "baseColorFactor",
    "nodes", "mesh", "matrix", "translation", "rotation", "scale", "children", "scene", "scenes"};

/* a JSON token's value */
enum { J_NONE, J_OBJ, J_ARR, J_STR, J_NUM, J_LIT };
typedef struct jval {
    int kind;
    double num;
    char str[40]; /* a string's first bytes (longer ones are no key nor type name we know) */
    uint32_t len;
} jval;

/* ---------------------------------------------------------------- the file through the window */

/* the byte at off (< file_len): 0..255, or -1 when src failed */
static int byte_at(cm_glb_reader *g, uint64_t off)
{
    if (off - g->win_off >= g->win_n) {
        uint64_t n = g->file_len - off < CM_GLB_WINDOW ? g->file_len - off : CM_GLB_WINDOW;
        if (g->src(g->ctx, off, g->win, (size_t)n) != 0) {
            g->win_n = 0;
            return -1;
        }
        g->win_off = off;
        g->win_n = (uint32_t)n;
    }
    return g->win[off - g->win_off];
}

/* n (<= 16) bytes at off into out: 0, or -1 when src failed */
static int bytes_at(cm_glb_reader *g, uint64_t off, uint8_t *out, uint32_t n)
{
    if (off - g->win_off >= g->win_n || g->win_n - (off - g->win_off) < n) {
        g->win_n = 0;
        if (byte_at(g, off) < 0 || g->win_n < n)
            return -1;
    }
    memcpy(out, g->win + (off - g->win_off), n);
    return 0;
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static float lef32(const uint8_t *p)
{
    uint32_t u = le32(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* ---------------------------------------------------------------- JSON tokens */

typedef struct jcursor {
    cm_glb_reader *g;
    uint64_t at, end;
    int io; /* src failed */
} jcursor;

/* the next byte (-1 at the end or on a failed read) */
static int jpeek(jcursor *c)
{
    if (c->at >= c->end)
        return -1;
    int b = byte_at(c->g, c->at);
    if (b < 0)
        c->io = 1;
    return b;
}

static void jskip_space(jcursor *c)
{
    for (int b = jpeek(c); b == ' ' || b == '\t' || b == '\n' || b == '\r'; b = jpeek(c))
        c->at++;
}

/* a string after its opening quote: its first bytes into v (escapes kept as a byte each); 0, or -1
   when it does not end */
static int jstring(jcursor *c, jval *v)
{
    v->kind = J_STR;
    v->len = 0;
    for (;;) {
        int b = jpeek(c);
        if (b < 0 || b < 0x20)
            return -1;
        c->at++;
        if (b == '"')
            break;
        if (b == '\\') { /* the escaped byte (\uXXXX: its four digits follow as bytes) */
            if ((b = jpeek(c)) < 0)
                return -1;
            c->at++;
        }
        if (v->len < sizeof v->str - 1)
            v->str[v->len] = (char)b;
        v->len++;
    }
    v->str[v->len < sizeof v->str - 1 ? v->len : sizeof v->str - 1] = '\0';
    return 0;
}

/* a number: up to 19 significant digits and a decimal exponent, made a double with a single
   rounding where the digits and the power of ten are exact in a double (the numbers a writer prints
   of a float or an index), else close to it; 0, or -1 when it is no number */
static int jnumber(jcursor *c, jval *v)
{
    static const double p10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                   1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    int neg = 0, digits = 0, b;
    uint64_t m = 0;
    int32_t e10 = 0;
    if (jpeek(c) == '-') {
        neg = 1;
        c->at++;
    }
    for (int frac = 0; frac < 2; frac++) {
        while ((b = jpeek(c)) >= '0' && b <= '9') {
            c->at++;
            digits++;
            if (m < 1000000000000000000ull)
                m = m * 10u + (uint64_t)(b - '0'), e10 -= frac;
            else
                e10 += 1 - frac;
        }
        if (frac == 0 && b == '.')
            c->at++;
        else
            break;
    }
    if (digits == 0)
        return -1;
    b = jpeek(c);
    if (b == 'e' || b == 'E') {
        c->at++;
        int eneg = 0, edigits = 0;
        int32_t e = 0;
        b = jpeek(c);
        if (b == '+' || b == '-') {
            eneg = b == '-';
            c->at++;
        }
        while ((b = jpeek(c)) >= '0' && b <= '9') {
            c->at++;
            edigits++;
            e = e < 100000 ? e * 10 + (b - '0') : e;
        }
        if (edigits == 0)
            return -1;
        e10 += eneg ? -e : e;
    }
    double x = (double)m;
    int32_t e = e10;
    while (e > 22 && x < 1e300) /* (beyond a double's range: the loops stop at infinity or 0) */
        x *= 1e22, e -= 22;
    while (e < -22 && x > 1e-300)
        x /= 1e22, e += 22;
    if (e > 22 || e < -22)
        x = e > 0 ? x * 1e22 : 0.0;
    else
        x = e >= 0 ? x * p10[e] : x / p10[-e];
    v->kind = J_NUM;
    v->num = neg ? -x : x;
    return 0;
}

/* true, false or null (whichever: none of them is a field we read) */
static int jliteral(jcursor *c, jval *v)
{
    int n = 0, b;
    while ((b = jpeek(c)) >= 'a' && b <= 'z' && n < 6) {
        c->at++;
        n++;
    }
    v->kind = J_LIT;
    return n >= 4 && n <= 5 ? 0 : -1;
}

/* a string's first bytes are s (the decoder imports no string comparison but memcmp: check-noheap) */
static int is(const jval *v, const char *s)
{
    size_t n = strlen(s);
    return v->kind == J_STR && v->len == n && memcmp(v->str, s, n) == 0;
}

static uint8_t key_id(const jval *v)
{
    for (uint8_t k = 1; k < K_COUNT_OF_KEYS; k++)
        if (is(v, key_names[k]))
            return k;
    return K_OTHER;
}

/* ---------------------------------------------------------------- what a value at a path means */

/* a number that is an index or a count: 0, or -1 */
static int as_u32(const jval *v, uint32_t *out)
{
    if (v->kind != J_NUM || !(v->num >= 0.0 && v->num < 4294967295.0) || v->num != floor(v->num))
        return -1;
    *out = (uint32_t)v->num;
    return 0;
}

typedef struct jpath {
    const cm_glb_jframe *f;
    int d; /* containers around the value (f[0] the root object) */
} jpath;

static int key_at(const jpath *p, int k) { return k < p->d && p->f[k].object ? p->f[k].key : -1; }
static uint32_t index_at(const jpath *p, int k) { return p->f[k].index; }

static cm_err limit(cm_status *st, uint64_t need, uint64_t have, const char *what)
{
    return cm_fail_limit(st, CM_NO_LIMIT, need, have, what);
}

static void node_init(cm_glb_node *n)
{
    int32_t parent = n->parent; /* (set by a node listed before it: kept) */
    memset(n, 0, sizeof *n);
    n->parent = parent;
    n->mesh = -1;
    n->r[3] = 1.0;
    n->s[0] = n->s[1] = n->s[2] = 1.0;
    for (int i = 0; i < 16; i += 5)
        n->m[i] = 1.0;
}

/* an object or array opens at path p (kind J_OBJ / J_ARR): the records it starts */
static cm_err on_open(cm_glb_reader *g, const jpath *p, int kind, cm_status *st)
{
    int k0 = key_at(p, 0);
    if (p->d == 2 && kind == J_OBJ) { /* an element of a top-level array */
        uint32_t i = index_at(p, 1);
        if (k0 == K_ACCESSORS) {
            if (i >= CM_GLB_MAX_ACCESSORS)
                return limit(st, (uint64_t)i + 1, CM_GLB_MAX_ACCESSORS, "glTF accessors (CM_GLB_MAX_ACCESSORS)");
            g->accessors[i] = (cm_glb_accessor){UINT32_MAX, 0, 0, 0, 0, 0};
            g->naccessors = i + 1;
        } else if (k0 == K_BUFFERVIEWS) {
            if (i >= CM_GLB_MAX_VIEWS)
                return limit(st, (uint64_t)i + 1, CM_GLB_MAX_VIEWS, "glTF buffer views (CM_GLB_MAX_VIEWS)");
            g->views[i] = (cm_glb_view){0, 0, 0, 0};
            g->nviews = i + 1;
        } else if (k0 == K_MESHES) {
            if (i >= CM_GLB_MAX_PRIMS)
                return limit(st, (uint64_t)i + 1, CM_GLB_MAX_PRIMS, "glTF meshes (CM_GLB_MAX_PRIMS)");
            g->nmeshes = i + 1;
        } else if (k0 == K_MATERIALS) {
            if (i >= CM_GLB_MAX_MATERIALS)
                return limit(st, (uint64_t)i + 1, CM_GLB_MAX_MATERIALS, "glTF materials (CM_GLB_MAX_MATERIALS)");
            g->material_rgb[i] = 0xffffffu; /* glTF's default base colour: white */
            g->material_color[i] = 1;
            g->nmaterials = i + 1;
        } else if (k0 == K_NODES) {
            if (i >= CM_GLB_MAX_NODES)
                return limit(st, (uint64_t)i + 1, CM_GLB_MAX_NODES, "glTF nodes (CM_GLB_MAX_NODES)");
            node_init(&g->nodes[i]);
            g->nnodes = g->nnodes > i + 1 ? g->nnodes : i + 1;
        }
    } else if (p->d == 4 && kind == J_OBJ && k0 == K_MESHES && key_at(p, 2) == K_PRIMITIVES) {
        if (g->nprims >= CM_GLB_MAX_PRIMS)
            return limit(st, (uint64_t)g->nprims + 1, CM_GLB_MAX_PRIMS, "glTF primitives (CM_GLB_MAX_PRIMS)");
        g->prims[g->nprims++] = (cm_glb_prim){-1, -1, -1, -1, index_at(p, 1), 4};
    } else if (p->d == 3 && k0 == K_ACCESSORS && key_at(p, 2) == K_SPARSE && index_at(p, 1) < g->naccessors) {
        g->accessors[index_at(p, 1)].sparse = 1;
    }
    return CM_OK;
}

/* a number, string or literal v at path p */
static cm_err on_scalar(cm_glb_reader *g, const jpath *p, const jval *v, cm_status *st)
{
    const int k0 = key_at(p, 0), d = p->d;
    uint32_t u = 0;
    int is_u = as_u32(v, &u) == 0;
    if (d == 1 && k0 == K_SCENE) {
        if (!is_u)
            return cm_fail(st, CM_E_FORMAT, "glTF scene: not an index");
        g->scene = (int32_t)(u < 0x7fffffffu ? u : 0x7fffffffu);
        return CM_OK;
    }
    if (d == 3 && k0 == K_ACCESSORS && index_at(p, 1) < g->naccessors) {
        cm_glb_accessor *a = &g->accessors[index_at(p, 1)];
        int k = key_at(p, 2);
        if (k == K_TYPE && v->kind == J_STR)
            a->ncomp = is(v, "SCALAR") ? 1 : is(v, "VEC3") ? 3 : 0;
        else if ((k == K_BUFFERVIEW || k == K_BYTEOFFSET || k == K_COMPONENTTYPE || k == K_COUNT) && !is_u)
            return cm_fail(st, CM_E_FORMAT, "glTF accessor: a field that is not a count");
        else if (k == K_BUFFERVIEW)
            a->view = u;
        else if (k == K_BYTEOFFSET)
            a->offset = u;
        else if (k == K_COMPONENTTYPE)
            a->ctype = (uint16_t)(u < 65535u ? u : 0);
        else if (k == K_COUNT)
            a->count = u;
        return CM_OK;
    }
    if (d == 3 && k0 == K_BUFFERVIEWS && index_at(p, 1) < g->nviews) {
        cm_glb_view *w = &g->views[index_at(p, 1)];
        int k = key_at(p, 2);
        if ((k == K_BUFFER || k == K_BYTEOFFSET || k == K_BYTELENGTH || k == K_BYTESTRIDE) && !is_u)
            return cm_fail(st, CM_E_FORMAT, "glTF buffer view: a field that is not a count");
        if (k == K_BUFFER)
            w->buffer = u;
        else if (k == K_BYTEOFFSET)
            w->offset = u;
        else if (k == K_BYTELENGTH)
            w->length = u;
        else if (k == K_BYTESTRIDE)
            w->stride = u;
        return CM_OK;
    }
    if (d == 3 && k0 == K_BUFFERS && key_at(p, 2) == K_URI) {
        g->buffer0_uri |= index_at(p, 1) == 0;
        return CM_OK;
    }
    if (d >= 5 && k0 == K_MESHES && key_at(p, 2) == K_PRIMITIVES && g->nprims > 0) {
        cm_glb_prim *q = &g->prims[g->nprims - 1];
        int k = key_at(p, 4), ka = d == 6 && k == K_ATTRIBUTES ? key_at(p, 5) : -1;
        int32_t *field = d == 5 && k == K_INDICES ? &q->idx : d == 5 && k == K_MATERIAL ? &q->material
                         : ka == K_POSITION       ? &q->pos
                         : ka == K_NORMAL         ? &q->nrm
                                                  : NULL;
        if ((field || (d == 5 && k == K_MODE)) && !(is_u && u < 0x7fffffffu))
            return cm_fail(st, CM_E_FORMAT, "glTF primitive: a field that is not an index");
        if (field)
            *field = (int32_t)u;
        else if (d == 5 && k == K_MODE)
            q->mode = (uint8_t)(u < 255u ? u : 255u);
        return CM_OK;
    }
    if (k0 == K_MATERIALS && d >= 3 && index_at(p, 1) < g->nmaterials) {
        uint32_t i = index_at(p, 1);
        if (d == 3 && key_at(p, 2) == K_NAME && is(v, "default"))
            g->material_color[i] = 0; /* `cmz decode`'s material of the faces without colour */
        if (d == 5 && key_at(p, 2) == K_PBR && key_at(p, 3) == K_BASECOLOR && index_at(p, 4) < 3) {
            if (v->kind != J_NUM)
                return cm_fail(st, CM_E_FORMAT, "glTF material: a colour that is not a number");
            double x = v->num < 0.0 ? 0.0 : v->num > 1.0 ? 1.0 : v->num;
            uint32_t c = (uint32_t)floor(x * 255.0 + 0.5), sh = 16u - 8u * index_at(p, 4);
            g->material_rgb[i] = (g->material_rgb[i] & ~(0xffu << sh)) | (c << sh);
        }
        return CM_OK;
    }
    if (k0 == K_NODES && d >= 3 && index_at(p, 1) < g->nnodes) {
        uint32_t i = index_at(p, 1);
        cm_glb_node *n = &g->nodes[i];
        int k = key_at(p, 2);
        if (d == 3 && k == K_MESH) {
            if (!(is_u && u < 0x7fffffffu))
                return cm_fail(st, CM_E_FORMAT, "glTF node: a mesh that is not an index");
            n->mesh = (int32_t)u;
        } else if (d == 4 && (k == K_MATRIX || k == K_TRANSLATION || k == K_ROTATION || k == K_SCALE)) {
            uint32_t c = index_at(p, 3);
            if (v->kind != J_NUM || !isfinite(v->num))
                return cm_fail(st, CM_E_FORMAT, "glTF node: a transform that is not a number");
            if (k == K_MATRIX && c < 16)
                n->m[c] = v->num, n->has_matrix = 1;
            else if (k == K_TRANSLATION && c < 3)
                n->t[c] = v->num;
            else if (k == K_ROTATION && c < 4)
                n->r[c] = v->num;
            else if (k == K_SCALE && c < 3)
                n->s[c] = v->num;
        } else if (d == 4 && k == K_CHILDREN) {
            if (!is_u || u >= CM_GLB_MAX_NODES)
                return is_u ? limit(st, (uint64_t)u + 1, CM_GLB_MAX_NODES, "glTF nodes (CM_GLB_MAX_NODES)")
                            : cm_fail(st, CM_E_FORMAT, "glTF node: a child that is not an index");
            if (g->nodes[u].parent >= 0 || u == i)
                return cm_fail(st, CM_E_FORMAT, "glTF node: a node with two parents (or its own)");
            g->nodes[u].parent = (int32_t)i;
        }
        return CM_OK;
    }
    if (d == 4 && k0 == K_SCENES && key_at(p, 2) == K_NODES) {
        if (!is_u)
            return cm_fail(st, CM_E_FORMAT, "glTF scene: a node that is not an index");
        if (g->nroots >= CM_GLB_MAX_NODES)
            return limit(st, (uint64_t)g->nroots + 1, CM_GLB_MAX_NODES, "glTF scenes' nodes (CM_GLB_MAX_NODES)");
        g->root_scene[g->nroots] = index_at(p, 1);
        g->root_node[g->nroots++] = u;
    }
    return CM_OK;
}

/* ---------------------------------------------------------------- the JSON chunk */

static cm_err parse_json(cm_glb_reader *g, uint64_t at, uint64_t end, cm_status *st)
{
    jcursor c = {g, at, end, 0};
    enum { VALUE, FIRST_KEY, KEY, COLON, AFTER, FIRST_ELEM } want = VALUE;
    int depth = 0; /* containers open; frames kept for the first CM_GLB_MAX_DEPTH */
    uint8_t open_obj[64];   /* (whether each open container up to 64 deep is an object) */
    cm_err e = CM_OK;
    for (;;) {
        jskip_space(&c);
        int b = jpeek(&c);
        if (c.io)
            return cm_fail_at(st, CM_E_IO, (uint32_t)c.at, "glTF JSON: reading the file");
        if (b < 0)
            return cm_fail_at(st, CM_E_TRUNCATED, (uint32_t)c.at, "glTF JSON: ends inside its value");
        jpath p = {g->frame, depth < CM_GLB_MAX_DEPTH ? depth : CM_GLB_MAX_DEPTH};
        int tracked = depth <= CM_GLB_MAX_DEPTH;
        if (want == FIRST_KEY && b == '}') {
            want = AFTER;
            c.at++;
            depth--;
        } else if (want == FIRST_ELEM && b == ']') {
            want = AFTER;
            c.at++;
            depth--;
        } else if (want == FIRST_KEY || want == KEY) {
            jval k;
            if (b != '"' || (c.at++, jstring(&c, &k)) != 0)
                return cm_fail_at(st, CM_E_FORMAT, (uint32_t)c.at, "glTF JSON: a key expected");
            if (depth - 1 < CM_GLB_MAX_DEPTH)
                g->frame[depth - 1].key = key_id(&k);
            want = COLON;
        } else if (want == COLON) {
            if (b != ':')
                return cm_fail_at(st, CM_E_FORMAT, (uint32_t)c.at, "glTF JSON: ':' expected");
            c.at++;
            want = VALUE;
        } else if (want == AFTER) {
            if (depth == 0)
                return CM_OK; /* the root value is whole (what follows it is padding) */
            int obj = open_obj[depth - 1 < 64 ? depth - 1 : 63];
            c.at++;
            if (b == ',') {
                want = obj ? KEY : VALUE;
                if (!obj && depth - 1 < CM_GLB_MAX_DEPTH)
                    g->frame[depth - 1].index++;
            } else if (b == (obj ? '}' : ']')) {
                depth--;
            } else {
                return cm_fail_at(st, CM_E_FORMAT, (uint32_t)c.at - 1, "glTF JSON: ',' or the container's end expected");
            }
        } else { /* a value: FIRST_ELEM or VALUE */
            if (b == '{' || b == '[') {
                if (depth == 0 && b != '{')
                    return cm_fail_at(st, CM_E_FORMAT, (uint32_t)c.at, "glTF JSON: not an object");
                if (depth >= 64)
                    return cm_fail_at(st, CM_E_LIMIT, (uint32_t)c.at, "glTF JSON: nested more than 64 deep");
                if (tracked && (e = on_open(g, &p, b == '{' ? J_OBJ : J_ARR, st)) != CM_OK)
                    return e;
                c.at++;
                open_obj[depth] = b == '{';
                if (depth < CM_GLB_MAX_DEPTH)
                    g->frame[depth] = (cm_glb_jframe){(uint8_t)(b == '{'), K_OTHER, 0};
                depth++;
                want = b == '{' ? FIRST_KEY : FIRST_ELEM;
                continue;
            }
            if (depth == 0)
                return cm_fail_at(st, CM_E_FORMAT, (uint32_t)c.at, "glTF JSON: not an object");
            jval v;
            int r = b == '"' ? (c.at++, jstring(&c, &v)) : (b == '-' || (b >= '0' && b <= '9')) ? jnumber(&c, &v)
                                                                                                : jliteral(&c, &v);
            if (r != 0)
                return cm_fail_at(st, CM_E_FORMAT, (uint32_t)c.at, "glTF JSON: a value expected");
            if (tracked && (e = on_scalar(g, &p, &v, st)) != CM_OK)
                return e;
            want = AFTER;
        }
        if (want == AFTER && depth == 0)
            return CM_OK;
    }
}

/* ---------------------------------------------------------------- nodes, accessors, the mesh */

/* c = a b, 4 x 4 column-major */
static void mat_mul(const double *a, const double *b, double *c)
{
    for (int col = 0; col < 4; col++)
        for (int row = 0; row < 4; row++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++)
                s += a[4 * k + row] * b[4 * col + k];
            c[4 * col + row] = s;
        }
}

/* a node's local matrix: its matrix, or T R S */
static void local_matrix(const cm_glb_node *n, double *m)
{
    if (n->has_matrix) {
        memcpy(m, n->m, sizeof n->m);
        return;
    }
    double x = n->r[0], y = n->r[1], z = n->r[2], w = n->r[3];
    double q = x * x + y * y + z * z + w * w, s2 = q > 0.0 ? 2.0 / q : 0.0;
    double R[9] = {1 - s2 * (y * y + z * z), s2 * (x * y + z * w),     s2 * (x * z - y * w),
                   s2 * (x * y - z * w),     1 - s2 * (x * x + z * z), s2 * (y * z + x * w),
                   s2 * (x * z + y * w),     s2 * (y * z - x * w),     1 - s2 * (x * x + y * y)}; /* columns */
    for (int col = 0; col < 3; col++) {
        for (int row = 0; row < 3; row++)
            m[4 * col + row] = R[3 * col + row] * n->s[col];
        m[4 * col + 3] = 0.0;
    }
    m[12] = n->t[0], m[13] = n->t[1], m[14] = n->t[2], m[15] = 1.0;
}

/* accessor i checked for what a primitive reads of it (ncomp components of ctype, or any unsigned
   integer when ctype is 0): its first element's offset in the file and its stride; NULL with st set */
static const cm_glb_accessor *accessor_for(cm_glb_reader *g, int32_t i, unsigned ncomp, unsigned ctype, uint64_t *at,
                                           uint32_t *stride, const char *what, cm_status *st)
{
    if (i < 0 || (uint32_t)i >= g->naccessors) {
        cm_fail(st, CM_E_RANGE, what);
        return NULL;
    }
    const cm_glb_accessor *a = &g->accessors[i];
    unsigned size = a->ctype == 5121 ? 1u : a->ctype == 5123 ? 2u : a->ctype == 5125 || a->ctype == 5126 ? 4u : 0u;
    if (a->sparse || a->ncomp != ncomp || size == 0 || (ctype ? a->ctype != ctype : a->ctype == 5126) ||
        a->view >= g->nviews) {
        cm_fail(st, CM_E_FORMAT, what);
        return NULL;
    }
    const cm_glb_view *v = &g->views[a->view];
    uint32_t elem = size * ncomp;
    *stride = v->stride ? v->stride : elem;
    uint64_t last = a->count ? (uint64_t)a->offset + (uint64_t)(a->count - 1) * *stride + elem : 0;
    if (v->buffer != 0 || *stride < elem || last > v->length || (uint64_t)v->offset + v->length > g->bin_len) {
        cm_fail(st, CM_E_RANGE, what);
        return NULL;
    }
    *at = g->bin_off + v->offset + a->offset;
    return a;
}

static cm_err read_fail(cm_status *st) { return cm_fail(st, CM_E_IO, "glTF BIN: reading the file"); }

/* where a primitive's data lie, and how it is placed */
typedef struct prim_src {
    uint64_t pat, nat, iat; /* first POSITION, NORMAL, index */
    uint32_t ps, ns, is;    /* their strides */
    unsigned isize;         /* bytes an index (0: none, the vertices in order) */
    int normals;
    double w[16];           /* the node's matrix to the model (glTF's units and axes) */
    double cf[9];           /* its linear part's cofactors (normals), signed to keep them outwards */
    int mirror;             /* w turns the triangles */
} prim_src;

/* vertex i's position and normal (unit; (0,0,0) without NORMAL), placed, in CAD millimetres, Z up */
static int read_vertex(cm_glb_reader *g, const prim_src *ps, uint32_t i, float P[3], float Q[3])
{
    uint8_t b[12];
    if (bytes_at(g, ps->pat + (uint64_t)i * ps->ps, b, 12) != 0)
        return -1;
    double x = (double)lef32(b), y = (double)lef32(b + 4), z = (double)lef32(b + 8), o[3];
    for (int r = 0; r < 3; r++)
        o[r] = ps->w[r] * x + ps->w[4 + r] * y + ps->w[8 + r] * z + ps->w[12 + r];
    P[0] = (float)(1000.0 * o[0]), P[1] = (float)(-1000.0 * o[2]), P[2] = (float)(1000.0 * o[1]);
    Q[0] = Q[1] = Q[2] = 0.0f;
    if (!ps->normals)
        return 0;
    if (bytes_at(g, ps->nat + (uint64_t)i * ps->ns, b, 12) != 0)
        return -1;
    x = (double)lef32(b), y = (double)lef32(b + 4), z = (double)lef32(b + 8);
    for (int r = 0; r < 3; r++)
        o[r] = ps->cf[r] * x + ps->cf[3 + r] * y + ps->cf[6 + r] * z;
    double len = sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
    if (len > 0.0 && isfinite(len))
        Q[0] = (float)(o[0] / len), Q[1] = (float)(-o[2] / len), Q[2] = (float)(o[1] / len);
    else
        Q[2] = 1.0f;
    return 0;
}

/* index k of the primitive (k itself without indices), in *v: 0, -1 (read failed) */
static int read_index(cm_glb_reader *g, const prim_src *ps, uint32_t k, uint32_t *v)
{
    uint8_t b[4];
    if (ps->isize == 0) {
        *v = k;
        return 0;
    }
    if (bytes_at(g, ps->iat + (uint64_t)k * ps->is, b, ps->isize) != 0)
        return -1;
    *v = ps->isize == 1 ? b[0] : ps->isize == 2 ? (uint32_t)(b[0] | (b[1] << 8)) : le32(b);
    return 0;
}

/* the normals of vertices [first, first + nv) from the triangles of indices [firsti, firsti + ni)
   (each vertex the sum of its triangles', each its area's weight), made unit */
static void normals_from_triangles(cm_mesh *mesh, uint32_t first, uint32_t nv, uint32_t firsti, uint32_t ni)
{
    for (uint32_t k = 0; k < ni; k += 3) {
        uint32_t t[3] = {*cm_mesh_widx(mesh, firsti + k), *cm_mesh_widx(mesh, firsti + k + 1),
                         *cm_mesh_widx(mesh, firsti + k + 2)};
        const float *a = cm_mesh_wpos(mesh, t[0]), *p1 = cm_mesh_wpos(mesh, t[1]), *p2 = cm_mesh_wpos(mesh, t[2]);
        double u1[3] = {(double)p1[0] - (double)a[0], (double)p1[1] - (double)a[1], (double)p1[2] - (double)a[2]};
        double u2[3] = {(double)p2[0] - (double)a[0], (double)p2[1] - (double)a[1], (double)p2[2] - (double)a[2]};
        double n[3] = {u1[1] * u2[2] - u1[2] * u2[1], u1[2] * u2[0] - u1[0] * u2[2], u1[0] * u2[1] - u1[1] * u2[0]};
        for (int j = 0; j < 3; j++) {
            float *Q = cm_mesh_wnrm(mesh, t[j]);
            Q[0] = (float)((double)Q[0] + n[0]), Q[1] = (float)((double)Q[1] + n[1]), Q[2] = (float)((double)Q[2] + n[2]);
        }
    }
    for (uint32_t i = 0; i < nv; i++) {
        float *Q = cm_mesh_wnrm(mesh, first + i);
        double x = (double)Q[0], y = (double)Q[1], z = (double)Q[2], len = sqrt(x * x + y * y + z * z);
        if (len > 0.0 && isfinite(len))
            Q[0] = (float)(x / len), Q[1] = (float)(y / len), Q[2] = (float)(z / len);
        else
            Q[0] = Q[1] = 0.0f, Q[2] = 1.0f;
    }
}

/* a face of the mesh and of the model for what was appended from (first, firsti) on */
static cm_err add_face(cm_glb_reader *g, const cm_glb_prim *q, uint32_t part, uint32_t first, uint32_t firsti,
                       cm_mesh *mesh, cm_model *model, cm_status *st)
{
    if (model->nfaces >= CM_MAX_FACES)
        return cm_fail_limit(st, CM_LIMIT_MAX_FACES, (uint64_t)model->nfaces + 1, CM_MAX_FACES, "glTF primitives placed");
    if (mesh->nfaces >= mesh->cap_faces)
        return cm_fail_limit(st, CM_LIMIT_MAX_FACES, (uint64_t)mesh->nfaces + 1, mesh->cap_faces, "glTF primitives placed");
    cm_mesh_face *F = &mesh->faces[mesh->nfaces++];
    int coloured = q->material >= 0 && (uint32_t)q->material < g->nmaterials && g->material_color[q->material];
    *F = (cm_mesh_face){first, mesh->nverts - first, firsti, mesh->nindex - firsti,
                        coloured ? g->material_rgb[q->material] : 0u, (uint8_t)coloured, model->nfaces};
    memset(&model->faces[model->nfaces], 0, sizeof model->faces[0]);
    model->faces[model->nfaces++].part = part;
    return CM_OK;
}

/*
 * Primitive q placed by w (glTF metres, Y up) as a face of the mesh, in CAD millimetres, Z up.  One
 * larger than the mesh's window (a streaming terminal holds one face's tessellation in memory: 3072
 * points) goes as faces of its triangles in runs that fit, each triangle with corners of its own
 * (the same positions and normals; without NORMAL, each triangle's own normal).
 */
static cm_err emit_prim(cm_glb_reader *g, const cm_glb_prim *q, const double *w, uint32_t part, cm_mesh *mesh,
                        cm_model *model, cm_status *st)
{
    prim_src ps;
    memset(&ps, 0, sizeof ps);
    const cm_glb_accessor *A = accessor_for(g, q->pos, 3, 5126, &ps.pat, &ps.ps, "glTF primitive's POSITION (float VEC3)", st);
    const cm_glb_accessor *N = q->nrm < 0 ? NULL : accessor_for(g, q->nrm, 3, 5126, &ps.nat, &ps.ns, "glTF primitive's NORMAL (float VEC3)", st);
    const cm_glb_accessor *I = q->idx < 0 ? NULL : accessor_for(g, q->idx, 1, 0, &ps.iat, &ps.is, "glTF primitive's indices (unsigned SCALAR)", st);
    if (!A || (q->nrm >= 0 && !N) || (q->idx >= 0 && !I))
        return st ? st->code : CM_E_FORMAT;
    if (N && N->count < A->count)
        return cm_fail(st, CM_E_RANGE, "glTF primitive's NORMAL: fewer than its positions");
    ps.normals = N != NULL;
    ps.isize = !I ? 0u : I->ctype == 5121 ? 1u : I->ctype == 5123 ? 2u : 4u;
    uint32_t nv = A->count, ni = I ? I->count - I->count % 3u : nv - nv % 3u;
    if (nv == 0 || ni == 0)
        return CM_OK; /* nothing to draw */
    /* normals by the cofactors of w's linear part (its inverse transpose times det), so that they
       stay normal under a scale, signed so that a mirror keeps them outwards; the triangles turned
       where w mirrors */
    memcpy(ps.w, w, sizeof ps.w);
    for (int col = 0; col < 3; col++)
        for (int row = 0; row < 3; row++) {
            int r1 = (row + 1) % 3, r2 = (row + 2) % 3, c1 = (col + 1) % 3, c2 = (col + 2) % 3;
            ps.cf[3 * col + row] = w[4 * c1 + r1] * w[4 * c2 + r2] - w[4 * c2 + r1] * w[4 * c1 + r2];
        }
    double det = w[0] * ps.cf[0] + w[1] * ps.cf[1] + w[2] * ps.cf[2];
    ps.mirror = det < 0.0;
    for (int k = 0; k < 9 && ps.mirror; k++)
        ps.cf[k] = -ps.cf[k];
    const uint32_t room_v = mesh->spill ? mesh->win_cap_verts : mesh->cap_verts - mesh->nverts;
    const uint32_t room_i = mesh->spill ? mesh->win_cap_index : mesh->cap_index - mesh->nindex;
    const int whole = nv <= room_v && ni <= room_i;
    const uint32_t run = whole ? ni : (room_v < room_i ? room_v : room_i) / 3u * 3u; /* indices of one face */
    if (run == 0 || (!whole && !mesh->spill))
        return cm_fail_limit(st, CM_LIMIT_MAX_TRIS, ((uint64_t)mesh->nindex + ni) / 3u, mesh->cap_index / 3u,
                             "glTF mesh (its triangles and vertices)");
    for (uint32_t k0 = 0; k0 < ni; k0 += run) {
        uint32_t nk = ni - k0 < run ? ni - k0 : run, vk = whole ? nv : nk;
        if (vk > mesh->cap_verts - mesh->nverts || nk > mesh->cap_index - mesh->nindex)
            return cm_fail_limit(st, CM_LIMIT_MAX_TRIS, ((uint64_t)mesh->nindex + nk) / 3u, mesh->cap_index / 3u,
                                 "glTF mesh (its triangles and vertices)");
        cm_err e = cm_mesh_make_room(mesh, vk, nk, st);
        if (e != CM_OK)
            return e;
        const uint32_t first = mesh->nverts, firsti = mesh->nindex;
        for (uint32_t i = 0; whole && i < nv; i++)
            if (read_vertex(g, &ps, i, cm_mesh_wpos(mesh, first + i), cm_mesh_wnrm(mesh, first + i)) != 0)
                return read_fail(st);
        for (uint32_t k = 0; k < nk; k++) {
            uint32_t v;
            if (read_index(g, &ps, k0 + k, &v) != 0)
                return read_fail(st);
            if (v >= nv)
                return cm_fail(st, CM_E_RANGE, "glTF primitive's indices: beyond its positions");
            /* a mirroring placement turns each triangle (its second and third corners swapped) */
            uint32_t slot = ps.mirror && k % 3u != 0 ? k - k % 3u + 3u - k % 3u : k;
            if (!whole && read_vertex(g, &ps, v, cm_mesh_wpos(mesh, first + slot), cm_mesh_wnrm(mesh, first + slot)) != 0)
                return read_fail(st);
            *cm_mesh_widx(mesh, firsti + slot) = whole ? first + v : first + slot;
        }
        if (!N)
            normals_from_triangles(mesh, first, vk, firsti, nk);
        mesh->nverts += vk;
        mesh->nindex += nk;
        if ((e = add_face(g, q, part, first, firsti, mesh, model, st)) != CM_OK)
            return e;
    }
    return CM_OK;
}

int cm_glb_sniff(const uint8_t head[4]) { return le32(head) == GLB_MAGIC; }

cm_err cm_glb_read(cm_glb_reader *g, cm_glb_src_fn *src, void *ctx, uint64_t file_len, cm_mesh *mesh,
                   cm_model *model, cm_status *st)
{
    g->src = src;
    g->ctx = ctx;
    g->file_len = file_len;
    g->win_off = 0;
    g->win_n = 0;
    g->naccessors = g->nviews = g->nprims = g->nnodes = g->nmaterials = g->nroots = g->nmeshes = 0;
    g->scene = -1;
    g->buffer0_uri = 0;
    g->skipped_prims = 0;
    g->bin_off = g->bin_len = 0;
    for (uint32_t i = 0; i < CM_GLB_MAX_NODES; i++)
        g->nodes[i].parent = -1;
    cm_mesh_clear(mesh);
    model->nfaces = model->nedges = model->nuses = model->nloops = model->nverts = model->nsurfs = 0;
    model->nplacements = model->npalette = model->nparts = model->part_names_len = 0;
    model->part_names_left_out = 0; /* (no names: a GLB's nodes' are not read) */
    /* header, JSON chunk, BIN chunk (the first two chunks; any after them are extensions') */
    uint8_t h[20];
    if (file_len < 20)
        return cm_fail_at(st, CM_E_TRUNCATED, 0, "GLB header");
    if (bytes_at(g, 0, h, 20) != 0)
        return read_fail(st);
    if (le32(h) != GLB_MAGIC)
        return cm_fail_at(st, CM_E_FORMAT, 0, "GLB magic (not glTF binary)");
    if (le32(h + 4) != 2)
        return cm_fail_at(st, CM_E_VERSION, 4, "GLB version (not glTF 2)");
    uint64_t total = le32(h + 8), jlen = le32(h + 12);
    if (total > file_len)
        return cm_fail_at(st, CM_E_TRUNCATED, 8, "GLB length: beyond the file");
    if (le32(h + 16) != GLB_JSON || jlen > total - 20)
        return cm_fail_at(st, CM_E_FORMAT, 12, "GLB's first chunk (JSON)");
    uint64_t next = 20 + jlen;
    if (next + 8 <= total) {
        if (bytes_at(g, next, h, 8) != 0)
            return read_fail(st);
        uint64_t blen = le32(h);
        if (le32(h + 4) == GLB_BIN) {
            if (blen > total - next - 8)
                return cm_fail_at(st, CM_E_TRUNCATED, (uint32_t)next, "GLB's BIN chunk: beyond the file");
            g->bin_off = next + 8;
            g->bin_len = blen;
        }
    }
    cm_err e = parse_json(g, 20, 20 + jlen, st);
    if (e != CM_OK)
        return e;
    if (g->buffer0_uri)
        return cm_fail(st, CM_E_FORMAT, "glTF buffer with a uri (only the GLB's own BIN chunk is read)");
    /* the scene's roots: its nodes, else (no scenes) every node without a parent */
    uint32_t n = 0;
    uint32_t s = g->scene >= 0 ? (uint32_t)g->scene : 0;
    for (uint32_t i = 0; i < g->nnodes; i++)
        g->seen[i] = 0;
    for (uint32_t i = 0; i < g->nroots; i++) {
        uint32_t r = g->root_node[i];
        if (g->root_scene[i] == s && r < g->nnodes && g->nodes[r].parent < 0 && !g->seen[r])
            g->order[n++] = r, g->seen[r] = 1;
    }
    for (uint32_t i = 0; g->nroots == 0 && i < g->nnodes; i++)
        if (g->nodes[i].parent < 0)
            g->order[n++] = i;
    /* children, in node order, a list per parent */
    for (uint32_t i = 0; i <= g->nnodes; i++)
        g->first_child[i] = 0;
    for (uint32_t i = 0; i < g->nnodes; i++)
        if (g->nodes[i].parent >= 0 && (uint32_t)g->nodes[i].parent < g->nnodes)
            g->first_child[g->nodes[i].parent + 1]++;
    for (uint32_t i = 0; i < g->nnodes; i++)
        g->first_child[i + 1] += g->first_child[i];
    for (uint32_t i = 0; i < g->nnodes; i++) { /* each list filled from its start, which moves to its end */
        int32_t p = g->nodes[i].parent;
        if (p >= 0 && (uint32_t)p < g->nnodes)
            g->child[g->first_child[p]++] = i;
    }
    for (uint32_t i = g->nnodes; i > 0; i--) /* (so each start is the end of the list before it) */
        g->first_child[i] = g->first_child[i - 1];
    g->first_child[0] = 0;
    /* each mesh's primitives, one run (the JSON lists them mesh by mesh) */
    for (uint32_t i = 0; i <= g->nmeshes; i++)
        g->mesh_first[i] = 0;
    for (uint32_t q = 0; q < g->nprims; q++)
        g->mesh_first[g->prims[q].mesh + 1] = q + 1;
    for (uint32_t i = 0; i < g->nmeshes; i++) /* (a mesh without primitives: an empty run) */
        g->mesh_first[i + 1] = g->mesh_first[i + 1] > g->mesh_first[i] ? g->mesh_first[i + 1] : g->mesh_first[i];
    /* breadth first: each node's matrix to the model, its mesh's primitives placed */
    double local[16];
    uint32_t part = 0;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t i = g->order[k];
        cm_glb_node *nd = &g->nodes[i];
        if (nd->parent < 0) { /* a root: its own matrix (a child's was made as it was queued) */
            local_matrix(nd, local);
            memcpy(g->world[i], local, sizeof local);
        }
        for (uint32_t c = g->first_child[i]; c < g->first_child[i + 1] && n < CM_GLB_MAX_NODES; c++) {
            uint32_t j = g->child[c];
            double lj[16];
            local_matrix(&g->nodes[j], lj);
            mat_mul(g->world[i], lj, g->world[j]);
            g->order[n++] = j;
        }
        if (nd->mesh < 0 || (uint32_t)nd->mesh >= g->nmeshes)
            continue;
        part++;
        for (uint32_t q = g->mesh_first[nd->mesh]; q < g->mesh_first[nd->mesh + 1]; q++) {
            if (g->prims[q].mode != 4) {
                g->skipped_prims++;
                continue;
            }
            if ((e = emit_prim(g, &g->prims[q], g->world[i], part, mesh, model, st)) != CM_OK)
                return e;
        }
    }
    model->nparts = model->nfaces > 0 ? part : 0;
    return CM_OK;
}
