/*
 * cm_link_term.h - the terminal's end of a transfer: answers SYNC with
 * HELLO, accepts or refuses an OFFER, stores DATA chunks (selective
 * repeat, any order inside the window) and verifies the END.
 *
 * Storage in the output directory (docs/LINK.md "On the terminal"):
 *   .incoming.part   the bytes so far, written at their offsets
 *   .incoming.meta   size, CRC and the synced contiguous prefix of the
 *                    transfer in progress (replaced atomically): a resumed
 *                    transfer (cable pulled, terminal rebooted, sender
 *                    restarted) starts from that prefix
 *   .incoming.cmz    the complete file after its CRC matched; the caller
 *                    decodes it and moves it into place.  One found by
 *                    cm_link_term_open (a kill before it was decoded) is
 *                    finished by the caller at start (t->recovered)
 * Nothing here touches the model the viewer shows.
 *
 * The decoder is fed the bytes as they become contiguous, so a model the
 * build cannot hold is refused (REFUSE, with the limit) as soon as its
 * header is in, long before its body has crossed the cable.
 * No heap: everything is in the caller's struct.
 */
#ifndef CM_LINK_TERM_H
#define CM_LINK_TERM_H

#include <limits.h>

#include "cm/cm_decode.h"
#include "cm_link.h"

#define CM_TERM_PATH 512

typedef enum cm_term_event {
    CM_TERM_NONE = 0,
    CM_TERM_STARTED = 1,  /* an offer was accepted: receiving (busy) */
    CM_TERM_COMPLETE = 2, /* .incoming.cmz is verified and fully fed to the decoder: decode it now */
    CM_TERM_FAILED = 3,   /* the transfer was refused or its CRC failed (t->why) */
    CM_TERM_IDLE = 4      /* an accepted transfer has had no frame for CM_TERM_IDLE_MS */
} cm_term_event;

#define CM_TERM_IDLE_MS 10000

typedef struct cm_link_term {
    cm_link link;
    cm_decoder *dec;
    cm_link_hello hello;
    char dir[CM_TERM_PATH];
    char part_path[CM_TERM_PATH], meta_path[CM_TERM_PATH], in_path[CM_TERM_PATH];
    int part_fd;
    /* the transfer in progress */
    bool active;
    cm_link_offer offer;
    uint32_t origin, chunk, prefix, synced;
    uint64_t held;         /* bit j: chunk at prefix + j*chunk is stored */
    int64_t last_frame_ms, last_sync_ms, last_ack_ms;
    uint32_t damage_reported;
    bool idle_reported;
    /* the last finished transfer, to answer a repeated END */
    bool have_last;
    uint32_t last_size, last_crc;
    uint64_t last_id;
    int last_stage, last_code;
    char last_text[CM_LINK_MAX_TEXT + 1];
    char why[CM_LINK_MAX_TEXT + 1]; /* text of the last FAILED event */
    /* set by cm_link_term_open: .incoming.cmz of an earlier run, verified and synced but never
       decoded; t->offer holds its size, CRC and id.  The caller decodes it (it is not fed to
       t->dec) and calls cm_link_term_recovered */
    bool recovered;
    bool writes_stl; /* set by the caller: the free-space check at OFFER counts model.stl too */
} cm_link_term;

/**
 * Set up on directory `dir` (must exist and be writable), loading what an
 * earlier run left: a transfer to resume, or a verified .incoming.cmz that
 * was never decoded (t->recovered); and remembering the model on screen
 * (DIR/model.cmz) as decoded, so that a sender repeating END for it after a
 * restart gets DONE.  @return 0, or -1 with t->why set
 */
int cm_link_term_open(cm_link_term *t, cm_decoder *dec, const char *dir, const char *name);

/** (Re)bind to a transport after it was opened. */
void cm_link_term_attach(cm_link_term *t, cm_transport *tr);

/**
 * Serve frames for at most timeout_ms, returning at the first event.
 * @return a cm_term_event, or CM_T_HANGUP / CM_T_IO from the transport
 */
int cm_link_term_poll(cm_link_term *t, int timeout_ms);

/** The model of the last COMPLETE event was decoded (code 0) or not: tell the sender. */
void cm_link_term_decoded(cm_link_term *t, int code, const char *text);

/**
 * The file recovered at open was decoded (code 0) or not: remembered like a finished transfer, so
 * the sender's repeated END (it waited through the restart) is answered with this DONE.
 */
void cm_link_term_recovered(cm_link_term *t, int code, const char *text);

/** The operator pressed the button: ask the workstation to send again. */
int cm_link_term_request(cm_link_term *t);

/** Close the part file (the transfer stays resumable). */
void cm_link_term_close(cm_link_term *t);

#endif /* CM_LINK_TERM_H */
