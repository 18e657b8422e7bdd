/*
 * test_fb.c - the framebuffer output's pixel work (platform/cm_fb.c,
 * cm_fb_compose) on plain memory: the frame centred on a larger screen with
 * the background round it, cut on a smaller one, in XRGB8888, RGB565 and a
 * 24-bit BGR layout, at the visible area's offset, the row padding left
 * alone.  (The device itself: tests/hw/vm-display.sh, on a real kernel's
 * framebuffer in the test VM.)
 */
#include "test_util.h"

#include "cm_fb.h"

static uint8_t mem[64 * 1024];

static uint32_t get(const cm_fb_format *f, uint32_t x, uint32_t y)
{
    const uint8_t *p = mem + (size_t)(f->yoffset + y) * f->stride + (size_t)(f->xoffset + x) * (f->bpp / 8);
    uint32_t v = 0;
    for (uint32_t k = 0; k < f->bpp / 8; k++)
        v |= (uint32_t)p[k] << (8 * k);
    return v;
}

/* a 4 x 2 frame: pixel (x, y) is (10 x + 1, 20 y + 2, 30) */
static uint8_t frame[4 * 2 * 3];
static void make_frame(void)
{
    for (int y = 0; y < 2; y++)
        for (int x = 0; x < 4; x++) {
            uint8_t *p = frame + (y * 4 + x) * 3;
            p[0] = (uint8_t)(10 * x + 1), p[1] = (uint8_t)(20 * y + 2), p[2] = 30;
        }
}

static void test_xrgb_centred(void **state)
{
    (void)state;
    make_frame();
    cm_fb_format f = {.width = 8, .height = 6, .bpp = 32, .stride = 8 * 4 + 12, .xoffset = 0, .yoffset = 1,
                      .r_off = 16, .r_len = 8, .g_off = 8, .g_len = 8, .b_off = 0, .b_len = 8};
    memset(mem, 0xee, sizeof mem);
    cm_fb_compose(&f, mem, frame, 4, 2, 0x112233u);
    /* the frame's corner at ((8 - 4) / 2, (6 - 2) / 2) = (2, 2) */
    assert_int_equal(get(&f, 2, 2), (1u << 16) | (2u << 8) | 30u);
    assert_int_equal(get(&f, 5, 3), (31u << 16) | (22u << 8) | 30u);
    assert_int_equal(get(&f, 0, 0), 0x112233u);
    assert_int_equal(get(&f, 7, 5), 0x112233u);
    assert_int_equal(get(&f, 6, 2), 0x112233u);
    /* the row padding and the rows above the visible area are not touched */
    assert_int_equal(mem[1 * f.stride + 8 * 4], 0xee);
    assert_int_equal(mem[0], 0xee);
}

static void test_rgb565_cut(void **state)
{
    (void)state;
    make_frame();
    cm_fb_format f = {.width = 2, .height = 1, .bpp = 16, .stride = 4, .r_off = 11, .r_len = 5, .g_off = 5,
                      .g_len = 6, .b_off = 0, .b_len = 5};
    cm_fb_compose(&f, mem, frame, 4, 2, 0);
    /* a 2 x 1 screen shows the frame's middle: corner (-1, 0) -> pixels (1, 0) and (2, 0) */
    assert_int_equal(get(&f, 0, 0), ((11u >> 3) << 11) | ((2u >> 2) << 5) | (30u >> 3));
    assert_int_equal(get(&f, 1, 0), ((21u >> 3) << 11) | ((2u >> 2) << 5) | (30u >> 3));
}

static void test_bgr24(void **state)
{
    (void)state;
    make_frame();
    cm_fb_format f = {.width = 4, .height = 2, .bpp = 24, .stride = 12, .r_off = 0, .r_len = 8, .g_off = 8,
                      .g_len = 8, .b_off = 16, .b_len = 8};
    cm_fb_compose(&f, mem, frame, 4, 2, 0);
    assert_int_equal(mem[12 + 3 * 3 + 0], 31); /* pixel (3, 1): red first in memory */
    assert_int_equal(mem[12 + 3 * 3 + 1], 22);
    assert_int_equal(mem[12 + 3 * 3 + 2], 30);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_xrgb_centred),
        cmocka_unit_test(test_rgb565_cut),
        cmocka_unit_test(test_bgr24),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
