/* cm_drm_none.c - a build without libdrm's headers: a DRM device is refused by name (see cm_drm.h). */
#define _POSIX_C_SOURCE 200809L
#include "cm_drm.h"

#include <string.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>

int cm_drm_is_drm(const char *dev)
{
    struct stat s;
    return stat(dev, &s) == 0 && S_ISCHR(s.st_mode) && major(s.st_rdev) == 226;
}

int cm_drm_open(cm_drm *d, const char *dev, uint32_t background, cm_status *st)
{
    (void)dev;
    (void)background;
    memset(d, 0, sizeof *d);
    d->fd = -1;
    cm_fail(st, CM_E_UNSUPPORTED, "drm: this build has no DRM support (built without libdrm-dev's headers)");
    return -1;
}

void cm_drm_close(cm_drm *d) { (void)d; }
