/*
 * usb_echo.c - the USB back ends of cm_transport against each other: the
 * gadget side echoes, the host side checks and times it.
 *
 *   usb_echo --selftest
 *       no hardware: VID:PID parsing and the errors of an absent device.
 *   usb_echo --gadget MOUNTDIR
 *       cm_ffs on a functionfs mount: echo every byte back; prints READY once
 *       the descriptors are written (then bind the UDC); runs until SIGTERM.
 *   usb_echo --host VID:PID[:SERIAL] N SIZE [--wait MS] [--deadline MS] [--expect-hangup] [--stall]
 *       cm_usb: waits for the device, opens it, echoes the edge sizes (1 byte,
 *       odd sizes, exactly wMaxPacketSize and multiples of it, the 16 KiB
 *       buffer +-1, larger than it), then N blocks of SIZE bytes, and prints
 *       TAP lines with MB/s.  --expect-hangup: the link is cut during the N
 *       blocks (by the test script); passes when a call reports CM_T_HANGUP
 *       within its deadline.
 *
 * Exit status: 0 when every check passed.
 */
#define _POSIX_C_SOURCE 200809L

#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cm_transport_ffs.h"
#include "cm_transport_usb.h"

/* the gadget echoes per read; the host sends at most this much before reading it back */
#define ECHO_CHUNK CM_FFS_BUF
#define MAX_BLOCK (1u << 20)

static int tap_n, tap_failed;

__attribute__((format(printf, 2, 3))) static void tap(int ok, const char *fmt, ...)
{
    va_list ap;
    printf("%sok %d - ", ok ? "" : "not ", ++tap_n);
    va_start(ap, fmt);
    vprintf(fmt, ap);
    va_end(ap);
    printf("\n");
    fflush(stdout);
    if (!ok)
        tap_failed++;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

static const char *result_name(long r)
{
    return r == CM_T_HANGUP ? "CM_T_HANGUP" : r == CM_T_IO ? "CM_T_IO" : r == 0 ? "deadline" : "bytes";
}

/* ---- gadget side ---- */

static volatile sig_atomic_t stop;
static void on_signal(int sig)
{
    (void)sig;
    stop = 1;
}

static int run_gadget(const char *dir)
{
    static cm_ffs f;
    static uint8_t buf[CM_FFS_BUF];
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal; /* no SA_RESTART: poll() returns EINTR and the loop sees stop */
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    if (cm_ffs_open(&f, dir) != 0) {
        fprintf(stderr, "usb_echo: %s\n", f.t.err);
        return 1;
    }
    printf("READY %s\n", f.t.name);
    fflush(stdout);
    unsigned long long echoed = 0;
    unsigned hangups = 0;
    int rc = 0;
    while (!stop) {
        long r = f.t.read(&f.t, buf, sizeof buf, 500);
        if (r == 0)
            continue;
        if (r == CM_T_HANGUP) {
            hangups++;
            fprintf(stderr, "usb_echo: gadget: %s (waiting for the host)\n", f.t.err);
            continue;
        }
        if (r < 0) {
            fprintf(stderr, "usb_echo: gadget: %s\n", f.t.err);
            rc = 1;
            break;
        }
        long w = f.t.write(&f.t, buf, (size_t)r, 5000);
        if (w == (long)r)
            echoed += (unsigned long long)r;
        else if (w == CM_T_HANGUP) {
            hangups++;
            fprintf(stderr, "usb_echo: gadget: %s (waiting for the host)\n", f.t.err);
        } else
            fprintf(stderr, "usb_echo: gadget: echo of %ld bytes: %s %s\n", r, result_name(w), f.t.err);
        if (w == CM_T_IO) {
            rc = 1;
            break;
        }
    }
    fprintf(stderr, "usb_echo: gadget: echoed %llu bytes, %u hangups\n", echoed, hangups);
    f.t.close(&f.t);
    f.t.close(&f.t); /* close is safe twice */
    return rc;
}

/* ---- host side ---- */

static uint8_t pattern_byte(unsigned block, size_t i)
{
    return (uint8_t)((i * 31u + block * 7u + (i >> 8)) ^ 0x5au);
}

typedef struct echo_result {
    long last;       /* result of the failing call (or the last one) */
    double call_s;   /* how long the failing call took */
    const char *op;  /* "write", "read", "compare" */
    size_t at;       /* byte offset of the failure */
} echo_result;

/* send one block in chunks the gadget echoes whole, read each back and compare; 0 ok */
static int echo_block(cm_usb *u, unsigned block, size_t size, int deadline_ms, echo_result *res)
{
    static uint8_t tx[MAX_BLOCK], rx[ECHO_CHUNK];
    for (size_t i = 0; i < size; i++)
        tx[i] = pattern_byte(block, i);
    for (size_t off = 0; off < size;) {
        size_t chunk = size - off < ECHO_CHUNK ? size - off : ECHO_CHUNK;
        double t0 = now_s();
        long w = u->t.write(&u->t, tx + off, chunk, deadline_ms);
        if (w != (long)chunk) {
            *res = (echo_result){w, now_s() - t0, "write", off};
            return -1;
        }
        for (size_t got = 0; got < chunk;) {
            t0 = now_s();
            long r = u->t.read(&u->t, rx + got, chunk - got, deadline_ms);
            if (r <= 0) {
                *res = (echo_result){r, now_s() - t0, "read", off + got};
                return -1;
            }
            got += (size_t)r;
        }
        if (memcmp(rx, tx + off, chunk) != 0) {
            size_t k = 0;
            while (rx[k] == tx[off + k])
                k++;
            *res = (echo_result){1, 0, "compare", off + k};
            return -1;
        }
        off += chunk;
    }
    return 0;
}

/*
 * Back-pressure: the host writes without reading, so the gadget's echo write
 * blocks, its read-ahead fills and the host's write must return 0 at its
 * deadline.  Then the host stays away longer than the gadget's 5 s write
 * deadline (the gadget cancels its write and drops that echo), drains what
 * is left, and a fresh echo must come back intact.
 */
static void stall_test(cm_usb *u)
{
    static uint8_t tx[ECHO_CHUNK], rx[ECHO_CHUNK];
    memset(tx, 0xa5, sizeof tx);
    int timed_out = 0, i;
    double dt = 0;
    for (i = 0; i < 64 && !timed_out; i++) {
        double t0 = now_s();
        long w = u->t.write(&u->t, tx, sizeof tx, 500);
        dt = now_s() - t0;
        if (w == 0)
            timed_out = 1;
        else if (w != (long)sizeof tx)
            break;
    }
    tap(timed_out && dt >= 0.45 && dt < 1.5, "write to a gadget that does not read returns 0 at its 500 ms deadline "
        "(block %d, after %.3f s) %s", i, dt, timed_out ? "" : u->t.err);
    struct timespec ts = {5, 500000000L};
    nanosleep(&ts, NULL);
    size_t drained = 0;
    long r;
    while ((r = u->t.read(&u->t, rx, sizeof rx, 700)) > 0)
        drained += (size_t)r;
    tap(r == 0, "drained %zu stale bytes after the gadget's write deadline (%s)", drained, result_name(r));
    echo_result er;
    int ok = echo_block(u, 77, 1000, 2000, &er) == 0 && echo_block(u, 78, ECHO_CHUNK, 2000, &er) == 0;
    tap(ok, "echo intact after the stall%s%s", ok ? "" : ": ", ok ? "" : er.op);
}

/* ---- without hardware: parsing, and the errors of an absent device ---- */

static void parse_case(const char *spec, int want_rc, unsigned want_vid, unsigned want_pid, const char *want_serial,
                       size_t cap)
{
    uint16_t vid = 0, pid = 0;
    char serial[CM_USB_SERIAL_MAX] = "?";
    int rc = cm_usb_parse(spec, &vid, &pid, serial, cap);
    int ok = rc == want_rc && (rc != 0 || (vid == want_vid && pid == want_pid && strcmp(serial, want_serial) == 0));
    tap(ok, "cm_usb_parse(\"%s\") = %d%s%s (%04x:%04x \"%s\")", spec, rc, rc ? ": " : "", cm_usb_parse_strerror(rc),
        vid, pid, rc == 0 ? serial : "");
}

static int run_selftest(void)
{
    parse_case("1209:0001", 0, 0x1209, 0x0001, "", CM_USB_SERIAL_MAX);
    parse_case("0x1209:0XA:CMZ-0042", 0, 0x1209, 0x000a, "CMZ-0042", CM_USB_SERIAL_MAX);
    parse_case("ffff:FFFF:a b", 0, 0xffff, 0xffff, "a b", CM_USB_SERIAL_MAX);
    parse_case("", CM_USB_PARSE_EMPTY, 0, 0, "", CM_USB_SERIAL_MAX);
    parse_case("1209", CM_USB_PARSE_VID, 0, 0, "", CM_USB_SERIAL_MAX);
    parse_case("12090:0001", CM_USB_PARSE_VID, 0, 0, "", CM_USB_SERIAL_MAX);
    parse_case(":0001", CM_USB_PARSE_VID, 0, 0, "", CM_USB_SERIAL_MAX);
    parse_case("1209:", CM_USB_PARSE_PID, 0, 0, "", CM_USB_SERIAL_MAX);
    parse_case("1209:00g1", CM_USB_PARSE_PID, 0, 0, "", CM_USB_SERIAL_MAX);
    parse_case("1209:0001:", CM_USB_PARSE_SERIAL, 0, 0, "", CM_USB_SERIAL_MAX);
    parse_case("1209:0001:a\tb", CM_USB_PARSE_SERIAL, 0, 0, "", CM_USB_SERIAL_MAX);
    parse_case("1209:0001:toolong", CM_USB_PARSE_SERIAL, 0, 0, "", 4);
    parse_case("0:1", CM_USB_PARSE_ZERO, 0, 0, "", CM_USB_SERIAL_MAX);

    /* 1209:fffe is not plugged in here (pid.codes keeps it unassigned) */
    static cm_usb u;
    int rc = cm_usb_open(&u, 0x1209, 0xfffe, "NOPE");
    tap(rc == -1 && strstr(u.t.err, "usb 1209:fffe:NOPE: ") == u.t.err && strstr(u.t.err, "cable"),
        "cm_usb_open of an absent device fails and says why: %s", u.t.err);
    u.t.close(&u.t);
    u.t.close(&u.t);
    tap(1, "close after a failed open, twice, is harmless");
    uint8_t b;
    tap(u.t.read(&u.t, &b, 1, 10) == CM_T_IO && u.t.write(&u.t, &b, 1, 10) == CM_T_IO,
        "read and write on a closed link return CM_T_IO: %s", u.t.err);
    double t0 = now_s();
    int w = cm_usb_wait(0x1209, 0xfffe, NULL, 250);
    double dt = now_s() - t0;
    tap(w == 0 && dt >= 0.24 && dt < 1.0, "cm_usb_wait for an absent device returns 0 after its 250 ms (%d, %.3f s)",
        w, dt);

    static cm_ffs f;
    rc = cm_ffs_open(&f, "/nonexistent-ffs");
    tap(rc == -1 && strstr(f.t.err, "functionfs") != NULL, "cm_ffs_open without a functionfs mount says so: %s",
        f.t.err);
    f.t.close(&f.t);
    f.t.close(&f.t);
    printf("1..%d\n", tap_n);
    return tap_failed ? 1 : 0;
}

static void usage(void)
{
    fprintf(stderr, "usage: usb_echo --selftest\n"
                    "       usb_echo --gadget MOUNTDIR\n"
                    "       usb_echo --host VID:PID[:SERIAL] N SIZE [--wait MS] [--deadline MS] [--expect-hangup] [--stall]\n");
}

static int run_host(int argc, char **argv)
{
    static cm_usb u;
    uint16_t vid, pid;
    char serial[CM_USB_SERIAL_MAX];
    int rc = cm_usb_parse(argv[0], &vid, &pid, serial, sizeof serial);
    if (rc != 0) {
        fprintf(stderr, "usb_echo: %s: %s\n", argv[0], cm_usb_parse_strerror(rc));
        return 2;
    }
    long n_blocks = strtol(argv[1], NULL, 10);
    long size = strtol(argv[2], NULL, 10);
    int wait_ms = 5000, deadline_ms = 2000, expect_hangup = 0, stall = 0;
    for (int i = 3; i < argc; i++) {
        if (strcmp(argv[i], "--wait") == 0 && i + 1 < argc)
            wait_ms = atoi(argv[++i]);
        else if (strcmp(argv[i], "--deadline") == 0 && i + 1 < argc)
            deadline_ms = atoi(argv[++i]);
        else if (strcmp(argv[i], "--expect-hangup") == 0)
            expect_hangup = 1;
        else if (strcmp(argv[i], "--stall") == 0)
            stall = 1;
        else {
            usage();
            return 2;
        }
    }
    if (n_blocks < 1 || size < 1 || size > (long)MAX_BLOCK) {
        fprintf(stderr, "usb_echo: N must be >= 1 and SIZE in 1..%u\n", MAX_BLOCK);
        return 2;
    }

    double t0 = now_s();
    int present = cm_usb_wait(vid, pid, serial, wait_ms);
    tap(present == 1, "device %s present (waited %.2f s)%s", argv[0], now_s() - t0,
        present == 1 ? "" : present == 0 ? ": not within --wait" : ": libusb_init failed");
    if (present != 1)
        return 1;
    rc = cm_usb_open(&u, vid, pid, serial);
    tap(rc == 0, "cm_usb_open %s", rc == 0 ? u.t.name : u.t.err);
    if (rc != 0)
        return 1;
    printf("# interface %d alt %d: bulk IN 0x%02x (wMaxPacketSize %u), bulk OUT 0x%02x (wMaxPacketSize %u)\n",
           u.iface, u.alt, u.ep_in, u.mps_in, u.ep_out, u.mps_out);

    echo_result er;
    if (stall)
        stall_test(&u);
    else if (!expect_hangup) {
        size_t mps = u.mps_out;
        size_t sizes[] = {1, 2, 63, 64, 65, mps - 1, mps, mps + 1, 2 * mps, 3 * mps + 17, 4095, 4096,
                          ECHO_CHUNK - 1, ECHO_CHUNK, ECHO_CHUNK + 1, 2 * ECHO_CHUNK, 65537, 100000};
        unsigned block = 0;
        for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
            int ok = echo_block(&u, block++, sizes[i], deadline_ms, &er) == 0;
            if (ok)
                tap(1, "echo of %zu bytes", sizes[i]);
            else
                tap(0, "echo of %zu bytes: %s at byte %zu: %s after %.3f s %s", sizes[i], er.op, er.at,
                    result_name(er.last), er.call_s, u.t.err);
        }
        /* a read with nothing coming returns 0 at its deadline, not earlier or later */
        uint8_t one;
        double r0 = now_s();
        long r = u.t.read(&u.t, &one, 1, 300);
        double dt = now_s() - r0;
        tap(r == 0 && dt >= 0.29 && dt < 1.0, "idle read returns 0 at its 300 ms deadline (%s after %.3f s)",
            result_name(r), dt);
    }

    double start = now_s();
    long done = 0;
    int failed = 0;
    for (; done < n_blocks; done++) {
        if (echo_block(&u, (unsigned)done, (size_t)size, deadline_ms, &er) != 0) {
            failed = 1;
            break;
        }
    }
    double dt = now_s() - start;
    if (!expect_hangup) {
        if (failed)
            tap(0, "%ld x %ld bytes: block %ld: %s at byte %zu: %s %s", n_blocks, size, done, er.op, er.at,
                result_name(er.last), u.t.err);
        else
            tap(1, "%ld x %ld bytes echoed in %.2f s: %.2f MB/s each way", n_blocks, size, dt,
                (double)n_blocks * (double)size / dt / 1e6);
    } else {
        int ok = failed && er.last == CM_T_HANGUP && er.call_s <= deadline_ms / 1000.0 + 0.5;
        tap(ok, "link cut after %ld good blocks: %s %s in %.3f s (deadline %d ms)%s%s", done,
            failed ? er.op : "completed", failed ? result_name(er.last) : "", failed ? er.call_s : 0.0,
            deadline_ms, failed ? ": " : "", failed ? u.t.err : ": no hangup seen");
    }
    u.t.close(&u.t);
    u.t.close(&u.t); /* close is safe twice */
    printf("1..%d\n", tap_n);
    return tap_failed ? 1 : 0;
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "--selftest") == 0)
        return run_selftest();
    if (argc == 3 && strcmp(argv[1], "--gadget") == 0)
        return run_gadget(argv[2]);
    if (argc >= 5 && strcmp(argv[1], "--host") == 0)
        return run_host(argc - 2, argv + 2);
    usage();
    return 2;
}
