/* cm_arith.c - adaptive binary range coder and integer models (see cm_arith.h). */
#include "cm/cm_arith.h"

#define TOP (1u << 24)
#define MOVE_BITS 5

void cm_ac_prob_init(cm_ac_prob *p)
{
    *p = (cm_ac_prob)CM_AC_PROB_INIT;
}

void cm_ac_int_init(cm_ac_int *m)
{
    for (int i = 0; i < CM_AC_MAX_LEN; i++) {
        m->len[i] = (cm_ac_prob)CM_AC_PROB_INIT;
        for (int j = 0; j < CM_AC_MANT_CTX; j++)
            m->mant[i][j] = (cm_ac_prob)CM_AC_PROB_INIT;
    }
    m->sign = (cm_ac_prob)CM_AC_PROB_INIT;
}

/* ---- encoder ---- */

void cm_ac_enc_init(cm_ac_enc *e, uint8_t *buf, size_t cap)
{
    e->buf = buf;
    e->cap = cap;
    e->pos = 0;
    e->low = 0;
    e->range = 0xFFFFFFFFu;
    e->cache = 0;
    e->cache_size = 1;
    e->overflow = 0;
}

static void put_byte(cm_ac_enc *e, uint8_t b)
{
    if (e->pos < e->cap)
        e->buf[e->pos] = b;
    else
        e->overflow = 1;
    e->pos++;
}

/* carry propagation: the top byte of `low` is held back until it can no longer change */
static void shift_low(cm_ac_enc *e)
{
    if ((uint32_t)e->low < 0xFF000000u || (e->low >> 32) != 0) {
        uint8_t carry = (uint8_t)(e->low >> 32);
        uint8_t temp = e->cache;
        do {
            put_byte(e, (uint8_t)(temp + carry));
            temp = 0xFF;
        } while (--e->cache_size != 0);
        e->cache = (uint8_t)(e->low >> 24);
    }
    e->cache_size++;
    e->low = (e->low & 0x00FFFFFFu) << 8;
}

void cm_ac_enc_bit(cm_ac_enc *e, cm_ac_prob *p, unsigned bit)
{
    uint32_t bound = (e->range >> CM_AC_PROB_BITS) * *p;
    if (bit == 0) {
        e->range = bound;
        *p = (cm_ac_prob)(*p + (((1u << CM_AC_PROB_BITS) - *p) >> MOVE_BITS));
    } else {
        e->low += bound;
        e->range -= bound;
        *p = (cm_ac_prob)(*p - (*p >> MOVE_BITS));
    }
    while (e->range < TOP) {
        e->range <<= 8;
        shift_low(e);
    }
}

void cm_ac_enc_direct(cm_ac_enc *e, uint32_t value, unsigned nbits)
{
    for (unsigned i = nbits; i-- > 0;) {
        e->range >>= 1;
        if ((value >> i) & 1u)
            e->low += e->range;
        while (e->range < TOP) {
            e->range <<= 8;
            shift_low(e);
        }
    }
}

static unsigned bit_length(uint64_t v)
{
    unsigned k = 0;
    while (v) {
        k++;
        v >>= 1;
    }
    return k;
}

void cm_ac_enc_uint(cm_ac_enc *e, cm_ac_int *m, uint64_t v)
{
    unsigned k = bit_length(v);
    if (k >= CM_AC_MAX_LEN) { /* out of the coder's range: encoders never send it; keep the stream valid */
        k = CM_AC_MAX_LEN - 1;
        v = (1ull << k) - 1;
    }
    for (unsigned i = 0; i < k; i++)
        cm_ac_enc_bit(e, &m->len[i], 1);
    if (k < CM_AC_MAX_LEN - 1)
        cm_ac_enc_bit(e, &m->len[k], 0);
    /* bits below the leading one, most significant first */
    for (unsigned i = 1; i < k; i++) {
        unsigned bit = (unsigned)(v >> (k - 1 - i)) & 1u;
        if (i - 1 < CM_AC_MANT_CTX)
            cm_ac_enc_bit(e, &m->mant[k][i - 1], bit);
        else
            cm_ac_enc_direct(e, bit, 1);
    }
}

void cm_ac_enc_sint(cm_ac_enc *e, cm_ac_int *m, int64_t v)
{
    uint64_t mag = v < 0 ? (uint64_t)(-(v + 1)) + 1u : (uint64_t)v;
    cm_ac_enc_uint(e, m, mag);
    if (mag)
        cm_ac_enc_bit(e, &m->sign, v < 0);
}

size_t cm_ac_enc_finish(cm_ac_enc *e)
{
    for (int i = 0; i < 5; i++)
        shift_low(e);
    return e->overflow ? 0 : e->pos;
}

size_t cm_ac_enc_finish_trimmed(cm_ac_enc *e)
{
    /* end on the value in [low, low + range) whose low 24 bits are zero (range >= 2^24: there is
       one), so the last three bytes of the flush are zeros */
    e->low = (e->low + 0xFFFFFFu) & ~(uint64_t)0xFFFFFFu;
    for (int i = 0; i < 5; i++)
        shift_low(e);
    if (e->overflow)
        return 0;
    size_t n = e->pos;
    /* the trailing zeros, at most CM_AC_TRIM_PAD of them, and the leading 0 */
    for (int i = 0; i < CM_AC_TRIM_PAD && n > 1 && e->buf[n - 1] == 0; i++)
        n--;
    for (size_t i = 1; i < n; i++)
        e->buf[i - 1] = e->buf[i];
    return n - 1;
}

/* ---- decoder ---- */

/* the next window, from d->pos on; 0 when it cannot be read (the one call through the fill:
   noinline, the stack gates' tables name this function) */
__attribute__((noinline)) static int next_window(cm_ac_dec *d)
{
    size_t avail = 0;
    const uint8_t *p = d->io_failed || d->fill == NULL ? NULL : d->fill(d->fill_ctx, d->pos, &avail);
    if (p == NULL || avail == 0) {
        d->io_failed = 1;
        return 0;
    }
    d->buf = p;
    d->win_start = d->pos;
    d->win_end = d->pos + avail;
    return 1;
}

static uint8_t get_byte(cm_ac_dec *d)
{
    if (d->pos < d->len) {
        /* only with a fill: without one the window is the stream */
        if (d->pos >= d->win_end && !next_window(d)) {
            d->overrun = 1;
            d->pos++;
            return 0;
        }
        return d->buf[d->pos++ - d->win_start];
    }
    if (d->pos - d->len >= d->pad)
        d->overrun = 1;
    d->pos++;
    return 0;
}

static void dec_start(cm_ac_dec *d, const uint8_t *buf, size_t len, int trimmed, cm_ac_fill *fill, void *ctx)
{
    d->buf = buf;
    d->win_start = 0;
    d->win_end = fill ? 0 : len;
    d->fill = fill;
    d->fill_ctx = ctx;
    d->io_failed = 0;
    d->len = len;
    d->pos = 0;
    d->pad = trimmed ? CM_AC_TRIM_PAD : 0;
    d->overrun = 0;
    d->range = 0xFFFFFFFFu;
    d->code = 0;
    for (int i = trimmed ? 1 : 0; i < 5; i++) /* trimmed: the leading 0 is not in the stream */
        d->code = (d->code << 8) | get_byte(d);
}

void cm_ac_dec_init(cm_ac_dec *d, const uint8_t *buf, size_t len) { dec_start(d, buf, len, 0, NULL, NULL); }

void cm_ac_dec_init_trimmed(cm_ac_dec *d, const uint8_t *buf, size_t len) { dec_start(d, buf, len, 1, NULL, NULL); }

void cm_ac_dec_init_fill(cm_ac_dec *d, size_t len, int trimmed, cm_ac_fill *fill, void *ctx)
{
    dec_start(d, NULL, len, trimmed, fill, ctx);
}

unsigned cm_ac_dec_bit(cm_ac_dec *d, cm_ac_prob *p)
{
    uint32_t bound = (d->range >> CM_AC_PROB_BITS) * *p;
    unsigned bit;
    if (d->code < bound) {
        d->range = bound;
        *p = (cm_ac_prob)(*p + (((1u << CM_AC_PROB_BITS) - *p) >> MOVE_BITS));
        bit = 0;
    } else {
        d->code -= bound;
        d->range -= bound;
        *p = (cm_ac_prob)(*p - (*p >> MOVE_BITS));
        bit = 1;
    }
    while (d->range < TOP) {
        d->range <<= 8;
        d->code = (d->code << 8) | get_byte(d);
    }
    return bit;
}

uint32_t cm_ac_dec_direct(cm_ac_dec *d, unsigned nbits)
{
    uint32_t v = 0;
    for (unsigned i = 0; i < nbits; i++) {
        d->range >>= 1;
        uint32_t bit = d->code >= d->range;
        if (bit)
            d->code -= d->range;
        v = (v << 1) | bit;
        while (d->range < TOP) {
            d->range <<= 8;
            d->code = (d->code << 8) | get_byte(d);
        }
    }
    return v;
}

uint64_t cm_ac_dec_uint(cm_ac_dec *d, cm_ac_int *m)
{
    unsigned k = 0;
    while (k < CM_AC_MAX_LEN - 1 && cm_ac_dec_bit(d, &m->len[k]))
        k++;
    if (k == 0)
        return 0;
    uint64_t v = 1;
    for (unsigned i = 1; i < k; i++) {
        unsigned bit = i - 1 < CM_AC_MANT_CTX ? cm_ac_dec_bit(d, &m->mant[k][i - 1]) : cm_ac_dec_direct(d, 1);
        v = (v << 1) | bit;
    }
    return v;
}

int64_t cm_ac_dec_sint(cm_ac_dec *d, cm_ac_int *m)
{
    uint64_t mag = cm_ac_dec_uint(d, m);
    if (mag == 0)
        return 0;
    if (cm_ac_dec_bit(d, &m->sign))
        return -(int64_t)(mag - 1u) - 1;
    return (int64_t)mag;
}
