/*
 * link_harness.h - what the link's C tests (test_link.c, test_link_recovery.c) share: TAP lines
 * ending in one "N passed, N failed" (tests/tools/sum_suites.sh adds them up), a child's exit
 * code, a stored file compared with what was sent, and the sender's options for a test (a loaded
 * CI machine under qemu is slow; TEST_LINK_VERBOSE=1 logs the sender's decisions to stderr).
 * Static functions in a header: each test is one translation unit.
 */
#ifndef CM_LINK_HARNESS_H
#define CM_LINK_HARNESS_H

#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cm_link.h"
#include "send/link_send.h"

static int n_test, n_fail;

__attribute__((format(printf, 2, 3))) static void tap(int ok, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    printf("%sok %d - ", ok ? "" : "not ", ++n_test);
    vprintf(fmt, ap);
    printf("\n");
    va_end(ap);
    fflush(stdout);
    if (!ok)
        n_fail++;
}

/* the child's exit code, 100 + the signal that ended it, -1 if it cannot be waited for */
static int wait_child(int pid)
{
    int status = 0;
    if (waitpid(pid, &status, 0) != pid)
        return -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 100 + WTERMSIG(status);
}

static int file_equals(const char *path, const uint8_t *data, size_t n)
{
    static uint8_t buf[1 << 20];
    int fd = open(path, O_RDONLY);
    if (fd < 0)
        return 0;
    ssize_t got = read(fd, buf, sizeof buf);
    close(fd);
    return got == (ssize_t)n && memcmp(buf, data, n) == 0;
}

static void log_stderr(void *ctx, const char *line)
{
    (void)ctx;
    fprintf(stderr, "# %lld %s\n", (long long)cm_link_now_ms() % 100000, line);
}

static void test_send_opts(link_send_opts *o)
{
    link_send_defaults(o);
    o->connect_timeout_ms = 15000; /* a loaded CI machine under qemu is slow */
    if (getenv("TEST_LINK_VERBOSE"))
        o->log = log_stderr;
}

/* the .cmz in a decode fuzz seed (one chunking byte, then the file): NULL after a message if `path`
   is not one */
static const uint8_t *read_seed(const char *prog, const char *path, uint32_t *size)
{
    static uint8_t seed[1 << 20];
    int fd = open(path, O_RDONLY);
    ssize_t n = fd >= 0 ? read(fd, seed, sizeof seed) : -1;
    if (fd >= 0)
        close(fd);
    if (n < 65 || seed[1] != 0x89 || seed[2] != 'C') {
        fprintf(stderr, "%s: %s is not a decode seed (chunking byte + .cmz)\n", prog, path);
        return NULL;
    }
    *size = (uint32_t)(n - 1);
    return seed + 1;
}

#endif /* CM_LINK_HARNESS_H */
