/*
 * cm_transport_serial.h - a cm_transport over a tty in raw mode: a UART
 * (/dev/ttyS*, /dev/ttyAMA*), a USB serial adapter (/dev/ttyUSB*, ttyACM*) or
 * a pty (tests).
 *
 * Open puts the line in raw 8N1 (no echo, no line editing, no CR/NL
 * translation, no XON/XOFF, CLOCAL so a missing DCD does not block),
 * VMIN=0/VTIME=0 with poll() for the deadlines, and reads the settings back
 * to make sure the driver kept them.  Close puts back what it found.
 *
 * This header is included by workstation code too, so it does not include
 * <termios.h>: the saved settings live in opaque storage (checked against
 * sizeof(struct termios) in the .c).
 */
#ifndef CM_TRANSPORT_SERIAL_H
#define CM_TRANSPORT_SERIAL_H

#include <stddef.h>

#include "cm_transport.h"

#define CM_SERIAL_DEFAULT_BAUD 115200u

/** cm_serial_open_flags: hardware flow control (RTS/CTS). */
#define CM_SERIAL_RTSCTS 1u
/**
 * cm_serial_open_flags: accept a driver that reads back another line speed
 * than asked (USB gadget ports such as ttyGS*, where the speed means nothing).
 */
#define CM_SERIAL_ANY_SPEED 2u

typedef struct cm_serial {
    cm_transport t;
    int fd;          /* -1 when closed */
    unsigned baud;   /* as asked and read back */
    unsigned flags;  /* CM_SERIAL_* */
    int have_saved;  /* saved holds the settings found at open */
    char dev[128];   /* the path (by-id names run long), for messages */
    /* struct termios as found at open (opaque here; big enough for any libc) */
    union cm_serial_saved {
        unsigned char bytes[128];
        long align_l; /* no long long: on armhf that would make cm_serial more aligned than its cm_transport */
        void *align_p;
    } saved;
} cm_serial;

/**
 * Split "DEV[:BAUD]" into the device path and the baud rate (default
 * CM_SERIAL_DEFAULT_BAUD).  A spec that names an existing file as a whole is
 * all path (by-path names contain ':'); otherwise the text after the last
 * ':' must be a rate termios can set (50 ... 4000000, see cm_serial_baud_ok).
 * @param dev     receives the path; on failure, a one-line message instead
 *                ("serial spec '/dev/ttyS0:96OO': baud '96OO' is not a number")
 * @param devcap  size of dev (64 or more to hold the messages whole)
 * @return 0, or -1 with the message in dev
 */
int cm_serial_parse(const char *spec, char *dev, size_t devcap, unsigned *baud);

/** 1 when termios has a constant (Bxxx) for this rate on this system, else 0. */
int cm_serial_baud_ok(unsigned baud);

/**
 * Open dev at baud, raw 8N1, no flow control (cm_serial_open_flags(s, dev, baud, 0)).
 * @return 0, or -1 with s->t.err set ("serial /dev/ttyUSB0: ..."); s->t.close is safe either way
 */
int cm_serial_open(cm_serial *s, const char *dev, unsigned baud);

/** cm_serial_open with CM_SERIAL_RTSCTS and/or CM_SERIAL_ANY_SPEED. */
int cm_serial_open_flags(cm_serial *s, const char *dev, unsigned baud, unsigned flags);

#endif /* CM_TRANSPORT_SERIAL_H */
