/* cm_crc32.c - CRC-32 (see cm_crc32.h). */
#include "cm/cm_crc32.h"

/* bitwise (no 1 KiB table: the terminal cares more about flash than speed here) */
uint32_t cm_crc32_update(uint32_t crc, const uint8_t *p, size_t n)
{
    crc = ~crc;
    for (size_t i = 0; i < n; i++) {
        crc ^= p[i];
        for (int k = 0; k < 8; k++)
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

uint32_t cm_crc32(const uint8_t *p, size_t n)
{
    return cm_crc32_update(0, p, n);
}
