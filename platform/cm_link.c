/* cm_link.c - frames and messages of the link protocol (see cm_link.h, docs/LINK.md). */
#define _POSIX_C_SOURCE 200809L
#include "cm_link.h"

#include <string.h>
#include <time.h>

#include "cm/cm_arith.h"
#include "cm/cm_format.h"

#define MAGIC0 0xC5u
#define MAGIC1 0x4Du

int64_t cm_link_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

void cm_link_init(cm_link *l, cm_transport *t)
{
    l->t = t;
    l->start = l->end = 0;
}

int cm_link_send(cm_link *l, uint8_t type, int seq, const uint8_t *payload, size_t len, int timeout_ms)
{
    if (len > CM_LINK_MAX_PAYLOAD)
        return CM_T_IO;
    uint8_t *b = l->tx;
    b[0] = MAGIC0;
    b[1] = MAGIC1;
    b[2] = type;
    b[3] = seq < 0 ? l->seq++ : (uint8_t)seq;
    b[4] = (uint8_t)len;
    b[5] = (uint8_t)(len >> 8);
    uint32_t h = cm_crc32(b, 6);
    b[6] = (uint8_t)h;
    b[7] = (uint8_t)(h >> 8);
    if (len)
        memcpy(b + CM_LINK_HEADER, payload, len);
    cm_link_put32(b + CM_LINK_HEADER + len, cm_crc32(b, CM_LINK_HEADER + len));
    size_t n = CM_LINK_HEADER + len + CM_LINK_TRAILER;
    long r = l->t->write(l->t, b, n, timeout_ms);
    if (r < 0)
        return (int)r;
    if ((size_t)r != n)
        return 0;
    l->stats.frames_out++;
    l->stats.bytes_out += n;
    return 1;
}

/* One good frame out of the bytes held, if there is one: 1 found, 0 need more bytes. */
static int parse(cm_link *l, cm_link_frame *f)
{
    for (;;) {
        size_t avail = l->end - l->start;
        const uint8_t *b = l->rx + l->start;
        if (avail == 0)
            return 0;
        if (b[0] != MAGIC0 || (avail >= 2 && b[1] != MAGIC1)) {
            l->start++;
            l->stats.skipped++;
            continue;
        }
        if (avail < CM_LINK_HEADER)
            return 0;
        uint32_t h = cm_crc32(b, 6);
        size_t len = (size_t)b[4] | (size_t)b[5] << 8;
        if (b[6] != (uint8_t)h || b[7] != (uint8_t)(h >> 8) || len > CM_LINK_MAX_PAYLOAD) {
            l->stats.bad_header++;
            l->start++;
            continue;
        }
        size_t n = CM_LINK_HEADER + len + CM_LINK_TRAILER;
        if (avail < n)
            return 0;
        if (cm_link_get32(b + CM_LINK_HEADER + len) != cm_crc32(b, CM_LINK_HEADER + len)) {
            l->stats.bad_crc++;
            l->start++;
            continue;
        }
        f->type = b[2];
        f->seq = b[3];
        f->len = (uint16_t)len;
        f->payload = b + CM_LINK_HEADER;
        l->start += n;
        l->stats.frames_in++;
        return 1;
    }
}

int cm_link_recv(cm_link *l, cm_link_frame *f, int timeout_ms)
{
    int64_t deadline = cm_link_now_ms() + (timeout_ms > 0 ? timeout_ms : 0);
    uint64_t damaged = l->stats.bad_crc + l->stats.bad_header;
    for (;;) {
        if (parse(l, f))
            return 1;
        if (l->stats.bad_crc + l->stats.bad_header != damaged)
            return 0; /* a damaged frame: let the caller react (resend, report) before the deadline */
        /* keep the unread tail at the front: a frame never spans more than the buffer */
        if (l->start > 0) {
            memmove(l->rx, l->rx + l->start, l->end - l->start);
            l->end -= l->start;
            l->start = 0;
        }
        int64_t left = deadline - cm_link_now_ms();
        if (left < 0)
            left = 0;
        long n = l->t->read(l->t, l->rx + l->end, sizeof l->rx - l->end, (int)left);
        if (n < 0)
            return (int)n;
        if (n == 0) {
            if (left == 0)
                return 0;
            continue;
        }
        l->end += (size_t)n;
        l->stats.bytes_in += (uint64_t)n;
    }
}

/* ---- messages ---- */

void cm_link_hello_local(cm_link_hello *h, const char *name)
{
    memset(h, 0, sizeof *h);
    h->proto = CM_LINK_PROTO;
    h->fmt_major_max = CM_FMT_VERSION_MAJOR;
    h->fmt_minor_max = CM_FMT_VERSION_MINOR;
    h->fmt_major_min = CM_FMT_VERSION_MIN_MAJOR;
    h->max_payload = (uint16_t)(CM_LINK_MAX_PAYLOAD > 65535u ? 65535u : CM_LINK_MAX_PAYLOAD);
    h->nlimits = (uint8_t)CM_LIMIT_COUNT;
    for (unsigned i = 0; i < (unsigned)CM_LIMIT_COUNT; i++)
        h->limit[i] = cm_limit_table[i].value;
    size_t n = name ? strlen(name) : 0;
    if (n > CM_LINK_MAX_NAME)
        n = CM_LINK_MAX_NAME;
    if (n)
        memcpy(h->name, name, n);
    h->name[n] = '\0';
}

size_t cm_link_hello_pack(const cm_link_hello *h, uint8_t *out)
{
    size_t nl = strlen(h->name);
    out[0] = h->proto;
    out[1] = h->fmt_major_max;
    out[2] = h->fmt_minor_max;
    out[3] = h->fmt_major_min;
    out[4] = (uint8_t)h->max_payload;
    out[5] = (uint8_t)(h->max_payload >> 8);
    out[6] = h->nlimits;
    out[7] = (uint8_t)nl;
    size_t p = 8;
    for (unsigned i = 0; i < h->nlimits; i++, p += 4)
        cm_link_put32(out + p, h->limit[i]);
    memcpy(out + p, h->name, nl);
    return p + nl;
}

bool cm_link_hello_unpack(const cm_link_frame *f, cm_link_hello *h)
{
    const uint8_t *b = f->payload;
    if (f->type != CM_LINK_HELLO || f->len < 8)
        return false;
    memset(h, 0, sizeof *h);
    h->proto = b[0];
    h->fmt_major_max = b[1];
    h->fmt_minor_max = b[2];
    h->fmt_major_min = b[3];
    h->max_payload = (uint16_t)(b[4] | b[5] << 8);
    unsigned n = b[6], nl = b[7];
    if ((size_t)8 + 4u * n + nl != f->len || nl > CM_LINK_MAX_NAME)
        return false;
    /* a newer terminal may announce limits this sender does not know: they are ignored */
    h->nlimits = (uint8_t)(n < (unsigned)CM_LIMIT_COUNT ? n : (unsigned)CM_LIMIT_COUNT);
    for (unsigned i = 0; i < h->nlimits; i++)
        h->limit[i] = cm_link_get32(b + 8 + 4 * i);
    memcpy(h->name, b + 8 + 4 * n, nl);
    h->name[nl] = '\0';
    return true;
}

size_t cm_link_offer_pack(const cm_link_offer *o, uint8_t *out)
{
    size_t nl = strlen(o->name);
    if (nl > CM_LINK_MAX_NAME)
        nl = CM_LINK_MAX_NAME;
    cm_link_put32(out, o->size);
    cm_link_put32(out + 4, o->crc);
    cm_link_put32(out + 8, o->chunk);
    out[12] = (uint8_t)nl;
    memcpy(out + 13, o->name, nl);
    return 13 + nl;
}

bool cm_link_offer_unpack(const cm_link_frame *f, cm_link_offer *o)
{
    if (f->type != CM_LINK_OFFER || f->len < 13)
        return false;
    const uint8_t *b = f->payload;
    size_t nl = b[12];
    if (13 + nl != f->len || nl > CM_LINK_MAX_NAME)
        return false;
    o->size = cm_link_get32(b);
    o->crc = cm_link_get32(b + 4);
    o->chunk = cm_link_get32(b + 8);
    memcpy(o->name, b + 13, nl);
    o->name[nl] = '\0';
    return true;
}

size_t cm_link_text_pack(int stage, int code, const char *text, uint8_t *out)
{
    size_t p = 0;
    if (stage >= 0)
        out[p++] = (uint8_t)stage;
    out[p++] = (uint8_t)code;
    size_t n = text ? strlen(text) : 0;
    if (n > CM_LINK_MAX_TEXT)
        n = CM_LINK_MAX_TEXT;
    memcpy(out + p, text, n);
    return p + n;
}

bool cm_link_text_unpack(const cm_link_frame *f, int has_stage, int *stage, int *code, char *text, size_t cap)
{
    size_t p = 0;
    if (f->len < (has_stage ? 2u : 1u) || cap == 0)
        return false;
    if (has_stage)
        *stage = f->payload[p++];
    *code = f->payload[p++];
    size_t n = f->len - p;
    if (n >= cap)
        n = cap - 1;
    for (size_t i = 0; i < n; i++) {
        char c = (char)f->payload[p + i];
        text[i] = (c >= 32 && c < 127) ? c : '?'; /* it goes to a log line: printable only */
    }
    text[n] = '\0';
    return true;
}

const char *cm_link_type_name(int type)
{
    static const char *const names[] = {"?",    "SYNC", "HELLO", "OFFER", "ACCEPT",  "REFUSE",
                                        "DATA", "ACK",  "END",   "DONE",  "REQUEST", "ABORT"};
    return type > 0 && type < (int)(sizeof names / sizeof names[0]) ? names[type] : "?";
}
