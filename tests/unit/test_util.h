/*
 * test_util.h - helpers shared by the cmocka unit tests: tolerance asserts
 * that print both values, a deterministic random generator, a few
 * reference shapes.  Every tolerance passed to assert_near says why at the
 * call site.
 */
#ifndef TEST_UTIL_H
#define TEST_UTIL_H

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "cm/cm_vec.h"

#define assert_near(a, b, tol)                                                                         \
    do {                                                                                               \
        double a_ = (a), b_ = (b), t_ = (tol);                                                         \
        if (!(fabs(a_ - b_) <= t_))                                                                    \
            fail_msg("%s = %.17g, expected %s = %.17g (|diff| %.3g > tol %.3g)", #a, a_, #b, b_,        \
                     fabs(a_ - b_), t_);                                                               \
    } while (0)

#define assert_vec_near(a, b, tol)                                                                     \
    do {                                                                                               \
        cm_vec3 a_ = (a), b_ = (b);                                                                    \
        double t_ = (tol), d_ = cm_dist(a_, b_);                                                       \
        if (!(d_ <= t_))                                                                               \
            fail_msg("%s = (%.17g %.17g %.17g), expected %s = (%.17g %.17g %.17g): dist %.3g > tol %.3g", \
                     #a, a_.x, a_.y, a_.z, #b, b_.x, b_.y, b_.z, d_, t_);                              \
    } while (0)

#define assert_ok(expr)                                                                                \
    do {                                                                                               \
        cm_err e_ = (expr);                                                                            \
        if (e_ != CM_OK)                                                                               \
            fail_msg("%s returned %s", #expr, cm_err_name(e_));                                        \
    } while (0)

#define assert_err(expr, code)                                                                         \
    do {                                                                                               \
        cm_err e_ = (expr);                                                                            \
        if (e_ != (code))                                                                              \
            fail_msg("%s returned %s, expected %s", #expr, cm_err_name(e_), cm_err_name(code));        \
    } while (0)

/* deterministic LCG (Numerical Recipes constants): tests never depend on libc rand() */
static inline double test_rand(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (double)(*s >> 8) / 16777216.0; /* [0,1) with 24 bits */
}

static inline cm_vec3 test_rand_vec(uint32_t *s, double scale)
{
    double x = test_rand(s), y = test_rand(s), z = test_rand(s);
    return cm_v3(scale * (2 * x - 1), scale * (2 * y - 1), scale * (2 * z - 1));
}

#define TEST_SQRT1_2 0.70710678118654752440
#ifndef M_PI
#define M_PI 3.14159265358979323846 /* -std=c11 hides the POSIX constant */
#endif

#endif /* TEST_UTIL_H */
