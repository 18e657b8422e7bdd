/*
 * test_serial.c - cm_serial on real pty pairs: the slave end has the kernel's
 * tty line discipline, so raw mode, settings read-back, restore on close,
 * deadlines and hang-up behave as on a UART (the speed is stored, not
 * enforced; see hw-testing NOTES section 3).  Plus cm_serial_parse.
 * Timing bounds are generous: a loaded machine or qemu-user must not fail them.
 */
#define _POSIX_C_SOURCE 200809L
#define _XOPEN_SOURCE 700 /* posix_openpt */
#define _DEFAULT_SOURCE   /* setitimer, CRTSCTS, B4000000 */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "cm_transport_serial.h"
#include "tap.h"

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

typedef struct pty_pair {
    int master;
    int watch; /* a second slave fd: the test's view of the tty's settings */
    char path[64];
} pty_pair;

static int pty_open(pty_pair *p)
{
    p->master = posix_openpt(O_RDWR | O_NOCTTY);
    if (p->master < 0 || grantpt(p->master) != 0 || unlockpt(p->master) != 0)
        return -1;
    snprintf(p->path, sizeof p->path, "%s", ptsname(p->master));
    p->watch = open(p->path, O_RDWR | O_NOCTTY);
    return p->watch < 0 ? -1 : 0;
}

static void pty_close(pty_pair *p)
{
    if (p->master >= 0)
        close(p->master);
    if (p->watch >= 0)
        close(p->watch);
    p->master = p->watch = -1;
}

/* read exactly n bytes from an fd, giving up after ms */
static size_t read_fd_all(int fd, uint8_t *buf, size_t n, int ms)
{
    size_t got = 0;
    double end = now_ms() + ms;
    while (got < n && now_ms() < end) {
        struct pollfd p = {fd, POLLIN, 0};
        if (poll(&p, 1, 50) <= 0)
            continue;
        ssize_t k = read(fd, buf + got, n - got);
        if (k <= 0)
            break;
        got += (size_t)k;
    }
    return got;
}

/* read exactly n bytes through a transport, giving up after ms */
static size_t read_t_all(cm_transport *t, uint8_t *buf, size_t n, int ms)
{
    size_t got = 0;
    double end = now_ms() + ms;
    while (got < n && now_ms() < end) {
        long k = t->read(t, buf + got, n - got, 100);
        if (k < 0)
            break;
        got += (size_t)k;
    }
    return got;
}

static int same_settings(const struct termios *a, const struct termios *b)
{
    return a->c_iflag == b->c_iflag && a->c_oflag == b->c_oflag && a->c_cflag == b->c_cflag &&
           a->c_lflag == b->c_lflag && memcmp(a->c_cc, b->c_cc, sizeof a->c_cc) == 0 &&
           cfgetispeed(a) == cfgetispeed(b) && cfgetospeed(a) == cfgetospeed(b);
}

/* Does this environment's termios store the rate at all?  qemu-user 7.2 translates only up to 460800. */
static int env_stores_speed(int fd, speed_t code)
{
    struct termios t, saved;
    tcgetattr(fd, &saved);
    t = saved;
    cfsetispeed(&t, code);
    cfsetospeed(&t, code);
    tcsetattr(fd, TCSANOW, &t);
    tcgetattr(fd, &t);
    int ok = cfgetospeed(&t) == code;
    tcsetattr(fd, TCSANOW, &saved);
    return ok;
}

static void test_parse(void)
{
    char dev[160];
    unsigned baud = 1;
    TAP_CHECK(cm_serial_parse("/dev/ttyUSB0", dev, sizeof dev, &baud) == 0 && !strcmp(dev, "/dev/ttyUSB0") &&
                  baud == 115200,
              "parse: DEV alone gets 115200");
    TAP_CHECK(cm_serial_parse("/dev/ttyS0:9600", dev, sizeof dev, &baud) == 0 && !strcmp(dev, "/dev/ttyS0") &&
                  baud == 9600,
              "parse: DEV:9600");
    TAP_CHECK(cm_serial_parse("/dev/ttyAMA0:4000000", dev, sizeof dev, &baud) == 0 && baud == 4000000,
              "parse: DEV:4000000 (the top of Linux's list)");

    /* a by-path style name with ':' in it, that exists */
    char dir[] = "/tmp/cm_serial_parse.XXXXXX";
    TAP_CHECK(mkdtemp(dir) != NULL, "mkdtemp %s", dir);
    char odd[128], spec[160];
    snprintf(odd, sizeof odd, "%s/pci-0000:00:14.0-usb-0:2:1.0-port0", dir);
    int fd = open(odd, O_CREAT | O_WRONLY, 0600);
    close(fd);
    TAP_CHECK(cm_serial_parse(odd, dev, sizeof dev, &baud) == 0 && !strcmp(dev, odd) && baud == 115200,
              "parse: an existing path with ':' is all path");
    snprintf(spec, sizeof spec, "%s:57600", odd);
    TAP_CHECK(cm_serial_parse(spec, dev, sizeof dev, &baud) == 0 && !strcmp(dev, odd) && baud == 57600,
              "parse: an existing path with ':' plus :57600");
    unlink(odd);
    rmdir(dir);

    static const struct {
        const char *spec, *msg;
    } bad[] = {
        {"", "empty"},
        {":9600", "no device"},
        {"/dev/ttyS0:", "nothing after ':'"},
        {"/dev/ttyS0:0", "baud 0 is not a rate"},
        {"/dev/ttyS0:12345", "not a rate termios can set (nearest: 9600, 19200)"},
        {"/dev/ttyS0:96OO", "baud '96OO' is not a number"},
        {"/dev/ttyS0:+9600", "is not a number"},
        {"/dev/ttyS0: 9600", "is not a number"},
        {"/dev/ttyS0:9600x", "is not a number"},
        {"/dev/ttyS0:-1", "is not a number"},
        {"/dev/ttyS0:99999999999999999999", "far too large"},
        {"/dev/ttyS0:5000000", "above the highest rate"},
        {"/dev/ttyS0:25", "below the lowest rate"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        int r = cm_serial_parse(bad[i].spec, dev, sizeof dev, &baud);
        TAP_CHECK(r == -1 && strstr(dev, bad[i].msg) != NULL, "parse refuses '%s': %s", bad[i].spec, dev);
    }
    char small[8];
    TAP_CHECK(cm_serial_parse("/dev/ttyUSB0:9600", small, sizeof small, &baud) == -1,
              "parse refuses a path longer than the buffer");
    TAP_CHECK(cm_serial_parse(NULL, dev, sizeof dev, &baud) == -1, "parse refuses NULL");
}

static void test_settings_and_restore(void)
{
    static const struct {
        unsigned baud;
        speed_t code;
    } rates[] = {{9600, B9600}, {115200, B115200}, {921600, B921600}, {4000000, B4000000}};
    pty_pair p;
    TAP_CHECK(pty_open(&p) == 0, "pty pair %s", p.path);
    /* a cooked starting state, as a fresh getty line would have */
    struct termios t;
    tcgetattr(p.watch, &t);
    t.c_lflag |= ICANON | ECHO | ISIG;
    t.c_iflag |= ICRNL | IXON;
    t.c_oflag |= OPOST;
    cfsetispeed(&t, B38400);
    cfsetospeed(&t, B38400);
    tcsetattr(p.watch, TCSANOW, &t);
    struct termios before;
    tcgetattr(p.watch, &before);

    for (size_t i = 0; i < sizeof rates / sizeof rates[0]; i++) {
        if (!env_stores_speed(p.watch, rates[i].code)) {
            /* the read-back is what notices: the open must fail, naming the field */
            cm_serial s;
            int r = cm_serial_open(&s, p.path, rates[i].baud);
            TAP_CHECK(r == -1 && strstr(s.t.err, "did not keep the output baud rate"),
                      "%u not stored here: open refuses, naming the field: %s", rates[i].baud, s.t.err);
            r = cm_serial_open_flags(&s, p.path, rates[i].baud, CM_SERIAL_ANY_SPEED);
            TAP_CHECK(r == 0, "%u with CM_SERIAL_ANY_SPEED opens anyway: %s", rates[i].baud, r ? s.t.err : "ok");
            s.t.close(&s.t);
            char what[64];
            snprintf(what, sizeof what, "settings at %u", rates[i].baud);
            tap_skip(what, "this environment's termios does not store the rate (qemu-user 7.2 translates up to 460800)");
            continue;
        }
        cm_serial s;
        int r = cm_serial_open(&s, p.path, rates[i].baud);
        TAP_CHECK(r == 0, "open %s at %u: %s", p.path, rates[i].baud, r ? s.t.err : "ok");
        if (r != 0)
            continue;
        struct termios got;
        tcgetattr(p.watch, &got);
        TAP_CHECK(cfgetospeed(&got) == rates[i].code && cfgetispeed(&got) == rates[i].code,
                  "%u: the baud rate is stored", rates[i].baud);
        TAP_CHECK((got.c_cflag & CSIZE) == CS8 && !(got.c_cflag & (PARENB | CSTOPB | CRTSCTS)) &&
                      (got.c_cflag & (CLOCAL | CREAD)) == (CLOCAL | CREAD),
                  "%u: 8N1, CLOCAL|CREAD, no RTS/CTS", rates[i].baud);
        TAP_CHECK(!(got.c_lflag & (ICANON | ECHO | ECHONL | ISIG | IEXTEN)) &&
                      !(got.c_iflag & (ICRNL | INLCR | IGNCR | IXON | IXOFF | ISTRIP)) && !(got.c_oflag & OPOST),
                  "%u: raw (no echo, no line editing, no translation, no XON/XOFF)", rates[i].baud);
        TAP_CHECK(got.c_cc[VMIN] == 0 && got.c_cc[VTIME] == 0, "%u: VMIN=0 VTIME=0", rates[i].baud);
        char want_name[96];
        snprintf(want_name, sizeof want_name, "serial %s %u", p.path, rates[i].baud);
        TAP_CHECK(!strcmp(s.t.name, want_name) && s.baud == rates[i].baud, "%u: name '%s'", rates[i].baud,
                  s.t.name);
        s.t.close(&s.t);
        struct termios after;
        tcgetattr(p.watch, &after);
        TAP_CHECK(same_settings(&before, &after), "%u: close restores the settings found at open", rates[i].baud);
        s.t.close(&s.t); /* twice is allowed */
    }

    cm_serial s;
    int r = cm_serial_open_flags(&s, p.path, 115200, CM_SERIAL_RTSCTS);
    if (r == 0) {
        tcgetattr(p.watch, &t);
        TAP_CHECK(t.c_cflag & CRTSCTS, "RTS/CTS when asked (the pty keeps CRTSCTS)");
        s.t.close(&s.t);
    } else
        TAP_CHECK(strstr(s.t.err, "CRTSCTS") != NULL, "RTS/CTS refused with a message naming it: %s", s.t.err);
    pty_close(&p);
}

static volatile sig_atomic_t alarms;
static void on_alarm(int sig)
{
    (void)sig;
    alarms++;
}

static void test_deadlines(void)
{
    pty_pair p;
    TAP_CHECK(pty_open(&p) == 0, "pty pair %s", p.path);
    /* bytes from before the open belong to someone else's session */
    (void)!write(p.master, "stale", 5);
    usleep(50000);
    cm_serial s;
    int r = cm_serial_open(&s, p.path, 115200);
    TAP_CHECK(r == 0, "open: %s", r ? s.t.err : "ok");
    uint8_t buf[64];
    double t0 = now_ms();
    long n = s.t.read(&s.t, buf, sizeof buf, 200);
    double dt = now_ms() - t0;
    TAP_CHECK(n == 0, "stale input was flushed at open, read with 200 ms returns 0 (got %ld)", n);
    TAP_CHECK(dt >= 150 && dt < 3000, "the 200 ms read deadline took %.0f ms", dt);
    t0 = now_ms();
    n = s.t.read(&s.t, buf, sizeof buf, 0);
    dt = now_ms() - t0;
    TAP_CHECK(n == 0 && dt < 500, "a 0 ms read returns 0 at once (%.1f ms)", dt);

    /* signals do not cut the deadline short */
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_alarm; /* no SA_RESTART: poll() sees EINTR */
    sigemptyset(&sa.sa_mask);
    sigaction(SIGALRM, &sa, NULL);
    struct itimerval it = {{0, 30000}, {0, 30000}};
    setitimer(ITIMER_REAL, &it, NULL);
    t0 = now_ms();
    n = s.t.read(&s.t, buf, sizeof buf, 300);
    dt = now_ms() - t0;
    struct itimerval off = {{0, 0}, {0, 0}};
    setitimer(ITIMER_REAL, &off, NULL);
    TAP_CHECK(n == 0 && dt >= 250 && dt < 5000 && alarms > 0,
              "a 300 ms read interrupted by %d signals still waits (%.0f ms, got %ld)", (int)alarms, dt, n);

    /* a write that cannot finish (nobody reads the master) stops at its deadline */
    static uint8_t big[1 << 18];
    t0 = now_ms();
    n = s.t.write(&s.t, big, sizeof big, 300);
    dt = now_ms() - t0;
    TAP_CHECK(n == 0 && dt >= 250 && dt < 5000, "a 256 KiB write nobody reads returns 0 at its 300 ms deadline (%.0f ms)",
              dt);
    s.t.close(&s.t);
    pty_close(&p);
}

static void test_data_both_ways(void)
{
    pty_pair p;
    TAP_CHECK(pty_open(&p) == 0, "pty pair %s", p.path);
    cm_serial s;
    int r = cm_serial_open(&s, p.path, 460800);
    TAP_CHECK(r == 0, "open: %s", r ? s.t.err : "ok");
    uint8_t all[256], got[8192];
    for (int i = 0; i < 256; i++)
        all[i] = (uint8_t)i;
    /* every byte value, including ^C ^Q ^S CR NL DEL, passes untouched both ways */
    long n = s.t.write(&s.t, all, sizeof all, 1000);
    size_t k = read_fd_all(p.master, got, sizeof all, 2000);
    TAP_CHECK(n == 256 && k == 256 && !memcmp(got, all, 256), "256 byte values out (write %ld, master read %zu)", n, k);
    uint8_t in[6000];
    uint32_t x = 12345;
    for (size_t i = 0; i < sizeof in; i++) {
        x = x * 1103515245u + 12345u;
        in[i] = (uint8_t)(x >> 24);
    }
    memcpy(in, all, 256);
    size_t put = 0;
    while (put < sizeof in) { /* the master is blocking: chunks the line discipline can take */
        ssize_t w = write(p.master, in + put, sizeof in - put < 1024 ? sizeof in - put : 1024);
        if (w <= 0)
            break;
        put += (size_t)w;
        k = read_t_all(&s.t, got + put - (size_t)w, (size_t)w, 2000);
        if (k != (size_t)w)
            break;
    }
    TAP_CHECK(put == sizeof in && !memcmp(got, in, sizeof in), "6000 bytes in, all 256 values, intact (%zu)", put);
    s.t.close(&s.t);
    pty_close(&p);
}

static void test_hangup(void)
{
    pty_pair p;
    TAP_CHECK(pty_open(&p) == 0, "pty pair %s", p.path);
    cm_serial s;
    int r = cm_serial_open(&s, p.path, 115200);
    TAP_CHECK(r == 0, "open: %s", r ? s.t.err : "ok");
    close(p.master); /* the cable is pulled */
    p.master = -1;
    uint8_t buf[16];
    double t0 = now_ms();
    long n = s.t.read(&s.t, buf, sizeof buf, 3000);
    double dt = now_ms() - t0;
    TAP_CHECK(n == CM_T_HANGUP && dt < 2000, "read after the other end closed: CM_T_HANGUP in %.0f ms (%ld: %s)", dt, n,
              s.t.err);
    TAP_CHECK(strstr(s.t.err, "hung up") && strstr(s.t.err, p.path), "the message names the device: %s", s.t.err);
    n = s.t.write(&s.t, buf, sizeof buf, 1000);
    TAP_CHECK(n == CM_T_HANGUP, "write after the hang-up: CM_T_HANGUP (%ld: %s)", n, s.t.err);
    s.t.close(&s.t);
    s.t.close(&s.t);
    n = s.t.read(&s.t, buf, sizeof buf, 10);
    TAP_CHECK(n == CM_T_IO, "read after close: CM_T_IO (%s)", s.t.err);
    pty_close(&p);
}

static void test_refusals(void)
{
    cm_serial s;
    int r = cm_serial_open(&s, "/dev/null", 115200);
    TAP_CHECK(r == -1 && strstr(s.t.err, "serial /dev/null: not a tty (a character device that is not a terminal)"),
              "/dev/null refused: %s", s.t.err);
    char path[] = "/tmp/cm_serial_file.XXXXXX";
    int fd = mkstemp(path);
    close(fd);
    r = cm_serial_open(&s, path, 115200);
    TAP_CHECK(r == -1 && strstr(s.t.err, "not a tty (a regular file)") && strstr(s.t.err, path),
              "a regular file refused: %s", s.t.err);
    unlink(path);
    r = cm_serial_open(&s, "/nonexistent/ttyUSB9", 115200);
    TAP_CHECK(r == -1 && strstr(s.t.err, "serial /nonexistent/ttyUSB9: open: "), "a missing device: %s", s.t.err);
    r = cm_serial_open(&s, "/tmp", 115200);
    TAP_CHECK(r == -1 && strstr(s.t.err, "serial /tmp: open: "), "a directory: %s", s.t.err);
    r = cm_serial_open(&s, "/dev/ttyS0", 12345);
    TAP_CHECK(r == -1 && strstr(s.t.err, "baud 12345 is not a rate"), "a rate termios lacks: %s", s.t.err);
    r = cm_serial_open(&s, "/dev/ttyS0", 0);
    TAP_CHECK(r == -1 && strstr(s.t.err, "baud 0"), "baud 0: %s", s.t.err);
    s.t.close(&s.t); /* after a failed open too */
    TAP_CHECK(cm_serial_baud_ok(115200) && cm_serial_baud_ok(50) && !cm_serial_baud_ok(115201),
              "cm_serial_baud_ok");
}

int main(void)
{
    test_parse();
    test_refusals();
    test_settings_and_restore();
    test_deadlines();
    test_data_both_ways();
    test_hangup();
    return tap_done();
}
