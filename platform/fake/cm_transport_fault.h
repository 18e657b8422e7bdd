/*
 * cm_transport_fault.h - a bad cable in software: a cm_transport that wraps
 * another one and damages the bytes it writes (and, if asked, those it
 * reads): drops, single-bit flips, inserted garbage, and a hang-up after N
 * bytes.  Every decision comes from a PRNG seeded by the caller, so a
 * failing test replays exactly.  Nothing is allocated.
 *
 * The noise itself (cm_fault_noise) is usable alone: tests/tools/pty_relay
 * puts it between two ptys.
 */
#ifndef CM_TRANSPORT_FAULT_H
#define CM_TRANSPORT_FAULT_H

#include <stddef.h>
#include <stdint.h>

#include "cm_transport.h"

typedef struct cm_fault_counts {
    unsigned long long bytes_in;  /* bytes offered */
    unsigned long long bytes_out; /* bytes passed on (bytes_in - dropped + inserted) */
    unsigned long long dropped;   /* bytes that vanished */
    unsigned long long flipped;   /* bytes passed on with one bit inverted */
    unsigned long long inserted;  /* garbage bytes added */
} cm_fault_counts;

/** One direction's noise: a PRNG and per-byte probabilities (as 53-bit thresholds). */
typedef struct cm_fault_noise {
    uint64_t rng;
    uint64_t drop_thr, flip_thr, insert_thr;
    cm_fault_counts n;
} cm_fault_noise;

/**
 * Set up noise with probabilities per byte (each in [0, 1]) and a seed (any value).
 * @return 0, or -1 when a probability is out of range (or NaN)
 */
int cm_fault_noise_init(cm_fault_noise *z, double drop, double flip, double insert, uint64_t seed);

/**
 * Damage in[0..n) into out[0..cap): for each byte, maybe insert a random byte
 * before it, maybe drop it, maybe flip one of its bits.  Stops early when out
 * has less than 2 bytes of room left (cap >= 2 always makes progress).
 * @param used  input bytes consumed
 * @return bytes written to out
 */
size_t cm_fault_noise_apply(cm_fault_noise *z, const uint8_t *in, size_t n, size_t *used, uint8_t *out, size_t cap);

typedef struct cm_fault_config {
    double drop;            /* probability per byte written that it vanishes */
    double flip;            /* ... that one random bit of it is inverted */
    double insert;          /* ... that a random byte goes out before it */
    long long hangup_after; /* bytes written (offered) after which every call returns CM_T_HANGUP; < 0: never */
    int on_read;            /* also damage the bytes read (same probabilities, own PRNG stream) */
    uint64_t seed;
} cm_fault_config;

typedef struct cm_fault {
    cm_transport t;
    cm_transport *inner;
    cm_fault_noise wr; /* counters of what was written: f->wr.n */
    cm_fault_noise rd; /* counters of what was read: f->rd.n */
    long long hangup_after;
    int on_read;
    int hung;               /* 1 once the hang-up fired */
    size_t carry_len, carry_pos; /* read bytes damaged but not yet returned (inserts grow a chunk) */
    uint8_t carry[512];
} cm_fault;

/**
 * Wrap inner.  close() closes inner too.  The write and read streams use
 * separate PRNGs derived from cfg->seed, so what one direction gets does not
 * depend on how calls interleave.
 * @return 0, or -1 with f->t.err set (a probability out of range)
 */
int cm_fault_open(cm_fault *f, cm_transport *inner, const cm_fault_config *cfg);

#endif /* CM_TRANSPORT_FAULT_H */
