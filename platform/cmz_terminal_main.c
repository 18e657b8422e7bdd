/*
 * cmz-terminal - the shop-floor terminal's daemon: receives models over a
 * serial line or USB, decodes them with the heap-free decoder into the
 * directory the viewer watches, and shows what it is doing on GPIO lines.
 *
 *   cmz-terminal --serial DEV[:BAUD] | --usb VID:PID[:SERIAL] | --stdio
 *                --out DIR [options]          (cmz-terminal --help)
 *
 * Data flow: link frames -> .incoming.part (resumable) -> CRC verified ->
 * .incoming.cmz -> decoder (fed as the bytes arrived) -> a new generation
 * DIR/.gen-N (model.glb, model.stl, model.cmz) -> one rename of the symlink
 * DIR/current shows it (cm_term_store.h).  The previous model stays on
 * screen until the new one is complete and decoded; a power cut at any
 * point leaves either the old model or the new one, never half of one or
 * a mix, and a restart finishes a verified file that was not yet shown.
 * CM_TERM_KILL_AT=STEP kills the daemon at a step of that (cm_kill_point.h).
 *
 * Exit status: 0 stopped by SIGTERM/SIGINT (or --once and the model
 * decoded), 1 --once and the model was refused or failed to decode,
 * 2 usage or configuration error, 3 the output directory or the device
 * cannot be used, 4 a GPIO line cannot be used.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "cm/cm_decode_state.h"
#include "cm_clock.h"
#include "cm_decode_file.h"
#include "cm_gpio.h"
#include "cm_kill_point.h"
#include "cm_link_term.h"
#include "cm_report.h"
#include "cm_term_store.h"
#include "cm_transport_fd.h"
#include "cm_transport_serial.h"
#ifdef CM_HAVE_LIBUSB
#include "cm_transport_usb.h"
#endif

#define PROG "cmz-terminal"

/* everything big is static: the decode path never touches the heap */
static cm_decode_state state;
static cm_link_term term;
static cm_term_store store;
static cm_serial serial;
static cm_fdlink stdio_link;
#ifdef CM_HAVE_LIBUSB
static cm_usb usb;
#endif
static cm_gpio gpio;

static volatile sig_atomic_t stop_signal;
static int quiet;

/* at most this many viewer options after -- */
#define VIEW_ARGS_MAX 16

typedef struct config {
    char serial[256], usb[128], out[CM_TERM_PATH], name[CM_LINK_MAX_NAME + 1];
    char display[256], viewer[256]; /* --display DEV: the viewer program draws each model there */
    char gpio_spec[CM_GPIO_NOUT + 1][128];
    int use_stdio, stl, once, ready_pulse_ms;
    double tess;
    char **view_args; /* after --: more options for the viewer of a model (its buttons) */
    int nview_args;
} config;

static void on_signal(int sig)
{
    stop_signal = sig;
}

/* one greppable line per event: "cmz-terminal: level=info event=stored name=x bytes=1234" */
__attribute__((format(printf, 3, 4))) static void logline(const char *level, const char *event, const char *fmt, ...)
{
    if (quiet && strcmp(level, "info") == 0)
        return;
    char rest[600] = "";
    if (fmt) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(rest, sizeof rest, fmt, ap);
        va_end(ap);
    }
    fprintf(stderr, PROG ": level=%s event=%s%s%s\n", level, event, rest[0] ? " " : "", rest);
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: " PROG " (--serial DEV[:BAUD] | --usb VID:PID[:SERIAL] | --stdio) --out DIR [options]\n"
            "       " PROG " ... --display DEV [-- VIEWER-OPTION...]\n"
            "       " PROG " --limits | --version | --help\n"
            "\n"
            "Receive curvemesh models from `cmz send`, decode each into DIR/model.glb (atomically) and\n"
            "keep the last good one on screen.  Interrupted transfers resume where they stopped.\n"
            "\n"
            "link (one of):\n"
            "  --serial DEV[:BAUD]    a serial line in raw mode, 8N1, default 115200 baud\n"
            "  --usb VID:PID[:SERIAL] the workstation's USB gadget (hex ids), bulk endpoints via libusb\n"
            "  --stdio                frames on stdin/stdout (tests, socat)\n"
            "options:\n"
            "  --out DIR              directory the viewer watches (model.glb, model.cmz)\n"
            "  --stl                  also write DIR/model.stl\n"
            "  --name NAME            terminal name announced to the sender (default: host name)\n"
            "  --tess MM              chordal tolerance (default: the file's recommendation)\n"
            "  --gpio-busy SPEC       output, active while receiving or decoding\n"
            "  --gpio-ready SPEC      output, pulsed when a new model is on screen\n"
            "  --gpio-error SPEC      output, active after a refused or failed model until the next good one\n"
            "  --gpio-request SPEC    input (button), a rising edge asks the workstation to send again\n"
            "  --ready-pulse-ms N     length of the ready pulse (default 500)\n"
            "  --display DEV          show each model and a status line on the framebuffer DEV\n"
            "                         (/dev/fb0) or DRM device (/dev/dri/card0: one viewer for the\n"
            "                         whole run, cmz-view --serve; auto: a DRM screen, else fb0)\n"
            "                         with --viewer PROG (cmz-view);\n"
            "                         options after -- go to the viewer (its buttons, e.g.\n"
            "                         -- --gpio-next gpiochip0:5)\n"
            "  --config FILE          read 'key = value' lines (the long options without --) first\n"
            "  --once                 exit after the first model (status 0 decoded, 1 not)\n"
            "  -q                     only warnings and errors\n"
            "environment: CM_TERM_KILL_AT=STEP  SIGKILL at that step of storing a model (tests)\n"
            "             CM_TERM_FREE_BYTES=N  the output directory looks N bytes free at an offer (tests)\n"
            "GPIO SPEC: CHIP:LINE, CHIP a name (gpiochip0), path or label, LINE a name or offset;\n"
            "           a leading '!' makes the line active-low.\n"
            "\n"
            "Log lines on stderr: '" PROG ": level=L event=E key=value...'.\n"
            "exit status: 0 stopped by SIGTERM/SIGINT (or --once, decoded), 1 --once and the model\n"
            "failed, 2 usage or configuration, 3 output directory or device unusable, 4 GPIO.\n");
}

static int set_opt(config *c, const char *key, const char *val, const char *where)
{
    static const char *const gpio_keys[CM_GPIO_NOUT + 1] = {"gpio-busy", "gpio-ready", "gpio-error", "gpio-request"};
    for (int i = 0; i <= CM_GPIO_NOUT; i++)
        if (strcmp(key, gpio_keys[i]) == 0) {
            snprintf(c->gpio_spec[i], sizeof c->gpio_spec[i], "%s", val);
            return 0;
        }
    if (strcmp(key, "serial") == 0)
        snprintf(c->serial, sizeof c->serial, "%s", val);
    else if (strcmp(key, "usb") == 0)
        snprintf(c->usb, sizeof c->usb, "%s", val);
    else if (strcmp(key, "out") == 0)
        snprintf(c->out, sizeof c->out, "%s", val);
    else if (strcmp(key, "name") == 0)
        snprintf(c->name, sizeof c->name, "%s", val);
    else if (strcmp(key, "display") == 0)
        snprintf(c->display, sizeof c->display, "%s", val);
    else if (strcmp(key, "viewer") == 0)
        snprintf(c->viewer, sizeof c->viewer, "%s", val);
    else if (strcmp(key, "ready-pulse-ms") == 0) {
        char *end;
        long v = strtol(val, &end, 10);
        if (*end || v < 1 || v > 60000) {
            fprintf(stderr, PROG ": %s: ready-pulse-ms wants 1..60000, not '%s'\n", where, val);
            return -1;
        }
        c->ready_pulse_ms = (int)v;
    } else if (strcmp(key, "tess") == 0) {
        char *end;
        c->tess = strtod(val, &end);
        if (*end || !(c->tess > 0)) {
            fprintf(stderr, PROG ": %s: tess wants a positive number of millimetres, not '%s'\n", where, val);
            return -1;
        }
    } else if (strcmp(key, "stl") == 0 || strcmp(key, "stdio") == 0 || strcmp(key, "once") == 0) {
        int on = strcmp(val, "1") == 0 || strcmp(val, "yes") == 0 || strcmp(val, "true") == 0;
        if (!on && strcmp(val, "0") && strcmp(val, "no") && strcmp(val, "false")) {
            fprintf(stderr, PROG ": %s: %s wants yes or no, not '%s'\n", where, key, val);
            return -1;
        }
        int *flag = strcmp(key, "stl") == 0 ? &c->stl : strcmp(key, "stdio") == 0 ? &c->use_stdio : &c->once;
        *flag = on;
    } else {
        fprintf(stderr, PROG ": %s: unknown setting '%s'\n", where, key);
        return -1;
    }
    return 0;
}

/* the config file: '# comments', blank lines, 'key = value' */
static int read_config(config *c, const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, PROG ": cannot read config %s: %s\n", path, strerror(errno));
        return -1;
    }
    char line[512];
    int n = 0, rc = 0;
    while (fgets(line, sizeof line, f)) {
        n++;
        char *s = line;
        while (*s == ' ' || *s == '\t')
            s++;
        size_t len = strlen(s);
        while (len && (s[len - 1] == '\n' || s[len - 1] == '\r' || s[len - 1] == ' ' || s[len - 1] == '\t'))
            s[--len] = '\0';
        if (!*s || *s == '#')
            continue;
        char *eq = strchr(s, '=');
        char where[600];
        snprintf(where, sizeof where, "%s:%d", path, n);
        if (!eq) {
            fprintf(stderr, PROG ": %s: expected 'key = value'\n", where);
            rc = -1;
            break;
        }
        char *k_end = eq;
        while (k_end > s && (k_end[-1] == ' ' || k_end[-1] == '\t'))
            k_end--;
        *k_end = '\0';
        char *v = eq + 1;
        while (*v == ' ' || *v == '\t')
            v++;
        if (set_opt(c, s, v, where) != 0) {
            rc = -1;
            break;
        }
    }
    fclose(f);
    return rc;
}

static int parse_args(config *c, int argc, char **argv)
{
    for (int i = 1; i < argc; i++) /* the config file first, so the command line wins */
        if (strcmp(argv[i], "--config") == 0) {
            if (i + 1 >= argc || read_config(c, argv[i + 1]) != 0)
                return -1;
        }
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--config") == 0) {
            i++;
        } else if (strcmp(a, "--") == 0) {
            if (argc - i - 1 > VIEW_ARGS_MAX) {
                fprintf(stderr, PROG ": at most %d viewer options after --, not %d\n", VIEW_ARGS_MAX, argc - i - 1);
                return -1;
            }
            c->view_args = argv + i + 1;
            c->nview_args = argc - i - 1;
            break;
        } else if (strcmp(a, "-q") == 0) {
            quiet = 1;
        } else if (strcmp(a, "--stl") == 0 || strcmp(a, "--stdio") == 0 || strcmp(a, "--once") == 0) {
            if (set_opt(c, a + 2, "yes", "command line") != 0)
                return -1;
        } else if (strncmp(a, "--", 2) == 0 && i + 1 < argc) {
            if (set_opt(c, a + 2, argv[++i], "command line") != 0)
                return -1;
        } else {
            fprintf(stderr, PROG ": unexpected argument '%s'\n", a);
            return -1;
        }
    }
    int links = (c->serial[0] != 0) + (c->usb[0] != 0) + (c->use_stdio != 0);
    if (links != 1 || !c->out[0]) {
        fprintf(stderr, PROG ": %s\n", links != 1 ? "give exactly one of --serial, --usb, --stdio" : "--out DIR is required");
        return -1;
    }
    return 0;
}

static cm_transport *open_link(const config *c, int *fatal)
{
    *fatal = 0;
    if (c->use_stdio) {
        if (cm_fd_open(&stdio_link, 0, 1, "stdio") != 0) {
            *fatal = 1;
            logline("error", "link", "link=stdio why=\"%s\"", stdio_link.t.err);
            return NULL;
        }
        return &stdio_link.t;
    }
    if (c->serial[0]) {
        char dev[256];
        unsigned baud;
        if (cm_serial_parse(c->serial, dev, sizeof dev, &baud) != 0) {
            *fatal = 1;
            logline("error", "config", "why=\"bad --serial '%s'\"", c->serial);
            return NULL;
        }
        if (cm_serial_open(&serial, dev, baud) != 0)
            return NULL;
        return &serial.t;
    }
#ifdef CM_HAVE_LIBUSB
    uint16_t vid, pid;
    char sn[64];
    if (cm_usb_parse(c->usb, &vid, &pid, sn, sizeof sn) != 0) {
        *fatal = 1;
        logline("error", "config", "why=\"bad --usb '%s'\"", c->usb);
        return NULL;
    }
    if (cm_usb_open(&usb, vid, pid, sn[0] ? sn : NULL) != 0)
        return NULL;
    return &usb.t;
#else
    *fatal = 1;
    logline("error", "config", "why=\"this build has no USB support (libusb-1.0 was not found at build time)\"");
    return NULL;
#endif
}

static const char *open_error(const config *c)
{
    if (c->serial[0])
        return serial.t.err;
#ifdef CM_HAVE_LIBUSB
    if (c->usb[0])
        return usb.t.err;
#endif
    return stdio_link.t.err;
}

/* snprintf into a message buffer, where cutting a long path short is fine */
__attribute__((format(printf, 3, 4))) static void textf(char *out, size_t cap, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(out, cap, fmt, ap);
    va_end(ap);
}

static void nap_ms(int ms)
{
    struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

/* the viewer drawing the model on the display (issue 17): a program of its own (cmz-view), so that
   the daemon's code and RAM stay within their budgets; 0 when none runs */
static pid_t viewer_pid;
/* a DRM display (/dev/dri/cardN): its screen shows a buffer only while the process that made it
   holds the device, and one process at a time, so one viewer serves the whole run (cmz-view
   --serve), told what to show through a pipe (viewer_in, -1 when none runs); a framebuffer (fbdev)
   keeps its pixels, and gets a viewer per picture */
static int display_drm, viewer_in = -1;

static int is_drm_device(const char *dev)
{
    struct stat s;
    return stat(dev, &s) == 0 && S_ISCHR(s.st_mode) && major(s.st_rdev) == 226;
}

/* reap the viewers that have finished (wait: block until every one has: a status line still being
   drawn must not land over a newer picture), logging a failure */
static void viewer_reap(int wait)
{
    int status = 0;
    pid_t p;
    while ((p = waitpid(-1, &status, wait ? 0 : WNOHANG)) > 0) {
        if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
            logline("warn", "display", "status=%d", WIFEXITED(status) ? WEXITSTATUS(status) : -1);
        if (p == viewer_pid) {
            viewer_pid = 0;
            if (viewer_in >= 0) /* (the serving viewer went: the next picture starts another) */
                close(viewer_in);
            viewer_in = -1;
        }
    }
}

/* start the serving viewer of a DRM display (its buttons from the options after --) */
static void serve_start(const config *c)
{
    const char *prog = c->viewer[0] ? c->viewer : "cmz-view";
    int fds[2];
    if (pipe(fds) != 0) {
        logline("warn", "display", "why=pipe");
        return;
    }
    pid_t pid = fork();
    if (pid == 0) {
        dup2(fds[0], 0);
        close(fds[0]);
        close(fds[1]);
        const char *av[VIEW_ARGS_MAX + 8] = {prog, "--fb", c->display, "--serve"};
        int k = 4;
        for (int i = 0; i < c->nview_args; i++)
            av[k++] = c->view_args[i];
        av[k] = NULL;
        execvp(prog, (char *const *)av);
        _exit(127);
    }
    close(fds[0]);
    if (pid < 0) {
        close(fds[1]);
        logline("warn", "display", "why=fork");
        return;
    }
    (void)fcntl(fds[1], F_SETFD, FD_CLOEXEC);
    viewer_pid = pid;
    viewer_in = fds[1];
}

/* a command line to the serving viewer (started when none runs; once more when it has gone) */
static void serve_send(const config *c, const char *line)
{
    for (int attempt = 0; attempt < 2; attempt++) {
        if (viewer_in < 0)
            serve_start(c);
        if (viewer_in < 0)
            return;
        size_t n = strlen(line), done = 0;
        while (done < n) {
            ssize_t k = write(viewer_in, line + done, n - done);
            if (k < 0 && errno == EINTR)
                continue;
            if (k <= 0)
                break;
            done += (size_t)k;
        }
        if (done == n)
            return;
        logline("warn", "display", "why=viewer-gone");
        close(viewer_in); /* (EPIPE: the viewer ended; reaped by viewer_reap) */
        viewer_in = -1;
        if (viewer_pid > 0)
            kill(viewer_pid, SIGTERM);
        viewer_reap(1);
    }
}

/* run the viewer: model (NULL: the status line alone) with the status line text, a model's with the
   options after -- (its buttons: such a viewer stays until stopped); its pid */
static pid_t viewer_run(const config *c, const char *model, const char *text)
{
    const char *prog = c->viewer[0] ? c->viewer : "cmz-view";
    pid_t pid = fork();
    if (pid == 0) {
        const char *av[VIEW_ARGS_MAX + 8] = {prog, "--fb", c->display, "--status", text};
        int k = 5;
        if (model) {
            av[k++] = model;
            av[k++] = "-q";
            for (int i = 0; i < c->nview_args; i++)
                av[k++] = c->view_args[i];
        }
        av[k] = NULL;
        execvp(prog, (char *const *)av);
        _exit(127);
    }
    if (pid < 0)
        logline("warn", "display", "why=fork");
    return pid > 0 ? pid : 0;
}

/* draw DIR/current/model.cmz on the display with the status text: a viewer still drawing an older
   model is stopped first */
static void show_current(const config *c, const char *text)
{
    if (!c->display[0])
        return;
    if (display_drm) { /* the serving viewer keeps the old picture until the new one is drawn */
        if (strpbrk(c->out, "\t\n")) {
            logline("warn", "display", "why=\"the output directory's name holds a tab or a newline\"");
            return;
        }
        char line[CM_TERM_PATH + CM_LINK_MAX_TEXT + 64];
        snprintf(line, sizeof line, "model %s/current/model.cmz\t%s\n", c->out, text);
        char path[CM_TERM_PATH + 32];
        snprintf(path, sizeof path, "%s/current/model.cmz", c->out);
        if (access(path, R_OK) == 0)
            serve_send(c, line);
        return;
    }
    if (viewer_pid > 0)
        kill(viewer_pid, SIGTERM);
    viewer_reap(1);
    char path[CM_TERM_PATH + 32];
    snprintf(path, sizeof path, "%s/current/model.cmz", c->out);
    if (access(path, R_OK) == 0) /* (nothing stored yet: nothing to show) */
        viewer_pid = viewer_run(c, path, text);
}

/* the status line alone (receiving, refused, failed), over the model on the screen */
static void show_status(const config *c, const char *name, const char *what)
{
    if (!c->display[0])
        return;
    char text[CM_LINK_MAX_TEXT + CM_LINK_MAX_NAME + 8];
    snprintf(text, sizeof text, "%s: %s", name, what);
    if (display_drm) {
        /* one command a line: the sender's name may hold any byte, a newline included, which would
           start a command of its own (show another file): control bytes go as '?' */
        for (char *p = text; *p; p++)
            if ((unsigned char)*p < 32 || *p == 127)
                *p = '?';
        char line[sizeof text + 16];
        snprintf(line, sizeof line, "status %s\n", text);
        serve_send(c, line);
        return;
    }
    (void)viewer_run(c, NULL, text);
}

/* decode .incoming.cmz (fed: already fed to the decoder as it arrived) and show it; 0 ok */
static int decode_into_place(const config *c, int fed, char *text, size_t cap)
{
    static cm_mesh mesh;
    mesh = cm_decode_stream_mesh(&state, c->out, 1);
    cm_status st;
    cm_status_init(&st);
    cm_decode_summary sum;
    uint64_t bytes = 0;
    char bad[CM_TERM_PATH + 16];
    snprintf(bad, sizeof bad, "%s/rejected.cmz", c->out);
    int64_t t0 = cm_clock_ms();
    cm_err e;
    if (fed && state.dec.file_len <= (uint32_t)CM_FILE_WINDOW_BYTES) { /* held whole as it came */
        e = cm_dec_finish(&state.dec, &st);
    } else if (fed) { /* its bytes were checked as they came; its sections are read again from the file */
        static int fd;
        fd = open(term.in_path, O_RDONLY | O_CLOEXEC);
        if (fd < 0) {
            e = cm_fail(&st, CM_E_IO, "open the received file");
            st.sys_errno = errno;
        } else {
            cm_dec_set_source(&state.dec, cm_decode_pread, &fd);
            e = cm_dec_finish(&state.dec, &st);
            close(fd);
        }
    } else {
        e = cm_decode_read(term.in_path, &state.dec, &st);
    }
    if (e == CM_OK)
        e = cm_decode_mesh(&state.dec, c->tess, &mesh, &state.tess, &sum, &st);
    if (e == CM_OK)
        e = cm_term_store_install(&store, &mesh, term.in_path, &bytes, &st);
    cm_decode_spill_close(); /* the mesh is in the store, or gone */
    if (e != CM_OK) {
        /* the model on screen is untouched (the store changes nothing until its one rename) */
        cm_format_status(text, cap, &st);
        if (rename(term.in_path, bad) != 0)
            unlink(term.in_path);
        return st.code ? (int)st.code : 1;
    }
    /* one bad face never sinks a model: the others are shown, and each one left out is logged */
    for (uint32_t i = 0; i < sum.faces_left_out && i < CM_DECODE_LEFT_OUT_LIST; i++) {
        char why[256];
        cm_format_status(why, sizeof why, &sum.left_out[i]);
        logline("warn", "decode", "face left out: %s", why);
    }
    /* short: on a noisy line a long DONE rarely arrives whole (the log line has the details) */
    if (sum.faces_left_out)
        textf(text, cap, "%u faces, %u triangles, %u left out", sum.faces, sum.triangles, sum.faces_left_out);
    else
        textf(text, cap, "%u faces, %u triangles", sum.faces, sum.triangles);
    char methods[128];
    cm_report_method_counts(methods, sizeof methods, sum.faces_by_method, 1);
    logline("info", "decode", "faces=%u %s left_out=%u triangles=%u glb_bytes=%llu ms=%lld", sum.faces, methods,
            sum.faces_left_out, sum.triangles, (unsigned long long)bytes, (long long)(cm_clock_ms() - t0));
    return 0;
}

int main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return 0;
        }
        if (strcmp(argv[i], "--limits") == 0) {
            cm_report_limits(stdout);
            const cm_ram_part own[] = {
                {"  link", "the link's frames, paths and state", sizeof term},
                {"  store", "the displayed model's store", sizeof store},
                {"  transports", "the serial line and stdio links", sizeof serial + sizeof stdio_link},
#ifdef CM_HAVE_LIBUSB
                {"  usb", "the USB transport", sizeof usb},
#endif
                {"  gpio", "the GPIO lines", sizeof gpio},
                {"  I/O chunks", "the reader's and the writer's chunks, the mesh spill's files", cm_decode_file_static_bytes()}};
            cm_report_program_ram(stdout, own, sizeof own / sizeof own[0]);
            return 0;
        }
        if (strcmp(argv[i], "--version") == 0) {
            printf(PROG " 0.1.0 (link protocol %d, format %d.%d, profile %s)\n", CM_LINK_PROTO, CM_FMT_VERSION_MAJOR,
                   CM_FMT_VERSION_MINOR, cm_profile_name);
            return 0;
        }
    }
    static config c;
    c.ready_pulse_ms = 500;
    if (parse_args(&c, argc, argv) != 0) {
        fprintf(stderr, "Try '" PROG " --help'.\n");
        return 2;
    }
    if (!c.name[0] && gethostname(c.name, sizeof c.name - 1) != 0)
        snprintf(c.name, sizeof c.name, "terminal");
    /* (auto: the viewer picks a DRM device, else the framebuffer; served either way) */
    display_drm = c.display[0] && (strcmp(c.display, "auto") == 0 || is_drm_device(c.display));

    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal; /* no SA_RESTART: a blocking poll returns and the loop sees the flag */
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    sa.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &sa, NULL);

    cm_gpio_config gc = {.consumer = PROG};
    for (int i = 0; i < CM_GPIO_NOUT; i++)
        gc.out[i] = c.gpio_spec[i][0] ? c.gpio_spec[i] : NULL;
    gc.request = c.gpio_spec[CM_GPIO_NOUT][0] ? c.gpio_spec[CM_GPIO_NOUT] : NULL;
    if (cm_gpio_open(&gpio, &gc) != 0) {
        logline("error", "gpio", "why=\"%s\"", gpio.err);
        return 4;
    }
    if (cm_link_term_open(&term, &state.dec, c.out, c.name) != 0) {
        logline("error", "output", "why=\"%s\"", term.why);
        cm_gpio_close(&gpio);
        return 3;
    }
    term.writes_stl = c.stl != 0;
    /* what a kill left of storing a model: half-built generations, temporary files and links */
    if (cm_term_store_open(&store, c.out, c.stl != 0) != 0) {
        logline("error", "output", "why=\"%s\"", store.why);
        cm_gpio_close(&gpio);
        return 3;
    }
    if (term.active)
        logline("info", "resumable", "bytes=%u of=%u", (unsigned)term.prefix, (unsigned)term.offer.size);
    logline("info", "start", "out=%s profile=%s max_file_bytes=%u", c.out, cm_profile_name, (unsigned)CM_MAX_FILE_BYTES);

    int rc = 0, said_waiting = 0, busy = 0;
    int64_t ready_off_at = 0, started_ms = 0, shown_ms = 0;
    unsigned shown_pct = 0; /* the progress on the status line */
    if (!term.recovered)
        show_current(&c, "ready"); /* the last good model, on the screen again after a restart */
    if (term.recovered) {
        /* received whole and verified, then killed before it was shown: show it now, and answer the
           sender's repeated END with the outcome (it waited through the restart) */
        logline("info", "recovered", "bytes=%u crc=%08x", (unsigned)term.offer.size, (unsigned)term.offer.crc);
        cm_gpio_set(&gpio, CM_GPIO_BUSY, 1);
        char text[CM_LINK_MAX_TEXT + 1];
        int code = decode_into_place(&c, 0, text, sizeof text);
        cm_link_term_recovered(&term, code, text);
        cm_gpio_set(&gpio, CM_GPIO_BUSY, 0);
        show_current(&c, text);
        if (code == 0) {
            logline("info", "decoded", "name=\"%s\" %s", term.offer.name, text);
            cm_gpio_set(&gpio, CM_GPIO_READY, 1);
            ready_off_at = cm_clock_ms() + c.ready_pulse_ms;
        } else {
            logline("error", "decode-failed", "name=\"%s\" why=\"%s\"", term.offer.name, text);
            cm_gpio_set(&gpio, CM_GPIO_ERROR, 1);
        }
    }
    cm_transport *link = NULL;
    while (!stop_signal) {
        viewer_reap(0);
        if (ready_off_at && cm_clock_ms() >= ready_off_at) {
            cm_gpio_set(&gpio, CM_GPIO_READY, 0);
            ready_off_at = 0;
        }
        int pressed = cm_gpio_request_pressed(&gpio);
        if (!link) {
            int fatal;
            link = open_link(&c, &fatal);
            if (!link) {
                if (fatal) {
                    rc = 3;
                    break;
                }
                if (!said_waiting)
                    logline("warn", "link-down", "why=\"%s\" retry=500ms", open_error(&c));
                said_waiting = 1;
                nap_ms(500);
                continue;
            }
            said_waiting = 0;
            cm_link_term_attach(&term, link);
            logline("info", "link-up", "link=\"%s\"", link->name);
        }
        if (pressed > 0) {
            logline("info", "request", "why=button");
            (void)cm_link_term_request(&term);
        }
        int ev = cm_link_term_poll(&term, 200);
        if (term.active && term.prefix >= term.offer.size / 2 && term.prefix < term.offer.size)
            cm_kill_point("incoming-mid-write");
        /* the transfer's progress on the status line: in steps of 10 %, at most once a second */
        if (term.active && term.offer.size && cm_clock_ms() - shown_ms >= 1000) {
            unsigned pct = (unsigned)((uint64_t)term.prefix * 10u / term.offer.size) * 10u;
            if (pct != shown_pct && pct < 100) {
                char what[32];
                snprintf(what, sizeof what, "receiving %u %%", pct);
                show_status(&c, term.offer.name, what);
                shown_pct = pct;
                shown_ms = cm_clock_ms();
            }
        }
        if (ev < 0) {
            logline("warn", "link-down", "link=\"%s\" why=\"%s\"", link->name,
                    ev == CM_T_HANGUP ? "hang-up" : link->err);
            link->close(link);
            link = NULL;
            cm_link_term_close(&term);
            if (busy)
                cm_gpio_set(&gpio, CM_GPIO_BUSY, 0), busy = 0;
            continue;
        }
        switch (ev) {
        case CM_TERM_STARTED:
            started_ms = cm_clock_ms();
            logline("info", "receiving", "name=\"%s\" bytes=%u from=%u chunk=%u", term.offer.name,
                    (unsigned)term.offer.size, (unsigned)term.prefix, (unsigned)term.chunk);
            cm_gpio_set(&gpio, CM_GPIO_BUSY, 1), busy = 1;
            show_status(&c, term.offer.name, "receiving");
            shown_pct = 0; /* (a resumed transfer shows where it resumed a second from now) */
            shown_ms = started_ms;
            if (term.prefix == 0)
                cm_kill_point("part-created");
            break;
        case CM_TERM_IDLE:
            logline("warn", "stalled", "name=\"%s\" bytes=%u of=%u", term.offer.name, (unsigned)term.prefix,
                    (unsigned)term.offer.size);
            cm_gpio_set(&gpio, CM_GPIO_BUSY, 0), busy = 0;
            break;
        case CM_TERM_FAILED:
            logline("error", "refused", "name=\"%s\" why=\"%s\"", term.offer.name, term.why);
            show_status(&c, term.offer.name, term.why);
            cm_gpio_set(&gpio, CM_GPIO_BUSY, 0), busy = 0;
            cm_gpio_set(&gpio, CM_GPIO_ERROR, 1);
            if (c.once) {
                rc = 1;
                stop_signal = -1;
            }
            break;
        case CM_TERM_COMPLETE: {
            cm_gpio_set(&gpio, CM_GPIO_BUSY, 1), busy = 1;
            logline("info", "stored", "name=\"%s\" bytes=%u crc=%08x ms=%lld", term.offer.name,
                    (unsigned)term.offer.size, (unsigned)term.offer.crc, (long long)(cm_clock_ms() - started_ms));
            cm_kill_point("incoming-renamed");
            char text[CM_LINK_MAX_TEXT + 1];
            int code = decode_into_place(&c, 1, text, sizeof text);
            cm_link_term_decoded(&term, code, text);
            cm_gpio_set(&gpio, CM_GPIO_BUSY, 0), busy = 0;
            if (code == 0) {
                show_current(&c, text);
                logline("info", "decoded", "name=\"%s\" %s", term.offer.name, text);
                cm_gpio_set(&gpio, CM_GPIO_ERROR, 0);
                cm_gpio_set(&gpio, CM_GPIO_READY, 1);
                ready_off_at = cm_clock_ms() + c.ready_pulse_ms;
            } else {
                logline("error", "decode-failed", "name=\"%s\" why=\"%s\"", term.offer.name, text);
                cm_gpio_set(&gpio, CM_GPIO_ERROR, 1);
                show_status(&c, term.offer.name, text);
            }
            if (c.once) {
                rc = code == 0 ? 0 : 1;
                stop_signal = -1;
            }
            break;
        }
        default:
            break;
        }
    }
    if (stop_signal > 0)
        logline("info", "stop", "signal=%d", (int)stop_signal);
    if (ready_off_at)
        nap_ms((int)(ready_off_at - cm_clock_ms() > 0 ? ready_off_at - cm_clock_ms() : 0));
    if (viewer_in >= 0) { /* the serving viewer of a DRM display goes with the daemon (so does its picture) */
        close(viewer_in);
        viewer_in = -1;
    }
    if ((c.nview_args || display_drm) && viewer_pid > 0) /* a viewer waiting for its buttons goes with the daemon */
        kill(viewer_pid, SIGTERM);
    viewer_reap(1); /* (the picture it draws stays on the screen) */
    cm_link_term_close(&term);
    cm_term_store_close(&store);
    if (link)
        link->close(link);
    cm_gpio_close(&gpio);
    return rc;
}
