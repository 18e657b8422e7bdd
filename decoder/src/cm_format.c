/* cm_format.c - byte order helpers and kernel views of the decoded model. */
#include "cm/cm_format.h"

#include <math.h>
#include <string.h>

#include "cm/cm_arith.h"
#include "cm/cm_bspline.h"
#include "cm/cm_crc32.h"
#include "cm/cm_limits_info.h"
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

/* the origin's largest common power-of-two factor of q (4.1 on), and the multiples of it */
static uint32_t origin_multiples(const cm_fmt_header *h, int64_t m[3])
{
    double q = cm_fmt_grid_step(h->q_exp);
    uint32_t shift = CM_FMT_MAX_ORIGIN_SHIFT;
    for (int k = 0; k < 3; k++) {
        double g = h->origin[k] / q; /* (beyond +-2^62 steps: the nearest the field holds; the reader refuses it) */
        m[k] = !(g > -0x1p62) ? -((int64_t)1 << 62) : !(g < 0x1p62) ? (int64_t)1 << 62 : (int64_t)g;
        uint32_t z = 0;
        while (m[k] != 0 && z < shift && (m[k] & ((int64_t)1 << z)) == 0)
            z++;
        if (m[k] != 0 && z < shift)
            shift = z;
    }
    if (m[0] == 0 && m[1] == 0 && m[2] == 0)
        shift = 0;
    for (int k = 0; k < 3; k++)
        m[k] /= (int64_t)1 << shift;
    return shift;
}

/* the writers' tolerances as the header's integers, whatever the writer was given: the chordal one
   in grid steps q (0 .. 2^63), the rebuild one in units of 2^-24 (-2^40 .. 2^40; a NaN as the
   lowest); out of range, the nearest the field holds, which the reader refuses */
static uint64_t tess_steps(const cm_fmt_header *h, double q)
{
    double t = h->tess_tol / q;
    return !(t >= 0.0) ? 0u : t >= 0x1p63 ? (uint64_t)1 << 63 : (uint64_t)t;
}

static int64_t rel_units(const cm_fmt_header *h)
{
    double r = floor(h->rel_tol * (double)CM_FMT_REL_TOL_ONE + 0.5);
    return !(r >= -0x1p40) ? -((int64_t)1 << 40) : r > 0x1p40 ? (int64_t)1 << 40 : (int64_t)r;
}

/* magic, version, the varint H (which counts itself), the n bytes of fields written at
   b + CM_FMT_COMPACT_AT_H + 5, the CRC: H, or 0 past CM_FMT_MAX_HEADER */
static uint32_t close_header(uint8_t *b, cm_fmt_header *h, uint32_t n, uint64_t body_len)
{
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
    memmove(b + CM_FMT_COMPACT_AT_H + lh, b + CM_FMT_COMPACT_AT_H + 5u, n);
    memcpy(b + CM_FMT_COMPACT_AT_H, hb, lh);
    cm_put_u32(b + H - 4, cm_crc32(b, H - 4));
    h->header_len = H;
    h->file_len = (uint32_t)(H + body_len + 4u);
    return H;
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
    int64_t relu = rel_units(h);
    uint64_t rel = relu < 0 ? 0u : (uint64_t)relu, tess = tess_steps(h, q);
    if (h->minor >= CM_FMT_SHORT_ORIGIN_MINOR) {
        /* the origin's step (the writer may floor it onto a coarse one), then its multiples */
        int64_t m[3];
        uint32_t shift = origin_multiples(h, m);
        n += cm_fmt_put_varint(body + n, shift);
        for (int k = 0; k < 3; k++)
            n += cm_fmt_put_varint(body + n, cm_fmt_zigzag(m[k]));
        n += cm_fmt_put_varint(body + n, tess);
        n += cm_fmt_put_varint(body + n, cm_fmt_zigzag((int64_t)rel - (int64_t)CM_FMT_REL_TOL_DEFAULT));
    } else {
        for (int k = 0; k < 3; k++)
            n += cm_fmt_put_varint(body + n, cm_fmt_zigzag((int64_t)(h->origin[k] / q)));
        n += cm_fmt_put_varint(body + n, tess);
        n += cm_fmt_put_varint(body + n, rel);
    }
    return close_header(b, h, n, sections);
}

/* ---- format 4.6: the header's fields range-coded ---- */

/* each field its own model, all needs one (the unpredicted ones) or another (the differences) */
typedef struct hdr_models {
    cm_ac_int flags, extra_needs, body, need, need_diff, qexp, origin_shift, origin, tess, rel;
} hdr_models;

static void hdr_models_init(hdr_models *m)
{
    cm_ac_int *all[] = {&m->flags, &m->extra_needs, &m->body, &m->need, &m->need_diff,
                        &m->qexp, &m->origin_shift, &m->origin, &m->tess, &m->rel};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
        cm_ac_int_init(all[i]);
}

/*
 * A model's counts and totals follow from each other more often than not: a closed shell has
 * V = E - F + 2 vertices, two uses per edge, one loop per face; a straight edge two points and
 * four knots; a loop's uses are its face's.  Only earlier needs are used, so the reader can follow.
 */
static int64_t need_pred_raw(uint32_t i, const uint32_t *need)
{
    switch (i) {
    case CM_LIMIT_MAX_FACE_EDGES: return need[CM_LIMIT_MAX_LOOP_EDGES];
    case CM_LIMIT_MAX_EDGES: return 2 * (int64_t)need[CM_LIMIT_MAX_FACES];
    case CM_LIMIT_MAX_VERTICES: return (int64_t)need[CM_LIMIT_MAX_EDGES] - need[CM_LIMIT_MAX_FACES] + 2;
    case CM_LIMIT_MAX_MODEL_CTRL: return 2 * (int64_t)need[CM_LIMIT_MAX_EDGES];
    case CM_LIMIT_MAX_MODEL_KNOTS: return (int64_t)need[CM_LIMIT_MAX_MODEL_CTRL] + 2 * (int64_t)need[CM_LIMIT_MAX_EDGES];
    case CM_LIMIT_MAX_MODEL_LOOPS: return need[CM_LIMIT_MAX_FACES];
    case CM_LIMIT_MAX_MODEL_USES: return 2 * (int64_t)need[CM_LIMIT_MAX_EDGES];
    default: return 0;
    }
}

/* held to a need's range, so that a need less its prediction is within the coder's 2^33 - 1 */
int64_t cm_fmt_need_pred(uint32_t i, const uint32_t *need)
{
    int64_t p = need_pred_raw(i, need);
    return p < 0 ? 0 : p > (int64_t)UINT32_MAX ? (int64_t)UINT32_MAX : p;
}
/* (MAX_FILE_BYTES predicts nothing: the writer's value of it and the reader's are made apart) */
_Static_assert(CM_LIMIT_MAX_FILE_BYTES != CM_LIMIT_MAX_LOOP_EDGES && CM_LIMIT_MAX_FILE_BYTES != CM_LIMIT_MAX_FACES &&
                   CM_LIMIT_MAX_FILE_BYTES != CM_LIMIT_MAX_EDGES && CM_LIMIT_MAX_FILE_BYTES != CM_LIMIT_MAX_MODEL_CTRL,
               "no need is predicted from MAX_FILE_BYTES");
_Static_assert(CM_LIMIT_MAX_FACE_EDGES > CM_LIMIT_MAX_LOOP_EDGES && CM_LIMIT_MAX_VERTICES > CM_LIMIT_MAX_EDGES &&
                   CM_LIMIT_MAX_EDGES > CM_LIMIT_MAX_FACES && CM_LIMIT_MAX_MODEL_CTRL > CM_LIMIT_MAX_EDGES &&
                   CM_LIMIT_MAX_MODEL_KNOTS > CM_LIMIT_MAX_MODEL_CTRL && CM_LIMIT_MAX_MODEL_LOOPS > CM_LIMIT_MAX_FACES &&
                   CM_LIMIT_MAX_MODEL_USES > CM_LIMIT_MAX_EDGES,
               "a need is predicted from needs before it");

/* a value of up to 64 bits: below 2^33 - 1 as a uint, else that escape and the value's 64 bits */
#define WIDE_ESCAPE ((1ull << 33) - 1u)
static void put_wide(cm_ac_enc *e, cm_ac_int *m, uint64_t v)
{
    cm_ac_enc_uint(e, m, v < WIDE_ESCAPE ? v : WIDE_ESCAPE);
    if (v >= WIDE_ESCAPE)
        for (int k = 3; k >= 0; k--)
            cm_ac_enc_direct(e, (uint32_t)(v >> (16 * k)) & 0xFFFFu, 16);
}

static uint64_t get_wide(cm_ac_dec *d, cm_ac_int *m)
{
    uint64_t v = cm_ac_dec_uint(d, m);
    if (v == WIDE_ESCAPE) {
        v = 0;
        for (int k = 0; k < 4; k++)
            v = (v << 16) | cm_ac_dec_direct(d, 16);
    }
    return v;
}

uint32_t cm_fmt_stream_pack(uint8_t *b, cm_fmt_header *h, const uint32_t *need, uint32_t body_len)
{
    if (h->nlimits < CM_FMT_MIN_NEEDS)
        return 0; /* every writer declares format 1.0's 25 */
    /* the fields' stream first, after room for the longest H (5 bytes), then moved up to it */
    uint8_t *fields = b + CM_FMT_COMPACT_AT_H + 5u;
    uint32_t room = CM_FMT_MAX_HEADER - CM_FMT_COMPACT_AT_H - 5u - 4u;
    hdr_models m;
    hdr_models_init(&m);
    cm_ac_enc e;
    cm_ac_enc_init(&e, fields, room);
    double q = cm_fmt_grid_step(h->q_exp);
    cm_ac_enc_uint(&e, &m.flags, h->flags);
    cm_ac_enc_uint(&e, &m.extra_needs, h->nlimits - CM_FMT_MIN_NEEDS);
    cm_ac_enc_uint(&e, &m.body, body_len);
    uint32_t nd[CM_LIMIT_COUNT] = {0};
    for (uint32_t i = 0; i < h->nlimits; i++) {
        uint32_t v = need ? need[i] : 0;
        if (i < (uint32_t)CM_LIMIT_COUNT)
            nd[i] = v;
        if (i == CM_LIMIT_MAX_FILE_BYTES)
            continue;
        int64_t pred = i < (uint32_t)CM_LIMIT_COUNT ? cm_fmt_need_pred(i, nd) : 0;
        if (pred == 0)
            cm_ac_enc_uint(&e, &m.need, v);
        else
            cm_ac_enc_sint(&e, &m.need_diff, (int64_t)v - pred);
    }
    cm_ac_enc_sint(&e, &m.qexp, h->q_exp);
    int64_t om[3];
    uint32_t shift = origin_multiples(h, om);
    cm_ac_enc_uint(&e, &m.origin_shift, shift);
    for (int k = 0; k < 3; k++)
        put_wide(&e, &m.origin, cm_fmt_zigzag(om[k]));
    put_wide(&e, &m.tess, tess_steps(h, q));
    put_wide(&e, &m.rel, cm_fmt_zigzag(rel_units(h) - (int64_t)CM_FMT_REL_TOL_DEFAULT));
    size_t n = cm_ac_enc_finish_trimmed(&e);
    if (e.overflow)
        return 0;
    /* a header holds at least its minimum (zeros the trimmed stream left out count as its own) */
    while (CM_FMT_COMPACT_AT_H + 1u + n + 4u < CM_FMT_STREAM_MIN_HEADER)
        fields[n++] = 0;
    return close_header(b, h, (uint32_t)n, body_len);
}

const char *cm_fmt_stream_unpack(const uint8_t *b, uint32_t H, cm_fmt_header *h, uint32_t *need, uint32_t cap,
                                 uint32_t *unknown)
{
    uint32_t at = CM_FMT_COMPACT_AT_H;
    uint64_t x;
    if (H < CM_FMT_STREAM_MIN_HEADER || !cm_fmt_get_varint(b, H - 4u, &at, &x) || x != H)
        return "header length";
    memset(h, 0, sizeof *h);
    h->major = b[CM_HDR_MAJOR];
    h->minor = b[CM_HDR_MINOR];
    h->header_len = H;
    h->nsections = CM_SEC_COUNT;
    *unknown = UINT32_MAX;
    hdr_models m;
    hdr_models_init(&m);
    cm_ac_dec d;
    cm_ac_dec_init_trimmed(&d, b + at, H - 4u - at);
    x = cm_ac_dec_uint(&d, &m.flags);
    if (x > UINT16_MAX)
        return "header flags";
    h->flags = (uint16_t)x;
    x = cm_ac_dec_uint(&d, &m.extra_needs);
    if (x > 255u - CM_FMT_MIN_NEEDS)
        return "need count";
    h->nlimits = (uint8_t)(x + CM_FMT_MIN_NEEDS);
    uint64_t body = cm_ac_dec_uint(&d, &m.body);
    if (body > UINT32_MAX - 4u - H)
        return "file length";
    h->file_len = (uint32_t)(H + body + 4u);
    uint32_t nd[CM_LIMIT_COUNT] = {0};
    for (uint32_t i = 0; i < h->nlimits; i++) {
        int64_t v;
        if (i == CM_LIMIT_MAX_FILE_BYTES) {
            v = h->file_len;
        } else {
            int64_t pred = i < (uint32_t)CM_LIMIT_COUNT ? cm_fmt_need_pred(i, nd) : 0;
            v = pred == 0 ? (int64_t)cm_ac_dec_uint(&d, &m.need) : pred + cm_ac_dec_sint(&d, &m.need_diff);
            if (v < 0 || v > (int64_t)UINT32_MAX)
                return "header needs";
        }
        if (i < (uint32_t)CM_LIMIT_COUNT)
            nd[i] = (uint32_t)v;
        if (i < cap)
            need[i] = (uint32_t)v;
        else if (v != 0 && *unknown == UINT32_MAX)
            *unknown = i;
    }
    int64_t qe = cm_ac_dec_sint(&d, &m.qexp);
    if (qe < -128 || qe > 127)
        return "quantisation exponent";
    h->q_exp = (int8_t)qe;
    uint64_t shift = cm_ac_dec_uint(&d, &m.origin_shift);
    if (shift > CM_FMT_MAX_ORIGIN_SHIFT)
        return "grid origin step";
    /* the range of e, and so of the origin, is the reader's to check (CM_E_RANGE): here only what
       keeps the arithmetic defined */
    int e_ok = qe >= -60 && qe <= 20;
    double oq = cm_fmt_grid_step(e_ok ? (int)qe + (int)shift : 0);
    for (int k = 0; k < 3; k++)
        h->origin[k] = (double)cm_fmt_unzigzag(get_wide(&d, &m.origin)) * oq;
    h->tess_tol = (double)get_wide(&d, &m.tess) * cm_fmt_grid_step(e_ok ? (int)qe : 0);
    h->rel_tol = cm_fmt_rel_tol(cm_fmt_unzigzag(get_wide(&d, &m.rel)));
    if (d.overrun)
        return "header fields (past the header CRC)";
    /* an honest trimmed stream is read up to its end or past it (its zeros): bytes left unread are
       no field's, and a header padded with them would say the same in other bytes */
    if (d.pos < d.len)
        return "header length: fields end before the header CRC";
    return NULL;
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
    if (b[CM_HDR_MINOR] >= CM_FMT_ONE_STREAM_MINOR) {
        cm_fmt_header h;
        uint32_t unknown;
        if (!cm_fmt_get_varint(b, n, &at, &v) || v > n || cm_fmt_stream_unpack(b, (uint32_t)v, &h, need, cap, &unknown))
            return 0;
        *count = h.nlimits;
        return 1;
    }
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

const char *cm_model_part_name(const cm_model *m, uint32_t part)
{
    uint32_t at = 0;
    for (uint32_t p = 1; p < part && at < m->part_names_len; p++)
        while (at < m->part_names_len && m->part_names[at++] != 0)
            ;
    return part >= 1 && part <= m->nparts && at < m->part_names_len && m->part_names[at] != 0 ? &m->part_names[at]
                                                                                              : NULL;
}
