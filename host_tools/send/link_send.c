/* link_send.c - the workstation's end of a transfer (see link_send.h, docs/LINK.md). */
#define _POSIX_C_SOURCE 200809L
#include "link_send.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cm/cm_arith.h"

#define CHUNK_MIN 16u
#define EPOCH 16u        /* sends between chunk-size decisions */
#define RTO_MIN_MS 20
#define RTO_MAX_MS 5000
#define LINK_LOST_MS 4000 /* no frame at all for this long while we wait: the link is gone */

void link_send_defaults(link_send_opts *o)
{
    memset(o, 0, sizeof *o);
    o->connect_timeout_ms = 30000;
    o->wait_decoded = 1;
    o->decode_timeout_ms = 600000;
}

__attribute__((format(printf, 2, 3))) static void logf_(const link_send_opts *o, const char *fmt, ...)
{
    if (!o->log)
        return;
    char line[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    o->log(o->log_ctx, line);
}

/* CMZ_LINK_DEBUG=1: phase times on stderr (for tuning the timeouts on a real line) */
__attribute__((format(printf, 1, 2))) static void debugf(const char *fmt, ...)
{
    static int on = -1;
    if (on < 0)
        on = getenv("CMZ_LINK_DEBUG") != NULL;
    if (!on)
        return;
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "link-debug %lld ", (long long)(cm_link_now_ms() % 1000000));
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

__attribute__((format(printf, 3, 4))) static void fail_text(link_send_result *r, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->text, sizeof r->text, fmt, ap);
    va_end(ap);
    r->code = code;
}

/* time to push n bytes through a paced line, ms (0 if not paced) */
static int line_ms(const link_send_opts *o, uint64_t n)
{
    return o->baud ? (int)(n * 10u * 1000u / o->baud) + 1 : 0;
}

/* a hang-up: reopen if we can; 0 reopened, -1 not */
static int reopen(cm_link *l, const link_send_opts *o, link_send_result *r)
{
    if (o->hangup_keeps_transport) {
        struct timespec ts = {0, 200 * 1000000L};
        nanosleep(&ts, NULL);
        cm_link_init(l, l->t); /* drop what was half received */
        return 0;
    }
    if (!o->reopen) {
        fail_text(r, -1, "%s: the other end hung up", l->t->name);
        return -1;
    }
    int64_t until = cm_link_now_ms() + o->connect_timeout_ms;
    l->t->close(l->t);
    while (cm_link_now_ms() < until) {
        cm_transport *t = NULL;
        if (o->reopen(o->reopen_ctx, &t) == 0 && t) {
            cm_link_init(l, t);
            return 0;
        }
        struct timespec ts = {0, 200 * 1000000L};
        nanosleep(&ts, NULL);
    }
    fail_text(r, -1, "%s: could not reopen within %d s", l->t->name, o->connect_timeout_ms / 1000);
    return -1;
}

/* SYNC until HELLO; *rtt_ms: the round trip of the SYNC that was answered, *tries: SYNCs sent */
static int connect_rtt(cm_link *l, const link_send_opts *o, cm_link_hello *h, link_send_result *r, int *rtt_ms,
                       int *tries)
{
    int n_sync = 0;
    const uint64_t damaged0 = l->stats.bad_crc + l->stats.bad_header;
    int64_t until = cm_link_now_ms() + o->connect_timeout_ms;
    uint8_t p[1] = {CM_LINK_PROTO};
    /* short: on a noisy line most HELLOs (137 bytes) arrive damaged, and each try costs this */
    int wait = 25 + line_ms(o, 2 * (8 + 4 * CM_LIMIT_COUNT + CM_LINK_MAX_NAME + 24));
    while (cm_link_now_ms() < until) {
        int s = cm_link_send(l, CM_LINK_SYNC, -1, p, 1, 1000);
        n_sync++;
        if (s < 0) {
            if (s == CM_T_HANGUP && reopen(l, o, r) == 0)
                continue;
            if (s != CM_T_HANGUP)
                fail_text(r, -1, "%s: %s", l->t->name, l->t->err);
            return -1;
        }
        int64_t sent = cm_link_now_ms(), stop = sent + wait;
        for (;;) {
            int64_t left = stop - cm_link_now_ms();
            if (left <= 0)
                break;
            cm_link_frame f;
            int g = cm_link_recv(l, &f, (int)left);
            if (g < 0) {
                if (g == CM_T_HANGUP && reopen(l, o, r) == 0)
                    break;
                if (g != CM_T_HANGUP)
                    fail_text(r, -1, "%s: %s", l->t->name, l->t->err);
                return -1;
            }
            if (g == 0)
                break;
            if (f.type == CM_LINK_HELLO && cm_link_hello_unpack(&f, h)) {
                if (h->proto != CM_LINK_PROTO) {
                    fail_text(r, -1, "terminal '%s' speaks link protocol %u, this sender %u", h->name, h->proto,
                              CM_LINK_PROTO);
                    return -1;
                }
                if (rtt_ms)
                    *rtt_ms = (int)(cm_link_now_ms() - sent);
                /* "tries" that tell of the line: damaged frames, not SYNCs nobody heard yet */
                int damaged = (int)(l->stats.bad_crc + l->stats.bad_header - damaged0);
                if (tries)
                    *tries = 1 + damaged;
                r->connect_rtt_ms = (int)(cm_link_now_ms() - sent);
                r->connect_tries = 1 + damaged;
                return 0;
            }
        }
    }
    fail_text(r, -1, "no terminal answered on %s within %d s", l->t->name, o->connect_timeout_ms / 1000);
    return -1;
}

int link_send_connect(cm_link *l, const link_send_opts *o, cm_link_hello *h, link_send_result *r)
{
    return connect_rtt(l, o, h, r, NULL, NULL);
}

/* ---- the transfer ---- */

typedef struct window {
    uint32_t size, origin, chunk, base; /* base: first chunk not held contiguously (index on the grid) */
    uint32_t nchunks;
    uint64_t held;                      /* bit j: chunk base+j is held beyond the prefix */
    int64_t sent_at[CM_LINK_WINDOW];    /* 0: not in flight */
    uint64_t sent_no[CM_LINK_WINDOW];   /* order of the last send, to spot a hole the line ate */
    uint8_t sends[CM_LINK_WINDOW];
    uint64_t counter;
    /* round trip estimate (Jacobson/Karels, ms * 8) */
    int64_t srtt8, rttvar4;
    int rto;
    int min_rtt; /* the fastest round trip seen: control frames wait for this, not for a data queue */
    int64_t line_free_at; /* paced line: when what we wrote will have left the wire */
    /* chunk-size adaptation: chunks newly held, and frames the terminal reports damaged, since
       the last decision (timeouts do not count: a terminal busy in fsync is not a noisy line) */
    unsigned epoch_ok, epoch_lost;
    uint32_t damaged, damaged0;
    bool have_damaged;
} window;

static uint32_t chunk_len(const window *w, uint32_t k)
{
    uint32_t off = w->origin + k * w->chunk;
    return w->size - off < w->chunk ? w->size - off : w->chunk;
}

static void window_start(window *w, uint32_t size, uint32_t origin, uint32_t chunk)
{
    int rto = w->rto ? w->rto : 500, min_rtt = w->min_rtt;
    int64_t srtt8 = w->srtt8, rttvar4 = w->rttvar4;
    memset(w, 0, sizeof *w);
    w->size = size;
    w->origin = origin;
    w->chunk = chunk;
    w->nchunks = size > origin ? (size - origin + chunk - 1) / chunk : 0;
    w->rto = rto;
    w->srtt8 = srtt8;
    w->rttvar4 = rttvar4;
    w->min_rtt = min_rtt;
}

/* how long to wait for the answer to a control frame (OFFER, END) */
static int control_wait(const window *w, const link_send_opts *o)
{
    return 2 * (w->min_rtt > 0 ? w->min_rtt : 100) + 30 + line_ms(o, 160);
}

static void rtt_sample(window *w, int64_t ms, const link_send_opts *o)
{
    if (w->min_rtt == 0 || ms < w->min_rtt)
        w->min_rtt = ms > 0 ? (int)ms : 1;
    if (w->srtt8 == 0) {
        w->srtt8 = ms * 8;
        w->rttvar4 = ms * 2;
    } else {
        int64_t d = ms - w->srtt8 / 8;
        w->srtt8 += d;
        w->rttvar4 += (d < 0 ? -d : d) - w->rttvar4 / 4;
    }
    (void)o; /* the samples include the line time of what was queued ahead */
    int64_t rto = w->srtt8 / 8 + w->rttvar4;
    w->rto = (int)(rto < RTO_MIN_MS ? RTO_MIN_MS : rto > RTO_MAX_MS ? RTO_MAX_MS : rto);
}

/* an ACK: the terminal's contiguous prefix and the chunks it holds beyond it */
static void on_ack(window *w, uint32_t prefix, uint64_t held, const link_send_opts *o)
{
    if (prefix < w->origin + w->base * w->chunk)
        return; /* older than what we know */
    uint32_t nb = prefix >= w->size ? w->nchunks : (prefix - w->origin) / w->chunk;
    if (prefix < w->size && (prefix - w->origin) % w->chunk)
        return; /* not on our grid: an answer to an older offer */
    int64_t now = cm_link_now_ms();
    /* chunks now acknowledged: RTT samples from those sent once (Karn) */
    for (uint32_t k = w->base; k < nb && k - w->base < CM_LINK_WINDOW; k++) {
        uint32_t j = k - w->base;
        if (!(w->held >> j & 1) && w->sends[j])
            w->epoch_ok++;
        if (w->sent_at[j] && w->sends[j] == 1)
            rtt_sample(w, now - w->sent_at[j], o);
    }
    for (unsigned j = 0; j < CM_LINK_WINDOW; j++) {
        if (nb == w->base && (held >> j & 1) && !(w->held >> j & 1) && w->sends[j]) {
            w->epoch_ok++;
            if (w->sends[j] == 1 && w->sent_at[j])
                rtt_sample(w, now - w->sent_at[j], o);
        }
    }
    uint32_t shift = nb - w->base;
    if (shift >= CM_LINK_WINDOW) {
        memset(w->sent_at, 0, sizeof w->sent_at);
        memset(w->sent_no, 0, sizeof w->sent_no);
        memset(w->sends, 0, sizeof w->sends);
    } else if (shift) {
        memmove(w->sent_at, w->sent_at + shift, (CM_LINK_WINDOW - shift) * sizeof w->sent_at[0]);
        memmove(w->sent_no, w->sent_no + shift, (CM_LINK_WINDOW - shift) * sizeof w->sent_no[0]);
        memmove(w->sends, w->sends + shift, (CM_LINK_WINDOW - shift) * sizeof w->sends[0]);
        memset(w->sent_at + CM_LINK_WINDOW - shift, 0, shift * sizeof w->sent_at[0]);
        memset(w->sent_no + CM_LINK_WINDOW - shift, 0, shift * sizeof w->sent_no[0]);
        memset(w->sends + CM_LINK_WINDOW - shift, 0, shift * sizeof w->sends[0]);
    }
    w->base = nb;
    w->held = held;
    /* frames arrive in order: a chunk sent before one the terminal has, but missing, was lost */
    uint64_t newest = 0;
    for (unsigned j = 0; j < CM_LINK_WINDOW; j++)
        if ((held >> j & 1) && w->sent_no[j] > newest)
            newest = w->sent_no[j];
    for (unsigned j = 0; j < CM_LINK_WINDOW; j++)
        if (!(held >> j & 1) && w->sent_at[j] && w->sent_no[j] < newest)
            w->sent_at[j] = 0; /* send again now */
}

/* a frame during the data phase: 1 if the terminal refused the file (r filled), else 0 */
static int data_reply(window *w, const cm_link_frame *f, const link_send_opts *o, link_send_result *r,
                      const char *term_name, const char *name, uint32_t size, uint32_t chunk)
{
    if (f->type == CM_LINK_ACK && f->len == 16) {
        uint64_t held = (uint64_t)cm_link_get32(f->payload + 4) | (uint64_t)cm_link_get32(f->payload + 8) << 32;
        uint32_t dmg = cm_link_get32(f->payload + 12);
        if (!w->have_damaged) {
            w->have_damaged = true;
            w->damaged0 = dmg;
        }
        w->damaged = dmg;
        w->epoch_lost = w->damaged - w->damaged0;
        uint32_t before = w->base;
        on_ack(w, cm_link_get32(f->payload), held, o);
        if (w->base != before && o->progress) {
            uint32_t done = w->base >= w->nchunks ? size : w->origin + w->base * w->chunk;
            o->progress(o->progress_ctx, done, size, chunk);
        }
    } else if (f->type == CM_LINK_REFUSE) {
        int code = 0, st = 0;
        char text[CM_LINK_MAX_TEXT + 1];
        if (cm_link_text_unpack(f, 0, &st, &code, text, sizeof text)) {
            fail_text(r, code ? code : 1, "terminal '%s' refused %s: %s", term_name, name, text);
            return 1;
        }
    }
    return 0; /* anything else (an unasked HELLO, a REQUEST) does not concern this transfer */
}

static int send_chunk(cm_link *l, const uint8_t *data, window *w, uint32_t j)
{
    static uint8_t p[CM_LINK_MAX_PAYLOAD];
    uint32_t k = w->base + j, off = w->origin + k * w->chunk, n = chunk_len(w, k);
    cm_link_put32(p, off);
    memcpy(p + 4, data + off, n);
    return cm_link_send(l, CM_LINK_DATA, -1, p, n + 4, 2000 + n);
}

/* wait for a DONE of `stage` (resending END), 0 got it, 1 the terminal moved back (ACK), -1 link */
static int wait_done(cm_link *l, uint32_t size, uint32_t crc, int stage, int timeout_ms, int every_ms,
                     const link_send_opts *o, link_send_result *r, uint32_t *ack_prefix)
{
    uint8_t end[8];
    cm_link_put32(end, size);
    cm_link_put32(end + 4, crc);
    int64_t until = cm_link_now_ms() + timeout_ms, last_frame = cm_link_now_ms();
    /* END again after every_ms, then twice as long each time up to 0.5 s: a DONE that a noisy line
       damaged is asked for again soon, and a terminal busy decoding for seconds is not flooded */
    int interval = every_ms;
    while (cm_link_now_ms() < until) {
        int s = cm_link_send(l, CM_LINK_END, -1, end, sizeof end, 1000);
        if (s < 0)
            return -1;
        int64_t stop = cm_link_now_ms() + interval;
        if (stage == CM_LINK_STAGE_DECODED)
            interval = interval * 2 > 500 ? 500 : interval * 2;
        for (;;) {
            int64_t left = stop - cm_link_now_ms();
            if (left <= 0)
                break;
            cm_link_frame f;
            int g = cm_link_recv(l, &f, (int)left);
            if (g < 0)
                return -1;
            if (g == 0)
                break;
            last_frame = cm_link_now_ms();
            int st = 0, code = 0;
            char text[CM_LINK_MAX_TEXT + 1];
            if (f.type == CM_LINK_DONE && cm_link_text_unpack(&f, 1, &st, &code, text, sizeof text)) {
                if (st >= r->stage) {
                    r->stage = st;
                    r->code = code;
                    snprintf(r->text, sizeof r->text, "%s", text);
                }
                if (code != 0 || st >= stage)
                    return 0;
            } else if (f.type == CM_LINK_ACK && f.len == 16 && r->stage == 0) {
                *ack_prefix = cm_link_get32(f.payload);
                if (*ack_prefix < size)
                    return 1;
            } else if (f.type == CM_LINK_ABORT && cm_link_text_unpack(&f, 0, &st, &code, text, sizeof text)) {
                logf_(o, "terminal: %s", text);
                return 1; /* it lost the transfer (restarted without its state): offer again */
            }
        }
        if (stage == CM_LINK_STAGE_STORED && cm_link_now_ms() - last_frame > LINK_LOST_MS)
            return -1;
    }
    fail_text(r, -1, "no %s verdict from the terminal within %d s", stage == CM_LINK_STAGE_DECODED ? "decode" : "store",
              timeout_ms / 1000);
    return -2;
}

int link_send_file(cm_link *l, const uint8_t *data, uint32_t size, const char *name, const link_send_opts *o,
                   link_send_result *r)
{
    memset(r, 0, sizeof *r);
    r->resumed_from = UINT32_MAX;
    const uint32_t crc = cm_crc32(data, size);
    cm_link_hello h;
    window w;
    memset(&w, 0, sizeof w);
    uint32_t chunk = 0, chunk_max = 0;
    bool connected = false, fresh = false;
    for (;;) {
        /* ---- find the terminal (again) ---- */
        if (!connected) {
            fresh = true;
            int rtt = 0, tries = 1;
            if (o->hello && r->reconnects == 0 && chunk == 0) {
                h = *o->hello; /* the caller has just found it */
                rtt = o->hello_rtt_ms;
                tries = o->hello_tries > 0 ? o->hello_tries : 1;
            } else if (connect_rtt(l, o, &h, r, &rtt, &tries) != 0) {
                return -1;
            }
            debugf("connected rtt %d", rtt);
            if (w.min_rtt == 0 || rtt < w.min_rtt)
                w.min_rtt = rtt > 0 ? rtt : 1;
            if (w.srtt8 == 0) {
                /* the first estimate of the round trip: SYNC -> HELLO */
                w.srtt8 = 8 * (int64_t)(rtt > 0 ? rtt : 1);
                w.rttvar4 = 2 * (int64_t)(rtt > 0 ? rtt : 1);
                w.rto = 2 * rtt + 20 + line_ms(o, (uint64_t)CM_LINK_WINDOW * 64u);
            }
            connected = true;
            chunk_max = h.max_payload > 4 ? h.max_payload - 4u : CHUNK_MIN;
            if (o->chunk_max && o->chunk_max < chunk_max)
                chunk_max = o->chunk_max;
            /* the first chunk: what the line is (a serial line starts at 1 KiB), and how many
               damaged frames came before the first whole HELLO (137 bytes): a noisy line starts
               small */
            if (chunk == 0)
                chunk = o->chunk ? o->chunk : tries > 3 ? 32u : tries > 1 ? 128u : (o->baud ? 1024u : chunk_max);
            if (chunk > chunk_max)
                chunk = chunk_max;
            if (chunk < CHUNK_MIN)
                chunk = CHUNK_MIN;
        }
        /* ---- offer: where does the terminal want us to start? ---- */
        cm_link_offer of = {size, crc, chunk, {0}};
        snprintf(of.name, sizeof of.name, "%s", name);
        uint8_t op[16 + CM_LINK_MAX_NAME];
        size_t on = cm_link_offer_pack(&of, op);
        int accepted = 0;
        uint32_t origin = 0;
        int64_t until = cm_link_now_ms() + LINK_LOST_MS * 2;
        while (!accepted && cm_link_now_ms() < until) {
            int s = cm_link_send(l, CM_LINK_OFFER, -1, op, on, 1000);
            if (s < 0)
                break;
            int64_t stop = cm_link_now_ms() + control_wait(&w, o);
            for (;;) {
                int64_t left = stop - cm_link_now_ms();
                cm_link_frame f;
                int g = left > 0 ? cm_link_recv(l, &f, (int)left) : 0;
                if (g <= 0) {
                    if (g < 0)
                        until = 0;
                    break;
                }
                if (f.type == CM_LINK_ACCEPT && f.len == 12 && cm_link_get32(f.payload + 8) == crc) {
                    origin = cm_link_get32(f.payload);
                    uint32_t c = cm_link_get32(f.payload + 4);
                    if (origin <= size && c >= 1) {
                        chunk = c < chunk ? c : chunk;
                        accepted = 1;
                        break;
                    }
                } else if (f.type == CM_LINK_REFUSE) {
                    int code = 0, st = 0;
                    char text[CM_LINK_MAX_TEXT + 1];
                    if (cm_link_text_unpack(&f, 0, &st, &code, text, sizeof text)) {
                        fail_text(r, code ? code : 1, "terminal '%s' refused %s: %s", h.name, name, text);
                        return 1;
                    }
                }
            }
        }
        if (!accepted) {
            logf_(o, "link: no answer to the offer; looking for the terminal again");
            r->reconnects++;
            connected = false; /* a hang-up shows up, and is reopened, in the SYNC that follows */
            continue;
        }
        debugf("accepted at %u chunk %u rto %d min_rtt %d", origin, chunk, w.rto, w.min_rtt);
        if (r->resumed_from == UINT32_MAX)
            r->resumed_from = origin;
        if (fresh && origin > 0) {
            r->resume_offset = origin;
            r->resumes++;
            logf_(o, "link: the terminal holds %u of %u bytes: resuming there", origin, size);
        }
        fresh = false;
        window_start(&w, size, origin, chunk);
        if (o->progress)
            o->progress(o->progress_ctx, origin, size, chunk);
        /* ---- stream the chunks: selective repeat over the window ---- */
        int64_t last_frame = cm_link_now_ms();
        int lost = 0, rechunk = 0;
        unsigned last_judged = 0, last_lost = 0;
        while (w.base < w.nchunks) {
            int64_t now = cm_link_now_ms();
            uint32_t span = w.nchunks - w.base < CM_LINK_WINDOW ? w.nchunks - w.base : CM_LINK_WINDOW;
            int64_t next_due = now + 1000;
            /* When every chunk the window allows is in flight, nothing new can be sent until the
               window moves, and only a chunk the line ate holds it: on a noisy line that is most
               of the time.  So a stalled window repeats its chunks after one round trip instead
               of the full timeout (the line is idle anyway). */
            bool stalled = true;
            for (uint32_t j = 0; j < span; j++)
                if (!(w.held >> j & 1) && w.sends[j] == 0)
                    stalled = false;
            int64_t srtt = w.srtt8 / 8;
            int due_ms = stalled ? (int)(2 * srtt + 2 < w.rto ? 2 * srtt + 2 : w.rto) : w.rto;
            for (uint32_t j = 0; j < span; j++) {
                if (w.held >> j & 1)
                    continue;
                if (w.sent_at[j] && now - w.sent_at[j] < due_ms) {
                    if (w.sent_at[j] + due_ms < next_due)
                        next_due = w.sent_at[j] + due_ms;
                    continue;
                }
                /* A paced line (a real UART) carries baud/10 bytes a second whatever we write: more
                   than ~20 ms ahead only waits in the tty queue, where a timer cannot tell it from a
                   lost frame.  So keep the queue short, and time each chunk from when it will have
                   left the wire. */
                if (o->baud && w.line_free_at > cm_link_now_ms() + 20) {
                    if (w.line_free_at - 20 < next_due)
                        next_due = w.line_free_at - 20;
                    break;
                }
                int s = send_chunk(l, data, &w, j);
                if (s < 0) {
                    lost = s;
                    break;
                }
                if (o->baud) {
                    int64_t t = cm_link_now_ms();
                    w.line_free_at = (w.line_free_at > t ? w.line_free_at : t) + line_ms(o, chunk_len(&w, w.base + j) + 16u);
                }
                /* take the replies that are already in between sends: over USB the terminal's
                   ACK waits until our side reads, and it stops reading our DATA meanwhile */
                cm_link_frame f;
                int g;
                while ((g = cm_link_recv(l, &f, 0)) > 0) {
                    last_frame = cm_link_now_ms();
                    if (data_reply(&w, &f, o, r, h.name, name, size, chunk))
                        return 1;
                }
                if (g < 0) {
                    lost = g;
                    break;
                }
                w.sent_at[j] = o->baud && w.line_free_at > cm_link_now_ms() ? w.line_free_at : cm_link_now_ms();
                w.sent_no[j] = ++w.counter;
                if (w.sends[j] < 255)
                    w.sends[j]++;
                r->chunks_sent++;
                if (w.sends[j] > 1)
                    r->chunks_resent++;
                if (w.sent_at[j] + due_ms < next_due)
                    next_due = w.sent_at[j] + due_ms;
            }
            if (lost)
                break;
            /* one chunk size decision per EPOCH sends, or sooner when most of them are lost (a
               long frame on a noisy line may never arrive: waiting for EPOCH would stall) */
            if (w.epoch_ok + w.epoch_lost >= EPOCH || (w.epoch_lost >= 4 && w.epoch_lost > 2 * w.epoch_ok)) {
                unsigned lost_n = w.epoch_lost, judged = w.epoch_ok + w.epoch_lost;
                last_judged = judged;
                last_lost = lost_n;
                w.epoch_ok = w.epoch_lost = 0;
                w.damaged0 = w.damaged;
                if (lost_n * 2 > judged && chunk > CHUNK_MIN) {
                    chunk = chunk / 2 < CHUNK_MIN ? CHUNK_MIN : chunk / 2;
                    rechunk = 1;
                } else if (lost_n * 20 < judged && chunk < chunk_max) {
                    chunk = chunk * 2 > chunk_max ? chunk_max : chunk * 2;
                    rechunk = 1;
                }
                if (rechunk) {
                    r->chunk_changes++;
                    break;
                }
            }
            /* collect ACKs until the next send is due */
            int64_t wait = next_due - cm_link_now_ms();
            if (wait < 1)
                wait = 1;
            cm_link_frame f;
            int g = cm_link_recv(l, &f, (int)wait);
            if (g < 0) {
                lost = g;
                break;
            }
            if (g > 0) {
                last_frame = cm_link_now_ms();
                if (data_reply(&w, &f, o, r, h.name, name, size, chunk))
                    return 1;
            } else if (cm_link_now_ms() - last_frame > LINK_LOST_MS + 4 * w.rto) {
                lost = 1; /* silence: the terminal is gone (unplugged, restarting) */
                break;
            }
        }
        if (rechunk) {
            logf_(o, "link: chunk size now %u bytes (of the last %u frames judged, %u damaged)", chunk, last_judged,
                  last_lost);
            continue; /* offer again with the new chunk size: the terminal keeps its prefix */
        }
        if (lost) {
            r->reconnects++;
            logf_(o, "link: %s; resuming", lost == CM_T_HANGUP ? "hang-up" : "no answer");
            if (lost == CM_T_HANGUP && reopen(l, o, r) != 0)
                return -1;
            if (lost == CM_T_IO) {
                fail_text(r, -1, "%s: %s", l->t->name, l->t->err);
                return -1;
            }
            connected = false;
            continue;
        }
        debugf("data done rto %d srtt %lld", w.rto, (long long)(w.srtt8 / 8));
        /* ---- the end: stored, then decoded ---- */
        uint32_t ack_prefix = 0;
        int d = wait_done(l, size, crc, CM_LINK_STAGE_STORED, LINK_LOST_MS * 4, control_wait(&w, o) + 20, o, r,
                          &ack_prefix);
        if (d == 1 || d == -1) {
            r->reconnects++;
            connected = false;
            continue;
        }
        if (d < 0)
            return -1;
        if (r->code != 0)
            return 1;
        debugf("stored");
        if (!o->wait_decoded)
            return 0;
        if (r->stage >= CM_LINK_STAGE_DECODED) /* the stored DONE was lost, the decoded one came */
            return r->code == 0 ? 0 : 1;
        d = wait_done(l, size, crc, CM_LINK_STAGE_DECODED, o->decode_timeout_ms, control_wait(&w, o) + 20, o, r,
                      &ack_prefix);
        if (d != 0)
            return -1;
        return r->code == 0 && r->stage == CM_LINK_STAGE_DECODED ? 0 : 1;
    }
}
