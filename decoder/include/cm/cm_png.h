/*
 * cm_png.h - an RGB frame as a PNG file, streamed: for the viewer's images
 * (cmz-view --png) on the workstation and on terminals that hand images to
 * another display.
 *
 * 8-bit RGB, no interlace, every row unfiltered, the zlib stream made of
 * stored (uncompressed) deflate blocks: no compressor state, no heap, a
 * few hundred bytes of stack, and the same bytes on every machine.  The
 * price is size (width x height x 3 bytes and a little): the terminal's
 * display takes frames, not files, and a workstation that keeps images can
 * recompress them with any PNG tool.
 */
#ifndef CM_PNG_H
#define CM_PNG_H

#include <stddef.h>
#include <stdint.h>

#include "cm/cm_error.h"

/** Output sink: take n bytes; 0 on success (any other value stops the writer with CM_E_IO). */
typedef int cm_png_put(void *ctx, const uint8_t *p, size_t n);

/** Bytes of the PNG of a w x h frame (what cm_png_write puts in all). */
uint64_t cm_png_size(uint32_t w, uint32_t h);

/**
 * Write the w x h frame rgb (row by row from the top, 3 bytes a pixel) as a PNG through put.
 * @return CM_OK; CM_E_ARG for an empty frame or one beyond PNG's and zlib's ranges (each row
 *         at most 2^31 bytes); CM_E_IO when put fails
 */
CM_NODISCARD cm_err cm_png_write(const uint8_t *rgb, uint32_t w, uint32_t h, cm_png_put *put, void *ctx,
                                 cm_status *st);

#endif /* CM_PNG_H */
