/*
 * cm_gpio.h - the terminal's signal lines: what the operator sees (busy,
 * ready, error lamps), the button that asks for the model again, and the
 * viewer's buttons (rotate, next step, previous step, reset view: issue 17).
 *
 * One back end, cm_gpio_gpiod.c (libgpiod 1.6, the only file that includes
 * <gpiod.h>); a build without libgpiod gets cm_gpio_none.c, whose open
 * fails with a clear message when any line is configured.  A line is named
 * "CHIP:LINE": CHIP is a chip name (gpiochip0), path (/dev/gpiochip0) or
 * label (decoder-sim); LINE is a line name (busy-led) or an offset (3).
 * A leading '!' makes the line active-low ("!gpiochip0:4").
 * Lines left NULL are not used.
 */
#ifndef CM_GPIO_H
#define CM_GPIO_H

#include <stdbool.h>
#include <stddef.h>

typedef enum cm_gpio_line { CM_GPIO_BUSY, CM_GPIO_READY, CM_GPIO_ERROR, CM_GPIO_NOUT } cm_gpio_line;

/* the viewer's buttons (cmz-view --gpio-rotate ...) */
typedef enum cm_gpio_button {
    CM_GPIO_ROTATE,
    CM_GPIO_NEXT,
    CM_GPIO_PREV,
    CM_GPIO_RESET,
    CM_GPIO_NBUTTON
} cm_gpio_button;

/* slots: the outputs, the request button, the viewer's buttons */
#define CM_GPIO_SLOTS (CM_GPIO_NOUT + 1 + CM_GPIO_NBUTTON)

typedef struct cm_gpio_config {
    const char *out[CM_GPIO_NOUT]; /* output lines, NULL = unused */
    const char *request;           /* input line (button), rising edge = pressed; NULL = unused */
    const char *consumer;          /* consumer name shown by gpioinfo ("cmz-terminal") */
    const char *button[CM_GPIO_NBUTTON]; /* the viewer's input lines, as request; NULL = unused */
} cm_gpio_config;

/* each slot's name in messages, as the configuration calls it (both back ends) */
#define CM_GPIO_ROLE_NAMES {"busy", "ready", "error", "request", "rotate", "next", "prev", "reset"}

/** The line configured for slot `slot` (an output, the request button, a viewer's button), or NULL. */
static inline const char *cm_gpio_slot_spec(const cm_gpio_config *cfg, int slot)
{
    return slot < CM_GPIO_NOUT ? cfg->out[slot] : slot == CM_GPIO_NOUT ? cfg->request : cfg->button[slot - CM_GPIO_NOUT - 1];
}

typedef struct cm_gpio {
    void *chip[CM_GPIO_SLOTS]; /* back end's handles (libgpiod: struct gpiod_chip *) */
    void *line[CM_GPIO_SLOTS]; /* (struct gpiod_line *) */
    bool active_low[CM_GPIO_SLOTS];
    bool open;
    char err[192];
} cm_gpio;

/** Request every configured line (outputs start inactive). @return 0, or -1 with g->err set */
int cm_gpio_open(cm_gpio *g, const cm_gpio_config *cfg);
/** Drive an output line (1 = active); unused lines are ignored. @return 0 or -1 */
int cm_gpio_set(cm_gpio *g, cm_gpio_line line, int active);
/** A file descriptor that becomes readable on a request edge (poll it with the link), or -1. */
int cm_gpio_request_fd(const cm_gpio *g);
/** Consume pending request edges. @return 1 if the button was pressed since the last call, 0 if not, -1 on error */
int cm_gpio_request_pressed(cm_gpio *g);
/** The same for a viewer's button: its fd (-1 when not configured), and whether it was pressed. */
int cm_gpio_button_fd(const cm_gpio *g, cm_gpio_button b);
int cm_gpio_button_pressed(cm_gpio *g, cm_gpio_button b);
/** Release every line (outputs go inactive first); safe to call twice. */
void cm_gpio_close(cm_gpio *g);

#endif /* CM_GPIO_H */
