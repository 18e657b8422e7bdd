/* cm_gregface.c - GREGORY surface construction (spec §5.4, §6.2-§6.5). */
#include "cm/cm_gregface.h"

#include <stddef.h>
#include <string.h>

#include "cm/cm_limits_info.h"
#include "cm/cm_project.h"

/* spec 6.2: the 2x2 system is singular below this relative determinant */
#define CROSS_DET_REL 1e-20
/* spec 6.5: the fan is linear when the two edge directions are closer than this cosine */
#define FAN_LINEAR_COS (1.0 - 1e-12)

static const cm_vec3 zero3 = {0.0, 0.0, 0.0};

/* unit(v) into *out if |v| > eps; 0 (and *out untouched) otherwise */
static int unit_chk(cm_vec3 v, double eps, cm_vec3 *out)
{
    int ok;
    cm_vec3 r = cm_unit_or(v, eps, zero3, &ok);
    if (ok)
        *out = r;
    return ok;
}

/* v minus its component along the unit vector n */
static cm_vec3 reject(cm_vec3 v, cm_vec3 n)
{
    return cm_sub(v, cm_scale(n, cm_dot(v, n)));
}

static cm_err degenerate(cm_status *st, const char *where)
{
    return cm_fail(st, CM_E_DEGENERATE, where);
}

cm_err cm_greg_edge_basis(const cm_cubic *c, cm_vec3 Ns, cm_vec3 Ne, double eps_len, cm_vec3 *As, cm_vec3 *Ae,
                          cm_status *st)
{
    cm_vec3 ts, te;
    if (!unit_chk(cm_sub(c->c[1], c->c[0]), eps_len, &ts) && !unit_chk(cm_sub(c->c[2], c->c[1]), eps_len, &ts))
        return degenerate(st, "gregface: zero start tangent");
    if (!unit_chk(cm_sub(c->c[3], c->c[2]), eps_len, &te) && !unit_chk(cm_sub(c->c[2], c->c[1]), eps_len, &te))
        return degenerate(st, "gregface: zero end tangent");
    if (!unit_chk(cm_cross(Ns, ts), CM_GREG_EPS_DIR, As) || !unit_chk(cm_cross(Ne, te), CM_GREG_EPS_DIR, Ae))
        return degenerate(st, "gregface: basis normal parallel to the edge");
    return CM_OK;
}

cm_err cm_greg_fit_kh(cm_vec3 A, cm_vec3 c, cm_vec3 b, double eps_len, double *k, double *h, cm_status *st)
{
    *k = 0.0;
    *h = 0.0;
    if (!(cm_norm(b) > eps_len))
        return CM_OK; /* degenerate corner: k = h = 0 */
    double aa = cm_dot(A, A), cc = cm_dot(c, c), ac = cm_dot(A, c);
    double ab = cm_dot(A, b), cb = cm_dot(c, b);
    if (!(aa > 0.0))
        return degenerate(st, "gregface: zero basis vector");
    if (!(cm_norm(c) > eps_len)) {
        *k = ab / aa; /* rank one: h is free, take 0 */
        return CM_OK;
    }
    double det = aa * cc - ac * ac;
    if (!(det >= CROSS_DET_REL * aa * cc) || !(det > 0.0))
        return degenerate(st, "gregface: edge tangent to its basis vector");
    *k = (cc * ab - ac * cb) / det;
    *h = (aa * cb - ac * ab) / det;
    return CM_OK;
}

cm_err cm_greg_cross(const cm_cubic *c, cm_vec3 As, cm_vec3 Ae, cm_vec3 b0, cm_vec3 b3, double eps_len, cm_vec3 *X1,
                     cm_vec3 *X2, double kh[4], cm_status *st)
{
    cm_vec3 c0 = cm_sub(c->c[1], c->c[0]), c1 = cm_sub(c->c[2], c->c[1]), c2 = cm_sub(c->c[3], c->c[2]);
    double k0, h0, k1, h1;
    cm_err e;
    if ((e = cm_greg_fit_kh(As, c0, b0, eps_len, &k0, &h0, st)) != CM_OK)
        return e;
    if ((e = cm_greg_fit_kh(Ae, c2, b3, eps_len, &k1, &h1, st)) != CM_OK)
        return e;
    cm_vec3 A1 = cm_scale(cm_add(cm_scale(As, 2.0), Ae), 1.0 / 3.0);
    cm_vec3 A2 = cm_scale(cm_add(As, cm_scale(Ae, 2.0)), 1.0 / 3.0);
    double dk = (k1 - k0) / 3.0;
    /* b1 = (k1-k0)/3 As + k0 A1 + (2/3)h0 c1 + (1/3)h1 c0 ; b2 = k1 A2 - (k1-k0)/3 Ae + (1/3)h0 c2 + (2/3)h1 c1 */
    cm_vec3 b1 = cm_scale(As, dk);
    b1 = cm_axpy(b1, k0, A1);
    b1 = cm_axpy(b1, (2.0 / 3.0) * h0, c1);
    b1 = cm_axpy(b1, (1.0 / 3.0) * h1, c0);
    cm_vec3 b2 = cm_scale(A2, k1);
    b2 = cm_axpy(b2, -dk, Ae);
    b2 = cm_axpy(b2, (1.0 / 3.0) * h0, c2);
    b2 = cm_axpy(b2, (2.0 / 3.0) * h1, c1);
    *X1 = cm_add(c->c[1], b1);
    *X2 = cm_add(c->c[2], b2);
    if (kh) {
        kh[0] = k0;
        kh[1] = h0;
        kh[2] = k1;
        kh[3] = h1;
    }
    return CM_OK;
}

cm_err cm_greg_quad(const cm_greg_quad_side s[4], int skip_side3, double eps_len, cm_gregory *g, cm_status *st)
{
    /* boundary, in the order of spec 6.3 */
    for (int i = 0; i < 4; i++)
        g->P[i][0] = s[0].c.c[i];
    for (int l = 0; l < 4; l++)
        g->P[3][l] = s[1].c.c[l];
    for (int i = 0; i < 4; i++)
        g->P[i][3] = s[2].c.c[3 - i];
    for (int l = 0; l < 4; l++)
        g->P[0][l] = s[3].c.c[3 - l];
    for (int k = 0; k < 4; k++) {
        if (k == 3 && skip_side3)
            break;
        const cm_cubic *prev = &s[(k + 3) & 3].c, *next = &s[(k + 1) & 3].c;
        cm_vec3 b0 = cm_sub(prev->c[2], prev->c[3]);
        cm_vec3 b3 = cm_sub(next->c[1], next->c[0]);
        cm_vec3 X1, X2;
        cm_err e = cm_greg_cross(&s[k].c, s[k].As, s[k].Ae, b0, b3, eps_len, &X1, &X2, NULL, st);
        if (e != CM_OK)
            return e;
        switch (k) {
        case 0: /* v = 0 */
            g->I[0][0][0] = X1;
            g->I[1][0][0] = X2;
            break;
        case 1: /* u = 1 */
            g->I[1][0][1] = X1;
            g->I[1][1][1] = X2;
            break;
        case 2: /* v = 1 */
            g->I[1][1][0] = X1;
            g->I[0][1][0] = X2;
            break;
        default: /* u = 0 */
            g->I[0][1][1] = X1;
            g->I[0][0][1] = X2;
            break;
        }
    }
    return CM_OK;
}

double cm_greg_arc_handle(cm_vec3 P, cm_vec3 t0, cm_vec3 Q, cm_vec3 t1)
{
    double c = cm_dot(t0, t1);
    if (!(c > -1.0))
        c = -1.0;
    if (c > 1.0)
        c = 1.0;
    return (2.0 / 3.0) * cm_dist(Q, P) / (1.0 + sqrt((1.0 + c) / 2.0));
}

/* orientation check of spec 6.3 */
static cm_err check_orientation(const cm_gregory *g, cm_vec3 nF, cm_status *st)
{
    cm_vec3 S, Su, Sv;
    cm_greg_eval(g, 0.5, 0.5, &S, &Su, &Sv);
    if (!(cm_dot(cm_cross(Su, Sv), nF) > 0.0))
        return degenerate(st, "gregface: orientation check");
    return CM_OK;
}

/* ---- layout 0 (spec 6.3) ---- */
static cm_err build_quad_face(const cm_greg_input *in, cm_greg_surface *out, cm_status *st)
{
    cm_greg_quad_side q[4];
    for (int k = 0; k < 4; k++) {
        q[k].c = in->side[k].c;
        cm_err e = cm_greg_edge_basis(&q[k].c, in->side[k].Ns, in->side[k].Ne, in->eps_len, &q[k].As, &q[k].Ae, st);
        if (e != CM_OK)
            return e;
    }
    cm_err e = cm_greg_quad(q, 0, in->eps_len, &out->g[0], st);
    if (e != CM_OK)
        return e;
    out->npatch = 1;
    return check_orientation(&out->g[0], in->nF, st);
}

cm_err cm_greg_fan(cm_vec3 e0, cm_vec3 e2, double eps, cm_vec3 *f1, cm_vec3 *f2, cm_status *st)
{
    cm_vec3 u0, u2;
    if (!unit_chk(e0, eps, &u0) || !unit_chk(e2, eps, &u2))
        return degenerate(st, "gregface: zero edge at the collapsed vertex");
    double gam = cm_dot(u0, u2);
    if (gam > FAN_LINEAR_COS) {
        *f1 = cm_add(e0, cm_scale(cm_sub(e2, e0), 1.0 / 3.0));
        *f2 = cm_add(e2, cm_scale(cm_sub(e0, e2), 1.0 / 3.0));
        return CM_OK;
    }
    cm_vec3 w0, w2;
    if (!unit_chk(cm_sub(u2, cm_scale(u0, gam)), CM_GREG_EPS_DIR, &w0) ||
        !unit_chk(cm_sub(u0, cm_scale(u2, gam)), CM_GREG_EPS_DIR, &w2))
        return degenerate(st, "gregface: flat collapsed corner");
    double kap = (4.0 / 3.0) * sqrt((1.0 - gam) / 2.0) / (1.0 + sqrt((1.0 + gam) / 2.0));
    *f1 = cm_axpy(e0, kap * cm_norm(e0), w0);
    *f2 = cm_axpy(e2, kap * cm_norm(e2), w2);
    return CM_OK;
}

/* ---- layout 2 (spec 6.5): degenerate quad collapsed at V_j, circular fan on u = 0 ---- */
static cm_err build_degen_face(const cm_greg_input *in, int j, cm_greg_surface *out, cm_status *st)
{
    cm_greg_quad_side q[4];
    double eps = in->eps_len;
    for (int m = 0; m < 3; m++) {
        const cm_greg_side *sd = &in->side[(j + m) % 3];
        q[m].c = sd->c;
        cm_err e = cm_greg_edge_basis(&q[m].c, sd->Ns, sd->Ne, eps, &q[m].As, &q[m].Ae, st);
        if (e != CM_OK)
            return e;
    }
    cm_vec3 Vj = q[0].c.c[0];
    for (int l = 0; l < 4; l++)
        q[3].c.c[l] = Vj;
    q[3].As = q[3].Ae = zero3;
    cm_gregory *g = &out->g[0];
    cm_err e = cm_greg_quad(q, 1, eps, g, st);
    if (e != CM_OK)
        return e;
    /* the circular fan */
    cm_vec3 f1, f2;
    if ((e = cm_greg_fan(cm_sub(q[0].c.c[1], Vj), cm_sub(q[2].c.c[2], Vj), eps, &f1, &f2, st)) != CM_OK)
        return e;
    g->I[0][0][1] = cm_add(Vj, f1);
    g->I[0][1][1] = cm_add(Vj, f2);
    out->npatch = 1;
    return check_orientation(g, in->nF, st);
}

/* ---- layout 1 (spec 6.4): N quads around a centre ---- */

/* temporaries of the N-split (kept apart from the frame of the sub-patch builder) */
typedef struct split_ws {
    cm_cubic ha[CM_MAX_SIDES], hb[CM_MAX_SIDES]; /* H_k^a, H_k^b */
    cm_vec3 A0[CM_MAX_SIDES], A1[CM_MAX_SIDES];  /* A_k(0), A_k(1) */
    cm_vec3 beta[CM_MAX_SIDES], nmid[CM_MAX_SIDES], T[CM_MAX_SIDES], U[CM_MAX_SIDES];
} split_ws;

static cm_err split_mid(const cm_greg_input *in, split_ws *w, cm_status *st)
{
    int n = in->n;
    double eps = in->eps_len;
    for (int k = 0; k < n; k++) {
        const cm_cubic *c = &in->side[k].c;
        const cm_cubic *prev = &in->side[(k + n - 1) % n].c, *next = &in->side[(k + 1) % n].c;
        cm_err e = cm_greg_edge_basis(c, in->side[k].Ns, in->side[k].Ne, eps, &w->A0[k], &w->A1[k], st);
        if (e != CM_OK)
            return e;
        cm_vec3 X1, X2;
        double kh[4];
        e = cm_greg_cross(c, w->A0[k], w->A1[k], cm_sub(prev->c[2], prev->c[3]), cm_sub(next->c[1], next->c[0]), eps,
                          &X1, &X2, kh, st);
        if (e != CM_OK)
            return e;
        cm_cubic_split(c, CM_GREG_SPLIT_T, &w->ha[k], &w->hb[k]);
        cm_vec3 c0 = cm_sub(c->c[1], c->c[0]), c1 = cm_sub(c->c[2], c->c[1]), c2 = cm_sub(c->c[3], c->c[2]);
        cm_vec3 dmid = cm_add(cm_add(c0, cm_scale(c1, 2.0)), c2); /* c0 + 2c1 + c2 = (4/3) C'(1/2) */
        cm_vec3 Ah = cm_scale(cm_add(w->A0[k], w->A1[k]), 0.5);
        double km = (kh[0] + kh[2]) / 2.0, hm = (kh[1] + kh[3]) / 2.0;
        w->beta[k] = cm_add(cm_scale(Ah, km), cm_scale(dmid, hm / 4.0));
        cm_vec3 tmid;
        if (!unit_chk(dmid, eps, &tmid))
            return degenerate(st, "gregface: zero mid tangent");
        if (!unit_chk(w->beta[k], eps, &w->T[k]))
            return degenerate(st, "gregface: zero mid cross vector");
        if (!unit_chk(cm_cross(tmid, w->beta[k]), eps, &w->nmid[k]))
            return degenerate(st, "gregface: mid cross vector along the edge");
    }
    return CM_OK;
}

cm_err cm_greg_spoke_centre(int n, const cm_vec3 *Mk, const cm_vec3 *T, const cm_vec3 *nmid, const cm_vec3 *V,
                            const cm_vec3 *corner_normal, double eps, cm_vec3 *U, cm_greg_surface *out,
                            cm_status *st)
{
    double r;
    switch (n) {
    case 3: r = CM_GREG_SPOKE_R3; break;
    case 5: r = CM_GREG_SPOKE_R5; break;
    case 7: r = CM_GREG_SPOKE_R7; break;
    default: r = 0.5; break; /* even N (n <= CM_HARD_MAX_SIDES = 8) */
    }
    cm_vec3 sum = zero3, nsum = zero3;
    for (int k = 0; k < n; k++) {
        cm_vec3 M = Mk[k], O, tau;
        if ((n & 1) == 0) {
            int o = (k + n / 2) % n;
            O = Mk[o];
            tau = cm_neg(T[o]);
        } else {
            int vj = (k + (n + 1) / 2) % n;
            O = V[vj];
            cm_vec3 d;
            if (!unit_chk(reject(cm_sub(M, O), corner_normal[vj]), eps, &d))
                return degenerate(st, "gregface: short spoke projection");
            tau = cm_neg(d);
        }
        double l = cm_greg_arc_handle(M, T[k], O, tau);
        cm_cubic spoke = {{M, cm_axpy(M, l, T[k]), cm_axpy(O, -l, tau), O}};
        cm_vec3 d[3];
        cm_cubic_eval(&spoke, r, d);
        sum = cm_add(sum, d[0]);
        nsum = cm_add(nsum, nmid[k]);
    }
    cm_vec3 C = cm_scale(sum, 1.0 / (double)n), nC;
    if (!unit_chk(nsum, CM_GREG_EPS_DIR, &nC))
        return degenerate(st, "gregface: centre normal");
    out->centre = C;
    out->centre_normal = nC;
    for (int k = 0; k < n; k++) {
        cm_vec3 M = Mk[k], d = cm_sub(M, C);
        if (!(cm_norm(d) > eps) || !unit_chk(reject(d, nC), eps, &U[k]))
            return degenerate(st, "gregface: internal curve too short");
        double l = cm_greg_arc_handle(M, T[k], C, cm_neg(U[k]));
        cm_cubic I = {{M, cm_axpy(M, l, T[k]), cm_axpy(C, l, U[k]), C}};
        out->inner[k] = I;
    }
    return CM_OK;
}

static cm_err split_centre(const cm_greg_input *in, split_ws *w, cm_greg_surface *out, cm_status *st)
{
    cm_vec3 M[CM_MAX_SIDES], V[CM_MAX_SIDES];
    for (int k = 0; k < in->n; k++) {
        M[k] = w->ha[k].c[3];
        V[k] = in->side[k].c.c[0];
    }
    return cm_greg_spoke_centre(in->n, M, w->T, w->nmid, V, in->corner_normal, in->eps_len, w->U, out, st);
}

static cm_err split_patches(const cm_greg_input *in, const split_ws *w, cm_greg_surface *out, cm_status *st)
{
    int n = in->n;
    cm_vec3 nC = out->centre_normal;
    for (int k = 0; k < n; k++) {
        int p = (k + n - 1) % n;
        cm_greg_quad_side q[4];
        q[0].c = w->ha[k];
        q[0].As = w->A0[k];
        q[0].Ae = cm_scale(cm_add(w->A0[k], w->A1[k]), 0.5);
        q[1].c = out->inner[k];
        if (!unit_chk(cm_cross(w->nmid[k], w->T[k]), CM_GREG_EPS_DIR, &q[1].As) ||
            !unit_chk(cm_cross(nC, cm_neg(w->U[k])), CM_GREG_EPS_DIR, &q[1].Ae))
            return degenerate(st, "gregface: internal basis");
        q[2].c = cm_cubic_reverse(&out->inner[p]);
        if (!unit_chk(cm_cross(nC, w->U[p]), CM_GREG_EPS_DIR, &q[2].As) ||
            !unit_chk(cm_cross(w->nmid[p], cm_neg(w->T[p])), CM_GREG_EPS_DIR, &q[2].Ae))
            return degenerate(st, "gregface: internal basis");
        q[3].c = w->hb[p];
        q[3].As = cm_scale(cm_add(w->A0[p], w->A1[p]), 0.5);
        q[3].Ae = w->A1[p];
        cm_err e = cm_greg_quad(q, 0, in->eps_len, &out->g[k], st);
        if (e != CM_OK)
            return e;
        if ((e = check_orientation(&out->g[k], in->nF, st)) != CM_OK)
            return e;
    }
    out->npatch = n;
    out->t_split = CM_GREG_SPLIT_T;
    return CM_OK;
}

static cm_err build_split_face(const cm_greg_input *in, cm_greg_surface *out, cm_status *st)
{
    split_ws w;
    cm_err e = split_mid(in, &w, st);
    if (e == CM_OK)
        e = split_centre(in, &w, out, st);
    if (e == CM_OK)
        e = split_patches(in, &w, out, st);
    return e;
}

static int input_finite(const cm_greg_input *in, int exact)
{
    for (int k = 0; k < in->n; k++) {
        const cm_greg_side *s = &in->side[k];
        for (int i = 0; i < 4 && !exact; i++)
            if (!cm_finite3(s->c.c[i]))
                return 0;
        if (!cm_finite3(s->Ns) || !cm_finite3(s->Ne) || !cm_finite3(in->corner_normal[k]))
            return 0;
    }
    return cm_finite3(in->nF);
}

int cm_greg_joined_ok(unsigned bits, int n)
{
    int c = 0, run = 0, longest = 0;
    if (n < 5 || n > CM_GREG_JOINED_MAX_EDGES || (bits >> n) != 0)
        return 0;
    for (int k = 0; k < 2 * n; k++) { /* round the loop twice: the side that wraps is counted too */
        int corner = (int)((bits >> (k % n)) & 1u);
        c += k < n ? corner : 0;
        run = corner ? 1 : run + 1;
        longest = run > longest ? run : longest;
    }
    return c == CM_GREG_JOINED_CORNERS && longest <= CM_GREG_JOINED_MAX_PIECES;
}

void cm_greg_surface_reset(cm_greg_surface *out, int layout, int n, int j, int exact)
{
    /* zero what the layout can use: the header, its patches and their corrections (every reader,
       evaluation and checksum alike, stops at npatch: n for layout 1, else 1).  The whole struct is
       45.8 KB on the terminal, most of it patches a 4-sided face never has: 3 % of a GREGORY model's
       decode went to clearing them */
    int np = layout == CM_GREG_LAYOUT_SPLIT ? n : 1;
    np = np < 1 ? 1 : (np > CM_MAX_GREG ? CM_MAX_GREG : np);
    memset(out, 0, offsetof(cm_greg_surface, e));
    memset(out->e, 0, (size_t)np * (sizeof out->e[0] > sizeof out->g[0] ? sizeof out->e[0] : sizeof out->g[0]));
    memset(out->inner, 0, sizeof out->inner);
    out->centre = out->centre_normal = cm_v3(0, 0, 0);
    out->fit = 0;
    memset(out->corr, 0, (size_t)np * sizeof out->corr[0]);
    out->layout = layout;
    out->n = n;
    out->j = layout == CM_GREG_LAYOUT_DEGEN || layout == CM_GREG_LAYOUT_JOINED ? j : 0;
    out->exact = exact;
}

cm_err cm_greg_begin(const cm_greg_input *in, int layout, int j, int exact, cm_greg_surface *out, cm_status *st)
{
    if (!in || !out)
        return cm_fail(st, CM_E_ARG, __func__);
    int n = in->n;
    cm_greg_surface_reset(out, layout, n, j, exact);
    if (!(in->eps_len >= 0.0) || !isfinite(in->eps_len))
        return cm_fail(st, CM_E_ARG, "gregface: eps_len");
    if (n > (layout == CM_GREG_LAYOUT_JOINED ? CM_GREG_MAX_INPUT : CM_MAX_SIDES))
        return cm_fail_limit(st, CM_LIMIT_MAX_SIDES, (uint64_t)n, CM_MAX_SIDES, "gregface: sides");
    if (n < 3)
        return cm_fail(st, CM_E_RANGE, "gregface: fewer than 3 sides");
    switch (layout) {
    case CM_GREG_LAYOUT_QUAD:
        if (n != 4)
            return cm_fail(st, CM_E_RANGE, "gregface: layout 0 needs 4 sides");
        break;
    case CM_GREG_LAYOUT_SPLIT:
        if (n > CM_MAX_GREG)
            return cm_fail_limit(st, CM_LIMIT_MAX_GREG, (uint64_t)n, CM_MAX_GREG, "gregface: N-split patches");
        break;
    case CM_GREG_LAYOUT_DEGEN:
        if (n != 3)
            return cm_fail(st, CM_E_RANGE, "gregface: layout 2 needs 3 sides");
        if (j < 0 || j > 2)
            return cm_fail(st, CM_E_RANGE, "gregface: layout 2 vertex index");
        break;
    case CM_GREG_LAYOUT_JOINED: {
        if (!exact)
            return cm_fail(st, CM_E_UNSUPPORTED, "gregface: layout 3 joins exact edges only");
        if (n < 5)
            return cm_fail(st, CM_E_RANGE, "gregface: layout 3 needs 5 or more edges");
        if (j < 0 || !cm_greg_joined_ok((unsigned)j, n))
            return cm_fail(st, CM_E_RANGE, "gregface: layout 3 corners");
        break;
    }
    default:
        return cm_fail(st, CM_E_RANGE, "gregface: unknown layout");
    }
    if (!input_finite(in, exact))
        return cm_fail(st, CM_E_NONFINITE, "gregface: input");
    return CM_OK;
}

cm_err cm_greg_build(const cm_greg_input *in, int layout, int j, cm_greg_surface *out, cm_status *st)
{
    cm_err e = cm_greg_begin(in, layout, j, 0, out, st);
    if (e != CM_OK)
        return e;
    if (layout == CM_GREG_LAYOUT_QUAD)
        e = build_quad_face(in, out, st);
    else if (layout == CM_GREG_LAYOUT_SPLIT)
        e = build_split_face(in, out, st);
    else
        e = build_degen_face(in, j, out, st);
    if (e != CM_OK)
        cm_greg_surface_reset(out, layout, in->n, j, 0);
    return e;
}

double cm_greg_surface_project(const cm_greg_surface *s, cm_vec3 p, int *patch, double *u, double *v)
{
    double best = HUGE_VAL, bu = 0.0, bv = 0.0;
    int bk = -1;
    int np = s->npatch < CM_MAX_GREG ? s->npatch : CM_MAX_GREG;
    for (int k = 0; k < np; k++) {
        cm_patch pa = s->exact ? cm_patch_of_egreg(&s->e[k]) : cm_patch_of_gregory(&s->g[k]);
        pa.corr = s->corr[k];
        pa.fit = s->fit;
        double pu, pv, d;
        if (cm_patch_project(&pa, p, &pu, &pv, &d, NULL) != CM_OK)
            continue; /* cannot happen for a Gregory patch */
        if (bk < 0 || d < best) {
            best = d;
            bu = pu;
            bv = pv;
            bk = k;
        }
    }
    if (patch)
        *patch = bk;
    if (u)
        *u = bu;
    if (v)
        *v = bv;
    return best;
}

cm_err cm_greg_surface_eval(const cm_greg_surface *s, int k, double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv)
{
    return cm_greg_surface_eval_memo(s, k, u, v, S, Su, Sv, NULL);
}

cm_err cm_greg_surface_eval_memo(const cm_greg_surface *s, int k, double u, double v, cm_vec3 *S, cm_vec3 *Su,
                                 cm_vec3 *Sv, cm_egreg_memo *memo)
{
    cm_err e = CM_OK;
    if (k >= 0 && k < s->npatch && k < CM_MAX_GREG) {
        if (!s->exact) {
            cm_greg_eval(&s->g[k], u, v, S, Su, Sv);
            cm_fit_add(s->corr[k], s->fit, u, v, S, Su, Sv);
            return CM_OK;
        }
        if ((e = cm_egreg_eval_memo(&s->e[k], u, v, S, Su, Sv, memo, NULL)) == CM_OK) {
            cm_fit_add(s->corr[k], s->fit, u, v, S, Su, Sv);
            return CM_OK;
        }
    }
    *S = zero3;
    if (Su)
        *Su = zero3;
    if (Sv)
        *Sv = zero3;
    return e;
}

#define FNV_OFFSET 2166136261u
#define FNV_PRIME 16777619u

static uint32_t fnv_double(uint32_t h, double x)
{
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    for (int b = 0; b < 8; b++) {
        h ^= (uint32_t)((bits >> (8 * b)) & 0xFFu);
        h *= FNV_PRIME;
    }
    return h;
}

static uint32_t fnv_vec(uint32_t h, cm_vec3 p)
{
    h = fnv_double(h, p.x);
    h = fnv_double(h, p.y);
    return fnv_double(h, p.z);
}

/* an exact patch: per side its kind, edge, range, cubic, fan and cross data, then the corner data
   (the curve itself is the model's, checked by the CRCs; its number says which) */
int cm_greg_surface_turns(const cm_greg_surface *s)
{
    if (!s || !s->exact)
        return 0;
    for (int k = 0; k < s->npatch && k < CM_MAX_GREG; k++)
        for (int i = 0; i < 4; i++) {
            const cm_egreg_side *sd = &s->e[k].side[i];
            if (sd->tb.mode != CM_EGREG_TURN_NONE)
                return 1;
            for (int j = 0; j < sd->npiece && j < CM_EGREG_MAX_PIECES && sd->kind == CM_EGREG_SIDE_CHAIN; j++)
                if (sd->piece[j].tb.mode != CM_EGREG_TURN_NONE)
                    return 1;
        }
    return 0;
}

/* a turning basis in the checksum: nothing for the linear one, so that older files' sums stay */
static uint32_t turn_checksum(uint32_t h, const cm_egreg_turn *tb)
{
    if (tb->mode == CM_EGREG_TURN_NONE)
        return h;
    h = fnv_double(h, (double)tb->mode);
    if (tb->mode == CM_EGREG_TURN_BLEND) {
        h = fnv_vec(h, tb->N0);
        return fnv_vec(h, tb->N1);
    }
    h = fnv_vec(h, tb->P);
    h = fnv_double(h, tb->a0);
    h = fnv_double(h, tb->a1);
    h = fnv_double(h, tb->b0);
    return fnv_double(h, tb->b1);
}

static uint32_t egreg_checksum(uint32_t h, const cm_egreg *g)
{
    for (int k = 0; k < 4; k++) {
        const cm_egreg_side *sd = &g->side[k];
        h = fnv_double(h, (double)sd->kind);
        h = fnv_double(h, (double)sd->edge);
        h = fnv_double(h, sd->t0);
        h = fnv_double(h, sd->t1);
        for (int i = 0; i < sd->npiece && i < CM_EGREG_MAX_PIECES && sd->kind == CM_EGREG_SIDE_CHAIN; i++) {
            const cm_egreg_piece *P = &sd->piece[i]; /* (layout 3 only: older files' sums stay) */
            h = fnv_double(h, (double)P->edge);
            h = fnv_double(h, P->t0);
            h = fnv_double(h, P->t1);
            h = fnv_double(h, P->s0);
            h = fnv_double(h, P->s1);
            h = fnv_vec(h, P->As);
            h = fnv_vec(h, P->Ae);
            h = turn_checksum(h, &P->tb); /* (format 2.6 only: older files' sums stay) */
        }
        for (int i = 0; i < 4 && sd->kind == CM_EGREG_SIDE_CUBIC; i++)
            h = fnv_vec(h, sd->cub.c[i]); /* an edge side's union holds pointers: not hashed */
        h = fnv_double(h, (double)sd->fan);
        h = fnv_vec(h, sd->As);
        h = fnv_vec(h, sd->Ae);
        h = fnv_double(h, sd->k0);
        h = fnv_double(h, sd->h0);
        h = fnv_double(h, sd->k1);
        h = fnv_double(h, sd->h1);
        h = turn_checksum(h, &sd->tb);
        for (int i = 0; i < 4; i++)
            h = fnv_vec(h, sd->fx[i]);
    }
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            h = fnv_vec(h, g->M[i][j]);
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) {
            h = fnv_vec(h, g->tw_a[a][b]);
            h = fnv_vec(h, g->tw_b[a][b]);
        }
    return h;
}

/* GREGORY-FIT: the corrections as the terminal dequantised them (nothing without: older files' sums stay) */
static uint32_t fit_checksum(uint32_t h, const cm_greg_surface *s)
{
    int np = s->npatch < CM_MAX_GREG ? s->npatch : CM_MAX_GREG;
    if (s->fit < 1 || s->fit > CM_FIT_MAX_M)
        return h;
    h = fnv_double(h, (double)s->fit);
    for (int k = 0; k < np; k++)
        for (int i = 0; i < s->fit * s->fit; i++)
            h = fnv_vec(h, s->corr[k][i]);
    return h;
}

uint32_t cm_greg_surface_checksum(const cm_greg_surface *s)
{
    uint32_t h = FNV_OFFSET;
    int np = s->npatch < CM_MAX_GREG ? s->npatch : CM_MAX_GREG;
    if (s->exact) {
        for (int k = 0; k < np; k++)
            h = egreg_checksum(h, &s->e[k]);
        return fit_checksum(h, s);
    }
    for (int k = 0; k < np; k++) {
        const cm_gregory *g = &s->g[k];
        for (int i = 0; i < 4; i++)
            for (int l = 0; l < 4; l++)
                if (i == 0 || i == 3 || l == 0 || l == 3)
                    h = fnv_vec(h, g->P[i][l]);
        for (int a = 0; a < 2; a++)
            for (int b = 0; b < 2; b++)
                for (int c = 0; c < 2; c++)
                    h = fnv_vec(h, g->I[a][b][c]);
    }
    return fit_checksum(h, s);
}
