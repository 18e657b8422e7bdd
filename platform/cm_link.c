/* cm_link.c - frames and messages of the link protocol (see cm_link.h, docs/LINK.md). */
#define _POSIX_C_SOURCE 200809L
#include "cm_link.h"

#include <string.h>

#include "cm/cm_crc32.h"
#include "cm/cm_format.h"
#include "cm_clock.h"

#define MAGIC0 0xC5u
#define MAGIC1 0x4Du

int64_t cm_link_now_ms(void)
{
    return cm_clock_ms();
}

void cm_link_init(cm_link *l, cm_transport *t)
{
    l->t = t;
    l->start = l->end = 0;
    l->rx_off = 0;
    l->cand = l->stale_to = l->nest_from = 0;
    l->rxcrc[0] = 0;
    l->last_rx_ms = cm_clock_ms();
}

void cm_link_set_rate(cm_link *l, unsigned bytes_per_s)
{
    l->rate_bps = bytes_per_s;
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

/* ---- the CRC of any stretch of rx from the running CRC (as zlib's crc32_combine) ---- */

#define CRC_POLY 0xEDB88320u

/* a * b modulo the CRC polynomial, bit-reflected */
static uint32_t multmodp(uint32_t a, uint32_t b)
{
    uint32_t m = 1u << 31, p = 0;
    for (;;) {
        if (a & m) {
            p ^= b;
            if ((a & (m - 1)) == 0)
                break;
        }
        m >>= 1;
        b = b & 1 ? (b >> 1) ^ CRC_POLY : b >> 1;
    }
    return p;
}

/* x^(8 n) modulo the polynomial: what n zero bytes do to a CRC register */
static uint32_t shift_bytes(size_t n)
{
    static uint32_t x2n[32]; /* x^(2^k); computed once, static: no heap on the terminal */
    static int ready;
    if (!ready) {
        uint32_t p = 1u << 30; /* x^1 */
        x2n[0] = p;
        for (int k = 1; k < 32; k++)
            x2n[k] = p = multmodp(p, p);
        ready = 1;
    }
    uint32_t p = 1u << 31; /* x^0 */
    for (unsigned k = 3; n; n >>= 1, k++)
        if (n & 1)
            p = multmodp(x2n[k & 31], p);
    return p;
}

/* CRC-32 of rx[p..q): crc(A B) = crc(A) * x^(8 |B|) + crc(B), so crc(B) comes from the two prefixes */
static uint32_t crc_window(const cm_link *l, size_t p, size_t q)
{
    return l->rxcrc[q] ^ multmodp(shift_bytes(q - p), l->rxcrc[p]);
}

/* bytes just read into rx[from..to): extend the running CRC */
static void crc_extend(cm_link *l, size_t from, size_t to)
{
    uint32_t c = ~l->rxcrc[from];
    for (size_t i = from; i < to; i++) {
        c ^= l->rx[i];
        for (int k = 0; k < 8; k++)
            c = (c >> 1) ^ (CRC_POLY & (0u - (c & 1u)));
        l->rxcrc[i + 1] = ~c;
    }
}

/* line time of n bytes at the link's rate (assumed when unknown), ms */
static int64_t rx_line_ms(const cm_link *l, size_t n)
{
    unsigned bps = l->rate_bps ? l->rate_bps : CM_LINK_ASSUMED_BPS;
    return (int64_t)(n * 1000u / bps) + 1;
}

/* the frame at rx[q] if its header is good: its length (header + payload + CRC), else 0 */
static size_t frame_at(const cm_link *l, size_t q)
{
    const uint8_t *b = l->rx + q;
    if (b[0] != MAGIC0 || b[1] != MAGIC1)
        return 0;
    uint32_t h = cm_crc32(b, 6);
    size_t len = (size_t)b[4] | (size_t)b[5] << 8;
    if (b[6] != (uint8_t)h || b[7] != (uint8_t)(h >> 8) || len > CM_LINK_MAX_PAYLOAD)
        return 0;
    return CM_LINK_HEADER + len + CM_LINK_TRAILER;
}

/* a whole frame with a good CRC after the candidate's header?  Scans each byte once (nest_from);
   a nested header still incomplete is where the next look starts.  *at: where it begins */
static bool nested_frame(cm_link *l, size_t *at)
{
    size_t q = l->nest_from > l->rx_off + l->start ? (size_t)(l->nest_from - l->rx_off) : l->start + 1;
    for (; q + CM_LINK_HEADER <= l->end; q++) {
        size_t n = frame_at(l, q);
        if (n == 0)
            continue;
        if (q + n > l->end)
            break; /* look again when it is in */
        if (cm_link_get32(l->rx + q + n - CM_LINK_TRAILER) == crc_window(l, q, q + n - CM_LINK_TRAILER)) {
            *at = q;
            return true;
        }
    }
    l->nest_from = l->rx_off + q;
    return false;
}

/*
 * One good frame out of the bytes held, if there is one: 1 found, 0 need more bytes.
 * A frame whose header is good but whose bytes are not all in becomes the candidate, with a deadline
 * (cm_link_recv gives it up then, or at a silence; cm_link.h).  A whole frame after its header gives
 * it up at once.  Candidates that began before a candidate was given up (stream offsets below
 * stale_to) are given up at once when they are still incomplete: otherwise, after a flood of headers
 * each announcing 16 KiB, every one of them would wait out its own deadline in turn.
 */
static int parse(cm_link *l, cm_link_frame *f, int64_t now)
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
            return 0; /* the next bytes, whatever they are, settle it: no deadline needed */
        uint32_t h = cm_crc32(b, 6);
        size_t len = (size_t)b[4] | (size_t)b[5] << 8;
        if (b[6] != (uint8_t)h || b[7] != (uint8_t)(h >> 8) || len > CM_LINK_MAX_PAYLOAD) {
            l->stats.bad_header++;
            l->start++;
            continue;
        }
        size_t n = CM_LINK_HEADER + len + CM_LINK_TRAILER;
        if (avail < n) {
            uint64_t at = l->rx_off + l->start;
            if (at < l->stale_to) {
                l->stats.stalled++;
                l->start++;
                continue;
            }
            if (l->cand != at + 1) {
                l->cand = at + 1;
                l->nest_from = 0;
                l->cand_deadline = now + CM_LINK_PARTIAL_FLOOR_MS + rx_line_ms(l, n - avail);
                l->cand_t0 = now;
                l->cand_have = avail;
                l->cand_cap = now + CM_LINK_PARTIAL_FLOOR_MS +
                              (int64_t)CM_LINK_PARTIAL_SLACK * (int64_t)((n - avail) * 1000u / CM_LINK_ASSUMED_BPS);
            }
            size_t q;
            if (nested_frame(l, &q)) {
                l->stats.stalled++;
                l->stale_to = l->rx_off + q; /* and every incomplete one before the whole frame */
                l->start++;
                l->cand = 0;
                continue;
            }
            return 0;
        }
        if (cm_link_get32(b + CM_LINK_HEADER + len) != crc_window(l, l->start, l->start + CM_LINK_HEADER + len)) {
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

/* The candidate's deadline has passed: if its bytes are still coming, move it to when the rest will be
   in at the pace seen since the wait began, plus the floor (cm_link.h), never past cand_cap.
   True if it was moved. */
static bool still_coming(cm_link *l, int64_t now)
{
    size_t avail = l->end - l->start, n = frame_at(l, l->start);
    if (avail <= l->cand_have || avail >= n || now - l->last_rx_ms >= CM_LINK_PARTIAL_GAP_MS)
        return false;
    int64_t spent = now - l->cand_t0;
    int64_t rest = (int64_t)((n - avail) * (uint64_t)(spent > 0 ? spent : 1) / (avail - l->cand_have));
    int64_t moved = now + CM_LINK_PARTIAL_FLOOR_MS + rest;
    if (moved > l->cand_cap)
        moved = l->cand_cap;
    if (moved <= l->cand_deadline)
        return false;
    l->cand_deadline = moved;
    return true;
}

/* the partial frame at rx[start] is the one waited for */
static bool waiting(const cm_link *l)
{
    return l->cand == l->rx_off + l->start + 1 && l->end > l->start;
}

int cm_link_recv(cm_link *l, cm_link_frame *f, int timeout_ms)
{
    int64_t now = cm_clock_ms();
    int64_t deadline = now + (timeout_ms > 0 ? timeout_ms : 0);
    uint64_t damaged = l->stats.bad_crc + l->stats.bad_header + l->stats.stalled;
    for (;;) {
        if (parse(l, f, now))
            return 1;
        if (l->stats.bad_crc + l->stats.bad_header + l->stats.stalled != damaged)
            return 0; /* a damaged frame: let the caller react (resend, report) before the deadline */
        /* keep the unread tail at the front, but only when the room behind it is less than a frame:
           moving it on every call costs a buffer's worth of bytes per frame in a burst of small ones */
        if (l->start > 0 && sizeof l->rx - l->end < CM_LINK_MAX_FRAME) {
            memmove(l->rx, l->rx + l->start, l->end - l->start);
            memmove(l->rxcrc, l->rxcrc + l->start, (l->end - l->start + 1) * sizeof l->rxcrc[0]);
            l->rx_off += l->start;
            l->end -= l->start;
            l->start = 0;
        } else if (l->start == l->end && l->start > 0) {
            l->rxcrc[0] = l->rxcrc[l->end];
            l->rx_off += l->start;
            l->start = l->end = 0;
        }
        now = cm_clock_ms();
        int64_t left = deadline - now;
        bool cand = waiting(l);
        if (cand && now >= l->cand_deadline)
            (void)still_coming(l, now);
        int64_t give_up = l->cand_deadline < l->last_rx_ms + CM_LINK_PARTIAL_GAP_MS ? l->cand_deadline
                                                                                    : l->last_rx_ms + CM_LINK_PARTIAL_GAP_MS;
        if (cand && give_up - now < left)
            left = give_up - now;
        if (left < 0)
            left = 0;
        long n = l->t->read(l->t, l->rx + l->end, sizeof l->rx - l->end, (int)left);
        if (n < 0)
            return (int)n;
        now = cm_clock_ms();
        if (n == 0) {
            /* nothing more came (the kernel's queue is empty, so a slow reader is not mistaken for a
               stalled sender): give the partial frame up and resynchronise past its magic */
            if (cand && now >= give_up && !still_coming(l, now)) {
                l->stats.stalled++;
                l->stale_to = l->rx_off + l->end;
                l->start++;
                l->cand = 0;
                continue;
            }
            if (now >= deadline)
                return 0;
            continue;
        }
        crc_extend(l, l->end, l->end + (size_t)n);
        l->last_rx_ms = now;
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

void cm_link_hello_parts_reset(cm_link_hello_parts *p)
{
    memset(p->have, 0, sizeof p->have);
    p->count = p->len = p->held = 0;
    p->check = 0;
}

size_t cm_link_sync_pack(const cm_link_hello_parts *p, uint8_t *out)
{
    unsigned first = 0;
    uint32_t mask = 0xFFFFFFFFu;
    if (p->count) {
        while (first < p->count && (p->have[first / 8] >> (first % 8) & 1))
            first++;
        mask = 0;
        for (unsigned j = 0; j < 32 && first + j < p->count; j++)
            if (!(p->have[(first + j) / 8] >> ((first + j) % 8) & 1))
                mask |= 1u << j;
    }
    out[0] = CM_LINK_PROTO;
    out[1] = (uint8_t)first;
    cm_link_put32(out + 2, mask);
    return CM_LINK_SYNC_BYTES;
}

int cm_link_sync_unpack(const cm_link_frame *f, unsigned *first, uint32_t *mask)
{
    if (f->type != CM_LINK_SYNC || f->len < 1)
        return -1;
    if (f->len < CM_LINK_SYNC_BYTES)
        return 0; /* the plain SYNC: the whole HELLO */
    *first = f->payload[1];
    *mask = cm_link_get32(f->payload + 2);
    return 1;
}

size_t cm_link_hello_part_pack(const uint8_t *hello, size_t n, unsigned k, uint8_t *out)
{
    size_t count = (n + CM_LINK_HELLO_PIECE - 1) / CM_LINK_HELLO_PIECE;
    if (k >= count || count > 255)
        return 0;
    size_t at = (size_t)k * CM_LINK_HELLO_PIECE, m = n - at < CM_LINK_HELLO_PIECE ? n - at : CM_LINK_HELLO_PIECE;
    uint32_t c = cm_crc32(hello, n);
    out[0] = (uint8_t)k;
    out[1] = (uint8_t)count;
    out[2] = (uint8_t)c;
    out[3] = (uint8_t)(c >> 8);
    memcpy(out + 4, hello + at, m);
    return 4 + m;
}

int cm_link_hello_part_add(cm_link_hello_parts *p, const cm_link_frame *f, cm_link_hello *h)
{
    if (f->type != CM_LINK_HELLO_PART || f->len < 5 || f->len > 4 + CM_LINK_HELLO_PIECE)
        return 0;
    const uint8_t *b = f->payload;
    unsigned k = b[0], count = b[1], m = f->len - 4u;
    uint16_t check = (uint16_t)(b[2] | b[3] << 8);
    /* every piece but the last is whole; more pieces than a HELLO can have is a damaged frame */
    if (count == 0 || k >= count || (size_t)count * CM_LINK_HELLO_PIECE > CM_LINK_HELLO_MAX + CM_LINK_HELLO_PIECE - 1 ||
        (k + 1 < count && m != CM_LINK_HELLO_PIECE))
        return 0;
    if (p->count != count || p->check != check)
        cm_link_hello_parts_reset(p); /* another terminal, or one restarted with other limits */
    p->count = count;
    p->check = check;
    if (!(p->have[k / 8] >> (k % 8) & 1)) {
        memcpy(p->buf + (size_t)k * CM_LINK_HELLO_PIECE, b + 4, m);
        p->have[k / 8] |= (uint8_t)(1u << (k % 8));
        p->held++;
        if (k + 1 == count)
            p->len = k * CM_LINK_HELLO_PIECE + m;
    }
    if (p->held < count)
        return 0;
    cm_link_frame whole = {CM_LINK_HELLO, 0, (uint16_t)p->len, p->buf};
    if ((uint16_t)cm_crc32(p->buf, p->len) != check || !cm_link_hello_unpack(&whole, h)) {
        cm_link_hello_parts_reset(p); /* pieces of two HELLOs with the same check: start again */
        return 0;
    }
    return 1;
}

uint64_t cm_link_id_update(uint64_t id, const uint8_t *p, size_t n)
{
    /* bitwise, like cm_crc32_update: no table to place on the terminal, and the id is computed once
       per file (about 10 ms per MB on the boards) */
    id = ~id;
    for (size_t i = 0; i < n; i++) {
        id ^= p[i];
        for (int k = 0; k < 8; k++)
            id = (id >> 1) ^ (0xC96C5795D7870F42ull & (0ull - (id & 1u)));
    }
    return ~id;
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
    cm_link_put64(out + 13 + nl, o->id);
    return 13 + nl + 8;
}

bool cm_link_offer_unpack(const cm_link_frame *f, cm_link_offer *o)
{
    if (f->type != CM_LINK_OFFER || f->len < 13 + 8)
        return false;
    const uint8_t *b = f->payload;
    size_t nl = b[12];
    if (13 + nl + 8 != f->len || nl > CM_LINK_MAX_NAME)
        return false;
    o->size = cm_link_get32(b);
    o->crc = cm_link_get32(b + 4);
    o->chunk = cm_link_get32(b + 8);
    memcpy(o->name, b + 13, nl);
    o->name[nl] = '\0';
    o->id = cm_link_get64(b + 13 + nl);
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
