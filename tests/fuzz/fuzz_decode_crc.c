/*
 * fuzz_decode_crc - libFuzzer on the decode path of the product build: the
 * decoder is built WITHOUT FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION, so every
 * CRC (header, each section, the whole file) and every GREGORY checksum is
 * checked, as on the terminal.  Random mutations would stop at the first
 * CRC, so this target brings its own mutator (LLVMFuzzerCustomMutator) that
 * knows the .cmz layout (docs/FORMAT.md):
 *
 *   - mostly, one section's bytes are mutated by libFuzzer (LLVMFuzzerMutate:
 *     bit flips, inserted and erased bytes, dictionary words...) and the file
 *     is laid out again around it: offsets, lengths, header and file length,
 *     every CRC recomputed, so the bytes reach the section decoders, the
 *     rebuild and the tessellation;
 *   - sometimes the header itself is made hostile on purpose, CRCs still
 *     valid: the section count (0..255, the table grown or cut to match, or
 *     not), the need count and needs (0, 1, the build's limit and one more,
 *     2^32-1), one section-table entry (tag, reserved bytes, offset, length),
 *     the header or file length, the quantisation exponent, the origin and
 *     tolerances (NaN, infinities, huge, zero, negative); or the feed's chunk
 *     size (byte 0).
 *   - format 4 files (the compact header, no section table) take libFuzzer's
 *     own mutation with their header and file CRCs made right again.
 *
 * The input format and the checks are fuzz_decode.c's (included below): the
 * first byte chooses the feed size, the rest is a .cmz; every failure must
 * carry a code, a reason and a byte offset (and, for a face, the face); a
 * face that fails is left out and the mesh rolled back; no face works past
 * the points its header declares.  Seeds: tests/fuzz/corpus_decode (valid
 * files, CRCs correct, and files the CRC-less fuzzer found, whose CRCs the
 * mutator repairs on their first mutation).
 *
 * make fuzz-decode-crc FUZZ_SECONDS=600 runs it; make check-fuzz-decode-replay
 * replays the seeds and tests/fuzz/regressions_decode through it (replay_main.c,
 * where the mutator is never called and LLVMFuzzerMutate, a weak reference,
 * is absent).
 */
#include "fuzz_decode.c"

#include "cm/cm_arith.h"
#include "cm/cm_crc32.h"
#include "cm/cm_limits_info.h"

size_t LLVMFuzzerMutate(uint8_t *data, size_t size, size_t max_size) __attribute__((weak));
size_t LLVMFuzzerCustomMutator(uint8_t *data, size_t size, size_t max_size, unsigned int seed);

#define MAX_FILE (1u << 18) /* > -max_len of make fuzz-decode-crc */
#define MAX_SECS 255

static uint8_t work[MAX_FILE], sec_buf[MAX_FILE];

static uint32_t rng;
static uint32_t rnd(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
}
static uint32_t below(uint32_t n) { return n ? rnd() % n : 0; }

/* a .cmz taken apart: the header's fixed fields, the needs, the sections (tag, reserved, bytes) */
typedef struct parts {
    uint8_t fixed[CM_FMT_FIXED_HEADER];
    uint32_t nneeds, needs[255];
    uint32_t nsec;
    uint8_t tag[MAX_SECS], reserved[MAX_SECS][3];
    const uint8_t *body[MAX_SECS];
    uint32_t len[MAX_SECS];
} parts;
static parts P;

/* split b[0, n) by its own header; 0 if the header does not describe a layout inside b */
static int take_apart(const uint8_t *b, size_t n, parts *p)
{
    if (n < CM_FMT_FIXED_HEADER + 8)
        return 0;
    uint32_t H = cm_get_u32(b + CM_HDR_LENGTH);
    p->nneeds = b[CM_HDR_NLIMITS];
    p->nsec = b[CM_HDR_NSECTIONS];
    if (H != cm_fmt_header_len(p->nneeds, p->nsec) || H > n)
        return 0;
    memcpy(p->fixed, b, CM_FMT_FIXED_HEADER);
    for (uint32_t i = 0; i < p->nneeds; i++)
        p->needs[i] = cm_get_u32(b + cm_fmt_need_at(i));
    for (uint32_t s = 0; s < p->nsec; s++) {
        const uint8_t *e = b + cm_fmt_entry_at(p->nneeds, s);
        uint32_t off = cm_get_u32(e + CM_ENT_OFFSET), len = cm_get_u32(e + CM_ENT_LENGTH);
        if (off > n || len > n - off)
            return 0;
        p->tag[s] = e[CM_ENT_TAG];
        memcpy(p->reserved[s], e + CM_ENT_RESERVED, 3);
        p->body[s] = b + off;
        p->len[s] = len;
    }
    return 1;
}

/* lay p out into out (cap bytes) with every length, offset and CRC right; 0 if it does not fit */
static size_t put_together(const parts *p, uint8_t *out, size_t cap)
{
    size_t H = cm_fmt_header_len(p->nneeds, p->nsec), total = H + 4;
    for (uint32_t s = 0; s < p->nsec; s++)
        total += p->len[s];
    if (total > cap)
        return 0;
    /* the fixed fields as they were taken apart (or mutated: magic and reserved byte included, so
       not through cm_fmt_header_pack), the lengths and counts of this layout over them */
    memcpy(out, p->fixed, CM_FMT_FIXED_HEADER);
    cm_put_u32(out + CM_HDR_LENGTH, (uint32_t)H);
    cm_put_u32(out + CM_HDR_FILE_LENGTH, (uint32_t)total);
    out[CM_HDR_NLIMITS] = (uint8_t)p->nneeds;
    out[CM_HDR_NSECTIONS] = (uint8_t)p->nsec;
    for (uint32_t i = 0; i < p->nneeds; i++)
        cm_put_u32(out + cm_fmt_need_at(i), p->needs[i]);
    size_t off = H;
    for (uint32_t s = 0; s < p->nsec; s++) {
        uint8_t *e = out + cm_fmt_entry_at(p->nneeds, s);
        e[CM_ENT_TAG] = p->tag[s];
        memcpy(e + CM_ENT_RESERVED, p->reserved[s], 3);
        cm_put_u32(e + CM_ENT_OFFSET, (uint32_t)off);
        cm_put_u32(e + CM_ENT_LENGTH, p->len[s]);
        cm_put_u32(e + CM_ENT_CRC, cm_crc32(p->body[s], p->len[s]));
        memmove(out + off, p->body[s], p->len[s]);
        off += p->len[s];
    }
    cm_put_u32(out + H - 4, cm_crc32(out, H - 4));
    cm_put_u32(out + total - 4, cm_crc32(out, total - 4));
    return total;
}

/* make whatever CRCs b[0, n) has room for right again, after a change that broke its layout on purpose */
static void fix_crcs(uint8_t *b, size_t n)
{
    if (n >= 12 && b[CM_HDR_MAJOR] >= CM_FMT_COMPACT_MAJOR) {
        /* format 4: no table to lay out (the generic mutation's), the header's and the file's CRCs */
        uint32_t at = CM_FMT_COMPACT_AT_H;
        uint64_t H;
        if (cm_fmt_get_varint(b, (uint32_t)n, &at, &H) && H >= 16 && H + 4 <= n) {
            cm_put_u32(b + H - 4, cm_crc32(b, (size_t)H - 4));
            cm_put_u32(b + n - 4, cm_crc32(b, n - 4));
        }
        return;
    }
    if (n < CM_FMT_FIXED_HEADER + 8)
        return;
    uint32_t H = cm_get_u32(b + CM_HDR_LENGTH), L = cm_get_u32(b + CM_HDR_FILE_LENGTH), nl = b[CM_HDR_NLIMITS];
    for (uint32_t s = 0; s < b[CM_HDR_NSECTIONS] && cm_fmt_entry_at(nl, s + 1) <= n; s++) {
        uint8_t *e = b + cm_fmt_entry_at(nl, s);
        uint32_t off = cm_get_u32(e + CM_ENT_OFFSET), len = cm_get_u32(e + CM_ENT_LENGTH);
        if (off <= n && len <= n - off)
            cm_put_u32(e + CM_ENT_CRC, cm_crc32(b + off, len));
    }
    if (H >= CM_FMT_FIXED_HEADER + 4 && H <= n) /* (a shorter H has no room for its CRC) */
        cm_put_u32(b + H - 4, cm_crc32(b, H - 4));
    if (L >= H + 4 && L <= n) /* (a shorter L would put it into the header) */
        cm_put_u32(b + L - 4, cm_crc32(b, L - 4));
}

static uint32_t interesting_u32(uint32_t near)
{
    static const uint32_t v[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 16, 64, 255, 256, 4095, 4096, 65535, 65536,
                                 0x7fffffffu, 0x80000000u, 0xfffffffcu, 0xffffffffu};
    switch (below(4)) {
    case 0: return v[below(sizeof v / sizeof v[0])];
    case 1: return near + below(9) - 4;
    case 2: return near ^ (1u << below(32));
    default: return rnd();
    }
}

static void put_interesting_f64(uint8_t *at)
{
    static const double v[] = {0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, 1e300, -1e300, 0x1p100, 0x1p101, 5e-324};
    uint64_t bits;
    double d;
    switch (below(4)) {
    case 0:
        d = v[below(sizeof v / sizeof v[0])];
        break;
    case 1:
        bits = 0x7ff0000000000000ull | (below(2) ? 1ull : 0ull) | ((uint64_t)below(2) << 63); /* inf, NaN */
        memcpy(&d, &bits, sizeof d);
        break;
    case 2:
        d = cm_get_f64(at) * (below(2) ? 1e6 : 1e-6);
        break;
    default:
        memcpy(&bits, at, sizeof bits);
        bits ^= 1ull << below(64);
        memcpy(&d, &bits, sizeof d);
        break;
    }
    cm_put_f64(at, d);
}

/* a hostile header field (the layout stays consistent: put_together recomputes lengths and CRCs) */
static void mutate_fixed(parts *p)
{
    switch (below(6)) {
    case 0: p->fixed[CM_HDR_MAJOR + below(2)] = (uint8_t)interesting_u32(p->fixed[CM_HDR_MAJOR]); break; /* version */
    case 1: p->fixed[CM_HDR_FLAGS + below(2)] ^= (uint8_t)(1u << below(8)); break;                    /* flags */
    case 2: p->fixed[CM_HDR_QEXP] = (uint8_t)interesting_u32(p->fixed[CM_HDR_QEXP]); break; /* grid exponent */
    case 3: p->fixed[CM_HDR_RESERVED] = (uint8_t)rnd(); break;                              /* reserved */
    case 4: put_interesting_f64(p->fixed + CM_HDR_ORIGIN + 8 * below(3)); break;            /* origin */
    default: put_interesting_f64(p->fixed + CM_HDR_TESS_TOL + 8 * below(2)); break;         /* tolerances */
    }
}

static void mutate_needs(parts *p)
{
    if (below(3) == 0) {
        static const uint32_t counts[] = {0, 1, CM_LIMIT_COUNT - 1, CM_LIMIT_COUNT, CM_LIMIT_COUNT + 1, 64, 255};
        uint32_t n = below(4) ? counts[below(sizeof counts / sizeof counts[0])] : below(256);
        for (uint32_t i = p->nneeds; i < n; i++)
            p->needs[i] = below(2) ? 0 : interesting_u32(0);
        p->nneeds = n;
        return;
    }
    if (p->nneeds == 0)
        return;
    uint32_t i = below(p->nneeds);
    uint32_t limit = i < CM_LIMIT_COUNT ? (uint32_t)cm_limit_table[i].value : 0;
    switch (below(4)) {
    case 0: p->needs[i] = limit; break;
    case 1: p->needs[i] = limit + 1; break;
    case 2: p->needs[i] = 0; break;
    default: p->needs[i] = interesting_u32(p->needs[i]); break;
    }
}

/* another number of sections: extra ones empty, copies of others or random bytes, or some dropped */
static void mutate_section_count(parts *p)
{
    static const uint32_t counts[] = {0, 1, 4, 6, 7, 16, 200, 255};
    static const uint8_t none[1];
    uint32_t n = below(2) ? counts[below(sizeof counts / sizeof counts[0])] : below(256);
    for (uint32_t s = p->nsec; s < n; s++) {
        p->tag[s] = below(4) ? (uint8_t)(s + 1) : (uint8_t)rnd();
        memset(p->reserved[s], 0, 3);
        p->len[s] = 0;
        p->body[s] = none;
        if (p->nsec > 0 && below(2)) {
            uint32_t from = below(p->nsec);
            p->body[s] = p->body[from];
            p->len[s] = p->len[from];
        }
    }
    if (n < p->nsec && below(2)) { /* drop nsec - n entries from `at` on rather than from the end */
        uint32_t at = below(n + 1);
        memmove(p->tag + at, p->tag + at + (p->nsec - n), n - at);
        memmove(p->reserved + at, p->reserved + at + (p->nsec - n), 3u * (n - at));
        memmove(p->body + at, p->body + at + (p->nsec - n), sizeof p->body[0] * (n - at));
        memmove(p->len + at, p->len + at + (p->nsec - n), sizeof p->len[0] * (n - at));
    }
    p->nsec = n;
}

/* after layout: one entry of the section table, or a length of the header, made wrong on purpose */
static void break_layout(uint8_t *b, size_t n)
{
    uint32_t nl = b[CM_HDR_NLIMITS], ns = b[CM_HDR_NSECTIONS];
    if (below(3) == 0 || ns == 0) {
        uint32_t at = below(2) ? CM_HDR_LENGTH : CM_HDR_FILE_LENGTH;
        cm_put_u32(b + at, interesting_u32(cm_get_u32(b + at)));
        return;
    }
    uint8_t *e = b + cm_fmt_entry_at(nl, below(ns));
    if (e + CM_FMT_SECTION_ENTRY > b + n)
        return;
    switch (below(4)) {
    case 0: e[CM_ENT_TAG] = (uint8_t)interesting_u32(e[CM_ENT_TAG]); break;
    case 1: e[CM_ENT_RESERVED + below(3)] = (uint8_t)rnd(); break; /* the reserved bytes */
    case 2:
        cm_put_u32(e + CM_ENT_OFFSET,
                   below(2) ? (uint32_t)n - below(8) : interesting_u32(cm_get_u32(e + CM_ENT_OFFSET)));
        break;
    default: cm_put_u32(e + CM_ENT_LENGTH, interesting_u32(cm_get_u32(e + CM_ENT_LENGTH))); break;
    }
}

size_t LLVMFuzzerCustomMutator(uint8_t *data, size_t size, size_t max_size, unsigned int seed)
{
    rng = seed ? seed : 0x9e3779b9u;
    if (max_size > MAX_FILE)
        max_size = MAX_FILE;
    if (size < 2 || size > max_size || !take_apart(data + 1, size - 1, &P) || below(32) == 0) {
        /* not a layout this mutator knows (or, now and then, on purpose): libFuzzer's own mutation,
           then whatever CRCs can be made right */
        size_t n = LLVMFuzzerMutate(data, size, max_size);
        if (n > 1)
            fix_crcs(data + 1, n - 1);
        return n;
    }
    uint32_t what = below(100);
    int broken = 0;
    if (what < 6) {
        data[0] = (uint8_t)rnd(); /* another feed size */
        return size;
    } else if (what < 72 && P.nsec > 0) {
        /* the main road: one section's bytes mutated, the file laid out around them */
        uint32_t s = below(P.nsec);
        size_t others = size - 1 - P.len[s];
        if (others + 1 >= max_size)
            return size;
        memcpy(sec_buf, P.body[s], P.len[s]);
        size_t cap = max_size - 1 - others;
        P.len[s] = (uint32_t)LLVMFuzzerMutate(sec_buf, P.len[s], cap);
        P.body[s] = sec_buf;
    } else if (what < 80) {
        mutate_fixed(&P);
    } else if (what < 86) {
        mutate_needs(&P);
    } else if (what < 92) {
        mutate_section_count(&P);
    } else {
        broken = 1;
    }
    size_t n = put_together(&P, work, max_size - 1);
    if (n == 0)
        return size;
    if (broken) {
        break_layout(work, n);
        fix_crcs(work, n);
    }
    memcpy(data + 1, work, n);
    return n + 1;
}
