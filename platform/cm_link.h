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

/* protocol version, in SYNC and HELLO.  2: OFFER, ACCEPT and END carry the file's 64-bit content id
   (protocol 1 identified a file by size and the CRC-32 of all its bytes, which for every .cmz is the
   same constant: a .cmz ends with the CRC of what precedes it, so a resume could splice two files) */
#define CM_LINK_PROTO 2
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
    CM_LINK_OFFER = 0x03,   /* S->T: size, crc, chunk size wanted, name, content id */
    CM_LINK_ACCEPT = 0x04,  /* T->S: start offset (resume point), chunk size, crc and id of the offer */
    CM_LINK_REFUSE = 0x05,  /* T->S: error code, text (over a limit, no space, ...) */
    CM_LINK_DATA = 0x06,    /* S->T: offset, bytes */
    CM_LINK_ACK = 0x07,     /* T->S: contiguous offset, bitmap of the next chunks held */
    CM_LINK_END = 0x08,     /* S->T: size, crc and content id of the whole file */
    CM_LINK_DONE = 0x09,    /* T->S: stage (stored/decoded), error code, text */
    CM_LINK_REQUEST = 0x0A, /* T->S: the operator asks for the model again */
    CM_LINK_ABORT = 0x0B,   /* either way: give up this transfer, text */
    CM_LINK_HELLO_PART = 0x0C /* T->S: one piece of the HELLO, asked for by SYNC (noisy lines) */
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
    uint64_t stalled; /* partial frames given up at their deadline (the rest never came) */
} cm_link_stats;

/* A partial frame (good header, bytes missing) is given up, and the receiver resynchronises past its
   magic, when
     - the line has been silent for CM_LINK_PARTIAL_GAP_MS (a UART delivers a frame's bytes without
       pauses; a USB serial adapter holds them at most its latency timer, 16 ms by default), or
     - a whole frame with a good CRC has arrived after its header (a new sender: a real frame does not
       contain one, but for a 2^-64 chance or a payload made of captured link traffic), or
     - CM_LINK_PARTIAL_FLOOR_MS plus the line time of the bytes it missed when the wait began has
       passed, at the link's rate (cm_link_set_rate) or, when unknown, at CM_LINK_ASSUMED_BPS, the
       slowest line used (a legitimate frame on it must never be given up), and the bytes are not
       still coming: while they are, the deadline moves to when they will be in at the pace seen since
       the wait began, plus the floor.  A line's real pace is not its nominal rate (gaps between
       characters, a converter's latency timer, a radio or USB bridge slower than the local UART's
       setting); a frame still arriving is never cut for being slower than the number said.  That
       waiting is bounded: at most CM_LINK_PARTIAL_SLACK times the frame's time at the slowest line.
   Without this a sender that stalls mid-frame leaves a header announcing 16 KiB that swallows whatever
   comes next until that many bytes have come. */
#define CM_LINK_PARTIAL_GAP_MS 500
#define CM_LINK_PARTIAL_FLOOR_MS 1000
#define CM_LINK_ASSUMED_BPS 240u /* 2400 baud 8N1 */
#define CM_LINK_PARTIAL_SLACK 3

typedef struct cm_link {
    cm_transport *t;
    uint8_t seq;
    size_t start, end; /* unread bytes of rx */
    unsigned rate_bps; /* bytes per second of the line if known (cm_link_set_rate), 0: not known */
    uint64_t rx_off;   /* stream offset of rx[0]: candidate positions survive the buffer's compaction */
    uint64_t cand, stale_to; /* the partial frame waited for (stream offset + 1, 0: none); see parse */
    uint64_t nest_from;      /* stream offset from which to look for a whole frame inside the candidate */
    int64_t cand_deadline, last_rx_ms;
    int64_t cand_t0, cand_cap; /* when the wait for the candidate began; the latest it may be moved to */
    size_t cand_have;          /* its bytes held when the wait began */
    uint8_t rx[2 * CM_LINK_MAX_FRAME];
    /* rxcrc[i]: CRC-32 of the stream up to rx[i], so any frame's CRC is two lookups and a shift
       (cm_link.c, crc_window) instead of a pass over its bytes: a flood of valid-looking headers
       announcing 16 KiB each would otherwise cost a 16 KiB CRC per byte of resynchronisation */
    uint32_t rxcrc[2 * CM_LINK_MAX_FRAME + 1];
    uint8_t tx[CM_LINK_MAX_FRAME];
    cm_link_stats stats;
} cm_link;

/** Milliseconds of CLOCK_MONOTONIC: cm_clock_ms() (cm_clock.h), for the link's users outside platform/. */
int64_t cm_link_now_ms(void);

/** Bind a link to a transport (also after a reopen; unread bytes are dropped, the rate is kept). */
void cm_link_init(cm_link *l, cm_transport *t);

/** The line's rate in bytes per second (a serial line: baud / 10), 0 unknown: sizes partial-frame deadlines. */
void cm_link_set_rate(cm_link *l, unsigned bytes_per_s);

/**
 * Send one frame (seq: the link's next one if < 0, else echoed).
 * @return 1 sent, 0 deadline, CM_T_HANGUP / CM_T_IO
 */
int cm_link_send(cm_link *l, uint8_t type, int seq, const uint8_t *payload, size_t len, int timeout_ms);

/**
 * Wait at most timeout_ms for the next good frame.
 * @return 1 with *f filled, 0 at the deadline or earlier when a damaged frame was dropped (or a
 *         partial one given up), CM_T_HANGUP / CM_T_IO
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
    uint64_t id; /* cm_link_id of the whole file: what a resume must match */
    char name[CM_LINK_MAX_NAME + 1];
} cm_link_offer;

/* payload bytes of ACCEPT (start, chunk, crc, id) and END (size, crc, id) */
#define CM_LINK_ACCEPT_BYTES 20u
#define CM_LINK_END_BYTES 16u

/**
 * A file's content id: CRC-64/XZ (ECMA-182 polynomial, reflected) of all its bytes, continued from
 * `id` (start with 0).  Unlike the file's CRC-32 it differs between two valid .cmz files of the same
 * size (but for a 2^-64 chance), so it is what decides that a transfer resumes.
 */
uint64_t cm_link_id_update(uint64_t id, const uint8_t *p, size_t n);

/*
 * The HELLO in pieces.  A whole HELLO is a ~130-byte frame: at 10 % bad bytes one arrives whole once
 * in 800 tries.  So a SYNC may ask for pieces instead (payload: u8 proto, u8 first, u32 mask: bit j
 * asks for piece first + j), and the terminal answers each asked piece with a HELLO_PART of
 * CM_LINK_HELLO_PIECE bytes of the HELLO payload (payload: u8 index, u8 count, u16 low half of the
 * CRC-32 of the whole HELLO payload, the bytes): a 24-byte frame, as likely to arrive as a small DATA
 * frame.  The sender keeps the pieces it has and asks for the others.  A 1-byte SYNC asks for the
 * whole HELLO in one frame.
 */
#define CM_LINK_HELLO_PIECE 8u
#define CM_LINK_HELLO_MAX (8u + 4u * 255u + CM_LINK_MAX_NAME)
#define CM_LINK_SYNC_BYTES 6u

typedef struct cm_link_hello_parts {
    uint8_t buf[CM_LINK_HELLO_MAX];
    uint8_t have[(CM_LINK_HELLO_MAX / CM_LINK_HELLO_PIECE + 8) / 8]; /* bit k: piece k is in buf */
    unsigned count, len, held; /* pieces (0: not known yet), payload bytes, pieces held */
    uint16_t check;
} cm_link_hello_parts;

/** SYNC payload asking for the pieces of the HELLO not yet in *p (all of them when none is known). */
size_t cm_link_sync_pack(const cm_link_hello_parts *p, uint8_t *out);
/** A SYNC's request: 1 with first and mask (pieces first + j), 0 for a whole HELLO, -1 malformed. */
int cm_link_sync_unpack(const cm_link_frame *f, unsigned *first, uint32_t *mask);
/** Piece k of a packed HELLO payload (hello, n bytes): the HELLO_PART payload, 0 if there is no piece k. */
size_t cm_link_hello_part_pack(const uint8_t *hello, size_t n, unsigned k, uint8_t *out);
void cm_link_hello_parts_reset(cm_link_hello_parts *p);
/**
 * Take a HELLO_PART.  @return 1 when the pieces make the whole HELLO (*h filled; its CRC matched),
 * 0 otherwise (a piece of another HELLO than the ones held restarts the collection)
 */
int cm_link_hello_part_add(cm_link_hello_parts *p, const cm_link_frame *f, cm_link_hello *h);

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
static inline void cm_link_put64(uint8_t *p, uint64_t v)
{
    cm_link_put32(p, (uint32_t)v);
    cm_link_put32(p + 4, (uint32_t)(v >> 32));
}
static inline uint64_t cm_link_get64(const uint8_t *p)
{
    return (uint64_t)cm_link_get32(p) | (uint64_t)cm_link_get32(p + 4) << 32;
}

#endif /* CM_LINK_H */
