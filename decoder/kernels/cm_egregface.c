/*
 * cm_egregface.c - GREGORY's layouts (spec 6.3-6.5) over the exact edges:
 * the same corner normals, bases, N-split centre and internal curves as
 * cm_gregface.c, but every side on the face's loop is the edge itself (or
 * its half, for the N-split) and the patches are cm_egreg (cm_egreg.h).
 * The cross derivative along a side is k(s) A(s) + h(s) B'(s) with the
 * edge's own tangent B', fitted at the ends to the neighbouring sides'
 * tangents (cm_greg_fit_kh, spec 6.2 in Hermite scale).
 */
#include "cm/cm_gregface.h"

#include <stddef.h>
#include <string.h>

#include "cm/cm_limits_info.h"

static const cm_vec3 zero3 = {0.0, 0.0, 0.0};

static int unit_chk(cm_vec3 v, double eps, cm_vec3 *out)
{
    int ok;
    cm_vec3 r = cm_unit_or(v, eps, zero3, &ok);
    if (ok)
        *out = r;
    return ok;
}

static cm_err degenerate(cm_status *st, const char *where)
{
    return cm_fail(st, CM_E_DEGENERATE, where);
}

/* the turning basis of the EDGE side sd (its bases set) where cm_egreg_choose_turn() asks for it, in
   files that have it (format 2.6); else the linear basis */
static cm_err pick_turn(const cm_greg_input *in, cm_egreg_side *sd, cm_vec3 Ns, cm_vec3 Ne, cm_status *st)
{
    if (!in->turning) {
        memset(&sd->tb, 0, sizeof sd->tb);
        return CM_OK;
    }
    return cm_egreg_choose_turn(sd, Ns, Ne, &sd->tb, st);
}

/* side k of the loop, or the part [a, b] of it (fractions of the use, in the face's direction) */
static void edge_side(const cm_greg_side *gs, double a, double b, cm_egreg_side *out)
{
    memset(out, 0, sizeof *out);
    out->kind = CM_EGREG_SIDE_EDGE;
    out->edge = gs->edge;
    out->curve = gs->curve;
    out->t0 = gs->rev ? 1.0 - a : a;
    out->t1 = gs->rev ? 1.0 - b : b;
}

static void cubic_side(const cm_cubic *c, cm_egreg_side *out)
{
    memset(out, 0, sizeof *out);
    out->kind = CM_EGREG_SIDE_CUBIC;
    out->cub = *c;
}

/* point and first two derivatives of a side at s */
static cm_err side_at(const cm_egreg_side *sd, double s, cm_vec3 d[3], cm_status *st)
{
    return cm_egreg_side_eval(sd, s, d, NULL, st);
}

/* spec 5.4 on the exact side: A_s = unit(N_s x B'(0)), A_e = unit(N_e x B'(1)) */
static cm_err side_basis(const cm_egreg_side *sd, cm_vec3 Ns, cm_vec3 Ne, double eps, cm_vec3 *As, cm_vec3 *Ae,
                         cm_status *st)
{
    cm_vec3 d0[3], d1[3], ts, te;
    cm_err e;
    if ((e = side_at(sd, 0.0, d0, st)) != CM_OK || (e = side_at(sd, 1.0, d1, st)) != CM_OK)
        return e;
    if (!unit_chk(d0[1], eps, &ts) || !unit_chk(d1[1], eps, &te))
        return degenerate(st, "egregface: zero end tangent");
    if (!unit_chk(cm_cross(Ns, ts), CM_GREG_EPS_DIR, As) || !unit_chk(cm_cross(Ne, te), CM_GREG_EPS_DIR, Ae))
        return degenerate(st, "egregface: basis normal parallel to the edge");
    return CM_OK;
}

/*
 * The cross derivative of side sd from the tangents of the sides beside it (spec 6.2 per unit
 * parameter): at its start it must give b0 = -prev'(1), the previous side run back from the
 * corner, at its end b3 = next'(0); c0, c1 are the side's own tangents at its ends.
 */
static cm_err fit_side(cm_egreg_side *sd, cm_vec3 c0, cm_vec3 c1, cm_vec3 prev_end, cm_vec3 next_start, double eps,
                       cm_status *st)
{
    cm_err e = cm_greg_fit_kh(sd->As, c0, cm_neg(prev_end), eps, &sd->k0, &sd->h0, st);
    if (e == CM_OK)
        e = cm_greg_fit_kh(sd->Ae, c1, next_start, eps, &sd->k1, &sd->h1, st);
    return e;
}

/*
 * A patch from four sides whose kinds, ranges and bases (or fan) are set: the cross derivatives
 * fitted at each side's ends to the neighbouring sides' tangents leaving that corner, the corner
 * data, and the orientation check.  Spec 6.3 compares the normal at (1/2,1/2) with n_F; on a face
 * that turns half a circle or more (a half or full cylinder) that normal is square to n_F or
 * opposite it.  Here the patch must face the way of the normal N[c] at each of its corners
 * (0,0), (1,0), (1,1), (0,1), a tenth of the way in: a patch folded over near a corner fails.
 */
static cm_err finish_patch(cm_egreg *g, const cm_vec3 N[4], double eps, cm_status *st)
{
    cm_vec3 d[4][2][3];
    for (int k = 0; k < 4; k++)
        for (int end = 0; end < 2; end++) {
            cm_err e = side_at(&g->side[k], (double)end, d[k][end], st);
            if (e != CM_OK)
                return e;
        }
    for (int k = 0; k < 4; k++) {
        cm_egreg_side *sd = &g->side[k];
        if (sd->fan)
            continue;
        cm_err e = fit_side(sd, d[k][0][1], d[k][1][1], d[(k + 3) & 3][1][1], d[(k + 1) & 3][0][1], eps, st);
        if (e != CM_OK)
            return e;
    }
    cm_err e = cm_egreg_finish(g, st);
    if (e != CM_OK)
        return e;
    static const double cu[4] = {0.1, 0.9, 0.9, 0.1}, cv[4] = {0.1, 0.1, 0.9, 0.9};
    for (int c = 0; c < 4; c++) {
        cm_vec3 S, Su, Sv;
        if ((e = cm_egreg_eval(g, cu[c], cv[c], &S, &Su, &Sv, st)) != CM_OK)
            return e;
        if (!(cm_dot(cm_cross(Su, Sv), N[c]) > 0.0))
            return degenerate(st, "egregface: orientation check");
    }
    return CM_OK;
}

/* ---- layout 2: collapsed at V_j, the circular fan of spec 6.5 as side 3's cross derivative ---- */
static cm_err build_degen(const cm_greg_input *in, int j, cm_greg_surface *out, cm_status *st)
{
    cm_egreg *g = &out->e[0];
    double eps = in->eps_len;
    cm_vec3 d0[3], d2[3];
    cm_err e;
    for (int m = 0; m < 3; m++) {
        const cm_greg_side *gs = &in->side[(j + m) % 3];
        cm_egreg_side *sd = &g->side[m];
        edge_side(gs, 0.0, 1.0, sd);
        if ((e = side_basis(sd, gs->Ns, gs->Ne, eps, &sd->As, &sd->Ae, st)) != CM_OK)
            return e;
        if ((e = pick_turn(in, sd, gs->Ns, gs->Ne, st)) != CM_OK)
            return e;
    }
    if ((e = side_at(&g->side[0], 0.0, d0, st)) != CM_OK || (e = side_at(&g->side[2], 1.0, d2, st)) != CM_OK)
        return e;
    cm_vec3 Vj = d0[0];
    cm_cubic point = {{Vj, Vj, Vj, Vj}};
    cubic_side(&point, &g->side[3]);
    /* S_u(0, v) turns from e0 = S_u(0,0) (side 0's tangent) to e2 = S_u(0,1) (side 2's, reversed) */
    cm_vec3 e0 = d0[1], e2 = cm_neg(d2[1]), f1, f2;
    if ((e = cm_greg_fan(e0, e2, eps, &f1, &f2, st)) != CM_OK)
        return e;
    /* side 3 runs from (0,1) to (0,0): its cross derivative X3(s) = S_u(0, 1-s) */
    g->side[3].fan = 1;
    g->side[3].fx[0] = e2;
    g->side[3].fx[1] = f2;
    g->side[3].fx[2] = f1;
    g->side[3].fx[3] = e0;
    out->npatch = 1;
    cm_vec3 N[4] = {in->corner_normal[j], in->corner_normal[(j + 1) % 3], in->corner_normal[(j + 2) % 3],
                    in->corner_normal[j]};
    return finish_patch(g, N, eps, st);
}

/* ---- layout 3: one quad whose sides may be several edges joined at T-vertices ---- */

/*
 * Side m of the joined quad: the uses first .. first+count-1 (mod n).  One use is an ordinary edge
 * side.  Several make a CHAIN: each edge keeps its own basis (spec 5.4 with the normals of its own
 * ends, so a neighbour across it meets it G1), and gets a share of the side's parameter such that
 * the speed |B'| is the same on both sides of each joint: piece i+1 is w_{i+1} = w_i |B_{i+1}'(0)| /
 * |B_i'(1)| wide, then all are scaled to 1.  Where the edges meet tangentially (the flat corner of
 * a T-vertex) the side is then C1 and the patch has no crease running in from the joint.
 */
static cm_err joined_side(const cm_greg_input *in, int first, int count, cm_egreg_side *sd, cm_status *st)
{
    int n = in->n;
    double eps = in->eps_len;
    cm_err e;
    if (count == 1) {
        const cm_greg_side *gs = &in->side[first];
        edge_side(gs, 0.0, 1.0, sd);
        if ((e = side_basis(sd, gs->Ns, gs->Ne, eps, &sd->As, &sd->Ae, st)) != CM_OK)
            return e;
        return pick_turn(in, sd, gs->Ns, gs->Ne, st);
    }
    if (count < 2 || count > CM_EGREG_MAX_PIECES)
        return cm_fail(st, CM_E_UNSUPPORTED, "egregface: more edges joined into one side than a patch side holds");
    memset(sd, 0, sizeof *sd);
    sd->kind = CM_EGREG_SIDE_CHAIN;
    sd->npiece = count;
    double w[CM_EGREG_MAX_PIECES], total = 0.0, prev_end = 0.0;
    for (int i = 0; i < count; i++) {
        const cm_greg_side *gs = &in->side[(first + i) % n];
        cm_egreg_side one;
        cm_vec3 d0[3], d1[3];
        edge_side(gs, 0.0, 1.0, &one);
        if ((e = side_at(&one, 0.0, d0, st)) != CM_OK || (e = side_at(&one, 1.0, d1, st)) != CM_OK)
            return e;
        cm_egreg_piece *P = &sd->piece[i];
        P->curve = one.curve;
        P->edge = one.edge;
        P->t0 = one.t0;
        P->t1 = one.t1;
        if ((e = side_basis(&one, gs->Ns, gs->Ne, eps, &P->As, &P->Ae, st)) != CM_OK)
            return e;
        one.As = P->As;
        one.Ae = P->Ae;
        if ((e = pick_turn(in, &one, gs->Ns, gs->Ne, st)) != CM_OK)
            return e;
        P->tb = one.tb;
        double sp0 = cm_norm(d0[1]), sp1 = cm_norm(d1[1]);
        w[i] = i == 0 ? 1.0 : w[i - 1] * (sp0 / prev_end);
        if (!(w[i] > 1e-6 && w[i] < 1e6))
            return degenerate(st, "egregface: joined edges' speeds too far apart");
        prev_end = sp1;
        total += w[i];
    }
    double at = 0.0;
    for (int i = 0; i < count; i++) {
        sd->piece[i].s0 = at;
        at += w[i] / total;
        sd->piece[i].s1 = i == count - 1 ? 1.0 : at;
    }
    sd->As = sd->piece[0].As;
    sd->Ae = sd->piece[count - 1].Ae;
    return CM_OK;
}

static cm_err build_joined(const cm_greg_input *in, int bits, cm_greg_surface *out, cm_status *st)
{
    int n = in->n, c[CM_GREG_JOINED_CORNERS], nc = 0;
    for (int k = 0; k < n; k++)
        if ((bits >> k) & 1)
            c[nc++] = k;
    cm_egreg *g = &out->e[0];
    for (int m = 0; m < CM_GREG_JOINED_CORNERS; m++) {
        int next = m + 1 < CM_GREG_JOINED_CORNERS ? c[m + 1] : c[0] + n;
        cm_err e = joined_side(in, c[m], next - c[m], &g->side[m], st);
        if (e != CM_OK)
            return e;
    }
    out->npatch = 1;
    cm_vec3 N[4] = {in->corner_normal[c[0]], in->corner_normal[c[1]], in->corner_normal[c[2]],
                    in->corner_normal[c[3]]};
    return finish_patch(g, N, in->eps_len, st);
}

/* ---- layout 0: the four edges (layout 3 with every vertex a corner) ---- */
static cm_err build_quad(const cm_greg_input *in, cm_greg_surface *out, cm_status *st)
{
    return build_joined(in, 0xF, out, st);
}

/* ---- layout 1: N quads around a centre; the loop's sides are halves of the edges ---- */
typedef struct esplit_ws {
    cm_egreg_side full; /* the edge of the side at hand (one at a time: a side is large) */
    cm_vec3 A0[CM_MAX_SIDES], A1[CM_MAX_SIDES];
    cm_vec3 M[CM_MAX_SIDES], V[CM_MAX_SIDES], T[CM_MAX_SIDES], nmid[CM_MAX_SIDES], U[CM_MAX_SIDES];
    cm_vec3 Amid[CM_MAX_SIDES];    /* each edge's basis at its middle */
    cm_egreg_turn tb[CM_MAX_SIDES]; /* each edge's turning basis (mode NONE: the linear one) */
} esplit_ws;

static cm_err esplit_mid(const cm_greg_input *in, esplit_ws *w, cm_status *st)
{
    int n = in->n;
    double eps = in->eps_len;
    cm_vec3 d[CM_MAX_SIDES][2][3];
    cm_err e;
    for (int k = 0; k < n; k++) {
        edge_side(&in->side[k], 0.0, 1.0, &w->full);
        for (int end = 0; end < 2; end++)
            if ((e = side_at(&w->full, (double)end, d[k][end], st)) != CM_OK)
                return e;
        w->V[k] = d[k][0][0];
    }
    for (int k = 0; k < n; k++) {
        cm_egreg_side *sd = &w->full;
        edge_side(&in->side[k], 0.0, 1.0, sd);
        if ((e = side_basis(sd, in->side[k].Ns, in->side[k].Ne, eps, &w->A0[k], &w->A1[k], st)) != CM_OK)
            return e;
        sd->As = w->A0[k];
        sd->Ae = w->A1[k];
        if ((e = pick_turn(in, sd, in->side[k].Ns, in->side[k].Ne, st)) != CM_OK)
            return e;
        w->tb[k] = sd->tb;
        w->Amid[k] = cm_scale(cm_add(w->A0[k], w->A1[k]), 0.5);
        if (sd->tb.mode != CM_EGREG_TURN_NONE &&
            (e = cm_egreg_side_basis(sd, CM_GREG_SPLIT_T, &w->Amid[k], st)) != CM_OK)
            return e;
        if ((e = fit_side(sd, d[k][0][1], d[k][1][1], d[(k + n - 1) % n][1][1], d[(k + 1) % n][0][1], eps, st)) !=
            CM_OK)
            return e;
        cm_vec3 m[3], x[2], tmid;
        if ((e = cm_egreg_side_eval(sd, CM_GREG_SPLIT_T, m, x, st)) != CM_OK)
            return e;
        w->M[k] = m[0];
        if (!unit_chk(m[1], eps, &tmid))
            return degenerate(st, "egregface: zero mid tangent");
        if (!unit_chk(x[0], eps, &w->T[k]))
            return degenerate(st, "egregface: zero mid cross vector");
        if (!unit_chk(cm_cross(tmid, x[0]), eps, &w->nmid[k]))
            return degenerate(st, "egregface: mid cross vector along the edge");
    }
    return CM_OK;
}

static cm_err esplit_patches(const cm_greg_input *in, const esplit_ws *w, cm_greg_surface *out, cm_status *st)
{
    int n = in->n;
    cm_vec3 nC = out->centre_normal;
    for (int k = 0; k < n; k++) {
        int p = (k + n - 1) % n;
        cm_egreg *g = &out->e[k];
        cm_egreg_side *q = g->side;
        edge_side(&in->side[k], 0.0, CM_GREG_SPLIT_T, &q[0]);
        q[0].As = w->A0[k];
        q[0].Ae = w->Amid[k];
        q[0].tb = cm_egreg_turn_part(&w->tb[k], 0.0, CM_GREG_SPLIT_T);
        cubic_side(&out->inner[k], &q[1]);
        if (!unit_chk(cm_cross(w->nmid[k], w->T[k]), CM_GREG_EPS_DIR, &q[1].As) ||
            !unit_chk(cm_cross(nC, cm_neg(w->U[k])), CM_GREG_EPS_DIR, &q[1].Ae))
            return degenerate(st, "egregface: internal basis");
        cm_cubic back = cm_cubic_reverse(&out->inner[p]);
        cubic_side(&back, &q[2]);
        if (!unit_chk(cm_cross(nC, w->U[p]), CM_GREG_EPS_DIR, &q[2].As) ||
            !unit_chk(cm_cross(w->nmid[p], cm_neg(w->T[p])), CM_GREG_EPS_DIR, &q[2].Ae))
            return degenerate(st, "egregface: internal basis");
        edge_side(&in->side[p], CM_GREG_SPLIT_T, 1.0, &q[3]);
        q[3].As = w->Amid[p];
        q[3].Ae = w->A1[p];
        q[3].tb = cm_egreg_turn_part(&w->tb[p], CM_GREG_SPLIT_T, 1.0);
        cm_vec3 N[4] = {in->corner_normal[k], w->nmid[k], nC, w->nmid[p]};
        cm_err e = finish_patch(g, N, in->eps_len, st);
        if (e != CM_OK)
            return e;
    }
    out->npatch = n;
    out->t_split = CM_GREG_SPLIT_T;
    return CM_OK;
}

static cm_err build_split(const cm_greg_input *in, cm_greg_surface *out, cm_status *st)
{
    esplit_ws w;
    cm_err e = esplit_mid(in, &w, st);
    if (e == CM_OK)
        e = cm_greg_spoke_centre(in->n, w.M, w.T, w.nmid, w.V, in->corner_normal, in->eps_len, w.U, out, st);
    if (e == CM_OK)
        e = esplit_patches(in, &w, out, st);
    return e;
}

cm_err cm_egreg_build(const cm_greg_input *in, int layout, int j, cm_greg_surface *out, cm_status *st)
{
    cm_err e = cm_greg_begin(in, layout, j, 1, out, st);
    if (e != CM_OK)
        return e;
    if (layout == CM_GREG_LAYOUT_QUAD)
        e = build_quad(in, out, st);
    else if (layout == CM_GREG_LAYOUT_SPLIT)
        e = build_split(in, out, st);
    else if (layout == CM_GREG_LAYOUT_JOINED)
        e = build_joined(in, j, out, st);
    else
        e = build_degen(in, j, out, st);
    if (e != CM_OK)
        cm_greg_surface_reset(out, layout, in->n, j, 1);
    return e;
}
