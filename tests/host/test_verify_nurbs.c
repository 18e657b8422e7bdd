/*
 * test_verify_nurbs.c - the encoder's measurements (verify.c) of a face
 * rebuilt as a NURBS surface (cm_rebuilt.repr == CM_REPR_NURBS, what NFILL
 * gives: a B-spline over a rectangle that contains the face).  Spec §17 T12,
 * the error evaluator's self test: a B-spline face against itself, and
 * against itself moved 0.5 % of its size along its normal; the deep copy
 * face_surface_set keeps of a surface whose arrays the next rebuild reuses;
 * and the §13 normal of a NURBS face (sign * unit(Su x Sv)).
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <stdio.h>
#include <stdlib.h>

#include "cm/cm_bspline.h"
#include "cm/cm_decode.h"
#include "cm/cm_rebuild.h"
#include "encode/encode.h"
#include "encode/verify.h"
#include "igs_writer.h"
#include "model_load.h"

static cm_decoder dec;
static cm_rebuild_ws rbws;

#define SQ 10.0  /* the square's side, the triangle's legs */
#define SQZ 1.0  /* the square's height */
#define CR 10.0  /* the split half cylinder: radius, length */
#define CH 20.0
#define OFF 0.005 /* spec T12: the translation, a fraction of bbox_F */

/* the model w holds, loaded (w freed), encoded (every face kept or a plane: nothing else tried) and
   decoded into dec; it must have `faces` faces */
static void load_encode_decode(igw *w, const char *name, int faces, loaded_model *lm)
{
    cm_status st;
    assert_ok(igw_load(w, name, lm, &st));
    assert_int_equal(lm->mesh.nfaces, faces);
    encode_opts o;
    encode_opts_default(&o);
    o.gregory = o.gregory_exact = o.gregory_fit = o.nfill = 0;
    encode_result r;
    memset(&r, 0, sizeof r);
    assert_ok(encode_model(lm, &o, &r, &st));
    cm_dec_init(&dec);
    assert_ok(cm_dec_feed(&dec, r.bytes, r.len, &st));
    assert_ok(cm_dec_finish(&dec, &st));
    encode_result_free(&r);
    assert_int_equal((int)dec.model.nfaces, faces);
}

/* the face's own source surface, as the import holds it */
static const cm_surf *source_surf(const loaded_model *lm, int f)
{
    const face_domain *fd = &lm->fds[lm->mesh.faces[f].brep_face];
    assert_non_null(fd->uv);
    return &fd->ps.s;
}

/* face f rebuilt by the decoder (for bbox_F and the record), then made a NURBS face on s */
static cm_rebuilt nurbs_rebuilt(const cm_model *m, int f, const cm_surf *s, double sign)
{
    cm_rebuilt rb;
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_rebuild_face(m, (uint32_t)f, &rb, &rbws, &st));
    rb.repr = CM_REPR_NURBS;
    rb.surf = *s;
    rb.sign = sign;
    rb.greg = NULL;
    return rb;
}

/* storage of a surface made or copied by the tests */
typedef struct surf_buf {
    cm_surf s;
    cm_vec3 ctrl[64];
    double U[32], V[32], w[64];
} surf_buf;

/* b: a copy of s, its control points moved by t */
static void surf_moved(surf_buf *b, const cm_surf *s, cm_vec3 t)
{
    int n = s->nu * s->nv;
    assert_true(n <= 64 && s->nu + s->p + 1 <= 32 && s->nv + s->q + 1 <= 32);
    for (int i = 0; i < n; i++) {
        b->ctrl[i] = cm_add(s->ctrl[i], t);
        b->w[i] = s->w ? s->w[i] : 1.0;
    }
    memcpy(b->U, s->U, (size_t)(s->nu + s->p + 1) * sizeof *b->U);
    memcpy(b->V, s->V, (size_t)(s->nv + s->q + 1) * sizeof *b->V);
    b->s = *s;
    b->s.ctrl = b->ctrl;
    b->s.U = b->U;
    b->s.V = b->V;
    b->s.w = s->w ? b->w : NULL;
}

/* S (d = 0) or the unit normal Su x Sv (d = 1) of s at the fraction t of its domain in u and v */
static cm_vec3 surf_at(const cm_surf *s, double t, int d)
{
    cm_vec3 S[CM_MAX_DERS + 1][CM_MAX_DERS + 1];
    cm_status st;
    cm_status_init(&st);
    double u = s->U[s->p] + t * (s->U[s->nu] - s->U[s->p]), v = s->V[s->q] + t * (s->V[s->nv] - s->V[s->q]);
    assert_ok(cm_surf_eval(s, u, v, 1, S, &st));
    return d ? cm_unit(cm_cross(S[1][0], S[0][1])) : S[0][0];
}

static cm_vec3 mid_normal(const cm_surf *s) { return surf_at(s, 0.5, 1); }

/*
 * An exact bicubic copy of the plane z = SQZ + dz over a rectangle that contains the square face
 * (as NFILL's does): [-0.1, 1.1] SQ on both axes, clamped uniform knots, 6 x 6 control points at
 * their Greville abscissae (a B-spline reproduces linear data exactly).
 */
static void plane_bicubic(surf_buf *b, double dz)
{
    cm_status st;
    cm_status_init(&st);
    double xi[6];
    assert_ok(cm_knots_uniform(6, 3, b->U, &st));
    assert_ok(cm_knots_uniform(6, 3, b->V, &st));
    assert_ok(cm_greville(6, 3, b->U, xi, &st));
    for (int i = 0; i < 6; i++)
        for (int j = 0; j < 6; j++)
            b->ctrl[i * 6 + j] = cm_v3(SQ * (-0.1 + 1.2 * xi[i]), SQ * (-0.1 + 1.2 * xi[j]), SQZ + dz);
    cm_surf s = {3, 3, 6, 6, b->U, b->V, b->ctrl, NULL};
    b->s = s;
}

/* verify_face measuring every point; the numbers of points checked too */
static face_error measure(const loaded_model *lm, const cm_model *m, int f, const cm_rebuilt *rb, int edges)
{
    face_error fe;
    assert_true(verify_face(lm, m, f, rb, HUGE_VAL, &fe));
    assert_true(fe.complete);
    assert_true(fe.grid_points > 0);
    assert_int_equal(fe.boundary_points, 21 * edges);
    assert_near(fe.bbox, rb->bbox, 0.0);
    assert_true(fe.back == 0.0); /* no patches-to-source pass for a NURBS surface (it extends past the face) */
    return fe;
}

/* T12 on a curved B-spline face: the biquartic bump over a square, trimmed to a triangle (the surface
 * contains the face), measured against its own surface */
static void test_t12_curved_face_against_itself(void **state)
{
    (void)state;
    loaded_model lm;
    igw w;
    igw_init(&w);
    igw_tri_bump_144(&w, SQ, 2.0);
    load_encode_decode(&w, "tri-bump", 1, &lm);
    const cm_model *m = &dec.model;
    const cm_surf *src = source_surf(&lm, 0);
    assert_int_equal(src->p, 4);
    cm_rebuilt rb = nurbs_rebuilt(m, 0, src, 1.0);
    assert_near(rb.bbox, SQ * sqrt(2.0), 1e-12 * SQ);
    face_error fe = measure(&lm, m, 0, &rb, 3);
    if (!(fe.max <= 1e-10 * rb.bbox))
        fail_msg("T12: the face against its own surface: max %.3g mm > 1e-10 bbox", fe.max);
    /* and lifted 0.5 % of its size: every point is measured that far (the bump is not a plane: its
       feet move, the distances stay within a hair of the lift) */
    surf_buf *b = malloc(sizeof *b);
    assert_non_null(b);
    surf_moved(b, src, cm_v3(0, 0, OFF * rb.bbox));
    rb.surf = b->s;
    fe = measure(&lm, m, 0, &rb, 3);
    if (!(fe.ratio > 0.5 * OFF && fe.ratio <= OFF * (1 + 1e-9)))
        fail_msg("the bump lifted %.3g bbox: ratio %.9g", OFF, fe.ratio);
    free(b);
    model_free(&lm);
}

/* T12 on a planar B-spline face (a bilinear 128 square): against itself, then against itself moved
 * 0.5 % of bbox_F along its normal: Ratio = 0.5 % +- 1e-9; the same with an exact bicubic copy of
 * the plane over a larger rectangle (NFILL's shape), and with the face normal flipped (sign -1) */
static void test_t12_planar_face_translated(void **state)
{
    (void)state;
    loaded_model lm;
    igw w;
    igw_init(&w);
    igw_square_144(&w, SQ, SQZ, 0);
    load_encode_decode(&w, "square", 1, &lm);
    const cm_model *m = &dec.model;
    const cm_surf *src = source_surf(&lm, 0);
    cm_rebuilt rb = nurbs_rebuilt(m, 0, src, 1.0);
    face_error fe = measure(&lm, m, 0, &rb, 4);
    if (!(fe.max <= 1e-10 * rb.bbox))
        fail_msg("T12: the square against its own surface: max %.3g mm", fe.max);
    surf_buf *b = malloc(sizeof *b);
    assert_non_null(b);
    cm_vec3 n = mid_normal(src);
    assert_near(fabs(n.z), 1.0, 1e-15);
    for (int flip = 0; flip < 2; flip++) {
        surf_moved(b, src, cm_scale(n, (flip ? -OFF : OFF) * rb.bbox));
        rb = nurbs_rebuilt(m, 0, &b->s, flip ? -1.0 : 1.0);
        fe = measure(&lm, m, 0, &rb, 4);
        if (!(fabs(fe.ratio - OFF) <= 1e-9))
            fail_msg("T12: moved %.3g bbox along the normal: ratio %.12g", OFF, fe.ratio);
        assert_near(fe.avg, OFF * rb.bbox, 1e-9 * rb.bbox);
    }
    /* a bicubic over a rectangle 20 % larger than the face, as NFILL builds: the same numbers */
    plane_bicubic(b, 0.0);
    rb = nurbs_rebuilt(m, 0, &b->s, 1.0);
    fe = measure(&lm, m, 0, &rb, 4);
    if (!(fe.max <= 1e-10 * rb.bbox))
        fail_msg("T12: the square against a bicubic copy of its plane: max %.3g mm", fe.max);
    plane_bicubic(b, OFF * rb.bbox);
    rb = nurbs_rebuilt(m, 0, &b->s, 1.0);
    fe = measure(&lm, m, 0, &rb, 4);
    if (!(fabs(fe.ratio - OFF) <= 1e-9))
        fail_msg("T12: the bicubic plane moved %.3g bbox: ratio %.12g", OFF, fe.ratio);
    /* stopping at the first point at or over the tolerance: the face fails, incomplete */
    assert_true(verify_face(&lm, m, 0, &rb, 0.5 * OFF * rb.bbox, &fe));
    assert_false(fe.complete);
    assert_int_equal(fe.grid_points + fe.boundary_points, 0); /* the first grid point already fails */
    assert_near(fe.max, OFF * rb.bbox, 1e-9 * rb.bbox);
    free(b);
    model_free(&lm);
}

/* the edge both faces of m use */
static uint32_t shared_edge(const cm_model *m)
{
    int shared = -1;
    for (uint32_t e = 0; e < m->nedges; e++)
        if (m->edge_face[e][0] >= 0 && m->edge_face[e][1] >= 0 && m->edge_face[e][0] != m->edge_face[e][1])
            shared = (int)e;
    assert_true(shared >= 0);
    return (uint32_t)shared;
}

/*
 * A plane through the split cylinder's shared line (0, CR, z), turned by `deg` about it from the
 * cylinder's tangent plane there: u along t = (cos, -sin, 0), v along z, so that
 * Su x Sv = t x ez = -(sin, cos, 0).
 */
static void tilted_plane(surf_buf *b, double deg)
{
    double a = deg * M_PI / 180.0;
    cm_vec3 t = cm_v3(cos(a), -sin(a), 0), o = cm_v3(0, CR, 0);
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++)
            b->ctrl[i * 2 + j] = cm_add(o, cm_add(cm_scale(t, i ? CR : -CR), cm_v3(0, 0, j ? CH + 1.0 : -1.0)));
    static const double k[4] = {0, 0, 1, 1};
    memcpy(b->U, k, sizeof k);
    memcpy(b->V, k, sizeof k);
    cm_surf s = {1, 1, 2, 2, b->U, b->V, b->ctrl, NULL};
    b->s = s;
}

/* b's arrays overwritten with another surface and nonsense: what a reused workspace does */
static void scribble(surf_buf *b)
{
    tilted_plane(b, 40.0);
    for (int i = 0; i < 32; i++)
        b->U[i] = b->V[i] = (double)NAN;
    for (int i = 0; i < 64; i++) {
        b->ctrl[i] = cm_scale(b->ctrl[i], 3.0);
        b->w[i] = 1.0;
    }
}

/*
 * face_surface_set keeps a deep copy (control points, knots, weights, sign) that outlives the
 * surface it was given; §13 takes a NURBS face's normal from that copy at the edge point's foot,
 * sign * unit(Su x Sv): a plane turned 10 degrees about the shared line of the split cylinder gives
 * |nF.nG| = cos 10 degrees and is the face to blame; its own (rational) surface gives 1.
 */
static void test_g1_normal_and_deep_copy(void **state)
{
    (void)state;
    loaded_model lm;
    igw w;
    igw_init(&w);
    igw_split_half_cylinder_144(&w, CR, CH);
    load_encode_decode(&w, "split-cylinder", 2, &lm);
    const cm_model *m = &dec.model;
    uint32_t e = shared_edge(m);
    face_surface fs[2];
    memset(fs, 0, sizeof fs);
    assert_true(verify_g1_edge(&lm, m, e, fs, NULL) >= 1.0 - 1e-9); /* both kept: the cylinder */
    surf_buf *b = calloc(1, sizeof *b);
    assert_non_null(b);
    const double c10 = cos(10.0 * M_PI / 180.0);
    for (int side = 0; side < 2; side++) {
        int f = m->edge_face[e][side];
        /* the turned plane: copied, the original overwritten, the copy still measured */
        tilted_plane(b, 10.0);
        cm_rebuilt rb = nurbs_rebuilt(m, f, &b->s, -1.0);
        assert_true(face_surface_set(&fs[f], &rb));
        assert_true(fs[f].rebuilt && fs[f].repr == CM_REPR_NURBS && fs[f].sign == -1.0);
        assert_true(fs[f].nurbs.ctrl != b->ctrl && fs[f].nurbs.U != b->U && fs[f].nurbs.V != b->V);
        assert_null(fs[f].nurbs.w);
        scribble(b);
        int worse = -1;
        assert_near(verify_g1_edge(&lm, m, e, fs, &worse), c10, 1e-9);
        assert_int_equal(worse, side);
        /* the normal itself: sign * unit(Su x Sv) = -(-(sin, cos, 0)) */
        cm_vec3 P = cm_v3(0, CR, 0.5 * CH), nrm;
        assert_true(verify_face_normal(&lm, f, fs, P, &nrm));
        assert_vec_near(nrm, cm_v3(sin(10.0 * M_PI / 180.0), c10, 0), 1e-12);
        fs[f].sign = 1.0;
        assert_true(verify_face_normal(&lm, f, fs, P, &nrm));
        assert_vec_near(nrm, cm_v3(-sin(10.0 * M_PI / 180.0), -c10, 0), 1e-12);
        /* its own surface (rational: the weights are copied too) replaces the plane, then the
           original arrays are overwritten */
        const cm_surf *src = source_surf(&lm, f);
        assert_non_null(src->w);
        surf_moved(b, src, cm_v3(0, 0, 0));
        rb = nurbs_rebuilt(m, f, &b->s, 1.0);
        assert_true(face_surface_set(&fs[f], &rb));
        assert_true(fs[f].nurbs.w != NULL && fs[f].nurbs.w != b->w);
        scribble(b);
        double c = verify_g1_edge(&lm, m, e, fs, NULL);
        if (!(c >= 1.0 - 1e-9))
            fail_msg("face %d on a copy of its own surface: |nF.nG| = %.12g", f, c);
        /* its normal is the cylinder's: radial at the shared line, and inside the face, where the
           weights shape it (at the arc's ends and its middle they do not), to the side sign says */
        assert_true(verify_face_normal(&lm, f, fs, P, &nrm));
        assert_near(fabs(nrm.y), 1.0, 1e-9);
        cm_vec3 in, Q = surf_at(src, 0.3, 0);
        assert_true(verify_face_normal(&lm, f, fs, Q, &in));
        assert_near(fabs(cm_dot(in, cm_unit(cm_v3(Q.x, Q.y, 0)))), 1.0, 1e-12);
        cm_vec3 flipped;
        fs[f].sign = -fs[f].sign;
        assert_true(verify_face_normal(&lm, f, fs, P, &flipped));
        assert_vec_near(flipped, cm_scale(nrm, -1.0), 1e-15);
        face_surface_free(&fs[f]);
        assert_false(fs[f].rebuilt);
        assert_null(fs[f].nurbs_ctrl);
        assert_null(fs[f].nurbs_num);
        assert_true(verify_g1_edge(&lm, m, e, fs, NULL) >= 1.0 - 1e-9);
    }
    /* both faces NURBS at once: the two turned planes (each 10 degrees off, to opposite sides) */
    for (int side = 0; side < 2; side++) {
        tilted_plane(b, side ? -10.0 : 10.0);
        cm_rebuilt rb = nurbs_rebuilt(m, m->edge_face[e][side], &b->s, 1.0);
        assert_true(face_surface_set(&fs[m->edge_face[e][side]], &rb));
    }
    scribble(b);
    assert_near(verify_g1_edge(&lm, m, e, fs, NULL), cos(20.0 * M_PI / 180.0), 1e-9);
    for (int f = 0; f < 2; f++)
        face_surface_free(&fs[f]);
    free(b);
    model_free(&lm);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_t12_curved_face_against_itself),
        cmocka_unit_test(test_t12_planar_face_translated),
        cmocka_unit_test(test_g1_normal_and_deep_copy),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
