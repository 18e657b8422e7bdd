/*
 * test_out.c - the mesh writers (GLB, STL, OBJ), the number formatter and
 * the mesh helpers.
 *
 * The reference mesh is a unit cube (6 faces, 4 vertices and 2 triangles
 * each, three colours used twice) and a tetrahedron with awkward
 * coordinates and no colour (face 6): 36 vertices, 16 triangles, 7 faces,
 * 4 materials.  test_write_files leaves cube.glb/.stl/.obj in
 * build/test_out/ (or $CM_TEST_OUT_DIR) for independent readers
 * (tests/tools/gltf_check, assimp).
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>

#include "test_util.h"
#include "test_mesh.h"

#include "cm/cm_mesh.h"
#include "cm/cm_numfmt.h"
#include "cm/cm_out.h"

/* ---- reference mesh ---- */

#define MAXV 256
#define MAXI 512
#define MAXF 96
static float g_pos[MAXV][3], g_nrm[MAXV][3];
static uint32_t g_idx[MAXI];
static cm_mesh_face g_faces[MAXF];
static uint8_t g_out[1 << 16], g_out2[1 << 16];

static cm_mesh mesh_storage(void) { return test_mesh_on(g_pos, g_nrm, g_idx, g_faces, MAXV, MAXI, MAXF); }

static void add_vertex(cm_mesh *m, const float p[3], const float n[3])
{
    memcpy(m->pos[m->nverts], p, sizeof(float[3]));
    memcpy(m->nrm[m->nverts], n, sizeof(float[3]));
    m->nverts++;
}

static void begin_face(cm_mesh *m, uint32_t source, uint32_t rgb, int has_color)
{
    cm_mesh_face *f = &m->faces[m->nfaces++];
    memset(f, 0, sizeof *f);
    f->first_vert = m->nverts;
    f->first_index = m->nindex;
    f->rgb = rgb;
    f->has_color = (uint8_t)has_color;
    f->source_face = source;
}

static void add_tri(cm_mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    cm_mesh_face *f = &m->faces[m->nfaces - 1];
    m->idx[m->nindex++] = f->first_vert + a;
    m->idx[m->nindex++] = f->first_vert + b;
    m->idx[m->nindex++] = f->first_vert + c;
    f->nindex += 3;
}

static void end_face(cm_mesh *m)
{
    cm_mesh_face *f = &m->faces[m->nfaces - 1];
    f->nverts = m->nverts - f->first_vert;
}

/* unit normal of (a, b, c) */
static void tri_normal(const float *a, const float *b, const float *c, float n[3])
{
    cm_vec3 u = cm_v3((double)b[0] - (double)a[0], (double)b[1] - (double)a[1], (double)b[2] - (double)a[2]);
    cm_vec3 v = cm_v3((double)c[0] - (double)a[0], (double)c[1] - (double)a[1], (double)c[2] - (double)a[2]);
    cm_vec3 w = cm_unit(cm_cross(u, v));
    n[0] = (float)w.x;
    n[1] = (float)w.y;
    n[2] = (float)w.z;
}

/* the tetrahedron's corners: min (-12.3456793, -1, 9.99999975e-06), max (-10, 1.5, 2.25) */
static const float TET[4][3] = {{-12.3456793f, -1.0f, 0.00001f},
                                {-10.0f, -1.0f, 0.00001f},
                                {-11.0f, 1.5f, 0.00001f},
                                {-11.0f, 0.0f, 2.25f}};
static const uint32_t CUBE_RGB[3] = {0xC81E1E, 0x1EC81E, 0x1E1EC8};

static cm_mesh make_cube_tetra(void)
{
    cm_mesh m = mesh_storage();
    /* cube sides: corner quads counter-clockwise seen from outside */
    static const float q[6][4][3] = {
        {{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}}, /* z = 0, normal -z (face 0) */
        {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}, /* z = 1, +z */
        {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}, /* y = 0, -y */
        {{0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}}, /* y = 1, +y */
        {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}}, /* x = 0, -x */
        {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}, /* x = 1, +x */
    };
    for (uint32_t s = 0; s < 6; s++) {
        float n[3];
        tri_normal(q[s][0], q[s][1], q[s][2], n);
        begin_face(&m, s, CUBE_RGB[s % 3], 1);
        for (int k = 0; k < 4; k++)
            add_vertex(&m, q[s][k], n);
        add_tri(&m, 0, 1, 2);
        add_tri(&m, 0, 2, 3);
        end_face(&m);
    }
    /* tetrahedron: one face of four flat sides, each side oriented away from the opposite corner */
    begin_face(&m, 6, 0, 0);
    static const int side[4][4] = {{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 3, 1}, {1, 2, 3, 0}};
    for (int s = 0; s < 4; s++) {
        const float *a = TET[side[s][0]], *b = TET[side[s][1]], *c = TET[side[s][2]], *o = TET[side[s][3]];
        float n[3];
        tri_normal(a, b, c, n);
        double d = 0;
        for (int k = 0; k < 3; k++)
            d += (double)n[k] * ((double)o[k] - (double)a[k]);
        if (d > 0) { /* the opposite corner is in front: flip */
            const float *t = b;
            b = c;
            c = t;
            tri_normal(a, b, c, n);
        }
        uint32_t base = m.nverts - m.faces[m.nfaces - 1].first_vert;
        add_vertex(&m, a, n);
        add_vertex(&m, b, n);
        add_vertex(&m, c, n);
        add_tri(&m, base, base + 1, base + 2);
    }
    end_face(&m);
    return m;
}

/* whole file with a caller buffer of `cap` bytes (cap 0: sizes cycling 1..13) */
static size_t write_all(cm_out_format fmt, const cm_mesh *m, size_t cap, uint8_t *out, size_t outcap)
{
    cm_out w;
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_out_begin(&w, fmt, m, &st));
    size_t len = 0;
    int done = 0;
    for (int calls = 0; !done; calls++) {
        size_t c = cap != 0 ? cap : (size_t)(calls % 13) + 1;
        if (c > outcap - len)
            c = outcap - len;
        assert_true(c > 0); /* the output fits the test buffer */
        size_t n = 0;
        assert_ok(cm_out_next(&w, out + len, c, &n, &done, &st));
        assert_true(n <= c);
        if (!done)
            assert_int_equal(n, c); /* fills the buffer unless the file ends */
        len += n;
    }
    size_t n = 99;
    assert_ok(cm_out_next(&w, out + len, 1, &n, &done, &st)); /* after the end: nothing more */
    assert_int_equal(n, 0);
    assert_int_equal(done, 1);
    if (fmt != CM_OUT_OBJ)
        assert_int_equal(cm_out_size(&w), len);
    else
        assert_int_equal(cm_out_size(&w), 0);
    return len;
}

static uint32_t rd32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float rdf32(const uint8_t *p)
{
    uint32_t u = rd32(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static size_t count_substr(const char *hay, size_t n, const char *needle)
{
    size_t k = strlen(needle), c = 0;
    for (size_t i = 0; i + k <= n; i++)
        if (memcmp(hay + i, needle, k) == 0)
            c++;
    return c;
}

static size_t count_line_prefix(const char *txt, size_t n, const char *prefix)
{
    size_t k = strlen(prefix), c = 0;
    for (size_t i = 0; i + k <= n; i++)
        if ((i == 0 || txt[i - 1] == '\n') && memcmp(txt + i, prefix, k) == 0)
            c++;
    return c;
}

/* ---- number formatting ---- */

static void check_f32(float f)
{
    char ours[CM_FMT_F32_MAX + 8], ref[64];
    memset(ours, 'x', sizeof ours);
    size_t n = cm_fmt_f32(ours, f);
    assert_int_equal(n, strlen(ours));
    assert_true(n < CM_FMT_F32_MAX);
    snprintf(ref, sizeof ref, "%.9g", (double)f);
    if (strcmp(ours, ref) != 0)
        fail_msg("cm_fmt_f32(%a) = \"%s\", %%.9g gives \"%s\"", (double)f, ours, ref);
    float back = strtof(ours, NULL);
    float back_d = (float)strtod(ours, NULL); /* as JSON readers do: double, then float */
    if (memcmp(&back, &f, sizeof f) != 0 || memcmp(&back_d, &f, sizeof f) != 0)
        fail_msg("\"%s\" reads back as %a / %a, not %a", ours, (double)back, (double)back_d, (double)f);
}

static float f32_of_bits(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static void test_fmt_examples(void **state)
{
    (void)state;
    char t[CM_FMT_F32_MAX];
    static const struct {
        float f;
        const char *s;
    } ex[] = {
        {-12.3456793f, "-12.3456793"}, {1.00000007e-05f, "1.00000007e-05"}, {0.00001f, "9.99999975e-06"},
        {0.0f, "0"},
        {1.0f, "1"}, {0.6f, "0.600000024"}, {1e9f, "1e+09"}, {123456789.0f, "123456792"},
        {100000000.0f, "100000000"}, {0.0001f, "9.99999975e-05"}, {0.001f, "0.00100000005"},
        {FLT_MAX, "3.40282347e+38"}, {-FLT_MAX, "-3.40282347e+38"}, {FLT_MIN, "1.17549435e-38"},
        {FLT_TRUE_MIN, "1.40129846e-45"}, {-1.17549421e-38f, "-1.17549421e-38"},
        {1000000.125f, "1000000.12"}, /* an exact tie: to even */
        {1000000.375f, "1000000.38"},
    };
    for (size_t i = 0; i < sizeof ex / sizeof ex[0]; i++) {
        cm_fmt_f32(t, ex[i].f);
        assert_string_equal(t, ex[i].s);
        check_f32(ex[i].f);
    }
    cm_fmt_f32(t, -0.0f);
    assert_string_equal(t, "-0");
    /* non-finite values write nothing */
    assert_int_equal(cm_fmt_f32(t, f32_of_bits(0x7F800000u)), 0);
    assert_string_equal(t, "");
    assert_int_equal(cm_fmt_f32(t, f32_of_bits(0xFF800000u)), 0);
    assert_int_equal(cm_fmt_f32(t, f32_of_bits(0x7FC00000u)), 0);
    /* integers */
    char u[CM_FMT_U64_MAX];
    assert_int_equal(cm_fmt_u64(u, 0), 1);
    assert_string_equal(u, "0");
    cm_fmt_u64(u, 10);
    assert_string_equal(u, "10");
    cm_fmt_u64(u, 4294967295u);
    assert_string_equal(u, "4294967295");
    assert_int_equal(cm_fmt_u64(u, UINT64_MAX), 20);
    assert_string_equal(u, "18446744073709551615");
}

/* random bit patterns, subnormals, neighbours of powers of ten and two, near-ties: all equal to %.9g and round-trip */
static void test_fmt_f32_round_trip(void **state)
{
    (void)state;
    uint32_t seed = 12345;
    int n = 0;
    for (int i = 0; i < 200000; i++) {
        uint32_t u = (uint32_t)(test_rand(&seed) * 65536.0) << 16 | (uint32_t)(test_rand(&seed) * 65536.0);
        if ((u & 0x7F800000u) == 0x7F800000u)
            continue;
        check_f32(f32_of_bits(u));
        n++;
    }
    assert_true(n > 190000);
    for (int i = 0; i < 20000; i++) { /* subnormals of both signs */
        uint32_t u = (uint32_t)(test_rand(&seed) * 8388608.0) | (i & 1 ? 0x80000000u : 0u);
        check_f32(f32_of_bits(u));
    }
    for (int e = -45; e <= 38; e++) { /* around every power of ten */
        float p = (float)pow(10.0, e);
        float lo = p, hi = p;
        for (int k = 0; k < 6; k++) {
            check_f32(lo);
            check_f32(hi);
            check_f32(-hi);
            lo = nextafterf(lo, 0.0f);
            hi = nextafterf(hi, FLT_MAX);
        }
    }
    for (int e = -149; e <= 127; e++) { /* powers of two and their neighbours */
        float p = ldexpf(1.0f, e);
        check_f32(p);
        check_f32(nextafterf(p, 0.0f));
        check_f32(nextafterf(p, FLT_MAX));
    }
    /* near-ties the double scaling alone would round the wrong way (found by an exhaustive sweep) */
    check_f32(f32_of_bits(0xE53812E1u));
    check_f32(f32_of_bits(0xF28CF220u));
    /* every float of a few dense ranges */
    for (uint32_t u = 0x3F800000u; u < 0x3F800000u + 20000u; u++)
        check_f32(f32_of_bits(u));
    for (uint32_t u = 0x00000000u; u < 5000u; u++)
        check_f32(f32_of_bits(u));
}

/* ---- mesh helpers ---- */

static void test_mesh_clear_bounds(void **state)
{
    (void)state;
    cm_mesh m = make_cube_tetra();
    assert_int_equal(m.nverts, 36);
    assert_int_equal(m.nindex, 48);
    assert_int_equal(m.nfaces, 7);
    float lo[3] = {7, 7, 7}, hi[3] = {7, 7, 7};
    assert_int_equal(cm_mesh_bounds(&m, lo, hi), 1);
    assert_true(lo[0] == -12.3456793f && lo[1] == -1.0f && lo[2] == 0.0f);
    assert_true(hi[0] == 1.0f && hi[1] == 1.5f && hi[2] == 2.25f);
    cm_mesh_clear(&m);
    assert_int_equal(m.nverts + m.nindex + m.nfaces, 0);
    assert_int_equal(m.cap_verts, MAXV); /* storage kept */
    assert_true(m.pos == g_pos);
    lo[0] = hi[0] = 7;
    assert_int_equal(cm_mesh_bounds(&m, lo, hi), 0);
    assert_true(lo[0] == 7 && hi[0] == 7); /* untouched */
    cm_mesh_clear(NULL);
}

/* ---- STL ---- */

static void test_stl_layout(void **state)
{
    (void)state;
    cm_mesh m = make_cube_tetra();
    size_t len = write_all(CM_OUT_STL, &m, 4096, g_out, sizeof g_out);
    assert_int_equal(len, 84 + 50 * 16);
    assert_memory_equal(g_out, "curvemesh binary STL ", 21);
    for (int i = 20; i < 80; i++)
        assert_int_equal(g_out[i], ' ');
    assert_int_equal(rd32(g_out + 80), 16);
    /* triangle 0: cube side z = 0, corners (0,0,0) (0,1,0) (1,1,0), normal -z */
    const uint8_t *t0 = g_out + 84;
    static const uint8_t minus_one[4] = {0x00, 0x00, 0x80, 0xBF}; /* -1.0f little-endian */
    assert_true(rdf32(t0) == 0.0f && rdf32(t0 + 4) == 0.0f);
    assert_memory_equal(t0 + 8, minus_one, 4);
    assert_true(rdf32(t0 + 24) == 0.0f && rdf32(t0 + 28) == 1.0f && rdf32(t0 + 32) == 0.0f);
    assert_int_equal(t0[48] | t0[49] << 8, 0);
    /* the last triangle is a tetrahedron side: its vertices, its unit normal pointing away from the solid */
    const uint8_t *tl = g_out + 84 + 50 * 15;
    const cm_mesh_face *tf = &m.faces[6];
    const float *v0 = m.pos[m.idx[tf->first_index + 9]];
    for (int k = 0; k < 3; k++)
        assert_true(rdf32(tl + 12 + 4 * k) == v0[k]);
    double nx = (double)rdf32(tl), ny = (double)rdf32(tl + 4), nz = (double)rdf32(tl + 8);
    assert_near(sqrt(nx * nx + ny * ny + nz * nz), 1.0, 1e-6); /* float rounding of a unit vector */
    const float *mn = m.nrm[m.idx[tf->first_index + 9]];
    assert_near(nx * (double)mn[0] + ny * (double)mn[1] + nz * (double)mn[2], 1.0, 1e-6);

    /* a degenerate (collinear) triangle gets the zero normal */
    cm_mesh d = mesh_storage();
    static const float line[3][3] = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}, up[3] = {0, 0, 1};
    begin_face(&d, 0, 0, 0);
    for (int k = 0; k < 3; k++)
        add_vertex(&d, line[k], up);
    add_tri(&d, 0, 1, 2);
    end_face(&d);
    len = write_all(CM_OUT_STL, &d, 4096, g_out, sizeof g_out);
    assert_int_equal(len, 134);
    assert_int_equal(rd32(g_out + 80), 1);
    for (int k = 0; k < 12; k++)
        assert_int_equal(g_out[84 + k], 0);
}

/* ---- GLB ---- */

static void test_glb_layout(void **state)
{
    (void)state;
    cm_mesh m = make_cube_tetra();
    size_t len = write_all(CM_OUT_GLB, &m, 4096, g_out, sizeof g_out);
    assert_int_equal(rd32(g_out), 0x46546C67u); /* "glTF" */
    assert_memory_equal(g_out, "glTF", 4);
    assert_int_equal(rd32(g_out + 4), 2);
    assert_int_equal(rd32(g_out + 8), len);
    uint32_t jlen = rd32(g_out + 12);
    assert_memory_equal(g_out + 16, "JSON", 4);
    assert_int_equal(jlen % 4, 0);
    const char *json = (const char *)g_out + 20;
    assert_int_equal(json[0], '{');
    size_t jend = jlen;
    while (jend > 0 && json[jend - 1] == ' ')
        jend--;
    assert_true(jlen - jend <= 3);
    assert_int_equal(json[jend - 1], '}');
    const uint8_t *bin = g_out + 20 + jlen;
    assert_int_equal((20 + jlen) % 4, 0);
    uint32_t blen = rd32(bin);
    assert_memory_equal(bin + 4, "BIN\0", 4);
    assert_int_equal(blen, 24 * 36 + 4 * 48);
    assert_int_equal(20 + jlen + 8 + blen, len);

    /* JSON content: asset, node transform, primitives, materials, accessors, views */
    assert_int_equal(count_substr(json, jend, "\"asset\":{\"version\":\"2.0\",\"generator\":\"curvemesh\"}"), 1);
    assert_int_equal(count_substr(json, jend, "\"matrix\":[0.001,0,0,0,0,0,-0.001,0,0,0.001,0,0,0,0,0,1]"), 1);
    assert_int_equal(count_substr(json, jend, "\"mode\":4"), 7);
    assert_int_equal(count_substr(json, jend, "\"extras\":{\"face\":6}"), 1);
    assert_int_equal(count_substr(json, jend, "{\"attributes\":{\"POSITION\":18,\"NORMAL\":19},\"indices\":20,"
                                              "\"material\":3,"), 1);
    assert_int_equal(count_substr(json, jend, "\"material\":0,"), 2);
    assert_int_equal(count_substr(json, jend, "\"pbrMetallicRoughness\""), 4);
    assert_int_equal(count_substr(json, jend, "\"name\":\"rgb_c81e1e\",\"pbrMetallicRoughness\":{\"baseColorFactor\":"
                                              "[0.784313738,0.117647059,0.117647059,1],\"metallicFactor\":0,"
                                              "\"roughnessFactor\":0.6},\"doubleSided\":false"), 1);
    assert_int_equal(count_substr(json, jend, "\"name\":\"default\""), 1);
    assert_int_equal(count_substr(json, jend, "\"componentType\":5126,\"count\":4,\"type\":\"VEC3\""), 12);
    assert_int_equal(count_substr(json, jend, "\"componentType\":5125,\"count\":6,\"type\":\"SCALAR\""), 6);
    assert_int_equal(count_substr(json, jend, "\"componentType\":5126,\"count\":12,\"type\":\"VEC3\""), 2);
    assert_int_equal(count_substr(json, jend, "\"componentType\":5125,\"count\":12,\"type\":\"SCALAR\""), 1);
    assert_int_equal(count_substr(json, jend, "\"min\""), 7);
    assert_int_equal(count_substr(json, jend, "\"min\":[0,0,0],\"max\":[1,1,0]}"), 1); /* side z = 0 */
    assert_int_equal(count_substr(json, jend, "{\"bufferView\":0,\"byteOffset\":288,\"componentType\":5126,\"count\":12,"
                                              "\"type\":\"VEC3\",\"min\":[-12.3456793,-1,9.99999975e-06],"
                                              "\"max\":[-10,1.5,2.25]}"), 1);
    assert_int_equal(count_substr(json, jend, "{\"bufferView\":2,\"byteOffset\":144,\"componentType\":5125,"
                                              "\"count\":12,\"type\":\"SCALAR\"}"), 1);
    assert_int_equal(count_substr(json, jend, "\"target\":34962"), 2);
    assert_int_equal(count_substr(json, jend, "\"target\":34963"), 1);
    assert_int_equal(count_substr(json, jend, "\"buffers\":[{\"byteLength\":1056}]"), 1);

    /* BIN: positions, normals, then indices rebased per face */
    assert_true(rdf32(bin + 8 + 12 * 24) == -12.3456793f);                 /* first tetrahedron vertex x */
    assert_true(rdf32(bin + 8 + 36 * 12 + 8) == -1.0f);                     /* normal 0 z */
    const uint8_t *ix = bin + 8 + 2 * 36 * 12;
    static const uint32_t first[6] = {0, 1, 2, 0, 2, 3};
    for (int k = 0; k < 6; k++)
        assert_int_equal(rd32(ix + 4 * k), first[k]);
    for (int k = 0; k < 12; k++) /* tetrahedron: 0..11, not 24..35 */
        assert_int_equal(rd32(ix + 4 * (36 + k)), (uint32_t)k);
}

/* more than 64 colours: the first 64 get materials, the rest the default grey; empty faces are skipped */
static void test_glb_materials_and_empty_faces(void **state)
{
    (void)state;
    cm_mesh m = mesh_storage();
    static const float n[3] = {0, 0, 1};
    for (uint32_t f = 0; f < 71; f++) {
        begin_face(&m, 100 + f, 0x010203u * f, 1);
        if (f != 5) { /* face 105 has vertices but no triangle */
            float p[3][3] = {{(float)f, 0, 0}, {(float)f + 1, 0, 0}, {(float)f, 1, 0}};
            for (int k = 0; k < 3; k++)
                add_vertex(&m, p[k], n);
            add_tri(&m, 0, 1, 2);
        } else {
            static const float p[3] = {-1, -1, -1};
            add_vertex(&m, p, n);
        }
        end_face(&m);
    }
    size_t len = write_all(CM_OUT_GLB, &m, 7, g_out, sizeof g_out);
    const char *json = (const char *)g_out + 20;
    size_t jlen = rd32(g_out + 12);
    assert_true(len > jlen);
    assert_int_equal(count_substr(json, jlen, "\"name\":\"rgb_"), 64);
    assert_int_equal(count_substr(json, jlen, "\"name\":\"default\""), 1);
    assert_int_equal(count_substr(json, jlen, "\"mode\":4"), 70);
    assert_int_equal(count_substr(json, jlen, "\"extras\":{\"face\":105}"), 0);
    assert_int_equal(count_substr(json, jlen, "\"material\":64,"), 70 - 64);
    assert_int_equal(count_substr(json, jlen, "\"name\":\"rgb_4080c0\""), 1); /* f = 64: the 64th colour */
    assert_int_equal(count_substr(json, jlen, "\"name\":\"rgb_4182c3\""), 0); /* f = 65: default grey */
    assert_int_equal(count_substr(json, jlen, "\"name\":\"rgb_000000\""), 1);  /* f = 0: a colour, black */
    /* the empty face has no group in OBJ either */
    len = write_all(CM_OUT_OBJ, &m, 4096, g_out, sizeof g_out);
    assert_int_equal(count_line_prefix((const char *)g_out, len, "g "), 70);
    assert_int_equal(count_line_prefix((const char *)g_out, len, "g face_105\n"), 0);
    assert_int_equal(count_line_prefix((const char *)g_out, len, "v "), 211);
}

/* ---- OBJ ---- */

static void test_obj_lines(void **state)
{
    (void)state;
    cm_mesh m = make_cube_tetra();
    size_t len = write_all(CM_OUT_OBJ, &m, 4096, g_out, sizeof g_out);
    const char *t = (const char *)g_out;
    assert_true(len > 0 && t[len - 1] == '\n');
    assert_int_equal(count_line_prefix(t, len, "# "), 2);
    assert_int_equal(count_substr(t, len, "# 36 vertices, 16 triangles, 7 faces\n"), 1);
    assert_int_equal(count_line_prefix(t, len, "v "), 36);
    assert_int_equal(count_line_prefix(t, len, "vn "), 36);
    assert_int_equal(count_line_prefix(t, len, "g "), 7);
    assert_int_equal(count_line_prefix(t, len, "f "), 16);
    assert_int_equal(count_substr(t, len, "\n"), 2 + 36 + 36 + 7 + 16);
    assert_int_equal(count_line_prefix(t, len, "g face_6\n"), 1);
    assert_int_equal(count_substr(t, len, "\nf 1//1 2//2 3//3\nf 1//1 3//3 4//4\n"), 1);
    assert_int_equal(count_substr(t, len, "\nv -12.3456793 -1 9.99999975e-06\n"), 3); /* in three sides */
    /* every v line reads back to the exact positions */
    char line[128];
    size_t pos = 0, v = 0;
    while (pos < len && v < 36) {
        size_t e = pos;
        while (e < len && t[e] != '\n')
            e++;
        if (e - pos < sizeof line && t[pos] == 'v' && t[pos + 1] == ' ') {
            memcpy(line, t + pos, e - pos);
            line[e - pos] = '\0';
            char *s = line + 2, *end;
            for (int k = 0; k < 3; k++) {
                float f = strtof(s, &end);
                assert_true(end != s);
                assert_true(f == m.pos[v][k]);
                s = end;
            }
            v++;
        }
        pos = e + 1;
    }
    assert_int_equal(v, 36);
}

/* ---- chunk-size independence ---- */

static void test_chunk_independence(void **state)
{
    (void)state;
    cm_mesh m = make_cube_tetra();
    static const cm_out_format fmts[3] = {CM_OUT_GLB, CM_OUT_STL, CM_OUT_OBJ};
    static const size_t caps[4] = {1, 7, 4096, 0 /* cycling 1..13 */};
    for (int f = 0; f < 3; f++) {
        size_t ref = write_all(fmts[f], &m, caps[2], g_out, sizeof g_out);
        for (int c = 0; c < 4; c++) {
            memset(g_out2, 0xAA, sizeof g_out2);
            size_t len = write_all(fmts[f], &m, caps[c], g_out2, sizeof g_out2);
            assert_int_equal(len, ref);
            assert_memory_equal(g_out, g_out2, ref);
        }
        /* one buffer exactly the file size: done with the last bytes */
        if (fmts[f] != CM_OUT_OBJ) {
            cm_out w;
            size_t n;
            int done;
            assert_ok(cm_out_begin(&w, fmts[f], &m, NULL));
            assert_ok(cm_out_next(&w, g_out2, ref, &n, &done, NULL));
            assert_int_equal(n, ref);
            assert_int_equal(done, 1);
        }
    }
}

/* ---- errors ---- */

static void test_errors(void **state)
{
    (void)state;
    cm_out w;
    cm_status st;
    size_t n;
    int done;
    cm_mesh m = make_cube_tetra();

    cm_status_init(&st);
    assert_err(cm_out_begin(&w, (cm_out_format)7, &m, &st), CM_E_ARG);
    assert_err(cm_out_begin(&w, CM_OUT_GLB, NULL, NULL), CM_E_ARG);
    assert_err(cm_out_begin(NULL, CM_OUT_GLB, &m, NULL), CM_E_ARG);
    assert_err(cm_out_next(&w, g_out, 16, &n, &done, NULL), CM_E_ARG); /* begin failed */
    assert_int_equal(cm_out_size(&w), 0);

    /* empty meshes */
    cm_mesh e = mesh_storage();
    cm_status_init(&st);
    assert_err(cm_out_begin(&w, CM_OUT_STL, &e, &st), CM_E_RANGE);
    assert_int_equal(st.code, CM_E_RANGE);
    assert_non_null(st.where);
    begin_face(&e, 0, 0, 0);
    end_face(&e); /* a face without triangles */
    for (int f = 0; f < 3; f++)
        assert_err(cm_out_begin(&w, (cm_out_format)f, &e, NULL), CM_E_RANGE);

    /* non-finite numbers */
    m = make_cube_tetra();
    g_pos[30][1] = NAN;
    for (int f = 0; f < 3; f++) {
        cm_status_init(&st);
        assert_err(cm_out_begin(&w, (cm_out_format)f, &m, &st), CM_E_NONFINITE);
        assert_int_equal(st.offset, 30);
    }
    m = make_cube_tetra();
    g_nrm[3][0] = INFINITY;
    assert_err(cm_out_begin(&w, CM_OUT_GLB, &m, NULL), CM_E_NONFINITE);
    assert_err(cm_out_begin(&w, CM_OUT_OBJ, &m, NULL), CM_E_NONFINITE);
    assert_ok(cm_out_begin(&w, CM_OUT_STL, &m, NULL)); /* STL does not write the mesh normals */
    m = make_cube_tetra();
    g_pos[0][2] = -INFINITY;
    assert_err(cm_out_begin(&w, CM_OUT_STL, &m, NULL), CM_E_NONFINITE);

    /* bad ranges and indices */
    m = make_cube_tetra();
    g_idx[5] = 4; /* face 0 owns vertices 0..3 */
    assert_err(cm_out_begin(&w, CM_OUT_GLB, &m, NULL), CM_E_RANGE);
    assert_err(cm_out_begin(&w, CM_OUT_STL, &m, NULL), CM_E_RANGE);
    m = make_cube_tetra();
    g_faces[6].nindex = 11;
    m.nindex = 47;
    assert_err(cm_out_begin(&w, CM_OUT_OBJ, &m, NULL), CM_E_RANGE);
    m = make_cube_tetra();
    g_faces[6].nverts = 13; /* past the mesh's vertices */
    assert_err(cm_out_begin(&w, CM_OUT_GLB, &m, NULL), CM_E_RANGE);
    m = make_cube_tetra();
    g_faces[1].first_index = 46;
    assert_err(cm_out_begin(&w, CM_OUT_GLB, &m, NULL), CM_E_RANGE);

    /* caller bugs */
    m = make_cube_tetra();
    m.cap_verts = 10;
    assert_err(cm_out_begin(&w, CM_OUT_STL, &m, NULL), CM_E_ARG);
    m = make_cube_tetra();
    m.nrm = NULL;
    assert_err(cm_out_begin(&w, CM_OUT_GLB, &m, NULL), CM_E_ARG);
    assert_ok(cm_out_begin(&w, CM_OUT_STL, &m, NULL)); /* STL needs no normals */
    m = make_cube_tetra();
    assert_ok(cm_out_begin(&w, CM_OUT_GLB, &m, NULL));
    assert_err(cm_out_next(&w, g_out, 0, &n, &done, NULL), CM_E_ARG);
    assert_err(cm_out_next(&w, NULL, 8, &n, &done, NULL), CM_E_ARG);
    assert_err(cm_out_next(&w, g_out, 8, NULL, &done, NULL), CM_E_ARG);

    /* the mesh changing under the writer is caught at the end */
    assert_ok(cm_out_begin(&w, CM_OUT_STL, &m, NULL));
    g_faces[6].nindex = 9;
    cm_status_init(&st);
    cm_err r = CM_OK;
    done = 0;
    for (int i = 0; i < 100 && r == CM_OK && !done; i++)
        r = cm_out_next(&w, g_out, 64, &n, &done, &st);
    assert_int_equal(r, CM_E_FORMAT);
}

/* ---- files for independent readers ---- */

static void test_write_files(void **state)
{
    (void)state;
    const char *dir = getenv("CM_TEST_OUT_DIR");
    if (dir == NULL || dir[0] == '\0') {
        dir = "build/test_out";
        if (mkdir("build", 0777) != 0 && errno != EEXIST)
            skip();
    }
    if (mkdir(dir, 0777) != 0 && errno != EEXIST) {
        print_message("cannot create %s: %s\n", dir, strerror(errno));
        skip();
    }
    cm_mesh m = make_cube_tetra();
    static const struct {
        cm_out_format fmt;
        const char *name;
    } files[3] = {{CM_OUT_GLB, "cube.glb"}, {CM_OUT_STL, "cube.stl"}, {CM_OUT_OBJ, "cube.obj"}};
    for (int i = 0; i < 3; i++) {
        size_t len = write_all(files[i].fmt, &m, 4096, g_out, sizeof g_out);
        char path[512];
        snprintf(path, sizeof path, "%s/%s", dir, files[i].name);
        FILE *fp = fopen(path, "wb");
        assert_non_null(fp);
        assert_int_equal(fwrite(g_out, 1, len, fp), len);
        assert_int_equal(fclose(fp), 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fmt_examples),
        cmocka_unit_test(test_fmt_f32_round_trip),
        cmocka_unit_test(test_mesh_clear_bounds),
        cmocka_unit_test(test_stl_layout),
        cmocka_unit_test(test_glb_layout),
        cmocka_unit_test(test_glb_materials_and_empty_faces),
        cmocka_unit_test(test_obj_lines),
        cmocka_unit_test(test_chunk_independence),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_write_files),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
