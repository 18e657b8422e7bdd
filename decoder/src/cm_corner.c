/*
 * cm_corner.c - corner normals (spec 5.3), the edge basis normals (5.4) and the
 * input of the Gregory construction, read from the decoded curve mesh only.
 *
 * A face's rebuild depends on the mesh, the G1 bits and its own record: across
 * a G1 edge it also reads the partner face's loop geometry at the shared
 * vertices and its outer-loop normal (spec 15.4), never the partner's record.
 * Everything is computed in the edge's stored direction and reversed after, so
 * both faces of an edge get bit-identical cubics and opposite basis vectors.
 */
#include "cm/cm_corner.h"

#include <stddef.h>

#include "cm/cm_const.h"
#include "cm/cm_cubic_convert.h"
#include "cm/cm_limits_info.h"
#include "cm/cm_face_samples.h"
#include "cm/cm_geom.h"

int cm_use_tangent(const cm_model *m, const cm_use *U, int at_end, double eps, cm_vec3 *t)
{
    cm_curve c;
    cm_model_edge_curve(m, U->edge, &c);
    double s = (at_end != 0) != (U->rev != 0) ? 1.0 : 0.0; /* curve parameter of that end */
    cm_vec3 d[2];
    if (cm_curve_eval(&c, s, 1, d, NULL) != CM_OK)
        return 0;
    cm_vec3 dir = d[1];
    if (!(cm_norm(dir) > eps)) {
        /* a vanishing end derivative (doubled control point): the chord to a nearby point */
        cm_vec3 q[1];
        if (cm_curve_eval(&c, s == 0.0 ? 1e-3 : 1.0 - 1e-3, 0, q, NULL) != CM_OK)
            return 0;
        dir = s == 0.0 ? cm_sub(q[0], d[0]) : cm_sub(d[0], q[0]);
    }
    int ok;
    cm_vec3 u = cm_unit_or(dir, eps, cm_v3(0, 0, 0), &ok);
    *t = U->rev ? cm_neg(u) : u;
    return ok;
}

cm_err cm_face_normal(const cm_model *m, uint32_t f, cm_vec3 *samples, double *bbox, cm_vec3 *n, cm_status *st)
{
    int ns, n_outer;
    cm_err e = cm_face_samples(m, f, samples, CM_MAX_FACE_SAMPLES, &ns, &n_outer, st);
    if (e != CM_OK)
        return e;
    *bbox = cm_points_diag(samples, ns);
    cm_frame fr;
    if ((e = cm_face_frame(samples, n_outer, samples, ns, CM_EPS_LEN_REL * *bbox, &fr, st)) != CM_OK)
        return e;
    *n = fr.ez;
    return CM_OK;
}

void cm_corner_cache_begin(cm_corner_ws *ws, const cm_model *m)
{
    for (int i = 0; i < CM_CORNER_CACHE; i++) {
        ws->normal_cache[i].face = -1;
        ws->cubic_cache[i].edge = -1;
    }
    ws->cache_model = m;
}

void cm_corner_cache_end(cm_corner_ws *ws) { cm_corner_cache_begin(ws, NULL); }

/* cm_face_normal, from the cache where on (samples is scratch here: a cached answer leaves it alone) */
static cm_err face_normal_cached(cm_corner_ws *ws, const cm_model *m, uint32_t f, cm_vec3 *samples, double *bbox,
                                 cm_vec3 *n, cm_status *st)
{
    if (ws->cache_model != m)
        return cm_face_normal(m, f, samples, bbox, n, st);
    int slot = (int)(f & (CM_CORNER_CACHE - 1));
    if (ws->normal_cache[slot].face == (int32_t)f) {
        *bbox = ws->normal_cache[slot].bbox;
        *n = ws->normal_cache[slot].n;
        return CM_OK;
    }
    cm_err e = cm_face_normal(m, f, samples, bbox, n, st);
    if (e == CM_OK) {
        ws->normal_cache[slot].face = (int32_t)f;
        ws->normal_cache[slot].bbox = *bbox;
        ws->normal_cache[slot].n = *n;
    }
    return e;
}

/* the cubic of edge e (curve cv) over its whole range (K7, or from 4.14 a conic's closed form), from
   the cache where on */
static cm_err edge_cubic_cached(cm_corner_ws *ws, const cm_model *m, uint32_t e, const cm_curve *cv, cm_cubic *out,
                                cm_status *st)
{
    int slot = (int)(e & (CM_CORNER_CACHE - 1));
    if (ws->cache_model == m && ws->cubic_cache[slot].edge == (int32_t)e) {
        *out = ws->cubic_cache[slot].c;
        return CM_OK;
    }
    cm_err err = cm_edge_cubic(cv, m->conic_cubic, out, st);
    if (err == CM_OK && ws->cache_model == m) {
        ws->cubic_cache[slot].edge = (int32_t)e;
        ws->cubic_cache[slot].c = *out;
    }
    return err;
}

/*
 * N_geo at the corner between uses `in` and `out` (spec 5.3), turned to nF; 0 where undefined.
 * nF NULL: as the loop's direction makes it (GREGORY-EXACT: a loop runs counter-clockwise about
 * its face's outward normal, so at a convex corner this is that normal, however far it turns
 * from the face's mean normal on a half cylinder; turning it to nF there is a coin toss).
 */
static int geo_normal(const cm_model *m, const cm_use *in, const cm_use *out, const cm_vec3 *nF, double eps,
                      cm_vec3 *N)
{
    cm_vec3 ta, tb;
    if (!cm_use_tangent(m, in, 1, eps, &ta) || !cm_use_tangent(m, out, 0, eps, &tb))
        return 0;
    cm_vec3 a = cm_neg(ta), c = cm_cross(tb, a);
    if (!(cm_norm(c) >= CM_SIN_FLAT))
        return 0;
    *N = cm_unit(c);
    if (nF && cm_dot(*N, *nF) < 0)
        *N = cm_neg(*N);
    return 1;
}

/* the partner's corner at vertex v next to edge e (as its incoming or outgoing use): N_geo(G, v) */
static int partner_geo(const cm_model *m, uint32_t g, uint32_t e, int32_t v, const cm_vec3 *nG, double eps,
                       cm_vec3 *N)
{
    const cm_face *G = &m->faces[g];
    for (uint32_t l = 0; l < G->nloops; l++) {
        const cm_loop *L = &m->loops[G->loop0 + l];
        for (uint32_t k = 0; k < L->nuse; k++) {
            const cm_use *in = &m->uses[L->use0 + (k + L->nuse - 1) % L->nuse], *out = &m->uses[L->use0 + k];
            const cm_edge *Ei = &m->edges[in->edge];
            int32_t at = in->rev ? Ei->v0 : Ei->v1; /* the corner's vertex: where `in` ends */
            if (at == v && (in->edge == e || out->edge == e))
                return geo_normal(m, in, out, nG, eps, N);
        }
    }
    return 0;
}

/* what the partner lookups of one face share */
typedef struct corner_ctx {
    const cm_model *m;
    cm_vec3 nF;
    double eps;
    cm_corner_ws *ws; /* its scratch: samples for partner normals */
    int exact;        /* GREGORY-EXACT: normals as the loops orient them, never turned (geo_normal) */
} corner_ctx;

static cm_err partner_normal(const corner_ctx *c, uint32_t g, double *bbox_g, cm_vec3 *nG, cm_status *st)
{
    cm_err e = face_normal_cached(c->ws, c->m, g, c->ws->scratch, bbox_g, nG, st);
    if (e == CM_OK && !c->exact && cm_dot(*nG, c->nF) < 0)
        *nG = cm_neg(*nG); /* sign-matched to n_F (spec 5.3 (i), 5.4) */
    return e;
}

cm_err cm_greg_input_build(const cm_model *m, uint32_t f, int exact, cm_greg_input *in, cm_corner_ws *ws,
                           cm_status *st)
{
    const cm_face *F = &m->faces[f];
    const cm_loop *L = &m->loops[F->loop0];
    int n = (int)L->nuse;
    if (n < 3)
        return cm_fail(st, CM_E_UNSUPPORTED, "GREGORY needs 3 or more sides");
    if (n > CM_GREG_MAX_INPUT)
        return cm_fail_limit(st, CM_LIMIT_MAX_SIDES, (uint64_t)n, CM_MAX_SIDES, __func__);
    double bbox;
    cm_err e = face_normal_cached(ws, m, f, ws->samples, &bbox, &in->nF, st);
    if (e != CM_OK)
        return e;
    in->n = n;
    in->eps_len = CM_EPS_LEN_REL * bbox;
    in->turning = m->turning_basis;
    corner_ctx c = {m, in->nF, in->eps_len, ws, exact};
    const cm_vec3 *turn = exact ? NULL : &in->nF; /* what corner normals are turned to */
    /* the record's hints (format 4.13), one for each bit, in corner order */
    const unsigned hints = cm_face_hint_mask(F);
    uint32_t hint_at = cm_face_hint_first(F);
    /* per corner k (vertex V_k, between use k-1 and use k): N_geo and its partner fallback */
    for (int k = 0; k < n; k++) {
        const cm_use *uin = &m->uses[L->use0 + (uint32_t)((k + n - 1) % n)], *uout = &m->uses[L->use0 + (uint32_t)k];
        const cm_edge *Ei = &m->edges[uin->edge];
        int32_t v = uin->rev ? Ei->v0 : Ei->v1;
        const int hinted = (hints >> k) & 1u, g1 = m->edges[uin->edge].g1 || m->edges[uout->edge].g1;
        ws->vert[k] = v;
        ws->has_geo[k] = geo_normal(m, uin, uout, turn, c.eps, &ws->geo[k]);
        in->corner_normal[k] = ws->geo[k];
        /* (ii) a hint, only at a flat corner with no G1 edge (spec 5.3): a hint anywhere else is not
           the encoder's (hint_at < nctrl: the reader put one there for each bit) */
        if (hinted && (ws->has_geo[k] || g1 || hint_at >= m->nctrl))
            return cm_fail(st, CM_E_FORMAT, "GREGORY hint at a corner that has its own normal");
        if (hinted)
            in->corner_normal[k] = m->ctrl[hint_at++];
        if (ws->has_geo[k] || hinted)
            continue;
        /* (i) across a G1 edge at this corner, the partner's geometric normal; (iii) n_F */
        in->corner_normal[k] = in->nF;
        for (int s = 0; s < 2; s++) {
            const cm_use *U = s == 0 ? uin : uout;
            int32_t g = m->edges[U->edge].g1 ? cm_model_partner(m, U->edge, f) : CM_NO_FACE;
            if (g < 0)
                continue;
            double bg;
            cm_vec3 nG, Ng;
            if ((e = partner_normal(&c, (uint32_t)g, &bg, &nG, st)) != CM_OK)
                return e;
            if (partner_geo(m, (uint32_t)g, U->edge, v, exact ? NULL : &nG, CM_EPS_LEN_REL * bg, &Ng)) {
                in->corner_normal[k] = !exact && cm_dot(Ng, in->nF) < 0 ? cm_neg(Ng) : Ng;
                break;
            }
        }
    }
    /* per side k (use k, V_k -> V_k+1): the K7 cubic in the edge's stored direction, and the basis normals */
    for (int k = 0; k < n; k++) {
        const cm_use *U = &m->uses[L->use0 + (uint32_t)k];
        cm_curve cv;
        cm_model_edge_curve(m, U->edge, &cv);
        cm_cubic cub = {{{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}}};
        if (!exact && (e = edge_cubic_cached(ws, m, U->edge, &cv, &cub, st)) != CM_OK)
            return e;
        cm_greg_side *S = &in->side[k];
        S->c = U->rev ? cm_cubic_reverse(&cub) : cub;
        S->curve = cv;
        S->edge = U->edge;
        S->rev = U->rev != 0;
        int k1 = (k + 1) % n;
        S->Ns = in->corner_normal[k];
        S->Ne = in->corner_normal[k1];
        int32_t g = m->edges[U->edge].g1 ? cm_model_partner(m, U->edge, f) : CM_NO_FACE;
        if (g < 0)
            continue;
        /* G1 edge (spec 5.4): the symmetric rule, the same normals from both faces */
        double bg;
        cm_vec3 nG;
        if ((e = partner_normal(&c, (uint32_t)g, &bg, &nG, st)) != CM_OK)
            return e;
        for (int end = 0; end < 2; end++) {
            int kv = end ? k1 : k;
            cm_vec3 Ng, N;
            int has_g = partner_geo(m, (uint32_t)g, U->edge, ws->vert[kv], exact ? NULL : &nG, CM_EPS_LEN_REL * bg, &Ng);
            if (ws->has_geo[kv] && has_g && !(exact && !(cm_dot(ws->geo[kv], Ng) > 0)))
                N = cm_unit(cm_add(ws->geo[kv], Ng));
            else if (ws->has_geo[kv]) /* (exact: also where the partner's loop runs against ours) */
                N = ws->geo[kv];
            else if (has_g)
                N = Ng;
            else if (!exact || cm_dot(in->nF, nG) > 0)
                N = cm_unit(cm_add(in->nF, nG));
            else
                N = in->nF;
            if (end)
                S->Ne = N;
            else
                S->Ns = N;
        }
    }
    return CM_OK;
}
