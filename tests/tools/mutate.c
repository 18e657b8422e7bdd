/*
 * mutate - one hostile variant of a model file, for the hostile-input run (tests/tools/hostile_run.sh).
 *
 *   mutate FAMILY SEED IN OUT
 *
 * IGES families (80-column records, last column the section letter):
 *   iges-truncate   cut at a random byte
 *   iges-flip       1-8 random bytes replaced by random printable characters
 *   iges-number     a number of the Parameter section replaced by an extreme one (±1e308, 2^31-1,
 *                   5.02e13, -1, 0, 1e-320, a 400-digit run, ...)
 *   iges-pointer    an integer of the Parameter section (most are pointers) made odd and out of range,
 *                   negative, zero or the entity's own DE
 *   iges-directory  an 8-column field of the Directory section replaced by an extreme integer
 *   iges-lines      records deleted, duplicated or swapped
 * .cmz families (CRCs made valid again after the change, except where noted):
 *   cmz-truncate    cut at a random byte (CRCs not fixed: the file is short)
 *   cmz-flip        1-4 random bits flipped, CRCs not fixed: every one must be a CRC refusal
 *   cmz-flip-crc    1-4 random bits flipped in the body, every CRC fixed: reaches the section decoders
 *   cmz-header      a header byte (version, lengths, counts, quantisation, origin, tolerances, the
 *                   section table) set to an extreme value, CRCs fixed
 *   cmz-needs       a declared need set to 0, 1 or 2^32-1, CRCs fixed
 *   cmz-table       the section table: the count of sections or of needs, or an entry's tag, offset
 *                   or length set to an extreme value (the header's length kept consistent or not), CRCs
 *                   fixed
 * Format 4's compact header (varints): cmz-header sets a byte of it, cmz-needs a need and
 * cmz-table the count of sections or of needs or a section's length (or adds empty sections), the
 * varints written again around the change and H with them.  Format 4.6 (the fields range-coded):
 * cmz-needs a need, cmz-table the need count or the body's length, the stream written again.
 *
 * Deterministic: the same SEED gives the same file.  Exit status 0, or 2 on a usage or I/O error.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_arith.h"
#include "cm/cm_crc32.h"
#include "cm/cm_format.h"

static uint64_t rng;
static uint32_t next(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (uint32_t)(rng >> 16);
}
static size_t pick(size_t n) { return n ? (size_t)next() % n : 0; }

typedef struct buf {
    uint8_t *p;
    size_t n, cap;
} buf;

static int load(const char *path, buf *b)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return -1;
    b->cap = 1 << 16;
    b->p = malloc(b->cap);
    b->n = 0;
    for (;;) {
        if (b->n == b->cap) {
            b->cap *= 2;
            uint8_t *q = realloc(b->p, b->cap);
            if (!q) {
                fclose(f);
                return -1;
            }
            b->p = q;
        }
        size_t got = fread(b->p + b->n, 1, b->cap - b->n, f);
        if (got == 0)
            break;
        b->n += got;
    }
    fclose(f);
    return 0;
}

/* replace b[at, at+len) by text */
static void splice(buf *b, size_t at, size_t len, const char *text)
{
    size_t tl = strlen(text);
    if (b->n - len + tl + 1 > b->cap) {
        b->cap = b->n - len + tl + 1;
        b->p = realloc(b->p, b->cap);
    }
    memmove(b->p + at + tl, b->p + at + len, b->n - at - len);
    memcpy(b->p + at, text, tl);
    b->n = b->n - len + tl;
}

/* ---- IGES ---- */

/* start of a random record of section `sec` (column 73), or SIZE_MAX */
static size_t record_of(const buf *b, char sec)
{
    size_t chosen = SIZE_MAX, seen = 0, line = 0;
    for (size_t i = 0; i <= b->n; i++)
        if (i == b->n || b->p[i] == '\n') {
            /* reservoir sampling: each record of the section equally likely */
            if (i - line >= 73 && b->p[line + 72] == (uint8_t)sec && pick(++seen) == 0)
                chosen = line;
            line = i + 1;
        }
    return chosen;
}

/* a number token inside columns 1-64 of a Parameter record: [*at, *at+*len); 0 if none */
static int number_in_record(const buf *b, size_t rec, int integers_only, size_t *at, size_t *len)
{
    size_t cand[64][2];
    int n = 0;
    for (size_t i = rec; i < rec + 64 && i < b->n;) {
        uint8_t c = b->p[i];
        if ((c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.') {
            size_t j = i, isint = 1;
            while (j < rec + 64 && j < b->n &&
                   ((b->p[j] >= '0' && b->p[j] <= '9') || b->p[j] == '-' || b->p[j] == '+' || b->p[j] == '.' ||
                    b->p[j] == 'E' || b->p[j] == 'D' || b->p[j] == 'e' || b->p[j] == 'd')) {
                if (!(b->p[j] >= '0' && b->p[j] <= '9'))
                    isint = 0;
                j++;
            }
            if ((!integers_only || isint) && n < 64) {
                cand[n][0] = i;
                cand[n][1] = j - i;
                n++;
            }
            i = j;
        } else {
            i++;
        }
    }
    if (!n)
        return 0;
    int k = (int)pick((size_t)n);
    *at = cand[k][0];
    *len = cand[k][1];
    return 1;
}

static void iges_mutate(const char *fam, buf *b)
{
    static const char *extreme[] = {"1.0D308", "-1.0D308", "2147483647", "-2147483648", "5.02E13", "-1", "0",
                                    "1.0E-320", "9999999999999999999999", "-0.0", "1.0E309", "3"};
    if (strcmp(fam, "iges-truncate") == 0) {
        b->n = pick(b->n);
    } else if (strcmp(fam, "iges-flip") == 0) {
        int k = 1 + (int)pick(8);
        for (int i = 0; i < k && b->n; i++)
            b->p[pick(b->n)] = (uint8_t)(32 + pick(95));
    } else if (strcmp(fam, "iges-number") == 0 || strcmp(fam, "iges-pointer") == 0) {
        int ptr = fam[5] == 'p';
        for (int tries = 0; tries < 50; tries++) {
            size_t rec = record_of(b, 'P'), at, len;
            if (rec == SIZE_MAX || !number_in_record(b, rec, ptr, &at, &len))
                continue;
            char text[64];
            if (ptr) {
                static const long vals[] = {0, -1, -7, 1, 3, 2147483647, 999999, 99999999};
                long v = pick(3) == 0 ? (long)(2 * pick(4000) + 1) : vals[pick(8)];
                snprintf(text, sizeof text, "%ld", v);
            } else {
                snprintf(text, sizeof text, "%s", extreme[pick(sizeof extreme / sizeof *extreme)]);
            }
            /* keep the 80-column layout: pad or cut inside the record's data columns */
            splice(b, at, len, text);
            long delta = (long)strlen(text) - (long)len;
            if (delta > 0) {
                /* take the same number of blanks out before column 65, if there are any */
                for (size_t i = rec + 63; delta > 0 && i > at + strlen(text); i--)
                    if (b->p[i] == ' ') {
                        memmove(b->p + i, b->p + i + 1, b->n - i - 1);
                        b->n--;
                        delta--;
                    }
            } else {
                for (; delta < 0; delta++)
                    splice(b, rec + 60, 0, " ");
            }
            return;
        }
    } else if (strcmp(fam, "iges-directory") == 0) {
        static const char *vals[] = {"2147483647", "-99999", "0", "99999999", "       -1", "5020000000000"};
        size_t rec = record_of(b, 'D');
        if (rec == SIZE_MAX)
            return;
        size_t field = pick(9) * 8;
        char text[16];
        snprintf(text, sizeof text, "%8.8s", vals[pick(6)]);
        memcpy(b->p + rec + field, text, 8);
    } else if (strcmp(fam, "iges-lines") == 0) {
        size_t rec = record_of(b, "SGDP"[pick(4)]);
        if (rec == SIZE_MAX)
            return;
        size_t end = rec;
        while (end < b->n && b->p[end] != '\n')
            end++;
        if (end < b->n)
            end++;
        int op = (int)pick(3);
        if (op == 0) { /* delete */
            memmove(b->p + rec, b->p + end, b->n - end);
            b->n -= end - rec;
        } else if (op == 1) { /* duplicate */
            char line[256];
            size_t l = end - rec < sizeof line - 1 ? end - rec : sizeof line - 1;
            memcpy(line, b->p + rec, l);
            line[l] = 0;
            splice(b, rec, 0, line);
        } else { /* swap with the next record */
            size_t e2 = end;
            while (e2 < b->n && b->p[e2] != '\n')
                e2++;
            if (e2 < b->n)
                e2++;
            if (e2 - end == end - rec) {
                uint8_t tmp[256];
                size_t l = end - rec;
                if (l <= sizeof tmp) {
                    memcpy(tmp, b->p + rec, l);
                    memmove(b->p + rec, b->p + end, l);
                    memcpy(b->p + end, tmp, l);
                }
            }
        }
    }
}

/* ---- .cmz ---- */

/* format 4: the header's varints after H (flags, N, needs, S, lengths, grid, tolerances), 0 if they
   do not parse */
#define MAX_FIELDS 600
static int compact_fields(const buf *b, uint32_t *H, uint64_t *f, uint32_t *nf)
{
    uint32_t at = CM_FMT_COMPACT_AT_H;
    uint64_t h;
    if (b->n < 12 || b->p[CM_HDR_MAJOR] < CM_FMT_COMPACT_MAJOR || !cm_fmt_get_varint(b->p, (uint32_t)b->n, &at, &h) ||
        h > b->n || h < at + 4)
        return 0;
    *H = (uint32_t)h;
    *nf = 0;
    while (at < h - 4 && *nf < MAX_FIELDS)
        if (!cm_fmt_get_varint(b->p, (uint32_t)h - 4, &at, &f[(*nf)++]))
            return 0;
    return at == h - 4;
}

/* the header H bytes long replaced by one of the fields f (H anew, its CRC left to fix_crcs) */
static void compact_emit(buf *b, uint32_t H, const uint64_t *f, uint32_t nf)
{
    static uint8_t body[MAX_FIELDS * CM_FMT_VARINT_MAX];
    uint32_t nb = 0;
    for (uint32_t k = 0; k < nf; k++)
        nb += cm_fmt_put_varint(body + nb, f[k]);
    uint8_t hb[CM_FMT_VARINT_MAX];
    uint32_t nh = 0;
    for (uint32_t lh = 1; lh <= 5 && !nh; lh++)
        if (cm_fmt_put_varint(hb, CM_FMT_COMPACT_AT_H + lh + nb + 4u) == lh)
            nh = CM_FMT_COMPACT_AT_H + lh + nb + 4u;
    size_t rest = b->n - H, n = nh + rest;
    uint8_t *p = malloc(n);
    memcpy(p, b->p, CM_FMT_COMPACT_AT_H);
    uint32_t lh = cm_fmt_put_varint(p + CM_FMT_COMPACT_AT_H, nh);
    memcpy(p + CM_FMT_COMPACT_AT_H + lh, body, nb);
    memcpy(p + nh, b->p + H, rest);
    free(b->p);
    b->p = p;
    b->n = b->cap = n;
}

/* the header's length, either format (0 if it is no use) */
static uint32_t header_len(const buf *b)
{
    if (b->n >= 12 && b->p[CM_HDR_MAJOR] >= CM_FMT_COMPACT_MAJOR) {
        uint32_t at = CM_FMT_COMPACT_AT_H;
        uint64_t h;
        return cm_fmt_get_varint(b->p, (uint32_t)b->n, &at, &h) && h <= b->n ? (uint32_t)h : 0;
    }
    return b->n >= CM_FMT_FIXED_HEADER ? cm_get_u32(b->p + CM_HDR_LENGTH) : 0;
}

/* every CRC the file holds made right for its present bytes */
static void fix_crcs(buf *b)
{
    if (b->n < (b->n > CM_HDR_MAJOR && b->p[CM_HDR_MAJOR] >= CM_FMT_COMPACT_MAJOR ? 16u : CM_FMT_FIXED_HEADER + 8u))
        return;
    uint32_t H = header_len(b);
    if (H < 16 || H > b->n)
        return;
    if (b->p[CM_HDR_MAJOR] < CM_FMT_COMPACT_MAJOR) {
        if (H < CM_FMT_FIXED_HEADER + 4)
            return;
        for (uint32_t s = 0; s < b->p[CM_HDR_NSECTIONS]; s++) {
            uint32_t at = cm_fmt_entry_at(b->p[CM_HDR_NLIMITS], s);
            if (at + CM_FMT_SECTION_ENTRY > H - 4)
                break;
            uint32_t off = cm_get_u32(b->p + at + CM_ENT_OFFSET), len = cm_get_u32(b->p + at + CM_ENT_LENGTH);
            if (off <= b->n && len <= b->n - off)
                cm_put_u32(b->p + at + CM_ENT_CRC, cm_crc32(b->p + off, len));
        }
    }
    cm_put_u32(b->p + H - 4, cm_crc32(b->p, H - 4));
    cm_put_u32(b->p + b->n - 4, cm_crc32(b->p, b->n - 4));
}

/* format 4's cmz-table and cmz-needs: one varint field (a count, a length, a need) changed */
static void compact_mutate(const char *fam, buf *b)
{
    static uint64_t f[MAX_FIELDS + 256];
    uint32_t H, nf;
    if (!compact_fields(b, &H, f, &nf) || nf < 3 || f[1] + 3 > nf)
        return;
    uint32_t N = (uint32_t)f[1], iS = 2 + N;
    static const uint64_t vals[] = {0, 1, 4, 6, 24, 200, 255, 256, 0xffffffffu, 0x7fffffffu, 0x10000u, 1ull << 40};
    uint64_t v = vals[pick(12)];
    if (strcmp(fam, "cmz-needs") == 0) {
        static const uint64_t nv[] = {0, 1, 0xffffffffu, 0x100000000ull};
        if (N)
            f[2 + pick(N)] = nv[pick(4)];
    } else {
        int what = (int)pick(4);
        if (what == 0)
            f[iS] = v; /* the section count */
        else if (what == 1)
            f[1] = v; /* the need count */
        else if (what == 2 && iS + 1 + CM_SEC_COUNT <= nf) /* a length: extreme, or off by a little */
            f[iS + 1 + pick(CM_SEC_COUNT)] = pick(2) ? v : f[iS + 1 + pick(CM_SEC_COUNT)] + pick(64);
        else if (iS < nf && f[iS] == CM_SEC_COUNT) {
            /* empty sections after the five: their lengths 0, the count with them */
            uint32_t extra = pick(2) ? 1 : 1 + (uint32_t)pick(250 - CM_SEC_COUNT), at = iS + 1 + CM_SEC_COUNT;
            memmove(f + at + extra, f + at, (nf - at) * sizeof *f);
            memset(f + at, 0, extra * sizeof *f);
            nf += extra;
            f[iS] = CM_SEC_COUNT + extra;
        }
    }
    compact_emit(b, H, f, nf);
    fix_crcs(b);
}

/* format 4.6's cmz-table and cmz-needs: the header's stream read, a need, the need count or the body's
   length changed, the stream written again (cm_fmt_stream_pack) before the unchanged body */
static void stream_mutate(const char *fam, buf *b)
{
    uint32_t H = header_len(b), unknown;
    cm_fmt_header h;
    uint32_t need[256] = {0};
    if (H < CM_FMT_STREAM_MIN_HEADER || H > b->n || cm_fmt_stream_unpack(b->p, H, &h, need, 256, &unknown))
        return;
    uint32_t body = h.file_len - H - 4u;
    if (strcmp(fam, "cmz-needs") == 0) {
        static const uint32_t nv[] = {0, 1, 0xffffffffu};
        need[pick(h.nlimits)] = nv[pick(3)];
    } else if (pick(2)) {
        static const uint32_t nn[] = {25, 26, 27, 100, 255};
        h.nlimits = (uint8_t)nn[pick(5)];
    } else {
        static const uint32_t bl[] = {0, 1, 0x7fffffffu, 0xfffffff0u};
        body = pick(2) ? bl[pick(4)] : body + (uint32_t)pick(64) - 32u;
    }
    static uint8_t hb[CM_FMT_MAX_HEADER];
    uint32_t nh = cm_fmt_stream_pack(hb, &h, need, body);
    if (nh == 0)
        return;
    size_t rest = b->n - H, n = nh + rest;
    uint8_t *p = malloc(n);
    memcpy(p, hb, nh);
    memcpy(p + nh, b->p + H, rest);
    free(b->p);
    b->p = p;
    b->n = b->cap = n;
    fix_crcs(b);
}

static void cmz_mutate(const char *fam, buf *b)
{
    if (b->n < CM_FMT_STREAM_MIN_HEADER + 4u) /* (a format 4.6 file can be 58 bytes) */
        return;
    uint32_t H = header_len(b);
    if (b->p[CM_HDR_MAJOR] >= CM_FMT_COMPACT_MAJOR && (strcmp(fam, "cmz-table") == 0 || strcmp(fam, "cmz-needs") == 0)) {
        if (b->p[CM_HDR_MINOR] >= CM_FMT_ONE_STREAM_MINOR)
            stream_mutate(fam, b);
        else
            compact_mutate(fam, b);
        return;
    }
    if (strcmp(fam, "cmz-truncate") == 0) {
        b->n = pick(b->n);
    } else if (strcmp(fam, "cmz-flip") == 0 || strcmp(fam, "cmz-flip-crc") == 0) {
        int fix = fam[8] == '-';
        int k = 1 + (int)pick(4);
        size_t lo = fix && H + 4 < b->n ? H : 0, span = b->n - lo - (fix ? 4 : 0);
        for (int i = 0; i < k; i++)
            b->p[lo + pick(span)] ^= (uint8_t)(1u << pick(8));
        if (fix)
            fix_crcs(b);
    } else if (strcmp(fam, "cmz-header") == 0) {
        static const uint32_t vals[] = {0, 1, 5, 6, 200, 255, 0xffffffffu, 0x7fffffffu, 60, 4096};
        /* a byte after the magic and before the header's CRC (the first 64 bytes if H is no use) */
        size_t at = CM_HDR_MAJOR + pick((H > 8 && H <= b->n ? H - 4 : b->n < 64 ? b->n : 64) - CM_HDR_MAJOR);
        uint32_t v = vals[pick(10)];
        if (at == CM_HDR_NLIMITS || at == CM_HDR_NSECTIONS || at == CM_HDR_QEXP || at == CM_HDR_MAJOR ||
            at == CM_HDR_MINOR || pick(2)) /* the one-byte fields, and any byte half the time */
            b->p[at] = (uint8_t)v;
        else if (at + 4 <= b->n)
            cm_put_u32(b->p + at, v);
        fix_crcs(b);
    } else if (strcmp(fam, "cmz-table") == 0) {
        static const uint32_t vals[] = {0, 1, 4, 6, 200, 255, 0xffffffffu, 0x7fffffffu, 0x10000u};
        uint32_t v = vals[pick(9)], nl = b->p[CM_HDR_NLIMITS];
        int what = (int)pick(5);
        if (what == 4 && b->p[CM_HDR_NSECTIONS] == CM_SEC_COUNT) {
            /* well-formed extra sections after the five: tags 6, 7, ..., empty, at the file's end */
            uint32_t extra = pick(2) ? 1 : 1 + (uint32_t)pick(250 - CM_SEC_COUNT);
            uint32_t grow = CM_FMT_SECTION_ENTRY * extra, at_end = H - 4;
            uint8_t *ins = calloc(grow, 1);
            uint32_t end = (uint32_t)b->n - 4 + grow;
            for (uint32_t k = 0; k < extra; k++) {
                ins[CM_FMT_SECTION_ENTRY * k + CM_ENT_TAG] = (uint8_t)(CM_SEC_COUNT + 1 + k);
                cm_put_u32(ins + CM_FMT_SECTION_ENTRY * k + CM_ENT_OFFSET, end);
            }
            /* the existing entries' offsets move with the header */
            for (uint32_t k = 0; k < CM_SEC_COUNT; k++) {
                uint8_t *e = b->p + cm_fmt_entry_at(nl, k);
                cm_put_u32(e + CM_ENT_OFFSET, cm_get_u32(e + CM_ENT_OFFSET) + grow);
            }
            b->p = realloc(b->p, b->n + grow);
            memmove(b->p + at_end + grow, b->p + at_end, b->n - at_end);
            memcpy(b->p + at_end, ins, grow);
            b->n += grow;
            free(ins);
            b->p[CM_HDR_NSECTIONS] = (uint8_t)(CM_SEC_COUNT + extra);
            cm_put_u32(b->p + CM_HDR_LENGTH, H + grow);
            cm_put_u32(b->p + CM_HDR_FILE_LENGTH, (uint32_t)b->n);
        } else if (what == 0 || what == 1) {
            /* a count, and (half the time) the header length made to agree with it */
            b->p[what == 0 ? CM_HDR_NSECTIONS : CM_HDR_NLIMITS] = (uint8_t)v;
            if (pick(2)) {
                uint32_t nh = cm_fmt_header_len(b->p[CM_HDR_NLIMITS], b->p[CM_HDR_NSECTIONS]);
                if (nh <= b->n)
                    cm_put_u32(b->p + CM_HDR_LENGTH, nh);
            }
        } else if (cm_fmt_entry_at(nl, CM_SEC_COUNT) <= b->n) {
            uint32_t at = cm_fmt_entry_at(nl, (uint32_t)pick(CM_SEC_COUNT));
            if (what == 2)
                b->p[at + CM_ENT_TAG] = (uint8_t)v;
            else /* its offset or its length */
                cm_put_u32(b->p + at + CM_ENT_OFFSET + (CM_ENT_LENGTH - CM_ENT_OFFSET) * pick(2),
                           pick(2) ? v : cm_get_u32(b->p + at + CM_ENT_OFFSET) + (uint32_t)pick(64));
        }
        fix_crcs(b);
    } else if (strcmp(fam, "cmz-needs") == 0) {
        static const uint32_t vals[] = {0, 1, 0xffffffffu};
        uint32_t nl = b->p[CM_HDR_NLIMITS];
        if (nl)
            cm_put_u32(b->p + cm_fmt_need_at((uint32_t)pick(nl)), vals[pick(3)]);
        fix_crcs(b);
    }
}

int main(int argc, char **argv)
{
    if (argc != 5) {
        fprintf(stderr, "usage: mutate FAMILY SEED IN OUT\n");
        return 2;
    }
    const char *fam = argv[1];
    rng = 0x9E3779B97F4A7C15ull ^ strtoull(argv[2], NULL, 10) * 0x2545F4914F6CDD1Dull;
    if (!rng)
        rng = 1;
    for (int i = 0; i < 8; i++)
        next();
    buf b = {0};
    if (load(argv[3], &b) != 0) {
        fprintf(stderr, "mutate: cannot read %s\n", argv[3]);
        return 2;
    }
    if (strncmp(fam, "iges-", 5) == 0)
        iges_mutate(fam, &b);
    else if (strncmp(fam, "cmz-", 4) == 0)
        cmz_mutate(fam, &b);
    else {
        fprintf(stderr, "mutate: unknown family %s\n", fam);
        return 2;
    }
    FILE *f = fopen(argv[4], "wb");
    if (!f || fwrite(b.p, 1, b.n, f) != b.n || fclose(f) != 0) {
        fprintf(stderr, "mutate: cannot write %s\n", argv[4]);
        return 2;
    }
    free(b.p);
    return 0;
}
