/* cm_png.c - an RGB frame as a stored-deflate PNG, streamed (see cm_png.h). */
#include "cm/cm_png.h"

#include "cm/cm_crc32.h"

#define STORED_MAX 65535u /* bytes of one stored deflate block */

/* what goes out, through a small buffer: put calls of a few KB, the CRC of the chunk in progress */
typedef struct png_out {
    cm_png_put *put;
    void *ctx;
    uint32_t crc;  /* of the current chunk's type and data so far */
    int failed;
    size_t n;
    uint8_t buf[1024];
} png_out;

static void flush(png_out *o)
{
    if (o->n > 0 && !o->failed && o->put(o->ctx, o->buf, o->n) != 0)
        o->failed = 1;
    o->n = 0;
}

/* bytes that are part of a chunk (its type and data: they enter the CRC) */
static void emit(png_out *o, const uint8_t *p, size_t n)
{
    o->crc = cm_crc32_update(o->crc, p, n);
    while (n > 0) {
        size_t k = sizeof o->buf - o->n < n ? sizeof o->buf - o->n : n;
        for (size_t i = 0; i < k; i++)
            o->buf[o->n + i] = p[i];
        o->n += k;
        p += k;
        n -= k;
        if (o->n == sizeof o->buf)
            flush(o);
    }
}

static void emit_u32be(png_out *o, uint32_t v)
{
    uint8_t b[4] = {(uint8_t)(v >> 24), (uint8_t)(v >> 16), (uint8_t)(v >> 8), (uint8_t)v};
    emit(o, b, 4);
}

/* a chunk's length, then its type (the CRC starts there) */
static void chunk_begin(png_out *o, uint32_t len, const char *type)
{
    emit_u32be(o, len);
    o->crc = 0;
    emit(o, (const uint8_t *)type, 4);
}

static void chunk_end(png_out *o) { emit_u32be(o, o->crc); }

/* raw (filtered) bytes of the image: each row is a filter byte (0: none) and its pixels */
static uint64_t raw_size(uint32_t w, uint32_t h) { return (uint64_t)h * (1u + 3u * (uint64_t)w); }

static uint64_t zlib_size(uint64_t raw)
{
    uint64_t blocks = raw == 0 ? 1 : (raw + STORED_MAX - 1) / STORED_MAX;
    return 2 + raw + 5 * blocks + 4; /* header, data, each block's 5-byte header, Adler-32 */
}

uint64_t cm_png_size(uint32_t w, uint32_t h)
{
    return 8 + (12 + 13) + (12 + zlib_size(raw_size(w, h))) + 12;
}

cm_err cm_png_write(const uint8_t *rgb, uint32_t w, uint32_t h, cm_png_put *put, void *ctx, cm_status *st)
{
    if (!rgb || !put || w < 1 || h < 1 || w > 0x7fffffffu / 3u || h > 0x7fffffffu)
        return cm_fail(st, CM_E_ARG, "png: frame size");
    uint64_t raw = raw_size(w, h), z = zlib_size(raw);
    if (z > 0x7fffffffu)
        return cm_fail(st, CM_E_ARG, "png: a frame beyond one IDAT chunk (2^31 bytes)");
    png_out o;
    o.put = put;
    o.ctx = ctx;
    o.crc = 0;
    o.failed = 0;
    o.n = 0;
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    emit(&o, sig, sizeof sig);
    chunk_begin(&o, 13, "IHDR");
    emit_u32be(&o, w);
    emit_u32be(&o, h);
    static const uint8_t ihdr_rest[5] = {8, 2, 0, 0, 0}; /* 8 bits, RGB, deflate, adaptive filters, no interlace */
    emit(&o, ihdr_rest, sizeof ihdr_rest);
    chunk_end(&o);

    chunk_begin(&o, (uint32_t)z, "IDAT");
    static const uint8_t zhdr[2] = {0x78, 0x01}; /* deflate, 32 KB window, no dictionary, check bits */
    emit(&o, zhdr, 2);
    uint32_t a = 1, b = 0; /* Adler-32 */
    const uint64_t row_bytes = 1u + 3u * (uint64_t)w;
    uint64_t pos = 0;
    do {
        uint64_t left = raw - pos;
        uint32_t len = left > STORED_MAX ? STORED_MAX : (uint32_t)left;
        uint8_t bh[5] = {(uint8_t)(pos + len == raw ? 1 : 0), (uint8_t)len, (uint8_t)(len >> 8),
                         (uint8_t)~len, (uint8_t)(~len >> 8)};
        emit(&o, bh, 5);
        /* the block's bytes, in runs within a row: the filter byte, then pixels */
        for (uint32_t done = 0; done < len;) {
            uint64_t row = (pos + done) / row_bytes, col = (pos + done) % row_bytes;
            const uint8_t *src;
            uint64_t run;
            static const uint8_t filter_none = 0;
            if (col == 0) {
                src = &filter_none;
                run = 1;
            } else {
                src = rgb + row * 3u * (uint64_t)w + (col - 1);
                run = row_bytes - col;
            }
            if (run > len - done)
                run = len - done;
            for (uint64_t i = 0; i < run; i++) {
                a = (a + src[i]) % 65521u;
                b = (b + a) % 65521u;
            }
            emit(&o, src, (size_t)run);
            done += (uint32_t)run;
        }
        pos += len;
    } while (pos < raw);
    emit_u32be(&o, (b << 16) | a);
    chunk_end(&o);
    chunk_begin(&o, 0, "IEND");
    chunk_end(&o);
    flush(&o);
    if (o.failed)
        return cm_fail(st, CM_E_IO, "png: write");
    return CM_OK;
}
