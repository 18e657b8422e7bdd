/*
 * cm_numfmt.h - numbers as text without stdio (the decoder may not link
 * printf): unsigned integers, and float32 values with 9 significant digits
 * that read back as exactly the same float.
 *
 * Used by the JSON (glTF) and OBJ writers; public so that the tests and
 * other writers can use the very same text.
 */
#ifndef CM_NUMFMT_H
#define CM_NUMFMT_H

#include <stddef.h>
#include <stdint.h>

/** Buffer size that holds any cm_fmt_f32 text and its NUL ("-1.17549435e-38"). */
#define CM_FMT_F32_MAX 16
/** Buffer size that holds any cm_fmt_u64 text and its NUL (20 digits). */
#define CM_FMT_U64_MAX 21

/**
 * Write f as the shortest form of C's "%.9g" (9 significant digits,
 * trailing zeros dropped; exponent form "d.dddddddde±XX" when the decimal
 * exponent is below -4 or above 8), e.g. "-12.3456791", "1.00000001e-05",
 * "0", "-0", "3.40282347e+38".  The text read back by a correctly rounding
 * parser (strtof, or strtod followed by a cast to float) gives f bit for bit.
 * Non-finite f writes nothing (returns 0, out[0] = 0): callers reject them.
 * @param out at least CM_FMT_F32_MAX bytes; NUL-terminated
 * @return the text length (without the NUL)
 */
size_t cm_fmt_f32(char out[CM_FMT_F32_MAX], float f);

/** Decimal text of v, NUL-terminated; returns its length (1..20). */
size_t cm_fmt_u64(char out[CM_FMT_U64_MAX], uint64_t v);

#endif /* CM_NUMFMT_H */
