/*
 * cm_link.h - the link protocol between the workstation (`cmz send`) and
 * the terminal (cmz-terminal): frames, messages and the two ends of a
 * transfer.  docs/LINK.md is the specification; this is its code.
 *
 * A frame on the wire (little-endian):
 *
 *   0  2  magic 0xC5 0x4D
 *   2  1  type (CM_LINK_*)
 *   3  1  seq: the sender's counter; a reply echoes the seq it answers
 *   4  2  payload length (<= CM_LINK_MAX_PAYLOAD)
 *   6  2  header check: low 16 bits of CRC-32 over bytes 0..5
 *   8  n  payload
 *   8+n 4 CRC-32 over bytes 0..8+n-1
 *
 * The header check lets a receiver drop a corrupted length at once
 * instead of waiting for bytes that will never come; after any bad frame
 * it resynchronises on the next magic in what it already holds.
 *
 * No heap: the receive buffer and every frame live in caller-owned
 * structs (static on the terminal).
 */
#ifndef CM_LINK_H
#define CM_LINK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cm/cm_limits_info.h"
#include "cm_transport.h"

#define CM_LINK_PROTO 1            /* protocol version, in SYNC and HELLO */
#define CM_LINK_MAX_PAYLOAD 16384u /* DATA chunk ceiling: 16 KiB keeps USB bulk efficient */
#define CM_LINK_HEADER 8u
#define CM_LINK_TRAILER 4u
#define CM_LINK_MAX_FRAME (CM_LINK_HEADER + CM_LINK_MAX_PAYLOAD + CM_LINK_TRAILER)
#define CM_LINK_WINDOW 64u         /* chunks in flight (selective repeat; one bit each in ACK) */
#define CM_LINK_MAX_NAME 64u       /* model name in OFFER, terminal name in HELLO */
#define CM_LINK_MAX_TEXT 240u      /* REFUSE/DONE/ABORT message */

typedef enum cm_link_type {
    CM_LINK_SYNC = 0x01,    /* S->T: is anyone there? (proto) */
    CM_LINK_HELLO = 0x02,   /* T->S: format versions, max payload, limits, name */
    CM_LINK_OFFER = 0x03,   /* S->T: size, crc, chunk size wanted, name */
    CM_LINK_ACCEPT = 0x04,  /* T->S: start offset (resume point), chunk size, crc of the offer */
    CM_LINK_REFUSE = 0x05,  /* T->S: error code, text (over a limit, no space, ...) */
    CM_LINK_DATA = 0x06,    /* S->T: offset, bytes */
    CM_LINK_ACK = 0x07,     /* T->S: contiguous offset, bitmap of the next chunks held */
    CM_LINK_END = 0x08,     /* S->T: size, crc of the whole file */
    CM_LINK_DONE = 0x09,    /* T->S: stage (stored/decoded), error code, text */
    CM_LINK_REQUEST = 0x0A, /* T->S: the operator asks for the model again */
    CM_LINK_ABORT = 0x0B    /* either way: give up this transfer, text */
} cm_link_type;

enum { CM_LINK_STAGE_STORED = 1, CM_LINK_STAGE_DECODED = 2 };

typedef struct cm_link_frame {
    uint8_t type, seq;
    uint16_t len;
    const uint8_t *payload; /* points into the receiver's buffer: valid until the next cm_link_recv */
} cm_link_frame;

typedef struct cm_link_stats {
    uint64_t frames_in, frames_out, bytes_in, bytes_out;
    uint64_t bad_header, bad_crc, skipped; /* frames dropped, bytes skipped while resynchronising */
} cm_link_stats;

typedef struct cm_link {
    cm_transport *t;
    uint8_t seq;
    size_t start, end; /* unread bytes of rx */
    uint8_t rx[2 * CM_LINK_MAX_FRAME];
    uint8_t tx[CM_LINK_MAX_FRAME];
    cm_link_stats stats;
} cm_link;

/** Milliseconds of CLOCK_MONOTONIC. */
int64_t cm_link_now_ms(void);

/** Bind a link to a transport (also after a reopen; unread bytes are dropped). */
void cm_link_init(cm_link *l, cm_transport *t);

/**
 * Send one frame (seq: the link's next one if < 0, else echoed).
 * @return 1 sent, 0 deadline, CM_T_HANGUP / CM_T_IO
 */
int cm_link_send(cm_link *l, uint8_t type, int seq, const uint8_t *payload, size_t len, int timeout_ms);

/**
 * Wait at most timeout_ms for the next good frame.
 * @return 1 with *f filled, 0 at the deadline or earlier when a damaged frame was dropped,
 *         CM_T_HANGUP / CM_T_IO
 */
int cm_link_recv(cm_link *l, cm_link_frame *f, int timeout_ms);

/* ---- messages ---- */

typedef struct cm_link_hello {
    uint8_t proto, fmt_major_max, fmt_minor_max, fmt_major_min;
    uint16_t max_payload;
    uint8_t nlimits;
    uint32_t limit[CM_LIMIT_COUNT]; /* by limit id (cm_limits_list.h order); missing ids: 0 = unknown */
    char name[CM_LINK_MAX_NAME + 1];
} cm_link_hello;

typedef struct cm_link_offer {
    uint32_t size, crc, chunk;
    char name[CM_LINK_MAX_NAME + 1];
} cm_link_offer;

/** This build's HELLO (its format versions and limits). */
void cm_link_hello_local(cm_link_hello *h, const char *name);
size_t cm_link_hello_pack(const cm_link_hello *h, uint8_t *out);
bool cm_link_hello_unpack(const cm_link_frame *f, cm_link_hello *h);
size_t cm_link_offer_pack(const cm_link_offer *o, uint8_t *out);
bool cm_link_offer_unpack(const cm_link_frame *f, cm_link_offer *o);
/** code + text payloads (REFUSE, DONE with stage first, ABORT) */
size_t cm_link_text_pack(int stage, int code, const char *text, uint8_t *out);
bool cm_link_text_unpack(const cm_link_frame *f, int has_stage, int *stage, int *code, char *text, size_t cap);

static inline void cm_link_put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}
static inline uint32_t cm_link_get32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/** Name of a frame type for logs ("DATA"), "?" if unknown. */
const char *cm_link_type_name(int type);

#endif /* CM_LINK_H */
