/* cm_format.c - byte order helpers and kernel views of the decoded model. */
#include "cm/cm_format.h"

#include <math.h>
#include <string.h>

#include "cm/cm_bspline.h"
#include "cm/cm_crc32.h"
#include "cm/cm_method.h"

double cm_get_f64(const uint8_t *p)
{
    uint64_t u = 0;
    for (int i = 7; i >= 0; i--)
        u = (u << 8) | p[i];
    double v;
    memcpy(&v, &u, sizeof v);
    return v;
}

void cm_put_f64(uint8_t *p, double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    for (int i = 0; i < 8; i++) {
        p[i] = (uint8_t)u;
        u >>= 8;
    }
}

/* the six bytes every version starts with: magic, major, minor */
static void put_magic_version(uint8_t *b, const cm_fmt_header *h)
{
    b[CM_HDR_MAGIC + 0] = CM_FMT_MAGIC0;
    b[CM_HDR_MAGIC + 1] = CM_FMT_MAGIC1;
    b[CM_HDR_MAGIC + 2] = CM_FMT_MAGIC2;
    b[CM_HDR_MAGIC + 3] = CM_FMT_MAGIC3;
    b[CM_HDR_MAJOR] = h->major;
    b[CM_HDR_MINOR] = h->minor;
}

void cm_fmt_header_pack(uint8_t *b, const cm_fmt_header *h)
{
    put_magic_version(b, h);
    cm_put_u16(b + CM_HDR_FLAGS, h->flags);
    cm_put_u32(b + CM_HDR_LENGTH, h->header_len);
    cm_put_u32(b + CM_HDR_FILE_LENGTH, h->file_len);
    b[CM_HDR_NLIMITS] = h->nlimits;
    b[CM_HDR_NSECTIONS] = h->nsections;
    b[CM_HDR_QEXP] = (uint8_t)h->q_exp;
    b[CM_HDR_RESERVED] = 0;
    for (uint32_t k = 0; k < 3; k++)
        cm_put_f64(b + CM_HDR_ORIGIN + 8 * k, h->origin[k]);
    cm_put_f64(b + CM_HDR_TESS_TOL, h->tess_tol);
    cm_put_f64(b + CM_HDR_REL_TOL, h->rel_tol);
}

void cm_fmt_header_unpack(const uint8_t *b, cm_fmt_header *h)
{
    h->major = b[CM_HDR_MAJOR];
    h->minor = b[CM_HDR_MINOR];
    h->flags = cm_get_u16(b + CM_HDR_FLAGS);
    h->header_len = cm_get_u32(b + CM_HDR_LENGTH);
    h->file_len = cm_get_u32(b + CM_HDR_FILE_LENGTH);
    h->nlimits = b[CM_HDR_NLIMITS];
    h->nsections = b[CM_HDR_NSECTIONS];
    h->q_exp = (int8_t)b[CM_HDR_QEXP];
    for (uint32_t k = 0; k < 3; k++)
        h->origin[k] = cm_get_f64(b + CM_HDR_ORIGIN + 8 * k);
    h->tess_tol = cm_get_f64(b + CM_HDR_TESS_TOL);
    h->rel_tol = cm_get_f64(b + CM_HDR_REL_TOL);
}

/* ---- format 4's compact header ---- */

uint32_t cm_fmt_put_varint(uint8_t *b, uint64_t v)
{
    uint32_t n = 0;
    while (v >= 0x80u) {
        b[n++] = (uint8_t)(v | 0x80u);
        v >>= 7;
    }
    b[n++] = (uint8_t)v;
    return n;
}

int cm_fmt_get_varint(const uint8_t *b, uint32_t end, uint32_t *at, uint64_t *v)
{
    uint64_t r = 0;
    for (uint32_t i = 0; i < CM_FMT_VARINT_MAX; i++) {
        if (*at >= end)
            return 0;
        uint8_t c = b[(*at)++];
        uint64_t part = (uint64_t)(c & 0x7Fu);
        if (i == CM_FMT_VARINT_MAX - 1 && part > 1u) /* past 64 bits */
            return 0;
        r |= part << (7 * i);
        if (!(c & 0x80u)) {
            *v = r;
            return 1;
        }
    }
    return 0;
}

double cm_fmt_grid_step(int q_exp)
{
    double q = 1.0;
    for (int i = 0; i < (q_exp < 0 ? -q_exp : q_exp); i++)
        q = q_exp < 0 ? q * 0.5 : q * 2.0;
    return q;
}

double cm_fmt_compact_tess(double tess, int q_exp)
{
    double q = cm_fmt_grid_step(q_exp), m = floor(tess / q + 0.5);
    return (m >= 1.0 ? m : 1.0) * q;
}

uint32_t cm_fmt_compact_pack(uint8_t *b, cm_fmt_header *h, const uint32_t *need, const uint32_t *sec_len)
{
    /* everything after H's varint and before the CRC, written first after room for the longest H
       (5 bytes), then moved up to it: H counts its own varint */
    if (CM_FMT_COMPACT_AT_H + 5u + (h->nlimits + h->nsections + 8u) * CM_FMT_VARINT_MAX + 4u > CM_FMT_MAX_HEADER)
        return 0;
    uint8_t *body = b + CM_FMT_COMPACT_AT_H + 5u;
    uint32_t n = 0;
    double q = cm_fmt_grid_step(h->q_exp);
    n += cm_fmt_put_varint(body + n, h->flags);
    n += cm_fmt_put_varint(body + n, h->nlimits);
    for (uint32_t i = 0; i < h->nlimits; i++)
        n += cm_fmt_put_varint(body + n, need ? need[i] : 0);
    n += cm_fmt_put_varint(body + n, h->nsections);
    uint64_t sections = 0;
    for (uint32_t s = 0; s < h->nsections; s++) {
        n += cm_fmt_put_varint(body + n, sec_len[s]);
        sections += sec_len[s];
    }
    n += cm_fmt_put_varint(body + n, cm_fmt_zigzag(h->q_exp));
    uint64_t rel = (uint64_t)floor(h->rel_tol * (double)CM_FMT_REL_TOL_ONE + 0.5);
    if (h->minor >= CM_FMT_SHORT_ORIGIN_MINOR) {
        /* the origin's largest common power-of-two factor of q (the writer may floor it onto a coarse
           step), then the multiples of that */
        int64_t m[3];
        uint32_t shift = CM_FMT_MAX_ORIGIN_SHIFT;
        for (int k = 0; k < 3; k++) {
            m[k] = (int64_t)(h->origin[k] / q);
            uint32_t z = 0;
            while (m[k] != 0 && z < shift && (m[k] & ((int64_t)1 << z)) == 0)
                z++;
            if (m[k] != 0 && z < shift)
                shift = z;
        }
        if (m[0] == 0 && m[1] == 0 && m[2] == 0)
            shift = 0;
        n += cm_fmt_put_varint(body + n, shift);
        for (int k = 0; k < 3; k++)
            n += cm_fmt_put_varint(body + n, cm_fmt_zigzag(m[k] / ((int64_t)1 << shift)));
        n += cm_fmt_put_varint(body + n, (uint64_t)(h->tess_tol / q));
        n += cm_fmt_put_varint(body + n, cm_fmt_zigzag((int64_t)rel - (int64_t)CM_FMT_REL_TOL_DEFAULT));
    } else {
        for (int k = 0; k < 3; k++)
            n += cm_fmt_put_varint(body + n, cm_fmt_zigzag((int64_t)(h->origin[k] / q)));
        n += cm_fmt_put_varint(body + n, (uint64_t)(h->tess_tol / q));
        n += cm_fmt_put_varint(body + n, rel);
    }
    uint8_t hb[CM_FMT_VARINT_MAX];
    uint32_t H = 0;
    for (uint32_t lh = 1; lh <= 5 && !H; lh++) {
        uint32_t cand = CM_FMT_COMPACT_AT_H + lh + n + 4u;
        if (cm_fmt_put_varint(hb, cand) == lh)
            H = cand;
    }
    if (H == 0 || H > CM_FMT_MAX_HEADER)
        return 0;
    put_magic_version(b, h);
    uint32_t lh = cm_fmt_put_varint(hb, H);
    memmove(b + CM_FMT_COMPACT_AT_H + lh, body, n);
    memcpy(b + CM_FMT_COMPACT_AT_H, hb, lh);
    cm_put_u32(b + H - 4, cm_crc32(b, H - 4));
    h->header_len = H;
    h->file_len = (uint32_t)(H + sections + 4u);
    return H;
}

int cm_fmt_header_needs(const uint8_t *b, uint32_t n, uint32_t *need, uint32_t cap, uint32_t *count)
{
    if (n < CM_HDR_LENGTH + 4u)
        return 0;
    if (b[CM_HDR_MAJOR] < CM_FMT_COMPACT_MAJOR) {
        uint32_t nn = b[CM_HDR_NLIMITS];
        if (n < CM_FMT_FIXED_HEADER || cm_fmt_need_at(nn) > n)
            return 0;
        for (uint32_t i = 0; i < nn && i < cap; i++)
            need[i] = cm_get_u32(b + cm_fmt_need_at(i));
        *count = nn;
        return 1;
    }
    uint32_t at = CM_FMT_COMPACT_AT_H;
    uint64_t v, nn;
    if (!cm_fmt_get_varint(b, n, &at, &v) || !cm_fmt_get_varint(b, n, &at, &v) || !cm_fmt_get_varint(b, n, &at, &nn) ||
        nn > 255)
        return 0;
    for (uint32_t i = 0; i < (uint32_t)nn; i++) {
        if (!cm_fmt_get_varint(b, n, &at, &v))
            return 0;
        if (i < cap)
            need[i] = v > UINT32_MAX ? UINT32_MAX : (uint32_t)v;
    }
    *count = (uint32_t)nn;
    return 1;
}

void cm_model_edge_curve(const cm_model *m, uint32_t e, cm_curve *out)
{
    const cm_edge *E = &m->edges[e];
    out->p = E->p;
    out->n_ctrl = E->nctrl;
    out->knots = m->knots + E->knot0;
    out->ctrl = m->ctrl + E->ctrl0;
    out->w = E->rational ? m->w + E->ctrl0 : NULL;
}

void cm_model_surface(const cm_model *m, uint32_t s, cm_surf *out)
{
    const cm_ksurf *S = &m->surfs[s];
    out->p = S->p;
    out->q = S->q;
    out->nu = S->nu;
    out->nv = S->nv;
    out->U = m->knots + S->uknot0;
    out->V = m->knots + S->vknot0;
    out->ctrl = m->ctrl + S->ctrl0;
    out->w = S->rational ? m->w + S->ctrl0 : NULL;
}

void cm_model_adjacency(cm_model *m)
{
    for (uint32_t e = 0; e < m->nedges; e++) {
        m->edge_face[e][0] = m->edge_face[e][1] = CM_NO_FACE;
        m->edge_split[e] = 0;
    }
    for (uint32_t f = 0; f < m->nfaces; f++) {
        const cm_face *F = &m->faces[f];
        const cm_method *M = cm_method_of(F->method);
        int split = M && cm_method_needs_midpoints(M, F);
        for (uint32_t l = 0; l < F->nloops; l++) {
            const cm_loop *L = &m->loops[F->loop0 + l];
            for (uint32_t u = 0; u < L->nuse; u++) {
                uint32_t e = m->uses[L->use0 + u].edge;
                int32_t *ef = m->edge_face[e];
                if (split && l == 0)
                    m->edge_split[e] = 1;
                if (ef[0] == CM_NO_FACE)
                    ef[0] = (int32_t)f;
                else if (ef[1] == CM_NO_FACE)
                    ef[1] = (int32_t)f;
                else
                    ef[1] = CM_MANY_FACES;
            }
        }
    }
}

int32_t cm_model_partner(const cm_model *m, uint32_t e, uint32_t f)
{
    const int32_t *ef = m->edge_face[e];
    if (ef[1] < 0 || ef[0] == ef[1])
        return CM_NO_FACE; /* free, non-manifold, or a seam of one face */
    return ef[0] == (int32_t)f ? ef[1] : (ef[1] == (int32_t)f ? ef[0] : CM_NO_FACE);
}

const char *cm_fmt_placement_fault(const double m[12])
{
    for (int i = 0; i < 12; i++) {
        double lim = i % 4 == 3 ? CM_FMT_PLACE_MAX_SHIFT : CM_FMT_PLACE_MAX_LINEAR;
        if (!(fabs(m[i]) <= lim))
            return i % 4 == 3 ? "placement's translation" : "placement's transform";
    }
    double det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
                 m[2] * (m[4] * m[9] - m[5] * m[8]);
    return fabs(det) >= CM_FMT_PLACE_MIN_DET ? NULL : "placement's transform (singular)";
}
