/*
 * enc_workers.h - the encoder's per-face work spread over worker processes (`cmz encode -j N`).
 *
 * The encoder forks N - 1 workers that share everything it has built so far copy-on-write (the
 * loaded model, the decoded model with its megabytes of fixed arrays: a thread would need its own
 * copy of each) and take faces off a counter in shared memory, as the encoder itself does; each
 * answer goes back through memory the caller shared (enc_shared_alloc).  What a face's work may read
 * of other faces is the caller's to settle (choose_methods.c: in order afterwards).  A worker that
 * cannot start or dies leaves its unanswered faces to the caller, so the answer never depends on N.
 */
#ifndef ENC_WORKERS_H
#define ENC_WORKERS_H

#include <stdatomic.h>
#include <stddef.h>

/** Zeroed memory shared with the workers forked after it (NULL when it cannot be had). */
void *enc_shared_alloc(size_t size);
void enc_shared_free(void *p, size_t size);

/**
 * item(ctx, i, self) for every i in 0..n-1, each once, taken off *next (zero, in shared memory) by
 * this process (self = 1) and jobs - 1 forked workers (self = 0), which end when none is left; returns
 * when they have.  A worker's item writes its answer to shared memory and marks it complete last.
 * die_after (tests only): each worker dies on taking its die_after-th item (0: never).
 */
void enc_workers_run(int jobs, int n, atomic_int *next, void (*item)(void *ctx, int i, int self), void *ctx,
                     int die_after);

#endif /* ENC_WORKERS_H */
