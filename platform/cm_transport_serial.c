/* cm_transport_serial.c - a tty in raw mode with poll() deadlines (see cm_transport_serial.h). */
#define _POSIX_C_SOURCE 200809L
/* CRTSCTS, TIOCOUTQ and the rates above 38400 are not POSIX */
#define _DEFAULT_SOURCE
#include "cm_transport_serial.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "cm_transport_fd.h"

_Static_assert(sizeof(struct termios) <= sizeof(((cm_serial *)0)->saved.bytes),
               "cm_serial.saved is too small for this libc's struct termios: enlarge it in cm_transport_serial.h");
_Static_assert(_Alignof(struct termios) <= _Alignof(union cm_serial_saved),
               "cm_serial.saved is not aligned enough for this libc's struct termios");

/* ---- rates ---- */

typedef struct baud_code {
    unsigned baud;
    speed_t code;
} baud_code;

/* Linux's standard list; other systems get the ones their <termios.h> has */
static const baud_code baud_table[] = {
    {50, B50}, {75, B75}, {110, B110}, {134, B134}, {150, B150}, {200, B200}, {300, B300}, {600, B600},
    {1200, B1200}, {1800, B1800}, {2400, B2400}, {4800, B4800}, {9600, B9600}, {19200, B19200},
    {38400, B38400},
#ifdef B57600
    {57600, B57600},
#endif
#ifdef B115200
    {115200, B115200},
#endif
#ifdef B230400
    {230400, B230400},
#endif
#ifdef B460800
    {460800, B460800},
#endif
#ifdef B500000
    {500000, B500000},
#endif
#ifdef B576000
    {576000, B576000},
#endif
#ifdef B921600
    {921600, B921600},
#endif
#ifdef B1000000
    {1000000, B1000000},
#endif
#ifdef B1152000
    {1152000, B1152000},
#endif
#ifdef B1500000
    {1500000, B1500000},
#endif
#ifdef B2000000
    {2000000, B2000000},
#endif
#ifdef B2500000
    {2500000, B2500000},
#endif
#ifdef B3000000
    {3000000, B3000000},
#endif
#ifdef B3500000
    {3500000, B3500000},
#endif
#ifdef B4000000
    {4000000, B4000000},
#endif
};

static int speed_of(unsigned baud, speed_t *code)
{
    for (size_t i = 0; i < sizeof baud_table / sizeof baud_table[0]; i++)
        if (baud_table[i].baud == baud) {
            *code = baud_table[i].code;
            return 1;
        }
    return 0;
}

static unsigned baud_of(speed_t code)
{
    for (size_t i = 0; i < sizeof baud_table / sizeof baud_table[0]; i++)
        if (baud_table[i].code == code)
            return baud_table[i].baud;
    return 0;
}

int cm_serial_baud_ok(unsigned baud)
{
    speed_t code;
    return speed_of(baud, &code);
}

/* "9600, 19200, ..." for messages: the nearest standard rates around a refused one */
static void nearest_rates(unsigned baud, unsigned *below, unsigned *above)
{
    size_t n = sizeof baud_table / sizeof baud_table[0];
    *below = 0;
    *above = 0;
    for (size_t i = 0; i < n; i++) {
        if (baud_table[i].baud < baud)
            *below = baud_table[i].baud;
        else if (*above == 0)
            *above = baud_table[i].baud;
    }
}

static void rate_refused(char *msg, size_t cap, unsigned baud)
{
    unsigned lo, hi;
    nearest_rates(baud, &lo, &hi);
    if (baud == 0)
        snprintf(msg, cap, "baud 0 is not a rate (B0 means 'hang up')");
    else if (hi == 0)
        snprintf(msg, cap, "baud %u is above the highest rate termios can set here (%u)", baud, lo);
    else if (lo == 0)
        snprintf(msg, cap, "baud %u is below the lowest rate termios can set (%u)", baud, hi);
    else
        snprintf(msg, cap, "baud %u is not a rate termios can set (nearest: %u, %u)", baud, lo, hi);
}

/* ---- spec ---- */

int cm_serial_parse(const char *spec, char *dev, size_t devcap, unsigned *baud)
{
    char what[96];
    if (devcap == 0)
        return -1;
    dev[0] = '\0';
    if (!spec || !*spec) {
        snprintf(dev, devcap, "serial spec is empty (expected DEV[:BAUD], e.g. /dev/ttyUSB0:115200)");
        return -1;
    }
    snprintf(what, sizeof what, "serial spec '%.60s'", spec);
    size_t len = strlen(spec);
    const char *colon = strrchr(spec, ':');
    struct stat st;
    size_t dev_len = len;
    unsigned rate = CM_SERIAL_DEFAULT_BAUD;
    /* a whole existing path wins: /dev/serial/by-path/ names contain ':' */
    if (colon && stat(spec, &st) != 0) {
        const char *d = colon + 1;
        dev_len = (size_t)(colon - spec);
        if (*d == '\0') {
            snprintf(dev, devcap, "%s: nothing after ':' (expected DEV[:BAUD])", what);
            return -1;
        }
        unsigned long v = 0;
        for (const char *c = d; *c; c++) {
            if (*c < '0' || *c > '9') {
                snprintf(dev, devcap, "%s: baud '%.20s' is not a number", what, d);
                return -1;
            }
            v = v * 10 + (unsigned long)(*c - '0');
            if (v > 100000000ul) {
                snprintf(dev, devcap, "%s: baud '%.20s' is far too large", what, d);
                return -1;
            }
        }
        rate = (unsigned)v;
        if (!cm_serial_baud_ok(rate)) {
            char why[96];
            rate_refused(why, sizeof why, rate);
            snprintf(dev, devcap, "%s: %s", what, why);
            return -1;
        }
    }
    if (dev_len == 0) {
        snprintf(dev, devcap, "%s: no device before ':'", what);
        return -1;
    }
    if (dev_len >= devcap) {
        snprintf(dev, devcap, "%s: device path longer than %zu bytes", what, devcap - 1);
        return -1;
    }
    memcpy(dev, spec, dev_len);
    dev[dev_len] = '\0';
    *baud = rate;
    return 0;
}

/* ---- the transport ---- */

/* s->t.err = "serial DEV: " + the rest; a long path shortens the message, never overruns it */
__attribute__((format(printf, 2, 3))) static void serial_err(cm_serial *s, const char *fmt, ...)
{
    int k = snprintf(s->t.err, sizeof s->t.err, "serial %s: ", s->dev);
    if (k < 0 || (size_t)k >= sizeof s->t.err)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(s->t.err + k, sizeof s->t.err - (size_t)k, fmt, ap);
    va_end(ap);
}

static long serial_fail(cm_serial *s, const char *op, long r, int e)
{
    if (r == CM_T_HANGUP)
        serial_err(s, "%s: hung up (%s)", op, e ? strerror(e) : "EOF");
    else
        serial_err(s, "%s: %s", op, strerror(e));
    return r;
}

/* t is the first member (C11 6.7.2.1p15), so the back end's struct starts where t does;
 * the cast goes through void * because -Wcast-align cannot know that */
static cm_serial *serial_of(cm_transport *t)
{
    return (cm_serial *)(void *)t;
}

static long serial_read(cm_transport *t, uint8_t *buf, size_t n, int timeout_ms)
{
    cm_serial *s = serial_of(t);
    if (s->fd < 0) {
        serial_err(s, "read: not open");
        return CM_T_IO;
    }
    int e;
    long r = cm_fd_read_within(s->fd, buf, n, timeout_ms, 1, &e);
    return r < 0 ? serial_fail(s, "read", r, e) : r;
}

static long serial_write(cm_transport *t, const uint8_t *buf, size_t n, int timeout_ms)
{
    cm_serial *s = serial_of(t);
    if (s->fd < 0) {
        serial_err(s, "write: not open");
        return CM_T_IO;
    }
    int e;
    long r = cm_fd_write_within(s->fd, buf, n, timeout_ms, 0, &e);
    return r < 0 ? serial_fail(s, "write", r, e) : r;
}

/*
 * Restoring the old settings changes the line speed at once, which would
 * garble bytes still in the UART's queue (write() returns when the kernel has
 * them, not when they are on the wire).  So wait for the queue to empty, but
 * only about twice the time it needs at this rate: a line held up by flow
 * control must not stop close().
 */
static void drain_bounded(cm_serial *s)
{
#ifdef TIOCOUTQ
    int queued = 0;
    if (ioctl(s->fd, TIOCOUTQ, &queued) != 0 || queued <= 0 || s->baud == 0)
        return;
    long long budget_ms = (long long)queued * 10 * 1000 * 2 / s->baud + 50;
    if (budget_ms > 2000)
        budget_ms = 2000;
    for (long long waited = 0; waited < budget_ms; waited += 10) {
        struct timespec ts = {0, 10 * 1000000L};
        nanosleep(&ts, NULL);
        if (ioctl(s->fd, TIOCOUTQ, &queued) != 0 || queued <= 0)
            return;
    }
#else
    (void)s;
#endif
}

static void serial_close(cm_transport *t)
{
    cm_serial *s = serial_of(t);
    if (s->fd < 0)
        return;
    if (s->have_saved) {
        struct termios saved;
        memcpy(&saved, s->saved.bytes, sizeof saved);
        drain_bounded(s);
        /* fails with EIO on a hung-up line, which has nothing left to restore */
        (void)tcsetattr(s->fd, TCSANOW, &saved);
    }
    close(s->fd);
    s->fd = -1;
    s->have_saved = 0;
}

static const char *file_kind(mode_t m)
{
    if (S_ISREG(m))
        return "a regular file";
    if (S_ISDIR(m))
        return "a directory";
    if (S_ISFIFO(m))
        return "a FIFO";
    if (S_ISSOCK(m))
        return "a socket";
    if (S_ISBLK(m))
        return "a block device";
    if (S_ISCHR(m))
        return "a character device that is not a terminal";
    return "not a device";
}

/*
 * Which field of the read-back settings differs from what was asked ("" if
 * none).  Only what this back end asks for is checked: a pty forces CS8 and
 * clears PARENB whatever it is told (8N1 is what we want anyway), and it
 * stores but does not enforce the speed, so a pty passes; qemu-user 7.2
 * reads back speed 0 above 460800, which fails here as it should.
 */
static const char *field_not_kept(const struct termios *want, const struct termios *got, unsigned flags)
{
    if (!(flags & CM_SERIAL_ANY_SPEED)) {
        if (cfgetospeed(got) != cfgetospeed(want))
            return "the output baud rate";
        /* input speed 0 means "same as output" */
        if (cfgetispeed(got) != cfgetispeed(want) && cfgetispeed(got) != 0)
            return "the input baud rate";
    }
    if ((got->c_cflag & CSIZE) != CS8)
        return "the character size (CS8)";
    if (got->c_cflag & PARENB)
        return "no parity (PARENB)";
    if (got->c_cflag & CSTOPB)
        return "one stop bit (CSTOPB)";
    if ((got->c_cflag & (CLOCAL | CREAD)) != (CLOCAL | CREAD))
        return "CLOCAL|CREAD";
#ifdef CRTSCTS
    if ((got->c_cflag & CRTSCTS) != (want->c_cflag & CRTSCTS))
        return "RTS/CTS flow control (CRTSCTS)";
#endif
    if (got->c_lflag & (ICANON | ECHO | ECHONL | ISIG | IEXTEN))
        return "raw input (ICANON/ECHO/ISIG/IEXTEN off)";
    if (got->c_iflag & (IXON | IXOFF | ICRNL | INLCR | IGNCR | ISTRIP | BRKINT | PARMRK | INPCK))
        return "untranslated input (IXON/IXOFF/ICRNL/INLCR/IGNCR/ISTRIP/BRKINT/PARMRK/INPCK off)";
    if (got->c_oflag & OPOST)
        return "unprocessed output (OPOST off)";
    if (got->c_cc[VMIN] != 0 || got->c_cc[VTIME] != 0)
        return "VMIN=0/VTIME=0";
    return "";
}

static int open_fail(cm_serial *s, const char *why, int e)
{
    if (e)
        serial_err(s, "%s: %s", why, strerror(e));
    else
        serial_err(s, "%s", why);
    serial_close(&s->t);
    return -1;
}

int cm_serial_open_flags(cm_serial *s, const char *dev, unsigned baud, unsigned flags)
{
    memset(s, 0, sizeof *s);
    s->t.read = serial_read;
    s->t.write = serial_write;
    s->t.close = serial_close;
    s->fd = -1;
    s->flags = flags;
    snprintf(s->dev, sizeof s->dev, "%s", dev ? dev : "");
    snprintf(s->t.name, sizeof s->t.name, "serial %.80s %u", s->dev, baud);
    if (!dev || !*dev) {
        snprintf(s->t.err, sizeof s->t.err, "serial: no device path");
        return -1;
    }
    if (strlen(dev) >= sizeof s->dev) {
        serial_err(s, "device path longer than %zu bytes", sizeof s->dev - 1);
        return -1;
    }
    speed_t code;
    if (!speed_of(baud, &code)) {
        char why[96];
        rate_refused(why, sizeof why, baud);
        serial_err(s, "%s", why);
        return -1;
    }
#ifndef CRTSCTS
    if (flags & CM_SERIAL_RTSCTS) {
        serial_err(s, "RTS/CTS flow control is not available on this system");
        return -1;
    }
#endif
    /* O_NONBLOCK: a modem line without carrier must not hang open(); deadlines come from poll() */
    s->fd = open(dev, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (s->fd < 0)
        return open_fail(s, "open", errno);
    if (!isatty(s->fd)) {
        struct stat st;
        char why[96];
        snprintf(why, sizeof why, "not a tty (%s)", fstat(s->fd, &st) == 0 ? file_kind(st.st_mode) : "?");
        return open_fail(s, why, 0);
    }
    struct termios old, want, got;
    if (tcgetattr(s->fd, &old) != 0)
        return open_fail(s, "tcgetattr", errno);
    memcpy(s->saved.bytes, &old, sizeof old);
    s->have_saved = 1;

    /* raw 8N1, as cfmakeraw() does, spelt out because cfmakeraw is not POSIX */
    want = old;
    want.c_iflag &= (tcflag_t) ~(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON | IXOFF | IXANY |
                                 INPCK);
    want.c_oflag &= (tcflag_t)~OPOST;
    want.c_lflag &= (tcflag_t) ~(ECHO | ECHONL | ECHOE | ECHOK | ICANON | ISIG | IEXTEN);
    want.c_cflag &= (tcflag_t) ~(CSIZE | PARENB | CSTOPB);
    want.c_cflag |= CS8 | CLOCAL | CREAD;
#ifdef CRTSCTS
    if (flags & CM_SERIAL_RTSCTS)
        want.c_cflag |= CRTSCTS;
    else
        want.c_cflag &= (tcflag_t)~CRTSCTS;
#endif
    want.c_cc[VMIN] = 0;
    want.c_cc[VTIME] = 0;
    if (cfsetispeed(&want, code) != 0 || cfsetospeed(&want, code) != 0)
        return open_fail(s, "cfsetspeed", errno);
    /*
     * tcsetattr succeeds when the driver took *any* of the settings; some
     * libcs re-read and report a partial change as EINVAL.  Either way the
     * read-back below is what decides.
     */
    if (tcsetattr(s->fd, TCSANOW, &want) != 0 && errno != EINVAL)
        return open_fail(s, "tcsetattr", errno);
    if (tcgetattr(s->fd, &got) != 0)
        return open_fail(s, "tcgetattr after setting", errno);
    const char *bad = field_not_kept(&want, &got, flags);
    if (*bad) {
        char why[160];
        if (strstr(bad, "baud"))
            snprintf(why, sizeof why, "the driver did not keep %s (asked %u, reads back %u)", bad, baud,
                     baud_of(strstr(bad, "input") ? cfgetispeed(&got) : cfgetospeed(&got)));
        else
            snprintf(why, sizeof why, "the driver did not keep %s", bad);
        return open_fail(s, why, 0);
    }
    /* bytes that arrived before we owned the line are from someone else's session */
    (void)tcflush(s->fd, TCIFLUSH);
    s->baud = baud;
    return 0;
}

int cm_serial_open(cm_serial *s, const char *dev, unsigned baud)
{
    return cm_serial_open_flags(s, dev, baud, 0);
}
