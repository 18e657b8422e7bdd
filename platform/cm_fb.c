/* cm_fb.c - a frame on the Linux framebuffer (see cm_fb.h). */
#define _POSIX_C_SOURCE 200809L
#include "cm_fb.h"
#include "cm_report.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/fb.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

static int fb_fail(cm_status *st, const char *where)
{
    cm_fail_errno(st, where);
    return -1;
}

static int query_fd(int fd, cm_fb_format *fmt, cm_status *st)
{
    struct fb_var_screeninfo var;
    struct fb_fix_screeninfo fix;
    if (ioctl(fd, FBIOGET_VSCREENINFO, &var) != 0 || ioctl(fd, FBIOGET_FSCREENINFO, &fix) != 0)
        return fb_fail(st, "fb: not a framebuffer (FBIOGET_VSCREENINFO)");
    if (fix.type != FB_TYPE_PACKED_PIXELS || fix.visual != FB_VISUAL_TRUECOLOR ||
        (var.bits_per_pixel != 16 && var.bits_per_pixel != 24 && var.bits_per_pixel != 32)) {
        cm_fail(st, CM_E_UNSUPPORTED, "fb: not a 16, 24 or 32-bit true-colour framebuffer");
        return -1;
    }
    fmt->width = var.xres;
    fmt->height = var.yres;
    fmt->bpp = var.bits_per_pixel;
    fmt->stride = fix.line_length;
    fmt->xoffset = var.xoffset;
    fmt->yoffset = var.yoffset;
    fmt->r_off = var.red.offset, fmt->r_len = var.red.length;
    fmt->g_off = var.green.offset, fmt->g_len = var.green.length;
    fmt->b_off = var.blue.offset, fmt->b_len = var.blue.length;
    /* the visible area must lie in the memory the driver maps */
    uint64_t need = ((uint64_t)fmt->yoffset + fmt->height) * fmt->stride;
    if (fmt->r_len > 8 || fmt->g_len > 8 || fmt->b_len > 8 || fmt->stride < (uint64_t)fmt->width * (fmt->bpp / 8) ||
        need > fix.smem_len) {
        cm_fail(st, CM_E_UNSUPPORTED, "fb: a layout this viewer does not know");
        return -1;
    }
    return 0;
}

int cm_fb_query(const char *dev, cm_fb_format *fmt, cm_status *st)
{
    int fd = open(dev, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return fb_fail(st, "fb: open");
    int r = query_fd(fd, fmt, st);
    close(fd);
    return r;
}

/* a channel of 8 bits in a field of len bits at off */
static uint32_t field(uint32_t c8, uint32_t off, uint32_t len)
{
    return len == 0 ? 0 : (c8 >> (8 - len)) << off;
}

static uint32_t pixel(const cm_fb_format *f, uint32_t r, uint32_t g, uint32_t b)
{
    return field(r, f->r_off, f->r_len) | field(g, f->g_off, f->g_len) | field(b, f->b_off, f->b_len);
}

void cm_fb_compose(const cm_fb_format *fmt, uint8_t *mem, const uint8_t *rgb, uint32_t w, uint32_t h,
                   uint32_t background)
{
    uint32_t bytes = fmt->bpp / 8;
    uint32_t bg = pixel(fmt, (background >> 16) & 0xffu, (background >> 8) & 0xffu, background & 0xffu);
    /* the frame's corner on the screen (negative: the frame is cut) */
    int64_t x0 = ((int64_t)fmt->width - (int64_t)w) / 2, y0 = ((int64_t)fmt->height - (int64_t)h) / 2;
    for (uint32_t y = 0; y < fmt->height; y++) {
        uint8_t *row = mem + (uint64_t)(fmt->yoffset + y) * fmt->stride + (uint64_t)fmt->xoffset * bytes;
        int64_t fy = (int64_t)y - y0;
        for (uint32_t x = 0; x < fmt->width; x++) {
            int64_t fx = (int64_t)x - x0;
            uint32_t v = bg;
            if (fy >= 0 && fy < (int64_t)h && fx >= 0 && fx < (int64_t)w) {
                const uint8_t *p = rgb + ((uint64_t)fy * w + (uint64_t)fx) * 3;
                v = pixel(fmt, p[0], p[1], p[2]);
            }
            for (uint32_t k = 0; k < bytes; k++) /* little-endian, as the kernel's fbdev formats are */
                row[(uint64_t)x * bytes + k] = (uint8_t)(v >> (8 * k));
        }
    }
}

void cm_fb_compose_bottom(const cm_fb_format *fmt, uint8_t *mem, const uint8_t *rgb, uint32_t w, uint32_t h)
{
    uint32_t bytes = fmt->bpp / 8, rows = h < fmt->height ? h : fmt->height, cols = w < fmt->width ? w : fmt->width;
    for (uint32_t r = 0; r < rows; r++) {
        uint32_t y = fmt->height - rows + r, fy = h - rows + r;
        uint8_t *row = mem + (uint64_t)(fmt->yoffset + y) * fmt->stride + (uint64_t)fmt->xoffset * bytes;
        for (uint32_t x = 0; x < cols; x++) {
            const uint8_t *p = rgb + ((uint64_t)fy * w + x) * 3;
            uint32_t v = pixel(fmt, p[0], p[1], p[2]);
            for (uint32_t k = 0; k < bytes; k++)
                row[(uint64_t)x * bytes + k] = (uint8_t)(v >> (8 * k));
        }
    }
}

/* map dev's screen and put the frame on it: centred over a background, or (bottom) on its last rows */
static int show(const char *dev, const uint8_t *rgb, uint32_t w, uint32_t h, uint32_t background, int bottom,
                cm_status *st)
{
    int fd = open(dev, O_RDWR | O_CLOEXEC);
    if (fd < 0)
        return fb_fail(st, "fb: open");
    cm_fb_format fmt;
    if (query_fd(fd, &fmt, st) != 0) {
        close(fd);
        return -1;
    }
    size_t len = (size_t)(fmt.yoffset + fmt.height) * fmt.stride;
    void *mem = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    if (mem == MAP_FAILED) {
        fb_fail(st, "fb: mmap");
        close(fd);
        return -1;
    }
    if (bottom)
        cm_fb_compose_bottom(&fmt, mem, rgb, w, h);
    else
        cm_fb_compose(&fmt, mem, rgb, w, h, background);
    munmap(mem, len);
    close(fd);
    return 0;
}

int cm_fb_show(const char *dev, const uint8_t *rgb, uint32_t w, uint32_t h, uint32_t background, cm_status *st)
{
    return show(dev, rgb, w, h, background, 0, st);
}

int cm_fb_show_bottom(const char *dev, const uint8_t *rgb, uint32_t w, uint32_t h, cm_status *st)
{
    return show(dev, rgb, w, h, 0, 1, st);
}
