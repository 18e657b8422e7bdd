/* cm_transport_fd.c - a byte link over file descriptors, with poll() deadlines (see cm_transport_fd.h). */
#define _POSIX_C_SOURCE 200809L
#include "cm_transport_fd.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cm_clock.h"

/* What is left of a deadline for poll(): -1 (no limit) stays -1, a passed one is 0. */
static int ms_left(int timeout_ms, long long deadline)
{
    if (timeout_ms < 0)
        return -1;
    long long left = deadline - cm_clock_ms();
    return left <= 0 ? 0 : (int)left;
}

/* errnos that mean "the device or the peer is gone", not "something is wrong here" */
static int is_hangup_errno(int e)
{
    return e == EIO || e == EPIPE || e == ECONNRESET || e == ENXIO || e == ENODEV || e == ENOTCONN;
}

long cm_fd_read_within(int fd, uint8_t *buf, size_t n, int timeout_ms, int is_tty, int *err_no)
{
    *err_no = 0;
    int empty_reads = 0;
    if (n == 0)
        return 0;
    long long deadline = cm_clock_ms() + (timeout_ms > 0 ? timeout_ms : 0);
    for (;;) {
        struct pollfd p = {.fd = fd, .events = POLLIN, .revents = 0};
        int pr = poll(&p, 1, ms_left(timeout_ms, deadline));
        if (pr < 0) {
            if (errno == EINTR)
                continue; /* a signal is not the deadline: wait again for what is left */
            *err_no = errno;
            return CM_T_IO;
        }
        if (pr == 0)
            return 0;
        if (p.revents & POLLNVAL) {
            *err_no = EBADF;
            return CM_T_IO;
        }
        /* POLLIN, POLLHUP or POLLERR: read() says which (a pipe can hold data after POLLHUP) */
        ssize_t got = read(fd, buf, n);
        if (got > 0)
            return (long)got;
        if (got == 0) {
            /* EOF: the writer closed, the tty was hung up, or a file ended.  A live
             * tty can also say 0 when another reader took the bytes poll() saw */
            if (!is_tty || (p.revents & (POLLHUP | POLLERR)) || ++empty_reads >= 3)
                return CM_T_HANGUP;
            continue;
        }
        int e = errno;
        if (e == EINTR)
            continue;
        if (e == EAGAIN || e == EWOULDBLOCK) {
            if (p.revents & POLLHUP)
                return CM_T_HANGUP;
            continue; /* someone else took the bytes: keep waiting */
        }
        *err_no = e;
        return is_hangup_errno(e) ? CM_T_HANGUP : CM_T_IO;
    }
}

long cm_fd_write_within(int fd, const uint8_t *buf, size_t n, int timeout_ms, int use_send, int *err_no)
{
    *err_no = 0;
    long long deadline = cm_clock_ms() + (timeout_ms > 0 ? timeout_ms : 0);
    size_t done = 0;
    while (done < n) {
        ssize_t put = use_send ? send(fd, buf + done, n - done, MSG_NOSIGNAL) : write(fd, buf + done, n - done);
        if (put > 0) {
            done += (size_t)put;
            continue;
        }
        int e = put < 0 ? errno : EAGAIN;
        if (e == EINTR)
            continue;
        if (e != EAGAIN && e != EWOULDBLOCK) {
            *err_no = e;
            return is_hangup_errno(e) ? CM_T_HANGUP : CM_T_IO;
        }
        /* the kernel's buffer is full: wait for room, but not past the deadline */
        for (;;) {
            int left = ms_left(timeout_ms, deadline);
            if (left == 0)
                return 0;
            struct pollfd p = {.fd = fd, .events = POLLOUT, .revents = 0};
            int pr = poll(&p, 1, left);
            if (pr < 0 && errno == EINTR)
                continue;
            if (pr < 0) {
                *err_no = errno;
                return CM_T_IO;
            }
            if (pr == 0)
                return 0;
            if (p.revents & POLLNVAL) {
                *err_no = EBADF;
                return CM_T_IO;
            }
            break; /* POLLOUT, POLLHUP or POLLERR: the next write() tells */
        }
    }
    return (long)n;
}

/* ---- the cm_transport ---- */

static void fd_fail(cm_fdlink *l, const char *op, long r, int e)
{
    if (r == CM_T_HANGUP && e == 0)
        snprintf(l->t.err, sizeof l->t.err, "%s: %s: the other end closed (EOF)", l->t.name, op);
    else
        snprintf(l->t.err, sizeof l->t.err, "%s: %s: %s", l->t.name, op, strerror(e));
}

/* t is the first member (C11 6.7.2.1p15), so the back end's struct starts where t does;
 * the cast goes through void * because -Wcast-align cannot know that */
static cm_fdlink *fdlink_of(cm_transport *t)
{
    return (cm_fdlink *)(void *)t;
}

static long fd_read(cm_transport *t, uint8_t *buf, size_t n, int timeout_ms)
{
    cm_fdlink *l = fdlink_of(t);
    if (l->rfd < 0) {
        snprintf(t->err, sizeof t->err, "%s: read: not open for reading", t->name);
        return CM_T_IO;
    }
    int e;
    long r = cm_fd_read_within(l->rfd, buf, n, timeout_ms, 0, &e);
    if (r < 0)
        fd_fail(l, "read", r, e);
    return r;
}

static long fd_write(cm_transport *t, const uint8_t *buf, size_t n, int timeout_ms)
{
    cm_fdlink *l = fdlink_of(t);
    if (l->wfd < 0) {
        snprintf(t->err, sizeof t->err, "%s: write: not open for writing", t->name);
        return CM_T_IO;
    }
    int e;
    long r = cm_fd_write_within(l->wfd, buf, n, timeout_ms, l->wfd_is_socket, &e);
    if (r < 0)
        fd_fail(l, "write", r, e);
    return r;
}

static void fd_close(cm_transport *t)
{
    cm_fdlink *l = fdlink_of(t);
    if (l->wfd >= 0 && l->wfd_fl_saved >= 0)
        (void)fcntl(l->wfd, F_SETFL, l->wfd_fl_saved);
    if (l->flags & CM_FD_OWN) {
        if (l->rfd >= 0)
            close(l->rfd);
        if (l->wfd >= 0 && l->wfd != l->rfd)
            close(l->wfd);
    }
    l->rfd = -1;
    l->wfd = -1;
    l->wfd_fl_saved = -1;
}

int cm_fd_open_flags(cm_fdlink *l, int rfd, int wfd, const char *name, unsigned flags)
{
    memset(l, 0, sizeof *l);
    l->t.read = fd_read;
    l->t.write = fd_write;
    l->t.close = fd_close;
    snprintf(l->t.name, sizeof l->t.name, "fd %s", name ? name : "?");
    l->rfd = rfd;
    l->wfd = wfd;
    l->flags = flags;
    l->wfd_fl_saved = -1;
    if (rfd < 0 && wfd < 0) {
        snprintf(l->t.err, sizeof l->t.err, "%s: neither a read nor a write fd", l->t.name);
        return -1;
    }
    if (wfd >= 0) {
        struct stat st;
        if (fstat(wfd, &st) != 0) {
            snprintf(l->t.err, sizeof l->t.err, "%s: write fd %d: %s", l->t.name, wfd, strerror(errno));
            l->rfd = l->wfd = -1;
            return -1;
        }
        l->wfd_is_socket = S_ISSOCK(st.st_mode);
        /* a blocking write into a full pipe or tty would sleep past any deadline */
        int fl = fcntl(wfd, F_GETFL);
        if (fl < 0 || ((fl & O_NONBLOCK) == 0 && fcntl(wfd, F_SETFL, fl | O_NONBLOCK) != 0)) {
            snprintf(l->t.err, sizeof l->t.err, "%s: write fd %d: cannot make it non-blocking: %s", l->t.name, wfd,
                     strerror(errno));
            l->rfd = l->wfd = -1;
            return -1;
        }
        if ((fl & O_NONBLOCK) == 0)
            l->wfd_fl_saved = fl;
    }
    return 0;
}

int cm_fd_open(cm_fdlink *l, int rfd, int wfd, const char *name)
{
    return cm_fd_open_flags(l, rfd, wfd, name, 0);
}
