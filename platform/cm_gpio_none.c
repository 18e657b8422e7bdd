/*
 * cm_gpio_none.c - the GPIO back end of a build without libgpiod 1.6.
 *
 * A terminal with no lamps and no button configured runs as usual; one that
 * names a line gets told at start-up that this binary cannot drive it,
 * instead of lamps that silently never light.
 */
#include "cm_gpio.h"

#include <stdio.h>
#include <string.h>

int cm_gpio_open(cm_gpio *g, const cm_gpio_config *cfg) {
    static const char *const role_name[CM_GPIO_SLOTS] = CM_GPIO_ROLE_NAMES;
    memset(g, 0, sizeof *g);
    for (int slot = 0; slot < CM_GPIO_SLOTS; slot++) {
        const char *spec = cm_gpio_slot_spec(cfg, slot);
        if (!spec) continue;
        snprintf(g->err, sizeof g->err,
                 "gpio %s=%s: this build has no GPIO support (libgpiod 1.6 was not found at build time)",
                 role_name[slot], spec);
        return -1;
    }
    g->open = true;
    return 0;
}

int cm_gpio_set(cm_gpio *g, cm_gpio_line line, int active) {
    (void)active;
    if ((int)line < 0 || line >= CM_GPIO_NOUT) {
        snprintf(g->err, sizeof g->err, "gpio: no output line number %d", (int)line);
        return -1;
    }
    return 0; /* no line can be configured, so every line is unused */
}

int cm_gpio_request_fd(const cm_gpio *g) {
    (void)g;
    return -1;
}

int cm_gpio_request_pressed(cm_gpio *g) {
    (void)g;
    return 0;
}

int cm_gpio_button_fd(const cm_gpio *g, cm_gpio_button b) {
    (void)g;
    (void)b;
    return -1;
}

int cm_gpio_button_pressed(cm_gpio *g, cm_gpio_button b) {
    (void)g;
    (void)b;
    return 0;
}

void cm_gpio_close(cm_gpio *g) {
    g->open = false;
}
