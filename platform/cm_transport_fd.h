/*
 * cm_transport_fd.h - a cm_transport over a read fd and a write fd: files,
 * pipes, sockets, stdin/stdout.  Also the poll()-with-deadline reads and
 * writes that the serial back end shares (a tty is an fd too).
 *
 * Deadline semantics are those of cm_transport.h: read waits at most
 * timeout_ms for the first byte, write gives up when timeout_ms has passed.
 * A negative timeout_ms waits without limit (tools on stdin only; the
 * terminal always passes one).  EOF, POLLHUP without data, EPIPE and EIO are
 * CM_T_HANGUP; a regular file therefore "hangs up" at its end.
 *
 * Writing to a pipe whose reader has gone raises SIGPIPE: a program that
 * writes to pipes must ignore SIGPIPE (the write then reports CM_T_HANGUP).
 * Sockets are written with MSG_NOSIGNAL, so they need nothing.
 */
#ifndef CM_TRANSPORT_FD_H
#define CM_TRANSPORT_FD_H

#include <stddef.h>
#include <stdint.h>

#include "cm_transport.h"

/** cm_fd_open_flags: close() also closes the fds (the default leaves them to the caller). */
#define CM_FD_OWN 1u

typedef struct cm_fdlink {
    cm_transport t;
    int rfd;          /* -1: not readable */
    int wfd;          /* -1: not writable */
    unsigned flags;   /* CM_FD_OWN */
    int wfd_is_socket;
    int wfd_fl_saved; /* wfd's file status flags before open set O_NONBLOCK; -1 = untouched */
} cm_fdlink;

/**
 * Wrap rfd (for reading) and wfd (for writing); either may be -1, and they
 * may be the same fd (a socket).  wfd is made non-blocking, which is what lets
 * a write honour its deadline; close() puts its flags back.  The fds stay
 * open after close() (see cm_fd_open_flags).
 * @param name  for log lines, e.g. "stdio" or "pipe"; stored as "fd NAME"
 * @return 0, or -1 with l->t.err set (both fds -1, or fcntl failed)
 */
int cm_fd_open(cm_fdlink *l, int rfd, int wfd, const char *name);

/** cm_fd_open with flags: CM_FD_OWN makes close() close the fds too. */
int cm_fd_open_flags(cm_fdlink *l, int rfd, int wfd, const char *name, unsigned flags);

/**
 * Read 1..n bytes from fd, waiting at most timeout_ms (negative: no limit)
 * for the first one.  Retries EINTR with the time that is left.
 * @param is_tty  fd is a tty in VMIN=0 mode, where read() returns 0 for "no
 *                bytes" too: 0 is then a hang-up only with POLLHUP/POLLERR
 *                (which a hung-up tty always reports) or when it repeats
 * @param err_no  set to the errno behind a CM_T_IO or CM_T_HANGUP (0 for EOF/POLLHUP)
 * @return bytes read (> 0), 0 when the deadline passed, CM_T_HANGUP or CM_T_IO
 */
long cm_fd_read_within(int fd, uint8_t *buf, size_t n, int timeout_ms, int is_tty, int *err_no);

/**
 * Write all n bytes to a non-blocking fd within timeout_ms (negative: no limit).
 * @param use_send  write with send(MSG_NOSIGNAL) (fd is a socket)
 * @param err_no    as for cm_fd_read_within
 * @return n, 0 when the deadline passed first (some bytes may have gone), CM_T_HANGUP or CM_T_IO
 */
long cm_fd_write_within(int fd, const uint8_t *buf, size_t n, int timeout_ms, int use_send, int *err_no);

#endif /* CM_TRANSPORT_FD_H */
