/*
 * test_glb_read.c - the viewer's glTF input (cm_glb_read.h, `cmz-view MODEL.glb`): GLBs built here
 * read into the mesh in CAD millimetres with Z up, coloured by their materials ("default": none),
 * placed by their nodes (matrix, or translation / rotation / scale, times the parents'), one part a
 * node, a mirror turning the triangles, missing normals made from the triangles; and malformed or
 * hostile files (cut short, wrong magic or version, broken JSON, nesting, indices beyond their
 * positions, accessors beyond their data, sparse accessors, external buffers, wrong component types,
 * a node with two parents, a child beyond the build's nodes, numbers of 600 digits) each refused by
 * name, never a crash.
 */
#include "test_util.h"
#include "test_mesh.h"

#include <math.h>
#include <stdio.h>

#include "cm/cm_glb_read.h"

static cm_glb_reader g;
static cm_model model;
static uint8_t file[1 << 16];
static size_t flen;

#define MAXV 256
#define MAXI 768
static float g_pos[MAXV][3], g_nrm[MAXV][3];
static uint32_t g_idx[MAXI];
static cm_mesh_face g_faces[16];
static cm_mesh mesh;

static void put32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

/* a GLB of the JSON text and the BIN bytes (each chunk padded to 4 bytes) */
static void make_glb(const char *json, const void *bin, size_t binlen)
{
    size_t jl = strlen(json), jp = (jl + 3u) & ~(size_t)3u, bp = (binlen + 3u) & ~(size_t)3u;
    flen = 12 + 8 + jp + (bin ? 8 + bp : 0);
    assert_true(flen <= sizeof file);
    memset(file, 0, flen);
    put32(file, 0x46546C67u);
    put32(file + 4, 2);
    put32(file + 8, (uint32_t)flen);
    put32(file + 12, (uint32_t)jp);
    put32(file + 16, 0x4E4F534Au);
    memcpy(file + 20, json, jl);
    memset(file + 20 + jl, ' ', jp - jl);
    if (bin) {
        put32(file + 20 + jp, (uint32_t)bp);
        put32(file + 24 + jp, 0x004E4942u);
        memcpy(file + 28 + jp, bin, binlen);
    }
}

static int mem_src(void *ctx, uint64_t off, void *buf, size_t n)
{
    (void)ctx;
    if (off > flen || n > flen - off)
        return -1;
    memcpy(buf, file + off, n);
    return 0;
}

static cm_err read_glb(cm_status *st)
{
    mesh = test_mesh_on(g_pos, g_nrm, g_idx, g_faces, MAXV, MAXI, 16);
    cm_status_init(st);
    return cm_glb_read(&g, mem_src, NULL, flen, &mesh, &model, st);
}

/* one triangle (0,0,0), (1,0,0), (0,1,0) in glTF metres, u16 indices, and its normals +Z */
typedef struct tri_bin {
    float pos[3][3];
    float nrm[3][3];
    uint16_t idx[3];
    uint16_t pad;
} tri_bin;
static tri_bin tri = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}}, {0, 1, 2}, 0};

#define TRI_VIEWS                                                                                          \
    "\"buffers\":[{\"byteLength\":80}],\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":72}," \
    "{\"buffer\":0,\"byteOffset\":72,\"byteLength\":6}],"
#define TRI_ACCESSORS                                                                                      \
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"             \
    "{\"bufferView\":0,\"byteOffset\":36,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"          \
    "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}],"

static void assert_pos(uint32_t v, double x, double y, double z)
{
    assert_true(fabs((double)g_pos[v][0] - x) < 1e-3 && fabs((double)g_pos[v][1] - y) < 1e-3 &&
                fabs((double)g_pos[v][2] - z) < 1e-3);
}

/* the triangle as is: CAD millimetres, Z up ((x, y, z) glTF -> 1000 (x, -z, y)); red; normals -Y */
static void test_one_triangle(void **state)
{
    (void)state;
    make_glb("{\"asset\":{\"version\":\"2.0\"}," TRI_VIEWS TRI_ACCESSORS
             "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,0,0.2,1]}}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1},\"indices\":2,"
             "\"material\":0}]}],\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0}",
             &tri, sizeof tri);
    cm_status st;
    assert_ok(read_glb(&st));
    assert_int_equal(mesh.nfaces, 1);
    assert_int_equal(mesh.nverts, 3);
    assert_int_equal(mesh.nindex, 3);
    assert_int_equal(model.nfaces, 1);
    assert_int_equal(model.nparts, 1);
    assert_int_equal(model.faces[0].part, 1);
    assert_int_equal(model.nedges, 0);
    assert_true(g_faces[0].has_color);
    assert_int_equal(g_faces[0].rgb, 0xff0033);
    assert_pos(1, 1000, 0, 0);
    assert_pos(2, 0, 0, 1000);
    assert_true(fabs((double)g_nrm[0][1] + 1.0) < 1e-6); /* glTF +Z is CAD -Y */
    for (int k = 0; k < 3; k++)
        assert_int_equal(g_idx[k], (uint32_t)k);
}

/* no NORMAL: each vertex the normal of its triangle; no material, and `cmz decode`'s "default" one:
   no colour; no scenes: every node without a parent */
static void test_normals_made_and_no_colour(void **state)
{
    (void)state;
    make_glb("{" TRI_VIEWS TRI_ACCESSORS "\"materials\":[{\"name\":\"default\",\"pbrMetallicRoughness\":"
             "{\"baseColorFactor\":[0.8,0.8,0.8,1]}}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":2,\"material\":0},"
             "{\"attributes\":{\"POSITION\":0},\"indices\":2}]}],\"nodes\":[{\"mesh\":0}]}",
             &tri, sizeof tri);
    cm_status st;
    assert_ok(read_glb(&st));
    assert_int_equal(mesh.nfaces, 2);
    assert_false(g_faces[0].has_color);
    assert_false(g_faces[1].has_color);
    for (uint32_t v = 0; v < 6; v++)
        assert_true(fabs((double)g_nrm[v][1] + 1.0) < 1e-6 && fabs((double)g_nrm[v][0]) < 1e-6);
}

/*
 * Nodes: the root scales by 0.001 and turns Z up into Y up (as `cmz decode` writes it), its two
 * children place the triangle moved and mirrored (scale -1 along x): three parts' worth of nodes,
 * two with the mesh: two parts; the mirrored copy's triangle turned
 */
static void test_nodes_place_and_mirror(void **state)
{
    (void)state;
    make_glb("{" TRI_VIEWS TRI_ACCESSORS
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1},\"indices\":2}]}],"
             "\"nodes\":[{\"matrix\":[0.001,0,0,0, 0,0,-0.001,0, 0,0.001,0,0, 0,0,0,1],\"children\":[1,2]},"
             "{\"mesh\":0,\"translation\":[10,0,0]},{\"mesh\":0,\"scale\":[-1,1,1]}],"
             "\"scenes\":[{\"nodes\":[0]}]}",
             &tri, sizeof tri);
    cm_status st;
    assert_ok(read_glb(&st));
    assert_int_equal(mesh.nfaces, 2);
    assert_int_equal(model.nparts, 2);
    assert_int_equal(model.faces[0].part, 1);
    assert_int_equal(model.faces[1].part, 2);
    /* the root maps CAD (x, y, z) mm to glTF: the model comes back in its own millimetres */
    assert_pos(0, 10, 0, 0);
    assert_pos(1, 11, 0, 0);
    assert_pos(2, 10, 1, 0);
    assert_pos(4, -1, 0, 0);
    /* the mirrored copy: corners 0, 2, 1, so that it still turns the same way seen from its front */
    assert_int_equal(g_idx[3], 3);
    assert_int_equal(g_idx[4], 5);
    assert_int_equal(g_idx[5], 4);
    /* TRS: a quarter turn about glTF's Y (CAD Z): (1,0,0) -> (0,0,-1) glTF -> (0, 1000, 0) CAD */
    make_glb("{" TRI_VIEWS TRI_ACCESSORS
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":2}]}],"
             "\"nodes\":[{\"mesh\":0,\"rotation\":[0,0.70710678118654752,0,0.70710678118654752]}]}",
             &tri, sizeof tri);
    assert_ok(read_glb(&st));
    assert_pos(1, 0, 1000, 0);
}

/* points and lines are left out and counted */
static void test_not_triangles(void **state)
{
    (void)state;
    make_glb("{" TRI_VIEWS TRI_ACCESSORS
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"mode\":0},"
             "{\"attributes\":{\"POSITION\":0},\"indices\":2,\"mode\":4}]}],\"nodes\":[{\"mesh\":0}]}",
             &tri, sizeof tri);
    cm_status st;
    assert_ok(read_glb(&st));
    assert_int_equal(mesh.nfaces, 1);
    assert_int_equal(g.skipped_prims, 1);
}

static void refused(const char *json, const void *bin, size_t binlen, cm_err code, const char *says)
{
    make_glb(json, bin, binlen);
    cm_status st;
    cm_err e = read_glb(&st);
    if (e != code || !st.where || !strstr(st.where, says))
        fail_msg("%.60s...: %s (%s), expected %s (%s)", json, cm_err_name(e), st.where ? st.where : "-",
                 cm_err_name(code), says);
}

#define TRI_MESH "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":2}]}],\"nodes\":[{\"mesh\":0}]"

static void test_malformed_refused(void **state)
{
    (void)state;
    cm_status st;
    /* the container */
    make_glb("{}", NULL, 0);
    flen = 10;
    assert_err(read_glb(&st), CM_E_TRUNCATED);
    make_glb("{}", NULL, 0);
    file[0] = 'X';
    assert_err(read_glb(&st), CM_E_FORMAT);
    make_glb("{}", NULL, 0);
    file[4] = 1;
    assert_err(read_glb(&st), CM_E_VERSION);
    make_glb("{}", NULL, 0);
    put32(file + 8, (uint32_t)flen + 1);
    assert_err(read_glb(&st), CM_E_TRUNCATED);
    make_glb("{}", &tri, sizeof tri);
    put32(file + 20 + 4, 4096); /* the BIN chunk longer than the file */
    assert_err(read_glb(&st), CM_E_TRUNCATED);
    /* the JSON */
    refused("{\"nodes\":[{\"mesh\":0}", NULL, 0, CM_E_TRUNCATED, "ends inside");
    refused("[1,2]", NULL, 0, CM_E_FORMAT, "not an object");
    refused("{\"a\" 1}", NULL, 0, CM_E_FORMAT, "':' expected");
    refused("{\"a\":1 \"b\":2}", NULL, 0, CM_E_FORMAT, "',' or");
    refused("{\"a\":[1,2}", NULL, 0, CM_E_FORMAT, "',' or");
    refused("{\"a\":-}", NULL, 0, CM_E_FORMAT, "a value expected");
    refused("{1:2}", NULL, 0, CM_E_FORMAT, "a key expected");
    refused("{\"a\":\"open}", NULL, 0, CM_E_FORMAT, "a value expected");
    {
        char deep[200] = "{\"a\":";
        for (int i = 0; i < 70; i++)
            strcat(deep, "[");
        refused(deep, NULL, 0, CM_E_LIMIT, "nested more than 64");
    }
    /* a number of 600 digits and one past a double's range: read, not an index */
    {
        static char big[800];
        strcpy(big, "{\"scene\":");
        for (int i = 0; i < 600; i++)
            strcat(big, "9");
        strcat(big, "}");
        refused(big, NULL, 0, CM_E_FORMAT, "scene: not an index");
    }
    refused("{\"scene\":1e999999}", NULL, 0, CM_E_FORMAT, "scene: not an index");
    refused("{\"scene\":-1}", NULL, 0, CM_E_FORMAT, "scene: not an index");
    /* what the geometry says */
    refused("{" TRI_VIEWS TRI_ACCESSORS TRI_MESH ",\"buffers\":[{\"uri\":\"x.bin\",\"byteLength\":80}]}", &tri,
            sizeof tri, CM_E_FORMAT, "uri");
    refused("{" TRI_VIEWS
            "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"sparse\":"
            "{\"count\":1}},{},{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}]," TRI_MESH "}",
            &tri, sizeof tri, CM_E_FORMAT, "POSITION");
    refused("{" TRI_VIEWS
            "\"accessors\":[{\"bufferView\":0,\"componentType\":5121,\"count\":3,\"type\":\"VEC3\"},{},"
            "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}]," TRI_MESH "}",
            &tri, sizeof tri, CM_E_FORMAT, "POSITION (float VEC3)");
    refused("{" TRI_VIEWS
            "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":7,\"type\":\"VEC3\"},{},"
            "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}]," TRI_MESH "}",
            &tri, sizeof tri, CM_E_RANGE, "POSITION");
    refused("{" TRI_VIEWS
            "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},{},"
            "{\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"SCALAR\"}]," TRI_MESH "}",
            &tri, sizeof tri, CM_E_FORMAT, "indices");
    refused("{\"buffers\":[{\"byteLength\":80}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":72},"
            "{\"buffer\":0,\"byteOffset\":72,\"byteLength\":99999}]," TRI_ACCESSORS TRI_MESH "}",
            &tri, sizeof tri, CM_E_RANGE, "indices");
    {
        tri_bin bad = tri;
        bad.idx[2] = 3; /* one past the positions */
        refused("{" TRI_VIEWS TRI_ACCESSORS TRI_MESH "}", &bad, sizeof bad, CM_E_RANGE, "beyond its positions");
    }
    refused("{" TRI_VIEWS TRI_ACCESSORS "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":9}}]}],"
            "\"nodes\":[{\"mesh\":0}]}", &tri, sizeof tri, CM_E_RANGE, "POSITION");
    refused("{\"nodes\":[{\"children\":[1]},{\"children\":[1]}]}", NULL, 0, CM_E_FORMAT, "two parents");
    refused("{\"nodes\":[{\"children\":[1]},{},{\"children\":[1]}]}", NULL, 0, CM_E_FORMAT, "two parents");
    refused("{\"nodes\":[{\"children\":[4000000000]}]}", NULL, 0, CM_E_LIMIT, "glTF nodes");
    refused("{\"nodes\":[{\"matrix\":[1,\"x\"]}]}", NULL, 0, CM_E_FORMAT, "transform");
    /* a cycle of nodes is no scene's: nothing placed, no crash */
    make_glb("{" TRI_VIEWS TRI_ACCESSORS "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
             "\"nodes\":[{\"mesh\":0,\"children\":[1]},{\"mesh\":0,\"children\":[0]}]}",
             &tri, sizeof tri);
    assert_ok(read_glb(&st));
    assert_int_equal(mesh.nfaces, 0);
    /* more faces than the mesh holds: refused by name */
    {
        static char many[8192];
        strcpy(many, "{" TRI_VIEWS TRI_ACCESSORS "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                     "\"nodes\":[");
        for (int i = 0; i < 20; i++)
            strcat(many, i ? ",{\"mesh\":0}" : "{\"mesh\":0}");
        strcat(many, "]}");
        refused(many, &tri, sizeof tri, CM_E_LIMIT, "glTF primitives placed");
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_one_triangle),
        cmocka_unit_test(test_normals_made_and_no_colour),
        cmocka_unit_test(test_nodes_place_and_mirror),
        cmocka_unit_test(test_not_triangles),
        cmocka_unit_test(test_malformed_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
