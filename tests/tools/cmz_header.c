/*
 * cmz_header - read a .cmz header's needs, or write the file with one need changed (the header and
 * file CRCs made valid again), for the gates that lie to the decoders (docs/FORMAT.md, Header).
 *
 *   cmz_header need FILE ID                 print limit ID's need
 *   cmz_header set-need FILE ID VALUE OUT   write OUT: FILE with limit ID's need set to VALUE
 *
 * Formats 1-3: the fixed header (u32 H at byte 8, u8 N at 16, need i the u32 at 60 + 4 i); 4.0-4.5:
 * the compact header (varints from byte 6: H, flags, N, the N needs, ...; H counts its own varint, so
 * a need whose varint changes length moves everything after it and H itself); 4.6: the fields are a
 * range-coded stream, read and written again with the decoder's own cm_fmt_stream_unpack/pack (the
 * need MAX_FILE_BYTES is the file's length there: setting it is refused).  In C, not Python, because
 * of that stream: the tool and the reader cannot disagree on it.  Exit 0, 1 when the file has no such
 * need, 2 on a usage or I/O error.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_crc32.h"
#include "cm/cm_format.h"
#include "cm/cm_limits_info.h"

#define MAX_FIELDS 600

static uint8_t *load(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    size_t cap = 1 << 16, len = 0, got;
    uint8_t *p = malloc(cap);
    while (p && (got = fread(p + len, 1, cap - len, f)) > 0)
        if ((len += got) == cap)
            p = realloc(p, cap *= 2);
    fclose(f);
    *n = len;
    return p;
}

static int stream_header(const uint8_t *b) { return b[CM_HDR_MAJOR] == CM_FMT_COMPACT_MAJOR && b[CM_HDR_MINOR] >= CM_FMT_ONE_STREAM_MINOR; }

/* format 4.0-4.5: the varints between H and the CRC; 0 when they do not parse */
static int varint_fields(const uint8_t *b, size_t n, uint32_t *H, uint64_t *f, uint32_t *nf)
{
    uint32_t at = CM_FMT_COMPACT_AT_H;
    uint64_t h;
    if (!cm_fmt_get_varint(b, (uint32_t)n, &at, &h) || h > n || h < at + 4)
        return 0;
    *H = (uint32_t)h;
    *nf = 0;
    while (at < h - 4 && *nf < MAX_FIELDS)
        if (!cm_fmt_get_varint(b, (uint32_t)h - 4, &at, &f[(*nf)++]))
            return 0;
    return at == h - 4 && *nf >= 2;
}

int main(int argc, char **argv)
{
    int get = argc == 4 && strcmp(argv[1], "need") == 0, set = argc == 6 && strcmp(argv[1], "set-need") == 0;
    if (!get && !set) {
        fprintf(stderr, "usage: cmz_header need FILE ID | cmz_header set-need FILE ID VALUE OUT\n");
        return 2;
    }
    size_t n;
    uint8_t *b = load(argv[2], &n);
    if (!b || n < 16) {
        fprintf(stderr, "cmz_header: %s: cannot read a .cmz\n", argv[2]);
        return 2;
    }
    uint32_t id = (uint32_t)strtoul(argv[3], NULL, 10);
    uint64_t value = set ? strtoull(argv[4], NULL, 10) : 0;
    static uint8_t out[CM_FMT_MAX_HEADER];
    uint32_t H, nh = 0;
    if (b[CM_HDR_MAJOR] < CM_FMT_COMPACT_MAJOR) {
        H = cm_get_u32(b + CM_HDR_LENGTH);
        if (id >= b[CM_HDR_NLIMITS] || cm_fmt_need_at(id) + 4 > n || H > n || H > CM_FMT_MAX_HEADER)
            return 1;
        if (get) {
            printf("%u\n", cm_get_u32(b + cm_fmt_need_at(id)));
            return 0;
        }
        memcpy(out, b, H);
        cm_put_u32(out + cm_fmt_need_at(id), (uint32_t)value);
        cm_put_u32(out + H - 4, cm_crc32(out, H - 4));
        nh = H;
    } else if (stream_header(b)) {
        uint32_t at = CM_FMT_COMPACT_AT_H, unknown, need[256] = {0};
        uint64_t h;
        cm_fmt_header hd;
        const char *why = "header length";
        if (!cm_fmt_get_varint(b, (uint32_t)n, &at, &h) || h > n || (why = cm_fmt_stream_unpack(b, (uint32_t)h, &hd, need, 256, &unknown))) {
            fprintf(stderr, "cmz_header: %s: %s\n", argv[2], why);
            return 1;
        }
        H = (uint32_t)h;
        if (id >= hd.nlimits)
            return 1;
        if (get) {
            printf("%u\n", need[id]);
            return 0;
        }
        if (id == CM_LIMIT_MAX_FILE_BYTES)
            return 1;
        need[id] = (uint32_t)value;
        nh = cm_fmt_stream_pack(out, &hd, need, hd.file_len - H - 4u);
    } else {
        static uint64_t f[MAX_FIELDS];
        uint32_t nf;
        if (!varint_fields(b, n, &H, f, &nf) || id >= f[1] || 2 + id >= nf)
            return 1;
        if (get) {
            printf("%llu\n", (unsigned long long)f[2 + id]);
            return 0;
        }
        f[2 + id] = value;
        uint8_t fields[MAX_FIELDS * CM_FMT_VARINT_MAX];
        uint32_t nb = 0;
        for (uint32_t k = 0; k < nf; k++)
            nb += cm_fmt_put_varint(fields + nb, f[k]);
        uint8_t hb[CM_FMT_VARINT_MAX];
        for (uint32_t lh = 1; lh <= 5 && !nh; lh++)
            if (cm_fmt_put_varint(hb, CM_FMT_COMPACT_AT_H + lh + nb + 4u) == lh)
                nh = CM_FMT_COMPACT_AT_H + lh + nb + 4u;
        if (nh > CM_FMT_MAX_HEADER)
            return 1;
        memcpy(out, b, CM_FMT_COMPACT_AT_H);
        uint32_t lh = cm_fmt_put_varint(out + CM_FMT_COMPACT_AT_H, nh);
        memcpy(out + CM_FMT_COMPACT_AT_H + lh, fields, nb);
        cm_put_u32(out + nh - 4, cm_crc32(out, nh - 4));
    }
    if (nh == 0)
        return 1;
    size_t rest = n - H, total = nh + rest;
    uint8_t *file = malloc(total);
    memcpy(file, out, nh);
    memcpy(file + nh, b + H, rest);
    cm_put_u32(file + total - 4, cm_crc32(file, total - 4));
    FILE *f = fopen(argv[5], "wb");
    if (!f || fwrite(file, 1, total, f) != total || fclose(f) != 0) {
        fprintf(stderr, "cmz_header: %s: cannot write\n", argv[5]);
        return 2;
    }
    return 0;
}
