/*
 * cm_fb.h - a frame on the Linux framebuffer (fbdev: /dev/fb0), the display
 * every board's kernel offers (a DRM driver's fbdev emulation included).
 *
 * The RGB frame goes to the visible screen, centred (cut where the screen is
 * smaller, the rest of the screen in the frame's background colour), in the
 * screen's own pixel format: 16, 24 or 32 bits with the channel offsets and
 * lengths the driver reports (RGB565, XRGB8888, BGR...).  No heap: the
 * screen memory is mapped.
 */
#ifndef CM_FB_H
#define CM_FB_H

#include <stddef.h>
#include <stdint.h>

#include "cm/cm_error.h"

/** The screen's pixel format, as FBIOGET_VSCREENINFO / FSCREENINFO report it. */
typedef struct cm_fb_format {
    uint32_t width, height;       /* visible pixels */
    uint32_t bpp;                 /* 16, 24 or 32 */
    uint32_t stride;              /* bytes a row */
    uint32_t xoffset, yoffset;    /* the visible area's corner in the memory */
    uint32_t r_off, r_len, g_off, g_len, b_off, b_len; /* bit offset and length of each channel */
} cm_fb_format;

/** The screen's size and format (0 on success; -1 with st saying why). */
int cm_fb_query(const char *dev, cm_fb_format *fmt, cm_status *st);

/**
 * Put the w x h frame rgb (3 bytes a pixel, rows from the top) on the screen of format fmt whose
 * memory is mem: centred, the rest of the screen background (0xRRGGBB).  Pure: the tests run it on
 * plain memory.
 */
void cm_fb_compose(const cm_fb_format *fmt, uint8_t *mem, const uint8_t *rgb, uint32_t w, uint32_t h,
                   uint32_t background);

/** The w x h frame on the screen's last rows, from its left edge (cut to the screen), nothing else
 *  touched: a status line over what the screen shows. */
void cm_fb_compose_bottom(const cm_fb_format *fmt, uint8_t *mem, const uint8_t *rgb, uint32_t w, uint32_t h);

/** cm_fb_query, map the screen, cm_fb_compose, unmap (0 on success; -1 with st saying why). */
int cm_fb_show(const char *dev, const uint8_t *rgb, uint32_t w, uint32_t h, uint32_t background, cm_status *st);

/** The same with cm_fb_compose_bottom. */
int cm_fb_show_bottom(const char *dev, const uint8_t *rgb, uint32_t w, uint32_t h, cm_status *st);

#endif /* CM_FB_H */
