/*
 * link_send.h - the workstation's end of a transfer (`cmz send`): finds
 * the terminal (SYNC -> HELLO), offers the file, streams it with selective
 * repeat over a window of chunks, resumes after a cable pull or a terminal
 * restart, and waits for the terminal's verdict (stored, then decoded).
 *
 * Adapts to the line: the retransmit timeout follows the measured round
 * trip, and the chunk size halves when most chunks are lost (a noisy
 * serial line: at 2 % bad bytes a 1 KiB frame almost never arrives whole)
 * and doubles again when the line is clean.  docs/LINK.md has the rules.
 */
#ifndef LINK_SEND_H
#define LINK_SEND_H

#include <signal.h>
#include <stdint.h>

#include "cm_link.h"

typedef struct link_send_opts {
    int connect_timeout_ms;  /* give up finding the terminal after this (also after a cable pull) */
    uint32_t chunk;          /* first chunk size (0: from the link's kind) */
    uint32_t chunk_max;      /* ceiling for the adaptation (0: the terminal's max payload) */
    unsigned baud;           /* serial line rate for the timeouts (0: not a paced line) */
    int wait_decoded;        /* wait for the terminal's decode result */
    int decode_timeout_ms;
    /* reopen the transport after CM_T_HANGUP (NULL: cannot; the send fails) */
    int (*reopen)(void *ctx, cm_transport **t);
    void *reopen_ctx;
    /* a hang-up is reported once per lost session and the handle stays usable (the FunctionFS
       gadget: closing it would unbind the gadget): wait on it instead of reopening */
    int hangup_keeps_transport;
    /* progress: bytes the terminal holds contiguously, of total (NULL: none) */
    void (*progress)(void *ctx, uint32_t done, uint32_t total, uint32_t chunk);
    void *progress_ctx;
    /* log lines ("link: ..."), NULL: silent */
    void (*log)(void *ctx, const char *line);
    void *log_ctx;
    /* the terminal's HELLO if the caller has just connected (link_send_connect): saves a round */
    const cm_link_hello *hello;
    int hello_rtt_ms, hello_tries; /* from that link_send_connect's result */
    /* set (by a signal handler) to stop: every wait is sliced to 100 ms and looks at it, so a send
       stops within that, telling the terminal (ABORT: it syncs its prefix, the next send resumes).
       NULL: never */
    volatile sig_atomic_t *stop;
} link_send_opts;

/* link_send_connect and link_send_file: o->stop was set (r->text says so) */
#define LINK_SEND_STOPPED (-2)
/* fresh starts of the end phase ("no such transfer") before a send gives up: a terminal that accepts
   every byte and then forgets the transfer would otherwise be fed the file forever */
#define LINK_SEND_MAX_LOST 3
/* offers in a row that moved nothing (no byte more held by the terminal) before a send gives up */
#define LINK_SEND_MAX_FRUITLESS 16

typedef struct link_send_result {
    int stage;  /* the last DONE stage seen: 0 none, CM_LINK_STAGE_STORED, CM_LINK_STAGE_DECODED */
    int code;   /* the terminal's code at that stage (0 ok, a cm_err) or a local failure */
    char text[CM_LINK_MAX_TEXT + 64];
    uint64_t chunks_sent, chunks_resent;
    unsigned reconnects, chunk_changes;
    uint32_t resumed_from; /* offset of the first ACCEPT */
    uint32_t held; /* after LINK_SEND_STOPPED: the terminal's contiguous prefix as last seen */
    uint32_t resume_offset; /* the last ACCEPT after a (re)connect that started mid-file (0: none) */
    unsigned resumes;
    int connect_rtt_ms, connect_tries; /* of the last SYNC -> HELLO exchange (tries: 1 + damaged frames) */
    unsigned hello_pieces;  /* HELLO_PART frames taken in the last SYNC -> HELLO exchange */
    unsigned direct_offers; /* reconnects that offered at once, without a new HELLO */
    unsigned lost_transfers; /* times the terminal answered END with "no such transfer" */
} link_send_result;

void link_send_defaults(link_send_opts *o);

/**
 * SYNC until a HELLO comes back (whole, or in HELLO_PART pieces on a noisy line).
 * @return 0 with *h filled, -1 with r->text (no answer, hang-up without reopen), LINK_SEND_STOPPED
 */
int link_send_connect(cm_link *l, const link_send_opts *o, cm_link_hello *h, link_send_result *r);

/**
 * Offer and send `size` bytes named `name` to a connected terminal.
 * @return 0 when the terminal stored (and, if asked, decoded) it without
 *         error; 1 when the terminal refused it or failed (r->code, r->text);
 *         -1 when the link failed or the transfer made no progress (r->text); LINK_SEND_STOPPED
 *         when o->stop was set (the terminal was sent ABORT and keeps what it holds)
 */
int link_send_file(cm_link *l, const uint8_t *data, uint32_t size, const char *name, const link_send_opts *o,
                   link_send_result *r);

#endif /* LINK_SEND_H */
