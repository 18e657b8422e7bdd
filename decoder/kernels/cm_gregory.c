/* cm_gregory.c - bicubic Gregory patch evaluation (spec §6.1). */
#include "cm/cm_gregory.h"

#include <stddef.h>

#include "cm/cm_bezier.h"

void cm_greg_blend(cm_vec3 A, cm_vec3 B, double a, double b, double a_u, double a_v, double b_u, double b_v,
                  cm_vec3 *X, cm_vec3 *X_u, cm_vec3 *X_v)
{
    double den = a + b;
    if (den == 0.0) {
        *X = cm_scale(cm_add(A, B), 0.5);
        *X_u = *X_v = cm_v3(0, 0, 0);
        return;
    }
    *X = cm_scale(cm_add(cm_scale(A, a), cm_scale(B, b)), 1.0 / den);
    /* d/dx [(aA+bB)/(a+b)] = (a_x b - a b_x)(A - B)/(a+b)^2 */
    cm_vec3 AmB = cm_sub(A, B);
    double den2 = den * den;
    *X_u = cm_scale(AmB, (a_u * b - a * b_u) / den2);
    *X_v = cm_scale(AmB, (a_v * b - a * b_v) / den2);
}

void cm_greg_eval(const cm_gregory *g, double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv)
{
    if (!(u > 0.0))
        u = 0.0;
    if (u > 1.0)
        u = 1.0;
    if (!(v > 0.0))
        v = 0.0;
    if (v > 1.0)
        v = 1.0;
    cm_vec3 P[4][4], Pu[4][4], Pv[4][4];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            P[i][j] = g->P[i][j];
            Pu[i][j] = Pv[i][j] = cm_v3(0, 0, 0);
        }
    /* weights of P_ij0 (a) and P_ij1 (b) with their (u,v) gradients */
    cm_greg_blend(g->I[0][0][0], g->I[0][0][1], u, v, 1, 0, 0, 1, &P[1][1], &Pu[1][1], &Pv[1][1]);
    cm_greg_blend(g->I[0][1][0], g->I[0][1][1], u, 1.0 - v, 1, 0, 0, -1, &P[1][2], &Pu[1][2], &Pv[1][2]);
    cm_greg_blend(g->I[1][0][0], g->I[1][0][1], 1.0 - u, v, -1, 0, 0, 1, &P[2][1], &Pu[2][1], &Pv[2][1]);
    cm_greg_blend(g->I[1][1][0], g->I[1][1][1], 1.0 - u, 1.0 - v, -1, 0, 0, -1, &P[2][2], &Pu[2][2], &Pv[2][2]);

    double Bu[4], dBu[4], Bv[4], dBv[4];
    cm_bernstein3(u, Bu, dBu);
    cm_bernstein3(v, Bv, dBv);
    cm_vec3 s = cm_v3(0, 0, 0), su = cm_v3(0, 0, 0), sv = cm_v3(0, 0, 0);
    for (int j = 0; j < 4; j++) {
        cm_vec3 row = cm_v3(0, 0, 0), row_u = cm_v3(0, 0, 0), row_v = cm_v3(0, 0, 0);
        for (int i = 0; i < 4; i++) {
            row = cm_axpy(row, Bu[i], P[i][j]);
            row_u = cm_axpy(cm_axpy(row_u, dBu[i], P[i][j]), Bu[i], Pu[i][j]);
            row_v = cm_axpy(row_v, Bu[i], Pv[i][j]);
        }
        s = cm_axpy(s, Bv[j], row);
        su = cm_axpy(su, Bv[j], row_u);
        sv = cm_axpy(cm_axpy(sv, dBv[j], row), Bv[j], row_v);
    }
    *S = s;
    if (Su)
        *Su = su;
    if (Sv)
        *Sv = sv;
}
