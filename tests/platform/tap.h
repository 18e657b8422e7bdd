/*
 * tap.h - the few TAP helpers the platform tests share.  Plain TAP rather
 * than cmocka: these tests fork, exec the pty relay and run under
 * qemu-aarch64 without needing a foreign-architecture cmocka.
 *
 *   TAP_CHECK(cond, "what %d", x)   prints "ok N - what" or "not ok N - what: <cond> failed (file:line)"
 *   tap_skip("what", "why")         prints "not ok N # SKIP what: why" (cmocka's form, which
 *                                   tests/tools/run_suites.sh counts as skipped, not passed)
 *   return tap_done();              prints "1..N", returns 0 iff nothing failed
 */
#ifndef CM_TEST_TAP_H
#define CM_TEST_TAP_H

#include <stdio.h>

static int tap_n, tap_failed;

#define TAP_CHECK(cond, ...)                                                                    \
    do {                                                                                        \
        int ok_ = (cond) ? 1 : 0;                                                               \
        printf("%sok %d - ", ok_ ? "" : "not ", ++tap_n);                                       \
        printf(__VA_ARGS__);                                                                    \
        if (!ok_) {                                                                             \
            tap_failed++;                                                                       \
            printf(": '%s' failed (%s:%d)", #cond, __FILE__, __LINE__);                         \
        }                                                                                       \
        printf("\n");                                                                           \
        fflush(stdout);                                                                         \
    } while (0)

static inline void tap_skip(const char *what, const char *why)
{
    printf("not ok %d # SKIP %s: %s\n", ++tap_n, what, why);
    fflush(stdout);
}

static inline int tap_done(void)
{
    printf("1..%d\n", tap_n);
    return tap_failed ? 1 : 0;
}

#endif /* CM_TEST_TAP_H */
