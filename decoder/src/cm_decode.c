/* cm_decode.c - the .cmz v1 reader (see cm_decode.h and docs/FORMAT.md). */
#include "cm/cm_decode.h"

#include <string.h>

#include "cm/cm_arith.h"
#include "cm/cm_bspline.h"
#include "cm/cm_sections.h"

#define COORD_MAX (1ll << 40)   /* integer grid coordinates beyond this are hostile */
#define WEIGHT_ONE (1ll << CM_FMT_WEIGHT_BITS)
#define WEIGHT_MAX (1ll << 48)
#define KNOT_ONE (1ll << CM_FMT_KNOT_BITS)

/*
 * A fuzzing build (the libFuzzer target only, never a product build) accepts wrong CRCs, so that
 * mutated files reach the section decoders instead of stopping at the checksum (the convention of
 * libpng, zlib and others on OSS-Fuzz).
 */
static int crc_differs(uint32_t computed, uint32_t stored)
{
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
    (void)computed;
    (void)stored;
    return 0;
#else
    return computed != stored;
#endif
}

void cm_dec_init(cm_decoder *d)
{
    d->state = CM_DEC_HEADER;
    d->len = 0;
    d->header_len = d->file_len = 0;
    d->nsec = 0;
    d->nlimits = 0;
    d->model.nverts = d->model.nedges = d->model.nfaces = 0;
}

int cm_dec_header_ok(const cm_decoder *d)
{
    return d->state == CM_DEC_BODY || d->state == CM_DEC_DONE;
}

static cm_err fail(cm_decoder *d, cm_status *st, cm_err e, uint32_t offset, const char *where)
{
    d->state = CM_DEC_FAILED;
    return cm_fail_at(st, e, offset, where);
}

/* ---- header ---- */

static cm_err check_header(cm_decoder *d, cm_status *st)
{
    const uint8_t *b = d->buf;
    uint32_t H = d->header_len;
    d->version_major = b[4];
    d->version_minor = b[5];
    d->flags = cm_get_u16(b + 6);
    d->file_len = cm_get_u32(b + 12);
    d->nlimits = b[16];
    d->nsec = b[17];
    uint32_t table = CM_FMT_FIXED_HEADER + 4u * d->nlimits;
    if (H != table + CM_FMT_SECTION_ENTRY * d->nsec + 4u)
        return fail(d, st, CM_E_FORMAT, 8, "header length");
    uint32_t crc = cm_get_u32(b + H - 4);
    if (crc_differs(cm_crc32(b, H - 4), crc))
        return fail(d, st, CM_E_CRC, H - 4, "header CRC");
    if (d->file_len < H + 4u || d->file_len > (uint32_t)CM_MAX_FILE_BYTES) {
        if (d->file_len > (uint32_t)CM_MAX_FILE_BYTES) {
            d->state = CM_DEC_FAILED;
            cm_fail_limit(st, CM_LIMIT_MAX_FILE_BYTES, d->file_len, CM_MAX_FILE_BYTES, "file length");
            if (st)
                st->offset = 12;
            return CM_E_LIMIT;
        }
        return fail(d, st, CM_E_FORMAT, 12, "file length");
    }
    /* the model's needs against this build: refused here, before the body */
    for (uint32_t i = 0; i < d->nlimits; i++) {
        uint32_t need = cm_get_u32(b + CM_FMT_FIXED_HEADER + 4 * i);
        if (i < (uint32_t)CM_LIMIT_COUNT) {
            d->need[i] = need;
            if (need > cm_limit_table[i].value) {
                d->state = CM_DEC_FAILED;
                cm_fail_limit(st, i, need, cm_limit_table[i].value, "header needs");
                if (st)
                    st->offset = CM_FMT_FIXED_HEADER + 4 * i;
                return CM_E_LIMIT;
            }
        } else if (need != 0) {
            /* a limit this build does not know about, and the model needs it */
            return fail(d, st, CM_E_VERSION, CM_FMT_FIXED_HEADER + 4 * i, "unknown limit");
        }
    }
    for (uint32_t i = d->nlimits; i < (uint32_t)CM_LIMIT_COUNT; i++)
        d->need[i] = 0;
    uint32_t prev_end = H;
    for (uint32_t s = 0; s < d->nsec; s++) {
        const uint8_t *e = b + table + CM_FMT_SECTION_ENTRY * s;
        cm_dec_section *sec = &d->sec[s];
        sec->tag = e[0];
        sec->off = cm_get_u32(e + 4);
        sec->len = cm_get_u32(e + 8);
        sec->crc = cm_get_u32(e + 12);
        uint32_t at = table + CM_FMT_SECTION_ENTRY * s;
        /* sections in tag order 1..5, each once, back to back after the header */
        if (sec->tag != s + 1 || e[1] || e[2] || e[3])
            return fail(d, st, CM_E_FORMAT, at, "section table");
        if (sec->off != prev_end || sec->len > d->file_len - 4u - sec->off)
            return fail(d, st, CM_E_FORMAT, at + 4, "section bounds");
        prev_end = sec->off + sec->len;
    }
    if (prev_end != d->file_len - 4u)
        return fail(d, st, CM_E_FORMAT, 12, "sections do not fill the file");
    double q = 1.0;
    int qe = (int8_t)b[18];
    for (int i = 0; i < (qe < 0 ? -qe : qe); i++)
        q = qe < 0 ? q * 0.5 : q * 2.0;
    d->model.q = q;
    for (int k = 0; k < 3; k++)
        d->model.origin[k] = cm_get_f64(b + 20 + 8 * k);
    d->model.tess_tol = cm_get_f64(b + 44);
    d->model.rel_tol = cm_get_f64(b + 52);
    if (qe < -60 || qe > 20 || !isfinite(d->model.origin[0]) || !isfinite(d->model.origin[1]) ||
        !isfinite(d->model.origin[2]) || !(d->model.tess_tol > 0) || !isfinite(d->model.tess_tol) ||
        !(d->model.rel_tol >= 0) || !isfinite(d->model.rel_tol))
        return fail(d, st, CM_E_NONFINITE, 18, "quantisation");
    d->state = CM_DEC_BODY;
    return CM_OK;
}

/* append header bytes (n fits the buffer and does not pass the header's end) and check what is in */
static cm_err feed_header(cm_decoder *d, const uint8_t *p, size_t n, cm_status *st)
{
    memcpy(d->buf + d->len, p, n);
    d->len += (uint32_t)n;
    /* magic first: a wrong file is refused at its first bytes */
    static const uint8_t magic[4] = {CM_FMT_MAGIC0, CM_FMT_MAGIC1, CM_FMT_MAGIC2, CM_FMT_MAGIC3};
    for (uint32_t i = 0; i < d->len && i < 4; i++)
        if (d->buf[i] != magic[i])
            return fail(d, st, CM_E_MAGIC, i, "magic");
    if (d->len >= 6 && (d->buf[4] < CM_FMT_VERSION_MIN_MAJOR || d->buf[4] > CM_FMT_VERSION_MAJOR))
        return fail(d, st, CM_E_VERSION, 4, "version");
    if (d->len < 12)
        return CM_OK;
    d->header_len = cm_get_u32(d->buf + 8);
    if (d->header_len < CM_FMT_FIXED_HEADER + 4u || d->header_len > CM_FMT_MAX_HEADER)
        return fail(d, st, CM_E_FORMAT, 8, "header length");
    if (d->header_len > (uint32_t)CM_MAX_FILE_BYTES) {
        d->state = CM_DEC_FAILED;
        cm_fail_limit(st, CM_LIMIT_MAX_FILE_BYTES, d->header_len, CM_MAX_FILE_BYTES, "header length");
        if (st)
            st->offset = 8;
        return CM_E_LIMIT;
    }
    if (d->len < d->header_len)
        return CM_OK;
    return check_header(d, st);
}

cm_err cm_dec_feed(cm_decoder *d, const uint8_t *p, size_t n, cm_status *st)
{
    if (d->state == CM_DEC_FAILED || d->state == CM_DEC_DONE)
        return cm_fail(st, CM_E_ARG, "cm_dec_feed");
    /*
     * The header first, however the bytes arrive: its checks (magic, version, the model's needs
     * against this build) decide before anything is said about the body, so a file too large for
     * this build is refused by name (MAX_FILE_BYTES, or whatever else it needs) and not as excess.
     */
    while (n > 0 && d->state == CM_DEC_HEADER) {
        uint32_t upto = d->len < 12 ? 12u : d->header_len; /* the next point where a check can run */
        size_t step = upto - d->len < n ? upto - d->len : n;
        cm_err e = feed_header(d, p, step, st);
        if (e != CM_OK)
            return e;
        p += step;
        n -= step;
    }
    if (n == 0)
        return CM_OK;
    if (n > (size_t)(d->file_len - d->len))
        return fail(d, st, CM_E_RANGE, d->file_len, "more bytes than the file");
    memcpy(d->buf + d->len, p, n);
    d->len += (uint32_t)n;
    return CM_OK;
}

/* ---- sections ---- */

typedef struct reader {
    cm_ac_dec ac;
    uint32_t base; /* file offset of the section */
    cm_decoder *d;
    cm_status *st;
} reader;

static uint32_t pos(const reader *r)
{
    return r->base + (uint32_t)r->ac.pos;
}

static cm_err rfail(reader *r, cm_err e, const char *where)
{
    return fail(r->d, r->st, r->ac.overrun ? CM_E_TRUNCATED : e, pos(r), where);
}

static cm_err rlimit(reader *r, unsigned id, uint64_t need, uint64_t have, const char *where)
{
    r->d->state = CM_DEC_FAILED;
    cm_fail_limit(r->st, id, need, have, where);
    if (r->st)
        r->st->offset = pos(r);
    return CM_E_LIMIT;
}

/* a count field: at most `cap` (else CM_E_LIMIT naming `id`) and at most what the header promised */
static cm_err read_count(reader *r, cm_ac_int *m, unsigned id, uint64_t cap, uint32_t *out, const char *where)
{
    uint64_t v = cm_ac_dec_uint(&r->ac, m);
    if (r->ac.overrun)
        return rfail(r, CM_E_TRUNCATED, where);
    if (v > cap)
        return rlimit(r, id, v, cap, where);
    *out = (uint32_t)v;
    return CM_OK;
}

static cm_err read_coord(reader *r, cm_ac_int *m, int64_t pred, int64_t *out, const char *where)
{
    int64_t v = pred + cm_ac_dec_sint(&r->ac, m);
    if (r->ac.overrun)
        return rfail(r, CM_E_TRUNCATED, where);
    if (v > COORD_MAX || v < -COORD_MAX)
        return rfail(r, CM_E_RANGE, where);
    *out = v;
    return CM_OK;
}

static cm_vec3 grid_point(const cm_model *m, const int64_t k[3])
{
    return cm_v3(m->origin[0] + m->q * (double)k[0], m->origin[1] + m->q * (double)k[1],
                 m->origin[2] + m->q * (double)k[2]);
}

static cm_err sec_vert(reader *r)
{
    cm_decoder *d = r->d;
    cm_model *m = &d->model;
    cm_vert_ctx ctx;
    cm_vert_ctx_init(&ctx);
    cm_err e = read_count(r, &ctx.count, CM_LIMIT_MAX_VERTICES, CM_MAX_VERTICES, &m->nverts, "vertex count");
    if (e != CM_OK)
        return e;
    int64_t prev[3] = {0, 0, 0};
    for (uint32_t i = 0; i < m->nverts; i++) {
        for (int k = 0; k < 3; k++) {
            if ((e = read_coord(r, &ctx.coord[k], prev[k], &d->vq[i][k], "vertex")) != CM_OK)
                return e;
            prev[k] = d->vq[i][k];
        }
        m->verts[i] = grid_point(m, d->vq[i]);
    }
    return CM_OK;
}

/* knots of a clamped vector on [0,1] for degree p and n control points, appended to the pool */
static cm_err read_knots(reader *r, cm_ac_prob *uniform_p, cm_ac_int *mk, int p, int n, uint32_t *knot0)
{
    cm_model *m = &r->d->model;
    uint32_t nk = (uint32_t)(n + p + 1);
    if (nk > CM_MAX_MODEL_KNOTS - m->nknots)
        return rlimit(r, CM_LIMIT_MAX_MODEL_KNOTS, (uint64_t)m->nknots + nk, CM_MAX_MODEL_KNOTS, "knots");
    double *K = m->knots + m->nknots;
    int interior = n - p - 1;
    for (int i = 0; i <= p; i++) {
        K[i] = 0.0;
        K[n + i] = 1.0;
    }
    if (cm_ac_dec_bit(&r->ac, uniform_p)) {
        for (int j = 1; j <= interior; j++)
            K[p + j] = (double)j / (double)(interior + 1);
    } else {
        int64_t prev = 0;
        for (int j = 1; j <= interior; j++) {
            int64_t kq = prev + (int64_t)cm_ac_dec_uint(&r->ac, mk);
            if (r->ac.overrun)
                return rfail(r, CM_E_TRUNCATED, "knots");
            if (kq > KNOT_ONE)
                return rfail(r, CM_E_KNOTS, "knots");
            K[p + j] = (double)kq / (double)KNOT_ONE;
            prev = kq;
        }
    }
    *knot0 = m->nknots;
    m->nknots += nk;
    return CM_OK;
}

/* a vertex reference: the next unseen vertex, or one seen `back` references ago */
static cm_err read_vref(reader *r, cm_ac_prob *newp, cm_ac_int *mb, uint32_t *next, int32_t *out)
{
    const cm_model *m = &r->d->model;
    if (cm_ac_dec_bit(&r->ac, newp)) {
        if (*next >= m->nverts)
            return rfail(r, CM_E_RANGE, "vertex reference");
        *out = (int32_t)(*next)++;
        return CM_OK;
    }
    uint64_t back = cm_ac_dec_uint(&r->ac, mb);
    if (r->ac.overrun)
        return rfail(r, CM_E_TRUNCATED, "vertex reference");
    if (back >= *next)
        return rfail(r, CM_E_RANGE, "vertex reference");
    *out = (int32_t)(*next - 1 - back);
    return CM_OK;
}

static cm_err sec_edge(reader *r)
{
    cm_decoder *d = r->d;
    cm_model *m = &d->model;
    cm_edge_ctx ctx;
    cm_edge_ctx_init(&ctx);
    cm_err e = read_count(r, &ctx.count, CM_LIMIT_MAX_EDGES, CM_MAX_EDGES, &m->nedges, "edge count");
    if (e != CM_OK)
        return e;
    uint32_t vnext = 0;
    for (uint32_t i = 0; i < m->nedges; i++) {
        cm_edge *E = &m->edges[i];
        if ((e = read_vref(r, &ctx.is_new, &ctx.back, &vnext, &E->v0)) != CM_OK ||
            (e = read_vref(r, &ctx.is_new, &ctx.back, &vnext, &E->v1)) != CM_OK)
            return e;
        E->g1 = (uint8_t)cm_ac_dec_bit(&r->ac, &ctx.g1);
        E->kind = (uint8_t)cm_ac_dec_bit(&r->ac, &ctx.kind);
        int p = 1, n = 2, rational = 0;
        if (E->kind == CM_EDGE_CURVE) {
            uint64_t pv = cm_ac_dec_uint(&r->ac, &ctx.degree) + 1;
            if (pv > CM_MAX_DEGREE)
                return rlimit(r, CM_LIMIT_MAX_DEGREE, pv, CM_MAX_DEGREE, "edge degree");
            p = (int)pv;
            uint64_t nv = cm_ac_dec_uint(&r->ac, &ctx.ncoef) + (uint64_t)p + 1;
            if (nv > CM_MAX_EDGE_CTRL)
                return rlimit(r, CM_LIMIT_MAX_EDGE_CTRL, nv, CM_MAX_EDGE_CTRL, "edge control points");
            n = (int)nv;
            rational = (int)cm_ac_dec_bit(&r->ac, &ctx.rational);
        }
        if ((uint32_t)n > CM_MAX_MODEL_CTRL - m->nctrl)
            return rlimit(r, CM_LIMIT_MAX_MODEL_CTRL, (uint64_t)m->nctrl + (uint32_t)n, CM_MAX_MODEL_CTRL,
                          "control points");
        E->p = (uint8_t)p;
        E->nctrl = (uint16_t)n;
        E->rational = (uint8_t)rational;
        if (E->kind == CM_EDGE_LINE) {
            if (2 + 2 > CM_MAX_MODEL_KNOTS - m->nknots)
                return rlimit(r, CM_LIMIT_MAX_MODEL_KNOTS, (uint64_t)m->nknots + 4, CM_MAX_MODEL_KNOTS, "knots");
            double *K = m->knots + m->nknots;
            K[0] = K[1] = 0.0;
            K[2] = K[3] = 1.0;
            E->knot0 = m->nknots;
            m->nknots += 4;
        } else if ((e = read_knots(r, &ctx.uniform, &ctx.knot, p, n, &E->knot0)) != CM_OK) {
            return e;
        }
        E->ctrl0 = m->nctrl;
        cm_vec3 *P = m->ctrl + m->nctrl;
        double *W = m->w + m->nctrl;
        int64_t prev[3] = {d->vq[E->v0][0], d->vq[E->v0][1], d->vq[E->v0][2]};
        P[0] = m->verts[E->v0];
        for (int j = 1; j < n - 1; j++) {
            int64_t k3[3];
            for (int k = 0; k < 3; k++) {
                if ((e = read_coord(r, &ctx.coord[k], prev[k], &k3[k], "edge control point")) != CM_OK)
                    return e;
                prev[k] = k3[k];
            }
            P[j] = grid_point(m, k3);
        }
        P[n - 1] = m->verts[E->v1];
        int64_t wq = WEIGHT_ONE;
        W[0] = 1.0;
        for (int j = 1; j < n; j++) {
            if (rational) {
                wq += cm_ac_dec_sint(&r->ac, &ctx.weight);
                if (r->ac.overrun)
                    return rfail(r, CM_E_TRUNCATED, "weights");
                if (wq <= 0 || wq > WEIGHT_MAX)
                    return rfail(r, CM_E_RANGE, "weights");
            }
            W[j] = (double)wq / (double)WEIGHT_ONE;
        }
        m->nctrl += (uint32_t)n;
        cm_curve c;
        cm_model_edge_curve(m, i, &c);
        cm_status cst;
        cm_status_init(&cst);
        if (cm_curve_check(&c, &cst) != CM_OK)
            return rfail(r, cst.code == CM_E_LIMIT ? CM_E_FORMAT : cst.code, "edge curve");
    }
    if (vnext != m->nverts)
        return rfail(r, CM_E_FORMAT, "unused vertices");
    return CM_OK;
}

static cm_err sec_surf(reader *r)
{
    cm_decoder *d = r->d;
    cm_model *m = &d->model;
    cm_surf_ctx ctx;
    cm_surf_ctx_init(&ctx);
    cm_err e = read_count(r, &ctx.count, CM_LIMIT_MAX_FACES, CM_MAX_FACES, &m->nsurfs, "surface count");
    if (e != CM_OK)
        return e;
    for (uint32_t s = 0; s < m->nsurfs; s++) {
        cm_ksurf *S = &m->surfs[s];
        int deg[2], cnt[2];
        for (int dir = 0; dir < 2; dir++) {
            uint64_t pv = cm_ac_dec_uint(&r->ac, &ctx.degree) + 1;
            if (pv > CM_MAX_DEGREE)
                return rlimit(r, CM_LIMIT_MAX_DEGREE, pv, CM_MAX_DEGREE, "surface degree");
            uint64_t nv = cm_ac_dec_uint(&r->ac, &ctx.ncoef) + pv + 1;
            if (nv > CM_MAX_SURF_CTRL_DIR)
                return rlimit(r, CM_LIMIT_MAX_SURF_CTRL_DIR, nv, CM_MAX_SURF_CTRL_DIR, "surface control points");
            deg[dir] = (int)pv;
            cnt[dir] = (int)nv;
        }
        uint64_t total = (uint64_t)cnt[0] * (uint64_t)cnt[1];
        if (total > CM_MAX_SURF_CTRL)
            return rlimit(r, CM_LIMIT_MAX_SURF_CTRL, total, CM_MAX_SURF_CTRL, "surface control points");
        if (total > CM_MAX_MODEL_CTRL - m->nctrl)
            return rlimit(r, CM_LIMIT_MAX_MODEL_CTRL, m->nctrl + total, CM_MAX_MODEL_CTRL, "control points");
        S->p = (uint8_t)deg[0];
        S->q = (uint8_t)deg[1];
        S->nu = (uint16_t)cnt[0];
        S->nv = (uint16_t)cnt[1];
        S->rational = (uint8_t)cm_ac_dec_bit(&r->ac, &ctx.rational);
        if ((e = read_knots(r, &ctx.uniform, &ctx.knot, deg[0], cnt[0], &S->uknot0)) != CM_OK ||
            (e = read_knots(r, &ctx.uniform, &ctx.knot, deg[1], cnt[1], &S->vknot0)) != CM_OK)
            return e;
        S->ctrl0 = m->nctrl;
        int nu = cnt[0], nv = cnt[1];
        /* parallelogram prediction over the net, row-major in u */
        for (int i = 0; i < nu; i++)
            for (int j = 0; j < nv; j++) {
                int idx = i * nv + j;
                for (int k = 0; k < 3; k++) {
                    int64_t pred = i && j ? d->sq[idx - nv][k] + d->sq[idx - 1][k] - d->sq[idx - nv - 1][k]
                                   : i    ? d->sq[idx - nv][k]
                                   : j    ? d->sq[idx - 1][k]
                                          : 0;
                    if ((e = read_coord(r, &ctx.coord[k], pred, &d->sq[idx][k], "surface control point")) != CM_OK)
                        return e;
                }
                m->ctrl[S->ctrl0 + (uint32_t)idx] = grid_point(m, d->sq[idx]);
                int64_t wq = WEIGHT_ONE;
                if (S->rational && idx > 0) {
                    int64_t pred = i && j ? d->sw[idx - nv] + d->sw[idx - 1] - d->sw[idx - nv - 1]
                                   : i    ? d->sw[idx - nv]
                                          : d->sw[idx - 1];
                    wq = pred + cm_ac_dec_sint(&r->ac, &ctx.weight);
                    if (r->ac.overrun)
                        return rfail(r, CM_E_TRUNCATED, "weights");
                    if (wq <= 0 || wq > WEIGHT_MAX)
                        return rfail(r, CM_E_RANGE, "weights");
                }
                d->sw[idx] = wq;
                m->w[S->ctrl0 + (uint32_t)idx] = (double)wq / (double)WEIGHT_ONE;
            }
        m->nctrl += (uint32_t)total;
        cm_surf sv;
        cm_model_surface(m, s, &sv);
        cm_status cst;
        cm_status_init(&cst);
        if (cm_surf_check(&sv, &cst) != CM_OK)
            return rfail(r, cst.code == CM_E_LIMIT ? CM_E_FORMAT : cst.code, "surface");
    }
    return CM_OK;
}

static cm_err sec_face(reader *r)
{
    cm_model *m = &r->d->model;
    cm_face_ctx ctx;
    cm_face_ctx_init(&ctx);
    cm_err e = read_count(r, &ctx.count, CM_LIMIT_MAX_FACES, CM_MAX_FACES, &m->nfaces, "face count");
    if (e != CM_OK)
        return e;
    uint32_t enext = 0, snext = 0;
    m->nloops = m->nuses = 0;
    for (uint32_t f = 0; f < m->nfaces; f++) {
        cm_face *F = &m->faces[f];
        uint64_t meth = cm_ac_dec_uint(&r->ac, &ctx.method);
        if (r->ac.overrun)
            return rfail(r, CM_E_TRUNCATED, "face method");
        if (meth >= CM_METHOD_COUNT)
            return rfail(r, CM_E_UNSUPPORTED, "face method");
        /* format 1 knows KEEP and PLANE only */
        if (meth == CM_METHOD_GREGORY && r->d->buf[4] < 2)
            return rfail(r, CM_E_UNSUPPORTED, "GREGORY face in a format 1 file");
        F->method = (uint8_t)meth;
        F->layout = F->corner = 0;
        F->checksum = 0;
        if (F->method == CM_METHOD_GREGORY) {
            uint64_t layout = cm_ac_dec_uint(&r->ac, &ctx.layout);
            uint64_t corner = cm_ac_dec_uint(&r->ac, &ctx.corner);
            F->checksum = cm_ac_dec_direct(&r->ac, 16);
            F->checksum |= cm_ac_dec_direct(&r->ac, 16) << 16;
            if (r->ac.overrun)
                return rfail(r, CM_E_TRUNCATED, "face record");
            if (layout > 2)
                return rfail(r, CM_E_RANGE, "GREGORY layout");
            if (corner >= CM_MAX_SIDES || (layout != 2 && corner != 0))
                return rfail(r, CM_E_RANGE, "GREGORY corner");
            F->layout = (uint8_t)layout;
            F->corner = (uint8_t)corner;
        }
        F->flip = (uint8_t)cm_ac_dec_bit(&r->ac, &ctx.flip);
        F->color = 0;
        F->surf = 0;
        if (F->method == CM_METHOD_KEEP) {
            if (snext >= m->nsurfs)
                return rfail(r, CM_E_RANGE, "kept surface");
            F->surf = snext++;
        }
        uint32_t nl, face_uses = 0;
        if ((e = read_count(r, &ctx.loops, CM_LIMIT_MAX_LOOPS, CM_MAX_LOOPS, &nl, "loop count")) != CM_OK)
            return e;
        if (nl == 0)
            return rfail(r, CM_E_FORMAT, "face without loops");
        if (nl > CM_MAX_MODEL_LOOPS - m->nloops)
            return rlimit(r, CM_LIMIT_MAX_MODEL_LOOPS, (uint64_t)m->nloops + nl, CM_MAX_MODEL_LOOPS, "loops");
        F->loop0 = m->nloops;
        F->nloops = (uint16_t)nl;
        for (uint32_t l = 0; l < nl; l++) {
            cm_loop *L = &m->loops[m->nloops++];
            uint32_t nu;
            if ((e = read_count(r, &ctx.uses, CM_LIMIT_MAX_LOOP_EDGES, CM_MAX_LOOP_EDGES, &nu, "loop size")) != CM_OK)
                return e;
            if (nu == 0)
                return rfail(r, CM_E_FORMAT, "empty loop");
            face_uses += nu;
            if (face_uses > CM_MAX_FACE_EDGES)
                return rlimit(r, CM_LIMIT_MAX_FACE_EDGES, face_uses, CM_MAX_FACE_EDGES, "face edges");
            if (nu > CM_MAX_MODEL_USES - m->nuses)
                return rlimit(r, CM_LIMIT_MAX_MODEL_USES, (uint64_t)m->nuses + nu, CM_MAX_MODEL_USES, "edge uses");
            L->use0 = m->nuses;
            L->nuse = (uint16_t)nu;
            for (uint32_t k = 0; k < nu; k++) {
                cm_use *U = &m->uses[m->nuses++];
                if (cm_ac_dec_bit(&r->ac, &ctx.is_new)) {
                    if (enext >= m->nedges)
                        return rfail(r, CM_E_RANGE, "edge reference");
                    U->edge = enext++;
                    U->rev = (uint8_t)cm_ac_dec_bit(&r->ac, &ctx.rev_new);
                } else {
                    uint64_t back = cm_ac_dec_uint(&r->ac, &ctx.back);
                    if (r->ac.overrun)
                        return rfail(r, CM_E_TRUNCATED, "edge reference");
                    if (back >= enext)
                        return rfail(r, CM_E_RANGE, "edge reference");
                    U->edge = (uint32_t)(enext - 1 - back);
                    U->rev = (uint8_t)cm_ac_dec_bit(&r->ac, &ctx.rev_old);
                }
            }
            /* the loop must close: each use ends where the next begins */
            for (uint32_t k = 0; k < nu; k++) {
                const cm_use *a = &m->uses[L->use0 + k], *b = &m->uses[L->use0 + (k + 1) % nu];
                int32_t end = a->rev ? m->edges[a->edge].v0 : m->edges[a->edge].v1;
                int32_t start = b->rev ? m->edges[b->edge].v1 : m->edges[b->edge].v0;
                if (end != start)
                    return rfail(r, CM_E_FORMAT, "loop not closed");
            }
        }
    }
    if (r->ac.overrun)
        return rfail(r, CM_E_TRUNCATED, "faces");
    if (enext != m->nedges || snext != m->nsurfs)
        return rfail(r, CM_E_FORMAT, "unused edges or surfaces");
    /* GREGORY needs one loop of 3..CM_MAX_SIDES edges; layout 0 only for 4, layout 2 only for 3 */
    for (uint32_t f = 0; f < m->nfaces; f++) {
        const cm_face *F = &m->faces[f];
        uint32_t n = m->loops[F->loop0].nuse;
        if (F->method != CM_METHOD_GREGORY)
            continue;
        if (F->nloops != 1)
            return rfail(r, CM_E_FORMAT, "GREGORY face with holes");
        if (n < 3)
            return rfail(r, CM_E_FORMAT, "GREGORY face with fewer than 3 sides");
        if ((F->layout == 0 && n != 4) || (F->layout == 2 && n != 3))
            return rfail(r, CM_E_FORMAT, "GREGORY sides do not fit the layout");
        if (F->layout == 2 && F->corner >= n)
            return rfail(r, CM_E_FORMAT, "GREGORY corner beyond the loop");
        if (n > CM_MAX_SIDES)
            return rlimit(r, CM_LIMIT_MAX_SIDES, n, CM_MAX_SIDES, "GREGORY sides");
    }
    cm_model_adjacency(m);
    return CM_OK;
}

static cm_err sec_colr(reader *r)
{
    cm_model *m = &r->d->model;
    cm_colr_ctx ctx;
    cm_colr_ctx_init(&ctx);
    uint64_t np = cm_ac_dec_uint(&r->ac, &ctx.count);
    if (r->ac.overrun)
        return rfail(r, CM_E_TRUNCATED, "palette");
    if (np > CM_FMT_MAX_PALETTE)
        return rfail(r, CM_E_RANGE, "palette");
    m->npalette = (uint32_t)np;
    m->palette[0] = 0;
    for (uint32_t i = 1; i <= m->npalette; i++)
        m->palette[i] = cm_ac_dec_direct(&r->ac, 24);
    if (m->npalette == 0)
        return r->ac.overrun ? rfail(r, CM_E_TRUNCATED, "palette") : CM_OK;
    for (uint32_t f = 0; f < m->nfaces; f++) {
        uint64_t c = cm_ac_dec_uint(&r->ac, &ctx.index);
        if (c > m->npalette)
            return rfail(r, CM_E_RANGE, "face colour");
        m->faces[f].color = (uint8_t)c;
    }
    if (r->ac.overrun)
        return rfail(r, CM_E_TRUNCATED, "face colours");
    return CM_OK;
}

cm_err cm_dec_finish(cm_decoder *d, cm_status *st)
{
    if (d->state != CM_DEC_BODY) {
        if (d->state == CM_DEC_HEADER)
            return fail(d, st, CM_E_TRUNCATED, d->len, "header incomplete");
        return cm_fail(st, CM_E_ARG, "cm_dec_finish");
    }
    if (d->len < d->file_len)
        return fail(d, st, CM_E_TRUNCATED, d->len, "file shorter than its header says");
    if (crc_differs(cm_crc32(d->buf, d->file_len - 4), cm_get_u32(d->buf + d->file_len - 4)))
        return fail(d, st, CM_E_CRC, d->file_len - 4, "file CRC");
    cm_model *m = &d->model;
    m->nverts = m->nedges = m->nfaces = m->nloops = m->nuses = m->nsurfs = m->nctrl = m->nknots = 0;
    m->npalette = 0;
    for (uint32_t s = 0; s < d->nsec; s++) {
        const cm_dec_section *sec = &d->sec[s];
        if (crc_differs(cm_crc32(d->buf + sec->off, sec->len), sec->crc))
            return fail(d, st, CM_E_CRC, sec->off, "section CRC");
        reader r;
        cm_ac_dec_init(&r.ac, d->buf + sec->off, sec->len);
        r.base = sec->off;
        r.d = d;
        r.st = st;
        cm_err e;
        switch (sec->tag) {
        case CM_SEC_VERT: e = sec_vert(&r); break;
        case CM_SEC_EDGE: e = sec_edge(&r); break;
        case CM_SEC_SURF: e = sec_surf(&r); break;
        case CM_SEC_FACE: e = sec_face(&r); break;
        case CM_SEC_COLR: e = sec_colr(&r); break;
        default: e = fail(d, st, CM_E_FORMAT, sec->off, "section tag"); break;
        }
        if (e != CM_OK)
            return e;
    }
    if (d->nsec != CM_SEC_COUNT)
        return fail(d, st, CM_E_FORMAT, 17, "section count");
    d->state = CM_DEC_DONE;
    return CM_OK;
}
