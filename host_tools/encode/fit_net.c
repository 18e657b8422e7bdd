/*
 * fit_net.c - least-squares fit of a fitted net's interior correction (NFILL, G1FIT; format 4.2;
 * the decoder's half is cm_fit_net_add, see fit_correction.h).
 *
 * GREGORY-FIT's idea on a B-spline net: the net is built from the face's boundary alone, and on
 * real models it often comes back a little over the tolerance (asitus__Pieza1's four- to six-sided
 * G1 faces at 1.0-1.2 times it, whichever net size: the interior of a face is not what its border
 * predicts).  The correction D (cm_patchfit.h) moves the net's interior points by D at their
 * Greville abscissae; the surface is linear in D's coefficients, so they are fitted as
 * GREGORY-FIT's are: point pairs (the source on a grid over the face with its foot on the net, the
 * net on a grid with its foot on the source surface inside the face), normal equations with a
 * small ridge, three rounds from the feet of the corrected net.
 */
#include "fit_correction.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_lsq.h"
#include "cm/cm_param.h"
#include "cm/cm_patchfit.h"
#include "verify.h"

#define SRC_N 21  /* source grid per direction */
#define BACK_N 10 /* net grid per direction: (i/BACK_N), i = 1..BACK_N-1 */
#define ROUNDS 3
#define RIDGE 1e-3 /* of the mean diagonal of the normal matrix */
#define NMAX CM_MAX_FIT_CTRL

typedef struct net_pair {
    int live;        /* 0: no foot found, left out */
    double u, v;     /* on the net */
    cm_vec3 target;  /* a point of the source surface */
    cm_vec2 suv;     /* its source parameters */
} net_pair;

typedef struct net_fit {
    int nu, nv, m;
    double U[NMAX + 4], V[NMAX + 4];
    cm_vec3 base[NMAX * NMAX], cur[NMAX * NMAX];
    cm_vec3 c[CM_FIT_MAX_COEF];
    double bu[NMAX][CM_FIT_MAX_M], bv[NMAX][CM_FIT_MAX_M]; /* D's basis at each row's Greville abscissa */
    cm_psurf ps;     /* the current net, for the feet */
} net_fit;

static double greville3(const double *K, int i)
{
    return (K[i + 1] + K[i + 2] + K[i + 3]) / 3.0;
}

/* the current net: the base plus the correction, as the decoder adds it */
static int net_update(net_fit *F)
{
    memcpy(F->cur, F->base, sizeof(cm_vec3) * (size_t)(F->nu * F->nv));
    cm_fit_net_add(F->cur, F->nu, F->nv, F->U, F->V, F->c, F->m);
    cm_surf s = {3, 3, F->nu, F->nv, F->U, F->V, F->cur, NULL};
    F->ps.s = s; /* over the net's whole domain, closed in neither direction (as verify_face sees it) */
    F->ps.u0 = F->U[3];
    F->ps.u1 = F->U[F->nu];
    F->ps.v0 = F->V[3];
    F->ps.v1 = F->V[F->nv];
    F->ps.closed_u = F->ps.closed_v = 0;
    return 1;
}

/* the basis of each coefficient at (u,v): sum over interior points of N_i(u) N_j(v) b_k(xi_i) b_l(eta_j) */
static int phi_at(const net_fit *F, double u, double v, double *phi)
{
    int m = F->m, su = cm_bspl_find_span(F->nu, 3, F->U, u), sv = cm_bspl_find_span(F->nv, 3, F->V, v);
    double Nu[4], Nv[4];
    if (cm_bspl_basis(su, u, 3, F->U, Nu, NULL) != CM_OK || cm_bspl_basis(sv, v, 3, F->V, Nv, NULL) != CM_OK)
        return 0;
    for (int k = 0; k < m * m; k++)
        phi[k] = 0.0;
    for (int a = 0; a < 4; a++) {
        int i = su - 3 + a;
        if (i < 2 || i > F->nu - 3)
            continue;
        for (int b = 0; b < 4; b++) {
            int j = sv - 3 + b;
            if (j < 2 || j > F->nv - 3)
                continue;
            double w = Nu[a] * Nv[b];
            for (int k = 0; k < m; k++)
                for (int l = 0; l < m; l++)
                    phi[k * m + l] += w * F->bu[i][k] * F->bv[j][l];
        }
    }
    return 1;
}

/* one least-squares step on the pairs: the coefficients' change added to F->c */
static void solve_step(net_fit *F, const net_pair *pr, int np)
{
    enum { N = CM_FIT_MAX_COEF };
    double A[N * N];
    cm_vec3 b[N];
    int n = F->m * F->m, w = n - 1, used = 0;
    memset(A, 0, sizeof A);
    for (int i = 0; i < n; i++)
        b[i] = cm_v3(0, 0, 0);
    for (int q = 0; q < np; q++) {
        double phi[N];
        cm_vec3 d[3];
        if (!pr[q].live || !phi_at(F, pr[q].u, pr[q].v, phi) || cm_psurf_eval(&F->ps, pr[q].u, pr[q].v, d, NULL) != CM_OK)
            continue;
        cm_vec3 r = cm_sub(pr[q].target, d[0]);
        for (int a = 0; a < n; a++) {
            b[a] = cm_axpy(b[a], phi[a], r);
            for (int c = 0; c <= a; c++)
                A[CM_BAND_IDX(a, c, w)] += phi[a] * phi[c];
        }
        used++;
    }
    if (used == 0)
        return;
    double tr = 0;
    for (int i = 0; i < n; i++)
        tr += A[CM_BAND_IDX(i, i, w)];
    if (!(tr > 0))
        return;
    for (int i = 0; i < n; i++)
        A[CM_BAND_IDX(i, i, w)] += RIDGE * tr / n;
    if (cm_chol_band(A, n, w, NULL) != CM_OK)
        return;
    cm_chol_band_solve3(A, n, w, b);
    for (int i = 0; i < n; i++)
        F->c[i] = cm_add(F->c[i], b[i]);
}

int fit_net_correction(const loaded_model *lm, int bface, const cm_surf *net, int m, double tol, double grid,
                       fit_record *out)
{
    const face_domain *fd = &lm->fds[bface];
    if (!fd->uv || m < 1 || m > CM_FIT_MAX_M || net->p != 3 || net->q != 3 || net->w || net->nu > NMAX ||
        net->nv > NMAX || net->nu - 4 < m || net->nv - 4 < m)
        return 0;
    net_fit *F = malloc(sizeof *F);
    net_pair *pr = malloc(sizeof *pr * (SRC_N * SRC_N + BACK_N * BACK_N));
    if (!F || !pr) {
        free(F);
        free(pr);
        return 0;
    }
    F->nu = net->nu;
    F->nv = net->nv;
    F->m = m;
    memcpy(F->U, net->U, sizeof(double) * (size_t)(net->nu + 4));
    memcpy(F->V, net->V, sizeof(double) * (size_t)(net->nv + 4));
    memcpy(F->base, net->ctrl, sizeof(cm_vec3) * (size_t)(net->nu * net->nv));
    memset(F->c, 0, sizeof F->c);
    for (int i = 0; i < F->nu; i++)
        cm_fit_basis(m, greville3(F->U, i), F->bu[i], NULL);
    for (int j = 0; j < F->nv; j++)
        cm_fit_basis(m, greville3(F->V, j), F->bv[j], NULL);
    int ok = net_update(F), np = 0;
    /* the source grid inside the outer loop, each with its foot on the net (a serpentine: each foot
       starts from the one before, the first from a grid) */
    double u = 0.5, v = 0.5;
    int have = 0;
    for (int i = 0; i < SRC_N && ok; i++)
        for (int jj = 0; jj < SRC_N; jj++) {
            int j = i % 2 ? SRC_N - 1 - jj : jj;
            cm_vec2 uv = cm_v2(fd->umin + (fd->umax - fd->umin) * (i + 0.5) / SRC_N,
                               fd->vmin + (fd->vmax - fd->vmin) * (j + 0.5) / SRC_N);
            if (!face_domain_inside(fd, uv))
                continue;
            cm_vec3 P;
            if (face_domain_eval(&lm->brep, fd, uv.x, uv.y, &P, NULL, NULL) != CM_OK) {
                ok = 0;
                break;
            }
            verify_surf_foot(&F->ps.s, 0.1 * tol, P, &have, &u, &v);
            pr[np++] = (net_pair){1, u, v, P, uv};
        }
    int nsrc = np;
    if (nsrc == 0)
        ok = 0;
    /* the net's grid, its source parameters from the nearest source pair */
    for (int i = 1; i < BACK_N && ok; i++)
        for (int j = 1; j < BACK_N; j++) {
            cm_vec3 d[3];
            if (cm_psurf_eval(&F->ps, (double)i / BACK_N, (double)j / BACK_N, d, NULL) != CM_OK) {
                ok = 0;
                break;
            }
            double best = HUGE_VAL;
            cm_vec2 suv = pr[0].suv;
            for (int q = 0; q < nsrc; q++) {
                double dd = cm_norm2(cm_sub(pr[q].target, d[0]));
                if (dd < best) {
                    best = dd;
                    suv = pr[q].suv;
                }
            }
            pr[np++] = (net_pair){1, (double)i / BACK_N, (double)j / BACK_N, d[0], suv};
        }
    double worst = HUGE_VAL;
    for (int round = 0; round < ROUNDS && ok; round++) {
        /* the net pairs' targets: the foot on the source surface, kept only inside the face (an
           NFILL net reaches past it) */
        for (int q = nsrc; q < np; q++) {
            cm_vec3 d[3], T[3];
            double su = pr[q].suv.x, sv = pr[q].suv.y, dist;
            pr[q].live = 0;
            if (cm_psurf_eval(&F->ps, pr[q].u, pr[q].v, d, NULL) != CM_OK ||
                cm_psurf_project_from(&fd->ps, d[0], &su, &sv, &dist, NULL) != CM_OK ||
                !face_domain_inside(fd, cm_v2(su, sv)) || cm_psurf_eval(&fd->ps, su, sv, T, NULL) != CM_OK)
                continue;
            pr[q].live = 1;
            pr[q].suv = cm_v2(su, sv);
            pr[q].target = T[0];
        }
        solve_step(F, pr, np);
        if (!net_update(F)) {
            ok = 0;
            break;
        }
        /* the source pairs' feet on the corrected net; the largest miss, as the fit sees it */
        worst = 0;
        have = 0;
        for (int q = 0; q < nsrc; q++) {
            double d = verify_surf_foot(&F->ps.s, 0.1 * tol, pr[q].target, &have, &u, &v);
            pr[q].u = u;
            pr[q].v = v;
            worst = d > worst ? d : worst;
        }
    }
    if (!(worst < tol))
        ok = 0;
    if (ok)
        ok = fit_record_quantise(out, F->c, m, 1, tol, grid);
    free(F);
    free(pr);
    return ok;
}
