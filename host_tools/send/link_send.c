/* link_send.c - the workstation's end of a transfer (see link_send.h, docs/LINK.md). */
#define _POSIX_C_SOURCE 200809L
#include "link_send.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cm/cm_arith.h"
#include "cm/cm_crc32.h"
#include "cm/cm_error.h"

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

/* damaged frames and partial frames given up on this link so far */
static uint64_t damage(const cm_link *l)
{
    return l->stats.bad_crc + l->stats.bad_header + l->stats.stalled;
}

static bool stopped(const link_send_opts *o)
{
    return o->stop && *o->stop;
}

static int stop_result(link_send_result *r)
{
    fail_text(r, -1, "stopped by a signal");
    return LINK_SEND_STOPPED;
}

#define RECV_STOP (-100) /* recv_: o->stop was set */

/*
 * cm_link_recv in slices of at most 100 ms, looking at o->stop between them: a signal must end a send
 * within a second whatever it waits for (a transport retries its poll after EINTR until its deadline).
 * Returns like cm_link_recv (0 also early after a damaged frame), or RECV_STOP.
 */
static int recv_(cm_link *l, cm_link_frame *f, int64_t ms, const link_send_opts *o)
{
    int64_t until = cm_link_now_ms() + (ms > 0 ? ms : 0);
    const uint64_t dmg = damage(l);
    for (;;) {
        if (stopped(o))
            return RECV_STOP;
        int64_t left = until - cm_link_now_ms();
        int g = cm_link_recv(l, f, left > 100 ? 100 : left > 0 ? (int)left : 0);
        if (g != 0 || damage(l) != dmg || left <= 100)
            return g;
    }
}

/* tell the terminal we stop (it syncs its prefix: the next send resumes there); best effort */
static void send_abort(cm_link *l)
{
    uint8_t p[CM_LINK_MAX_TEXT + 2];
    size_t n = cm_link_text_pack(-1, CM_E_PROTOCOL, "the sender was stopped: the next send resumes", p);
    (void)cm_link_send(l, CM_LINK_ABORT, -1, p, n, 300);
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
        if (stopped(o)) {
            fail_text(r, -1, "stopped by a signal while reopening %s", l->t->name);
            return -1;
        }
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

/* our HELLO is this terminal's: the same protocol */
static int hello_ok(const cm_link_hello *h, link_send_result *r)
{
    if (h->proto == CM_LINK_PROTO)
        return 0;
    fail_text(r, -1, "terminal '%s' speaks link protocol %u, this sender %u", h->name, h->proto, CM_LINK_PROTO);
    return -1;
}

/*
 * SYNC until the HELLO is in; *rtt_ms: the round trip of the SYNC round that completed it, *tries:
 * 1 + damaged frames seen meanwhile.  The SYNCs ask for the HELLO in pieces (cm_link.h, "The HELLO in
 * pieces"): each piece is a small frame, the pieces held are kept, and the next SYNC asks only for
 * the others, so a line that damages most 130-byte frames still gives a HELLO within seconds.
 */
static int connect_rtt(cm_link *l, const link_send_opts *o, cm_link_hello *h, link_send_result *r, int *rtt_ms,
                       int *tries)
{
    static cm_link_hello_parts parts;
    cm_link_hello_parts_reset(&parts);
    r->hello_pieces = 0;
    const uint64_t damaged0 = damage(l);
    int64_t until = cm_link_now_ms() + o->connect_timeout_ms;
    while (cm_link_now_ms() < until) {
        if (stopped(o))
            return stop_result(r);
        uint8_t p[CM_LINK_SYNC_BYTES];
        size_t pn = cm_link_sync_pack(&parts, p);
        unsigned asked = parts.count ? parts.count - parts.held : 24;
        if (asked > 32)
            asked = 32;
        /* a line that damages frames: several SYNCs a round, each one answered with the pieces
           asked (the answers to a lost SYNC are lost with it) */
        int copies = damage(l) != damaged0 ? 3 : 1;
        int s = 1;
        for (int c = 0; c < copies && s >= 0; c++)
            s = cm_link_send(l, CM_LINK_SYNC, -1, p, pn, 1000);
        if (s < 0) {
            if (s == CM_T_HANGUP && reopen(l, o, r) == 0)
                continue;
            if (s != CM_T_HANGUP)
                fail_text(r, -1, "%s: %s", l->t->name, l->t->err);
            return -1;
        }
        /* the round: a round trip and the line time of the pieces asked */
        int wait = 25 + line_ms(o, (uint64_t)copies * (CM_LINK_SYNC_BYTES + 12u + asked * (CM_LINK_HELLO_PIECE + 16u)));
        int64_t sent = cm_link_now_ms(), stop = sent + wait;
        for (;;) {
            int64_t left = stop - cm_link_now_ms();
            if (left <= 0)
                break;
            cm_link_frame f;
            int g = recv_(l, &f, left, o);
            if (g == RECV_STOP)
                return stop_result(r);
            if (g < 0) {
                if (g == CM_T_HANGUP && reopen(l, o, r) == 0)
                    break;
                if (g != CM_T_HANGUP)
                    fail_text(r, -1, "%s: %s", l->t->name, l->t->err);
                return -1;
            }
            if (g == 0)
                continue; /* a damaged frame: the rest of the pieces may still come */
            bool whole = f.type == CM_LINK_HELLO && cm_link_hello_unpack(&f, h);
            if (f.type == CM_LINK_HELLO_PART)
                r->hello_pieces++;
            if (whole || (f.type == CM_LINK_HELLO_PART && cm_link_hello_part_add(&parts, &f, h))) {
                if (hello_ok(h, r) != 0)
                    return -1;
                /* "tries" that tell of the line: damaged frames, not SYNCs nobody heard yet */
                int damaged = (int)(damage(l) - damaged0);
                r->connect_rtt_ms = (int)(cm_link_now_ms() - sent);
                r->connect_tries = 1 + damaged;
                if (rtt_ms)
                    *rtt_ms = r->connect_rtt_ms;
                if (tries)
                    *tries = r->connect_tries;
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
    int64_t line_free_us; /* paced line: when what we wrote will have left the wire, in µs (a ms
                             rounded up per chunk would cap a fast line at 1000 chunks a second) */
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
    if (ms < 1)
        ms = 1; /* timed from when a paced chunk will have left the wire: its ACK can beat that guess */
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

/* a frame during the data phase: 1 if the terminal refused the file (r filled), 2 if its prefix went
   back (it restarted and lost what it had not synced: offer again to learn where it stands), else 0 */
static int data_reply(window *w, const cm_link_frame *f, const link_send_opts *o, link_send_result *r,
                      const char *term_name, const char *name, uint32_t size, uint32_t chunk)
{
    if (f->type == CM_LINK_ACK && f->len == 16) {
        /* a live terminal's prefix never shrinks (every ACK, also a late one, tells its current one) */
        if (cm_link_get32(f->payload) < w->origin)
            return 2;
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

/* wait for a DONE of `stage` (resending END), 0 got it, 1 the terminal moved back (ACK), 2 it lost the
   transfer (ABORT "no such transfer"), -1 link, -2 no verdict in time, LINK_SEND_STOPPED */
static int wait_done(cm_link *l, uint32_t size, uint32_t crc, uint64_t id, int stage, int timeout_ms, int every_ms,
                     bool noisy, const link_send_opts *o, link_send_result *r, uint32_t *ack_prefix)
{
    uint8_t end[CM_LINK_END_BYTES];
    cm_link_put32(end, size);
    cm_link_put32(end + 4, crc);
    cm_link_put64(end + 8, id);
    int64_t until = cm_link_now_ms() + timeout_ms;
    /* END again after every_ms, then twice as long each time up to 0.5 s: a DONE that a noisy line
       damaged is asked for again soon, and a terminal busy decoding for seconds is not flooded */
    int interval = every_ms;
    /* a noisy line loses most END/DONE pairs (DONE carries a line of text): the ENDs follow each other
       after their own line time there, and every one is answered */
    const int fast = 1 + line_ms(o, 4u * (CM_LINK_END_BYTES + 12u));
    while (cm_link_now_ms() < until) {
        if (stopped(o))
            return LINK_SEND_STOPPED;
        int s = 1;
        for (int k = 0; k < (noisy ? 4 : 1) && s >= 0; k++)
            s = cm_link_send(l, CM_LINK_END, -1, end, sizeof end, 1000);
        if (s < 0)
            return -1;
        int64_t stop = cm_link_now_ms() + (noisy ? fast : interval);
        if (stage == CM_LINK_STAGE_DECODED)
            interval = interval * 2 > 500 ? 500 : interval * 2;
        for (;;) {
            int64_t left = stop - cm_link_now_ms();
            if (left <= 0)
                break;
            cm_link_frame f;
            int g = recv_(l, &f, left, o);
            if (g == RECV_STOP)
                return LINK_SEND_STOPPED;
            if (g < 0)
                return -1;
            if (g == 0)
                break;
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
                snprintf(r->text, sizeof r->text, "%s", text);
                return 2; /* it lost the transfer (restarted without its state): offer again */
            }
        }
        /* no early way out on silence: offering again would find a terminal that has stored the
           file and start it over from byte 0; a hang-up, an ACK or an ABORT tells what happened */
    }
    fail_text(r, -1, "no %s verdict from the terminal within %d s", stage == CM_LINK_STAGE_DECODED ? "decode" : "store",
              timeout_ms / 1000);
    return -2;
}

/* the transfer is over without a verdict: ABORT for a stop (the terminal keeps its prefix) */
static int stop_file(cm_link *l, link_send_result *r, uint32_t held, const window *w)
{
    uint32_t in_window = w->nchunks && w->base >= w->nchunks ? w->size : w->origin + w->base * w->chunk;
    r->held = held > in_window ? held : in_window;
    send_abort(l);
    return stop_result(r);
}

int link_send_file(cm_link *l, const uint8_t *data, uint32_t size, const char *name, const link_send_opts *o,
                   link_send_result *r)
{
    memset(r, 0, sizeof *r);
    r->resumed_from = UINT32_MAX;
    const uint32_t crc = cm_crc32(data, size);
    const uint64_t id = cm_link_id_update(0, data, size); /* what makes a resume safe (cm_link.h) */
    if (o->baud)
        cm_link_set_rate(l, o->baud / 10u); /* partial frames from the terminal wait the line's time */
    cm_link_hello h;
    window w;
    memset(&w, 0, sizeof w);
    uint32_t chunk = 0, chunk_max = 0;
    bool connected = false, fresh = false, have_hello = false, direct = false, direct_failed = false;
    /* bounds (docs/LINK.md, "Giving up"): offers in a row that moved nothing, and fresh starts of the
       end phase; without them two ends that disagree (a terminal that accepts the whole file, then
       answers END with "no such transfer") feed each other forever */
    uint32_t held_best = 0, held_seen = 0; /* the terminal's contiguous prefix: best seen, at the last offer */
    unsigned fruitless = 0;
    bool noisy = false; /* frames were damaged: offers go out without waiting a round trip each */
    for (;;) {
        if (stopped(o))
            return stop_file(l, r, held_best, &w);
        /* ---- find the terminal (again) ---- */
        if (!connected && have_hello && !direct_failed) {
            /* it answered this run already: offer at once (the ACCEPT says where to resume); only
               when nobody answers is it looked for again with SYNC */
            connected = direct = fresh = true;
            r->direct_offers++;
        }
        if (!connected) {
            fresh = true;
            direct = false;
            int rtt = 0, tries = 1;
            if (o->hello && r->reconnects == 0 && chunk == 0) {
                h = *o->hello; /* the caller has just found it */
                rtt = o->hello_rtt_ms;
                tries = o->hello_tries > 0 ? o->hello_tries : 1;
            } else {
                int c = connect_rtt(l, o, &h, r, &rtt, &tries);
                if (c == LINK_SEND_STOPPED)
                    return stop_file(l, r, held_best, &w);
                if (c != 0)
                    return -1;
            }
            have_hello = true;
            if (tries > 1)
                noisy = true;
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
               damaged frames came before the HELLO was whole: a noisy line starts small */
            if (chunk == 0)
                chunk = o->chunk      ? o->chunk
                        : tries > 12  ? CHUNK_MIN /* ~10 % bad bytes: 32-byte frames mostly lost */
                        : tries > 3   ? 32u
                        : tries > 1   ? 128u
                                      : (o->baud ? 1024u : chunk_max);
            if (chunk > chunk_max)
                chunk = chunk_max;
            if (chunk < CHUNK_MIN)
                chunk = CHUNK_MIN;
        }
        if (held_best > held_seen || fruitless == 0) {
            held_seen = held_best;
            fruitless = 1;
        } else if (++fruitless > LINK_SEND_MAX_FRUITLESS) {
            fail_text(r, -1,
                      "no progress in %u offers to terminal '%s' (it holds %u of %u bytes): giving up; the line is "
                      "too bad or the terminal keeps losing the transfer",
                      LINK_SEND_MAX_FRUITLESS, h.name, (unsigned)held_best, (unsigned)size);
            return -1;
        }
        /* ---- offer: where does the terminal want us to start? ---- */
        cm_link_offer of = {size, crc, chunk, id, {0}};
        snprintf(of.name, sizeof of.name, "%s", name);
        uint8_t op[13 + CM_LINK_MAX_NAME + 8], op_short[13 + 8];
        size_t on = cm_link_offer_pack(&of, op);
        /* the same offer without the name (which only names the model in the terminal's log): on a
           line so noisy that the chunks are at their smallest, every other OFFER is this one, 14 + name
           bytes shorter and so several times as likely to arrive whole (the terminal's log may then
           show no name) */
        of.name[0] = '\0';
        size_t on_short = cm_link_offer_pack(&of, op_short);
        unsigned offers = 0;
        int accepted = 0;
        uint32_t origin = 0;
        int64_t until = cm_link_now_ms() + LINK_LOST_MS * 2;
        const uint64_t dmg0 = damage(l);
        while (!accepted && cm_link_now_ms() < until) {
            if (stopped(o))
                return stop_file(l, r, held_best, &w);
            int s = 1;
            for (int k = 0; k < (noisy ? 4 : 1) && s >= 0; k++) {
                bool shorter = chunk <= CHUNK_MIN && noisy && (offers++ & 1u);
                s = cm_link_send(l, CM_LINK_OFFER, -1, shorter ? op_short : op, shorter ? on_short : on, 1000);
            }
            if (s < 0)
                break;
            /* A noisy line loses most OFFER/ACCEPT pairs (two frames of ~45 and 32 bytes): waiting a
               round trip after each makes finding the resume point take longer than the data.  So
               there the OFFERs follow each other after their own line time: each is answered, the
               first ACCEPT that arrives whole counts (they all say the same). */
            if (damage(l) != dmg0)
                noisy = true;
            int64_t stop = cm_link_now_ms() + (noisy ? 1 + line_ms(o, 4u * (on + 12u)) : control_wait(&w, o));
            for (;;) {
                int64_t left = stop - cm_link_now_ms();
                cm_link_frame f;
                int g = left > 0 ? recv_(l, &f, left, o) : 0;
                if (g == RECV_STOP)
                    return stop_file(l, r, held_best, &w);
                if (g < 0) {
                    until = 0;
                    break;
                }
                if (g == 0) {
                    if (left > 0 && cm_link_now_ms() < stop)
                        continue; /* a damaged frame: its sibling may follow */
                    break;
                }
                if (f.type == CM_LINK_ACCEPT && f.len == CM_LINK_ACCEPT_BYTES && cm_link_get32(f.payload + 8) == crc &&
                    cm_link_get64(f.payload + 12) == id) {
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
            r->reconnects++;
            connected = false; /* a hang-up shows up, and is reopened, in the SYNC that follows */
            if (direct)
                direct_failed = true; /* look for it with SYNC until an offer is accepted again */
            logf_(o, "link: no answer to the offer; looking for the terminal again");
            continue;
        }
        direct_failed = false;
        if (origin > held_best)
            held_best = origin;
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
        int64_t last_frame = cm_link_now_ms(), last_move = last_frame;
        uint32_t moved_base = 0;
        uint64_t moved_held = 0;
        int lost = 0, rechunk = 0;
        unsigned last_judged = 0, last_lost = 0;
        int64_t dbg_at = 0;
        bool noisy_now = noisy;
        while (w.base < w.nchunks) {
            if (stopped(o))
                return stop_file(l, r, held_best, &w);
            int64_t now = cm_link_now_ms();
            if (now - dbg_at > 1000) {
                dbg_at = now;
                debugf("data base %u/%u held %016llx sent %llu rto %d srtt %lld dmg %llu in %llu out %llu", w.base, w.nchunks,
                       (unsigned long long)w.held, (unsigned long long)r->chunks_sent, w.rto, (long long)(w.srtt8 / 8),
                       (unsigned long long)damage(l), (unsigned long long)l->stats.frames_in,
                       (unsigned long long)l->stats.frames_out);
            }
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
            /* On a line that damages most frames the ACKs are lost too: the round trip measured from
               them grows with the ACK loss, not with the line.  There a stalled window repeats its
               holes after the fastest round trip seen (the line is idle otherwise, and a paced line
               still sends no faster than its rate) */
            if (stalled && noisy_now && w.min_rtt + 1 < due_ms)
                due_ms = w.min_rtt + 1;
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
                if (o->baud && w.line_free_us / 1000 > cm_link_now_ms() + 20) {
                    if (w.line_free_us / 1000 - 20 < next_due)
                        next_due = w.line_free_us / 1000 - 20;
                    break;
                }
                int s = send_chunk(l, data, &w, j);
                if (s < 0) {
                    lost = s;
                    break;
                }
                if (o->baud) {
                    int64_t t = cm_link_now_ms() * 1000;
                    w.line_free_us = (w.line_free_us > t ? w.line_free_us : t) +
                                     (int64_t)(chunk_len(&w, w.base + j) + 16u) * 10 * 1000000 / o->baud;
                }
                /* take the replies that are already in between sends: over USB the terminal's
                   ACK waits until our side reads, and it stops reading our DATA meanwhile */
                cm_link_frame f;
                int g;
                while ((g = cm_link_recv(l, &f, 0)) > 0) {
                    last_frame = cm_link_now_ms();
                    int d = data_reply(&w, &f, o, r, h.name, name, size, chunk);
                    if (d == 1)
                        return 1;
                    if (d == 2) {
                        lost = 3;
                        break;
                    }
                }
                if (lost)
                    break;
                if (g < 0) {
                    lost = g;
                    break;
                }
                w.sent_at[j] = o->baud && w.line_free_us / 1000 > cm_link_now_ms() ? w.line_free_us / 1000 : cm_link_now_ms();
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
                noisy_now = lost_n * 4 > judged; /* more than a quarter of the frames damaged */
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
            int g = recv_(l, &f, wait, o);
            if (g == RECV_STOP)
                return stop_file(l, r, held_best, &w);
            if (g < 0) {
                lost = g;
                break;
            }
            now = cm_link_now_ms();
            if (g > 0) {
                last_frame = now;
                int d = data_reply(&w, &f, o, r, h.name, name, size, chunk);
                if (d == 1)
                    return 1;
                if (d == 2) {
                    lost = 3;
                    break;
                }
            } else if (now - last_frame > LINK_LOST_MS + 4 * w.rto) {
                lost = 1; /* silence: the terminal is gone (unplugged, restarting) */
                break;
            }
            uint32_t held_now = w.base >= w.nchunks ? size : w.origin + w.base * w.chunk;
            if (held_now > held_best)
                held_best = held_now;
            if (w.base != moved_base || w.held != moved_held) {
                moved_base = w.base;
                moved_held = w.held;
                last_move = now;
            } else if (now - last_move > 2 * LINK_LOST_MS + 20 * w.rto + line_ms(o, 4u * (chunk + 16u))) {
                /* frames come, but none moves the window (ACKs of another grid, a terminal that
                   lost the transfer): offer again, which tells where the terminal stands */
                lost = 2;
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
            logf_(o, "link: %s; resuming", lost == CM_T_HANGUP ? "hang-up"
                                           : lost == 2         ? "no progress"
                                           : lost == 3         ? "the terminal went back (restarted)"
                                                               : "no answer");
            if (lost == CM_T_HANGUP && reopen(l, o, r) != 0)
                return stopped(o) ? stop_result(r) : -1;
            if (lost == CM_T_IO) {
                fail_text(r, -1, "%s: %s", l->t->name, l->t->err);
                return -1;
            }
            connected = false;
            continue;
        }
        if (size > held_best)
            held_best = size;
        debugf("data done rto %d srtt %lld", w.rto, (long long)(w.srtt8 / 8));
        /* ---- the end: stored, then decoded ---- */
        uint32_t ack_prefix = 0;
        int d = wait_done(l, size, crc, id, CM_LINK_STAGE_STORED, LINK_LOST_MS * 4, control_wait(&w, o) + 20,
                          noisy || noisy_now, o, r, &ack_prefix);
        if (d == LINK_SEND_STOPPED)
            return stop_file(l, r, held_best, &w);
        if (d == 2 && ++r->lost_transfers > LINK_SEND_MAX_LOST) {
            char why[sizeof r->text];
            snprintf(why, sizeof why, "%s", r->text);
            fail_text(r, -1,
                      "terminal '%s' lost the transfer %u times after it held all %u bytes (it answers END with "
                      "\"%.160s\"): giving up",
                      h.name, r->lost_transfers, (unsigned)size, why);
            return -1;
        }
        if (d == 2)
            logf_(o, "link: the terminal lost the transfer (%u of %u times): offering it again", r->lost_transfers,
                  LINK_SEND_MAX_LOST);
        if (d == 1 || d == 2 || d == -1 || d == -2) {
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
        d = wait_done(l, size, crc, id, CM_LINK_STAGE_DECODED, o->decode_timeout_ms, control_wait(&w, o) + 20,
                      noisy || noisy_now, o, r, &ack_prefix);
        if (d == LINK_SEND_STOPPED)
            return stop_file(l, r, held_best, &w); /* stored already: the ABORT is ignored, nothing to resume */
        if (d != 0)
            return -1;
        return r->code == 0 && r->stage == CM_LINK_STAGE_DECODED ? 0 : 1;
    }
}
