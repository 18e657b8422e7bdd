/*
 * pty_relay.c - a bad serial cable for tests: two pty pairs, A and B, with
 * this program copying bytes between their masters, damaged on the way by
 * seeded noise (the project's cm_fault_noise), paced like a real line, and
 * optionally unplugged and plugged in again.
 *
 *   pty_relay [--link-a PATH] [--link-b PATH] [--drop P] [--flip P] [--insert P]
 *             [--seed N] [--baud B] [--dir AB|BA|both] [--hangup-after N]
 *             [--reopen-ms M] [--timeout S]
 *
 * The program under test opens the slave ends (or the symlinks --link-a/-b
 * make to them).  stdout gets "A <slave path>", "B <slave path>" and then
 * "READY"; later "UNPLUGGED B" and "REPLUGGED B <slave path>".
 *
 *   --drop/--flip/--insert P  per-byte probabilities, in the directions --dir
 *                             names (default both); each direction has its own
 *                             PRNG stream from --seed (default 1)
 *   --baud B                  pace each direction like an 8N1 line at B (10 bits a byte)
 *   --hangup-after N          once N bytes have gone A->B (and B's reader has
 *                             taken them, up to 10 s): unlink B's link and close
 *                             B's master (B's users see a hang-up: EIO/POLLHUP);
 *                             after --reopen-ms M (default 1000; -1: never) a
 *                             fresh pty appears at the same link.  Bytes sent
 *                             while unplugged are lost.  Fires once.
 *   --timeout S               exit after S seconds (a guard for tests that die)
 *
 * A side nobody reads fills its pty's buffer and then holds the sender back
 * (flow control, in effect): bytes are lost only to --drop or an unplug.
 * SIGTERM/SIGINT end it cleanly; the fault counters go to stderr on exit.
 * The relay holds each slave open itself, so a test can close and reopen a
 * slave without the master seeing EIO (as a UART does not notice a closed
 * program).
 */
#define _POSIX_C_SOURCE 200809L
#define _XOPEN_SOURCE 700 /* posix_openpt, grantpt, unlockpt, ptsname */
#define _DEFAULT_SOURCE   /* cfmakeraw, FIONREAD */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "fake/cm_transport_fault.h"

typedef struct pty_end {
    int master;     /* -1 while unplugged */
    int slave;      /* held open by the relay, never read */
    char path[64];  /* the slave's /dev/pts/N */
    const char *link;
} pty_end;

/* one direction of the cable */
typedef struct lane {
    const char *label; /* "A->B" */
    pty_end *from, *to;
    int faulty;
    cm_fault_noise noise;
    uint8_t buf[8192];
    size_t len, off;              /* buf[off..len) still to be written */
    double tokens;                /* pacing: bytes the line may send now */
    long long paced_at_ns;
    unsigned long long moved;     /* bytes taken from the source */
    unsigned long long lost;      /* bytes that went nowhere while B was unplugged */
} lane;

static int sig_pipe[2] = {-1, -1};

static void on_signal(int sig)
{
    (void)sig;
    int saved = errno;
    (void)!write(sig_pipe[1], "x", 1);
    errno = saved;
}

static long long now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long long)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void die(const char *what)
{
    fprintf(stderr, "pty_relay: %s: %s\n", what, strerror(errno));
    exit(1);
}

static void set_cloexec_nonblock(int fd, int nonblock)
{
    fcntl(fd, F_SETFD, FD_CLOEXEC);
    if (nonblock)
        fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
}

/* A fresh pty pair; the slave starts raw so that nothing is echoed back before a user opens it. */
static void plug(pty_end *e)
{
    e->master = posix_openpt(O_RDWR | O_NOCTTY);
    if (e->master < 0 || grantpt(e->master) != 0 || unlockpt(e->master) != 0)
        die("posix_openpt");
    const char *name = ptsname(e->master);
    if (!name)
        die("ptsname");
    snprintf(e->path, sizeof e->path, "%s", name);
    e->slave = open(e->path, O_RDWR | O_NOCTTY);
    if (e->slave < 0)
        die(e->path);
    struct termios t;
    if (tcgetattr(e->slave, &t) != 0)
        die("tcgetattr");
    cfmakeraw(&t);
    if (tcsetattr(e->slave, TCSANOW, &t) != 0)
        die("tcsetattr");
    set_cloexec_nonblock(e->master, 1);
    set_cloexec_nonblock(e->slave, 0);
    if (e->link) {
        /* rename over the old link: a reader never sees a half-made one */
        char tmp[4200];
        snprintf(tmp, sizeof tmp, "%s.tmp%ld", e->link, (long)getpid());
        unlink(tmp);
        if (symlink(e->path, tmp) != 0 || rename(tmp, e->link) != 0)
            die(e->link);
    }
}

static void unplug(pty_end *e)
{
    if (e->link)
        unlink(e->link); /* first, so whoever sees the hang-up finds no stale link */
    close(e->master);
    close(e->slave);
    e->master = e->slave = -1;
}

static int parse_prob(const char *s, double *p)
{
    char *end;
    errno = 0;
    *p = strtod(s, &end);
    return errno == 0 && end != s && *end == '\0' && *p >= 0.0 && *p <= 1.0;
}

static int parse_ll(const char *s, long long *v)
{
    char *end;
    errno = 0;
    *v = strtoll(s, &end, 0);
    return errno == 0 && end != s && *end == '\0';
}

static void usage(void)
{
    fprintf(stderr, "usage: pty_relay [--link-a PATH] [--link-b PATH] [--drop P] [--flip P] [--insert P]\n"
                    "                 [--seed N] [--baud B] [--dir AB|BA|both] [--hangup-after N]\n"
                    "                 [--reopen-ms M] [--timeout S]\n"
                    "(see the comment at the top of tests/tools/pty_relay.c)\n");
    exit(2);
}

/* bytes per second of an 8N1 line, and how many it may send at once (2 ms worth) */
static double rate_bps;
static double burst;

static void pace(lane *l, long long now)
{
    if (rate_bps <= 0)
        return;
    l->tokens += (double)(now - l->paced_at_ns) * rate_bps / 1e9;
    if (l->tokens > burst)
        l->tokens = burst;
    l->paced_at_ns = now;
}

/* ms until the lane may send its next byte (0: now) */
static int pace_wait_ms(const lane *l)
{
    if (rate_bps <= 0 || l->tokens >= 1.0)
        return 0;
    int ms = (int)((1.0 - l->tokens) * 1000.0 / rate_bps) + 1;
    return ms;
}

/* Take a chunk from the source, damaged, into the lane's buffer. */
static void fill(lane *l, size_t limit)
{
    uint8_t in[sizeof l->buf / 2];
    size_t want = sizeof in < limit ? sizeof in : limit;
    ssize_t got = read(l->from->master, in, want);
    if (got < 0) {
        if (errno == EAGAIN || errno == EINTR)
            return;
        die(l->label);
    }
    if (got == 0)
        return;
    l->moved += (unsigned long long)got;
    if (l->to->master < 0) {
        l->lost += (unsigned long long)got;
        return;
    }
    if (l->faulty) {
        size_t used;
        l->len = cm_fault_noise_apply(&l->noise, in, (size_t)got, &used, l->buf, sizeof l->buf);
    } else {
        memcpy(l->buf, in, (size_t)got);
        l->len = (size_t)got;
    }
    l->off = 0;
}

static long long last_write_ns;

static void drain(lane *l)
{
    size_t n = l->len - l->off;
    if (rate_bps > 0 && (double)n > l->tokens)
        n = (size_t)l->tokens;
    if (n == 0)
        return;
    ssize_t put = write(l->to->master, l->buf + l->off, n);
    if (put < 0) {
        if (errno == EAGAIN || errno == EINTR)
            return;
        die(l->label);
    }
    l->off += (size_t)put;
    if (rate_bps > 0)
        l->tokens -= (double)put;
    last_write_ns = now_ns();
}

static int pending(const lane *l)
{
    return l->off < l->len;
}

int main(int argc, char **argv)
{
    pty_end a = {-1, -1, "", NULL}, b = {-1, -1, "", NULL};
    double p_drop = 0, p_flip = 0, p_insert = 0;
    long long seed = 1, baud = 0, hangup_after = -1, reopen_ms = 1000, timeout_s = 0;
    int faults_ab = 1, faults_ba = 1;
    for (int i = 1; i < argc; i++) {
        const char *o = argv[i];
        if (i + 1 >= argc)
            usage();
        const char *v = argv[++i];
        long long n;
        if (!strcmp(o, "--link-a"))
            a.link = v;
        else if (!strcmp(o, "--link-b"))
            b.link = v;
        else if (!strcmp(o, "--drop") && parse_prob(v, &p_drop))
            ;
        else if (!strcmp(o, "--flip") && parse_prob(v, &p_flip))
            ;
        else if (!strcmp(o, "--insert") && parse_prob(v, &p_insert))
            ;
        else if (!strcmp(o, "--seed") && parse_ll(v, &seed))
            ;
        else if (!strcmp(o, "--baud") && parse_ll(v, &n) && n > 0)
            baud = n;
        else if (!strcmp(o, "--hangup-after") && parse_ll(v, &n) && n >= 0)
            hangup_after = n;
        else if (!strcmp(o, "--reopen-ms") && parse_ll(v, &n) && n >= -1)
            reopen_ms = n;
        else if (!strcmp(o, "--timeout") && parse_ll(v, &n) && n >= 0)
            timeout_s = n;
        else if (!strcmp(o, "--dir") && (!strcmp(v, "AB") || !strcmp(v, "BA") || !strcmp(v, "both"))) {
            faults_ab = strcmp(v, "BA") != 0;
            faults_ba = strcmp(v, "AB") != 0;
        } else {
            fprintf(stderr, "pty_relay: bad option or value: %s %s\n", o, v);
            usage();
        }
    }
    if (baud > 0) {
        rate_bps = (double)baud / 10.0;
        burst = rate_bps / 500.0 < 1.0 ? 1.0 : rate_bps / 500.0;
    }

    if (pipe(sig_pipe) != 0)
        die("pipe");
    set_cloexec_nonblock(sig_pipe[0], 1);
    set_cloexec_nonblock(sig_pipe[1], 1);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGHUP, &sa, NULL);
    signal(SIGPIPE, SIG_IGN); /* a test that stops reading our stdout must not kill us */

    lane ab = {.label = "A->B", .from = &a, .to = &b, .faulty = faults_ab};
    lane ba = {.label = "B->A", .from = &b, .to = &a, .faulty = faults_ba};
    uint64_t s = (uint64_t)seed;
    /* two unrelated streams: the B->A seed is a mixed, not a shifted, copy of the A->B seed */
    if (cm_fault_noise_init(&ab.noise, p_drop, p_flip, p_insert, s) ||
        cm_fault_noise_init(&ba.noise, p_drop, p_flip, p_insert, (s ^ 0x5DEECE66Dull) * 0xFF51AFD7ED558CCDull)) {
        fprintf(stderr, "pty_relay: probabilities must be in [0, 1]\n");
        return 2;
    }
    plug(&a);
    plug(&b);
    printf("A %s\nB %s\nREADY\n", a.path, b.path);
    fflush(stdout);

    long long start = now_ns();
    ab.paced_at_ns = ba.paced_at_ns = start;
    ab.tokens = ba.tokens = burst;
    int hangups = 0;
    int phase = 0; /* 0 plugged, 1 waiting for B's reader to take the last bytes, 2 unplugged, 3 done */
    long long phase_at = 0;
    int quiet_ticks = 0;
    int stop = 0;
    while (!stop) {
        long long now = now_ns();
        pace(&ab, now);
        pace(&ba, now);
        if (timeout_s > 0 && now - start >= timeout_s * 1000000000LL) {
            fprintf(stderr, "pty_relay: --timeout %lld s reached\n", timeout_s);
            break;
        }
        int wait_ms = -1;
#define WAIT_AT_MOST(ms)                                                                                          \
    do {                                                                                                          \
        int w_ = (ms);                                                                                            \
        if (wait_ms < 0 || w_ < wait_ms)                                                                          \
            wait_ms = w_;                                                                                         \
    } while (0)
        if (timeout_s > 0)
            WAIT_AT_MOST((int)((start + timeout_s * 1000000000LL - now) / 1000000) + 1);

        /* the cable pull: after N bytes A->B, once they have reached B's reader */
        size_t ab_limit = sizeof ab.buf;
        if (phase == 0 && hangup_after >= 0) {
            long long room = hangup_after - (long long)ab.moved;
            if (room <= 0 && !pending(&ab)) {
                phase = 1;
                phase_at = now;
                quiet_ticks = 0;
            } else if (room >= 0 && (unsigned long long)room < ab_limit)
                ab_limit = (size_t)room;
        }
        if (phase == 1) {
            int queued = 0;
            if (ioctl(b.slave, FIONREAD, &queued) == 0 && queued == 0 && now - last_write_ns > 100000000LL)
                quiet_ticks++;
            else
                quiet_ticks = 0;
            /* 10 s: a reader on a machine busy with another build may take seconds to be scheduled,
               and the bytes it has not taken would be lost to the unplug */
            if (quiet_ticks >= 3 || now - phase_at > 10000000000LL) {
                unplug(&b);
                ba.len = ba.off = 0;
                ab.len = ab.off = 0;
                hangups++;
                printf("UNPLUGGED B\n");
                fflush(stdout);
                phase = 2;
                phase_at = now;
            } else
                WAIT_AT_MOST(20);
        }
        if (phase == 2 && reopen_ms >= 0) {
            long long due = phase_at + reopen_ms * 1000000LL;
            if (now >= due) {
                plug(&b);
                printf("REPLUGGED B %s\n", b.path);
                fflush(stdout);
                phase = 3;
            } else
                WAIT_AT_MOST((int)((due - now) / 1000000) + 1);
        }

        struct pollfd pf[3];
        int np = 0;
        pf[np++] = (struct pollfd){.fd = sig_pipe[0], .events = POLLIN, .revents = 0};
        int ia = np++, ib = -1;
        pf[ia] = (struct pollfd){.fd = a.master, .events = 0, .revents = 0};
        /* A: read while A->B has room (and, before the pull, while under the limit); write B->A */
        if (!pending(&ab) && ab_limit > 0 && phase != 1)
            pf[ia].events |= POLLIN;
        if (pending(&ba)) {
            int w = pace_wait_ms(&ba);
            if (w == 0)
                pf[ia].events |= POLLOUT;
            else
                WAIT_AT_MOST(w);
        }
        if (b.master >= 0) {
            ib = np++;
            pf[ib] = (struct pollfd){.fd = b.master, .events = 0, .revents = 0};
            if (!pending(&ba))
                pf[ib].events |= POLLIN;
            if (pending(&ab)) {
                int w = pace_wait_ms(&ab);
                if (w == 0)
                    pf[ib].events |= POLLOUT;
                else
                    WAIT_AT_MOST(w);
            }
        }
        if (poll(pf, (nfds_t)np, wait_ms) < 0) {
            if (errno == EINTR)
                continue;
            die("poll");
        }
        if (pf[0].revents) {
            stop = 1;
            break;
        }
        now = now_ns();
        pace(&ab, now);
        pace(&ba, now);
        if (pf[ia].revents & (POLLIN | POLLHUP | POLLERR) && (pf[ia].events & POLLIN))
            fill(&ab, ab_limit);
        if (ib >= 0 && pf[ib].revents & (POLLIN | POLLHUP | POLLERR) && (pf[ib].events & POLLIN))
            fill(&ba, sizeof ba.buf);
        if (ib >= 0 && (pf[ib].revents & POLLOUT))
            drain(&ab);
        if (pf[ia].revents & POLLOUT)
            drain(&ba);
    }
    const lane *ls[2] = {&ab, &ba};
    for (int i = 0; i < 2; i++) {
        const cm_fault_counts *c = &ls[i]->noise.n;
        fprintf(stderr,
                "pty_relay: %s moved=%llu dropped=%llu flipped=%llu inserted=%llu lost_unplugged=%llu faults=%s\n",
                ls[i]->label, ls[i]->moved, c->dropped, c->flipped, c->inserted, ls[i]->lost,
                ls[i]->faulty ? "on" : "off");
    }
    fprintf(stderr, "pty_relay: hangups=%d\n", hangups);
    if (a.link)
        unlink(a.link);
    if (b.link && b.master >= 0)
        unlink(b.link);
    return 0;
}
