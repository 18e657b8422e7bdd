/* enc_workers.c - per-face work on forked worker processes (see enc_workers.h). */
#define _GNU_SOURCE /* mmap's MAP_ANONYMOUS; prctl's PR_SET_PDEATHSIG: a worker does not outlive its encoder */
#include "enc_workers.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

/* workers at most (cmz encode -j's own bound) */
#define ENC_MAX_JOBS 256

void *enc_shared_alloc(size_t size)
{
    void *p = mmap(NULL, size, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    return p == MAP_FAILED ? NULL : p;
}

void enc_shared_free(void *p, size_t size)
{
    if (p)
        munmap(p, size);
}

static void take_items(int n, atomic_int *next, void (*item)(void *ctx, int i, int self), void *ctx, int self,
                       int die_after)
{
    for (int taken = 1;; taken++) {
        int i = atomic_fetch_add(next, 1);
        if (i >= n)
            return;
        if (!self && taken == die_after)
            _exit(3); /* the tests' worker that dies holding an item */
        item(ctx, i, self);
    }
}

void enc_workers_run(int jobs, int n, atomic_int *next, void (*item)(void *ctx, int i, int self), void *ctx,
                     int die_after)
{
    pid_t pid[ENC_MAX_JOBS], self = getpid();
    int nkids = 0;
    fflush(NULL); /* nothing buffered is written twice */
    for (int k = 1; k < jobs && k < ENC_MAX_JOBS && k < n; k++) {
        pid_t p = fork();
        if (p == 0) {
            /* an encoder stopped (a vault's timeout kills it) takes its workers with it */
            prctl(PR_SET_PDEATHSIG, SIGKILL);
            if (getppid() != self)
                _exit(128 + SIGKILL);
            take_items(n, next, item, ctx, 0, die_after);
            _exit(0);
        }
        if (p > 0)
            pid[nkids++] = p;
    }
    take_items(n, next, item, ctx, 1, die_after);
    for (int k = 0; k < nkids; k++)
        while (waitpid(pid[k], NULL, 0) < 0 && errno == EINTR)
            ;
}
