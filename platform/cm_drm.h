/*
 * cm_drm.h - a frame on a Linux DRM/KMS device (/dev/dri/card0): a dumb buffer (XRGB8888, the format
 * every KMS driver scans out) at the mode the first connected connector prefers, shown on a CRTC
 * that can drive it, for boards whose kernel has no framebuffer device (no fbdev emulation).
 *
 * The kernel's own ioctls (libdrm's headers, Debian's libdrm-dev; not libdrm's drmModeGet*, which
 * allocate): no heap.  The screen belongs to the process while it holds the device open: the kernel
 * takes the buffer off the screen when it is closed, so a program that shows a picture this way
 * stays until it is told to go (cmz-view waits for SIGTERM or SIGINT).  Opening needs DRM master
 * (no other program, a display server or another viewer, drawing on that device).
 *
 * The frame is put into the mapped buffer with cm_fb_compose and cm_fb_compose_bottom (cm_fb.h),
 * the buffer's layout given as a framebuffer format.
 */
#ifndef CM_DRM_H
#define CM_DRM_H

#include <stdint.h>

#include "cm/cm_error.h"
#include "cm_fb.h"

typedef struct cm_drm {
    int fd;
    uint32_t crtc, connector, fb, handle;
    uint8_t *map;      /* the dumb buffer, mapped */
    uint64_t map_size;
    cm_fb_format fmt;  /* its layout: the mode's size, 32 bits, XRGB */
} cm_drm;

/** 1 when dev is a DRM device (character major 226), else 0 (an fbdev device, or none). */
int cm_drm_is_drm(const char *dev);

/** Open dev, find a connected screen and its preferred mode, make a dumb buffer of its size filled
    with `background` and show it (0; -1 with st saying why, nothing left open). */
int cm_drm_open(cm_drm *d, const char *dev, uint32_t background, cm_status *st);

/** Close the device (the kernel takes the buffer off the screen). */
void cm_drm_close(cm_drm *d);

#endif /* CM_DRM_H */
