/*
 * cm_gpio_gpiod.c - the terminal's lamps, its request button and the viewer's
 * buttons through libgpiod 1.6 (the GPIO character device).  The only file that includes <gpiod.h>.
 *
 * Each configured line gets its own chip handle, so "busy" and "request" may
 * sit on different chips.  Active-low is requested from the kernel
 * (GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW) rather than inverted here: gpioinfo
 * then shows the line as active-low, and the kernel also turns the edge
 * detection round, so "rising edge" always means "became active", i.e. the
 * button was pressed, whichever way it is wired.
 *
 * libgpiod allocates only inside cm_gpio_open (chip and line objects); set,
 * request_pressed and close do not touch the heap.
 */
#define _POSIX_C_SOURCE 200809L

#include "cm_gpio.h"

#include <errno.h>
#include <gpiod.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* libgpiod 2 replaced struct gpiod_line and the line_bulk API with line
 * requests; its gpiod.h defines no GPIOD_LINE_BULK_* macro, which every 1.x
 * release has.  mk/hw.mk also checks the version with pkg-config. */
#ifndef GPIOD_LINE_BULK_MAX_LINES
#error "cm_gpio_gpiod.c needs libgpiod 1.x (1.6 API: struct gpiod_line); this <gpiod.h> is libgpiod 2 or later. Install libgpiod-dev 1.6 (Debian 12) or build without GPIO (platform/cm_gpio_none.c)."
#endif

/* the name of each slot in error messages, as the configuration calls it */
static const char *const role_name[CM_GPIO_SLOTS] = CM_GPIO_ROLE_NAMES;

/* a chip or line description longer than this is a configuration mistake */
enum { SPEC_MAX = 96 };

/** Format the error text: "gpio ROLE=SPEC: cause". Always returns -1. */
static int gpio_fail(cm_gpio *g, int slot, const char *spec, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static int gpio_fail(cm_gpio *g, int slot, const char *spec, const char *fmt, ...) {
    int n = snprintf(g->err, sizeof g->err, "gpio %s=%s: ", role_name[slot], spec ? spec : "");
    if (n < 0 || (size_t)n >= sizeof g->err) return -1;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(g->err + n, sizeof g->err - (size_t)n, fmt, ap);
    va_end(ap);
    return -1;
}

/** True when s is a non-empty run of decimal digits (a line offset or chip number). */
static bool all_digits(const char *s) {
    if (*s == '\0') return false;
    for (; *s; s++)
        if (*s < '0' || *s > '9') return false;
    return true;
}

/**
 * Open the chip named by desc: a path (starts with '/'), a chip name
 * (gpiochip0) or a label (decoder-sim).  Names are tried before labels, so a
 * chip whose label happens to read "gpiochip1" cannot hide the real gpiochip1.
 */
static struct gpiod_chip *open_chip(cm_gpio *g, int slot, const char *spec, const char *desc) {
    struct gpiod_chip *chip;
    if (desc[0] == '/') {
        chip = gpiod_chip_open(desc);
        if (!chip) gpio_fail(g, slot, spec, "cannot open %s: %s", desc, strerror(errno));
        return chip;
    }
    errno = 0;
    chip = gpiod_chip_open_by_name(desc);
    if (chip) return chip;
    if (errno != ENOENT) {
        gpio_fail(g, slot, spec, "cannot open /dev/%s: %s", desc, strerror(errno));
        return NULL;
    }
    errno = 0;
    chip = gpiod_chip_open_by_label(desc);
    if (chip) return chip;
    if (errno == ENOENT || errno == 0)
        gpio_fail(g, slot, spec, "no GPIO chip named or labelled '%s' (gpiodetect lists them)", desc);
    else
        gpio_fail(g, slot, spec, "cannot look for a chip labelled '%s': %s", desc, strerror(errno));
    return NULL;
}

/** Find the line "name" or "offset" on chip; NULL with g->err set. */
static struct gpiod_line *find_line(cm_gpio *g, int slot, const char *spec, struct gpiod_chip *chip,
                                    const char *desc) {
    struct gpiod_line *line;
    if (all_digits(desc)) {
        unsigned long off = 0;
        for (const char *p = desc; *p && off <= 0xffffu; p++) off = off * 10u + (unsigned long)(*p - '0');
        if (off >= gpiod_chip_num_lines(chip)) {
            gpio_fail(g, slot, spec, "chip %s [%s] has %u lines, no offset %s", gpiod_chip_name(chip),
                      gpiod_chip_label(chip), gpiod_chip_num_lines(chip), desc);
            return NULL;
        }
        line = gpiod_chip_get_line(chip, (unsigned int)off);
        if (!line)
            gpio_fail(g, slot, spec, "cannot read line %s of chip %s: %s", desc, gpiod_chip_name(chip),
                      strerror(errno));
        return line;
    }
    errno = 0;
    line = gpiod_chip_find_line(chip, desc);
    if (!line) {
        if (errno == ENOENT || errno == 0)
            gpio_fail(g, slot, spec, "no line named '%s' on chip %s [%s]", desc, gpiod_chip_name(chip),
                      gpiod_chip_label(chip));
        else
            gpio_fail(g, slot, spec, "cannot read the line names of chip %s: %s", gpiod_chip_name(chip),
                      strerror(errno));
    }
    return line;
}

/** Say why a request failed; EBUSY names the consumer that holds the line. */
static void request_failed(cm_gpio *g, int slot, const char *spec, struct gpiod_line *line) {
    int e = errno;
    if (e == EBUSY) {
        const char *who = (gpiod_line_update(line) == 0) ? gpiod_line_consumer(line) : NULL;
        if (who && *who)
            gpio_fail(g, slot, spec, "line is used by '%s'", who);
        else
            gpio_fail(g, slot, spec, "line is used by another program (no consumer name)");
        return;
    }
    gpio_fail(g, slot, spec, "cannot request the line as %s: %s", slot >= CM_GPIO_NOUT ? "an edge input" : "an output",
              strerror(e));
}

/** Parse "[!]CHIP:LINE", open the chip, find and request the line into slot. */
static int open_one(cm_gpio *g, int slot, const char *spec, const char *consumer) {
    const char *p = spec;
    bool active_low = false;
    if (*p == '!') {
        active_low = true;
        p++;
    }
    /* the LAST ':' separates chip and line, so a label with a ':' in it still works */
    const char *colon = strrchr(p, ':');
    if (!colon || colon == p || colon[1] == '\0')
        return gpio_fail(g, slot, spec, "expected CHIP:LINE (e.g. gpiochip0:busy-led or !decoder-sim:3)");
    size_t chip_len = (size_t)(colon - p);
    if (chip_len >= SPEC_MAX || strlen(colon + 1) >= SPEC_MAX)
        return gpio_fail(g, slot, spec, "chip or line description longer than %d characters", SPEC_MAX - 1);
    char chip_desc[SPEC_MAX];
    memcpy(chip_desc, p, chip_len);
    chip_desc[chip_len] = '\0';

    struct gpiod_chip *chip = open_chip(g, slot, spec, chip_desc);
    if (!chip) return -1;
    struct gpiod_line *line = find_line(g, slot, spec, chip, colon + 1);
    if (!line) {
        gpiod_chip_close(chip);
        return -1;
    }
    int flags = active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
    int rc = (slot >= CM_GPIO_NOUT) ? gpiod_line_request_rising_edge_events_flags(line, consumer, flags)
                                    : gpiod_line_request_output_flags(line, consumer, flags, 0);
    if (rc < 0) {
        request_failed(g, slot, spec, line);
        gpiod_chip_close(chip);
        return -1;
    }
    g->chip[slot] = chip;
    g->line[slot] = line;
    g->active_low[slot] = active_low;
    return 0;
}

int cm_gpio_open(cm_gpio *g, const cm_gpio_config *cfg) {
    memset(g, 0, sizeof *g);
    const char *consumer = (cfg->consumer && *cfg->consumer) ? cfg->consumer : "curvemesh";
    for (int slot = 0; slot < CM_GPIO_SLOTS; slot++) {
        const char *spec = cm_gpio_slot_spec(cfg, slot);
        if (!spec) continue;
        if (open_one(g, slot, spec, consumer) < 0) {
            char keep[sizeof g->err];
            memcpy(keep, g->err, sizeof keep);
            g->open = true;
            cm_gpio_close(g); /* the lines already requested */
            memcpy(g->err, keep, sizeof keep);
            return -1;
        }
    }
    g->open = true;
    return 0;
}

int cm_gpio_set(cm_gpio *g, cm_gpio_line line, int active) {
    if ((int)line < 0 || line >= CM_GPIO_NOUT) {
        snprintf(g->err, sizeof g->err, "gpio: no output line number %d", (int)line);
        return -1;
    }
    struct gpiod_line *l = g->line[line];
    if (!l) return 0;
    if (gpiod_line_set_value(l, active ? 1 : 0) < 0) {
        int e = errno;
        snprintf(g->err, sizeof g->err, "gpio %s (%s line %u): cannot set it to %s: %s", role_name[line],
                 gpiod_chip_name(g->chip[line]), gpiod_line_offset(l), active ? "active" : "inactive", strerror(e));
        return -1;
    }
    return 0;
}

static int input_fd(const cm_gpio *g, int slot) {
    struct gpiod_line *l = g->line[slot];
    return l ? gpiod_line_event_get_fd(l) : -1;
}

/* the rising edges queued on input slot: 1 if any (a press), 0 if none, -1 on error */
static int input_pressed(cm_gpio *g, int slot) {
    struct gpiod_line *l = g->line[slot];
    if (!l) return 0;
    int fd = gpiod_line_event_get_fd(l);
    int pressed = 0;
    /* A bouncing contact queues several edges for one press: drain them all
     * (bounded, in case the line toggles faster than we read). */
    for (int i = 0; i < 64; i++) {
        struct pollfd pfd = {.fd = fd, .events = POLLIN};
        int n = poll(&pfd, 1, 0);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            snprintf(g->err, sizeof g->err, "gpio %s (%s line %u): poll: %s", role_name[slot],
                     gpiod_chip_name(g->chip[slot]), gpiod_line_offset(l), strerror(errno));
            return -1;
        }
        if (n == 0 || !(pfd.revents & POLLIN)) break;
        struct gpiod_line_event ev;
        if (gpiod_line_event_read(l, &ev) < 0) {
            snprintf(g->err, sizeof g->err, "gpio %s (%s line %u): cannot read the edge event: %s", role_name[slot],
                     gpiod_chip_name(g->chip[slot]), gpiod_line_offset(l), strerror(errno));
            return -1;
        }
        if (ev.event_type == GPIOD_LINE_EVENT_RISING_EDGE) pressed = 1;
    }
    return pressed;
}

int cm_gpio_request_fd(const cm_gpio *g) { return input_fd(g, CM_GPIO_NOUT); }
int cm_gpio_request_pressed(cm_gpio *g) { return input_pressed(g, CM_GPIO_NOUT); }

int cm_gpio_button_fd(const cm_gpio *g, cm_gpio_button b) {
    return (unsigned)b < CM_GPIO_NBUTTON ? input_fd(g, CM_GPIO_NOUT + 1 + (int)b) : -1;
}

int cm_gpio_button_pressed(cm_gpio *g, cm_gpio_button b) {
    return (unsigned)b < CM_GPIO_NBUTTON ? input_pressed(g, CM_GPIO_NOUT + 1 + (int)b) : 0;
}

void cm_gpio_close(cm_gpio *g) {
    if (!g->open) return;
    for (int slot = 0; slot < CM_GPIO_SLOTS; slot++) {
        struct gpiod_line *l = g->line[slot];
        if (l) {
            /* a lamp must not stay lit after the program is gone: the kernel
             * keeps the last level of a released output */
            if (slot < CM_GPIO_NOUT) (void)gpiod_line_set_value(l, 0);
            gpiod_line_release(l);
        }
        if (g->chip[slot]) gpiod_chip_close(g->chip[slot]);
        g->line[slot] = NULL;
        g->chip[slot] = NULL;
    }
    g->open = false;
}
