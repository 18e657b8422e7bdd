/*
 * test_egreg.c - the Gregory patch over exact boundaries (cm_egreg.h) on its
 * own: the properties its formula promises, checked on a warped patch whose
 * sides are cubics and whose cross derivatives are given explicitly and
 * agree at the corners (the case Gregory's construction makes exact):
 *   - the four boundary curves are interpolated;
 *   - the cross derivative along each side is the given one, all along it
 *     (the compatibility-corrected twists at work);
 *   - S_u and S_v are the true partial derivatives (central differences);
 *   - a surface linear in v between two curved sides is reproduced;
 *   - the turning basis (format 2.6) along a half circle: square to the edge
 *     and of unit length where the linear basis vanishes, exact on a dome's
 *     rim, the same line from either face, its derivative the true one, and
 *     chosen only where the bases turn (cm_egreg_choose_turn).
 */
#include "test_util.h"

#include "cm/cm_egreg.h"

/* the loop: side 0 v=0 (+u), side 1 u=1 (+v), side 2 v=1 (-u), side 3 u=0 (-v), as cubics */
static const cm_vec3 C00 = {0, 0, 0}, C10 = {10, 0, 1}, C11 = {11, 9, 3}, C01 = {-1, 10, 2};

static cm_cubic cubic_between(cm_vec3 a, cm_vec3 b, cm_vec3 bend)
{
    cm_vec3 d = cm_sub(b, a);
    cm_cubic c = {{a, cm_add(cm_axpy(a, 1.0 / 3.0, d), bend), cm_sub(cm_axpy(b, -1.0 / 3.0, d), bend), b}};
    return c;
}

/* cubic derivative (per unit s) at the ends */
static cm_vec3 d_start(const cm_cubic *c) { return cm_scale(cm_sub(c->c[1], c->c[0]), 3.0); }
static cm_vec3 d_end(const cm_cubic *c) { return cm_scale(cm_sub(c->c[3], c->c[2]), 3.0); }

/*
 * A patch with cubic sides and explicit (Bezier) cross derivatives X_k into the patch, chosen to
 * agree with the neighbouring sides at the corners: X_k(0) = -B_{k-1}'(1), X_k(1) = B_{k+1}'(0),
 * and free inner coefficients (a bulge of the cross derivative).
 */
static void warped_patch(cm_egreg *g, double bulge)
{
    memset(g, 0, sizeof *g);
    cm_cubic s[4] = {cubic_between(C00, C10, cm_v3(0, -1, 2)), cubic_between(C10, C11, cm_v3(1, 0, -1)),
                     cubic_between(C11, C01, cm_v3(0, 1, 1)), cubic_between(C01, C00, cm_v3(-1, 0, 0.5))};
    for (int k = 0; k < 4; k++) {
        cm_egreg_side *sd = &g->side[k];
        sd->kind = CM_EGREG_SIDE_CUBIC;
        sd->cub = s[k];
        sd->fan = 1;
        cm_vec3 x0 = cm_neg(d_end(&s[(k + 3) & 3])), x3 = d_start(&s[(k + 1) & 3]);
        /* inner coefficients lifted differently, so that X_k'(0) and X_k'(1) differ (twists) */
        cm_vec3 lift1 = cm_v3(0, 0, bulge * (k + 1)), lift2 = cm_v3(bulge * (k + 2), -bulge, 0);
        sd->fx[0] = x0;
        sd->fx[1] = cm_add(cm_axpy(x0, 1.0 / 3.0, cm_sub(x3, x0)), lift1);
        sd->fx[2] = cm_add(cm_axpy(x3, -1.0 / 3.0, cm_sub(x3, x0)), lift2);
        sd->fx[3] = x3;
    }
    cm_status st;
    cm_status_init(&st);
    assert_int_equal(cm_egreg_finish(g, &st), CM_OK);
}

static cm_vec3 side_point(const cm_egreg *g, int k, double s, cm_vec3 *x)
{
    cm_vec3 d[3], xx[2];
    assert_int_equal(cm_egreg_side_eval(&g->side[k], s, d, xx, NULL), CM_OK);
    if (x)
        *x = xx[0];
    return d[0];
}

static void eval(const cm_egreg *g, double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv)
{
    assert_int_equal(cm_egreg_eval(g, u, v, S, Su, Sv, NULL), CM_OK);
}

static void test_boundary_and_cross_derivatives(void **state)
{
    (void)state;
    cm_egreg g;
    warped_patch(&g, 3.0);
    for (int i = 0; i <= 16; i++) {
        double t = i / 16.0;
        cm_vec3 S, Su, Sv, X;
        /* side 0: S(t,0) = B0(t), S_v(t,0) = X0(t) */
        eval(&g, t, 0, &S, &Su, &Sv);
        assert_vec_near(S, side_point(&g, 0, t, &X), 1e-12);
        assert_vec_near(Sv, X, 1e-9);
        /* side 1: S(1,t) = B1(t), S_u(1,t) = -X1(t) (X points into the patch) */
        eval(&g, 1, t, &S, &Su, &Sv);
        assert_vec_near(S, side_point(&g, 1, t, &X), 1e-12);
        assert_vec_near(Su, cm_neg(X), 1e-9);
        /* side 2: S(t,1) = B2(1-t), S_v(t,1) = -X2(1-t) */
        eval(&g, t, 1, &S, &Su, &Sv);
        assert_vec_near(S, side_point(&g, 2, 1 - t, &X), 1e-12);
        assert_vec_near(Sv, cm_neg(X), 1e-9);
        /* side 3: S(0,t) = B3(1-t), S_u(0,t) = X3(1-t) */
        eval(&g, 0, t, &S, &Su, &Sv);
        assert_vec_near(S, side_point(&g, 3, 1 - t, &X), 1e-12);
        assert_vec_near(Su, X, 1e-9);
    }
}

/* S_u and S_v of g are its derivatives (central differences) at 49 inner points */
static void assert_partials(const cm_egreg *g)
{
    const double h = 1e-6;
    for (int i = 1; i < 8; i++)
        for (int j = 1; j < 8; j++) {
            double u = i / 8.0 + 0.01, v = j / 8.0 - 0.02;
            cm_vec3 S, Su, Sv, a, b;
            eval(g, u, v, &S, &Su, &Sv);
            eval(g, u + h, v, &a, NULL, NULL);
            eval(g, u - h, v, &b, NULL, NULL);
            assert_vec_near(Su, cm_scale(cm_sub(a, b), 0.5 / h), 1e-5 * (1 + cm_norm(Su)));
            eval(g, u, v + h, &a, NULL, NULL);
            eval(g, u, v - h, &b, NULL, NULL);
            assert_vec_near(Sv, cm_scale(cm_sub(a, b), 0.5 / h), 1e-5 * (1 + cm_norm(Sv)));
        }
}

static void test_partials_are_derivatives(void **state)
{
    (void)state;
    cm_egreg g;
    warped_patch(&g, 3.0);
    assert_partials(&g);
}

/* between two equal arcs (as cubics) at z = 0 and z = 5 joined by lines, with the cross derivative
   along the arcs the line vector: S(u,v) = arc(u) + v (0,0,5) exactly */
static void test_linear_between_curves(void **state)
{
    (void)state;
    cm_egreg g;
    memset(&g, 0, sizeof g);
    cm_cubic arc = {{{10, 0, 0}, {10, 5.5, 0}, {5.5, 10, 0}, {0, 10, 0}}};
    cm_vec3 up = {0, 0, 5};
    cm_cubic top = arc, line1, line3;
    for (int i = 0; i < 4; i++)
        top.c[i] = cm_add(arc.c[i], up);
    line1 = cubic_between(arc.c[3], top.c[3], cm_v3(0, 0, 0));
    line3 = cubic_between(arc.c[0], top.c[0], cm_v3(0, 0, 0));
    g.side[0].cub = arc;
    g.side[1].cub = line1;
    g.side[2].cub = cm_cubic_reverse(&top);
    g.side[3].cub = cm_cubic_reverse(&line3);
    for (int k = 0; k < 4; k++) {
        g.side[k].kind = CM_EGREG_SIDE_CUBIC;
        g.side[k].fan = 1;
    }
    /* arcs: the cross derivative is +-up; lines: the arc's tangent at its end, into the patch */
    for (int i = 0; i < 4; i++) {
        g.side[0].fx[i] = up;
        g.side[2].fx[i] = cm_neg(up);
    }
    cm_vec3 t1 = d_end(&arc), t0 = d_start(&arc);
    for (int i = 0; i < 4; i++) {
        g.side[1].fx[i] = cm_neg(t1);
        g.side[3].fx[i] = t0;
    }
    assert_int_equal(cm_egreg_finish(&g, NULL), CM_OK);
    for (int i = 0; i <= 8; i++)
        for (int j = 0; j <= 8; j++) {
            cm_vec3 S, d[3];
            eval(&g, i / 8.0, j / 8.0, &S, NULL, NULL);
            cm_cubic_eval(&arc, i / 8.0, d);
            assert_vec_near(S, cm_axpy(d[0], j / 8.0, up), 1e-12);
        }
}

/* hostile numbers in a patch: clean answers, never a NaN out */
static void test_nonfinite(void **state)
{
    (void)state;
    cm_egreg g;
    warped_patch(&g, 0.0);
    cm_vec3 S, Su, Sv;
    cm_status st;
    /* a NaN reaching a patch that was built: the evaluation says so */
    g.side[1].fx[1].x = nan("");
    cm_status_init(&st);
    assert_int_equal(cm_egreg_eval(&g, 0.9, 0.5, &S, &Su, &Sv, &st), CM_E_NONFINITE);
    assert_int_equal(st.code, CM_E_NONFINITE);
    /* ... and building with it: the twists use it, the corner data refuse it */
    cm_status_init(&st);
    assert_int_equal(cm_egreg_finish(&g, &st), CM_E_NONFINITE);
    assert_int_equal(st.code, CM_E_NONFINITE);
    g.side[1].fx[1].x = 0;
    g.side[1].fx[0].y = HUGE_VAL;
    cm_status_init(&st);
    assert_int_equal(cm_egreg_finish(&g, &st), CM_E_NONFINITE);
}

/* a half circle of radius R in z = 0 from (R,0,0) over (0,R,0) to (-R,0,0): two rational quarter arcs */
static const double half_knots[8] = {0, 0, 0, 0.5, 0.5, 1, 1, 1};
static const double half_w[5] = {1, 0.70710678118654752, 1, 0.70710678118654752, 1};
static const cm_vec3 half_ctrl[5] = {{10, 0, 0}, {10, 10, 0}, {0, 10, 0}, {-10, 10, 0}, {-10, 0, 0}};

/* an EDGE side along the half circle (backwards: from (-R,0,0)) with end normals Ns, Ne, its bases
   from them (spec 5.4), k = 1 and h = 0 (X = A), and the basis cm_egreg_choose_turn() picks */
static void half_circle_side(cm_egreg_side *sd, cm_vec3 Ns, cm_vec3 Ne, int backwards)
{
    memset(sd, 0, sizeof *sd);
    sd->kind = CM_EGREG_SIDE_EDGE;
    sd->curve = (cm_curve){2, 5, half_knots, half_ctrl, half_w};
    sd->t0 = backwards ? 1.0 : 0.0;
    sd->t1 = backwards ? 0.0 : 1.0;
    cm_vec3 d0[3], d1[3];
    assert_int_equal(cm_egreg_side_eval(sd, 0.0, d0, NULL, NULL), CM_OK);
    assert_int_equal(cm_egreg_side_eval(sd, 1.0, d1, NULL, NULL), CM_OK);
    sd->As = cm_unit(cm_cross(Ns, d0[1]));
    sd->Ae = cm_unit(cm_cross(Ne, d1[1]));
    sd->k0 = sd->k1 = 1.0;
    assert_int_equal(cm_egreg_choose_turn(sd, Ns, Ne, &sd->tb, NULL), CM_OK);
}

/* X = A at s, and X' against central differences */
static cm_vec3 basis_at(const cm_egreg_side *sd, double s, cm_vec3 d[3], int check_derivative)
{
    const double h = 1e-6;
    cm_vec3 x[2], xa[2], xb[2];
    assert_int_equal(cm_egreg_side_eval(sd, s, d, x, NULL), CM_OK);
    if (check_derivative) {
        assert_int_equal(cm_egreg_side_eval(sd, s + h, NULL, xa, NULL), CM_OK);
        assert_int_equal(cm_egreg_side_eval(sd, s - h, NULL, xb, NULL), CM_OK);
        assert_vec_near(x[1], cm_scale(cm_sub(xa[0], xb[0]), 0.5 / h), 1e-5 * (1 + cm_norm(x[1])));
    }
    return x[0];
}

/* the normal of the dome z = c - (x^2 + y^2) / 40 at (x, y) */
static cm_vec3 dome_normal(double x, double y) { return cm_unit(cm_v3(x / 20.0, y / 20.0, 1.0)); }

static void test_turning_basis_half_circle(void **state)
{
    (void)state;
    const cm_vec3 up = {0, 0, 1};
    cm_egreg_side lin, tur;
    cm_vec3 d[3];
    /* a flat face's half circle: opposite bases, equal normals: the plane's turning basis */
    half_circle_side(&tur, up, up, 0);
    assert_true(cm_dot(tur.As, tur.Ae) < -0.999);
    assert_int_equal(tur.tb.mode, CM_EGREG_TURN_PLANE);
    lin = tur;
    lin.tb.mode = CM_EGREG_TURN_NONE;
    /* the linear basis vanishes at the middle: the patch would be singular there */
    assert_true(cm_norm(basis_at(&lin, 0.5, d, 0)) < 1e-12);
    for (int i = 0; i <= 16; i++) {
        double s = i / 16.0;
        /* (inside, off the knot at s = 1/2, X' against differences; the clamp at the ends halves them) */
        cm_vec3 A = basis_at(&tur, i == 8 ? 0.52 : s, d, i > 0 && i < 16);
        /* unit, square to the edge, in the plane, inwards (N x B') */
        assert_true(fabs(cm_norm(A) - 1.0) < 1e-12);
        assert_true(fabs(cm_dot(A, d[1])) < 1e-9 * cm_norm(d[1]));
        assert_vec_near(A, cm_unit(cm_cross(up, d[1])), 1e-12);
        if (i == 0)
            assert_vec_near(A, tur.As, 1e-12);
        if (i == 16)
            assert_vec_near(A, tur.Ae, 1e-12);
    }
    /* the rim of a dome (a surface of revolution about the circle's axis): its normal along the rim
       turns with it, and the plane's turning basis follows it exactly */
    half_circle_side(&tur, dome_normal(10, 0), dome_normal(-10, 0), 0);
    assert_int_equal(tur.tb.mode, CM_EGREG_TURN_PLANE);
    for (int i = 1; i < 16; i++) {
        cm_vec3 A = basis_at(&tur, i / 16.0 + 0.01, d, 1);
        assert_vec_near(A, cm_unit(cm_cross(dome_normal(d[0].x, d[0].y), d[1])), 1e-12);
    }
    /* the same edge from the face on its other side (backwards, normals turned over): the same line */
    cm_egreg_side back;
    half_circle_side(&back, cm_neg(dome_normal(-10, 0)), cm_neg(dome_normal(10, 0)), 1);
    assert_int_equal(back.tb.mode, CM_EGREG_TURN_PLANE);
    for (int i = 0; i <= 8; i++) {
        cm_vec3 A = basis_at(&tur, i / 8.0, d, 0), B = basis_at(&back, 1.0 - i / 8.0, d, 0);
        assert_true(cm_norm(cm_cross(A, B)) < 1e-12);
    }
    /* end normals that disagree (a twisted band): X' is still the derivative */
    half_circle_side(&tur, up, cm_unit(cm_v3(0.4, -0.2, 1)), 0);
    assert_int_equal(tur.tb.mode, CM_EGREG_TURN_PLANE);
    for (int i = 1; i < 16; i++)
        assert_true(fabs(cm_norm(basis_at(&tur, i / 16.0 + 0.01, d, 1)) - 1.0) < 1e-12);
    /* the normals' blend (a space curve's turning basis), set by hand on the same edge */
    tur.tb.mode = CM_EGREG_TURN_BLEND;
    tur.tb.N0 = up;
    tur.tb.N1 = cm_unit(cm_v3(0.4, -0.2, 1));
    for (int i = 1; i < 16; i++) {
        cm_vec3 A = basis_at(&tur, i / 16.0 + 0.01, d, 1);
        assert_true(fabs(cm_norm(A) - 1.0) < 1e-12);
        assert_true(fabs(cm_dot(A, d[1])) < 1e-9 * cm_norm(d[1]));
    }
    /* a half cylinder's half circle: normals opposite, bases equal; the linear basis, exact there */
    half_circle_side(&lin, cm_v3(1, 0, 0), cm_v3(-1, 0, 0), 0);
    assert_true(cm_dot(lin.As, lin.Ae) > 0.999);
    assert_int_equal(lin.tb.mode, CM_EGREG_TURN_NONE);
    /* a quarter circle turns by a right angle: the linear basis (what a cubic GREGORY neighbour has) */
    half_circle_side(&lin, up, up, 0);
    lin.t1 = 0.5;
    lin.Ae = cm_unit(cm_cross(up, cm_v3(-1, 0, 0)));
    assert_int_equal(cm_egreg_choose_turn(&lin, up, up, &lin.tb, NULL), CM_OK);
    assert_int_equal(lin.tb.mode, CM_EGREG_TURN_NONE);
    /* a basis that vanishes is refused, not a NaN */
    half_circle_side(&tur, up, up, 0);
    tur.tb.a0 = tur.tb.a1 = tur.tb.b0 = tur.tb.b1 = 0.0;
    cm_status st;
    cm_status_init(&st);
    cm_vec3 x[2];
    assert_int_equal(cm_egreg_side_eval(&tur, 0.3, d, x, &st), CM_E_DEGENERATE);
    /* half of a turning edge (an N-split's): the whole edge's basis on that half */
    half_circle_side(&tur, dome_normal(10, 0), dome_normal(-10, 0), 0);
    cm_egreg_side half = tur;
    half.t1 = 0.5;
    half.tb = cm_egreg_turn_part(&tur.tb, 0.0, 0.5);
    for (int i = 0; i <= 8; i++)
        assert_vec_near(basis_at(&half, i / 8.0, d, 0), basis_at(&tur, i / 16.0, d, 0), 1e-12);
}

/* a CHAIN of the two quarter arcs, each with its own turning basis; and a patch with the turning
   basis on one side whose partials are its derivatives (the sides do not meet: only the derivatives
   of the formula are checked here) */
static void test_turning_basis_chain_and_patch(void **state)
{
    (void)state;
    cm_vec3 d[3], x[2];
#if CM_EGREG_MAX_PIECES >= 2 /* (a board of four sides joins no edges) */
    const cm_vec3 up = {0, 0, 1};
    cm_egreg_side sd;
    memset(&sd, 0, sizeof sd);
    sd.kind = CM_EGREG_SIDE_CHAIN;
    sd.npiece = 2;
    for (int i = 0; i < 2; i++) {
        cm_egreg_piece *P = &sd.piece[i];
        P->curve = (cm_curve){2, 5, half_knots, half_ctrl, half_w};
        P->t0 = 0.5 * i;
        P->t1 = 0.5 * (i + 1);
        P->s0 = i ? 0.4 : 0.0; /* unequal shares of the side */
        P->s1 = i ? 1.0 : 0.4;
        P->tb.mode = CM_EGREG_TURN_PLANE;
        P->tb.P = up;
        P->tb.a0 = i ? 0.9 : 1.0;
        P->tb.a1 = i ? 1.0 : 0.9;
        P->tb.b0 = i ? 0.2 : 0.0;
        P->tb.b1 = i ? 0.0 : 0.2;
    }
    sd.k0 = 1.0;
    sd.k1 = 2.0;
    sd.h0 = 0.1;
    sd.h1 = -0.2;
    for (int i = 1; i < 16; i++) {
        double s = i / 16.0 + 0.003;
        cm_vec3 X = basis_at(&sd, s, d, 1);
        assert_int_equal(cm_egreg_side_eval(&sd, s, d, x, NULL), CM_OK);
        double k = 1.0 + s, hh = 0.1 - 0.3 * s;
        /* X = k A + h B' with A square to B' and of unit length */
        cm_vec3 A = cm_scale(cm_sub(X, cm_scale(d[1], hh)), 1.0 / k);
        assert_true(fabs(cm_norm(A) - 1.0) < 1e-12);
        assert_true(fabs(cm_dot(A, d[1])) < 1e-9 * cm_norm(d[1]));
    }
#else
    (void)d, (void)x;
#endif
    /* the patch: side 0 the half circle with the dome rim's turning basis, the others the warped
       patch's */
    cm_egreg g;
    warped_patch(&g, 2.0);
    half_circle_side(&g.side[0], dome_normal(10, 0), dome_normal(-10, 0), 0);
    assert_int_equal(g.side[0].tb.mode, CM_EGREG_TURN_PLANE);
    g.side[0].h0 = 0.3;
    g.side[0].h1 = -0.1;
    assert_int_equal(cm_egreg_finish(&g, NULL), CM_OK);
    assert_partials(&g);
}

/* the memo of side evaluations (cm_egreg_eval_memo): the same bits as without it at every point of
   a grid walked twice (rows and columns repeat their side parameters), at parameters that fall in
   one slot of the memo (s found by search: two values hashed alike must not be taken for each
   other), and after a reset on another patch at the same points (an entry of the last patch must
   not answer).  Red without the comparison of s, and without the reset's new generation. */
static void same_bits(const cm_egreg *g, double u, double v, cm_egreg_memo *memo)
{
    cm_vec3 S0, Su0, Sv0, S1, Su1, Sv1;
    eval(g, u, v, &S0, &Su0, &Sv0);
    assert_int_equal(cm_egreg_eval_memo(g, u, v, &S1, &Su1, &Sv1, memo, NULL), CM_OK);
    if (memcmp(&S0, &S1, sizeof S0) || memcmp(&Su0, &Su1, sizeof Su0) || memcmp(&Sv0, &Sv1, sizeof Sv0))
        fail_msg("at (%.17g, %.17g) the memo gives other bits", u, v);
}

static void test_side_memo(void **state)
{
    (void)state;
    static cm_egreg g, h;
    static cm_egreg_memo memo;
    warped_patch(&g, 0.7);
    warped_patch(&h, -1.3);
    memset(&memo, 0, sizeof memo);
    cm_egreg_memo_reset(&memo);
    for (int pass = 0; pass < 2; pass++)
        for (int i = 0; i <= 12; i++)
            for (int j = 0; j <= 12; j++)
                same_bits(&g, i / 12.0, (j + 0.5) / 13.0, &memo);
    /* two parameters in one slot */
    double a = 0.3, b = -1.0;
    for (int k = 1; k < 100000 && b < 0; k++)
        if (cm_egreg_memo_slot(k / 100000.0) == cm_egreg_memo_slot(a) && k / 100000.0 != a)
            b = k / 100000.0;
    assert_true(b > 0);
    for (int pass = 0; pass < 3; pass++) {
        same_bits(&g, a, 0.5, &memo);
        same_bits(&g, b, 0.5, &memo);
        same_bits(&g, 0.5, a, &memo);
        same_bits(&g, 0.5, b, &memo);
    }
    /* another patch after a reset: nothing of g's answers */
    cm_egreg_memo_reset(&memo);
    for (int i = 0; i <= 12; i++)
        same_bits(&h, i / 12.0, (i + 0.5) / 13.0, &memo);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_boundary_and_cross_derivatives),
        cmocka_unit_test(test_partials_are_derivatives),
        cmocka_unit_test(test_linear_between_curves),
        cmocka_unit_test(test_nonfinite),
        cmocka_unit_test(test_turning_basis_half_circle),
        cmocka_unit_test(test_turning_basis_chain_and_patch),
        cmocka_unit_test(test_side_memo),
    };
    return cmocka_run_group_tests_name("egreg", tests, NULL, NULL);
}
