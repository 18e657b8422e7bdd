/* cm_drm.c - a frame on a Linux DRM/KMS device (see cm_drm.h). */
#define _POSIX_C_SOURCE 200809L
#include "cm_drm.h"
#include "cm_report.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <drm.h>
#include <drm_mode.h>

#define DRM_MAJOR 226
#define MAX_IDS 32    /* CRTCs, connectors, encoders looked at (a board has a handful) */
#define MAX_MODES 64  /* a connector's modes looked at (the preferred one comes first in practice) */

static int xioctl(int fd, unsigned long req, void *arg)
{
    int r;
    do
        r = ioctl(fd, req, arg);
    while (r == -1 && (errno == EINTR || errno == EAGAIN));
    return r;
}

int cm_drm_is_drm(const char *dev)
{
    struct stat s;
    return stat(dev, &s) == 0 && S_ISCHR(s.st_mode) && major(s.st_rdev) == DRM_MAJOR;
}

void cm_drm_close(cm_drm *d)
{
    if (d->map)
        munmap(d->map, (size_t)d->map_size);
    if (d->fd >= 0) {
        if (d->fb) {
            uint32_t fb = d->fb;
            xioctl(d->fd, DRM_IOCTL_MODE_RMFB, &fb);
        }
        if (d->handle) {
            struct drm_mode_destroy_dumb dd = {.handle = d->handle};
            xioctl(d->fd, DRM_IOCTL_MODE_DESTROY_DUMB, &dd);
        }
        close(d->fd);
    }
    memset(d, 0, sizeof *d);
    d->fd = -1;
}

static int drm_fail(cm_drm *d, cm_status *st, cm_err code, const char *where)
{
    if (code == CM_E_IO)
        cm_fail_errno(st, where);
    else
        cm_fail(st, code, where);
    cm_drm_close(d);
    return -1;
}

/* a CRTC that can drive connector c (its current encoder's, else one its encoders allow): 0 if none */
static uint32_t crtc_for(int fd, const struct drm_mode_get_connector *c, const uint32_t *encoders,
                         const uint32_t *crtcs, uint32_t ncrtcs)
{
    struct drm_mode_get_encoder e;
    if (c->encoder_id) {
        memset(&e, 0, sizeof e);
        e.encoder_id = c->encoder_id;
        if (xioctl(fd, DRM_IOCTL_MODE_GETENCODER, &e) == 0 && e.crtc_id)
            return e.crtc_id;
    }
    for (uint32_t k = 0; k < c->count_encoders && k < MAX_IDS; k++) {
        memset(&e, 0, sizeof e);
        e.encoder_id = encoders[k];
        if (xioctl(fd, DRM_IOCTL_MODE_GETENCODER, &e) != 0)
            continue;
        for (uint32_t i = 0; i < ncrtcs && i < 32; i++)
            if (e.possible_crtcs & (1u << i))
                return crtcs[i];
    }
    return 0;
}

int cm_drm_open(cm_drm *d, const char *dev, uint32_t background, cm_status *st)
{
    memset(d, 0, sizeof *d);
    d->fd = open(dev, O_RDWR | O_CLOEXEC);
    if (d->fd < 0)
        return drm_fail(d, st, CM_E_IO, "drm: open");
    struct drm_get_cap cap = {.capability = DRM_CAP_DUMB_BUFFER};
    if (xioctl(d->fd, DRM_IOCTL_GET_CAP, &cap) != 0 || cap.value == 0)
        return drm_fail(d, st, CM_E_UNSUPPORTED, "drm: the device has no dumb buffers (not a KMS device?)");
    /* the card's CRTCs, connectors and encoders (the first MAX_IDS of each) */
    uint32_t crtcs[MAX_IDS], connectors[MAX_IDS], encoders[MAX_IDS];
    struct drm_mode_card_res res;
    memset(&res, 0, sizeof res);
    if (xioctl(d->fd, DRM_IOCTL_MODE_GETRESOURCES, &res) != 0)
        return drm_fail(d, st, CM_E_IO, "drm: the card's resources (DRM_IOCTL_MODE_GETRESOURCES)");
    res.count_fbs = 0;
    res.fb_id_ptr = 0;
    res.count_crtcs = res.count_crtcs < MAX_IDS ? res.count_crtcs : MAX_IDS;
    res.count_connectors = res.count_connectors < MAX_IDS ? res.count_connectors : MAX_IDS;
    res.count_encoders = res.count_encoders < MAX_IDS ? res.count_encoders : MAX_IDS;
    res.crtc_id_ptr = (uint64_t)(uintptr_t)crtcs;
    res.connector_id_ptr = (uint64_t)(uintptr_t)connectors;
    res.encoder_id_ptr = (uint64_t)(uintptr_t)encoders;
    uint32_t ncrtcs = res.count_crtcs, nconnectors = res.count_connectors;
    if (xioctl(d->fd, DRM_IOCTL_MODE_GETRESOURCES, &res) != 0)
        return drm_fail(d, st, CM_E_IO, "drm: the card's resources (DRM_IOCTL_MODE_GETRESOURCES)");
    ncrtcs = res.count_crtcs < ncrtcs ? res.count_crtcs : ncrtcs;
    nconnectors = res.count_connectors < nconnectors ? res.count_connectors : nconnectors;
    /* the first connected connector with a mode and a CRTC for it; its preferred mode */
    static struct drm_mode_modeinfo modes[MAX_MODES]; /* (static: 4 KiB off the stack) */
    struct drm_mode_modeinfo mode;
    uint32_t conn_encoders[MAX_IDS];
    int found = 0;
    for (uint32_t i = 0; i < nconnectors && !found; i++) {
        struct drm_mode_get_connector c;
        memset(&c, 0, sizeof c);
        c.connector_id = connectors[i];
        if (xioctl(d->fd, DRM_IOCTL_MODE_GETCONNECTOR, &c) != 0 || c.connection != 1 || c.count_modes == 0)
            continue;
        uint32_t nmodes = c.count_modes < MAX_MODES ? c.count_modes : MAX_MODES;
        uint32_t nenc = c.count_encoders < MAX_IDS ? c.count_encoders : MAX_IDS;
        memset(&c, 0, sizeof c);
        c.connector_id = connectors[i];
        c.count_modes = nmodes;
        c.modes_ptr = (uint64_t)(uintptr_t)modes;
        c.count_encoders = nenc;
        c.encoders_ptr = (uint64_t)(uintptr_t)conn_encoders;
        if (xioctl(d->fd, DRM_IOCTL_MODE_GETCONNECTOR, &c) != 0 || c.count_modes == 0)
            continue;
        nmodes = c.count_modes < nmodes ? c.count_modes : nmodes;
        c.count_encoders = c.count_encoders < nenc ? c.count_encoders : nenc;
        mode = modes[0];
        for (uint32_t k = 0; k < nmodes; k++)
            if (modes[k].type & DRM_MODE_TYPE_PREFERRED) {
                mode = modes[k];
                break;
            }
        d->crtc = crtc_for(d->fd, &c, conn_encoders, crtcs, ncrtcs);
        d->connector = connectors[i];
        found = d->crtc != 0 && mode.hdisplay > 0 && mode.vdisplay > 0;
    }
    if (!found)
        return drm_fail(d, st, CM_E_UNSUPPORTED, "drm: no connected screen with a mode and a CRTC");
    /* a dumb buffer of the mode's size, 32 bits a pixel (XRGB8888), mapped and filled */
    struct drm_mode_create_dumb cd = {.height = mode.vdisplay, .width = mode.hdisplay, .bpp = 32};
    if (xioctl(d->fd, DRM_IOCTL_MODE_CREATE_DUMB, &cd) != 0)
        return drm_fail(d, st, CM_E_IO, "drm: a dumb buffer (DRM_IOCTL_MODE_CREATE_DUMB)");
    d->handle = cd.handle;
    struct drm_mode_fb_cmd fc = {.width = mode.hdisplay, .height = mode.vdisplay, .pitch = cd.pitch, .bpp = 32,
                                 .depth = 24, .handle = cd.handle};
    if (xioctl(d->fd, DRM_IOCTL_MODE_ADDFB, &fc) != 0)
        return drm_fail(d, st, CM_E_IO, "drm: a framebuffer of the buffer (DRM_IOCTL_MODE_ADDFB)");
    d->fb = fc.fb_id;
    struct drm_mode_map_dumb md = {.handle = cd.handle};
    if (xioctl(d->fd, DRM_IOCTL_MODE_MAP_DUMB, &md) != 0)
        return drm_fail(d, st, CM_E_IO, "drm: mapping the buffer (DRM_IOCTL_MODE_MAP_DUMB)");
    void *map = mmap(NULL, (size_t)cd.size, PROT_READ | PROT_WRITE, MAP_SHARED, d->fd, (off_t)md.offset);
    if (map == MAP_FAILED)
        return drm_fail(d, st, CM_E_IO, "drm: mapping the buffer (mmap)");
    d->map = map;
    d->map_size = cd.size;
    d->fmt = (cm_fb_format){.width = mode.hdisplay, .height = mode.vdisplay, .bpp = 32, .stride = cd.pitch,
                            .r_off = 16, .r_len = 8, .g_off = 8, .g_len = 8, .b_off = 0, .b_len = 8};
    for (uint32_t y = 0; y < d->fmt.height; y++) {
        uint32_t *row = (uint32_t *)(void *)(d->map + (size_t)y * d->fmt.stride);
        for (uint32_t x = 0; x < d->fmt.width; x++)
            row[x] = background & 0xffffffu;
    }
    /* on the screen (the buffer stays shown while the device is open) */
    struct drm_mode_crtc sc;
    memset(&sc, 0, sizeof sc);
    sc.crtc_id = d->crtc;
    sc.fb_id = d->fb;
    sc.set_connectors_ptr = (uint64_t)(uintptr_t)&d->connector;
    sc.count_connectors = 1;
    sc.mode = mode;
    sc.mode_valid = 1;
    if (xioctl(d->fd, DRM_IOCTL_MODE_SETCRTC, &sc) != 0)
        return drm_fail(d, st, CM_E_IO, "drm: showing the buffer (DRM_IOCTL_MODE_SETCRTC; another program holds "
                                        "the screen?)");
    return 0;
}
