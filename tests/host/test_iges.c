/*
 * test_iges.c - IGES import end to end on synthetic files with exact
 * expectations (counts, topology, G1 flags, sample points on the true
 * geometry), and the malformed-input cases with their messages.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "igs_writer.h"
#include "model_load.h"

/* write the writer's text (optionally edited) to a temporary file */
static char *temp_path(void)
{
    static char path[64];
    snprintf(path, sizeof path, "/tmp/cmz_test_%d_XXXXXX", (int)getpid());
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    return path;
}

static cm_err load(igw *w, loaded_model *lm)
{
    char *p = temp_path();
    assert_int_equal(igw_save(w, p), 0);
    cm_status st;
    cm_status_init(&st);
    cm_err e = model_load(p, lm, NULL, NULL, &st);
    unlink(p);
    return e;
}

static int count_kind(const cmesh *cm, cmesh_kind k)
{
    int n = 0;
    for (int e = 0; e < cm->nedges; e++)
        n += cm->edges[e].kind == k;
    return n;
}

static int count_g1(const cmesh *cm)
{
    int n = 0;
    for (int e = 0; e < cm->nedges; e++)
        n += cm->edges[e].g1;
    return n;
}

/* sample every face and check each point with `on_face(face_surface_type, point)` */
typedef int (*point_check)(const loaded_model *lm, int face, cm_vec3 p, double tol);

static void check_samples(const loaded_model *lm, point_check ok, int per_face)
{
    cm_vec2 uv[64];
    double tol = 1e-9 * brep_diag(&lm->brep);
    for (int f = 0; f < lm->brep.nfaces; f++) {
        assert_non_null(lm->fds[f].uv);
        int n = face_domain_sample(&lm->fds[f], per_face, 7u + (uint32_t)f, uv);
        if (n < per_face / 2)
            fail_msg("face %d got only %d of %d sample points", f, n, per_face);
        for (int k = 0; k < n; k++) {
            cm_vec3 P;
            assert_ok(face_domain_eval(&lm->brep, &lm->fds[f], uv[k].x, uv[k].y, &P, NULL, NULL));
            if (!ok(lm, f, P, tol))
                fail_msg("face %d (surface %d): sample (%.17g %.17g %.17g) is not on the face", f,
                         lm->brep.faces[f].surf_type, P.x, P.y, P.z);
        }
    }
}

/* ---- box with a hole: a = 40, b = 30, c = 10, r = 6 ---- */
#define BA 40.0
#define BB 30.0
#define BC 10.0
#define BR 6.0

static int on_box_with_hole(const loaded_model *lm, int face, cm_vec3 p, double tol)
{
    (void)face;
    (void)lm;
    double rho = hypot(p.x - BA / 2, p.y - BB / 2);
    int in_box = p.x > -tol && p.x < BA + tol && p.y > -tol && p.y < BB + tol && p.z > -tol && p.z < BC + tol;
    if (!in_box)
        return 0;
    int on_plane = fabs(p.z) <= tol || fabs(p.z - BC) <= tol || fabs(p.x) <= tol || fabs(p.x - BA) <= tol ||
                   fabs(p.y) <= tol || fabs(p.y - BB) <= tol;
    if (fabs(rho - BR) <= tol)
        return 1;                   /* on the hole */
    return on_plane && rho > BR; /* on a box face, and not inside the hole */
}

static void check_box_topology(const loaded_model *lm)
{
    const cmesh *cm = &lm->mesh;
    assert_int_equal(lm->brep.nfaces, 7);
    assert_int_equal(lm->brep.nloops, 9);
    assert_int_equal(cm->nverts, 10);      /* 8 corners + the seam's two ends */
    assert_int_equal(cm->nedges, 15);      /* 12 box edges, 2 circles, 1 seam */
    assert_int_equal(count_kind(cm, CMESH_SHARED), 14);
    assert_int_equal(count_kind(cm, CMESH_SEAM), 1);
    assert_int_equal(count_kind(cm, CMESH_FREE), 0);
    assert_int_equal(count_kind(cm, CMESH_NONMANIFOLD), 0);
    assert_int_equal(count_g1(cm), 1);     /* only the seam is smooth: every other edge is a 90 deg crease */
    int comp[7];
    assert_int_equal(cmesh_components(cm, comp), 1);
    assert_int_equal(lm->domains_failed, 0);
    assert_near(brep_diag(&lm->brep), sqrt(BA * BA + BB * BB + BC * BC), 1e-9);
}

static void test_box_with_hole_144(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_box_with_hole_144(&w, BA, BB, BC, BR);
    loaded_model lm;
    assert_ok(load(&w, &lm));
    assert_int_equal(lm.stats.faces_144, 7);
    check_box_topology(&lm);
    assert_int_equal(lm.iges.nwarn, 0);
    check_samples(&lm, on_box_with_hole, 30);
    model_free(&lm);
    igw_free(&w);
}

static void test_box_with_hole_186(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_box_with_hole_186(&w, BA, BB, BC, BR);
    loaded_model lm;
    assert_ok(load(&w, &lm));
    assert_int_equal(lm.stats.faces_510, 7);
    check_box_topology(&lm);
    /* the B-rep's shell orientation makes every shared edge run both ways */
    assert_int_equal(lm.mesh.inconsistent, 0);
    check_samples(&lm, on_box_with_hole, 30);
    model_free(&lm);
    igw_free(&w);
}

static int on_half_cylinder(const loaded_model *lm, int face, cm_vec3 p, double tol)
{
    (void)lm;
    (void)face;
    return fabs(hypot(p.x, p.y) - 5.0) <= tol && p.y >= -tol && p.z >= -tol && p.z <= 12.0 + tol;
}

static void test_half_cylinder_120(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_half_cylinder_120(&w, 5.0, 12.0);
    loaded_model lm;
    assert_ok(load(&w, &lm));
    assert_int_equal(lm.brep.nfaces, 1);
    assert_int_equal(lm.stats.faces_untrimmed, 1);
    assert_int_equal(lm.mesh.nedges, 4);
    assert_int_equal(lm.mesh.nverts, 4);
    assert_int_equal(count_kind(&lm.mesh, CMESH_FREE), 4);
    check_samples(&lm, on_half_cylinder, 40);
    model_free(&lm);
    igw_free(&w);
}

static int on_mirrored_half_cylinder(const loaded_model *lm, int face, cm_vec3 p, double tol)
{
    (void)lm;
    (void)face;
    return fabs(hypot(p.x, p.y) - 5.0) <= tol && p.y <= tol && p.z >= -tol && p.z <= 12.0 + tol;
}

/* a 120 under a mirroring transformation: revolved in its own frame, then mirrored (as OCCT reads it) */
static void test_half_cylinder_120_mirrored(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_half_cylinder_120_mirrored(&w, 5.0, 12.0);
    loaded_model lm;
    assert_ok(load(&w, &lm));
    assert_int_equal(lm.brep.nfaces, 1);
    check_samples(&lm, on_mirrored_half_cylinder, 40);
    model_free(&lm);
    igw_free(&w);
}

static int on_square(const loaded_model *lm, int face, cm_vec3 p, double tol)
{
    (void)lm;
    (void)face;
    return fabs(p.z) <= tol && p.x >= -tol && p.x <= 10 + tol && p.y >= -tol && p.y <= 10 + tol;
}

/* a trimming loop whose curves are listed out of order, some backwards, is chained by its end points */
static void test_scrambled_loop(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_square_scrambled_144(&w, 10.0);
    loaded_model lm;
    assert_ok(load(&w, &lm));
    assert_int_equal(lm.brep.nfaces, 1);
    assert_int_equal(lm.mesh.nverts, 4); /* no joint forced between curves that do not meet */
    assert_int_equal(lm.mesh.nedges, 4);
    assert_int_equal(lm.mesh.nforced, 0);
    assert_int_equal(count_kind(&lm.mesh, CMESH_FREE), 4);
    assert_true(lm.iges.nwarn >= 1); /* and says so */
    check_samples(&lm, on_square, 30);
    model_free(&lm);
    igw_free(&w);
}

static int on_bicubic(const loaded_model *lm, int face, cm_vec3 p, double tol)
{
    (void)lm;
    (void)face;
    /* x = 3u, y = 3v exactly (control x = i, y = j): z must be the Bezier z at (x/3, y/3) */
    double u = p.x / 3, v = p.y / 3, Bu[4], Bv[4], z = 0;
    if (u < -tol || u > 1 + tol || v < -tol || v > 1 + tol)
        return 0;
    for (int i = 0; i < 4; i++) {
        Bu[i] = (i == 0 ? 1 : i == 3 ? 1 : 3) * pow(u, i) * pow(1 - u, 3 - i);
        Bv[i] = (i == 0 ? 1 : i == 3 ? 1 : 3) * pow(v, i) * pow(1 - v, 3 - i);
    }
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            z += Bu[i] * Bv[j] * igw_bicubic_z[i][j];
    return fabs(z - p.z) <= 1e-12;
}

static void test_bicubic_128(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_bicubic_128(&w);
    loaded_model lm;
    assert_ok(load(&w, &lm));
    assert_int_equal(lm.brep.nfaces, 1);
    assert_int_equal(lm.stats.faces_untrimmed, 1);
    assert_int_equal(lm.mesh.nedges, 4);
    assert_int_equal(count_kind(&lm.mesh, CMESH_FREE), 4);
    check_samples(&lm, on_bicubic, 40);
    model_free(&lm);
    igw_free(&w);
}

/* The same box in inches: every coordinate is converted to millimetres. */
static void test_units_inch(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    w.units = 1;
    igw_box_with_hole_144(&w, 1.0, 1.0, 1.0, 0.25);
    loaded_model lm;
    assert_ok(load(&w, &lm));
    assert_near(lm.iges.to_mm, 25.4, 0);
    assert_near(brep_diag(&lm.brep), 25.4 * sqrt(3.0), 1e-9);
    model_free(&lm);
    igw_free(&w);
}

/* ---- malformed input: a clear error or warning, never a crash ---- */

static cm_err parse_text(const char *text, size_t len, iges_file *f)
{
    memset(f, 0, sizeof *f);
    cm_status st;
    cm_status_init(&st);
    return iges_parse(text, len, f, &st);
}

static char *box_text(size_t *len)
{
    igw w;
    igw_init(&w);
    igw_box_with_hole_144(&w, BA, BB, BC, BR);
    char *t = igw_text(&w, len);
    igw_free(&w);
    return t;
}

static void test_truncated(void **state)
{
    (void)state;
    size_t len;
    char *t = box_text(&len);
    /* cut in the middle of the Directory section, mid-line */
    char *d = strstr(t, "D      7\n");
    assert_non_null(d);
    size_t cut = (size_t)(d - t) - 40;
    iges_file f;
    assert_err(parse_text(t, cut, &f), CM_E_IGES);
    if (!strstr(f.err, "line ") || !strstr(f.err, "columns"))
        fail_msg("unclear message: %s", f.err);
    iges_free(&f);
    /* cut at a line boundary inside the Parameter section: entities point past its end */
    char *p = strstr(t, "P     20\n");
    assert_non_null(p);
    cut = (size_t)(p - t) + 9;
    assert_err(parse_text(t, cut, &f), CM_E_IGES);
    if (!strstr(f.err, "outside the 20-line Parameter section"))
        fail_msg("unclear message: %s", f.err);
    iges_free(&f);
    /* one Directory line removed: an odd number of D lines */
    char *copy = malloc(len);
    size_t dl = (size_t)(d - t) - 72;
    memcpy(copy, t, dl);
    memcpy(copy + dl, t + dl + 81, len - dl - 81);
    assert_err(parse_text(copy, len - 81, &f), CM_E_IGES);
    if (!strstr(f.err, "odd number of Directory lines"))
        fail_msg("unclear message: %s", f.err);
    iges_free(&f);
    free(copy);
    free(t);
}

static void test_terminate_counts_warn(void **state)
{
    (void)state;
    size_t len;
    char *t = box_text(&len);
    char *term = strstr(t, "S      1G");
    assert_non_null(term);
    term[7] = '9'; /* S count 9 instead of 1 */
    iges_file f;
    assert_ok(parse_text(t, len, &f));
    assert_true(f.nwarn >= 1);
    assert_non_null(strstr(f.warn[0].msg, "Terminate section counts 9 S lines, the file has 1"));
    iges_free(&f);
    free(t);
}

static void test_bad_pointer_skips_face(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    igw_box_with_hole_144(&w, BA, BB, BC, BR);
    int bad = igw_add(&w, 144, 0, "%d,1,0,%d", 9999, 9997);
    (void)bad;
    loaded_model lm;
    assert_ok(load(&w, &lm));
    assert_int_equal(lm.brep.nfaces, 7);
    assert_int_equal(lm.brep.faces_failed, 1);
    int found = 0;
    for (int i = 0; i < lm.iges.nwarn; i++)
        found |= strstr(lm.iges.warn[i].msg, "points to DE 9999, which is not an entity") != NULL;
    assert_true(found);
    model_free(&lm);
    igw_free(&w);
}

static void test_odd_metadata_is_fine(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    snprintf(w.exporter, sizeof w.exporter, "\xcf\xf0\xee\xe3\xf0\xe0\xec\xec\xe0 CP1251"); /* Cyrillic bytes */
    igw_box_with_hole_144(&w, BA, BB, BC, BR);
    size_t len;
    char *t = igw_text(&w, &len);
    char *date = strstr(t, "15H20261122.120000");
    assert_non_null(date);
    memcpy(date, "15H-17770108.0000", 17); /* a date of the kind some exporters write */
    iges_file f;
    assert_ok(parse_text(t, len, &f));
    assert_int_equal(f.nents, w.n);
    assert_non_null(strstr(f.g.system_id, "CP1251"));
    iges_free(&f);
    free(t);
    igw_free(&w);
}

static void test_unsupported_forms(void **state)
{
    (void)state;
    size_t len;
    char *t = box_text(&len);
    iges_file f;
    t[72] = 'C'; /* compressed ASCII marker on the first line */
    assert_err(parse_text(t, len, &f), CM_E_IGES);
    assert_non_null(strstr(f.err, "compressed ASCII IGES is not supported"));
    iges_free(&f);
    t[72] = 'S';
    /* sections out of order: the last Directory line marked as Global */
    char *p = strstr(t, "P      1\n");
    assert_non_null(p);
    p[-81] = 'G';
    assert_err(parse_text(t, len, &f), CM_E_IGES);
    assert_non_null(strstr(f.err, "out of order"));
    iges_free(&f);
    free(t);
    assert_err(parse_text("", 0, &f), CM_E_IGES);
    assert_non_null(strstr(f.err, "empty file"));
    iges_free(&f);
    const char junk[] = "\x7f" "ELF\x02\x01\x01\0\0\0\0\0";
    assert_err(parse_text(junk, sizeof junk, &f), CM_E_IGES);
    iges_free(&f);
}

static void test_bad_parameter_skips_entity(void **state)
{
    (void)state;
    size_t len;
    char *t = box_text(&len);
    /* corrupt the first number of the first 110 line entity's parameters */
    char *p = strstr(t, "110,");
    assert_non_null(p);
    p[4] = 'x';
    iges_file f;
    assert_ok(parse_text(t, len, &f));
    int found = 0;
    for (int i = 0; i < f.nwarn; i++)
        found |= strstr(f.warn[i].msg, "is not a number") != NULL && f.warn[i].line > 0;
    assert_true(found);
    iges_free(&f);
    free(t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_box_with_hole_144),
        cmocka_unit_test(test_box_with_hole_186),
        cmocka_unit_test(test_half_cylinder_120),
        cmocka_unit_test(test_half_cylinder_120_mirrored),
        cmocka_unit_test(test_scrambled_loop),
        cmocka_unit_test(test_bicubic_128),
        cmocka_unit_test(test_units_inch),
        cmocka_unit_test(test_truncated),
        cmocka_unit_test(test_terminate_counts_warn),
        cmocka_unit_test(test_bad_pointer_skips_face),
        cmocka_unit_test(test_odd_metadata_is_fine),
        cmocka_unit_test(test_unsupported_forms),
        cmocka_unit_test(test_bad_parameter_skips_entity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
