/*
 * fit_correction.c - least-squares fit of GREGORY-FIT's interior corrections (see fit_correction.h).
 *
 * Point pairs tie a point of the patches, (k, u, v), to where the source surface says it should be:
 * the source surface on a grid over the face, each with its foot on the patches (what spec §12
 * measures), and each patch on a grid, each with its foot on the source surface (what verify.c's
 * back measure sees).  Per patch the coefficients minimise the sum of squared misses plus a small
 * ridge (a patch with few pairs stays near zero instead of swinging); three rounds, each starting
 * from the feet of the corrected surface, since moving the surface moves the feet.
 */
#include "fit_correction.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_lsq.h"
#include "cm/cm_param.h"
#include "verify.h"

#define SRC_N 21      /* source grid per direction */
#define BACK_N 8      /* patch grid per direction: (i/BACK_N), i = 1..BACK_N-1 */
#define ROUNDS 3
#define RIDGE 1e-3    /* of the mean diagonal of the normal matrix */

/* a point (k, u, v) of the patches and where it should be; k < 0: left out (no target found) */
typedef struct pair {
    int k;
    double u, v;
    cm_vec3 target;  /* a point of the source surface */
    cm_vec2 suv;     /* its source parameters (back pairs: where the next foot search starts) */
} pair;

/* the normal equations of patch k's coefficients (m^2 unknowns, three right-hand sides), solved with
   the shared banded Cholesky at full bandwidth (m^2 can exceed the dense solver's CM_MAX_DENSE) */
static void solve_patch(const pair *pr, int np, const cm_greg_surface *gs, int k, int m, cm_vec3 *dc)
{
    enum { N = CM_FIT_MAX_COEF };
    double A[N * N]; /* banded lower storage, half bandwidth n - 1: row i at i*n */
    cm_vec3 b[N];
    int n = m * m, w = n - 1;
    memset(A, 0, sizeof A);
    for (int i = 0; i < n; i++)
        b[i] = cm_v3(0, 0, 0);
    int used = 0;
    for (int q = 0; q < np; q++) {
        if (pr[q].k != k)
            continue;
        double bu[CM_FIT_MAX_M], bv[CM_FIT_MAX_M], phi[N];
        cm_fit_basis(m, pr[q].u, bu, NULL);
        cm_fit_basis(m, pr[q].v, bv, NULL);
        for (int i = 0; i < m; i++)
            for (int j = 0; j < m; j++)
                phi[i * m + j] = bu[i] * bv[j];
        cm_vec3 S;
        if (cm_greg_surface_eval(gs, k, pr[q].u, pr[q].v, &S, NULL, NULL) != CM_OK)
            continue;
        cm_vec3 r = cm_sub(pr[q].target, S);
        for (int a = 0; a < n; a++) {
            b[a] = cm_axpy(b[a], phi[a], r);
            for (int c = 0; c <= a; c++)
                A[CM_BAND_IDX(a, c, w)] += phi[a] * phi[c];
        }
        used++;
    }
    for (int i = 0; i < n; i++)
        dc[i] = cm_v3(0, 0, 0);
    if (used == 0)
        return;
    double tr = 0;
    for (int i = 0; i < n; i++)
        tr += A[CM_BAND_IDX(i, i, w)];
    for (int i = 0; i < n; i++)
        A[CM_BAND_IDX(i, i, w)] += RIDGE * tr / n + 1e-300;
    if (cm_chol_band(A, n, w, NULL) != CM_OK)
        return;
    cm_chol_band_solve3(A, n, w, b);
    for (int i = 0; i < n; i++)
        dc[i] = b[i];
}

int fit_sides_within(const loaded_model *lm, int bface, const cm_greg_surface *gs, double tol)
{
    const face_domain *fd = &lm->fds[bface];
    if (!fd->uv || fd->npts < 1)
        return 1;
    for (int k = 0; k < gs->npatch; k++)
        for (int side = 0; side < 4; side++)
            for (int i = 1; i <= 3; i++) {
                /* sides 0, 1: v = 0, v = 1 (u = t); sides 2, 3: u = 0, u = 1 (v = t) */
                double t = i / 4.0, u = side < 2 ? t : (double)(side - 2), v = side < 2 ? (double)side : t;
                cm_vec3 S;
                if (cm_greg_surface_eval(gs, k, u, v, &S, NULL, NULL) != CM_OK)
                    return 0;
                /* the foot from the nearest boundary point of the domain, searched again over the
                   whole surface when that finds the point off (a local minimum only overstates) */
                double best = HUGE_VAL, d = HUGE_VAL, ug, vg, dg;
                cm_vec2 start = cm_v2(0, 0);
                verify_nearest_boundary(fd, S, &best, &start);
                double su = start.x, sv = start.y;
                if (best < HUGE_VAL && cm_psurf_project_from(&fd->ps, S, &su, &sv, &d, NULL) != CM_OK)
                    d = HUGE_VAL;
                if (!(d < tol) && face_domain_project_global(fd, S, &ug, &vg, &dg) == CM_OK && dg < d)
                    d = dg;
                if (!(d < tol))
                    return 0;
            }
    return 1;
}

int fit_correction(const loaded_model *lm, int bface, const cm_greg_surface *gs0, int m, double tol, double grid,
                   fit_record *out)
{
    const face_domain *fd = &lm->fds[bface];
    if (!fd->uv || m < 1 || m > CM_FIT_MAX_M || gs0->npatch < 1 || gs0->npatch > CM_MAX_GREG)
        return 0;
    cm_greg_surface *gs = malloc(sizeof *gs);
    pair *pr = malloc(sizeof *pr * (SRC_N * SRC_N + CM_MAX_GREG * BACK_N * BACK_N));
    if (!gs || !pr) {
        free(gs);
        free(pr);
        return 0;
    }
    *gs = *gs0;
    gs->fit = m;
    memset(gs->corr, 0, sizeof gs->corr);
    int np = 0, ok = 1;
    /* the source grid inside the outer loop, in a serpentine so that each foot starts from the last */
    int have = 0, k = 0;
    double u = 0, v = 0;
    for (int i = 0; i < SRC_N && ok; i++)
        for (int jj = 0; jj < SRC_N; jj++) {
            int j = i % 2 ? SRC_N - 1 - jj : jj;
            cm_vec2 uv = cm_v2(fd->umin + (fd->umax - fd->umin) * (i + 0.5) / SRC_N,
                               fd->vmin + (fd->vmax - fd->vmin) * (j + 0.5) / SRC_N);
            if (!cm_point_in_polygon(fd->uv + fd->loops[0].first, fd->loops[0].n, uv))
                continue;
            cm_vec3 P;
            if (face_domain_eval(&lm->brep, fd, uv.x, uv.y, &P, NULL, NULL) != CM_OK) {
                ok = 0;
                break;
            }
            verify_patch_foot(gs, 0.1 * tol, P, &have, &k, &u, &v);
            pr[np++] = (pair){k, u, v, P, uv};
        }
    int nsrc = np;
    /* each patch's grid, its source parameters from the nearest source pair */
    for (int kk = 0; kk < gs->npatch && ok; kk++)
        for (int i = 1; i < BACK_N; i++)
            for (int j = 1; j < BACK_N; j++) {
                cm_vec3 S;
                if (cm_greg_surface_eval(gs, kk, (double)i / BACK_N, (double)j / BACK_N, &S, NULL, NULL) != CM_OK) {
                    ok = 0;
                    break;
                }
                double best = HUGE_VAL;
                cm_vec2 suv = cm_v2(0.5 * (fd->umin + fd->umax), 0.5 * (fd->vmin + fd->vmax));
                for (int q = 0; q < nsrc; q++) {
                    double d = cm_norm2(cm_sub(pr[q].target, S));
                    if (d < best) {
                        best = d;
                        suv = pr[q].suv;
                    }
                }
                pr[np++] = (pair){kk, (double)i / BACK_N, (double)j / BACK_N, S, suv};
            }
    double worst = HUGE_VAL;
    for (int round = 0; round < ROUNDS && ok; round++) {
        /* targets of the back pairs: the foot on the source surface of the current patch point */
        for (int q = nsrc; q < np; q++) {
            cm_vec3 S;
            double su = pr[q].suv.x, sv = pr[q].suv.y, d;
            if (cm_greg_surface_eval(gs, pr[q].k, pr[q].u, pr[q].v, &S, NULL, NULL) != CM_OK ||
                cm_psurf_project_from(&fd->ps, S, &su, &sv, &d, NULL) != CM_OK) {
                pr[q].k = -1; /* no target: left out */
                continue;
            }
            /* a foot stuck in a local minimum: search again (as verify.c's back measure does), in the
               first round only (later ones start from that foot, and the surface moved little) */
            double ug, vg, dg;
            if (round == 0 && !(d < 0.5 * tol) && face_domain_project_global(fd, S, &ug, &vg, &dg) == CM_OK &&
                dg < d) {
                su = ug;
                sv = vg;
            }
            cm_vec3 T[3];
            if (cm_psurf_eval(&fd->ps, su, sv, T, NULL) != CM_OK) {
                pr[q].k = -1;
                continue;
            }
            pr[q].suv = cm_v2(su, sv);
            pr[q].target = T[0];
        }
        for (int kk = 0; kk < gs->npatch; kk++) {
            cm_vec3 dc[CM_FIT_MAX_COEF];
            solve_patch(pr, np, gs, kk, m, dc);
            for (int i = 0; i < m * m; i++)
                gs->corr[kk][i] = cm_add(gs->corr[kk][i], dc[i]);
        }
        /* the source pairs' feet on the corrected patches; the largest miss, as the fit sees it */
        worst = 0;
        for (int q = 0; q < nsrc; q++) {
            int h = 1, kq = pr[q].k;
            double uq = pr[q].u, vq = pr[q].v;
            double d = verify_patch_foot(gs, 0.1 * tol, pr[q].target, &h, &kq, &uq, &vq);
            worst = d > worst ? d : worst;
            pr[q].k = kq;
            pr[q].u = uq;
            pr[q].v = vq;
        }
    }
    /* the source grid still missed by the tolerance: no use quantising, rebuilding and measuring */
    if (!(worst < tol))
        ok = 0;
    if (ok) {
        cm_vec3 *c = malloc(sizeof *c * (size_t)(gs->npatch * m * m));
        for (int kk = 0; c && kk < gs->npatch; kk++)
            for (int i = 0; i < m * m; i++)
                c[kk * m * m + i] = gs->corr[kk][i];
        ok = c && fit_record_quantise(out, c, m, gs->npatch, tol, grid);
        free(c);
    }
    free(gs);
    free(pr);
    return ok;
}

int fit_record_quantise(fit_record *out, const cm_vec3 *c, int m, int npatch, double tol, double grid)
{
    /* the step: the grid's times the largest power of two at most tol / 256 */
    int e = (int)floor(log2(tol / 256.0 / grid));
    if (e < 0)
        e = 0;
    if (e > CM_FIT_MAX_EXP)
        e = CM_FIT_MAX_EXP;
    double step = ldexp(grid, e);
    out->m = m;
    out->npatch = npatch;
    out->exp = e;
    memset(out->q, 0, sizeof out->q);
    out->ntwist = 0; /* G1FIT's twists, when any, are put in by its trial */
    out->hint_mask = 0; /* (and GREGORY-FIT's hints by try_family) */
    for (int i = 0; i < npatch * m * m; i++) {
        double x[3] = {c[i].x, c[i].y, c[i].z};
        for (int a = 0; a < 3; a++) {
            double r = nearbyint(x[a] / step);
            if (!(fabs(r) <= CM_FIT_MAX_INT))
                return 0;
            out->q[i][a] = (int32_t)r;
        }
    }
    return 1;
}
