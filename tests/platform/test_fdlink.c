/*
 * test_fdlink.c - cm_fdlink over pipes, a socketpair and a regular file:
 * deadlines, EOF as a hang-up, no SIGPIPE on sockets, fds left open (or
 * closed with CM_FD_OWN), the write fd's flags put back.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "cm_transport_fd.h"
#include "tap.h"

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

static int fd_is_open(int fd)
{
    return fcntl(fd, F_GETFD) != -1 || errno != EBADF;
}

static void test_pipe_loop(void)
{
    int p[2];
    TAP_CHECK(pipe(p) == 0, "pipe");
    int fl_before = fcntl(p[1], F_GETFL);
    cm_fdlink l;
    TAP_CHECK(cm_fd_open(&l, p[0], p[1], "pipe") == 0 && !strcmp(l.t.name, "fd pipe"), "open over a pipe: %s",
              l.t.name);
    uint8_t buf[64];
    long n = l.t.write(&l.t, (const uint8_t *)"hello", 5, 100);
    long m = l.t.read(&l.t, buf, sizeof buf, 100);
    TAP_CHECK(n == 5 && m == 5 && !memcmp(buf, "hello", 5), "bytes through (write %ld, read %ld)", n, m);
    double t0 = now_ms();
    m = l.t.read(&l.t, buf, sizeof buf, 150);
    double dt = now_ms() - t0;
    TAP_CHECK(m == 0 && dt >= 100 && dt < 3000, "an empty pipe: read returns 0 at its 150 ms deadline (%.0f ms)", dt);
    static uint8_t big[1 << 20];
    t0 = now_ms();
    n = l.t.write(&l.t, big, sizeof big, 200);
    dt = now_ms() - t0;
    TAP_CHECK(n == 0 && dt >= 150 && dt < 3000, "1 MiB into a pipe nobody drains: 0 at the 200 ms deadline (%.0f ms)",
              dt);
    l.t.close(&l.t);
    l.t.close(&l.t);
    TAP_CHECK(fd_is_open(p[0]) && fd_is_open(p[1]), "close leaves fds it did not open");
    TAP_CHECK(fcntl(p[1], F_GETFL) == fl_before, "close puts the write fd's flags back (O_NONBLOCK off)");
    close(p[0]);
    close(p[1]);
}

static void test_eof_and_own(void)
{
    int p[2];
    TAP_CHECK(pipe(p) == 0, "pipe");
    cm_fdlink l;
    TAP_CHECK(cm_fd_open_flags(&l, p[0], -1, "pipe-r", CM_FD_OWN) == 0, "read-only link, owning its fd");
    (void)!write(p[1], "xyz", 3);
    close(p[1]); /* the writer went away, after writing */
    uint8_t buf[16];
    long n = l.t.read(&l.t, buf, sizeof buf, 500);
    TAP_CHECK(n == 3 && !memcmp(buf, "xyz", 3), "data before the EOF still arrives (%ld)", n);
    n = l.t.read(&l.t, buf, sizeof buf, 500);
    TAP_CHECK(n == CM_T_HANGUP && strstr(l.t.err, "EOF"), "then EOF is CM_T_HANGUP: %s", l.t.err);
    n = l.t.write(&l.t, buf, 1, 10);
    TAP_CHECK(n == CM_T_IO && strstr(l.t.err, "not open for writing"), "write on a read-only link: %s", l.t.err);
    l.t.close(&l.t);
    TAP_CHECK(!fd_is_open(p[0]), "CM_FD_OWN: close closes the fd");
    TAP_CHECK(cm_fd_open(&l, -1, -1, "none") == -1 && strstr(l.t.err, "neither"), "no fds refused: %s", l.t.err);
    TAP_CHECK(cm_fd_open(&l, -1, 987, "bad") == -1 && strstr(l.t.err, "write fd 987"), "a bad fd refused: %s",
              l.t.err);
}

static void test_socket_no_sigpipe(void)
{
    signal(SIGPIPE, SIG_DFL); /* a SIGPIPE would kill this test */
    int sv[2];
    TAP_CHECK(socketpair(AF_UNIX, SOCK_STREAM, 0, sv) == 0, "socketpair");
    cm_fdlink l;
    TAP_CHECK(cm_fd_open(&l, sv[0], sv[0], "sock") == 0 && l.wfd_is_socket, "open over a socket");
    close(sv[1]);
    uint8_t buf[8] = {0};
    long n = l.t.write(&l.t, buf, sizeof buf, 200);
    TAP_CHECK(n == CM_T_HANGUP, "write to a closed peer: CM_T_HANGUP, no SIGPIPE (%ld: %s)", n, l.t.err);
    n = l.t.read(&l.t, buf, sizeof buf, 200);
    TAP_CHECK(n == CM_T_HANGUP, "read from a closed peer: CM_T_HANGUP (%ld: %s)", n, l.t.err);
    l.t.close(&l.t);
    close(sv[0]);
}

static void test_regular_file(void)
{
    char path[] = "/tmp/cm_fdlink.XXXXXX";
    int fd = mkstemp(path);
    (void)!write(fd, "0123456789", 10);
    lseek(fd, 0, SEEK_SET);
    cm_fdlink l;
    TAP_CHECK(cm_fd_open_flags(&l, fd, -1, path, CM_FD_OWN) == 0, "open over a file");
    uint8_t buf[64];
    size_t got = 0;
    long n;
    while ((n = l.t.read(&l.t, buf + got, 4, 100)) > 0)
        got += (size_t)n;
    TAP_CHECK(got == 10 && !memcmp(buf, "0123456789", 10) && n == CM_T_HANGUP,
              "a file reads in full, then its end is CM_T_HANGUP (%zu bytes, last %ld)", got, n);
    l.t.close(&l.t);
    unlink(path);
}

int main(void)
{
    test_pipe_loop();
    test_eof_and_own();
    test_socket_no_sigpipe();
    test_regular_file();
    return tap_done();
}
