/*
 * test_relay.c - cm_serial through tests/tools/pty_relay, the "bad cable":
 * clean both ways (bytes identical, the line paced at --baud), seeded noise
 * (the relay's counters explain every byte, the same seed damages alike) and
 * a cable pull with re-plug (the reader sees CM_T_HANGUP, reopens the same
 * link path and carries on).
 *
 * The relay is $CM_PTY_RELAY, else ../tools/pty_relay next to this binary.
 * Under qemu-user point CM_PTY_RELAY at a native build: a qemu-user process
 * cannot exec a foreign-architecture binary.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
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

static void sleep_ms(int ms)
{
    struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

static char relay_bin[4096];
static char tmpdir[] = "/tmp/cm_relay_test.XXXXXX";
static char link_a[256], link_b[256], errfile[256];

typedef struct relay {
    pid_t pid;
    int out;         /* the relay's stdout */
    char lines[4096]; /* what it printed so far */
    size_t len;
    char err[2048];  /* its stderr, after relay_stop */
} relay;

/* Read the relay's stdout until a line starting with `word` appears (or ms pass). */
static int relay_wait(relay *r, const char *word, int ms)
{
    double end = now_ms() + ms;
    for (;;) {
        for (const char *l = r->lines; l && *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : NULL)
            if (!strncmp(l, word, strlen(word)))
                return 1;
        int left = (int)(end - now_ms());
        if (left <= 0)
            return 0;
        struct pollfd p = {r->out, POLLIN, 0};
        if (poll(&p, 1, left) <= 0)
            continue;
        ssize_t k = read(r->out, r->lines + r->len, sizeof r->lines - 1 - r->len);
        if (k <= 0)
            return 0; /* the relay died */
        r->len += (size_t)k;
        r->lines[r->len] = '\0';
    }
}

static int relay_start(relay *r, const char *const *opts)
{
    memset(r, 0, sizeof *r);
    const char *argv[32];
    int n = 0;
    argv[n++] = relay_bin;
    static const char *const common[] = {"--link-a", link_a, "--link-b", link_b, "--timeout", "120"};
    for (size_t i = 0; i < sizeof common / sizeof common[0]; i++)
        argv[n++] = common[i];
    while (*opts && n < 30)
        argv[n++] = *opts++;
    argv[n] = NULL;
    int p[2];
    if (pipe(p) != 0)
        return -1;
    r->pid = fork();
    if (r->pid == 0) {
        dup2(p[1], 1);
        int e = open(errfile, O_WRONLY | O_CREAT | O_TRUNC, 0600);
        dup2(e, 2);
        close(p[0]);
        execv(relay_bin, (char *const *)argv);
        _exit(127);
    }
    close(p[1]);
    r->out = p[0];
    if (!relay_wait(r, "READY", 10000)) {
        int st = 0;
        waitpid(r->pid, &st, 0);
        close(r->out);
        return WIFEXITED(st) && WEXITSTATUS(st) == 127 ? -2 : -1;
    }
    return 0;
}

/* SIGTERM, reap (SIGKILL after 5 s), keep its stderr; returns its exit status or -1 */
static int relay_stop(relay *r)
{
    kill(r->pid, SIGTERM);
    int st = 0, got = 0;
    for (int i = 0; i < 500 && !(got = (int)waitpid(r->pid, &st, WNOHANG)); i++)
        sleep_ms(10);
    if (!got) {
        kill(r->pid, SIGKILL);
        waitpid(r->pid, &st, 0);
    }
    close(r->out);
    int fd = open(errfile, O_RDONLY);
    ssize_t k = fd >= 0 ? read(fd, r->err, sizeof r->err - 1) : 0;
    r->err[k > 0 ? k : 0] = '\0';
    /* one line, so that it fits in a TAP line */
    for (char *c = r->err; *c; c++)
        if (*c == '\n')
            *c = c[1] ? ';' : '\0';
    if (fd >= 0)
        close(fd);
    return got && WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* A relay counter from its exit report: lane "A->B", name "dropped" */
static unsigned long long counter(const relay *r, const char *lane, const char *name)
{
    const char *l = strstr(r->err, lane);
    char key[32];
    snprintf(key, sizeof key, " %s=", name);
    const char *k = l ? strstr(l, key) : NULL;
    return k ? strtoull(k + strlen(key), NULL, 10) : ~0ull;
}

/* fork a writer that opens `link` and sends buf; returns its pid */
static pid_t spawn_writer(const char *link, const uint8_t *buf, size_t n)
{
    pid_t pid = fork();
    if (pid == 0) {
        cm_serial s;
        if (cm_serial_open(&s, link, 115200) != 0)
            _exit(2);
        long r = s.t.write(&s.t, buf, n, 20000);
        s.t.close(&s.t);
        _exit(r == (long)n ? 0 : 3);
    }
    return pid;
}

static int status_ok(int st)
{
    return WIFEXITED(st) && WEXITSTATUS(st) == 0;
}

/*
 * Read until n bytes arrived or the line has been quiet for quiet_ms while `writer` (if > 0) has
 * exited; returns the count.  A quiet spell while the writer still runs is a busy machine that has
 * not scheduled it yet, not the end of the data (bounded by 60 s).
 */
static size_t read_until_quiet(cm_transport *t, uint8_t *buf, size_t n, int quiet_ms, long *last, pid_t writer,
                               int *writer_status)
{
    size_t got = 0;
    *last = 0;
    double give_up = now_ms() + 60000;
    while (got < n) {
        long k = t->read(t, buf + got, n - got, quiet_ms);
        *last = k;
        if (k == 0 && writer > 0 && now_ms() < give_up) {
            pid_t w = waitpid(writer, writer_status, WNOHANG);
            if (w == 0)
                continue; /* still writing */
            writer = 0;   /* reaped: a last quiet spell ends it */
            continue;
        }
        if (k <= 0)
            break;
        got += (size_t)k;
    }
    if (writer > 0)
        waitpid(writer, writer_status, 0);
    return got;
}

#define NPAY 65536
static uint8_t payload[NPAY], rx[2 * NPAY], rx_first[2 * NPAY], rx_back[NPAY];

/* one direction through the relay: a child writes into `from`, this process reads `to` */
static size_t transfer(const char *from, const char *to, size_t n, uint8_t *into, double *ms)
{
    cm_serial rd;
    if (cm_serial_open(&rd, to, 115200) != 0) {
        TAP_CHECK(0, "open %s: %s", to, rd.t.err);
        return 0;
    }
    double t0 = now_ms();
    pid_t w = spawn_writer(from, payload, n);
    long last;
    int st = 0;
    size_t got = read_until_quiet(&rd.t, into, 2 * n, 700, &last, w, &st);
    *ms = now_ms() - t0 - 700; /* the quiet wait at the end is not transfer time */
    TAP_CHECK(status_ok(st), "the writer on %s sent %zu bytes", from, n);
    rd.t.close(&rd.t);
    return got;
}

static void test_clean(void)
{
    relay r;
    const char *opts[] = {"--baud", "2000000", NULL};
    int rc = relay_start(&r, opts);
    TAP_CHECK(rc == 0, "relay started, links %s and %s", link_a, link_b);
    if (rc)
        return;
    double ms;
    size_t got = transfer(link_a, link_b, NPAY, rx, &ms);
    TAP_CHECK(got == NPAY && !memcmp(rx, payload, NPAY), "clean A->B: 64 KiB arrive identical (%zu bytes)", got);
    /* 2 Mbaud 8N1 is 200000 bytes/s: 64 KiB take 328 ms at least */
    TAP_CHECK(ms > 250 && ms < 20000, "paced at --baud 2000000: %.0f ms for 64 KiB (ideal 328)", ms);
    got = transfer(link_b, link_a, 20000, rx, &ms);
    TAP_CHECK(got == 20000 && !memcmp(rx, payload, 20000), "clean B->A: 20000 bytes identical (%zu)", got);
    TAP_CHECK(relay_stop(&r) == 0, "relay exits 0 on SIGTERM");
    TAP_CHECK(counter(&r, "A->B", "moved") == NPAY && counter(&r, "A->B", "dropped") == 0 &&
                  counter(&r, "B->A", "moved") == 20000,
              "its counters: %s", r.err);
}

static void test_noisy(void)
{
    const char *opts[] = {"--drop", "0.01", "--flip", "0.01", "--insert", "0.005", "--seed", "9", "--dir", "AB", NULL};
    size_t got[2] = {0, 0};
    unsigned long long dropped = 0;
    for (int run = 0; run < 2; run++) {
        relay r;
        if (relay_start(&r, opts) != 0) {
            TAP_CHECK(0, "noisy relay started");
            return;
        }
        double ms;
        got[run] = transfer(link_a, link_b, 20000, run ? rx : rx_first, &ms);
        size_t back = transfer(link_b, link_a, 5000, rx_back, &ms);
        TAP_CHECK(back == 5000 && !memcmp(rx_back, payload, 5000), "run %d: --dir AB leaves B->A clean (%zu)", run, back);
        relay_stop(&r);
        unsigned long long moved = counter(&r, "A->B", "moved"), ins = counter(&r, "A->B", "inserted");
        dropped = counter(&r, "A->B", "dropped");
        TAP_CHECK(moved == 20000 && dropped > 50 && counter(&r, "A->B", "flipped") > 50 &&
                      got[run] == moved - dropped + ins,
                  "run %d: received %zu = 20000 - dropped %llu + inserted %llu", run, got[run], dropped, ins);
    }
    TAP_CHECK(got[0] == got[1] && !memcmp(rx_first, rx, got[0]), "the same --seed damages the same way twice");
}

static int exists(const char *p)
{
    struct stat st;
    return lstat(p, &st) == 0;
}

static void test_unplug(void)
{
    relay r;
    const char *opts[] = {"--hangup-after", "1000", "--reopen-ms", "300", NULL};
    if (relay_start(&r, opts) != 0) {
        TAP_CHECK(0, "hang-up relay started");
        return;
    }
    cm_serial rd;
    int rc = cm_serial_open(&rd, link_b, 115200);
    TAP_CHECK(rc == 0, "reader on %s: %s", link_b, rc ? rd.t.err : "ok");
    pid_t w = spawn_writer(link_a, payload, 1500);
    long last;
    int st = 0;
    /* the hang-up ends the read; 10 s of quiet (a busy machine) before calling it missing */
    size_t got = read_until_quiet(&rd.t, rx, sizeof rx, 10000, &last, 0, &st);
    waitpid(w, &st, 0);
    TAP_CHECK(status_ok(st), "the writer sent 1500 bytes");
    TAP_CHECK(got == 1000 && !memcmp(rx, payload, 1000) && last == CM_T_HANGUP,
              "the reader got exactly the first 1000 bytes, then CM_T_HANGUP (%zu, %ld: %s)", got, last, rd.t.err);
    rd.t.close(&rd.t);
    TAP_CHECK(relay_wait(&r, "UNPLUGGED", 10000) && !exists(link_b), "while unplugged, %s is gone", link_b);
    /* re-plug: the same path comes back, as udev's by-id link does */
    double t0 = now_ms();
    rc = -1;
    while (rc != 0 && now_ms() - t0 < 10000) {
        rc = cm_serial_open(&rd, link_b, 115200);
        if (rc != 0)
            sleep_ms(50);
    }
    /* the relay makes the link before it prints REPLUGGED: on a busy machine the print can lag */
    TAP_CHECK(rc == 0 && relay_wait(&r, "REPLUGGED", 10000), "reopened %s after %.0f ms (%s)", link_b, now_ms() - t0,
              rc ? rd.t.err : "ok");
    if (rc == 0) {
        w = spawn_writer(link_a, payload + 2000, 3000);
        got = read_until_quiet(&rd.t, rx, 3000, 3000, &last, w, &st);
        TAP_CHECK(status_ok(st) && got == 3000 && !memcmp(rx, payload + 2000, 3000),
                  "after the re-plug 3000 bytes arrive intact (%zu)", got);
        rd.t.close(&rd.t);
    }
    relay_stop(&r);
    TAP_CHECK(strstr(r.err, "hangups=1") && counter(&r, "A->B", "lost_unplugged") == 500,
              "the relay counted one hang-up and the 500 bytes sent into the unplugged line: %s", r.err);
}

int main(int argc, char **argv)
{
    (void)argc;
    const char *env = getenv("CM_PTY_RELAY");
    if (env && *env)
        snprintf(relay_bin, sizeof relay_bin, "%s", env);
    else {
        const char *slash = strrchr(argv[0], '/');
        int dir_len = slash ? (int)(slash - argv[0]) : 1;
        snprintf(relay_bin, sizeof relay_bin, "%.*s/../tools/pty_relay", dir_len, slash ? argv[0] : ".");
    }
    if (access(relay_bin, X_OK) != 0) {
        tap_skip("pty relay tests", "no relay binary (set CM_PTY_RELAY, or build tests/tools/pty_relay)");
        return tap_done();
    }
    signal(SIGPIPE, SIG_IGN);
    uint32_t x = 2024;
    for (size_t i = 0; i < NPAY; i++) {
        x = x * 1664525u + 1013904223u;
        payload[i] = (uint8_t)(x >> 24);
    }
    if (!mkdtemp(tmpdir)) {
        TAP_CHECK(0, "mkdtemp");
        return tap_done();
    }
    snprintf(link_a, sizeof link_a, "%s/ttyA", tmpdir);
    snprintf(link_b, sizeof link_b, "%s/ttyB", tmpdir);
    snprintf(errfile, sizeof errfile, "%s/relay.err", tmpdir);

    relay probe;
    const char *none[] = {NULL};
    int rc = relay_start(&probe, none);
    if (rc == -2) {
        tap_skip("pty relay tests", "the relay binary would not run (a foreign architecture? set CM_PTY_RELAY)");
    } else {
        if (rc == 0)
            relay_stop(&probe);
        test_clean();
        test_noisy();
        test_unplug();
    }
    unlink(link_a);
    unlink(link_b);
    unlink(errfile);
    rmdir(tmpdir);
    return tap_done();
}
