/*
 * kernel_vectors - a fixed set of kernel evaluations printed as hex doubles.
 *
 * `make check-cross` runs this on x86-64 and, under qemu-user, on aarch64
 * and armhf, and diffs the outputs: the shared kernels must give
 * bit-identical results on every architecture (spec §2; -ffp-contract=off).
 * Inputs use only exact constants, integer-seeded values and sqrt (correctly
 * rounded everywhere) - no libm transcendental, which may differ by target.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "cm/cm_arc.h"
#include "cm/cm_bezier.h"
#include "cm/cm_bspline.h"
#include "cm/cm_cubic_convert.h"
#include "cm/cm_geom.h"
#include "cm/cm_gregory.h"
#include "cm/cm_lsq.h"
#include "cm/cm_project.h"

static int failures;

static void pv(const char *tag, int i, cm_vec3 v)
{
    printf("%s %d: %a %a %a\n", tag, i, v.x, v.y, v.z);
}

static void pd(const char *tag, int i, double x)
{
    printf("%s %d: %a\n", tag, i, x);
}

static void ok(cm_err e, const char *what)
{
    if (e != CM_OK) {
        printf("ERROR %s: %s\n", what, cm_err_name(e));
        failures++;
    }
}

static double rnd(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (double)(*s >> 8) / 16777216.0;
}

static cm_vec3 rvec(uint32_t *s, double scale)
{
    double x = rnd(s), y = rnd(s), z = rnd(s);
    return cm_v3(scale * (2 * x - 1), scale * (2 * y - 1), scale * (2 * z - 1));
}

int main(void)
{
    uint32_t seed = 12345;
    const double h = 0.70710678118654752440; /* sqrt(1/2), rounded by the compiler identically everywhere */

    /* K1: Ex. 2.3 vector, basis and derivatives at 9 parameters */
    const double U23[11] = {0, 0, 0, 1, 2, 3, 4, 4, 5, 5, 5};
    for (int k = 0; k <= 8; k++) {
        double u = 5.0 * k / 8.0 + 0.01 * k, d[CM_MAX_DERS + 1][CM_MAX_ORDER];
        int span = cm_bspl_find_span(8, 2, U23, u);
        ok(cm_bspl_ders_basis(span, u, 2, 2, U23, d, NULL), "ders");
        for (int r = 0; r < 3; r++)
            printf("basis %d.%d: %d %a %a %a\n", k, r, span, d[0][r], d[1][r], d[2][r]);
    }

    /* K2: rational quarter circle, point and two derivatives */
    const cm_vec3 Pc[3] = {{3, 0, 0}, {3, 3, 0}, {0, 3, 0}};
    const double wc[3] = {1, h, 1}, Uq[6] = {0, 0, 0, 1, 1, 1};
    cm_curve circle = {2, 3, Uq, Pc, wc};
    for (int k = 0; k <= 6; k++) {
        cm_vec3 d[3];
        ok(cm_curve_eval(&circle, k / 6.0, 2, d, NULL), "curve");
        for (int j = 0; j < 3; j++)
            pv("circle", k * 3 + j, d[j]);
    }

    /* K2: rational sphere octant, all partials up to order 2 */
    const double wo[9] = {1, h, 1, h, 0.5, h, 1, h, 1};
    cm_vec3 Po[9];
    const double mx[3] = {2, 2, 0}, mz[3] = {0, 2, 2};
    for (int i = 0; i < 3; i++) {
        Po[i * 3 + 0] = cm_v3(mx[i], 0, mz[i]);
        Po[i * 3 + 1] = cm_v3(mx[i], mx[i], mz[i]);
        Po[i * 3 + 2] = cm_v3(0, mx[i], mz[i]);
    }
    cm_surf oct = {2, 2, 3, 3, Uq, Uq, Po, wo};
    for (int k = 0; k < 5; k++) {
        cm_vec3 S[3][3];
        ok(cm_surf_eval(&oct, 0.1 + 0.2 * k, 0.9 - 0.15 * k, 2, S, NULL), "surf");
        pv("octant", k * 6 + 0, S[0][0]);
        pv("octant", k * 6 + 1, S[1][0]);
        pv("octant", k * 6 + 2, S[0][1]);
        pv("octant", k * 6 + 3, S[2][0]);
        pv("octant", k * 6 + 4, S[1][1]);
        pv("octant", k * 6 + 5, S[0][2]);
    }

    /* K3: knot insertion into a rational cubic */
    const double U5[9] = {0, 0, 0, 0, 0.5, 1, 1, 1, 1};
    cm_vec3 P5[5], Q[8];
    double w5[5], K[12], wq[8];
    for (int i = 0; i < 5; i++) {
        P5[i] = rvec(&seed, 4.0);
        w5[i] = 0.5 + rnd(&seed);
    }
    cm_curve rc = {3, 5, U5, P5, w5};
    ok(cm_curve_insert_knot(&rc, 0.3, 2, K, Q, wq, 8, NULL), "insert");
    for (int i = 0; i < 7; i++) {
        pv("insert", i, Q[i]);
        pd("insert-w", i, wq[i]);
    }

    /* K4: split and elevation */
    cm_cubic cu = {{rvec(&seed, 2), rvec(&seed, 2), rvec(&seed, 2), rvec(&seed, 2)}}, a, b;
    cm_cubic_split(&cu, 0.37, &a, &b);
    for (int i = 0; i < 4; i++) {
        pv("split-a", i, a.c[i]);
        pv("split-b", i, b.c[i]);
    }
    cm_vec3 E[8];
    ok(cm_bez_elevate(cu.c, 3, 2, E, NULL), "elevate");
    for (int i = 0; i < 6; i++)
        pv("elevate", i, E[i]);

    /* Gregory patch with incompatible pairs */
    cm_gregory g;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            g.P[i][j] = cm_add(cm_v3(i, j, 0), rvec(&seed, 0.3));
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++)
            for (int k = 0; k < 2; k++)
                g.I[i][j][k] = cm_add(cm_v3(i + 1, j + 1, 0.2), rvec(&seed, 0.3));
    for (int k = 0; k < 9; k++) {
        cm_vec3 S, Su, Sv;
        cm_greg_eval(&g, (k % 3) / 2.0 * 0.8 + 0.05, (k / 3) / 2.0 * 0.9, &S, &Su, &Sv);
        pv("gregory", k * 3 + 0, S);
        pv("gregory", k * 3 + 1, Su);
        pv("gregory", k * 3 + 2, Sv);
    }

    /* K7: 90 deg arc (two spans of a half circle: the general path) and 120 deg arc */
    cm_cubic arc;
    double delta;
    ok(cm_cubic_convert(&circle, 0, 1, &arc, &delta, NULL, NULL), "k7-90");
    for (int i = 0; i < 4; i++)
        pv("k7-90", i, arc.c[i]);
    pd("k7-90-delta", 0, delta);
    const double s3 = 1.7320508075688772; /* sqrt(3) */
    const cm_vec3 P120[3] = {{1, 0, 0}, {1, s3, 0}, {-0.5, s3 / 2, 0}};
    const double w120[3] = {1, 0.5, 1};
    cm_curve c120 = {2, 3, Uq, P120, w120};
    ok(cm_cubic_convert(&c120, 0, 1, &arc, &delta, NULL, NULL), "k7-120");
    for (int i = 0; i < 4; i++)
        pv("k7-120", i, arc.c[i]);
    pd("k7-120-delta", 0, delta);
    /* format 4.14: the same arcs' cubics in closed form (cm_cubic_from_conic), and the edge's choice */
    ok(cm_cubic_from_conic(&c120, &arc) ? CM_OK : CM_E_ARG, "conic-120");
    for (int i = 0; i < 4; i++)
        pv("conic-120", i, arc.c[i]);
    ok(cm_edge_cubic(&c120, 1, &arc, NULL), "conic-120-edge");
    ok(cm_edge_cubic_delta(&c120, &arc, &delta, NULL), "conic-120-delta");
    pd("conic-120-delta", 0, delta);

    /* K6: least-squares cubic with fixed ends through noisy samples of a helix-like curve */
    enum { M = 40, N = 6 };
    cm_vec3 Qd[M], Pf[N];
    double td[M], Uf[N + 4], rms;
    static cm_fit_curve_ws ws;
    for (int k = 0; k < M; k++) {
        double s = k / (double)(M - 1);
        td[k] = s;
        Qd[k] = cm_add(cm_v3(s, s * s, s * s * s), rvec(&seed, 1e-3));
    }
    ok(cm_knots_uniform(N, 3, Uf, NULL), "knots");
    ok(cm_fit_curve(Qd, td, NULL, M, 3, N, Uf, &Qd[0], &Qd[M - 1], Pf, &rms, &ws, NULL), "fit");
    for (int i = 0; i < N; i++)
        pv("fit", i, Pf[i]);
    pd("fit-rms", 0, rms);

    /* K8c: banded Cholesky */
    enum { NB = 12, WB = 3 };
    static double band[NB * (WB + 1)];
    cm_vec3 rhs[NB];
    for (int i = 0; i < NB; i++) {
        for (int k = 0; k <= WB; k++)
            band[CM_BAND_IDX(i, i - k, WB)] = k == 0 ? 4.0 + rnd(&seed) : (i - k >= 0 ? 0.3 * rnd(&seed) : 0.0);
        rhs[i] = rvec(&seed, 1.0);
    }
    ok(cm_chol_band(band, NB, WB, NULL), "band");
    cm_chol_band_solve3(band, NB, WB, rhs);
    for (int i = 0; i < NB; i++)
        pv("band", i, rhs[i]);

    /* K9: projections */
    for (int k = 0; k < 5; k++) {
        double t, dist, u, v;
        cm_vec3 X = cm_add(cm_v3(2.0, 2.0, 0.1 * k), rvec(&seed, 0.5));
        ok(cm_curve_project(&circle, 0, 1, X, &t, &dist, NULL), "cproj");
        printf("cproj %d: %a %a\n", k, t, dist);
        cm_patch pa = cm_patch_of_gregory(&g);
        X = cm_add(cm_v3(1.5, 1.5, 0.5), rvec(&seed, 1.0));
        ok(cm_patch_project(&pa, X, &u, &v, &dist, NULL), "gproj");
        printf("gproj %d: %a %a %a\n", k, u, v, dist);
        cm_patch po = cm_patch_of_surf(&oct);
        ok(cm_patch_project(&po, cm_scale(X, 0.7), &u, &v, &dist, NULL), "sproj");
        printf("sproj %d: %a %a %a\n", k, u, v, dist);
    }

    /* format 4.4: arcs of one, two and four pieces from their ends and middle points, and points on
       them */
    for (int k = 0; k < 6; k++) {
        cm_vec3 a0 = rvec(&seed, 50.0), a2 = cm_add(a0, rvec(&seed, 10.0)), mid = cm_scale(cm_add(a0, a2), 0.5);
        cm_vec3 off = cm_scale(cm_cross(cm_sub(a2, a0), rvec(&seed, 1.0)), 0.1 * (k + 1) * (k + 1));
        cm_vec3 P[CM_ARC_MAX_CTRL];
        double W[CM_ARC_MAX_CTRL], AK[CM_ARC_MAX_KNOTS];
        int n = 0;
        ok(cm_arc_nurbs(a0, cm_add(mid, off), a2, P, W, AK, &n, NULL), "arc");
        for (int i = 0; i < n; i++) {
            pv("arc ctrl", k * 10 + i, P[i]);
            pd("arc weight", k * 10 + i, W[i]);
        }
        cm_curve ac = {2, n, AK, P, W};
        for (int i = 0; i <= 4; i++) {
            cm_vec3 d[2];
            ok(cm_curve_eval(&ac, i / 4.0 + (i < 4 ? 0.01 : 0.0), 1, d, NULL), "arc eval");
            pv("arc point", k * 10 + i, d[0]);
            pv("arc tangent", k * 10 + i, d[1]);
        }
    }

    /* ... and at its bounds: a half circle exactly (middle weight 0), a quarter circle (2w^2 = 1, as
       rounding makes it), an arc just short of the full-circle refusal (1 + w = 1.4e-6), far from
       the origin */
    const cm_vec3 bounds[3][3] = {{{995, 20, 7}, {1000, 25, 7}, {1005, 20, 7}},
                                  {{1001, 20, 7}, {1000 + h, 20 + h, 7}, {1000, 21, 7}},
                                  {{1000, 20, 7}, {1000.0005, 20.6, 7}, {1000.001, 20, 7}}};
    for (int k = 0; k < 3; k++) {
        cm_vec3 P[CM_ARC_MAX_CTRL];
        double W[CM_ARC_MAX_CTRL], AK[CM_ARC_MAX_KNOTS];
        int n = 0;
        ok(cm_arc_nurbs(bounds[k][0], bounds[k][1], bounds[k][2], P, W, AK, &n, NULL), "arc bound");
        for (int i = 0; i < n; i++) {
            pv("arc bound ctrl", k * 10 + i, P[i]);
            pd("arc bound weight", k * 10 + i, W[i]);
        }
    }

    /* ... and full circles from their vertex, halfway point and far point */
    for (int k = 0; k < 3; k++) {
        cm_vec3 c0 = rvec(&seed, 100.0), u = rvec(&seed, 5.0), v = cm_cross(u, rvec(&seed, 1.0));
        v = cm_scale(cm_unit(v), cm_norm(u));
        cm_vec3 P[CM_ARC_MAX_CTRL];
        double W[CM_ARC_MAX_CTRL], AK[CM_ARC_MAX_KNOTS];
        int n = 0;
        ok(cm_circle_nurbs(cm_add(c0, u), cm_add(c0, v), cm_sub(c0, u), P, W, AK, &n, NULL), "circle");
        for (int i = 0; i < n; i++) {
            pv("circle ctrl", k * 10 + i, P[i]);
            pd("circle weight", k * 10 + i, W[i]);
        }
    }

    /* K11: face frame of a skewed hexagon */
    cm_vec3 hex[6];
    for (int i = 0; i < 6; i++)
        hex[i] = cm_add(cm_v3(10 + i, 3 * (i % 2), 0.1 * i * i), rvec(&seed, 0.2));
    cm_frame f;
    ok(cm_face_frame(hex, 6, hex, 6, 1e-9, &f, NULL), "frame");
    pv("frame", 0, f.o);
    pv("frame", 1, f.ex);
    pv("frame", 2, f.ey);
    pv("frame", 3, f.ez);
    return failures ? 1 : 0;
}
