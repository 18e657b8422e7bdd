/* cm_decode.c - the .cmz reader, formats 1 to 4 (see cm_decode.h and docs/FORMAT.md). */
#include "cm/cm_decode.h"

#include <math.h>
#include <string.h>

#include "cm/cm_arc.h"
#include "cm/cm_arith.h"
#include "cm/cm_crc32.h"
#include "cm/cm_gregface.h"
#include "cm/cm_bspline.h"
#include "cm/cm_limits_info.h"
#include "cm/cm_method.h"
#include "cm/cm_predict.h"
#include "cm/cm_sections.h"
#include "cm/cm_use_adj.h"

#define COORD_MAX CM_FMT_COORD_MAX
#define WEIGHT_ONE (1ll << CM_FMT_WEIGHT_BITS)
#define WEIGHT_MAX CM_FMT_WEIGHT_MAX
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
    d->model.nplacements = 0;
    d->crc = 0;
    memset(d->file_crc, 0, sizeof d->file_crc);
    d->src_read = NULL;
    d->src_ctx = NULL;
}

void cm_dec_set_source(cm_decoder *d, cm_dec_read_fn *read, void *ctx)
{
    d->src_read = read;
    d->src_ctx = ctx;
}

/* bytes [off, off + n) of the body as they are fed (off = d->len): the part within the window kept,
   the part before the file's CRC into the running CRC, the CRC's own bytes aside */
static void take_bytes(cm_decoder *d, uint32_t off, const uint8_t *p, size_t n, int copy)
{
    const uint32_t crc_end = d->file_len - 4u;
    if (copy && off < (uint32_t)CM_FILE_WINDOW_BYTES) {
        size_t k = (uint32_t)CM_FILE_WINDOW_BYTES - off < n ? (uint32_t)CM_FILE_WINDOW_BYTES - off : n;
        memcpy(d->buf + off, p, k);
    }
    if (off < crc_end)
        d->crc = cm_crc32_update(d->crc, p, crc_end - off < n ? crc_end - off : n);
    for (size_t i = off < crc_end ? crc_end - off : 0; i < n; i++)
        d->file_crc[off + i - crc_end] = p[i];
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

/* |origin| at most 2^100 mm: every grid point origin + q k (|k| <= 2^40, q <= 2^20) stays below
   2^101, far inside the range of the float positions the writers emit (2^128) */
#define ORIGIN_MAX 0x1p100

static cm_err header_limit(cm_decoder *d, cm_status *st, unsigned id, uint64_t need, uint64_t have, uint32_t at,
                           const char *where)
{
    int open = st && st->code == CM_OK;
    d->state = CM_DEC_FAILED;
    cm_fail_limit(st, id, need, have, where);
    if (open)
        st->offset = at;
    return CM_E_LIMIT;
}

/*
 * The whole header is in (d->header_len bytes, a length feed_header checked).  Every field is
 * checked before anything uses it: counts before they size or index anything (the section table
 * has room for CM_SEC_COUNT entries: a file declaring another number of sections is refused here,
 * before the table is read), lengths and offsets before any byte is addressed through them.
 */
_Static_assert(CM_LIMIT_COUNT >= CM_FMT_MIN_NEEDS, "the limit list only grows (its position is the id on the wire)");

static uint32_t declared(uint32_t need) { return need > 0 ? need : 1u; }

/* the header's fields, wherever its format put them: the offsets name a refused field */
typedef struct header_view {
    cm_fmt_header h;
    uint32_t at_nlimits, at_nsec, at_file_len, at_qexp, at_origin[3], at_tess, at_rel;
} header_view;

/* need i of the model against this build (i past the build's list: must be 0) */
static cm_err check_need(cm_decoder *d, cm_status *st, uint32_t i, uint32_t need, uint32_t at)
{
    if (i < (uint32_t)CM_LIMIT_COUNT) {
        d->need[i] = need;
        if (need > cm_limit_table[i].value)
            return header_limit(d, st, i, need, cm_limit_table[i].value, at, "header needs");
    } else if (need != 0) {
        /* a limit this build does not know about, and the model needs it */
        return fail(d, st, CM_E_VERSION, at, "unknown limit");
    }
    return CM_OK;
}

/* the counts every version checks before its tables are read */
static cm_err check_counts(cm_decoder *d, cm_status *st, const header_view *v)
{
    if (v->h.nsections != CM_SEC_COUNT)
        return fail(d, st, CM_E_FORMAT, v->at_nsec, "section count (a .cmz has 5 sections)");
    /* every writer declares the 25 needs of format 1.0; without MAX_TRIS, MAX_TESS_POINTS and
       MAX_EDGE_SAMPLES the tessellation would be bounded only by this build's limits (on the
       workstation: minutes for a 4 KB file whose tolerance says 1e-300 mm) */
    if (v->h.nlimits < CM_FMT_MIN_NEEDS)
        return fail(d, st, CM_E_FORMAT, v->at_nlimits, "need table shorter than the 25 needs of format 1.0");
    return CM_OK;
}

/* formats 1-3: fixed fields, a u32 per need, a 16-byte entry per section with its CRC */
static cm_err parse_fixed(cm_decoder *d, cm_status *st, header_view *v)
{
    const uint8_t *b = d->buf;
    uint32_t H = d->header_len;
    cm_fmt_header_unpack(b, &v->h);
    v->at_nlimits = CM_HDR_NLIMITS;
    v->at_nsec = CM_HDR_NSECTIONS;
    v->at_file_len = CM_HDR_FILE_LENGTH;
    v->at_qexp = CM_HDR_QEXP;
    for (uint32_t k = 0; k < 3; k++)
        v->at_origin[k] = CM_HDR_ORIGIN + 8u * k;
    v->at_tess = CM_HDR_TESS_TOL;
    v->at_rel = CM_HDR_REL_TOL;
    uint32_t nsec = v->h.nsections;
    /* H must be exactly the fixed fields, the two tables and the CRC (nlimits, nsec <= 255: no
       overflow); then the CRC, which covers every field below */
    if (H != cm_fmt_header_len(v->h.nlimits, nsec))
        return fail(d, st, CM_E_FORMAT, CM_HDR_LENGTH, "header length does not fit its need and section counts");
    if (crc_differs(cm_crc32(b, H - 4), cm_get_u32(b + H - 4)))
        return fail(d, st, CM_E_CRC, H - 4, "header CRC");
    cm_err e = check_counts(d, st, v);
    if (e != CM_OK)
        return e;
    d->file_len = v->h.file_len;
    if (d->file_len > (uint32_t)CM_MAX_FILE_BYTES)
        return header_limit(d, st, CM_LIMIT_MAX_FILE_BYTES, d->file_len, CM_MAX_FILE_BYTES, CM_HDR_FILE_LENGTH,
                            "file length");
    if (d->file_len < H + 4u)
        return fail(d, st, CM_E_FORMAT, CM_HDR_FILE_LENGTH, "file length shorter than its header and trailer");
    /* the model's needs against this build: refused here, before the body */
    for (uint32_t i = 0; i < v->h.nlimits; i++)
        if ((e = check_need(d, st, i, cm_get_u32(b + cm_fmt_need_at(i)), cm_fmt_need_at(i))) != CM_OK)
            return e;
    /* the section table: tags 1..5 in order, each once, back to back after the header, filling the
       file up to its trailer (offsets and lengths checked before cm_dec_finish addresses bytes) */
    uint32_t prev_end = H;
    for (uint32_t s = 0; s < CM_SEC_COUNT; s++) {
        uint32_t at = cm_fmt_entry_at(v->h.nlimits, s);
        const uint8_t *en = b + at;
        cm_dec_section *sec = &d->sec[s];
        sec->tag = en[CM_ENT_TAG];
        sec->off = cm_get_u32(en + CM_ENT_OFFSET);
        sec->len = cm_get_u32(en + CM_ENT_LENGTH);
        sec->crc = cm_get_u32(en + CM_ENT_CRC);
        sec->has_crc = 1;
        if (sec->tag != s + 1)
            return fail(d, st, CM_E_FORMAT, at, "section table: tags must be 1..5 in order");
        if (en[CM_ENT_RESERVED] || en[CM_ENT_RESERVED + 1] || en[CM_ENT_RESERVED + 2])
            return fail(d, st, CM_E_FORMAT, at + CM_ENT_RESERVED, "section table: reserved bytes must be 0");
        if (sec->off != prev_end)
            return fail(d, st, CM_E_FORMAT, at + CM_ENT_OFFSET,
                        "section offset: sections follow the header back to back");
        if (sec->len > d->file_len - 4u - sec->off)
            return fail(d, st, CM_E_FORMAT, at + CM_ENT_LENGTH, "section length: beyond the end of the file");
        prev_end = sec->off + sec->len;
    }
    if (prev_end != d->file_len - 4u)
        return fail(d, st, CM_E_FORMAT, CM_HDR_FILE_LENGTH, "sections do not fill the file");
    return CM_OK;
}

/* one varint of format 4's header, at most `max` (a field past it is malformed: CM_E_FORMAT) */
static cm_err header_varint(cm_decoder *d, cm_status *st, uint32_t *at, uint64_t max, uint64_t *out,
                            uint32_t *field_at, const char *where)
{
    uint32_t end = d->header_len - 4u;
    *field_at = *at;
    if (!cm_fmt_get_varint(d->buf, end, at, out))
        return fail(d, st, CM_E_FORMAT, *field_at, where);
    if (*out > max)
        return fail(d, st, CM_E_FORMAT, *field_at, where);
    return CM_OK;
}

/*
 * Format 4.6: the fields are one range-coded stream (cm_fmt_stream_unpack); a malformed one is
 * named, then the file's length and each need are checked against this build in the order of 4.5's
 * header.  Offsets in messages are the stream's start: its fields have no byte of their own.
 */
static cm_err parse_stream(cm_decoder *d, cm_status *st, header_view *v)
{
    uint32_t at = CM_FMT_COMPACT_AT_H, unknown;
    uint32_t need[CM_LIMIT_COUNT];
    uint64_t H;
    (void)cm_fmt_get_varint(d->buf, d->header_len, &at, &H); /* feed_header read it: at is after it */
    const char *fault = cm_fmt_stream_unpack(d->buf, d->header_len, &v->h, need, CM_LIMIT_COUNT, &unknown);
    if (fault)
        return fail(d, st, CM_E_FORMAT, at, fault);
    v->at_nlimits = v->at_nsec = v->at_file_len = v->at_qexp = v->at_tess = v->at_rel = at;
    for (uint32_t k = 0; k < 3; k++)
        v->at_origin[k] = at;
    cm_err e = check_counts(d, st, v);
    if (e != CM_OK)
        return e;
    if (v->h.file_len > (uint32_t)CM_MAX_FILE_BYTES)
        return header_limit(d, st, CM_LIMIT_MAX_FILE_BYTES, v->h.file_len, CM_MAX_FILE_BYTES, at, "file length");
    for (uint32_t i = 0; i < v->h.nlimits && i < (uint32_t)CM_LIMIT_COUNT; i++)
        if ((e = check_need(d, st, i, need[i], at)) != CM_OK)
            return e;
    if (unknown != UINT32_MAX)
        return fail(d, st, CM_E_VERSION, at, "unknown limit");
    d->file_len = v->h.file_len;
    /* one stream of the five sections fills the body: cm_dec_finish reads it through */
    for (uint32_t s = 0; s < CM_SEC_COUNT; s++) {
        cm_dec_section *sec = &d->sec[s];
        sec->tag = (uint8_t)(s + 1);
        sec->off = s == 0 ? d->header_len : d->file_len - 4u;
        sec->len = s == 0 ? d->file_len - 4u - d->header_len : 0u;
        sec->crc = 0;
        sec->has_crc = 0;
    }
    return CM_OK;
}

/* format 4: the compact header (cm_format.h), CRC first, then each field in order */
static cm_err parse_compact(cm_decoder *d, cm_status *st, header_view *v)
{
    const uint8_t *b = d->buf;
    uint32_t H = d->header_len;
    if (crc_differs(cm_crc32(b, H - 4), cm_get_u32(b + H - 4)))
        return fail(d, st, CM_E_CRC, H - 4, "header CRC");
    if (b[CM_HDR_MINOR] >= CM_FMT_ONE_STREAM_MINOR)
        return parse_stream(d, st, v);
    memset(&v->h, 0, sizeof v->h);
    v->h.major = b[CM_HDR_MAJOR];
    v->h.minor = b[CM_HDR_MINOR];
    v->h.header_len = H;
    uint32_t at = CM_FMT_COMPACT_AT_H, fat;
    uint64_t x;
    cm_err e;
    /* H again (feed_header read it), then the flags */
    if ((e = header_varint(d, st, &at, UINT32_MAX, &x, &fat, "header length")) != CM_OK ||
        (e = header_varint(d, st, &at, UINT16_MAX, &x, &fat, "header flags")) != CM_OK)
        return e;
    v->h.flags = (uint16_t)x;
    if ((e = header_varint(d, st, &at, 255, &x, &v->at_nlimits, "need count")) != CM_OK)
        return e;
    v->h.nlimits = (uint8_t)x;
    /* a short need table is refused at its count, before its needs are read as other fields */
    if (v->h.nlimits < CM_FMT_MIN_NEEDS)
        return fail(d, st, CM_E_FORMAT, v->at_nlimits, "need table shorter than the 25 needs of format 1.0");
    for (uint32_t i = 0; i < v->h.nlimits; i++) {
        if ((e = header_varint(d, st, &at, UINT32_MAX, &x, &fat, "header needs")) != CM_OK ||
            (e = check_need(d, st, i, (uint32_t)x, fat)) != CM_OK)
            return e;
    }
    if ((e = header_varint(d, st, &at, 255, &x, &v->at_nsec, "section count")) != CM_OK)
        return e;
    v->h.nsections = (uint8_t)x;
    if ((e = check_counts(d, st, v)) != CM_OK)
        return e;
    /* the sections back to back after the header; the file is they and its trailer */
    uint64_t off = H;
    for (uint32_t s = 0; s < CM_SEC_COUNT; s++) {
        if ((e = header_varint(d, st, &at, UINT32_MAX, &x, &v->at_file_len, "section length")) != CM_OK)
            return e;
        cm_dec_section *sec = &d->sec[s];
        sec->tag = (uint8_t)(s + 1);
        sec->off = (uint32_t)(off < UINT32_MAX ? off : UINT32_MAX);
        sec->len = (uint32_t)x;
        sec->crc = 0;
        sec->has_crc = 0;
        off += x;
        if (off + 4u > (uint64_t)CM_MAX_FILE_BYTES)
            return header_limit(d, st, CM_LIMIT_MAX_FILE_BYTES, off + 4u > UINT32_MAX ? UINT32_MAX : off + 4u,
                                CM_MAX_FILE_BYTES, v->at_file_len, "file length");
    }
    d->file_len = (uint32_t)(off + 4u);
    v->h.file_len = d->file_len;
    if ((e = header_varint(d, st, &at, UINT64_MAX, &x, &v->at_qexp, "quantisation exponent")) != CM_OK)
        return e;
    int64_t qe = cm_fmt_unzigzag(x);
    if (qe < -60 || qe > 20)
        return fail(d, st, CM_E_RANGE, v->at_qexp, "quantisation exponent (grid step 2^e mm, e in -60..20)");
    v->h.q_exp = (int8_t)qe;
    double q = cm_fmt_grid_step((int)qe), oq = q;
    int short_origin = v->h.minor >= CM_FMT_SHORT_ORIGIN_MINOR;
    if (short_origin) {
        /* format 4.1: the origin's step, 2^shift grid steps */
        uint32_t fs;
        if ((e = header_varint(d, st, &at, CM_FMT_MAX_ORIGIN_SHIFT, &x, &fs, "grid origin step")) != CM_OK)
            return e;
        oq = cm_fmt_grid_step((int)qe + (int)x);
    }
    for (uint32_t k = 0; k < 3; k++) {
        if ((e = header_varint(d, st, &at, UINT64_MAX, &x, &v->at_origin[k], "grid origin")) != CM_OK)
            return e;
        /* exact for |k| <= 2^53 (the writer's origin is a multiple of the step), deterministic beyond;
           the range is checked below with the other versions' (|k q| < 2^146 here) */
        v->h.origin[k] = (double)cm_fmt_unzigzag(x) * oq;
    }
    if ((e = header_varint(d, st, &at, UINT64_MAX, &x, &v->at_tess, "chordal tolerance")) != CM_OK)
        return e;
    v->h.tess_tol = (double)x * q;
    if ((e = header_varint(d, st, &at, UINT64_MAX, &x, &v->at_rel, "rebuild tolerance")) != CM_OK)
        return e;
    if (short_origin) {
        /* the difference from the default; a negative tolerance is refused by check_header */
        v->h.rel_tol = cm_fmt_rel_tol(cm_fmt_unzigzag(x));
    } else {
        v->h.rel_tol = (double)x / (double)CM_FMT_REL_TOL_ONE;
    }
    if (at != H - 4u)
        return fail(d, st, CM_E_FORMAT, at, "header length: fields end before the header CRC");
    return CM_OK;
}

static cm_err check_header(cm_decoder *d, cm_status *st)
{
    header_view v;
    d->nsec = 0;
    d->nlimits = 0;
    for (uint32_t i = 0; i < (uint32_t)CM_LIMIT_COUNT; i++)
        d->need[i] = 0;
    cm_err e = d->buf[CM_HDR_MAJOR] >= CM_FMT_COMPACT_MAJOR ? parse_compact(d, st, &v) : parse_fixed(d, st, &v);
    if (e != CM_OK)
        return e;
    const cm_fmt_header *h = &v.h;
    d->version_major = h->major;
    d->version_minor = h->minor;
    d->flags = h->flags;
    d->nlimits = h->nlimits;
    d->nsec = CM_SEC_COUNT;
    /* the grid and the tolerances */
    int qe = h->q_exp;
    if (qe < -60 || qe > 20)
        return fail(d, st, CM_E_RANGE, v.at_qexp, "quantisation exponent (grid step 2^e mm, e in -60..20)");
    for (uint32_t k = 0; k < 3; k++) {
        double o = h->origin[k];
        if (!isfinite(o))
            return fail(d, st, CM_E_NONFINITE, v.at_origin[k], "grid origin");
        if (!(fabs(o) <= ORIGIN_MAX))
            return fail(d, st, CM_E_RANGE, v.at_origin[k], "grid origin (|origin| <= 2^100 mm)");
        d->model.origin[k] = o;
    }
    d->model.q = cm_fmt_grid_step(qe);
    d->model.tess_tol = h->tess_tol;
    d->model.turning_basis = h->major > 2 || (h->major == 2 && h->minor >= CM_FMT_TURNING_MINOR);
    d->model.kept_off_edges = h->major > 4 || (h->major == 4 && h->minor >= CM_FMT_KEPT_OFF_EDGES_MINOR);
    d->model.refine_47 = h->major > 4 || (h->major == 4 && h->minor >= CM_FMT_REFINE_MINOR);
    d->model.refine_48 = h->major > 4 || (h->major == 4 && h->minor >= CM_FMT_PREDICT_FLAT_MINOR);
    d->model.refine_49 = h->major > 4 || (h->major == 4 && h->minor >= CM_FMT_RULED_MINOR);
    d->model.refine_410 = h->major > 4 || (h->major == 4 && h->minor >= CM_FMT_PATCH_SCALE_MINOR);
    d->model.conic_cubic = h->major > 4 || (h->major == 4 && h->minor >= CM_FMT_CONIC_CUBIC_MINOR);
    d->model.predicted = h->major >= CM_FMT_PREDICT_MAJOR;
    if (!isfinite(d->model.tess_tol))
        return fail(d, st, CM_E_NONFINITE, v.at_tess, "chordal tolerance");
    if (!(d->model.tess_tol > 0))
        return fail(d, st, CM_E_RANGE, v.at_tess, "chordal tolerance (must be > 0)");
    d->model.rel_tol = h->rel_tol;
    if (!isfinite(d->model.rel_tol))
        return fail(d, st, CM_E_NONFINITE, v.at_rel, "rebuild tolerance");
    if (!(d->model.rel_tol >= 0))
        return fail(d, st, CM_E_RANGE, v.at_rel, "rebuild tolerance (must be >= 0)");
    /* what bounds the tessellation's work (cm_tessellate.c); a file declares them, so a need of 0
       is the model's figure, kept apart from 0 = "not declared" (the build's limit) */
    d->model.need_tess_points = declared(d->need[CM_LIMIT_MAX_TESS_POINTS]);
    d->model.need_edge_samples = declared(d->need[CM_LIMIT_MAX_EDGE_SAMPLES]);
    d->model.need_tris = declared(d->need[CM_LIMIT_MAX_TRIS]);
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
    if (d->len > CM_HDR_MAJOR &&
        (d->buf[CM_HDR_MAJOR] < CM_FMT_VERSION_MIN_MAJOR || d->buf[CM_HDR_MAJOR] > CM_FMT_VERSION_MAJOR))
        return fail(d, st, CM_E_VERSION, CM_HDR_MAJOR, "version");
    /* a newer minor of the compact header may lay its fields out differently */
    if (d->len > CM_HDR_MINOR && d->buf[CM_HDR_MAJOR] == CM_FMT_VERSION_MAJOR && d->buf[CM_HDR_MINOR] > CM_FMT_VERSION_MINOR)
        return fail(d, st, CM_E_VERSION, CM_HDR_MINOR, "version (a minor newer than this reader's)");
    if (d->len < CM_HDR_LENGTH + 4)
        return CM_OK;
    if (d->buf[CM_HDR_MAJOR] >= CM_FMT_COMPACT_MAJOR) {
        /* format 4: a varint at byte 6, within the 12 bytes in (a header holds at least 25 needs in
           4.0-4.5, and is at least CM_FMT_STREAM_MIN_HEADER = 12 bytes long in 4.6) */
        uint32_t at = CM_FMT_COMPACT_AT_H;
        uint64_t h;
        uint32_t least = d->buf[CM_HDR_MINOR] >= CM_FMT_ONE_STREAM_MINOR ? CM_FMT_STREAM_MIN_HEADER
                                                                         : CM_FMT_COMPACT_AT_H + CM_FMT_MIN_NEEDS + 4u;
        if (!cm_fmt_get_varint(d->buf, d->len, &at, &h) || at > CM_FMT_COMPACT_AT_H + 5u || h < least ||
            h > CM_FMT_MAX_HEADER)
            return fail(d, st, CM_E_FORMAT, CM_FMT_COMPACT_AT_H, "header length");
        d->header_len = (uint32_t)h;
    } else {
        d->header_len = cm_get_u32(d->buf + CM_HDR_LENGTH);
        if (d->header_len < CM_FMT_FIXED_HEADER + 4u || d->header_len > CM_FMT_MAX_HEADER)
            return fail(d, st, CM_E_FORMAT, CM_HDR_LENGTH, "header length");
    }
    if (d->header_len > (uint32_t)CM_MAX_FILE_BYTES)
        return header_limit(d, st, CM_LIMIT_MAX_FILE_BYTES, d->header_len, CM_MAX_FILE_BYTES, CM_HDR_LENGTH,
                            "header length");
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
        if (d->state == CM_DEC_BODY) /* the header's bytes (held: header_len < the file's CRC) */
            take_bytes(d, 0, d->buf, d->len, 0);
    }
    if (n == 0)
        return CM_OK;
    if (n > (size_t)(d->file_len - d->len))
        return fail(d, st, CM_E_RANGE, d->file_len, "more bytes than the file");
    take_bytes(d, d->len, p, n, 1);
    d->len += (uint32_t)n;
    return CM_OK;
}

/* ---- sections ---- */

typedef struct reader {
    cm_ac_dec ac;
    uint32_t stream_off; /* file offset of the coder's stream (a longer file is read through the window) */
    uint32_t base; /* file offset of the section */
    uint32_t face; /* the face whose record (FACE) or colour (COLR) is being read, or CM_NO_FACE_INDEX */
    cm_decoder *d;
    cm_status *st;
} reader;

/* where the reader is in the file: the range coder's read position (it reads a few bytes ahead of
   the bits it has decoded, so a field's own bytes are at or shortly before this offset) */
static uint32_t pos(const reader *r)
{
    return r->base + (uint32_t)r->ac.pos;
}

/* a failure at the reader's position, naming the face being read if any */
static cm_err rfail_at(reader *r, cm_err e, uint32_t at, const char *where)
{
    int open = r->st && r->st->code == CM_OK;
    cm_err code = fail(r->d, r->st, r->ac.overrun ? CM_E_TRUNCATED : e, at, where);
    if (open && r->face != CM_NO_FACE_INDEX)
        r->st->face = r->face;
    return code;
}

static cm_err rfail(reader *r, cm_err e, const char *where)
{
    return rfail_at(r, e, pos(r), where);
}

static cm_err rlimit_at(reader *r, unsigned id, uint64_t need, uint64_t have, uint32_t at, const char *where)
{
    int open = r->st && r->st->code == CM_OK;
    r->d->state = CM_DEC_FAILED;
    cm_fail_limit(r->st, id, need, have, where);
    if (open) {
        r->st->offset = at;
        if (r->face != CM_NO_FACE_INDEX)
            r->st->face = r->face;
    }
    return CM_E_LIMIT;
}

static cm_err rlimit(reader *r, unsigned id, uint64_t need, uint64_t have, const char *where)
{
    return rlimit_at(r, id, need, have, pos(r), where);
}

/* a count field: at most `cap`, the build's limit (else CM_E_LIMIT naming `id`), checked before the
   count sizes or indexes anything (the header's declared needs are not compared: 0 means undeclared) */
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

/* a grid coordinate sent as its prediction plus a multiple of step (1, or format 3's 2^s with
   s <= CM_FMT_MAX_STEP): |pred| < 3 * 2^40 (the coordinates it comes from were checked), the
   decoded multiple below 2^34, so nothing overflows before the range check */
static cm_err read_coord(reader *r, cm_ac_int *m, int64_t pred, int64_t step, int64_t *out, const char *where)
{
    int64_t v = pred + cm_ac_dec_sint(&r->ac, m) * step;
    if (r->ac.overrun)
        return rfail(r, CM_E_TRUNCATED, where);
    if (v > COORD_MAX || v < -COORD_MAX)
        return rfail(r, CM_E_RANGE, where);
    *out = v;
    return CM_OK;
}

/* format 3: a curve's or net's step exponent s, as the multiplier 2^s */
static cm_err read_step(reader *r, cm_ac_int *m, int64_t *step, const char *where)
{
    uint64_t s = cm_ac_dec_uint(&r->ac, m);
    if (r->ac.overrun)
        return rfail(r, CM_E_TRUNCATED, where);
    if (s > CM_FMT_MAX_STEP)
        return rfail(r, CM_E_RANGE, where);
    *step = (int64_t)1 << s;
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
    /* format 3: the vertices' step, of which their deltas are multiples */
    int64_t step = 1;
    if (m->predicted && (e = read_step(r, &ctx.step, &step, "vertex step")) != CM_OK)
        return e;
    /* format 4: per coordinate a bit "one of the axis's recent values" and its place (cm_vcache),
       else the difference as in format 3 */
    int recent = d->version_major >= CM_FMT_COMPACT_MAJOR;
    cm_vcache cache[3] = {{{0}, 0}, {{0}, 0}, {{0}, 0}};
    int64_t prev[3] = {0, 0, 0};
    for (uint32_t i = 0; i < m->nverts; i++) {
        for (int k = 0; k < 3; k++) {
            int slot = -1;
            if (recent && cm_ac_dec_bit(&r->ac, &ctx.repeat[k])) {
                uint64_t s = cm_ac_dec_uint(&r->ac, &ctx.slot[k]);
                if (r->ac.overrun)
                    return rfail(r, CM_E_TRUNCATED, "vertex");
                if (s >= (uint64_t)cache[k].n)
                    return rfail(r, CM_E_RANGE, "vertex repeat (past the recent values)");
                slot = (int)s;
                d->vq[i][k] = cache[k].v[slot];
            } else if ((e = read_coord(r, &ctx.coord[k], prev[k], step, &d->vq[i][k], "vertex")) != CM_OK) {
                return e;
            }
            if (recent)
                cm_vcache_front(&cache[k], slot, d->vq[i][k]);
            prev[k] = d->vq[i][k];
        }
        m->verts[i] = grid_point(m, d->vq[i]);
    }
    return CM_OK;
}

/* the coding models of a knot vector: format 2 sends each gap as it is, format 3 the first gap,
   then per gap a bit "zero" (a repeated knot) and otherwise the gap less the last gap that was not
   zero (cm_predict.h) */
typedef struct knot_models {
    cm_ac_prob *uniform, *zero;
    cm_ac_int *gap, *delta;
} knot_models;

/* knots of a clamped vector on [0,1] for degree p and n control points, appended to the pool */
static cm_err read_knots(reader *r, const knot_models *km, int p, int n, uint32_t *knot0)
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
    if (cm_ac_dec_bit(&r->ac, km->uniform)) {
        for (int j = 1; j <= interior; j++)
            K[p + j] = (double)j / (double)(interior + 1);
    } else {
        int64_t prev = 0, last_gap = 0;
        for (int j = 1; j <= interior; j++) {
            int64_t gap;
            if (!r->d->model.predicted || j == 1)
                gap = (int64_t)cm_ac_dec_uint(&r->ac, km->gap);
            else if (cm_ac_dec_bit(&r->ac, km->zero))
                gap = 0;
            else
                gap = last_gap + cm_ac_dec_sint(&r->ac, km->delta);
            if (r->ac.overrun)
                return rfail(r, CM_E_TRUNCATED, "knots");
            /* a gap beyond [0,1] (a hostile delta: |delta| < 2^34, no overflow) */
            if (gap < 0 || gap > KNOT_ONE)
                return rfail(r, CM_E_KNOTS, "knots");
            if (gap)
                last_gap = gap;
            int64_t kq = prev + gap;
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

/* the file is format 4.minor or newer */
static int at_least_4(const reader *r, unsigned minor)
{
    return r->d->version_major > 4 || (r->d->version_major == 4 && r->d->version_minor >= minor);
}

/*
 * Format 4.4: an arc edge.  Its middle point q comes as its offset from the chord's midpoint
 * (cm_pred_arc_mid) in steps of its own; the curve is cm_arc_nurbs's rational quadratic through the
 * edge's vertices and q, appended to the pools like any other curve.  A closed edge (v0 == v1) is a
 * full circle: the point across from its vertex and the one halfway to it (cm_circle_nurbs).
 */
static cm_err read_arc(reader *r, cm_edge_ctx *ctx, cm_edge *E)
{
    cm_model *m = &r->d->model;
    int64_t step, qk[3];
    cm_err e = read_step(r, &ctx->arc_step, &step, "arc step");
    if (e != CM_OK)
        return e;
    const int64_t *first = r->d->vq[E->v0], *last = r->d->vq[E->v1];
    int closed = E->v0 == E->v1;
    /* an arc: its middle point, from the chord's midpoint; a closed edge's circle: the point across
       from its vertex, from the vertex, then the one halfway to it, from their midpoint */
    for (int k = 0; k < 3; k++)
        if ((e = read_coord(r, &ctx->arc_coord[k], closed ? first[k] : cm_pred_arc_mid(first[k], last[k]), step,
                            &qk[k], closed ? "circle's far point" : "arc middle point")) != CM_OK)
            return e;
    int64_t rk[3];
    for (int k = 0; closed && k < 3; k++)
        if ((e = read_coord(r, &ctx->arc_coord[k], cm_pred_arc_mid(first[k], qk[k]), step, &rk[k],
                            "circle's middle point")) != CM_OK)
            return e;
    cm_vec3 P[CM_ARC_MAX_CTRL];
    double W[CM_ARC_MAX_CTRL], K[CM_ARC_MAX_KNOTS];
    int n;
    cm_status cst;
    cm_status_init(&cst);
    if (cm_arc_record(closed, m->verts[E->v0], grid_point(m, closed ? rk : qk), closed ? grid_point(m, qk) : m->verts[E->v1],
                      P, W, K, &n, &cst) != CM_OK)
        return rfail(r, cst.code, cst.where ? cst.where : "arc edge");
    if (2 > CM_MAX_DEGREE)
        return rlimit(r, CM_LIMIT_MAX_DEGREE, 2, CM_MAX_DEGREE, "edge degree");
    if ((uint32_t)n > CM_MAX_EDGE_CTRL)
        return rlimit(r, CM_LIMIT_MAX_EDGE_CTRL, (uint64_t)n, CM_MAX_EDGE_CTRL, "edge control points");
    if ((uint32_t)n > CM_MAX_MODEL_CTRL - m->nctrl)
        return rlimit(r, CM_LIMIT_MAX_MODEL_CTRL, (uint64_t)m->nctrl + (uint32_t)n, CM_MAX_MODEL_CTRL, "control points");
    if ((uint32_t)n + 3 > CM_MAX_MODEL_KNOTS - m->nknots)
        return rlimit(r, CM_LIMIT_MAX_MODEL_KNOTS, (uint64_t)m->nknots + (uint32_t)n + 3, CM_MAX_MODEL_KNOTS, "knots");
    E->p = 2;
    E->nctrl = (uint16_t)n;
    E->rational = 1;
    E->ctrl0 = m->nctrl;
    E->knot0 = m->nknots;
    for (int j = 0; j < n; j++) {
        m->ctrl[m->nctrl + (uint32_t)j] = P[j];
        m->w[m->nctrl + (uint32_t)j] = W[j];
    }
    for (int j = 0; j < n + 3; j++)
        m->knots[m->nknots + (uint32_t)j] = K[j];
    m->nctrl += (uint32_t)n;
    m->nknots += (uint32_t)n + 3;
    return CM_OK;
}

/* edge i's curve (or kept surface i) as the kernels will take it: degrees, counts, knots, finite
   points, weights > 0 */
static cm_err check_geometry(reader *r, uint32_t i, int surface)
{
    cm_status cst;
    cm_status_init(&cst);
    cm_curve c;
    cm_surf sv;
    if (surface)
        cm_model_surface(&r->d->model, i, &sv);
    else
        cm_model_edge_curve(&r->d->model, i, &c);
    if ((surface ? cm_surf_check(&sv, &cst) : cm_curve_check(&c, &cst)) != CM_OK)
        return rfail(r, cst.code == CM_E_LIMIT ? CM_E_FORMAT : cst.code, surface ? "surface" : "edge curve");
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
    int arcs = at_least_4(r, CM_FMT_ARC_MINOR);
    for (uint32_t i = 0; i < m->nedges; i++) {
        cm_edge *E = &m->edges[i];
        if ((e = read_vref(r, &ctx.is_new, &ctx.back, &vnext, &E->v0)) != CM_OK ||
            (e = read_vref(r, &ctx.is_new, &ctx.back, &vnext, &E->v1)) != CM_OK)
            return e;
        E->g1 = (uint8_t)cm_ac_dec_bit(&r->ac, &ctx.g1);
        E->kind = (uint8_t)cm_ac_dec_bit(&r->ac, &ctx.kind);
        int p = 1, n = 2, rational = 0;
        if (E->kind == CM_EDGE_CURVE && arcs && cm_ac_dec_bit(&r->ac, &ctx.arc)) {
            if ((e = read_arc(r, &ctx, E)) != CM_OK || (e = check_geometry(r, i, 0)) != CM_OK)
                return e;
            continue;
        }
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
        } else {
            knot_models km = {&ctx.uniform, &ctx.knot_zero, &ctx.knot, &ctx.knot_delta};
            if ((e = read_knots(r, &km, p, n, &E->knot0)) != CM_OK)
                return e;
        }
        E->ctrl0 = m->nctrl;
        cm_vec3 *P = m->ctrl + m->nctrl;
        double *W = m->w + m->nctrl;
        /* format 3: the curve's predictor (cm_predict.h) and its step, 2^step grid steps, of which
           its points are multiples away from their predictions; format 2: the previous point, 1 */
        int linear = 0;
        int64_t step = 1;
        if (m->predicted && n > 2) {
            linear = (int)cm_ac_dec_bit(&r->ac, &ctx.linear);
            if ((e = read_step(r, &ctx.step, &step, "edge step")) != CM_OK)
                return e;
        }
        const int64_t *first = d->vq[E->v0], *last = d->vq[E->v1];
        int64_t prev[3] = {first[0], first[1], first[2]}, prev2[3] = {first[0], first[1], first[2]};
        P[0] = m->verts[E->v0];
        for (int j = 1; j < n - 1; j++) {
            int64_t k3[3];
            for (int k = 0; k < 3; k++) {
                int64_t pred = cm_pred_ctrl(linear, j, n, first[k], last[k], prev[k], prev2[k]);
                if ((e = read_coord(r, &ctx.coord[k], pred, step, &k3[k], "edge control point")) != CM_OK)
                    return e;
                prev2[k] = prev[k];
                prev[k] = k3[k];
            }
            P[j] = grid_point(m, k3);
        }
        P[n - 1] = m->verts[E->v1];
        int64_t wq = WEIGHT_ONE, wprev = WEIGHT_ONE, wprev2 = WEIGHT_ONE;
        W[0] = 1.0;
        for (int j = 1; j < n; j++) {
            if (rational) {
                wq = (m->predicted ? cm_pred_weight(j, wprev, wprev2) : wprev) + cm_ac_dec_sint(&r->ac, &ctx.weight);
                if (r->ac.overrun)
                    return rfail(r, CM_E_TRUNCATED, "weights");
                if (wq <= 0 || wq > WEIGHT_MAX)
                    return rfail(r, CM_E_RANGE, "weights");
                wprev2 = wprev;
                wprev = wq;
            }
            W[j] = (double)wq / (double)WEIGHT_ONE;
        }
        m->nctrl += (uint32_t)n;
        if ((e = check_geometry(r, i, 0)) != CM_OK)
            return e;
    }
    if (vnext != m->nverts)
        return rfail(r, CM_E_FORMAT, "unused vertices");
    return CM_OK;
}

/*
 * Format 4.4: a kept surface ruled between two arcs, or two full circles (a cylinder's or a cone's
 * patch, a band): per row its first point, then its arc's end and middle point (a circle's far
 * point and the point halfway to it), each predicted by cm_pred_ruled, in steps of their own; each
 * row built as an arc edge is (cm_arc_nurbs, cm_circle_nurbs), the two of as many pieces; the net,
 * u along the arcs and v from the first row to the second (degree 1), or the other way round
 * (`along_v`), appended to the pools.
 */
static cm_err read_ruled(reader *r, cm_surf_ctx *ctx, cm_ksurf *S)
{
    cm_model *m = &r->d->model;
    int closed = (int)cm_ac_dec_bit(&r->ac, &ctx->closed), along_v = (int)cm_ac_dec_bit(&r->ac, &ctx->along_v);
    int64_t step, pt[2][3][3];
    cm_err e = read_step(r, &ctx->ruled_step, &step, "ruled surface step");
    for (int row = 0; row < 2 && e == CM_OK; row++)
        for (int j = 0; j < 3 && e == CM_OK; j++)
            for (int k = 0; k < 3 && e == CM_OK; k++)
                e = read_coord(r, &ctx->ruled_coord[k], cm_pred_ruled((const int64_t(*)[3][3])pt, row, j, k), step,
                               &pt[row][j][k], "ruled surface point");
    if (e != CM_OK)
        return e;
    cm_vec3 P[2][CM_ARC_MAX_CTRL];
    double W[2][CM_ARC_MAX_CTRL], K[2][CM_ARC_MAX_KNOTS];
    int n[2];
    for (int row = 0; row < 2; row++) {
        cm_vec3 a = grid_point(m, pt[row][0]), b = grid_point(m, pt[row][1]), c = grid_point(m, pt[row][2]);
        cm_status cst;
        cm_status_init(&cst);
        /* an arc from a through c to b; a circle from a through c to b and round */
        if (cm_arc_record(closed, a, c, b, P[row], W[row], K[row], &n[row], &cst) != CM_OK)
            return rfail(r, cst.code, cst.where ? cst.where : "ruled surface");
    }
    if (n[0] != n[1])
        return rfail(r, CM_E_FORMAT, "ruled surface's arcs of different pieces");
    uint32_t nu = (uint32_t)n[0];
    if (2 > CM_MAX_DEGREE)
        return rlimit(r, CM_LIMIT_MAX_DEGREE, 2, CM_MAX_DEGREE, "surface degree");
    if (nu > CM_MAX_SURF_CTRL_DIR)
        return rlimit(r, CM_LIMIT_MAX_SURF_CTRL_DIR, nu, CM_MAX_SURF_CTRL_DIR, "surface control points");
    if (2 * nu > CM_MAX_SURF_CTRL)
        return rlimit(r, CM_LIMIT_MAX_SURF_CTRL, 2 * nu, CM_MAX_SURF_CTRL, "surface control points");
    if (2 * nu > CM_MAX_MODEL_CTRL - m->nctrl)
        return rlimit(r, CM_LIMIT_MAX_MODEL_CTRL, m->nctrl + 2 * nu, CM_MAX_MODEL_CTRL, "control points");
    if (nu + 3 + 4 > CM_MAX_MODEL_KNOTS - m->nknots)
        return rlimit(r, CM_LIMIT_MAX_MODEL_KNOTS, m->nknots + nu + 7, CM_MAX_MODEL_KNOTS, "knots");
    /* the arcs along u (rows of the net), or along v (its columns: the surface as the source had it) */
    S->p = along_v ? 1 : 2;
    S->q = along_v ? 2 : 1;
    S->nu = (uint16_t)(along_v ? 2 : nu);
    S->nv = (uint16_t)(along_v ? nu : 2);
    S->rational = 1;
    uint32_t arc_knots = m->nknots, line_knots = m->nknots + nu + 3;
    for (uint32_t i = 0; i < nu + 3; i++)
        m->knots[m->nknots++] = K[0][i];
    for (int i = 0; i < 4; i++)
        m->knots[m->nknots++] = i < 2 ? 0.0 : 1.0;
    S->uknot0 = along_v ? line_knots : arc_knots;
    S->vknot0 = along_v ? arc_knots : line_knots;
    S->ctrl0 = m->nctrl;
    for (uint32_t i = 0; i < nu; i++)
        for (int row = 0; row < 2; row++) {
            uint32_t at = S->ctrl0 + (along_v ? (uint32_t)row * nu + i : i * 2u + (uint32_t)row);
            m->ctrl[at] = P[row][i];
            m->w[at] = W[row][i];
        }
    m->nctrl += 2 * nu;
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
    int ruled = at_least_4(r, CM_FMT_ARC_MINOR);
    for (uint32_t s = 0; s < m->nsurfs; s++) {
        cm_ksurf *S = &m->surfs[s];
        if (ruled && cm_ac_dec_bit(&r->ac, &ctx.ruled)) {
            if ((e = read_ruled(r, &ctx, S)) != CM_OK || (e = check_geometry(r, s, 1)) != CM_OK)
                return e;
            continue;
        }
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
        knot_models km = {&ctx.uniform, &ctx.knot_zero, &ctx.knot, &ctx.knot_delta};
        if ((e = read_knots(r, &km, deg[0], cnt[0], &S->uknot0)) != CM_OK ||
            (e = read_knots(r, &km, deg[1], cnt[1], &S->vknot0)) != CM_OK)
            return e;
        S->ctrl0 = m->nctrl;
        int nu = cnt[0], nv = cnt[1];
        /* the net row-major in u, each point predicted from those before it (cm_pred_net: format 2
           the parallelogram, format 3 the surface's choice) */
        int quadratic = 0;
        int64_t step = 1;
        if (m->predicted) {
            quadratic = (int)cm_ac_dec_bit(&r->ac, &ctx.quadratic);
            if ((e = read_step(r, &ctx.step, &step, "surface step")) != CM_OK)
                return e;
        }
        for (int i = 0; i < nu; i++)
            for (int j = 0; j < nv; j++) {
                int idx = i * nv + j;
                for (int k = 0; k < 3; k++) {
                    int64_t pred = cm_pred_net(quadratic, (const int64_t(*)[3])d->sq, nv, i, j, k);
                    if ((e = read_coord(r, &ctx.coord[k], pred, step, &d->sq[idx][k], "surface control point")) != CM_OK)
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
        if ((e = check_geometry(r, s, 1)) != CM_OK)
            return e;
    }
    return CM_OK;
}

/* a double sent as its 64 bits, most significant first (a placement's entries: exact on every machine) */
static double read_double(cm_ac_dec *ac)
{
    uint64_t b = 0;
    for (int i = 0; i < 4; i++)
        b = (b << 16) | cm_ac_dec_direct(ac, 16);
    double v;
    memcpy(&v, &b, sizeof v);
    return v;
}

/*
 * Format 4.3: the placed copies after the faces (cm_placement): their count, then per copy its
 * first face, its face count less one, the nine entries of its linear part row by row (each a uint
 * class: 0 is 0, 1 is 1, 2 is -1, 3 a double's 64 bits follow) and its translation as the grid
 * origin's displacement in grid steps (three sints).  A copy must name faces of the model, and its
 * transform pass cm_fmt_placement_fault (the writer's rule too).
 */
static cm_err read_placements(reader *r, cm_face_ctx *ctx)
{
    cm_model *m = &r->d->model;
    cm_err e = read_count(r, &ctx->place_n, CM_LIMIT_MAX_PLACEMENTS, CM_MAX_PLACEMENTS, &m->nplacements,
                          "placement count");
    if (e != CM_OK)
        return e;
    for (uint32_t k = 0; k < m->nplacements; k++) {
        cm_placement *P = &m->placements[k];
        uint64_t first = cm_ac_dec_uint(&r->ac, &ctx->place_first);
        uint64_t count = cm_ac_dec_uint(&r->ac, &ctx->place_count) + 1u;
        for (int i = 0; i < 12; i++) {
            if (i % 4 == 3)
                continue;
            uint64_t cls = cm_ac_dec_uint(&r->ac, &ctx->place_entry);
            if (cls > 3)
                return rfail(r, r->ac.overrun ? CM_E_TRUNCATED : CM_E_RANGE, "placement's transform");
            P->m[i] = cls == 0 ? 0.0 : cls == 1 ? 1.0 : cls == 2 ? -1.0 : read_double(&r->ac);
        }
        /* the translation as where the copy puts the grid origin o, less o, in grid steps (as
           bounded as the model's own coordinates): t = d q + o - M o */
        for (int i = 0; i < 3; i++) {
            int64_t d = cm_ac_dec_sint(&r->ac, &ctx->place_shift);
            const double *a = &P->m[4 * i];
            P->m[4 * i + 3] = (double)d * m->q + m->origin[i] -
                              (a[0] * m->origin[0] + a[1] * m->origin[1] + a[2] * m->origin[2]);
        }
        if (r->ac.overrun)
            return rfail(r, CM_E_TRUNCATED, "placement");
        if (first >= m->nfaces || count > m->nfaces - first)
            return rfail(r, CM_E_RANGE, "placement's faces");
        P->first = (uint32_t)first;
        P->count = (uint32_t)count;
        P->part = 0;
        const char *fault = cm_fmt_placement_fault(P->m);
        if (fault)
            return rfail(r, CM_E_RANGE, fault);
    }
    return CM_OK;
}


/*
 * Format 4.5: a use after the first of its loop, which begins where the use before ended (v): bit
 * "the next edge not referenced yet", else its place among the candidates at v (cm_use_adj.h), or
 * one past them and `back` as in 4.4; the direction is the one that begins at v, sent only for a
 * closed edge.  An edge that does not meet v fails the loop's closing test.
 */
static cm_err read_use_at(reader *r, cm_face_ctx *ctx, cm_use_adj *adj, cm_use *U, uint32_t *enext)
{
    cm_model *m = &r->d->model;
    const cm_use *prev = U - 1;
    int32_t v = prev->rev ? m->edges[prev->edge].v0 : m->edges[prev->edge].v1;
    uint32_t e;
    int is_new = (int)cm_ac_dec_bit(&r->ac, &ctx->is_new);
    if (is_new) {
        if (*enext >= m->nedges)
            return rfail(r, CM_E_RANGE, "edge reference");
        e = (*enext)++;
    } else {
        uint32_t cand[CM_USE_CANDIDATES];
        int n = cm_use_adj_list(adj, m->edges, v, cand);
        uint64_t i = cm_ac_dec_uint(&r->ac, &ctx->cand);
        if (r->ac.overrun)
            return rfail(r, CM_E_TRUNCATED, "edge reference");
        if (i < (uint64_t)n) {
            e = cand[i];
        } else if (i == (uint64_t)n) {
            uint64_t back = cm_ac_dec_uint(&r->ac, &ctx->back);
            if (r->ac.overrun)
                return rfail(r, CM_E_TRUNCATED, "edge reference");
            if (back >= *enext)
                return rfail(r, CM_E_RANGE, "edge reference");
            e = (uint32_t)(*enext - 1 - back);
        } else {
            return rfail(r, CM_E_RANGE, "edge candidate at its vertex");
        }
    }
    U->edge = e;
    U->rev = m->edges[e].v0 == m->edges[e].v1 ? (uint8_t)cm_ac_dec_bit(&r->ac, &ctx->rev_closed)
                                              : cm_use_adj_rev(m->edges, e, v);
    cm_use_adj_use(adj, m->edges, e, is_new);
    return CM_OK;
}

static cm_err sec_face(reader *r)
{
    cm_model *m = &r->d->model;
    cm_face_ctx ctx;
    cm_face_ctx_init(&ctx);
    ctx.net_fit = at_least_4(r, CM_FMT_NET_FIT_MINOR);
    ctx.placements = at_least_4(r, CM_FMT_PLACE_MINOR);
    ctx.hints = at_least_4(r, CM_FMT_HINTS_MINOR);
    cm_err e = read_count(r, &ctx.count, CM_LIMIT_MAX_FACES, CM_MAX_FACES, &m->nfaces, "face count");
    if (e != CM_OK)
        return e;
    /* format 4.13: whether any record has corner hints (else none has their field) */
    ctx.hints = ctx.hints && cm_ac_dec_bit(&r->ac, &ctx.hint_any);
    uint32_t enext = 0, snext = 0;
    m->nloops = m->nuses = 0;
    /* format 4.5: the lists of referenced edges at each vertex (cm_use_adj.h), in arrays that are
       free while FACE is read: the vertices' grid coordinates (read by VERT, EDGE and SURF only),
       and edge_face and edge_split, which cm_model_adjacency fills from the loops at the end */
    int by_vertex = at_least_4(r, CM_FMT_USE_ADJ_MINOR);
    cm_use_adj adj = {r->d->vhead, m->edge_face, m->edge_split};
    if (by_vertex)
        cm_use_adj_begin(&adj, m->nverts);
    for (uint32_t f = 0; f < m->nfaces; f++) {
        cm_face *F = &m->faces[f];
        r->face = f;
        F->rec_off = pos(r);
        uint64_t meth = cm_ac_dec_uint(&r->ac, &ctx.method);
        if (r->ac.overrun)
            return rfail(r, CM_E_TRUNCATED, "face method");
        const cm_method *M = cm_method_of(meth > 255 ? 255u : (unsigned)meth);
        if (!M)
            return rfail(r, CM_E_UNSUPPORTED, "face method");
        /* a method newer than the file's format version is a malformed file, not a newer one */
        if (r->d->version_major < M->since_major ||
            (r->d->version_major == M->since_major && r->d->version_minor < M->since_minor))
            return rfail(r, CM_E_UNSUPPORTED, M->too_new);
        F->method = (uint8_t)meth;
        F->layout = F->fit = 0;
        F->corner = 0;
        F->checksum = 0;
        F->surf = 0;
        cm_method_fault why = {0};
        if ((e = cm_method_read_record(M, &r->ac, &ctx, m, F, &why)) == CM_E_LIMIT)
            return rlimit_at(r, why.limit, why.need, cm_limit_table[why.limit].value, F->rec_off, why.what);
        if (e != CM_OK)
            return rfail(r, e, why.what);
        if (M->layouts && F->layout == CM_GREG_LAYOUT_JOINED &&
            r->d->version_major == 2 && r->d->version_minor < 3)
            return rfail(r, CM_E_UNSUPPORTED, "GREGORY layout 3 (joined sides) in a file older than format 2.3");
        F->flip = (uint8_t)cm_ac_dec_bit(&r->ac, &ctx.flip);
        F->color = 0;
        F->part = 0;
        if (M->kept_surface) {
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
                if (by_vertex && k > 0) {
                    if ((e = read_use_at(r, &ctx, &adj, U, &enext)) != CM_OK)
                        return e;
                    continue;
                }
                int fresh = (int)cm_ac_dec_bit(&r->ac, &ctx.is_new);
                if (fresh) {
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
                if (by_vertex)
                    cm_use_adj_use(&adj, m->edges, U->edge, fresh);
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
        /* the loops must fit the method (reported at the face's record) */
        if ((e = cm_method_check_loops(M, m, F, &why)) == CM_E_LIMIT)
            return rlimit_at(r, why.limit, why.need, cm_limit_table[why.limit].value, F->rec_off, why.what);
        if (e != CM_OK)
            return rfail_at(r, e, F->rec_off, why.what);
    }
    r->face = CM_NO_FACE_INDEX;
    if (r->ac.overrun)
        return rfail(r, CM_E_TRUNCATED, "faces");
    if (enext != m->nedges || snext != m->nsurfs)
        return rfail(r, CM_E_FORMAT, "unused edges or surfaces");
    if (ctx.placements && (e = read_placements(r, &ctx)) != CM_OK)
        return e;
    cm_model_adjacency(m);
    return CM_OK;
}

/*
 * Format 4.11: the parts (the order of the terminal's assembly steps), after the colours: their count
 * (0: none), then each face's part and each copy's, as the previous one's again, the next after the
 * highest so far, or by number.
 */
static cm_err read_parts(reader *r, cm_colr_ctx *ctx)
{
    cm_model *m = &r->d->model;
    const uint32_t n = m->nfaces + m->nplacements;
    uint64_t np = cm_ac_dec_uint(&r->ac, &ctx->nparts);
    if (np > n) /* (a part has a face or a copy) */
        return rfail(r, CM_E_RANGE, "part count");
    m->nparts = (uint32_t)np;
    uint32_t prev = 0, top = 0;
    for (uint32_t i = 0; i < n && np > 0; i++) {
        uint32_t p;
        if (i > 0 && cm_ac_dec_bit(&r->ac, &ctx->part_same))
            p = prev;
        else if (cm_ac_dec_bit(&r->ac, &ctx->part_next))
            p = top + 1u;
        else {
            uint64_t k = cm_ac_dec_uint(&r->ac, &ctx->part);
            p = k < np ? (uint32_t)k + 1u : 0u;
        }
        if (p == 0 || p > np)
            return rfail(r, CM_E_RANGE, "part");
        top = p > top ? p : top;
        prev = p;
        if (i < m->nfaces)
            m->faces[i].part = p;
        else
            m->placements[i - m->nfaces].part = p;
    }
    return r->ac.overrun ? rfail(r, CM_E_TRUNCATED, "parts") : CM_OK;
}

/* format 4.12: the parts' names, after them: the bytes sent in all (0: none), then each part's
   name, that of an earlier part again (a bit, and how many parts back) or its length and bytes (none
   below a space).  Kept, each with a 0 byte after it, while they fit the build; past that all left out, the
   rest read past (cm_model.part_names_left_out) */
static cm_err read_part_names(reader *r, cm_colr_ctx *ctx)
{
    cm_model *m = &r->d->model;
    uint64_t total = cm_ac_dec_uint(&r->ac, &ctx->name_bytes), sent = 0;
    if (total > (uint64_t)m->nparts * CM_FMT_MAX_PART_NAME)
        return rfail(r, CM_E_RANGE, "part names");
    int keep = 1;
    for (uint32_t p = 0; p < m->nparts && total > 0; p++) {
        if (p > 0 && cm_ac_dec_bit(&r->ac, &ctx->name_again)) {
            uint64_t back = cm_ac_dec_uint(&r->ac, &ctx->name_back);
            if (back >= p || r->ac.overrun)
                return rfail(r, r->ac.overrun ? CM_E_TRUNCATED : CM_E_RANGE, "part name");
            const char *name = keep ? cm_model_part_name(m, p - (uint32_t)back) : NULL;
            uint32_t len = 0;
            while (name && name[len] != 0)
                len++;
            keep = keep && m->part_names_len + len + 1u <= CM_MAX_PART_NAME_BYTES;
            for (uint32_t k = 0; keep && k < len; k++) /* (from the pool into the pool: name ends before) */
                m->part_names[m->part_names_len++] = name[k];
        } else {
            uint64_t len = cm_ac_dec_uint(&r->ac, &ctx->name_len);
            if (len > CM_FMT_MAX_PART_NAME || sent + len > total || r->ac.overrun)
                return rfail(r, r->ac.overrun ? CM_E_TRUNCATED : CM_E_RANGE, "part name");
            sent += len;
            keep = keep && m->part_names_len + len + 1u <= CM_MAX_PART_NAME_BYTES;
            for (uint64_t k = 0; k < len; k++) {
                uint32_t c = cm_ac_dec_direct(&r->ac, 8);
                if (c < 0x20u) /* (no control byte reaches a console or the status line) */
                    return rfail(r, CM_E_RANGE, "part name");
                if (keep)
                    m->part_names[m->part_names_len++] = (char)c;
            }
        }
        if (keep)
            m->part_names[m->part_names_len++] = 0;
    }
    if (sent != total)
        return rfail(r, CM_E_RANGE, "part names");
    if (!keep) { /* (all or none: a step's name is never another's) */
        m->part_names_len = 0;
        m->part_names_left_out = 1;
    }
    return r->ac.overrun ? rfail(r, CM_E_TRUNCATED, "part names") : CM_OK;
}

static cm_err sec_colr(reader *r)
{
    cm_model *m = &r->d->model;
    cm_colr_ctx ctx;
    cm_colr_ctx_init(&ctx);
    m->nparts = 0;
    m->part_names_len = 0;
    m->part_names_left_out = 0;
    uint64_t np = cm_ac_dec_uint(&r->ac, &ctx.count);
    if (r->ac.overrun)
        return rfail(r, CM_E_TRUNCATED, "palette");
    if (np > CM_FMT_MAX_PALETTE)
        return rfail(r, CM_E_RANGE, "palette");
    m->npalette = (uint32_t)np;
    m->palette[0] = 0;
    for (uint32_t i = 1; i <= m->npalette; i++)
        m->palette[i] = cm_ac_dec_direct(&r->ac, 24);
    for (uint32_t f = 0; f < m->nfaces && m->npalette > 0; f++) {
        r->face = f;
        uint64_t c = cm_ac_dec_uint(&r->ac, &ctx.index);
        if (c > m->npalette)
            return rfail(r, CM_E_RANGE, "face colour");
        m->faces[f].color = (uint8_t)c;
    }
    r->face = CM_NO_FACE_INDEX;
    if (r->ac.overrun)
        return rfail(r, CM_E_TRUNCATED, m->npalette > 0 ? "face colours" : "palette");
    cm_err e = at_least_4(r, CM_FMT_PARTS_MINOR) ? read_parts(r, &ctx) : CM_OK;
    return e == CM_OK && m->nparts > 0 && at_least_4(r, CM_FMT_PART_NAMES_MINOR) ? read_part_names(r, &ctx) : e;
}

/* cm_ac_fill for a file longer than the window: the stream's bytes from pos on, read again */
__attribute__((noinline)) static const uint8_t *refill_window(void *ctx, size_t pos, size_t *avail)
{
    reader *r = ctx;
    cm_decoder *d = r->d;
    uint32_t off = r->stream_off + (uint32_t)pos, n = d->file_len - off;
    if (n > (uint32_t)CM_FILE_WINDOW_BYTES)
        n = (uint32_t)CM_FILE_WINDOW_BYTES;
    if (off >= d->file_len || d->src_read == NULL || d->src_read(d->src_ctx, off, d->buf, n) != 0)
        return NULL;
    /* the body again, in order: a window reaches past its section's end, and the next section's
       first starts inside it, so what is new of each window goes on the CRC */
    const uint32_t end = d->file_len - 4u, stop = off + n < end ? off + n : end;
    if (off <= d->recrc_next && d->recrc_next < stop) {
        d->recrc = cm_crc32_update(d->recrc, d->buf + (d->recrc_next - off), stop - d->recrc_next);
        d->recrc_next = stop;
    }
    *avail = n;
    return d->buf;
}

/* the CRC *crc continued over bytes [off, off + len) of a file longer than the window, read again a
   window at a time; 0 when they cannot be read (the one loop of the section CRCs and same_as_fed;
   noinline: the stack gates' tables name this function) */
__attribute__((noinline)) static int crc_read_again(cm_decoder *d, uint32_t off, uint32_t len, uint32_t *crc)
{
    while (len > 0) {
        uint32_t n = len < (uint32_t)CM_FILE_WINDOW_BYTES ? len : (uint32_t)CM_FILE_WINDOW_BYTES;
        if (d->src_read(d->src_ctx, off, d->buf, n) != 0)
            return 0;
        *crc = cm_crc32_update(*crc, d->buf, n);
        off += n;
        len -= n;
    }
    return 1;
}

/* a file read again: the CRC of what was read, in order, completed by reading what the sections
   left (a trimmed stream's last bytes, a window's tail); 1 = the same bytes as were fed, 0 = the
   file changed, -1 = it could not be read */
static int same_as_fed(cm_decoder *d)
{
    const uint32_t end = d->file_len - 4u;
    if (d->recrc_next < end && !crc_read_again(d, d->recrc_next, end - d->recrc_next, &d->recrc))
        return -1;
    d->recrc_next = end;
    return !crc_differs(d->recrc, d->crc);
}

#define CHANGED_FILE "file CRC (the file changed after it was received)"

cm_err cm_dec_finish(cm_decoder *d, cm_status *st)
{
    if (d->state != CM_DEC_BODY) {
        if (d->state == CM_DEC_HEADER)
            return fail(d, st, CM_E_TRUNCATED, d->len, "header incomplete");
        return cm_fail(st, CM_E_ARG, "cm_dec_finish");
    }
    if (d->len < d->file_len)
        return fail(d, st, CM_E_TRUNCATED, d->len, "file shorter than its header says");
    if (crc_differs(d->crc, cm_get_u32(d->file_crc)))
        return fail(d, st, CM_E_CRC, d->file_len - 4, "file CRC");
    /* a file longer than the window is read again from where it is stored */
    const int windowed = d->file_len > (uint32_t)CM_FILE_WINDOW_BYTES;
    if (windowed && d->src_read == NULL)
        return fail(d, st, CM_E_ARG, CM_FILE_WINDOW_BYTES,
                    "a file longer than the decoder's window, and no source to read it again (cm_dec_set_source)");
    d->recrc = cm_crc32(d->buf, d->header_len); /* the header is still in the window */
    d->recrc_next = d->header_len;
    cm_model *m = &d->model;
    m->nverts = m->nedges = m->nfaces = m->nloops = m->nuses = m->nsurfs = m->nctrl = m->nknots = 0;
    m->npalette = 0;
    /* check_header accepted exactly CM_SEC_COUNT sections, each within the file */
    if (d->nsec != CM_SEC_COUNT)
        return fail(d, st, CM_E_FORMAT, CM_HDR_NSECTIONS, "section count (a .cmz has 5 sections)");
    /* format 4.6: the sections are one stream, which the first holds whole (parse_stream) */
    int one_stream = d->version_major == CM_FMT_COMPACT_MAJOR && d->version_minor >= CM_FMT_ONE_STREAM_MINOR;
    reader r;
    for (uint32_t s = 0; s < CM_SEC_COUNT; s++) {
        const cm_dec_section *sec = &d->sec[s];
        if (sec->has_crc) {
            uint32_t crc = 0;
            if (windowed && !crc_read_again(d, sec->off, sec->len, &crc))
                return fail(d, st, CM_E_IO, sec->off, "reading the file again (section CRC)");
            if (crc_differs(windowed ? crc : cm_crc32(d->buf + sec->off, sec->len), sec->crc))
                return fail(d, st, CM_E_CRC, sec->off, "section CRC");
        }
        r.face = CM_NO_FACE_INDEX;
        r.d = d;
        r.st = st;
        if (s == 0 || !one_stream) {
            int trimmed = d->version_major >= CM_FMT_COMPACT_MAJOR;
            r.stream_off = sec->off;
            if (windowed)
                cm_ac_dec_init_fill(&r.ac, sec->len, trimmed, refill_window, &r);
            else if (trimmed)
                cm_ac_dec_init_trimmed(&r.ac, d->buf + sec->off, sec->len);
            else
                cm_ac_dec_init(&r.ac, d->buf + sec->off, sec->len);
            r.base = sec->off;
        }
        cm_err e;
        switch (sec->tag) {
        case CM_SEC_VERT: e = sec_vert(&r); break;
        case CM_SEC_EDGE: e = sec_edge(&r); break;
        case CM_SEC_SURF: e = sec_surf(&r); break;
        case CM_SEC_FACE: e = sec_face(&r); break;
        case CM_SEC_COLR: e = sec_colr(&r); break;
        default: e = fail(d, st, CM_E_FORMAT, sec->off, "section tag"); break;
        }
        if (r.ac.io_failed) { /* what the section said about its bytes is moot: they were not read */
            cm_status_init(st);
            return fail(d, st, CM_E_IO, r.base + (uint32_t)r.ac.pos, "reading the file again");
        }
        if (e != CM_OK && windowed && same_as_fed(d) == 0) { /* the cause, not what it did to a section */
            cm_status_init(st);
            return fail(d, st, CM_E_CRC, d->file_len - 4u, CHANGED_FILE);
        }
        if (e != CM_OK)
            return e;
    }
    /* format 4.6: the stream read to its end (its trimmed zeros past it); bytes no section read are
       not the writer's (an honest stream's reader ends at or past its last byte) */
    if (one_stream && r.ac.pos < r.ac.len)
        return fail(d, st, CM_E_FORMAT, r.base + (uint32_t)r.ac.pos, "bytes after the sections");
    /* a file read again: the same bytes as were checked, or no model */
    if (windowed) {
        int same = same_as_fed(d);
        if (same < 0)
            return fail(d, st, CM_E_IO, d->recrc_next, "reading the file again");
        if (same == 0)
            return fail(d, st, CM_E_CRC, d->file_len - 4u, CHANGED_FILE);
    }
    d->state = CM_DEC_DONE;
    return CM_OK;
}
