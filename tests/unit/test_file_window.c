/*
 * test_file_window.c - the decoder's file window (issue 15: the terminal does not hold the whole
 * .cmz): a file longer than CM_FILE_WINDOW_BYTES is checked as it is fed and its sections read
 * again through the source (cm_dec_set_source).  On the terminal profile (8 KiB) the two files
 * below are longer than the window; on the workstation and tiny profiles the window is the whole
 * file (and tiny refuses them by their needs), and each test checks that side instead.
 *
 *  - tests/data/window/geo_example_tol2e-4.cmz: format 4.6, one stream, 13 241 bytes;
 *  - tests/data/window/geo_example_tol2e-4_v45.cmz, _v40.cmz: formats 4.5 and 4.0, five streams
 *    (a window reaches past a section's end into the next: the CRC of what is read again must
 *    follow, or a change in a later section went unnoticed);
 *  - tests/data/old_formats/geo_example_v26.cmz: format 2.6, a CRC per section, 13 041 bytes.
 *
 * Run from the repository's root (as make runs the unit tests).
 */
#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "test_util.h"

#include "cm/cm_decode.h"
#include "cm/cm_limits_info.h"

#define NFILES 4
static const char *const files[NFILES] = {
    "tests/data/window/geo_example_tol2e-4.cmz", "tests/data/window/geo_example_tol2e-4_v45.cmz",
    "tests/data/window/geo_example_tol2e-4_v40.cmz", "tests/data/old_formats/geo_example_v26.cmz"};

static uint8_t file[1 << 16];
static size_t nfile;
static cm_decoder dec; /* one: the workstation profile's is gigabytes of (untouched) storage */

static void load(const char *path)
{
    int fd = open(path, O_RDONLY);
    if (fd < 0)
        fail_msg("%s: cannot open (run from the repository's root)", path);
    ssize_t n = read(fd, file, sizeof file);
    close(fd);
    assert_true(n > 0 && (size_t)n < sizeof file);
    nfile = (size_t)n;
}

/* the source: the file in memory, failing from byte fail_at on, or with byte flip_at changed */
static long fail_at = -1, flip_at = -1, src_calls;

static int mem_read(void *ctx, uint32_t off, uint8_t *buf, size_t n)
{
    (void)ctx;
    src_calls++;
    if ((uint64_t)off + n > nfile || (fail_at >= 0 && (long)(off + n) > fail_at))
        return -1;
    memcpy(buf, file + off, n);
    if (flip_at >= (long)off && flip_at < (long)(off + n))
        buf[flip_at - (long)off] ^= 0x10;
    return 0;
}

/* feed the file in chunks of `chunk`, set the source (or not), finish */
static cm_err decode(cm_decoder *d, size_t chunk, int with_source, cm_status *st)
{
    cm_dec_init(d);
    cm_status_init(st);
    src_calls = 0;
    for (size_t at = 0; at < nfile; at += chunk) {
        cm_err e = cm_dec_feed(d, file + at, nfile - at < chunk ? nfile - at : chunk, st);
        if (e != CM_OK)
            return e;
    }
    if (with_source)
        cm_dec_set_source(d, mem_read, NULL);
    return cm_dec_finish(d, st);
}

static int windowed(void) { return nfile > (size_t)CM_FILE_WINDOW_BYTES; }

/* the header refuses the file on a profile that cannot hold the model: tiny, and only tiny */
static int fits(void)
{
    cm_status st;
    cm_dec_init(&dec);
    cm_status_init(&st);
    int ok = cm_dec_feed(&dec, file, nfile, &st) != CM_E_LIMIT;
    assert_int_equal(ok, strcmp(cm_profile_name, "tiny") != 0);
    return ok;
}

static uint64_t fnv(const void *p, size_t n)
{
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < n; i++)
        h = (h ^ ((const uint8_t *)p)[i]) * 1099511628211ull;
    return h;
}

/* fn on each of the two files, where this profile can hold its model */
static void each_file(void (*fn)(void))
{
    for (int k = 0; k < NFILES; k++) {
        load(files[k]);
        if (fits())
            fn();
    }
}

static void test_read_through_window_of(void)
{
    cm_status st;
    fail_at = flip_at = -1;
    assert_int_equal(decode(&dec, nfile, 1, &st), CM_OK);
    assert_int_equal(dec.model.nfaces, 8);
    assert_int_equal(dec.model.nedges, 30);
    uint32_t nctrl = dec.model.nctrl;
    uint64_t hc = fnv(dec.model.ctrl, nctrl * sizeof dec.model.ctrl[0]);
    uint64_t hf = fnv(dec.model.faces, 8 * sizeof dec.model.faces[0]);
    /* windowed, it reads the body again, in windows; else never */
    if (windowed())
        assert_true(src_calls >= (long)(nfile / CM_FILE_WINDOW_BYTES));
    else
        assert_int_equal(src_calls, 0);
    /* the same model however the bytes arrive */
    assert_int_equal(decode(&dec, 1000, 1, &st), CM_OK);
    assert_int_equal(dec.model.nctrl, nctrl);
    assert_true(fnv(dec.model.ctrl, nctrl * sizeof dec.model.ctrl[0]) == hc);
    assert_true(fnv(dec.model.faces, 8 * sizeof dec.model.faces[0]) == hf);
}

static void test_read_through_window(void **state)
{
    (void)state;
    each_file(test_read_through_window_of);
}

static void test_no_source_of(void)
{
    cm_status st;
    cm_err e = decode(&dec, 4096, 0, &st);
    if (windowed()) {
        assert_int_equal(e, CM_E_ARG);
        assert_non_null(strstr(st.where, "no source"));
    } else {
        assert_int_equal(e, CM_OK);
    }
}

static void test_no_source(void **state)
{
    (void)state;
    each_file(test_no_source_of);
}

static void test_source_fails_of(void)
{
    for (long at = (long)CM_FILE_WINDOW_BYTES; at < (long)nfile; at += 1500) {
        fail_at = at;
        cm_status st;
        cm_err e = decode(&dec, nfile, 1, &st);
        assert_int_equal(e, windowed() ? CM_E_IO : CM_OK);
        assert_int_equal(st.code, e); /* the status says so too (the terminal reports st.code) */
    }
    fail_at = -1;
}

static void test_source_fails(void **state)
{
    (void)state;
    each_file(test_source_fails_of);
}

/* a file that changes between its receipt and its decoding: refused, never a model of other bytes
   passed off as the checked one (the CRC of what is read again, or a section's own CRC) */
static void test_file_changed_of(void)
{
    long crc_refusals = 0, tried = 0;
    for (long at = (long)CM_FILE_WINDOW_BYTES; at < (long)nfile - 4; at += 37) {
        flip_at = at;
        cm_status st;
        cm_err e = decode(&dec, nfile, 1, &st);
        tried++;
        if (!windowed()) { /* the source is never read: the bytes fed are the file */
            assert_int_equal(e, CM_OK);
            continue;
        }
        assert_int_not_equal(e, CM_OK); /* every change refused, in every format */
        assert_int_equal(st.code, e);
        crc_refusals += e == CM_E_CRC;
    }
    flip_at = -1;
    if (windowed() && tried > 0) /* most changes decode as some model: the CRC refuses them */
        assert_true(crc_refusals * 2 > tried);
}

static void test_file_changed(void **state)
{
    (void)state;
    each_file(test_file_changed_of);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_read_through_window),
        cmocka_unit_test(test_no_source),
        cmocka_unit_test(test_source_fails),
        cmocka_unit_test(test_file_changed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
