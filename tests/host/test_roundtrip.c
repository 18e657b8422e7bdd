/*
 * test_roundtrip.c - IGES -> encoder -> .cmz bytes -> decoder -> triangles
 * on synthetic models with exactly known geometry: what the terminal
 * rebuilds is checked against the true solid (grid error, volume, distance
 * to the true surface, watertightness and orientation of the welded mesh),
 * and every named kind of damaged file is refused with its code and the
 * byte offset where it was detected.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_decode.h"
#include "cm/cm_tessellate.h"
#include "cm/cm_arith.h"
#include "cm/cm_crc32.h"
#include "cm/cm_method.h"
#include "cm/cm_corner.h"
#include "cm/cm_cubic_convert.h"
#include "cm/cm_limits_info.h"
#include "encode/encode.h"
#include "encode/verify.h"
#include "igs_writer.h"
#include "mesh/mesh_topo.h"
#include "model_load.h"

/* the decoder and the tessellation workspace, static as on the terminal */
static cm_decoder dec;
static cm_tess_ws tess;
#define MESH_TRIS 200000
static float pos[MESH_TRIS + 1024][3], nrm[MESH_TRIS + 1024][3];
static uint32_t idx[3 * MESH_TRIS];
static cm_mesh_face mfaces[1024];

/* ---- helpers ---- */

/* load the model w describes and encode it with options o */
static void encode_igw_opts(igw *w, loaded_model *lm, encode_result *r, const encode_opts *o)
{
    size_t len = 0;
    char *text = igw_text(w, &len);
    cm_status st;
    cm_status_init(&st);
    assert_ok(model_load_data("synthetic", text, len, lm, NULL, NULL, &st));
    free(text);
    memset(r, 0, sizeof *r);
    cm_status_init(&st);
    assert_ok(encode_model(lm, o, r, &st));
    assert_non_null(r->bytes);
}

/* the default options, GREGORY-FIT left out when `fit` is 0 */
static void encode_igw_fit(igw *w, loaded_model *lm, encode_result *r, int fit)
{
    encode_opts o;
    encode_opts_default(&o);
    o.gregory_fit = fit;
    encode_igw_opts(w, lm, r, &o);
}

static void encode_igw(igw *w, loaded_model *lm, encode_result *r)
{
    encode_igw_fit(w, lm, r, 1);
}

/* feed in `chunk`-byte pieces, then finish; the first failure is returned */
static cm_err decode_bytes(const uint8_t *p, size_t n, size_t chunk, cm_status *st)
{
    cm_status_init(st);
    cm_dec_init(&dec);
    for (size_t off = 0; off < n; off += chunk) {
        size_t k = n - off < chunk ? n - off : chunk;
        cm_err e = cm_dec_feed(&dec, p + off, k, st);
        if (e != CM_OK)
            return e;
    }
    return cm_dec_finish(&dec, st);
}

static void tessellate_all(cm_mesh *mesh)
{
    *mesh = (cm_mesh){pos, nrm, idx, mfaces, 0, MESH_TRIS + 1024, 0, 3 * MESH_TRIS, 0, 1024, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    cm_mesh_clear(mesh);
    for (uint32_t f = 0; f < dec.model.nfaces; f++) {
        cm_tess_info info;
        cm_status st;
        cm_status_init(&st);
        cm_err e = cm_tessellate_face(&dec.model, f, dec.model.tess_tol, mesh, &tess, &info, &st);
        if (e != CM_OK)
            fail_msg("face %u: %s (%s)", f, cm_err_name(e), st.where ? st.where : "?");
    }
    assert_int_equal(mesh->nfaces, dec.model.nfaces);
}

/* weld and census; fails on overlap, misorientation or degenerate triangles */
static void topo(const cm_mesh *m, mesh_topo *t)
{
    assert_int_equal(mesh_topo_analyse(m, t), 0);
    if (t->degenerate)
        fail_msg("%zu triangles have two corners at one point", t->degenerate);
    if (t->duplicate)
        fail_msg("%zu directed edges used twice: faces overlap or are misoriented", t->duplicate);
}

/* ---- box with a through hole (7 faces: 6 planes, 1 cylinder) ---- */
#define BA 40.0
#define BB 30.0
#define BC 10.0
#define BR 6.0

static void check_box(igw *w)
{
    loaded_model lm;
    encode_result r;
    encode_igw(w, &lm, &r);
    assert_int_equal(r.faces_by_method[CM_METHOD_PLANE], 6); /* the six planar faces need no surface data */
    /* the hole's cylinder, a full turn between two circles and its seam: its surface is deleted and
       comes back exactly over the circles themselves (GREGORY-EXACT; a full circle is no cubic) */
    assert_int_equal(r.faces_by_method[CM_METHOD_GREGORY_EXACT], 1);
    assert_int_equal(r.faces_by_method[CM_METHOD_KEEP], 0);
    for (int f = 0; f < lm.mesh.nfaces; f++)
        if (r.faces[f].method == CM_METHOD_PLANE && !(r.faces[f].ratio <= 0.01))
            fail_msg("plane face %d verified at %.3g of its size, above the 1%% tolerance", f, r.faces[f].ratio);

    cm_status st;
    assert_ok(decode_bytes(r.bytes, r.len, r.len, &st));
    const cm_model *m = &dec.model;
    assert_int_equal(m->nfaces, 7);
    assert_int_equal(m->nverts, 10); /* 8 corners + one vertex on each circle */
    assert_int_equal(m->nedges, 15); /* 12 box edges, 2 circles, the cylinder's seam */
    /* every vertex on the grid within half a step per axis of a true one */
    double q = m->q;
    for (uint32_t v = 0; v < m->nverts; v++) {
        cm_vec3 p = m->verts[v];
        int corner = (fabs(p.x) <= q || fabs(p.x - BA) <= q) && (fabs(p.y) <= q || fabs(p.y - BB) <= q) &&
                     (fabs(p.z) <= q || fabs(p.z - BC) <= q);
        int on_circle = fabs(hypot(p.x - BA / 2, p.y - BB / 2) - BR) <= 2 * q && (fabs(p.z) <= q || fabs(p.z - BC) <= q);
        if (!corner && !on_circle)
            fail_msg("vertex %u (%.17g %.17g %.17g) is not a vertex of the solid (grid %.3g)", v, p.x, p.y, p.z, q);
    }

    /* the same bytes fed one at a time decode to the same model */
    static cm_vec3 first[16];
    memcpy(first, m->verts, sizeof first);
    assert_ok(decode_bytes(r.bytes, r.len, 1, &st));
    assert_memory_equal(first, dec.model.verts, sizeof first);

    cm_mesh mesh;
    tessellate_all(&mesh);
    mesh_topo t;
    topo(&mesh, &t);
    assert_int_equal(t.unpaired, 0); /* closed, welded at shared edges, consistently oriented */
    /*
     * Volume: the box less the hole, outward (positive).  The only curved face
     * is the hole, tessellated inside its chordal tolerance: the polygon's area
     * differs from the disc's by at most perimeter x tolerance.
     */
    double exact = BA * BB * BC - M_PI * BR * BR * BC;
    double tol = 2 * M_PI * BR * m->tess_tol * BC + 1e-3;
    assert_near(t.volume, exact, tol);
    mesh_topo_free(&t);
    /* every vertex of the hole's triangles lies on the true cylinder */
    const cm_mesh_face *hole = NULL;
    for (uint32_t f = 0; f < mesh.nfaces; f++)
        if (m->faces[mesh.faces[f].source_face].method == CM_METHOD_GREGORY_EXACT)
            hole = &mesh.faces[f];
    assert_non_null(hole);
    for (uint32_t i = hole->first_vert; i < hole->first_vert + hole->nverts; i++) {
        double rho = hypot((double)pos[i][0] - BA / 2, (double)pos[i][1] - BB / 2);
        /* grid, float output and the exact rational circle's quantised weights: the patch over the
           circles is the cylinder (linear along its axis), not an approximation of it */
        assert_near(rho, BR, 4 * q + 1e-5);
    }
    encode_result_free(&r);
    model_free(&lm);
}

static void test_box_hole_144(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_box_with_hole_144(&w, BA, BB, BC, BR);
    check_box(&w);
    igw_free(&w);
}

static void test_box_hole_186(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_box_with_hole_186(&w, BA, BB, BC, BR);
    check_box(&w);
    igw_free(&w);
}

/* A solid written inside out (every face's flag in its shell turned), thick and thin: the part is
   turned outwards on the B-rep before anything is written, so the terminal's mesh encloses a positive
   volume and every face was turned once */
static void check_inside_out(double c)
{
    igw w;
    igw_init(&w);
    igw_box_with_hole_186_oriented(&w, BA, BB, c, BR, 1);
    loaded_model lm;
    encode_result r;
    encode_igw(&w, &lm, &r);
    cm_status st;
    assert_ok(decode_bytes(r.bytes, r.len, r.len, &st));
    cm_mesh mesh;
    tessellate_all(&mesh);
    mesh_topo t;
    topo(&mesh, &t);
    assert_int_equal(t.unpaired, 0);
    double exact = BA * BB * c - M_PI * BR * BR * c;
    double tol = 2 * M_PI * BR * dec.model.tess_tol * c + 1e-3;
    if (fabs(t.volume - exact) > tol)
        fail_msg("a %g mm thick solid written inside out encloses %.6g mm^3 after encoding, want %.6g (faces turned %d)",
                 c, t.volume, exact, r.faces_flipped);
    assert_int_equal(r.faces_flipped % 7, 0); /* all seven turned, or none twice */
    assert_true(r.faces_flipped > 0);
    mesh_topo_free(&t);
    encode_result_free(&r);
    model_free(&lm);
    igw_free(&w);
}

static void test_inside_out(void **state)
{
    (void)state;
    check_inside_out(BC);
    check_inside_out(0.25); /* thin: the two large faces nearly cancel */
}

/* ---- an open surface: half cylinder, r = 5, h = 12 ---- */
/*
 * An exactly flat face bounded by a circle is a PLANE with no error at any tolerance (issue 14.7):
 * the measure was the distance to the method's rectangle, which the circle bulges past between the
 * boundary samples, 0.8-0.9 % of the face, so at --tol 0.001 the disc was kept ("fewer than 3
 * sides").  A PLANE face is its plane trimmed by its boundary: the error is its height over it.
 */
static void test_flat_disc_plane(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_disc_144(&w, 20.0, 3.0);
    encode_opts o;
    encode_opts_default(&o);
    o.rel_tol = 0.001;
    o.rel_set = 1;
    o.budget_steps = 0; /* the points on the grid: the budget's steps would lift them off the plane by
                           up to half a step (3e-5 mm here), and the measure is under test, not them */
    loaded_model lm;
    encode_result r;
    encode_igw_opts(&w, &lm, &r, &o);
    igw_free(&w);
    assert_int_equal(r.faces_by_method[CM_METHOD_PLANE], 1);
    if (!(r.faces[0].rebuild_max < 1e-9 * r.faces[0].bbox))
        fail_msg("the disc's PLANE error is %g mm of a %g mm face", r.faces[0].rebuild_max, r.faces[0].bbox);
    encode_result_free(&r);
    model_free(&lm);
}

/*
 * Model-level accuracy by default (issue 14.6): a rebuilt face is within the smaller of 1 % of its
 * own box and 1e-3 of the model's diagonal.  With 1 % of the face alone, a face as large as its
 * model could drift ten times further than a mesh at 1e-3 of the diagonal would (as1_pe_203's 5 m
 * face was rebuilt 48 mm off, 0.75 % of the diagonal).  Curved one-face models, default options.
 */
static void test_default_tolerance_model_level(void **state)
{
    (void)state;
    for (int shape = 0; shape < 4; shape++) {
        igw w;
        igw_init(&w);
        if (shape == 0)
            igw_bump_144(&w, 10, 2);
        else if (shape == 1)
            igw_tri_bump_144(&w, 10, 2);
        else if (shape == 2)
            igw_dome_square_hole_144(&w, 12.0, 4.0);
        else
            igw_bicubic_128(&w);
        encode_opts o;
        encode_opts_default(&o);
        /* the bump in format 2's coding: in format 3 its kept net, on a step of its own, costs fewer
           bits than the GREGORY-FIT record that rebuilds it, and the face stays kept (and closer) */
        if (shape == 0)
            encode_opts_for_format(&o, 2, CM_FMT_V2_MINOR);
        loaded_model lm;
        encode_result r;
        encode_igw_opts(&w, &lm, &r, &o);
        igw_free(&w);
        double diag = brep_diag(&lm.brep);
        int rebuilt = 0;
        for (int f = 0; f < lm.mesh.nfaces; f++) {
            if (r.faces[f].method == CM_METHOD_KEEP)
                continue;
            rebuilt++;
            if (!(r.faces[f].rebuild_max <= 1e-3 * diag))
                fail_msg("shape %d, face %d (method %d): %g mm off, over 1e-3 of the %g mm diagonal", shape, f,
                         r.faces[f].method, r.faces[f].rebuild_max, diag);
        }
        if (shape == 0)
            assert_true(rebuilt > 0); /* the bump is still rebuilt, only closer */
        encode_result_free(&r);
        model_free(&lm);
    }
}

/*
 * The decoded mesh measured against the source (issue 14.6, --report's mesh_dev_mm): each face's
 * triangles at the recommended chordal tolerance, as the terminal makes them, lie within the face's
 * rebuild error plus that tolerance of its source; the same measure on the same triangles moved
 * 0.5 mm along their normals reads 0.5 mm.
 */
static void test_mesh_deviation_measured(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_bump_144(&w, 10, 2);
    encode_opts o;
    encode_opts_default(&o);
    o.measure_mesh = 1;
    loaded_model lm;
    encode_result r;
    encode_igw_opts(&w, &lm, &r, &o);
    igw_free(&w);
    cm_status st;
    assert_ok(decode_bytes(r.bytes, r.len, r.len, &st));
    int curved = 0;
    for (int f = 0; f < lm.mesh.nfaces; f++) {
        double dev = r.faces[f].mesh_dev, bound = r.faces[f].rebuild_max + 1.5 * r.tess_used;
        if (!(dev >= 0.0 && dev <= bound))
            fail_msg("face %d (method %d): mesh %g mm off its source, bound %g (rebuild %g, chord %g)", f,
                     r.faces[f].method, dev, bound, r.faces[f].rebuild_max, r.tess_used);
        curved += dev > 0.1 * r.tess_used;
        cm_mesh mesh = {pos, nrm, idx, mfaces, 0, MESH_TRIS + 1024, 0, 3 * MESH_TRIS, 0, 1024, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
        cm_mesh_clear(&mesh);
        cm_tess_info info;
        cm_status_init(&st);
        assert_ok(cm_tessellate_face(&dec.model, (uint32_t)f, dec.model.tess_tol, &mesh, &tess, &info, &st));
        double expect = r.faces[f].rebuild_max + dec.model.tess_tol;
        double again = verify_mesh_face(&lm, f, (const float(*)[3])pos, mesh.nverts, idx, mesh.nindex, expect);
        assert_true(fabs(again - dev) <= 1e-12 * (1.0 + dev)); /* the encoder's measure, on the terminal's mesh */
        /* half the triangles gone: only the source's side sees the hole */
        uint32_t half = 3 * (mesh.nindex / 6);
        double holed = verify_mesh_face(&lm, f, (const float(*)[3])pos, mesh.nverts, idx, half, expect);
        if (!(holed > 10.0 * dev && holed > 0.1))
            fail_msg("face %d: half its triangles gone reads %g mm (%g whole)", f, holed, dev);
        /* one more triangle 2 mm above the first vertex's: only the mesh's side sees it */
        if (mesh.nverts + 3 <= MESH_TRIS + 1024 && mesh.nindex + 3 <= 3 * MESH_TRIS) {
            for (int c = 0; c < 3; c++) {
                for (int k = 0; k < 3; k++)
                    pos[mesh.nverts + c][k] = pos[0][k] + 2.0f * nrm[0][k] + (c == k ? 0.01f : 0.0f);
                idx[mesh.nindex + c] = mesh.nverts + (uint32_t)c;
            }
            double flap =
                verify_mesh_face(&lm, f, (const float(*)[3])pos, mesh.nverts + 3, idx, mesh.nindex + 3, expect);
            if (!(flap >= 1.9 && flap <= 2.1 + dev))
                fail_msg("face %d: a triangle 2 mm off reads %g mm", f, flap);
        }
        /* 16 times the chordal tolerance: the chords' sag is seen */
        cm_mesh_clear(&mesh);
        assert_ok(cm_tessellate_face(&dec.model, (uint32_t)f, 16.0 * dec.model.tess_tol, &mesh, &tess, &info, &st));
        double coarse = verify_mesh_face(&lm, f, (const float(*)[3])pos, mesh.nverts, idx, mesh.nindex, expect);
        if (!(coarse >= 0.5 * 16.0 * r.tess_used)) /* measured 0.105 mm at 16 x 0.00707 (its vertices: 0.011) */
            fail_msg("face %d: at 16 times the chordal tolerance %g mm reads %g mm", f, r.tess_used, coarse);
        cm_mesh_clear(&mesh);
        assert_ok(cm_tessellate_face(&dec.model, (uint32_t)f, dec.model.tess_tol, &mesh, &tess, &info, &st));
        for (uint32_t v = 0; v < mesh.nverts; v++)
            for (int k = 0; k < 3; k++)
                pos[v][k] += 0.5f * nrm[v][k];
        double moved = verify_mesh_face(&lm, f, (const float(*)[3])pos, mesh.nverts, idx, mesh.nindex, expect);
        if (!(moved >= 0.5 - dev - 1e-4 && moved <= 0.5 + 2.0 * dev + r.tess_used + 1e-4))
            fail_msg("face %d: its mesh moved 0.5 mm reads %g mm (%g before)", f, moved, dev);
    }
    assert_true(curved > 0); /* the bump's chords are seen */
    encode_result_free(&r);
    model_free(&lm);
}

/*
 * Fit the board (issue 14.5): a profile whose tessellation limits the model passes at the asked
 * chordal tolerance gets a coarser recommended one (twice at a time, at most 16 times), stated in
 * the header and in the result, instead of a refusal; past 16 times it is still refused.
 */
static void test_profile_coarsens_tessellation(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_bump_144(&w, 10, 2);
    encode_opts o;
    encode_opts_default(&o);
    loaded_model lm;
    encode_result r;
    encode_igw_opts(&w, &lm, &r, &o);
    uint32_t points = r.need[CM_LIMIT_MAX_TESS_POINTS];
    assert_true(points > 100);
    assert_true(r.tess_used == r.tess_asked);
    encode_result_free(&r);
    model_free(&lm);

    static cm_limit_info board[CM_LIMIT_COUNT];
    for (int i = 0; i < CM_LIMIT_COUNT; i++)
        board[i] = cm_limit_table[i];
    board[CM_LIMIT_MAX_TESS_POINTS].value = points / 3;
    o.target = board;
    o.target_name = "test";
    encode_igw_opts(&w, &lm, &r, &o);
    assert_true(r.need[CM_LIMIT_MAX_TESS_POINTS] <= points / 3);
    assert_true(r.tess_used >= 2 * r.tess_asked && r.tess_used <= 16 * r.tess_asked);
    cm_status st;
    assert_ok(decode_bytes(r.bytes, r.len, 7, &st));
    assert_true(dec.model.tess_tol == r.tess_used);
    encode_result_free(&r);
    model_free(&lm);

    /* a limit no coarser tolerance within 16 times meets: refused, by name */
    board[CM_LIMIT_MAX_TESS_POINTS].value = 4;
    char *text = NULL;
    size_t len = 0;
    text = igw_text(&w, &len);
    assert_ok(model_load_data("synthetic", text, len, &lm, NULL, NULL, &st));
    free(text);
    memset(&r, 0, sizeof r);
    cm_status_init(&st);
    assert_int_equal(encode_model(&lm, &o, &r, &st), CM_E_LIMIT);
    assert_int_equal(st.limit, CM_LIMIT_MAX_TESS_POINTS);
    assert_non_null(strstr(r.refusal, "MAX_TESS_POINTS"));
    encode_result_free(&r);
    model_free(&lm);
    igw_free(&w);
}

/* the centre of the mesh's triangle t */
static void tri_centre(uint32_t t, double c[3])
{
    c[0] = c[1] = c[2] = 0;
    for (int k = 0; k < 3; k++)
        for (int j = 0; j < 3; j++)
            c[j] += (double)pos[idx[3 * t + (uint32_t)k]][j] / 3.0;
}

/* a cylinder of radius R about z: vertices on it, triangle centres within tol inside it */
static int cylinder_mesh_ok(const cm_mesh *mesh, double R, double q, double tol)
{
    for (uint32_t i = 0; i < mesh->nverts; i++)
        if (!(fabs(hypot((double)pos[i][0], (double)pos[i][1]) - R) <= 4 * q + 1e-5))
            return 0;
    for (uint32_t t = 0; t < mesh->nindex / 3; t++) {
        double c[3];
        tri_centre(t, c);
        double rho = hypot(c[0], c[1]);
        if (!(rho <= R + 4 * q + 1e-5 && rho >= R - tol - 4 * q - 1e-5))
            return 0;
    }
    return 1;
}

/* z = 4 h t (1 - t), t = y / b: vertices on it, centres (below it: it is concave) within tol; both
   up to `net` more, the kept net's own distance from the trough (the encoder may re-approximate it
   within a quarter of the face's tolerance) */
static int trough_mesh_ok(const cm_mesh *mesh, double b, double h, double q, double tol, double net)
{
    for (uint32_t i = 0; i < mesh->nverts; i++) {
        double t = (double)pos[i][1] / b;
        if (!(fabs((double)pos[i][2] - 4 * h * t * (1 - t)) <= net + 4 * q + 1e-5))
            return 0;
    }
    for (uint32_t f = 0; f < mesh->nindex / 3; f++) {
        double c[3];
        tri_centre(f, c);
        double t = c[1] / b, under = 4 * h * t * (1 - t) - c[2];
        if (!(under >= -net - 4 * q - 1e-5 && under <= tol + net + 4 * q + 1e-5))
            return 0;
    }
    return 1;
}

static void test_half_cylinder(void **state)
{
    (void)state;
    const double R = 5, H = 12;
    igw w;
    igw_init(&w);
    igw_half_cylinder_120(&w, R, H);
    loaded_model lm;
    encode_result r;
    encode_igw(&w, &lm, &r);
    igw_free(&w);
    /* two half circles and two lines: rebuilt over the half circles, exactly (see below) */
    assert_int_equal(r.faces_by_method[CM_METHOD_GREGORY_EXACT], 1);
    cm_status st;
    assert_ok(decode_bytes(r.bytes, r.len, 7, &st));
    double q = dec.model.q, tol = dec.model.tess_tol;
    cm_mesh mesh;
    tessellate_all(&mesh);
    /* vertices on the surface, triangle centres within the chordal tolerance inside it */
    if (!cylinder_mesh_ok(&mesh, R, q, tol))
        fail_msg("the mesh leaves the cylinder by more than the tolerance %.3g", tol);
    /* the open boundary is the face's four edges: two half circles (z = 0, z = H) and two lines (y = 0) */
    mesh_topo tp;
    topo(&mesh, &tp);
    assert_true(tp.unpaired >= 4);
    for (size_t i = 0; i < 2 * tp.unpaired; i++) {
        cm_vec3 p = tp.bnd[i];
        int ok = fabs(p.z) <= 2 * q || fabs(p.z - H) <= 2 * q || fabs(p.y) <= 2 * q;
        if (!ok)
            fail_msg("boundary point (%.9g %.9g %.9g) is not on the face's boundary", p.x, p.y, p.z);
    }
    mesh_topo_free(&tp);
    encode_result_free(&r);
    model_free(&lm);
}

/* ---- format 4.9: a kept face curved one way is meshed in strips along the other ----
   Two kept faces whose loops have points along their straight edges (each cut into four pieces, as
   as1_pe_203's half cylinders are): a long half cylinder (IGES 120: a line turned half round, a
   rational (1, 2) net: straight along its rulings) at 5 % of its radius, and a long trough (a
   bicubic 128, straight along x but of degree 3 both ways: the squeeze is then at most 4) at 5 % of
   its depth.  Format 4.8's tessellation (the model's refine_49 off) and 4.9's: both keep every
   vertex on the surface and every triangle's centre within the tolerance of it, 4.9's with fewer
   triangles (at most half on the cylinder, at most 3/4 on the trough) */
static void test_kept_strips(void **state)
{
    (void)state;
    const double R = 127, H = 940, A = 600, B = 60, D = 20;
    for (int model = 0; model < 2; model++) {
        igw w;
        igw_init(&w);
        if (model == 0)
            igw_ruled_half_cylinder_144(&w, R, H, 4);
        else
            igw_trough_144(&w, A, B, D, 4);
        loaded_model lm;
        encode_result r;
        encode_opts o;
        encode_opts_default(&o);
        o.gregory = o.gregory_exact = o.gregory_fit = o.g1fit = o.nfill = 0; /* kept */
        encode_igw_opts(&w, &lm, &r, &o);
        igw_free(&w);
        assert_int_equal(r.faces_by_method[CM_METHOD_KEEP], 1);
        cm_status st;
        assert_ok(decode_bytes(r.bytes, r.len, r.len, &st));
        assert_true(dec.model.refine_49); /* the default writer's format */
        dec.model.tess_tol = 0.05 * (model == 0 ? R : D);
        double q = dec.model.q, tol = dec.model.tess_tol;
        cm_mesh mesh;
        uint32_t tris[2];
        for (int v49 = 0; v49 < 2; v49++) {
            dec.model.refine_49 = v49;
            tessellate_all(&mesh);
            tris[v49] = mesh.nindex / 3;
            /* (the face's tolerance: 1e-3 of the model's diagonal, here the face's own) */
            double net = 0.25 * 1e-3 * sqrt(A * A + B * B + D * D);
            if (!(model == 0 ? cylinder_mesh_ok(&mesh, R, q, tol) : trough_mesh_ok(&mesh, B, D, q, tol, net)))
                fail_msg("%s, format 4.%d: the mesh leaves the surface by more than the tolerance %.3g",
                         model == 0 ? "cylinder" : "trough", 8 + v49, tol);
        }
        print_message("# %s kept: 4.8 %u triangles, 4.9 %u\n", model == 0 ? "half cylinder" : "trough", tris[0],
                      tris[1]);
        if (model == 0 ? !(2 * tris[1] <= tris[0]) : !(4 * tris[1] <= 3 * tris[0]))
            fail_msg("%s: 4.9 %u triangles, 4.8 %u (too few spared)", model == 0 ? "cylinder" : "trough", tris[1],
                     tris[0]);
        encode_result_free(&r);
        model_free(&lm);
    }
}

/* ---- format 4.14: a GREGORY side along an arc is its closed-form cubic, not K7's fit ----
   Two quarter cylinders sharing a tangent edge (R 5, length 12: four quarter arcs; each face a
   GREGORY patch over two arcs and two lines), written in the default format and in 4.13.  Each file
   decodes and meshes (its GREGORY checksums are of the patches its own version builds); each face's
   arc sides are cm_cubic_from_conic's cubics in 4.14 and K7's in 4.13; and each file read as the other
   version would read it (the model's conic_cubic flipped) is refused by the checksum of every face,
   so a reader that took the wrong cubic for a version could not go unnoticed. */
static void test_conic_cubic_414(void **state)
{
    (void)state;
    static cm_corner_ws cws;
    static cm_greg_input in;
    for (int v414 = 0; v414 < 2; v414++) {
        igw w;
        igw_init(&w);
        igw_split_half_cylinder_144(&w, 5, 12);
        loaded_model lm;
        encode_result r;
        encode_opts o;
        encode_opts_default(&o);
        if (!v414)
            encode_opts_for_format(&o, CM_FMT_COMPACT_MAJOR, (int)CM_FMT_CONIC_CUBIC_MINOR - 1);
        encode_igw_opts(&w, &lm, &r, &o);
        igw_free(&w);
        assert_int_equal(r.faces_by_method[CM_METHOD_GREGORY], 2);
        cm_status st;
        assert_ok(decode_bytes(r.bytes, r.len, r.len, &st));
        assert_int_equal(dec.model.conic_cubic, v414);
        cm_mesh mesh;
        tessellate_all(&mesh);
        int arcs = 0;
        for (uint32_t f = 0; f < dec.model.nfaces; f++) {
            cm_status_init(&st);
            assert_ok(cm_greg_input_build(&dec.model, f, 0, &in, &cws, &st));
            for (int k = 0; k < in.n; k++) {
                cm_cubic want;
                if (in.side[k].curve.p != 2 || !in.side[k].curve.w)
                    continue;
                arcs++;
                if (v414)
                    assert_int_equal(cm_cubic_from_conic(&in.side[k].curve, &want), 1);
                else
                    assert_ok(cm_cubic_convert(&in.side[k].curve, 0, 1, &want, NULL, NULL, NULL));
                cm_cubic got = in.side[k].rev ? cm_cubic_reverse(&in.side[k].c) : in.side[k].c;
                for (int i = 0; i < 4; i++)
                    assert_vec_near(got.c[i], want.c[i], 0.0);
            }
        }
        assert_int_equal(arcs, 4); /* two quarter arcs a face */
        dec.model.conic_cubic = !v414;
        cm_mesh_clear(&mesh);
        for (uint32_t f = 0; f < dec.model.nfaces; f++) {
            cm_tess_info info;
            cm_status_init(&st);
            cm_err e = cm_tessellate_face(&dec.model, f, dec.model.tess_tol, &mesh, &tess, &info, &st);
            if (e != CM_E_CHECKSUM)
                fail_msg("format 4.%d read as 4.%d: face %u gave %s, not the checksum's refusal", v414 ? 14 : 13,
                         v414 ? 13 : 14, f, cm_err_name(e));
        }
        encode_result_free(&r);
        model_free(&lm);
    }
}

/* ---- format 4.10: a GREGORY patch's plane of triangulation scaled by its boundary's lengths ----
   The exact half cylinder (two half circles of radius 5 and two lines), short (12) and long (60:
   the patch's u and v speeds far apart, so the scale shapes the triangles), tessellated as format
   4.9 (25 interior evaluations, the model's refine_410 off) and as 4.10: both keep every vertex on
   the cylinder and every triangle's centre within the tolerance of it, with triangle counts within
   a quarter of each other */
/* w's model (w freed) encoded as one GREGORY-EXACT face in the default format, and decoded */
static void decode_one_exact(igw *w, loaded_model *lm, encode_result *r)
{
    encode_igw(w, lm, r);
    igw_free(w);
    assert_int_equal(r->faces_by_method[CM_METHOD_GREGORY_EXACT], 1);
    cm_status st;
    assert_ok(decode_bytes(r->bytes, r->len, r->len, &st));
    assert_true(dec.model.refine_410); /* the default writer's format */
}

static void test_patch_scale_410(void **state)
{
    (void)state;
    static float keep_pos[MESH_TRIS + 1024][3];
    const double R = 5, lengths[2] = {12, 60};
    for (int k = 0; k < 2; k++) {
        igw w;
        igw_init(&w);
        igw_half_cylinder_120(&w, R, lengths[k]);
        loaded_model lm;
        encode_result r;
        decode_one_exact(&w, &lm, &r);
        double q = dec.model.q, tol = dec.model.tess_tol;
        cm_mesh mesh;
        uint32_t tris[2];
        for (int v410 = 0; v410 < 2; v410++) {
            dec.model.refine_410 = v410;
            tessellate_all(&mesh);
            tris[v410] = mesh.nindex / 3;
            if (!cylinder_mesh_ok(&mesh, R, q, tol))
                fail_msg("length %g, format 4.%d: the mesh leaves the cylinder by more than the tolerance %.3g",
                         lengths[k], v410 ? 10 : 9, tol);
        }
        print_message("# half cylinder of length %g: 4.9 %u triangles, 4.10 %u\n", lengths[k], tris[0], tris[1]);
        if (!(4 * tris[1] <= 5 * tris[0] && 4 * tris[0] <= 5 * tris[1]))
            fail_msg("length %g: 4.9 %u triangles, 4.10 %u", lengths[k], tris[0], tris[1]);
        encode_result_free(&r);
        model_free(&lm);
    }
    /* (a ruled patch's boundary lengths are its mean speeds: the cylinders mesh the same both ways)
       the half band on the paraboloid z = 5 (1 - r^2 / 400), 5 <= r <= 15 (GREGORY-EXACT): the
       interior bulges, and 4.10's scale makes another mesh of about the same triangles, on the
       surface as closely (vertices within the face's rebuild tolerance of it, 1e-3 of the model's
       diagonal: 0.05 here with the grid, triangle centres within the chordal tolerance more) */
    static uint32_t keep_idx[3 * MESH_TRIS];
    igw w;
    igw_init(&w);
    igw_half_dome_band_144(&w, 5, 15);
    loaded_model lm;
    encode_result r;
    decode_one_exact(&w, &lm, &r);
    double tol = dec.model.tess_tol, slack = 0.05;
    cm_mesh mesh;
    uint32_t tris[2];
    for (int v410 = 0; v410 < 2; v410++) {
        dec.model.refine_410 = v410;
        tessellate_all(&mesh);
        tris[v410] = mesh.nindex / 3;
        for (uint32_t i = 0; i < mesh.nverts; i++) {
            double x = (double)pos[i][0], y = (double)pos[i][1], z = (double)pos[i][2];
            if (!(fabs(z - 5 * (1 - (x * x + y * y) / 400)) <= slack))
                fail_msg("format 4.%d: vertex %u off the paraboloid by %.3g", v410 ? 10 : 9, i,
                         fabs(z - 5 * (1 - (x * x + y * y) / 400)));
        }
        for (uint32_t t = 0; t < mesh.nindex / 3; t++) {
            double c[3];
            tri_centre(t, c);
            double under = 5 * (1 - (c[0] * c[0] + c[1] * c[1]) / 400) - c[2];
            if (!(under >= -slack && under <= tol + slack))
                fail_msg("format 4.%d: triangle %u's centre %.3g under the paraboloid (tolerance %.3g)", v410 ? 10 : 9,
                         t, under, tol);
        }
        if (v410 == 0) {
            memcpy(keep_pos, pos, sizeof(float[3]) * mesh.nverts);
            memcpy(keep_idx, idx, sizeof(uint32_t) * mesh.nindex);
        }
    }
    print_message("# half dome band: 4.9 %u triangles, 4.10 %u\n", tris[0], tris[1]);
    if (!(20 * tris[1] <= 21 * tris[0] && 20 * tris[0] <= 21 * tris[1]))
        fail_msg("half dome band: 4.9 %u triangles, 4.10 %u", tris[0], tris[1]);
    if (tris[0] == tris[1] && memcmp(keep_pos, pos, sizeof(float[3]) * mesh.nverts) == 0 &&
        memcmp(keep_idx, idx, sizeof(uint32_t) * mesh.nindex) == 0)
        fail_msg("half dome band: 4.10 made 4.9's mesh (the patch's scale not in force?)");
    encode_result_free(&r);
    model_free(&lm);
}


/* ---- the refinement spares tests of pieces that passed the round before, and (format 4.8) of
   pieces its corners' normals predict flat, and gives the same mesh ----
   Each model (a KEEP B-spline net, an exact Gregory face over two half circles, a GREGORY-FIT bump)
   is tessellated testing every piece every round (ws.pass_slots = 1, ws.test_every_piece = 1),
   then with the pass cache, then with the cache and the predictions: the same positions, normals
   and indices to the bit, every piece of every round tested, passed again or predicted, and each
   of the two spared tests (else this would compare a path with itself) */
static uint32_t tessellate_counting(cm_mesh *mesh, long *tested, long *skipped, long *predicted)
{
    *mesh = (cm_mesh){pos, nrm, idx, mfaces, 0, MESH_TRIS + 1024, 0, 3 * MESH_TRIS, 0, 1024, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    cm_mesh_clear(mesh);
    *tested = *skipped = *predicted = 0;
    for (uint32_t f = 0; f < dec.model.nfaces; f++) {
        cm_tess_info info;
        cm_status st;
        cm_status_init(&st);
        assert_ok(cm_tessellate_face(&dec.model, f, dec.model.tess_tol, mesh, &tess, &info, &st));
        *tested += info.tested;
        *skipped += info.skipped;
        *predicted += info.predicted;
    }
    return mesh->nverts;
}

static void test_refine_skips_passed_pieces(void **state)
{
    (void)state;
    static float pos0[MESH_TRIS + 1024][3], nrm0[MESH_TRIS + 1024][3];
    static uint32_t idx0[3 * MESH_TRIS];
    long spared = 0, flat = 0;
    for (int model = 0; model < 3; model++) {
        igw w;
        igw_init(&w);
        if (model == 0)
            igw_bicubic_128(&w);
        else if (model == 1)
            igw_half_cylinder_120(&w, 5, 12);
        else
            igw_bump_144(&w, 10, 2); /* as test_gregory_face: GREGORY-FIT */
        loaded_model lm;
        encode_result r;
        encode_igw_fit(&w, &lm, &r, 1);
        igw_free(&w);
        cm_status st;
        assert_ok(decode_bytes(r.bytes, r.len, r.len, &st));
        assert_true(dec.model.refine_48 && dec.model.refine_49); /* the default writer's format */
        cm_mesh mesh;
        long tested, skipped, predicted, tested0, skipped0, predicted0;
        tess.pass_slots = 1;
        tess.test_every_piece = 1;
        uint32_t nv0 = tessellate_counting(&mesh, &tested0, &skipped0, &predicted0);
        uint32_t ni0 = mesh.nindex;
        memcpy(pos0, pos, sizeof pos0);
        memcpy(nrm0, nrm, sizeof nrm0);
        memcpy(idx0, idx, sizeof idx0);
        assert_int_equal(skipped0, 0);
        assert_int_equal(predicted0, 0);
        for (int predict = 0; predict < 2; predict++) {
            tess.pass_slots = 0;
            tess.test_every_piece = !predict;
            uint32_t nv = tessellate_counting(&mesh, &tested, &skipped, &predicted);
            if (predict)
                flat += predicted;
            else
                spared += skipped;
            assert_int_equal(tested + skipped + predicted, tested0);
            assert_int_equal(nv, nv0);
            assert_int_equal(mesh.nindex, ni0);
            assert_memory_equal(pos, pos0, (size_t)nv * sizeof pos[0]);
            assert_memory_equal(nrm, nrm0, (size_t)nv * sizeof nrm[0]);
            assert_memory_equal(idx, idx0, (size_t)ni0 * sizeof idx[0]);
        }
        tess.test_every_piece = 0;
        encode_result_free(&r);
        model_free(&lm);
    }
    /* the net and the bump take several rounds (over half their tests spared); the half cylinder's
       exact patch passes in the first round, so it has nothing to spare */
    if (!(spared > 0))
        fail_msg("the refinement spared no test");
    if (!(flat > 0))
        fail_msg("the refinement predicted no piece flat");
}

/* ---- a free-form patch: the kept net comes back within the grid (GREGORY-FIT, which would send a
   correction instead, left out) ---- */
static void test_bicubic_net(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_bicubic_128(&w);
    loaded_model lm;
    encode_result r;
    encode_igw_fit(&w, &lm, &r, 0);
    igw_free(&w);
    cm_status st;
    assert_ok(decode_bytes(r.bytes, r.len, r.len, &st));
    const cm_model *m = &dec.model;
    assert_int_equal(m->nsurfs, 1);
    const cm_ksurf *S = &m->surfs[0];
    assert_int_equal(S->nu, 4);
    assert_int_equal(S->nv, 4);
    /* the net is (i, j, z_ij) up to the transposition or reversal of the directions the encoder may pick,
       each point on the grid or, in format 3, within the net's budget (tx_coarsen.c: a sixteenth of
       the face's tolerance, at most 1e-3 of the diagonal) */
    double q = m->q + 1e-3 * brep_diag(&lm.brep) / 16.0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            cm_vec3 want = cm_v3(i, j, igw_bicubic_z[i][j]);
            int found = 0;
            for (int k = 0; k < 16; k++)
                found |= cm_dist(m->ctrl[S->ctrl0 + (uint32_t)k], want) <= q;
            if (!found)
                fail_msg("control point (%d %d %.17g) not in the decoded net (grid %.3g)", i, j, want.z, q);
        }
    cm_mesh mesh;
    tessellate_all(&mesh);
    assert_true(mesh.nindex > 0);
    encode_result_free(&r);
    model_free(&lm);
}

/* ---- damaged files: each named case, its code and where it was detected ---- */

static uint8_t *good;
static size_t good_len;

/* the box with a hole, written by the default encoder (format 4.6: the header's fields and the
   sections each one stream), for format 4.5 readers (the varint header) or for format 3 readers (the
   fixed header) */
static int setup_good_as(int major, int minor)
{
    igw w;
    igw_init(&w);
    igw_box_with_hole_144(&w, BA, BB, BC, BR);
    loaded_model lm;
    encode_result r;
    encode_opts o;
    encode_opts_default(&o);
    if (major)
        encode_opts_for_format(&o, major, minor);
    encode_igw_opts(&w, &lm, &r, &o);
    igw_free(&w);
    good = r.bytes;
    good_len = r.len;
    r.bytes = NULL;
    encode_result_free(&r);
    model_free(&lm);
    return 0;
}

static int setup_good(void **state)
{
    (void)state;
    return setup_good_as(0, 0);
}

static int setup_good45(void **state)
{
    (void)state;
    return setup_good_as(CM_FMT_COMPACT_MAJOR, (int)CM_FMT_USE_ADJ_MINOR);
}

static int setup_good3(void **state)
{
    (void)state;
    return setup_good_as(3, 0);
}

static int teardown_good(void **state)
{
    (void)state;
    free(good);
    return 0;
}

/* where a file's fields are, either header (docs/FORMAT.md) */
typedef struct layout {
    int compact;                      /* format 4 */
    int stream;                       /* format 4.6: the fields one stream, the sections one stream */
    uint32_t H, L;                    /* header (its CRC included) and file lengths */
    uint32_t off[CM_SEC_COUNT], len[CM_SEC_COUNT];
    uint32_t need_at[CM_LIMIT_COUNT]; /* each need's first byte */
    uint32_t fields[CM_FMT_MAX_HEADER], nfields; /* format 4: the varints after H */
} layout;

/* the layout of p (n bytes) read as format 4 (compact) or 3; 0 when it does not parse */
static int layout_of(const uint8_t *p, size_t n, int compact, layout *l)
{
    memset(l, 0, sizeof *l);
    l->compact = compact;
    l->L = (uint32_t)n;
    if (!l->compact) {
        l->H = cm_get_u32(p + CM_HDR_LENGTH);
        for (uint32_t s = 0; s < CM_SEC_COUNT; s++) {
            uint32_t e = cm_fmt_entry_at(p[CM_HDR_NLIMITS], s);
            l->off[s] = cm_get_u32(p + e + CM_ENT_OFFSET);
            l->len[s] = cm_get_u32(p + e + CM_ENT_LENGTH);
        }
        for (uint32_t i = 0; i < CM_LIMIT_COUNT; i++)
            l->need_at[i] = cm_fmt_need_at(i);
        return 1;
    }
    uint32_t at = CM_FMT_COMPACT_AT_H;
    uint64_t v;
    if (!cm_fmt_get_varint(p, (uint32_t)n, &at, &v) || v > n || v < 8)
        return 0;
    l->H = (uint32_t)v;
    if (p[CM_HDR_MINOR] >= CM_FMT_ONE_STREAM_MINOR) {
        /* the needs have no byte of their own: the stream's start; the body one section */
        l->stream = 1;
        for (uint32_t i = 0; i < CM_LIMIT_COUNT; i++)
            l->need_at[i] = at;
        for (uint32_t s = 0; s < CM_SEC_COUNT; s++) {
            l->off[s] = s == 0 ? l->H : l->L - 4;
            l->len[s] = s == 0 ? l->L - 4 - l->H : 0;
        }
        return 1;
    }
    /* flags, N, the needs, S, the lengths, grid exponent, origin, tolerances */
    while (at < l->H - 4) {
        uint32_t i = l->nfields, field_at = at;
        if (!cm_fmt_get_varint(p, l->H - 4, &at, &v))
            return 0;
        l->fields[l->nfields++] = (uint32_t)v;
        if (i >= 2 && i < 2 + CM_LIMIT_COUNT)
            l->need_at[i - 2] = field_at;
    }
    uint32_t nl = l->fields[1], off = l->H;
    for (uint32_t s = 0; s < CM_SEC_COUNT; s++) {
        l->len[s] = l->fields[3 + nl + s];
        l->off[s] = off;
        off += l->len[s];
    }
    return 1;
}

/* recompute the header CRC, every section CRC (formats 1-3) and the trailer, so only the intended
   damage remains */
static void reseal(uint8_t *p, size_t n, int compact)
{
    layout l;
    assert_true(layout_of(p, n, compact, &l));
    if (!l.compact)
        for (uint32_t s = 0; s < CM_SEC_COUNT; s++)
            cm_put_u32(p + cm_fmt_entry_at(p[CM_HDR_NLIMITS], s) + CM_ENT_CRC, cm_crc32(p + l.off[s], l.len[s]));
    cm_put_u32(p + l.H - 4, cm_crc32(p, l.H - 4));
    cm_put_u32(p + n - 4, cm_crc32(p, n - 4));
}

/* limit i's need set to v (format 4: the varints re-emitted, H anew; p has room for 16 more bytes) */
static void set_need(uint8_t *p, size_t *n, uint32_t i, uint32_t v)
{
    layout l;
    assert_true(layout_of(p, *n, p[CM_HDR_MAJOR] >= CM_FMT_COMPACT_MAJOR, &l));
    if (!l.compact) {
        cm_put_u32(p + l.need_at[i], v);
        return;
    }
    if (l.stream) {
        /* format 4.6: the fields read, the need changed, written again (the decoder's own code) */
        cm_fmt_header h;
        uint32_t need[CM_LIMIT_COUNT], unknown;
        uint8_t hb[CM_FMT_MAX_HEADER];
        assert_null(cm_fmt_stream_unpack(p, l.H, &h, need, CM_LIMIT_COUNT, &unknown));
        need[i] = v;
        uint32_t H = cm_fmt_stream_pack(hb, &h, need, l.L - l.H - 4);
        memmove(p + H, p + l.H, *n - l.H);
        memcpy(p, hb, H);
        *n = H + *n - l.H;
        return;
    }
    l.fields[2 + i] = v;
    uint8_t body[CM_FMT_MAX_HEADER];
    uint32_t nb = 0;
    for (uint32_t k = 0; k < l.nfields; k++)
        nb += cm_fmt_put_varint(body + nb, l.fields[k]);
    uint8_t hb[CM_FMT_VARINT_MAX];
    uint32_t H = 0, lh = 1;
    for (; lh <= 5 && !H; lh++)
        if (cm_fmt_put_varint(hb, CM_FMT_COMPACT_AT_H + lh + nb + 4u) == lh)
            H = CM_FMT_COMPACT_AT_H + lh + nb + 4u;
    size_t rest = *n - l.H;
    memmove(p + H, p + l.H, rest);
    cm_fmt_put_varint(p + CM_FMT_COMPACT_AT_H, H);
    memcpy(p + H - 4 - nb, body, nb);
    *n = H + rest;
}

typedef enum { CUT, FLIP_BYTE, SET_U8, SET_U32, APPEND, GARBLE_SECTION, SET_NEED } damage_kind;

typedef struct damage {
    const char *name;
    damage_kind kind;
    int64_t where; /* byte offset; negative: from the end; for GARBLE_SECTION the section index,
                      for SET_NEED the limit */
    uint32_t value;
    int reseal;
    cm_err want;
    int64_t want_offset; /* -1: any offset inside the damaged section; -2: not checked; -3: the
                            need's own offset */
} damage;

static void check_damage(const damage *d, uint8_t *buf, size_t c, const layout *l)
{
    size_t n = good_len;
    memcpy(buf, good, good_len);
    size_t at = d->where < 0 ? (size_t)((int64_t)n + d->where) : (size_t)d->where;
    uint32_t seed = 12345u + (uint32_t)c;
    switch (d->kind) {
    case CUT: n = at; break;
    case FLIP_BYTE: buf[at] ^= 0x5A; break;
    case SET_U8: buf[at] = (uint8_t)d->value; break;
    case SET_U32: cm_put_u32(buf + at, d->value); break;
    case APPEND: buf[n++] = 0; break;
    case SET_NEED: set_need(buf, &n, (uint32_t)d->where, d->value); break;
    case GARBLE_SECTION:
        for (uint32_t i = 0; i < l->len[d->where]; i++)
            buf[l->off[d->where] + i] = (uint8_t)(test_rand(&seed) * 256);
        break;
    }
    if (d->reseal)
        reseal(buf, n, l->compact);
    layout now = *l;
    if (d->kind == SET_NEED)
        assert_true(layout_of(buf, n, l->compact, &now));
    /* fed whole, and fed in 3-byte pieces: the same verdict */
    for (int pass = 0; pass < 2; pass++) {
        cm_status st;
        cm_err e = decode_bytes(buf, n, pass ? 3 : (n ? n : 1), &st);
        if (d->kind == GARBLE_SECTION) {
            /* random bytes with valid CRCs: any clear refusal, located inside that section */
            uint32_t so = l->off[d->where], sl = l->len[d->where];
            if (e == CM_OK)
                continue; /* random bits may happen to decode to a valid model; then it must also tessellate */
            if (st.offset == CM_NO_OFFSET || st.offset < so || st.offset > so + sl + 8)
                fail_msg("%s: %s at offset %u, outside the section [%u, %u)", d->name, cm_err_name(e), st.offset, so,
                         so + sl);
            assert_non_null(st.where);
            continue;
        }
        if (e != d->want)
            fail_msg("%s: %s (%s), expected %s", d->name, cm_err_name(e), st.where ? st.where : "?",
                     cm_err_name(d->want));
        int64_t want_at = d->want_offset == -3 ? (int64_t)now.need_at[d->where] : d->want_offset;
        if (want_at >= 0 && st.offset != (uint32_t)want_at)
            fail_msg("%s: offset %u, expected %lld", d->name, st.offset, (long long)want_at);
        if (d->want == CM_E_CRC && d->want_offset == -2 && !(st.offset >= l->off[3] && st.offset < l->L))
            fail_msg("%s: CRC failure reported at %u, not in the section", d->name, st.offset);
        if (d->want == CM_E_LIMIT) {
            assert_int_equal(st.limit, CM_LIMIT_MAX_FACES);
            assert_int_equal(st.need, CM_MAX_FACES + 1u);
            assert_int_equal(st.have, CM_MAX_FACES);
            /* refused before the body: a decoder fed only the header says the same */
            cm_status st2;
            assert_err(decode_bytes(buf, now.H, now.H, &st2), CM_E_LIMIT);
        }
        assert_non_null(st.where);
    }
}

/* the cases both headers share: cuts, magic, version, CRCs, excess, a need over this build's
   limit (refused from the header alone), sections rewritten with valid CRCs */
static const damage shared_cases[] = {
    {"empty file", CUT, 0, 0, 0, CM_E_TRUNCATED, 0},
    {"cut inside the header", CUT, 10, 0, 0, CM_E_TRUNCATED, 10},
    {"not a .cmz (magic)", SET_U8, CM_HDR_MAGIC + 1, 'X', 0, CM_E_MAGIC, CM_HDR_MAGIC + 1},
    {"7-bit transfer (high bit of the magic lost)", SET_U8, CM_HDR_MAGIC, 0x09, 0, CM_E_MAGIC, CM_HDR_MAGIC},
    {"newer major version", SET_U8, CM_HDR_MAJOR, CM_FMT_VERSION_MAJOR + 1, 1, CM_E_VERSION, CM_HDR_MAJOR},
    {"trailer damaged", FLIP_BYTE, -1, 0, 0, CM_E_CRC, -2},
    {"over this build's face limit", SET_NEED, CM_LIMIT_MAX_FACES, CM_MAX_FACES + 1u, 1, CM_E_LIMIT, -3},
    {"face section rewritten with valid CRCs", GARBLE_SECTION, 3, 0, 1, CM_OK, -1},
    {"edge section rewritten with valid CRCs", GARBLE_SECTION, 1, 0, 1, CM_OK, -1},
    {"vertex section rewritten with valid CRCs", GARBLE_SECTION, 0, 0, 1, CM_OK, -1},
};

static void test_damaged_files(void **state)
{
    (void)state;
    static layout l; /* 16 KB */
    assert_true(layout_of(good, good_len, good[CM_HDR_MAJOR] >= CM_FMT_COMPACT_MAJOR, &l));
    uint32_t H = l.H, L = (uint32_t)good_len;
    const damage fixed_cases[] = {
        {"cut inside the body", CUT, (int64_t)L - 9, 0, 0, CM_E_TRUNCATED, (int64_t)L - 9},
        {"cut before the trailer", CUT, (int64_t)L - 4, 0, 0, CM_E_TRUNCATED, (int64_t)L - 4},
        {"header damaged", FLIP_BYTE, CM_HDR_ORIGIN + 10, 0, 0, CM_E_CRC, (int64_t)H - 4}, /* in the origin's y */
        {"header length absurd", SET_U32, CM_HDR_LENGTH, 0xFFFFFF00u, 0, CM_E_FORMAT, CM_HDR_LENGTH},
        {"file length smaller than the header", SET_U32, CM_HDR_FILE_LENGTH, 8, 1, CM_E_FORMAT, CM_HDR_FILE_LENGTH},
        {"face section damaged", FLIP_BYTE, l.off[3] + 3, 0, 0, CM_E_CRC, -2}, /* its own CRC */
        {"a byte too many", APPEND, 0, 0, 0, CM_E_RANGE, L},
    };
    /* format 4: H a varint at byte 6, the section lengths varints (their offsets follow), no CRC
       per section (the file's, checked first, covers them) */
    uint32_t colr_len_at = 0;
    if (l.compact && !l.stream) {
        uint32_t at = CM_FMT_COMPACT_AT_H;
        uint64_t v;
        for (uint32_t k = 0; k < 1 + 3 + CM_FMT_MIN_NEEDS + CM_SEC_COUNT - 1; k++) /* (no placed copies: 25 needs) */
            assert_true(cm_fmt_get_varint(good, H, &at, &v));
        colr_len_at = at; /* H, flags, N, the needs, S, four lengths: the fifth (COLR) is next */
        assert_true(good[colr_len_at] < 0x7F);
    }
    const damage compact_cases[] = {
        {"cut inside the body", CUT, (int64_t)L - 9, 0, 0, CM_E_TRUNCATED, (int64_t)L - 9},
        {"cut before the trailer", CUT, (int64_t)L - 4, 0, 0, CM_E_TRUNCATED, (int64_t)L - 4},
        {"header damaged", FLIP_BYTE, l.need_at[0], 0, 0, CM_E_CRC, (int64_t)H - 4}, /* a need */
        {"header length below any header", SET_U8, CM_FMT_COMPACT_AT_H, 1, 0, CM_E_FORMAT, CM_FMT_COMPACT_AT_H},
        {"header length past the bound", SET_U32, CM_FMT_COMPACT_AT_H, 0x7FFFFFFFu, 0, CM_E_FORMAT,
         CM_FMT_COMPACT_AT_H},
        {"a section longer than the file", SET_U8, colr_len_at, 0x7F, 1, CM_E_TRUNCATED, L},
        {"face section damaged", FLIP_BYTE, l.off[3] + 3, 0, 0, CM_E_CRC, (int64_t)L - 4}, /* the file's CRC */
        {"a byte too many", APPEND, 0, 0, 0, CM_E_RANGE, L},
    };
    /* format 4.6: no section lengths; the body one stream, which the file's CRC covers */
    const damage stream_cases[] = {
        {"cut inside the body", CUT, (int64_t)L - 9, 0, 0, CM_E_TRUNCATED, (int64_t)L - 9},
        {"cut before the trailer", CUT, (int64_t)L - 4, 0, 0, CM_E_TRUNCATED, (int64_t)L - 4},
        {"header damaged", FLIP_BYTE, l.need_at[0], 0, 0, CM_E_CRC, (int64_t)H - 4},
        {"header length below any header", SET_U8, CM_FMT_COMPACT_AT_H, 1, 0, CM_E_FORMAT, CM_FMT_COMPACT_AT_H},
        {"header length past the bound", SET_U32, CM_FMT_COMPACT_AT_H, 0x7FFFFFFFu, 0, CM_E_FORMAT,
         CM_FMT_COMPACT_AT_H},
        {"body damaged", FLIP_BYTE, (int64_t)H + 3, 0, 0, CM_E_CRC, (int64_t)L - 4}, /* the file's CRC */
        {"a byte too many", APPEND, 0, 0, 0, CM_E_RANGE, L},
    };
    uint8_t *buf = malloc(good_len + 256); /* room for a header that grows (4.6: a need changed moves the predictions of others) */
    assert_non_null(buf);
    size_t c = 0;
    for (size_t i = 0; i < sizeof shared_cases / sizeof shared_cases[0]; i++)
        check_damage(&shared_cases[i], buf, c++, &l);
    if (l.stream)
        for (size_t i = 0; i < sizeof stream_cases / sizeof stream_cases[0]; i++)
            check_damage(&stream_cases[i], buf, c++, &l);
    else if (l.compact)
        for (size_t i = 0; i < sizeof compact_cases / sizeof compact_cases[0]; i++)
            check_damage(&compact_cases[i], buf, c++, &l);
    else
        for (size_t i = 0; i < sizeof fixed_cases / sizeof fixed_cases[0]; i++)
            check_damage(&fixed_cases[i], buf, c++, &l);
    free(buf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_box_hole_144),
        cmocka_unit_test(test_box_hole_186),
        cmocka_unit_test(test_inside_out),
        cmocka_unit_test(test_flat_disc_plane),
        cmocka_unit_test(test_default_tolerance_model_level),
        cmocka_unit_test(test_mesh_deviation_measured),
        cmocka_unit_test(test_profile_coarsens_tessellation),
        cmocka_unit_test(test_half_cylinder),
        cmocka_unit_test(test_bicubic_net),
        cmocka_unit_test(test_refine_skips_passed_pieces),
        cmocka_unit_test(test_kept_strips),
        cmocka_unit_test(test_patch_scale_410),
        cmocka_unit_test(test_conic_cubic_414),
        cmocka_unit_test_setup_teardown(test_damaged_files, setup_good, teardown_good),
        cmocka_unit_test_setup_teardown(test_damaged_files, setup_good45, teardown_good),
        cmocka_unit_test_setup_teardown(test_damaged_files, setup_good3, teardown_good),
    };
    return cmocka_run_group_tests_name("roundtrip", tests, NULL, NULL);
}
