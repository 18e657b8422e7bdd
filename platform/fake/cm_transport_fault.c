/* cm_transport_fault.c - seeded byte damage around any cm_transport (see cm_transport_fault.h). */
#define _POSIX_C_SOURCE 200809L
#include "cm_transport_fault.h"

#include <stdio.h>
#include <string.h>

#include "cm_clock.h"

/* splitmix64: any seed (0 too) gives a full-period stream, and it is a few lines */
static uint64_t next_u64(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* true with probability thr / 2^53; integer compare, so every machine decides alike */
static int chance(cm_fault_noise *z, uint64_t thr)
{
    return thr != 0 && (next_u64(&z->rng) >> 11) < thr;
}

static int to_threshold(double p, uint64_t *thr)
{
    if (!(p >= 0.0 && p <= 1.0)) /* also refuses NaN */
        return -1;
    *thr = (uint64_t)(p * 9007199254740992.0); /* 2^53 */
    return 0;
}

int cm_fault_noise_init(cm_fault_noise *z, double drop, double flip, double insert, uint64_t seed)
{
    memset(z, 0, sizeof *z);
    z->rng = seed;
    if (to_threshold(drop, &z->drop_thr) || to_threshold(flip, &z->flip_thr) || to_threshold(insert, &z->insert_thr))
        return -1;
    return 0;
}

size_t cm_fault_noise_apply(cm_fault_noise *z, const uint8_t *in, size_t n, size_t *used, uint8_t *out, size_t cap)
{
    size_t i = 0, o = 0;
    for (; i < n && cap - o >= 2; i++) {
        uint8_t c = in[i];
        z->n.bytes_in++;
        if (chance(z, z->insert_thr)) {
            out[o++] = (uint8_t)(next_u64(&z->rng) >> 56);
            z->n.inserted++;
        }
        if (chance(z, z->drop_thr)) {
            z->n.dropped++;
            continue;
        }
        if (chance(z, z->flip_thr)) {
            c ^= (uint8_t)(1u << (next_u64(&z->rng) >> 61));
            z->n.flipped++;
        }
        out[o++] = c;
    }
    z->n.bytes_out += o;
    *used = i;
    return o;
}

/* ---- the decorator ---- */

static int ms_left(int timeout_ms, long long deadline)
{
    if (timeout_ms < 0)
        return -1;
    long long left = deadline - cm_clock_ms();
    return left <= 0 ? 0 : (int)left;
}

static long hung_up(cm_fault *f)
{
    snprintf(f->t.err, sizeof f->t.err, "%s: hung up by fault injection after %lld bytes written", f->t.name,
             f->hangup_after);
    return CM_T_HANGUP;
}

static long pass_error(cm_fault *f, long r)
{
    if (r < 0)
        snprintf(f->t.err, sizeof f->t.err, "%s", f->inner->err);
    return r;
}

/* t is the first member (C11 6.7.2.1p15), so the back end's struct starts where t does;
 * the cast goes through void * because -Wcast-align cannot know that */
static cm_fault *fault_of(cm_transport *t)
{
    return (cm_fault *)(void *)t;
}

static long fault_write(cm_transport *t, const uint8_t *buf, size_t n, int timeout_ms)
{
    cm_fault *f = fault_of(t);
    if (f->hung)
        return hung_up(f);
    long long deadline = cm_clock_ms() + (timeout_ms > 0 ? timeout_ms : 0);
    size_t done = 0;
    while (done < n) {
        size_t take = n - done;
        int last = 0;
        if (f->hangup_after >= 0) {
            unsigned long long room = (unsigned long long)f->hangup_after - f->wr.n.bytes_in;
            if (room <= take) {
                take = (size_t)room;
                last = 1;
            }
        }
        while (take > 0) {
            uint8_t out[512];
            size_t used;
            size_t k = cm_fault_noise_apply(&f->wr, buf + done, take, &used, out, sizeof out);
            done += used;
            take -= used;
            if (k > 0) {
                long r = f->inner->write(f->inner, out, k, ms_left(timeout_ms, deadline));
                if (r <= 0)
                    return pass_error(f, r);
            }
        }
        if (last) {
            f->hung = 1;
            return hung_up(f);
        }
    }
    return (long)n;
}

static long fault_read(cm_transport *t, uint8_t *buf, size_t n, int timeout_ms)
{
    cm_fault *f = fault_of(t);
    if (f->hung)
        return hung_up(f);
    if (n == 0)
        return 0;
    if (!f->on_read)
        return pass_error(f, f->inner->read(f->inner, buf, n, timeout_ms));
    long long deadline = cm_clock_ms() + (timeout_ms > 0 ? timeout_ms : 0);
    for (;;) {
        if (f->carry_pos < f->carry_len) {
            size_t k = f->carry_len - f->carry_pos;
            if (k > n)
                k = n;
            memcpy(buf, f->carry + f->carry_pos, k);
            f->carry_pos += k;
            return (long)k;
        }
        uint8_t in[sizeof f->carry / 2];
        long r = f->inner->read(f->inner, in, n < sizeof in ? n : sizeof in, ms_left(timeout_ms, deadline));
        if (r <= 0)
            return pass_error(f, r);
        size_t used;
        f->carry_len = cm_fault_noise_apply(&f->rd, in, (size_t)r, &used, f->carry, sizeof f->carry);
        f->carry_pos = 0;
        /* everything dropped: wait for more while the deadline lasts */
        if (f->carry_len == 0 && ms_left(timeout_ms, deadline) == 0)
            return 0;
    }
}

static void fault_close(cm_transport *t)
{
    cm_fault *f = fault_of(t);
    if (f->inner)
        f->inner->close(f->inner);
}

int cm_fault_open(cm_fault *f, cm_transport *inner, const cm_fault_config *cfg)
{
    memset(f, 0, sizeof *f);
    f->t.read = fault_read;
    f->t.write = fault_write;
    f->t.close = fault_close;
    f->inner = inner;
    snprintf(f->t.name, sizeof f->t.name, "fault(%.80s)", inner->name);
    f->hangup_after = cfg->hangup_after;
    f->on_read = cfg->on_read;
    /* two streams from one seed: the write stream's state must not feed the read stream's */
    uint64_t s = cfg->seed;
    uint64_t seed_wr = next_u64(&s), seed_rd = next_u64(&s);
    if (cm_fault_noise_init(&f->wr, cfg->drop, cfg->flip, cfg->insert, seed_wr) ||
        cm_fault_noise_init(&f->rd, cfg->drop, cfg->flip, cfg->insert, seed_rd)) {
        snprintf(f->t.err, sizeof f->t.err, "%s: probabilities must be in [0, 1] (drop %g, flip %g, insert %g)",
                 f->t.name, cfg->drop, cfg->flip, cfg->insert);
        f->inner = NULL; /* a failed open must not close what the caller still owns */
        return -1;
    }
    return 0;
}
