/*
 * send_cmd.c - `cmz send`: move a model to a terminal over a serial line
 * or USB.  A .cmz is checked against the limits and format versions the
 * terminal announces in its HELLO; an IGES file is encoded for exactly
 * those limits first.  See link_send.h for the protocol side.
 */
#define _POSIX_C_SOURCE 200809L
#include "send_cmd.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cm_report.h"
#include "cm_transport_fd.h"
#include "cm_transport_serial.h"
#include "encode/encode.h"
#include "link_send.h"
#include "model_load.h"
#ifdef CM_HAVE_LIBUSB
#include "cm_transport_ffs.h"
#include "cm_transport_usb.h"
#endif

/* S_SIGNAL + the signal's number: stopped by SIGINT (130) or SIGTERM (143), as a shell reports a
   command a signal ended */
enum { S_OK = 0, S_INPUT = 1, S_USAGE = 2, S_LINK = 3, S_SIGNAL = 128 };

typedef struct send_ctx {
    const char *serial, *usb, *gadget;
    int use_stdio, quiet, tty;
    cm_serial ser;
    cm_fdlink fdl;
#ifdef CM_HAVE_LIBUSB
    cm_usb usb_t;
    cm_ffs ffs;
#endif
    int64_t t0;
    uint32_t last_done;
} send_ctx;

static volatile sig_atomic_t interrupted;
static void on_int(int sig)
{
    interrupted = sig;
}

static void send_usage(FILE *f)
{
    fprintf(f,
            "usage: cmz send MODEL.cmz|MODEL.igs|MODEL.stp (--serial DEV[:BAUD] | --usb VID:PID[:SERIAL] |\n"
            "                --gadget FFSDIR | --stdio) [--stay] [--no-wait] [--chunk N]\n"
            "                [--timeout S] [--tol REL] [-q]\n"
            "\n"
            "Send a model to a cmz-terminal.  The terminal announces its format versions and\n"
            "limits first: a .cmz it could not load is refused here, with the limit; an IGES\n"
            "or STEP model is encoded for exactly those limits (and for format 1 when the terminal is\n"
            "older).  Transfers survive noise, cable pulls and terminal restarts: they resume\n"
            "where the terminal's copy stops.  Shows a progress bar (bytes, rate, ETA) on a TTY.\n"
            "\n"
            "  --serial DEV[:BAUD]    serial line, raw 8N1 (default 115200)\n"
            "  --gadget FFSDIR        this machine is the USB device: FunctionFS mount set up by\n"
            "                         cmz-usb-gadget.sh (the terminal is the USB host)\n"
            "  --usb VID:PID[:SERIAL] this machine is the USB host (a host-to-host bridge cable)\n"
            "  --stdio                frames on stdin/stdout\n"
            "  --stay                 after sending, wait for the terminal's request button and\n"
            "                         send again each time it is pressed (until Ctrl-C)\n"
            "  --no-wait              stop when the terminal has stored the file (do not wait\n"
            "                         for its decode result)\n"
            "  --chunk N              first chunk size in bytes (default 1024 on serial, the\n"
            "                         terminal's maximum elsewhere; it adapts to the line)\n"
            "  --timeout S            give up finding the terminal after S seconds (default 30)\n"
            "  --tol REL              encoder tolerance for an IGES model (default 0.01)\n"
            "\n"
            "exit status: 0 stored and decoded on the terminal, 1 refused or not decodable there,\n"
            "             2 usage, 3 link failure (no terminal, cable, timeout, no progress),\n"
            "             130 / 143 stopped by SIGINT (Ctrl-C) / SIGTERM: within a second, the terminal\n"
            "             told (ABORT) and keeping what it holds, so the same command resumes there.\n");
}

static int open_transport(send_ctx *c, cm_transport **t)
{
    if (c->use_stdio) {
        if (cm_fd_open(&c->fdl, 0, 1, "stdio") != 0)
            return -1;
        *t = &c->fdl.t;
        return 0;
    }
    if (c->serial) {
        char dev[256];
        unsigned baud;
        if (cm_serial_parse(c->serial, dev, sizeof dev, &baud) != 0 || cm_serial_open(&c->ser, dev, baud) != 0)
            return -1;
        *t = &c->ser.t;
        return 0;
    }
#ifdef CM_HAVE_LIBUSB
    if (c->gadget) {
        if (cm_ffs_open(&c->ffs, c->gadget) != 0)
            return -1;
        *t = &c->ffs.t;
        return 0;
    }
    if (c->usb) {
        uint16_t vid, pid;
        char sn[64];
        if (cm_usb_parse(c->usb, &vid, &pid, sn, sizeof sn) != 0 || cm_usb_open(&c->usb_t, vid, pid, sn[0] ? sn : NULL) != 0)
            return -1;
        *t = &c->usb_t.t;
        return 0;
    }
#endif
    return -1;
}

static const char *open_error(send_ctx *c)
{
    if (c->serial)
        return c->ser.t.err;
#ifdef CM_HAVE_LIBUSB
    if (c->gadget)
        return c->ffs.t.err;
    if (c->usb)
        return c->usb_t.t.err;
#endif
    return c->fdl.t.err;
}

static int reopen_cb(void *ctx, cm_transport **t)
{
    return open_transport(ctx, t);
}

static void human(char *out, size_t cap, double bytes)
{
    if (bytes < 1024)
        snprintf(out, cap, "%.0f B", bytes);
    else if (bytes < 1024 * 1024)
        snprintf(out, cap, "%.1f KiB", bytes / 1024);
    else
        snprintf(out, cap, "%.2f MiB", bytes / (1024 * 1024));
}

static void progress_cb(void *ctx, uint32_t done, uint32_t total, uint32_t chunk)
{
    send_ctx *c = ctx;
    if (c->quiet || !c->tty)
        return;
    int64_t now = cm_link_now_ms();
    double s = (double)(now - c->t0) / 1000.0;
    double rate = s > 0.2 ? (double)(done - c->last_done) / s : 0;
    char a[32], b[32], r[32];
    human(a, sizeof a, done);
    human(b, sizeof b, total);
    human(r, sizeof r, rate);
    int pct = total ? (int)(100.0 * done / total) : 100;
    int bar = pct / 5;
    char eta[32] = "--";
    if (rate > 0 && done < total)
        snprintf(eta, sizeof eta, "%.0f s", (double)(total - done) / rate);
    fprintf(stderr, "\r[%.*s%*s] %3d%% %s / %s  %s/s  ETA %s  chunk %u \033[K", bar, "####################",
            20 - bar, "", pct, a, b, r, eta, chunk);
    if (done >= total)
        fputc('\n', stderr);
}

static void log_cb(void *ctx, const char *line)
{
    send_ctx *c = ctx;
    if (!c->quiet)
        fprintf(stderr, "%scmz send: %s\n", c->tty ? "\r\033[K" : "", line);
}

static int read_file(const char *path, uint8_t **data, uint32_t *size)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    struct stat s;
    if (fd < 0 || fstat(fd, &s) != 0) {
        fprintf(stderr, "cmz send: %s: %s\n", path, strerror(errno));
        if (fd >= 0)
            close(fd);
        return -1;
    }
    if (s.st_size <= 0 || s.st_size > 0x7fffffff) {
        fprintf(stderr, "cmz send: %s: %s\n", path, s.st_size <= 0 ? "empty file" : "larger than 2 GiB");
        close(fd);
        return -1;
    }
    *data = malloc((size_t)s.st_size);
    size_t got = 0;
    while (*data && got < (size_t)s.st_size) {
        ssize_t n = read(fd, *data + got, (size_t)s.st_size - got);
        if (n <= 0) {
            if (n < 0 && errno == EINTR)
                continue;
            fprintf(stderr, "cmz send: %s: %s\n", path, n < 0 ? strerror(errno) : "file shrank while read");
            free(*data);
            *data = NULL;
            break;
        }
        got += (size_t)n;
    }
    close(fd);
    if (!*data)
        return -1;
    *size = (uint32_t)got;
    return 0;
}

/* the terminal's limits as a profile table for the encoder and for the header check */
static void hello_table(const cm_link_hello *h, cm_limit_info *tab)
{
    for (unsigned i = 0; i < (unsigned)CM_LIMIT_COUNT; i++) {
        tab[i] = cm_limit_table[i];
        /* a limit an older terminal does not announce is not checked: its decoder has no such limit */
        tab[i].value = i < h->nlimits ? h->limit[i] : tab[i].hard_max;
    }
}

/* what can bring a model under the terminal's limit `id`: only the tessellation's own limits
   shrink with a coarser --tess; the others are the model's size (issue 11: the MAX_FILE_BYTES
   refusal used to suggest a coarser --tess, which makes the file no smaller) */
static const char *limit_hint(unsigned id)
{
    switch (id) {
    case CM_LIMIT_MAX_TRIS:
    case CM_LIMIT_MAX_TESS_POINTS:
    case CM_LIMIT_MAX_EDGE_SAMPLES:
        return "encode it again from the IGES with a coarser --tess, or use a larger board profile";
    case CM_LIMIT_STACK_FN_MAX:
    case CM_LIMIT_STACK_BUDGET:
        return "the terminal's build is older or smaller than this model needs: use a larger board profile";
    default:
        return "the model itself is larger than this terminal holds: split it, or use a larger board profile";
    }
}

/* would the terminal load this .cmz?  0 yes, else prints why */
static int check_cmz(const char *path, const uint8_t *b, uint32_t n, const cm_link_hello *h, const cm_limit_info *tab)
{
    if (n < CM_FMT_STREAM_MIN_HEADER + 4u || b[0] != 0x89 || b[1] != 'C' || b[2] != 'M' || b[3] != 'Z') {
        fprintf(stderr, "cmz send: %s: not a .cmz file (give a .cmz, or an IGES or STEP model to encode)\n", path);
        return -1;
    }
    if (b[4] > h->fmt_major_max || b[4] < h->fmt_major_min || (b[4] == h->fmt_major_max && b[5] > h->fmt_minor_max)) {
        fprintf(stderr,
                "cmz send: %s: format %u.%u, terminal '%s' reads %u.x to %u.%u: encode it again from the IGES "
                "(cmz send MODEL.igs does this for the terminal)\n",
                path, b[4], b[5], h->name, h->fmt_major_min, h->fmt_major_max, h->fmt_minor_max);
        return -1;
    }
    uint32_t need[CM_LIMIT_COUNT], nneed = 0;
    if (!cm_fmt_header_needs(b, n, need, CM_LIMIT_COUNT, &nneed))
        return 0; /* malformed: the terminal's decoder will say so */
    for (unsigned i = 0; i < nneed && i < (unsigned)CM_LIMIT_COUNT; i++) {
        if (need[i] > tab[i].value) {
            fprintf(stderr,
                    "cmz send: %s: refused before sending: the model needs %s=%u, terminal '%s' has %u (%s)\n",
                    path, tab[i].name, (unsigned)need[i], h->name, (unsigned)tab[i].value, limit_hint(i));
            return -1;
        }
    }
    return 0;
}

static int is_model(const char *path)
{
    const char *dot = strrchr(path, '.');
    return (dot && (strcasecmp(dot, ".igs") == 0 || strcasecmp(dot, ".iges") == 0 || strcasecmp(dot, ".stp") == 0 ||
                    strcasecmp(dot, ".step") == 0)) ||
           model_file_is_step(path); /* a CAD model (IGES or STEP) to encode, not a .cmz */
}

/* encode a CAD model (IGES or STEP) for the terminal; 0 with the bytes in data, size (malloc'd) */
static int encode_for(const char *path, const cm_link_hello *h, const cm_limit_info *tab, double tol, int quiet,
                      uint8_t **data, uint32_t *size)
{
    loaded_model lm;
    cm_status st;
    cm_status_init(&st);
    encode_opts o;
    encode_opts_default(&o);
    o.target = tab;
    o.target_name = h->name;
    if (tol > 0) {
        o.rel_tol = tol;
        o.rel_set = 1;
    }
    encode_opts_for_format(&o, h->fmt_major_max, h->fmt_minor_max); /* what the terminal reads */
    /* a part placed several times travels once where the terminal reads format 4.3 */
    if (model_load_ex(path, &lm, encode_places(&o) ? MODEL_LOAD_FOLD : 0, NULL, NULL, &st) != CM_OK) {
        cm_report_status(stderr, "cmz send", path, &st);
        model_free(&lm);
        return -1;
    }
    encode_result r;
    cm_status_init(&st);
    cm_err e = encode_model(&lm, &o, &r, &st);
    if (e == CM_E_LIMIT && st.limit == CM_LIMIT_MAX_PLACEMENTS && lm.brep.nplacements > 0) {
        /* more copies than the terminal places: every face sent as its own (a whole-model limit
           is the only kind that may refuse, and MAX_FACES counts the copies either way) */
        encode_result_free(&r);
        model_free(&lm);
        cm_status_init(&st);
        if (model_load(path, &lm, NULL, NULL, &st) != CM_OK) {
            cm_report_status(stderr, "cmz send", path, &st);
            model_free(&lm);
            return -1;
        }
        if (!quiet)
            fprintf(stderr, "cmz send: %s: '%s' places at most %u copies: every placed face sent as a face\n", path,
                    h->name, (unsigned)tab[CM_LIMIT_MAX_PLACEMENTS].value);
        e = encode_model(&lm, &o, &r, &st);
    }
    int rc = 0;
    if (e == CM_E_LIMIT && r.refusal[0]) {
        fprintf(stderr, "cmz send: %s: refused before sending: %s\n", path, r.refusal);
        rc = -1;
    } else if (e != CM_OK) {
        cm_report_status(stderr, "cmz send", path, &st);
        rc = -1;
    } else {
        *data = malloc(r.len);
        if (!*data) {
            rc = -1;
        } else {
            memcpy(*data, r.bytes, r.len);
            *size = (uint32_t)r.len;
            char methods[128];
            if (!quiet)
                fprintf(stderr, "cmz send: %s encoded for '%s': %zu bytes (%s)\n", path, h->name, r.len,
                        cm_report_method_counts(methods, sizeof methods, r.faces_by_method, 0));
        }
    }
    encode_result_free(&r);
    model_free(&lm);
    return rc;
}

static int report(const link_send_result *r, int rc, const char *name, uint32_t size, int64_t ms, int quiet)
{
    if (rc == 0) {
        if (!quiet)
        {
            char resumed[64] = "";
            if (r->resumes)
                snprintf(resumed, sizeof resumed, ", resumed at %u", (unsigned)r->resume_offset);
            printf("%s: %u bytes delivered in %.1f s (%llu chunks, %llu sent again, %u reconnects%s): %s\n", name,
                   (unsigned)size, (double)ms / 1000.0, (unsigned long long)r->chunks_sent,
                   (unsigned long long)r->chunks_resent, r->reconnects, resumed, r->text);
        }
        return S_OK;
    }
    if (rc == LINK_SEND_STOPPED) {
        if (!quiet)
            fprintf(stderr, "cmz send: %s: stopped; the terminal keeps the %u bytes it holds (send again to resume)\n",
                    name, (unsigned)r->held);
        return S_SIGNAL + (int)interrupted;
    }
    fprintf(stderr, "cmz send: %s: %s\n", name, r->text);
    return rc > 0 ? S_INPUT : S_LINK;
}

int cmz_cmd_send(int argc, char **argv)
{
    static send_ctx c;
    const char *path = NULL;
    link_send_opts o;
    link_send_defaults(&o);
    int stay = 0;
    double tol = 0;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            send_usage(stdout);
            return S_OK;
        } else if (strcmp(a, "--serial") == 0 && v)
            c.serial = argv[++i];
        else if (strcmp(a, "--usb") == 0 && v)
            c.usb = argv[++i];
        else if (strcmp(a, "--gadget") == 0 && v)
            c.gadget = argv[++i];
        else if (strcmp(a, "--stdio") == 0)
            c.use_stdio = 1;
        else if (strcmp(a, "--stay") == 0)
            stay = 1;
        else if (strcmp(a, "--no-wait") == 0)
            o.wait_decoded = 0;
        else if (strcmp(a, "-q") == 0)
            c.quiet = 1;
        else if ((strcmp(a, "--chunk") == 0 || strcmp(a, "--timeout") == 0 || strcmp(a, "--tol") == 0) && v) {
            char *end;
            double x = strtod(argv[++i], &end);
            int bad = *end != '\0';
            if (strcmp(a, "--chunk") == 0) {
                bad = bad || x < 16 || x > CM_LINK_MAX_PAYLOAD - 4;
                o.chunk = (uint32_t)x;
            } else if (strcmp(a, "--timeout") == 0) {
                bad = bad || x < 1 || x > 86400;
                o.connect_timeout_ms = (int)(x * 1000);
            } else {
                bad = bad || x < 1e-9 || x > 0.5;
                tol = x;
            }
            if (bad) {
                fprintf(stderr, "cmz send: bad value '%s' for %s (cmz send --help)\n", argv[i], a);
                return S_USAGE;
            }
        } else if (a[0] == '-' || path) {
            fprintf(stderr, "cmz send: unexpected argument '%s' (cmz send --help)\n", a);
            return S_USAGE;
        } else {
            path = a;
        }
    }
    int links = !!c.serial + !!c.usb + !!c.gadget + c.use_stdio;
    if (!path || links != 1) {
        send_usage(stderr);
        return S_USAGE;
    }
#ifndef CM_HAVE_LIBUSB
    if (c.usb || c.gadget) {
        fprintf(stderr, "cmz send: this build has no USB support (libusb-1.0 was not found at build time)\n");
        return S_USAGE;
    }
#endif
    if (c.serial) {
        char dev[256];
        if (cm_serial_parse(c.serial, dev, sizeof dev, &o.baud) != 0) {
            fprintf(stderr, "cmz send: bad --serial '%s': DEV[:BAUD]\n", c.serial);
            return S_USAGE;
        }
    }
    c.tty = isatty(2) && !c.use_stdio;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_int;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sa.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &sa, NULL);

    uint8_t *data = NULL;
    uint32_t size = 0;
    if (!is_model(path) && read_file(path, &data, &size) != 0)
        return S_INPUT;
    cm_transport *t = NULL;
    if (open_transport(&c, &t) != 0) {
        fprintf(stderr, "cmz send: %s\n", open_error(&c));
        free(data);
        return S_LINK;
    }
    static cm_link link;
    cm_link_init(&link, t);
    o.reopen = reopen_cb;
    o.reopen_ctx = &c;
    o.hangup_keeps_transport = c.gadget != NULL;
    o.progress = progress_cb;
    o.progress_ctx = &c;
    o.log = log_cb;
    o.log_ctx = &c;
    o.stop = &interrupted;
    link_send_result r;
    memset(&r, 0, sizeof r);
    cm_link_hello h;
    if (link_send_connect(&link, &o, &h, &r) != 0) {
        fprintf(stderr, "cmz send: %s\n", r.text);
        link.t->close(link.t);
        free(data);
        return interrupted ? S_SIGNAL + (int)interrupted : S_LINK;
    }
    if (!c.quiet)
        fprintf(stderr, "cmz send: terminal '%s' on %s: format %u.x-%u.%u, up to %u bytes per chunk\n", h.name,
                link.t->name, h.fmt_major_min, h.fmt_major_max, h.fmt_minor_max, h.max_payload);
    static cm_limit_info tab[CM_LIMIT_COUNT];
    hello_table(&h, tab);
    int rc;
    if (is_model(path)) {
        rc = encode_for(path, &h, tab, tol, c.quiet, &data, &size) == 0 ? S_OK : S_INPUT;
    } else {
        rc = check_cmz(path, data, size, &h, tab) == 0 ? S_OK : S_INPUT;
    }
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    char name[CM_LINK_MAX_NAME + 1];
    snprintf(name, sizeof name, "%s", base);
    if (is_model(path)) {
        char *dot = strrchr(name, '.');
        if (dot && (size_t)(dot - name) + 4 <= CM_LINK_MAX_NAME)
            strcpy(dot, ".cmz");
    }
    o.hello = &h;
    o.hello_rtt_ms = r.connect_rtt_ms;
    o.hello_tries = r.connect_tries;
    while (rc == S_OK && !interrupted) {
        c.t0 = cm_link_now_ms();
        c.last_done = 0;
        int s = link_send_file(&link, data, size, name, &o, &r);
        rc = report(&r, s, name, size, cm_link_now_ms() - c.t0, c.quiet);
        if (!stay || rc != S_OK)
            break;
        if (!c.quiet)
            fprintf(stderr, "cmz send: waiting for the terminal's request button (Ctrl-C to stop)\n");
        int again = 0;
        while (!again && !interrupted) {
            cm_link_frame f;
            int g = cm_link_recv(&link, &f, 500);
            if (g == CM_T_HANGUP && c.gadget) {
                cm_link_init(&link, link.t); /* the gadget waits for the host by itself */
            } else if (g == CM_T_HANGUP) {
                cm_transport *nt;
                link.t->close(link.t);
                while (!interrupted && open_transport(&c, &nt) != 0)
                    sleep(1);
                if (!interrupted)
                    cm_link_init(&link, nt);
            } else if (g < 0) {
                fprintf(stderr, "cmz send: %s\n", link.t->err);
                rc = S_LINK;
                break;
            } else if (g > 0 && f.type == CM_LINK_REQUEST) {
                if (!c.quiet)
                    fprintf(stderr, "cmz send: the terminal asks for the model again\n");
                again = 1;
            }
        }
        if (!again)
            break;
    }
    if (interrupted && rc == S_OK && stay)
        rc = S_OK; /* --stay ends with Ctrl-C: that is how it is stopped */
    else if (interrupted && rc < S_SIGNAL)
        rc = S_SIGNAL + (int)interrupted;
    link.t->close(link.t);
    free(data);
    return rc;
}
