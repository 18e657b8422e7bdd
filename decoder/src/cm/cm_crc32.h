/*
 * cm_crc32.h - CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320, as
 * zlib's crc32()): the .cmz file's header, section and whole-file checks,
 * the link protocol's frame checks and the terminal's stored metadata.
 * Kept apart from the range coder (cm_arith.h) so that the link code needs
 * only this.
 */
#ifndef CM_CRC32_H
#define CM_CRC32_H

#include <stddef.h>
#include <stdint.h>

/** Continue a CRC-32 over n more bytes (start with crc = 0; chunks give the same value as one call). */
uint32_t cm_crc32_update(uint32_t crc, const uint8_t *p, size_t n);

/** CRC-32 of a whole buffer (cm_crc32_update(0, p, n)). */
uint32_t cm_crc32(const uint8_t *p, size_t n);

#endif /* CM_CRC32_H */
