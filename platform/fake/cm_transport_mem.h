/*
 * cm_transport_mem.h - a cm_transport over memory, for unit tests and fuzz
 * targets: reads come from a given byte buffer, writes are appended to a
 * caller-provided buffer.  It never waits: a read with nothing left ends
 * the stream at once, as the caller chose (a hang-up, or "deadline passed").
 */
#ifndef CM_TRANSPORT_MEM_H
#define CM_TRANSPORT_MEM_H

#include <stddef.h>
#include <stdint.h>

#include "cm_transport.h"

/** What read returns once the input is used up. */
typedef enum cm_mem_end {
    CM_MEM_END_HANGUP,  /* CM_T_HANGUP: the peer went away */
    CM_MEM_END_TIMEOUT  /* 0: the peer went quiet */
} cm_mem_end;

typedef struct cm_memlink {
    cm_transport t;
    const uint8_t *in;
    size_t in_len, in_pos;
    uint8_t *out;
    size_t out_cap, out_len;
    size_t overflow;   /* bytes written that did not fit in out (counted, dropped) */
    size_t read_chunk; /* most bytes one read returns (0: no limit); small values exercise partial reads */
    cm_mem_end at_end;
    int closed;
    unsigned long long reads, writes; /* calls, for tests that count round trips */
} cm_memlink;

/**
 * Set up m over in[0..in_len) and out[0..out_cap); either buffer may be NULL
 * with length 0.  Writes always "succeed" (return n), overflow is counted;
 * after close() every call returns CM_T_IO.
 */
void cm_mem_open(cm_memlink *m, const uint8_t *in, size_t in_len, uint8_t *out, size_t out_cap, cm_mem_end at_end);

#endif /* CM_TRANSPORT_MEM_H */
