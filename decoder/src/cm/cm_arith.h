/*
 * cm_arith.h - the entropy coder of the .cmz format: an adaptive binary
 * range coder (LZMA-style: 32-bit range, 11-bit probabilities adapting by
 * 1/32) and the integer models built on it.  The encoder half runs on the
 * workstation, the decoder half on the terminal; both are here so they
 * cannot drift apart.
 *
 * Integers are binarised as: the bit length k = 0..33 of the magnitude,
 * coded as a unary run of adaptive bits (one context per position), then
 * the bits below the leading one: the first CM_AC_MANT_CTX of them with
 * adaptive contexts per (k, position), the rest at probability 1/2.  A
 * signed value adds an adaptive sign bit.  Each field of the format owns a
 * cm_ac_int model, so the statistics of vertex deltas, knot gaps and
 * indices stay apart.
 *
 * Decoding never reads outside its buffer: past the end it reads zeros and
 * sets `overrun`, which the caller turns into CM_E_TRUNCATED.
 *
 * Format 4 trims each stream (cm_ac_enc_finish_trimmed): the first byte, which
 * this coder always writes as 0, is left out, and the flush ends on a value
 * whose last bytes are zeros, which are left out too; its reader
 * (cm_ac_dec_init_trimmed) reads up to CM_AC_TRIM_PAD zeros past the end
 * before it calls that an overrun.  Four bytes fewer per section.
 */
#ifndef CM_ARITH_H
#define CM_ARITH_H

#include <stddef.h>
#include <stdint.h>

#include "cm/cm_error.h"

#define CM_AC_PROB_BITS 11
#define CM_AC_PROB_INIT (1u << (CM_AC_PROB_BITS - 1))
#define CM_AC_MANT_CTX 3   /* adaptive bits below the leading one */
#define CM_AC_MAX_LEN 34   /* bit lengths 0..33 (values up to 2^33 - 1) */

typedef uint16_t cm_ac_prob;

/** Model of one integer field. */
typedef struct cm_ac_int {
    cm_ac_prob len[CM_AC_MAX_LEN];                 /* unary bit-length run */
    cm_ac_prob mant[CM_AC_MAX_LEN][CM_AC_MANT_CTX]; /* top bits of the magnitude */
    cm_ac_prob sign;
} cm_ac_int;

void cm_ac_int_init(cm_ac_int *m);
void cm_ac_prob_init(cm_ac_prob *p);

/* ---- encoder (workstation): writes into a caller buffer, reports overflow ---- */
typedef struct cm_ac_enc {
    uint8_t *buf;
    size_t cap, pos;
    uint64_t low;
    uint32_t range;
    uint8_t cache;
    uint64_t cache_size;
    int overflow; /* the buffer was too small: the output is incomplete */
} cm_ac_enc;

void cm_ac_enc_init(cm_ac_enc *e, uint8_t *buf, size_t cap);
void cm_ac_enc_bit(cm_ac_enc *e, cm_ac_prob *p, unsigned bit);
void cm_ac_enc_direct(cm_ac_enc *e, uint32_t value, unsigned nbits);
void cm_ac_enc_uint(cm_ac_enc *e, cm_ac_int *m, uint64_t v);
void cm_ac_enc_sint(cm_ac_enc *e, cm_ac_int *m, int64_t v);
/** Flush; returns the number of bytes written (0 and overflow set if cap was too small). */
size_t cm_ac_enc_finish(cm_ac_enc *e);
/** Flush format 4's trimmed stream (see above); returns its bytes, which may be 0 (overflow: 0 and
    overflow set, as above). */
size_t cm_ac_enc_finish_trimmed(cm_ac_enc *e);

/* ---- decoder (terminal) ---- */
/* A stream read through a window (issue 15: the terminal does not hold the whole file): called when
   the reader leaves the window, with the stream position; returns bytes from pos on (*avail > 0), or
   NULL when they cannot be read (the stream ends there: overrun and io_failed are set). */
typedef const uint8_t *cm_ac_fill(void *ctx, size_t pos, size_t *avail);

typedef struct cm_ac_dec {
    const uint8_t *buf;          /* bytes [win_start, win_end) of the stream (all of it without fill) */
    size_t win_start, win_end;
    cm_ac_fill *fill;            /* NULL: buf is the whole stream */
    void *fill_ctx;
    int io_failed;
    size_t len, pos;
    uint32_t range, code;
    size_t pad;  /* zeros read past the end that are still the stream's (format 4: CM_AC_TRIM_PAD) */
    int overrun; /* tried to read past the end */
} cm_ac_dec;

#define CM_AC_TRIM_PAD 4 /* the trailing zero bytes a trimmed stream may leave out */

void cm_ac_dec_init(cm_ac_dec *d, const uint8_t *buf, size_t len);
/** The reader of a trimmed stream (format 4). */
void cm_ac_dec_init_trimmed(cm_ac_dec *d, const uint8_t *buf, size_t len);
/** A stream of len bytes read through fill (trimmed: format 4's streams, else formats 1-3's). */
void cm_ac_dec_init_fill(cm_ac_dec *d, size_t len, int trimmed, cm_ac_fill *fill, void *ctx);
unsigned cm_ac_dec_bit(cm_ac_dec *d, cm_ac_prob *p);
uint32_t cm_ac_dec_direct(cm_ac_dec *d, unsigned nbits);
uint64_t cm_ac_dec_uint(cm_ac_dec *d, cm_ac_int *m);
int64_t cm_ac_dec_sint(cm_ac_dec *d, cm_ac_int *m);

#endif /* CM_ARITH_H */
