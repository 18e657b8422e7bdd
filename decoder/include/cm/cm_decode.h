/*
 * cm_decode.h - the terminal's .cmz reader: fed in chunks of any size,
 * validates everything, fills a cm_model.
 *
 *   static cm_decoder dec;        // a few MiB: give it static storage
 *   cm_dec_init(&dec);
 *   while (bytes arrive) cm_dec_feed(&dec, p, n, &st);   // header checked as soon as it is in
 *   cm_dec_finish(&dec, &st);     // all bytes in: CRCs checked, sections decoded into dec.model
 *
 * Contract (the security model of README): the decoder never reads past
 * the bytes fed, never writes past any fixedcfg-sized array, never
 * allocates, never recurses, and finishes in time bounded by the input
 * size and the limits.  A model whose header declares a need above a limit
 * of this build is refused by cm_dec_feed as soon as the header is
 * complete, before any byte of the body is looked at: CM_E_LIMIT, with the
 * limit, the need and this build's value in the status.  After CM_OK every
 * count is within its limit, every index is valid, every number is finite
 * and every loop is closed.  Errors carry the byte offset where they were
 * detected, and an error about one face (its record, its colour) the face
 * (st->face).
 *
 * Every header field is checked before anything uses it: the section count
 * (exactly CM_SEC_COUNT: the table below has room for no more) and the need
 * count against the header's length before the table is read, the header
 * CRC, the file length, the needs, the grid exponent, origin and tolerances,
 * and each section's tag, offset and length before cm_dec_finish addresses a
 * byte through them.  The body's counts are checked against their limits
 * before they index or size anything.
 */
#ifndef CM_DECODE_H
#define CM_DECODE_H

#include <stddef.h>
#include <stdint.h>

#include "cm/cm_error.h"
#include "cm/cm_format.h"
#include "cm/cm_limits_info.h"

typedef struct cm_dec_section {
    uint8_t tag;
    uint8_t has_crc; /* formats 1-3: each section has a CRC; format 4 leaves it to the file's */
    uint32_t off, len, crc;
} cm_dec_section;

typedef enum cm_dec_state {
    CM_DEC_HEADER = 0, /* waiting for the header */
    CM_DEC_BODY = 1,   /* header accepted, body arriving */
    CM_DEC_DONE = 2,   /* model decoded */
    CM_DEC_FAILED = 3  /* an error was reported; feed/finish refuse further work */
} cm_dec_state;

typedef int cm_dec_read_fn(void *ctx, uint32_t off, uint8_t *buf, size_t n);

typedef struct cm_decoder {
    cm_dec_state state;
    uint32_t len;                      /* bytes received */
    uint32_t header_len, file_len;
    uint8_t version_major, version_minor;
    uint16_t flags;
    uint32_t nlimits;
    uint32_t need[CM_LIMIT_COUNT];     /* the model's needs, by limit id */
    uint32_t nsec;                     /* CM_SEC_COUNT once the header is accepted (0 before) */
    cm_dec_section sec[CM_SEC_COUNT];
    /* one storage, two uses in turn: the vertices on the integer grid, the predictors of VERT, EDGE
       and SURF; then, while FACE is read (format 4.5 on), the heads of the lists of edges at each
       vertex (cm_use_adj.h).  So vq holds the vertices after a decode only up to format 4.4. */
    union {
        int64_t vq[CM_MAX_VERTICES][3];
        int32_t vhead[CM_MAX_VERTICES];
    };
    int64_t sq[CM_MAX_SURF_CTRL][3];   /* one kept surface's net on the grid (predictor) */
    int64_t sw[CM_MAX_SURF_CTRL];      /* ... and its quantised weights */
    /* the file's first CM_FILE_WINDOW_BYTES (the header is read there); a longer file's sections are
       read again through it from the source, a window at a time */
    uint8_t buf[CM_FILE_WINDOW_BYTES];
    uint32_t crc;                      /* CRC-32 of the bytes fed so far, up to the file's CRC */
    uint8_t file_crc[4];               /* the file's last 4 bytes, as they are fed */
    cm_dec_read_fn *src_read;          /* cm_dec_set_source */
    void *src_ctx;
    uint32_t recrc, recrc_next;        /* the CRC of what was read again, in order, and where it is */
    cm_model model;
} cm_decoder;

void cm_dec_init(cm_decoder *d);

/**
 * Where the decoder reads the file's bytes again when the file is longer than its window
 * (CM_FILE_WINDOW_BYTES): read(ctx, off, buf, n) puts bytes [off, off + n) of the same file in buf
 * and returns 0, or returns non-zero (CM_E_IO).  Set after cm_dec_init (which forgets it), before
 * cm_dec_finish.  The file must not change in between: what is read again is checked against the
 * CRC taken as it was fed, and a file that changed is refused (CM_E_CRC) once its sections are read.
 */
void cm_dec_set_source(cm_decoder *d, cm_dec_read_fn *read, void *ctx);

/**
 * Append n bytes (n may be 0).  As soon as the header is complete it is
 * checked: magic, version, lengths, section and need counts, header CRC,
 * every need against this build's limits, grid, tolerances, section table.
 * @return CM_OK, or CM_E_MAGIC / CM_E_VERSION / CM_E_FORMAT / CM_E_CRC /
 *         CM_E_LIMIT (header refused) / CM_E_RANGE (more bytes than the file)
 */
CM_NODISCARD cm_err cm_dec_feed(cm_decoder *d, const uint8_t *p, size_t n, cm_status *st);

/** 1 once the header has been accepted (needs are then in d->need). */
int cm_dec_header_ok(const cm_decoder *d);

/**
 * All bytes fed: check the whole-file CRC and each section's, decode the
 * sections into d->model and validate the topology.
 * @return CM_OK, CM_E_TRUNCATED (fewer bytes than the header declares),
 *         CM_E_CRC, CM_E_RANGE, CM_E_KNOTS, CM_E_NONFINITE, CM_E_FORMAT,
 *         CM_E_LIMIT, CM_E_UNSUPPORTED (a method this version does not know)
 */
CM_NODISCARD cm_err cm_dec_finish(cm_decoder *d, cm_status *st);

#endif /* CM_DECODE_H */
