/*
 * test_fault.c - the in-memory transport's semantics, and the fault
 * decorator: same seed -> same damage, rates near what was asked over 1e5
 * bytes, counters that add up, hang-up after N bytes, damage on reads.
 */
#include <stdint.h>
#include <string.h>

#include "fake/cm_transport_fault.h"
#include "fake/cm_transport_mem.h"
#include "tap.h"

static void test_mem(void)
{
    static const uint8_t in[10] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
    uint8_t out[8], buf[16];
    cm_memlink m;
    cm_mem_open(&m, in, sizeof in, out, sizeof out, CM_MEM_END_HANGUP);
    long n = m.t.read(&m.t, buf, 4, 100);
    TAP_CHECK(n == 4 && !memcmp(buf, in, 4), "mem: read takes what fits (%ld)", n);
    m.read_chunk = 3;
    n = m.t.read(&m.t, buf, sizeof buf, 100);
    TAP_CHECK(n == 3 && !memcmp(buf, in + 4, 3), "mem: read_chunk limits one read (%ld)", n);
    m.read_chunk = 0;
    n = m.t.read(&m.t, buf, sizeof buf, 100);
    TAP_CHECK(n == 3 && !memcmp(buf, in + 7, 3), "mem: the rest (%ld)", n);
    n = m.t.read(&m.t, buf, sizeof buf, 100);
    TAP_CHECK(n == CM_T_HANGUP && strstr(m.t.err, "end of input"), "mem: then CM_T_HANGUP (%s)", m.t.err);
    TAP_CHECK(m.t.write(&m.t, in, 5, 0) == 5 && m.t.write(&m.t, in + 5, 5, 0) == 5 && m.out_len == 8 &&
                  m.overflow == 2 && !memcmp(out, in, 8),
              "mem: writes append, the overflow is counted (len %zu, overflow %zu)", m.out_len, m.overflow);
    TAP_CHECK(m.reads == 4 && m.writes == 2, "mem: calls counted");
    m.t.close(&m.t);
    m.t.close(&m.t);
    TAP_CHECK(m.t.read(&m.t, buf, 1, 0) == CM_T_IO && m.t.write(&m.t, buf, 1, 0) == CM_T_IO, "mem: CM_T_IO after close");

    cm_mem_open(&m, in, 2, NULL, 0, CM_MEM_END_TIMEOUT);
    n = m.t.read(&m.t, buf, sizeof buf, 100);
    long z = m.t.read(&m.t, buf, sizeof buf, 100);
    TAP_CHECK(n == 2 && z == 0 && m.t.read(&m.t, buf, sizeof buf, 0) == 0, "mem: END_TIMEOUT keeps returning 0");
    TAP_CHECK(m.t.write(&m.t, in, 3, 0) == 3 && m.overflow == 3, "mem: no output buffer counts everything as overflow");
}

#define NBYTES 100000
static uint8_t payload[NBYTES];
static uint8_t sink[2 * NBYTES];

/* push payload through a fault decorator over a mem link, in uneven chunks */
static void run_faults(const cm_fault_config *cfg, cm_fault *f, cm_memlink *m)
{
    cm_mem_open(m, NULL, 0, sink, sizeof sink, CM_MEM_END_HANGUP);
    cm_fault_open(f, &m->t, cfg);
    size_t at = 0, step = 1;
    while (at < NBYTES) {
        size_t k = step < NBYTES - at ? step : NBYTES - at;
        f->t.write(&f->t, payload + at, k, 100);
        at += k;
        step = step * 7 % 1999 + 1;
    }
}

static void test_fault_rates(void)
{
    uint32_t x = 99;
    for (size_t i = 0; i < NBYTES; i++) {
        x = x * 1664525u + 1013904223u;
        payload[i] = (uint8_t)(x >> 24);
    }
    cm_fault_config cfg = {.drop = 0.01, .flip = 0.02, .insert = 0.005, .hangup_after = -1, .seed = 42};
    cm_fault f1, f2, f3;
    cm_memlink m;
    run_faults(&cfg, &f1, &m);
    const cm_fault_counts *c = &f1.wr.n;
    TAP_CHECK(c->bytes_in == NBYTES && m.out_len == c->bytes_out && c->bytes_out == NBYTES - c->dropped + c->inserted,
              "counts add up: in %llu, out %llu = in - dropped %llu + inserted %llu", c->bytes_in, c->bytes_out,
              c->dropped, c->inserted);
    /* binomial, n = 1e5: sd of the drop count is ~31, so +-30% is > 9 sd */
    TAP_CHECK(c->dropped > 700 && c->dropped < 1300, "drop rate ~1%% (%llu of 1e5)", c->dropped);
    TAP_CHECK(c->flipped > 1400 && c->flipped < 2600, "flip rate ~2%% of the bytes kept (%llu)", c->flipped);
    TAP_CHECK(c->inserted > 350 && c->inserted < 650, "insert rate ~0.5%% (%llu)", c->inserted);
    size_t len1 = m.out_len;
    static uint8_t first[2 * NBYTES];
    memcpy(first, sink, len1);
    run_faults(&cfg, &f2, &m);
    TAP_CHECK(!memcmp(&f1.wr.n, &f2.wr.n, sizeof f1.wr.n) && m.out_len == len1 && !memcmp(first, sink, len1),
              "the same seed gives the same counts and the same bytes");
    cfg.seed = 43;
    run_faults(&cfg, &f3, &m);
    TAP_CHECK(f3.wr.n.dropped != f1.wr.n.dropped || f3.wr.n.flipped != f1.wr.n.flipped || m.out_len != len1 ||
                  memcmp(first, sink, len1) != 0,
              "another seed gives other damage");

    /* flips only: every damaged byte differs in exactly one bit */
    cm_fault_config flips = {.flip = 0.05, .hangup_after = -1, .seed = 7};
    run_faults(&flips, &f1, &m);
    unsigned long long diff = 0, one_bit = 0;
    for (size_t i = 0; i < NBYTES; i++) {
        unsigned d = (unsigned)(payload[i] ^ sink[i]);
        if (d) {
            diff++;
            one_bit += (d & (d - 1)) == 0;
        }
    }
    TAP_CHECK(m.out_len == NBYTES && diff == f1.wr.n.flipped && one_bit == diff,
              "flips: %llu bytes differ, each by one bit, as counted (%llu)", diff, f1.wr.n.flipped);

    cm_fault_config clean = {.hangup_after = -1, .seed = 1};
    run_faults(&clean, &f1, &m);
    TAP_CHECK(m.out_len == NBYTES && !memcmp(sink, payload, NBYTES) && f1.wr.n.dropped + f1.wr.n.flipped +
                  f1.wr.n.inserted == 0,
              "no faults configured: the bytes pass untouched");
}

static void test_fault_hangup_and_reads(void)
{
    cm_memlink m;
    cm_fault f;
    cm_fault_config cfg = {.hangup_after = 1000, .seed = 3};
    cm_mem_open(&m, payload, 5000, sink, sizeof sink, CM_MEM_END_HANGUP);
    TAP_CHECK(cm_fault_open(&f, &m.t, &cfg) == 0 && strstr(f.t.name, "fault(mem)"), "open: %s", f.t.name);
    long a = f.t.write(&f.t, payload, 600, 100);
    long b = f.t.write(&f.t, payload + 600, 600, 100);
    TAP_CHECK(a == 600 && b == CM_T_HANGUP && m.out_len == 1000 && !memcmp(sink, payload, 1000),
              "hang-up after 1000 bytes: 600 ok, then CM_T_HANGUP with exactly 1000 out (%ld, %ld, %zu)", a, b,
              m.out_len);
    uint8_t buf[64];
    TAP_CHECK(f.t.read(&f.t, buf, sizeof buf, 10) == CM_T_HANGUP && f.t.write(&f.t, buf, 1, 10) == CM_T_HANGUP &&
                  strstr(f.t.err, "hung up by fault injection after 1000 bytes"),
              "and forever after: %s", f.t.err);
    f.t.close(&f.t);
    TAP_CHECK(m.closed, "close closes the wrapped transport");

    cm_fault_config zero = {.hangup_after = 0, .seed = 3};
    cm_mem_open(&m, NULL, 0, sink, sizeof sink, CM_MEM_END_HANGUP);
    cm_fault_open(&f, &m.t, &zero);
    TAP_CHECK(f.t.write(&f.t, payload, 1, 10) == CM_T_HANGUP && m.out_len == 0, "hangup_after 0: nothing goes");

    /* damage on reads: drops and inserts change the length, the counts say by how much */
    cm_fault_config rd = {.drop = 0.03, .insert = 0.03, .flip = 0.01, .hangup_after = -1, .on_read = 1, .seed = 11};
    cm_mem_open(&m, payload, NBYTES, NULL, 0, CM_MEM_END_HANGUP);
    m.read_chunk = 300;
    cm_fault_open(&f, &m.t, &rd);
    size_t total = 0;
    long n;
    size_t want = 1;
    int over = 0; /* a read returned more than asked */
    while ((n = f.t.read(&f.t, sink, want, 100)) > 0) {
        over |= n > (long)want;
        total += (size_t)n;
        want = want % 97 + 1;
    }
    TAP_CHECK(!over, "reads never return more than asked, carry or not");
    const cm_fault_counts *c = &f.rd.n;
    TAP_CHECK(n == CM_T_HANGUP && c->bytes_in == NBYTES && total == NBYTES - c->dropped + c->inserted &&
                  c->dropped > 2000 && c->inserted > 2000 && c->flipped > 500 && f.wr.n.bytes_in == 0,
              "reads damaged: %zu bytes out of 1e5 (dropped %llu, inserted %llu, flipped %llu), then the hang-up",
              total, c->dropped, c->inserted, c->flipped);

    cm_fault_config bad = {.drop = 1.5, .hangup_after = -1};
    TAP_CHECK(cm_fault_open(&f, &m.t, &bad) == -1 && strstr(f.t.err, "[0, 1]"), "a probability > 1 refused: %s",
              f.t.err);
    volatile double zero_d = 0.0;
    cm_fault_noise z;
    TAP_CHECK(cm_fault_noise_init(&z, zero_d / zero_d, 0, 0, 1) == -1, "a NaN probability refused");
    cm_fault_noise_init(&z, 0, 0, 0, 1);
    uint8_t out[1];
    size_t used = 9;
    TAP_CHECK(cm_fault_noise_apply(&z, payload, 10, &used, out, sizeof out) == 0 && used == 0,
              "apply with less than 2 bytes of room consumes nothing");
}

int main(void)
{
    test_mem();
    test_fault_rates();
    test_fault_hangup_and_reads();
    return tap_done();
}
