/* cmz_splice.c - a test's edit of a format 4 file (cmz_splice.h) */
#include "cmz_splice.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_crc32.h"
#include "cm/cm_format.h"
#include "cm/cm_limits_info.h"

uint8_t *cmz_with_section(const encode_result *r, int tag, const uint8_t *edge, size_t elen, size_t *out_len)
{
    const uint8_t *b = r->bytes;
    uint32_t at = CM_FMT_COMPACT_AT_H, end = (uint32_t)r->section_bytes[0];
    uint64_t H = 0, flags = 0, N = 0, need[64], S = 0, len[8];
    if (!(cm_fmt_get_varint(b, end, &at, &H) && cm_fmt_get_varint(b, end, &at, &flags) &&
          cm_fmt_get_varint(b, end, &at, &N) && N <= 64))
        return NULL;
    for (uint64_t i = 0; i < N; i++)
        if (!cm_fmt_get_varint(b, end, &at, &need[i]))
            return NULL;
    if (!(cm_fmt_get_varint(b, end, &at, &S) && S == CM_SEC_COUNT))
        return NULL;
    for (uint64_t s = 0; s < S; s++)
        if (!cm_fmt_get_varint(b, end, &at, &len[s]))
            return NULL;
    uint32_t rest = at, rest_len = (uint32_t)H - 4 - rest; /* grid, origin, tolerances */
    len[tag - 1] = elen;
    size_t body = 0;
    for (uint64_t s = 0; s < S; s++)
        body += len[s];
    uint8_t *out = malloc(CM_FMT_MAX_HEADER + body + 4);
    if (!out)
        return NULL;
    size_t total = r->len;
    for (int pass = 0; pass < 8; pass++) { /* the file's length is a need: until it holds still */
        need[CM_LIMIT_MAX_FILE_BYTES] = total;
        uint8_t tail[CM_FMT_MAX_HEADER];
        size_t t = 0;
        t += cm_fmt_put_varint(tail + t, flags);
        t += cm_fmt_put_varint(tail + t, N);
        for (uint64_t i = 0; i < N; i++)
            t += cm_fmt_put_varint(tail + t, need[i]);
        t += cm_fmt_put_varint(tail + t, S);
        for (uint64_t s = 0; s < S; s++)
            t += cm_fmt_put_varint(tail + t, len[s]);
        memcpy(tail + t, b + rest, rest_len);
        t += rest_len;
        uint64_t h = CM_FMT_COMPACT_AT_H + t + 4 + 1;
        uint8_t hv[CM_FMT_VARINT_MAX];
        while (CM_FMT_COMPACT_AT_H + cm_fmt_put_varint(hv, h) + t + 4 != h)
            h = CM_FMT_COMPACT_AT_H + cm_fmt_put_varint(hv, h) + t + 4;
        size_t hl = cm_fmt_put_varint(hv, h);
        memcpy(out, b, CM_FMT_COMPACT_AT_H);
        memcpy(out + CM_FMT_COMPACT_AT_H, hv, hl);
        memcpy(out + CM_FMT_COMPACT_AT_H + hl, tail, t);
        cm_put_u32(out + h - 4, cm_crc32(out, (size_t)h - 4));
        size_t o = h, src = r->section_bytes[0];
        for (uint64_t s = 0; s < S; s++) {
            if (s == (uint64_t)tag - 1)
                memcpy(out + o, edge, elen);
            else
                memcpy(out + o, b + src, len[s]);
            o += len[s];
            src += r->section_bytes[s + 1];
        }
        cm_put_u32(out + o, cm_crc32(out, o));
        int still = o + 4 == total;
        total = o + 4;
        if (still)
            break;
    }
    *out_len = total;
    return out;
}

cm_err cmz_decode(cm_decoder *d, const uint8_t *b, size_t len, cm_status *st)
{
    cm_status_init(st);
    cm_dec_init(d);
    cm_err e = cm_dec_feed(d, b, len, st);
    return e == CM_OK ? cm_dec_finish(d, st) : e;
}

const char *cmz_section_refused(cm_decoder *d, const encode_result *r, int tag, const uint8_t *sec, size_t slen,
                                cm_err code, const char *cause)
{
    static char why[512];
    size_t len;
    uint8_t *b = cmz_with_section(r, tag, sec, slen, &len);
    if (!b)
        return "the file's header does not parse";
    cm_status st;
    cm_err e = cmz_decode(d, b, len, &st);
    free(b);
    const char *where = st.where ? st.where : "-";
    if (e == code && strstr(where, cause))
        return NULL;
    snprintf(why, sizeof why, "%s (%s), expected %s (\"%s\")", cm_err_name(e), where, cm_err_name(code), cause);
    return why;
}

const char *cmz_header_refused(cm_decoder *d, const uint8_t *b, size_t n, size_t hl, cm_err want, uint32_t at,
                               const char *where)
{
    static char why[512];
    for (int whole = 0; whole < 2; whole++) {
        cm_status st;
        cm_err e = cmz_decode(d, b, whole ? n : hl, &st);
        const char *said = st.where ? st.where : "?";
        if (e != want || st.offset != at || !st.where || !strstr(st.where, where)) {
            snprintf(why, sizeof why, "%s, fed %s: %s (%s) at byte %u, expected %s at byte %u", where,
                     whole ? "whole" : "its header alone", cm_err_name(e), said, st.offset, cm_err_name(want), at);
            return why;
        }
    }
    return NULL;
}
