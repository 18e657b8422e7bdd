/*
 * cmz-view - what the terminal shows, as a picture: a .cmz decoded and drawn
 * by the terminal's own software viewer (cm_view.h) into a PNG; or a .glb
 * (cm_glb_read.h) drawn the same way.
 *
 *   cmz-view MODEL.cmz|MODEL.glb --png OUT.png|--fb DEV [--size WxH] [--view iso|front|back|left|right|top|bottom]
 *            [--turn N] [--perspective] [--step K] [--no-edges] [--background RRGGBB] [--tess MM]
 *            [--status TEXT]
 *            [--gpio-rotate|--gpio-next|--gpio-prev|--gpio-reset SPEC] [--turntable S] [--idle S]
 *   cmz-view --fb DEV --status TEXT
 *   cmz-view --limits | --version | --help
 *
 * With --fb and a button or a turntable, the viewer stays on the screen: it keeps the decoded mesh
 * (its spill files) and draws again on each press or turntable tick, until SIGTERM or SIGINT.
 *
 * The same program on the workstation and the board (profile terminal by
 * default): a person at the workstation sees exactly the pixels the
 * terminal will show.  Heap-free like cmz-decode: the frame and its depth
 * buffer are static, sized by fixedcfg (CM_VIEW_MAX_W x CM_VIEW_MAX_H).
 * The PNG appears atomically (a temporary file renamed into place).
 *
 * Exit status: 0 success, 1 the file is malformed or exceeds a limit,
 * 2 usage, 3 I/O error, 4 GPIO (a button's line cannot be had: the picture stays).
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cm/cm_decode_state.h"
#include "cm/cm_glb_read.h"
#include "cm/cm_limits_info.h"
#include "cm/cm_png.h"
#include "cm/cm_view.h"
#include "cm_clock.h"
#include "cm_decode_file.h"
#include "cm_drm.h"
#include "cm_fb.h"
#include "cm_gpio.h"
#include "cm_report.h"

/* everything big is static: the decode and draw paths never touch the heap */
static cm_decode_state state;
static cm_view view;
/* the model's faces' boxes (cm_mesh_face_boxes: once a model, for each frame's fit) */
static float face_box[CM_MAX_FACES][6];
static cm_glb_reader glb; /* MODEL.glb's accessors, primitives and nodes */
static cm_drm drm = {.fd = -1}; /* --fb /dev/dri/cardN: the DRM screen this process holds (drm.map) */
static cm_gpio gpio;
static volatile sig_atomic_t stop_signal;

/* "cmz-view: [LEVEL]IN: [face F, ]byte N: text (CODE) [in where]" (cm_report_status) */
static void report(FILE *f, const char *level, const char *in, const cm_status *st)
{
    char subject[4096];
    snprintf(subject, sizeof subject, "%s%s", level, in);
    cm_report_status(f, "cmz-view", subject, st);
}

/* --camera: the view's camera, one line (before the summary; with -q alone) */
static void print_camera(void)
{
    printf("camera %d %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n",
           view.o.width, view.o.height, view.scale, view.eye, view.c[0], view.c[1], view.c[2], view.r[0], view.r[1],
           view.r[2], view.u[0], view.u[1], view.u[2], view.f[0], view.f[1], view.f[2]);
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: cmz-view MODEL.cmz|MODEL.glb --png OUT.png|--fb DEV [--size WxH] [--view DIR] [--turn N]\n"
            "                [--perspective] [--step K] [--no-edges] [--background RRGGBB] [--tess MM]\n"
            "                [--status TEXT] [--camera] [--frames N] [-q]\n"
            "                [--gpio-rotate SPEC] [--gpio-next SPEC] [--gpio-prev SPEC] [--gpio-reset SPEC]\n"
            "                [--turntable SECONDS] [--idle SECONDS]\n"
            "       cmz-view --fb DEV --status TEXT\n"
            "       cmz-view --fb DEV --serve [BUTTONS]\n"
            "       cmz-view --limits | --version | --help\n"
            "\n"
            "Rebuild a curvemesh model and draw it as the terminal's viewer does: shaded\n"
            "triangles with the decoder's normals, in the faces' colours, and the model's\n"
            "exact edges on top; the camera fitted to the model.  DIR: iso (default), front,\n"
            "back, left, right, top, bottom (CAD axes, Z up; front looks along +Y).\n"
            "MODEL.glb (a binary glTF 2.0, known by its first bytes: what `cmz decode` writes,\n"
            "or another tool's) is drawn the same way, turned from glTF's metres with Y up\n"
            "into millimetres with Z up, without edges (a GLB has no curve mesh; silhouettes\n"
            "are drawn), each node with a mesh one part; points and lines are left out.\n"
            "--png: write the picture as a PNG file; --fb: show it on the Linux framebuffer\n"
            "DEV (/dev/fb0: 16, 24 or 32-bit, centred, the rest of the screen background), or\n"
            "on a DRM/KMS device (/dev/dri/card0: the first connected screen at its preferred\n"
            "mode; the screen shows the picture while cmz-view runs: it stays until SIGTERM\n"
            "or SIGINT); --fb auto: the first DRM device with a connected screen, else\n"
            "/dev/fb0.  --serve (with --fb, no MODEL): one viewer for a terminal's whole\n"
            "run, told on its standard input what to show, a command a line: 'status TEXT',\n"
            "'model PATH<tab>TEXT' (the old picture stays until the new one is drawn); it\n"
            "ends at the end of its input (cmz-terminal --display on a DRM device).\n"
            "--size: pixels, default 800x480 (with --fb alone: the screen's), at most %dx%d\n"
            "in this build (profile %s).\n"
            "--turn N: the model turned N x %d degrees about its vertical axis, counter-clockwise\n"
            "seen from above (what N presses of the rotate button show).\n"
            "--perspective: a 30 degree field of view instead of a parallel projection.\n"
            "--step K: assembly step K: parts 1..K shown, part K highlighted, the others\n"
            "dimmed.  The parts are the file's (format 4.11: the workstation's instances,\n"
            "solids and groups, each placed copy, in the order of `cmz encode --steps`), else\n"
            "the model's connected pieces (faces joined by edges) in file order, then each\n"
            "placed copy of a part; the summary line counts them and names step K's part\n"
            "where the file names it (format 4.12).\n"
            "--background: the colour behind the model, default ffffff.  --tess: chordal\n"
            "tolerance in mm (default: the file's recommendation).  The PNG is uncompressed\n"
            "(stored deflate) and appears whole or not at all.  --status: a status line of\n"
            "TEXT across the bottom (without a model: drawn alone on the screen's last rows,\n"
            "the rest of the screen untouched).  --camera: a line 'camera W H SCALE EYE\n"
            "CX CY CZ RX RY RZ UX UY UZ FX FY FZ' before the summary: the frame's size, pixels\n"
            "per mm (perspective: the focal length in pixels), the eye's depth (perspective;\n"
            "else 0), the point the frame is centred on and the screen's right, up and\n"
            "into-the-screen axes in CAD millimetres, so that another renderer can match the\n"
            "view (tests/tools/check_three.sh).  --frames N: the frame drawn N times (as a\n"
            "button press draws it again), the summary saying its mean wall time: what this\n"
            "board takes to turn the model.  -q: no summary line.\n"
            "\n"
            "The operator's buttons (with --fb; the viewer then stays, drawing again on each\n"
            "press, until SIGTERM or SIGINT): --gpio-rotate turns the model one step, --gpio-next\n"
            "and --gpio-prev go through the assembly steps (the whole model, step 1, ..., the\n"
            "last, and round again; the status line says which), --gpio-reset goes back to the\n"
            "view and step the command line gave.  SPEC: CHIP:LINE, CHIP a name (gpiochip0),\n"
            "path or label, LINE a name or offset, '!' in front for active-low; a press is a\n"
            "rising edge.  --turntable S: after --idle S (default 30) without a press, the\n"
            "model turns one step every S seconds until the next press.\n"
            "\n"
            "exit status: 0 success, 1 malformed file or over a limit, 2 usage, 3 I/O error,\n"
            "4 a button's GPIO line cannot be had (the picture stays on the screen).\n",
            CM_VIEW_MAX_W, CM_VIEW_MAX_H, cm_profile_name, CM_VIEW_TURN_DEG);
}

static int put_fd(void *ctx, const uint8_t *p, size_t n)
{
    int fd = *(int *)ctx;
    while (n > 0) {
        ssize_t k = write(fd, p, n);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            return -1;
        p += k;
        n -= (size_t)k;
    }
    return 0;
}

/* the frame as out_path, atomically: 0, or 3 after saying why */
static int write_png(const char *out_path)
{
    char tmp[4096];
    if (strlen(out_path) + 24 > sizeof tmp) {
        fprintf(stderr, "cmz-view: %s: output path too long\n", out_path);
        return 2;
    }
    snprintf(tmp, sizeof tmp, "%s.part%ld", out_path, (long)getpid());
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) {
        fprintf(stderr, "cmz-view: %s: %s\n", tmp, strerror(errno));
        return 3;
    }
    cm_status st;
    cm_status_init(&st);
    cm_err e = cm_png_write(view.rgb, (uint32_t)view.o.width, (uint32_t)view.o.height, put_fd, &fd, &st);
    int err = e == CM_OK ? 0 : errno;
    if (close(fd) != 0 && e == CM_OK) {
        e = CM_E_IO;
        err = errno;
    }
    if (e == CM_OK && rename(tmp, out_path) != 0) {
        e = CM_E_IO;
        err = errno;
    }
    if (e != CM_OK) {
        unlink(tmp);
        fprintf(stderr, "cmz-view: %s: %s\n", out_path, err ? strerror(err) : cm_err_name(e));
        return 3;
    }
    return 0;
}

static int parse_hex_rgb(const char *s, uint32_t *rgb)
{
    char *end;
    unsigned long v = strtoul(s, &end, 16);
    if (strlen(s) != 6 || *end || v > 0xffffffUL)
        return 0;
    *rgb = (uint32_t)v;
    return 1;
}

/* the status line: the caller's text, and in an interactive viewer the step on show */
static const char *status_text(char *buf, size_t cap, const char *status, int interactive, uint32_t step,
                               uint32_t parts)
{
    if (!interactive || step == 0)
        return status;
    /* (the part's name where the file sends it, format 4.12: what the operator fits at this step) */
    const char *name = cm_model_part_name(&state.dec.model, step);
    snprintf(buf, cap, "%s%sstep %u of %u%s%s", status ? status : "", status ? "  -  " : "", step, parts,
             name ? ": " : "", name ? name : "");
    return buf;
}

/* draw the model into the frame as vo asks (the parts numbered again: cm_view_begin clears them)
   and count its parts: 0, or the exit status after reporting why not (3: the mesh could not be read
   back from its spill files) */
static int draw(const cm_view_opts *vo, const float lo[3], const float hi[3], const cm_mesh *mesh, uint32_t nboxed,
                const char *status, int interactive, const char *in, uint32_t *nparts)
{
    cm_status st;
    cm_status_init(&st);
    if (cm_view_begin(&view, vo, lo, hi, &st) != CM_OK) {
        report(stderr, "", in, &st);
        return 1;
    }
    uint32_t parts = cm_view_parts(&view, &state.dec.model);
    *nparts = parts;
    if (vo->step > parts) {
        fprintf(stderr, "cmz-view: %s: --step %u: the model has %u parts\n", in, vo->step, parts);
        return 2;
    }
    cm_view_fit(&view, mesh, (const float(*)[6])face_box, nboxed);
    cm_view_mesh(&view, mesh);
    cm_view_edges(&view, &state.dec.model);
    char buf[512];
    const char *text = status_text(buf, sizeof buf, status, interactive, vo->step, parts);
    if (text)
        cm_view_status(&view, text);
    if (cm_mesh_spill_failed(mesh)) {
        fprintf(stderr, "cmz-view: %s: reading the mesh back from its spill files failed\n", in);
        return 3;
    }
    return 0;
}

/* the frame on the framebuffer fb: 0, or the exit status after reporting why not */
static int show_frame(const char *fb, const cm_view_opts *vo)
{
    cm_status st;
    cm_status_init(&st);
    if (drm.map) { /* the DRM screen's buffer, mapped: the frame goes straight into it */
        cm_fb_compose(&drm.fmt, drm.map, view.rgb, (uint32_t)vo->width, (uint32_t)vo->height, vo->background);
        return 0;
    }
    if (cm_fb_show(fb, view.rgb, (uint32_t)vo->width, (uint32_t)vo->height, vo->background, &st) == 0)
        return 0;
    report(stderr, "", fb, &st);
    return st.code == CM_E_IO ? 3 : 1;
}

static void on_stop(int sig) { stop_signal = sig; }

static void catch_stop(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop; /* no SA_RESTART: poll returns EINTR */
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
}

/* a DRM screen shows this process's buffer while the process holds the device: stay until SIGTERM or
   SIGINT (0) */
static int hold_screen(void)
{
    catch_stop();
    while (!stop_signal)
        poll(NULL, 0, -1);
    cm_drm_close(&drm);
    return 0;
}

/* the GLB's bytes, as the decoder's (a GLB of 4 GiB or more is read no further than that) */
static int glb_pread(void *ctx, uint64_t off, void *buf, size_t n)
{
    return off > UINT32_MAX - n ? -1 : cm_decode_pread(ctx, (uint32_t)off, buf, n);
}

/* a .glb (by its first bytes, whatever its name) read into the mesh and the model's parts (*is_glb
   1); anything else left to the .cmz decoder (*is_glb 0) */
static cm_err read_glb(const char *in, cm_mesh *mesh, int *is_glb, cm_status *st)
{
    int fd = open(in, O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        *is_glb = 0;
        return CM_OK; /* (the .cmz path says why it cannot be opened) */
    }
    uint8_t head[4] = {0, 0, 0, 0};
    off_t len = lseek(fd, 0, SEEK_END);
    *is_glb = len >= 4 && glb_pread(&fd, 0, head, 4) == 0 && cm_glb_sniff(head);
    cm_err e = CM_OK;
    if (*is_glb) {
        e = cm_glb_read(&glb, glb_pread, &fd, (uint64_t)len, mesh, &state.dec.model, st);
        if (e == CM_E_IO && st->sys_errno == 0)
            st->sys_errno = errno;
    }
    close(fd);
    return e;
}

static int parse_seconds(const char *opt, const char *s, int64_t *ms)
{
    char *end;
    double v = strtod(s, &end);
    if (*end || !(v >= 0.05 && v <= 86400.0)) {
        fprintf(stderr, "cmz-view: %s wants seconds from 0.05 to 86400, not '%s'\n", opt, s);
        return 0;
    }
    *ms = (int64_t)(v * 1000.0 + 0.5);
    return 1;
}

/* decode (or read: a GLB) `in` into *mesh, its spill beside `spill` (a file; is_dir: in that directory):
   0, or the exit status after saying why */
static int load_model(const char *in, const char *spill, int is_dir, double tol, cm_mesh *mesh, cm_decode_summary *sum,
                      float lo[3], float hi[3], uint32_t *nboxed)
{
    cm_status st;
    cm_status_init(&st);
    *mesh = cm_decode_stream_mesh(&state, spill, is_dir);
    memset(sum, 0, sizeof *sum);
    int is_glb = 0;
    if (read_glb(in, mesh, &is_glb, &st) != CM_OK ||
        (!is_glb && (cm_decode_read(in, &state.dec, &st) != CM_OK ||
                     cm_decode_mesh(&state.dec, tol, mesh, &state.tess, sum, &st) != CM_OK))) {
        report(stderr, "", in, &st);
        return st.code == CM_E_IO ? 3 : 1;
    }
    if (is_glb) {
        sum->faces = state.dec.model.nfaces;
        sum->triangles = mesh->nindex / 3u;
        if (glb.skipped_prims > 0)
            fprintf(stderr, "cmz-view: %s: warning: %u primitives that are not triangles (points, lines, strips, "
                            "fans) left out\n", in, glb.skipped_prims);
    }
    for (uint32_t i = 0; i < sum->faces_left_out && i < CM_DECODE_LEFT_OUT_LIST; i++)
        report(stderr, "warning: ", in, &sum->left_out[i]);
    if (state.dec.model.part_names_left_out)
        fprintf(stderr, "cmz-view: %s: warning: the parts' names need more than this build's %d bytes "
                        "(CM_MAX_PART_NAME_BYTES): the steps are shown without them\n", in, CM_MAX_PART_NAME_BYTES);
    if (!cm_mesh_face_boxes(mesh, face_box, CM_MAX_FACES, nboxed, lo, hi)) {
        fprintf(stderr, "cmz-view: %s: nothing to show (no triangles)\n", in);
        return 1;
    }
    return 0;
}

/* the status line alone on the screen's last rows, over what it shows: 0, or the exit status */
static int bar_alone(const char *fb, const cm_view_opts *vo, const char *text)
{
    cm_status st;
    cm_status_init(&st);
    const float zero[3] = {0, 0, 0};
    if (cm_view_begin(&view, vo, zero, zero, &st) != CM_OK) {
        report(stderr, "", fb, &st);
        return 1;
    }
    cm_view_status(&view, text);
    int h = cm_view_status_height(&view);
    h = h < vo->height ? h : vo->height;
    const uint8_t *rows = view.rgb + (size_t)(vo->height - h) * (size_t)vo->width * 3;
    if (drm.map) {
        cm_fb_compose_bottom(&drm.fmt, drm.map, rows, (uint32_t)vo->width, (uint32_t)h);
        return 0;
    }
    if (cm_fb_show_bottom(fb, rows, (uint32_t)vo->width, (uint32_t)h, &st) != 0) {
        report(stderr, "", fb, &st);
        return st.code == CM_E_IO ? 3 : 1;
    }
    return 0;
}

/* the model on show in a viewer that stays (buttons, turntable, --serve) */
static struct {
    int loaded;
    cm_mesh mesh;
    float lo[3], hi[3];
    uint32_t nboxed; /* (its faces boxed in face_box) */
    uint32_t parts;
    int has_status;
    char status[1024];
    char path[4096];
} cur;

/*
 * The viewer that stays on the screen (issue 17), until SIGTERM or SIGINT: the operator's buttons
 * and the turntable act on the model on show (cur), drawing it again.  A press drains its line's
 * queued edges (a bouncing contact is one press); a turntable tick comes every `tick_ms` once
 * `idle_ms` have passed since the last press.  With `commands` (--serve: one viewer for a
 * terminal's whole run, cmz-terminal on a DRM screen, which one process holds while it shows
 * anything) it is also told what to show on its standard input, a command a line:
 *   status TEXT           the status line, over what is on the screen
 *   model PATH<tab>TEXT   PATH decoded and drawn with the status line TEXT; the picture on the
 *                         screen stays until the new one is ready (a file that does not decode
 *                         leaves it, and is said on stderr)
 * and ends at the end of its input.  Returns the exit status.
 */
static int screen_loop(const char *fb, const char *const button[CM_GPIO_NBUTTON], int64_t tick_ms, int64_t idle_ms,
                       cm_view_opts vo, double tol, int commands, int quiet)
{
    int buttons = 0;
    for (int b = 0; b < CM_GPIO_NBUTTON; b++)
        buttons |= button[b] != NULL;
    cm_gpio_config gc = {.consumer = "cmz-view"};
    for (int b = 0; b < CM_GPIO_NBUTTON; b++)
        gc.button[b] = button[b];
    if (buttons && cm_gpio_open(&gpio, &gc) != 0) {
        fprintf(stderr, "cmz-view: %s\n", gpio.err);
        return 4;
    }
    if (!commands && !quiet) /* (once the lines are held: a press from now on is seen) */
        printf("%s -> %s: %u parts, waiting for the buttons\n", cur.path, fb, cur.parts);
    fflush(stdout);
    catch_stop();
    if (commands)
        signal(SIGPIPE, SIG_IGN);
    const char *tmpdir = getenv("TMPDIR");
    const char *dir = tmpdir && tmpdir[0] ? tmpdir : "/tmp";
    static char line[8192];
    size_t used = 0;
    int skipping = 0, rc = 0, input = commands;
    cm_decode_summary sum;
    const cm_view_opts start = vo;
    int64_t next_tick = cm_clock_ms() + idle_ms;
    while (!stop_signal && rc == 0 && (input || !commands)) {
        struct pollfd pfd[1 + CM_GPIO_NBUTTON];
        nfds_t n = 0;
        if (commands)
            pfd[n++] = (struct pollfd){.fd = 0, .events = POLLIN};
        for (int b = 0; buttons && b < CM_GPIO_NBUTTON; b++) {
            int fd = cm_gpio_button_fd(&gpio, (cm_gpio_button)b);
            if (fd >= 0)
                pfd[n++] = (struct pollfd){.fd = fd, .events = POLLIN};
        }
        int timeout = -1;
        if (tick_ms > 0 && cur.loaded) {
            int64_t wait = next_tick - cm_clock_ms();
            timeout = wait <= 0 ? 0 : wait > 3600000 ? 3600000 : (int)wait;
        }
        int r = poll(pfd, n, timeout);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0) {
            fprintf(stderr, "cmz-view: waiting for the buttons%s: %s\n", commands ? " and commands" : "", strerror(errno));
            rc = 3;
            break;
        }
        int redraw = 0;
        if (commands && pfd[0].revents) { /* a line at a time (a line longer than the buffer is skipped) */
            ssize_t k = read(0, line + used, sizeof line - 1 - used);
            if (k < 0 && errno == EINTR)
                continue;
            if (k <= 0) {
                input = 0;
                break;
            }
            used += (size_t)k;
            char *nl;
            while ((nl = memchr(line, '\n', used)) != NULL) {
                *nl = '\0';
                size_t len = (size_t)(nl - line) + 1;
                if (!skipping && strncmp(line, "status ", 7) == 0) {
                    snprintf(cur.status, sizeof cur.status, "%.1023s", line + 7);
                    cur.has_status = 1;
                    if (cur.loaded)
                        redraw = 1;
                    else
                        rc = bar_alone(fb, &vo, cur.status);
                } else if (!skipping && strncmp(line, "model ", 6) == 0) {
                    char *tab = strchr(line + 6, '\t');
                    if (tab)
                        *tab = '\0';
                    snprintf(cur.path, sizeof cur.path, "%.4095s", line + 6);
                    snprintf(cur.status, sizeof cur.status, "%.1023s", tab ? tab + 1 : "");
                    cur.has_status = 1;
                    /* (a file that does not decode took the old mesh with it: the old picture stays
                       on the screen, the buttons wait for the next model) */
                    cur.loaded = load_model(cur.path, dir, 1, tol, &cur.mesh, &sum, cur.lo, cur.hi, &cur.nboxed) == 0;
                    vo = start;
                    redraw = cur.loaded;
                } else if (!skipping && line[0]) {
                    fprintf(stderr, "cmz-view: --serve: a command it does not know: %.60s\n", line);
                }
                skipping = 0;
                memmove(line, line + len, used - len);
                used -= len;
            }
            if (used == sizeof line - 1) { /* no end of line in the whole buffer */
                used = 0;
                skipping = 1;
            }
        }
        for (int b = 0; buttons && b < CM_GPIO_NBUTTON && rc == 0; b++) {
            int p = cm_gpio_button_pressed(&gpio, (cm_gpio_button)b);
            if (p < 0) {
                fprintf(stderr, "cmz-view: %s\n", gpio.err);
                rc = 4;
            } else if (p > 0 && cur.loaded) {
                redraw = 1;
                next_tick = cm_clock_ms() + idle_ms;
                if (b == CM_GPIO_ROTATE)
                    vo.turn = (vo.turn + 1) % CM_VIEW_TURNS;
                else if (b == CM_GPIO_NEXT) /* the whole model (0), 1, ..., parts, and round */
                    vo.step = vo.step >= cur.parts ? 0 : vo.step + 1;
                else if (b == CM_GPIO_PREV)
                    vo.step = vo.step == 0 ? cur.parts : vo.step - 1;
                else
                    vo = start;
            }
        }
        if (!redraw && rc == 0 && tick_ms > 0 && cur.loaded && cm_clock_ms() >= next_tick) {
            vo.turn = (vo.turn + 1) % CM_VIEW_TURNS;
            next_tick = cm_clock_ms() + tick_ms;
            redraw = 1;
        }
        if (!redraw || rc != 0)
            continue;
        const char *status = cur.has_status ? cur.status : NULL;
        rc = draw(&vo, cur.lo, cur.hi, &cur.mesh, cur.nboxed, status, buttons || tick_ms > 0, cur.path, &cur.parts);
        if (rc == 2 && commands) { /* (a --step beyond a new model's parts: the whole model) */
            vo.step = 0;
            rc = draw(&vo, cur.lo, cur.hi, &cur.mesh, cur.nboxed, status, buttons || tick_ms > 0, cur.path, &cur.parts);
        }
        if (rc == 0)
            rc = show_frame(fb, &vo);
    }
    if (buttons)
        cm_gpio_close(&gpio);
    cm_decode_spill_close();
    cm_drm_close(&drm);
    return rc;
}

int main(int argc, char **argv)
{
    const char *in = NULL, *out = NULL, *fb = NULL, *status = NULL;
    const char *button[CM_GPIO_NBUTTON] = {NULL, NULL, NULL, NULL};
    static const char *const button_opt[CM_GPIO_NBUTTON] = {"--gpio-rotate", "--gpio-next", "--gpio-prev",
                                                            "--gpio-reset"};
    int64_t tick_ms = 0, idle_ms = 30000;
    int sized = 0, quiet = 0, camera = 0, serving = 0;
    long frames = 1; /* --frames: the frame drawn this many times, the mean time reported */
    double tol = 0;
    cm_view_opts vo;
    cm_view_opts_default(&vo);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int more = i + 1 < argc;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(a, "--limits") == 0) {
            cm_report_limits(stdout);
            const cm_ram_part own[] = {
                {"  frame", "the viewer's RGB frame and depth buffer (CM_VIEW_MAX_W x CM_VIEW_MAX_H)", sizeof view},
                {"  face boxes", "each face's box, measured once a model for the frames' fit (CM_MAX_FACES)",
                 sizeof face_box},
                {"  glTF input", "MODEL.glb's accessors, primitives and nodes (CM_GLB_MAX_*)", sizeof glb},
                {"  I/O chunks", "the reader's chunk, the mesh spill's files", cm_decode_file_read_static_bytes()}};
            cm_report_program_ram(stdout, own, sizeof own / sizeof own[0]);
            return 0;
        } else if (strcmp(a, "--version") == 0) {
            printf("cmz-view 0.1.0 (profile %s)\n", cm_profile_name);
            return 0;
        } else if (strcmp(a, "--camera") == 0) {
            camera = 1;
        } else if (strcmp(a, "--serve") == 0) {
            serving = 1;
        } else if (strcmp(a, "--png") == 0 && more) {
            out = argv[++i];
        } else if (strcmp(a, "--fb") == 0 && more) {
            fb = argv[++i];
        } else if (strcmp(a, "--size") == 0 && more) {
            char *end;
            long w = strtol(argv[++i], &end, 10), h = 0;
            if (*end == 'x')
                h = strtol(end + 1, &end, 10);
            if (*end || w < 1 || h < 1 || w > CM_VIEW_MAX_W || h > CM_VIEW_MAX_H) {
                fprintf(stderr, "cmz-view: --size wants WxH within 1x1 .. %dx%d (this build), not '%s'\n",
                        CM_VIEW_MAX_W, CM_VIEW_MAX_H, argv[i]);
                return 2;
            }
            vo.width = (int)w;
            vo.height = (int)h;
            sized = 1;
        } else if (strcmp(a, "--view") == 0 && more) {
            int d = cm_view_dir_parse(argv[++i]);
            if (d < 0) {
                fprintf(stderr, "cmz-view: --view wants iso, front, back, left, right, top or bottom, not '%s'\n",
                        argv[i]);
                return 2;
            }
            vo.dir = (cm_view_dir)d;
        } else if (strcmp(a, "--step") == 0 && more) {
            char *end;
            long k = strtol(argv[++i], &end, 10);
            if (*end || k < 0 || k > 0x7fffffffL) {
                fprintf(stderr, "cmz-view: --step wants a part number from 1 (0: the whole model), not '%s'\n",
                        argv[i]);
                return 2;
            }
            vo.step = (uint32_t)k;
        } else if (strcmp(a, "--turn") == 0 && more) {
            char *end;
            long t = strtol(argv[++i], &end, 10);
            if (*end || argv[i][0] == '\0' || t < -1000000 || t > 1000000) {
                fprintf(stderr, "cmz-view: --turn wants a whole number of %d degree steps, not '%s'\n",
                        CM_VIEW_TURN_DEG, argv[i]);
                return 2;
            }
            vo.turn = (int)(t % CM_VIEW_TURNS);
        } else if (strcmp(a, "--turntable") == 0 && more) {
            if (!parse_seconds(a, argv[++i], &tick_ms))
                return 2;
        } else if (strcmp(a, "--idle") == 0 && more) {
            if (!parse_seconds(a, argv[++i], &idle_ms))
                return 2;
        } else if (strncmp(a, "--gpio-", 7) == 0 && more) {
            int b = 0;
            while (b < CM_GPIO_NBUTTON && strcmp(a, button_opt[b]) != 0)
                b++;
            if (b == CM_GPIO_NBUTTON) {
                fprintf(stderr, "cmz-view: unknown option %s (buttons: --gpio-rotate, --gpio-next, --gpio-prev, "
                                "--gpio-reset)\n", a);
                return 2;
            }
            button[b] = argv[++i];
        } else if (strcmp(a, "--status") == 0 && more) {
            status = argv[++i];
        } else if (strcmp(a, "-q") == 0) {
            quiet = 1;
        } else if (strcmp(a, "--perspective") == 0) {
            vo.perspective = 1;
        } else if (strcmp(a, "--no-edges") == 0) {
            vo.edges = 0;
        } else if (strcmp(a, "--background") == 0 && more) {
            if (!parse_hex_rgb(argv[++i], &vo.background)) {
                fprintf(stderr, "cmz-view: --background wants six hex digits RRGGBB, not '%s'\n", argv[i]);
                return 2;
            }
        } else if (strcmp(a, "--frames") == 0 && more) {
            char *end;
            frames = strtol(argv[++i], &end, 10);
            if (*end || frames < 1 || frames > 10000) {
                fprintf(stderr, "cmz-view: --frames wants a count from 1 to 10000, not '%s'\n", argv[i]);
                return 2;
            }
        } else if (strcmp(a, "--tess") == 0 && more) {
            char *end;
            tol = strtod(argv[++i], &end);
            if (*end || !(tol > 0)) {
                fprintf(stderr, "cmz-view: --tess wants a positive number of millimetres, not '%s'\n", argv[i]);
                return 2;
            }
        } else if (a[0] == '-') {
            fprintf(stderr, "cmz-view: unknown option %s\n", a);
            usage(stderr);
            return 2;
        } else if (!in) {
            in = a;
        } else {
            fprintf(stderr, "cmz-view: one model at a time\n");
            return 2;
        }
    }
    if (serving ? (!fb || in || out) : ((!in && !(status && fb)) || (in && !out && !fb))) {
        usage(stderr);
        return 2;
    }
    int stays = tick_ms > 0; /* a button or the turntable: the viewer stays to draw again */
    for (int b = 0; b < CM_GPIO_NBUTTON; b++)
        stays |= button[b] != NULL;
    if (stays && in && !fb) {
        fprintf(stderr, "cmz-view: the buttons and --turntable need --fb (a screen to draw on again)\n");
        return 2;
    }
    int interactive = stays && in;
    cm_status st;
    cm_status_init(&st);
    static char probed[32];
    if (fb && strcmp(fb, "auto") == 0) { /* the first DRM device with a screen, else the framebuffer */
        for (int k = 0; k < 8 && !drm.map; k++) {
            snprintf(probed, sizeof probed, "/dev/dri/card%d", k);
            cm_status_init(&st);
            if (cm_drm_is_drm(probed) && cm_drm_open(&drm, probed, vo.background, &st) == 0)
                fb = probed;
        }
        cm_status_init(&st);
        if (!drm.map)
            fb = "/dev/fb0";
    }
    if (fb && !drm.map && cm_drm_is_drm(fb) && cm_drm_open(&drm, fb, vo.background, &st) != 0) {
        report(stderr, "", fb, &st);
        return st.code == CM_E_IO ? 3 : 1;
    }
    if (fb && (!sized || !in)) { /* the screen's size, within the build's frame */
        cm_fb_format ff = drm.fmt;
        if (!drm.map && cm_fb_query(fb, &ff, &st) != 0) {
            report(stderr, "", fb, &st);
            return st.code == CM_E_IO ? 3 : 1;
        }
        vo.width = ff.width < CM_VIEW_MAX_W ? (int)ff.width : CM_VIEW_MAX_W;
        vo.height = ff.height < CM_VIEW_MAX_H ? (int)ff.height : CM_VIEW_MAX_H;
    }
    if (serving)
        return screen_loop(fb, button, tick_ms, idle_ms, vo, tol, 1, quiet);
    if (!in) { /* the status line alone, over what the screen shows */
        int rc = bar_alone(fb, &vo, status);
        return rc == 0 && drm.map ? hold_screen() : rc;
    }
    /* the mesh spills beside the PNG, or in $TMPDIR (/tmp) */
    const char *tmpdir = getenv("TMPDIR");
    cm_decode_summary sum;
    int lrc = load_model(in, out ? out : (tmpdir && tmpdir[0] ? tmpdir : "/tmp"), out ? 0 : 1, tol, &cur.mesh, &sum,
                         cur.lo, cur.hi, &cur.nboxed);
    if (lrc != 0)
        return lrc;
    uint32_t parts = 0;
    /* (--frames: the same frame again, as a button press draws it: the drawing's wall time alone,
       without the decode, the PNG or the screen) */
    const struct timespec t0 = cm_clock_now();
    int rc = 0;
    for (long k = 0; k < frames && rc == 0; k++)
        rc = draw(&vo, cur.lo, cur.hi, &cur.mesh, cur.nboxed, status, interactive, in, &parts);
    const struct timespec t1 = cm_clock_now();
    if (rc != 0)
        return rc;
    const double frame_ms =
        ((double)(t1.tv_sec - t0.tv_sec) * 1e3 + (double)(t1.tv_nsec - t0.tv_nsec) * 1e-6) / (double)frames;
    rc = out ? write_png(out) : 0;
    if (rc == 0 && fb)
        rc = show_frame(fb, &vo);
    if (rc != 0)
        return rc;
    if (interactive) { /* the buttons (the mesh stays in its spill files for the next pictures) */
        cur.loaded = 1;
        cur.parts = parts;
        cur.has_status = status != NULL;
        snprintf(cur.status, sizeof cur.status, "%s", status ? status : "");
        snprintf(cur.path, sizeof cur.path, "%s", in);
        return screen_loop(fb, button, tick_ms, idle_ms, vo, tol, 0, quiet);
    }
    cm_decode_spill_close();
    if (camera)
        print_camera();
    if (quiet)
        return drm.map ? hold_screen() : 0;
    printf("%s -> %s%s%s: %dx%d, %s%s, %u faces, %u parts", in, out ? out : "", out && fb ? " and " : "", fb ? fb : "",
           vo.width, vo.height, cm_view_dir_name(vo.dir),
           vo.perspective ? " perspective" : "", sum.faces, parts);
    if (vo.step > 0) { /* (and the part's name, format 4.12: what the terminal's status line says) */
        const char *name = cm_model_part_name(&state.dec.model, vo.step);
        printf(" (step %u%s%s)", vo.step, name ? ": " : "", name ? name : "");
    }
    printf(", %u triangles (%llu drawn)", sum.triangles, (unsigned long long)view.triangles);
    if (frames > 1)
        printf(", %.3f ms a frame (mean of %ld)", frame_ms, frames);
    if (sum.faces_left_out > 0)
        printf(", %lu faces left out", (unsigned long)sum.faces_left_out);
    printf("%s\n", drm.map ? "; on the screen until SIGTERM" : "");
    fflush(stdout);
    return drm.map ? hold_screen() : 0;
}
