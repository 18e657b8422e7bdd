/*
 * cm_transport.h - one byte link with deadlines: the only thing the link
 * protocol (cm_link.c) knows about a cable.
 *
 * Back ends (each in its own file, the only places that include the
 * system's device headers):
 *   cm_transport_fd.c      a pair of file descriptors: files, pipes, stdin/stdout
 *   cm_transport_serial.c  a tty in raw mode (termios), any baud the driver takes
 *   cm_transport_usb.c     libusb-1.0 bulk endpoints: the terminal is the USB host
 *   cm_transport_ffs.c     FunctionFS bulk endpoints: the workstation is the USB gadget
 *   fake/cm_transport_fake.c  an in-memory pair with seeded faults, for tests
 *
 * Every back end embeds a cm_transport as its first member and fills in the
 * three operations; nothing is allocated (the caller owns the back end's
 * struct, static on the terminal).  Deadlines are relative, in ms; no call
 * ever blocks longer than its deadline, so a pulled cable is noticed.
 */
#ifndef CM_TRANSPORT_H
#define CM_TRANSPORT_H

#include <stddef.h>
#include <stdint.h>

/* negative results of read/write; 0 from read means "deadline passed, no byte" */
enum {
    CM_T_HANGUP = -1, /* the other end went away (EOF, POLLHUP, EIO, USB device gone): reopen */
    CM_T_IO = -2      /* any other failure; err holds the text */
};

typedef struct cm_transport cm_transport;
struct cm_transport {
    /**
     * Read 1..n bytes into buf, waiting at most timeout_ms for the first.
     * @return bytes read (> 0), 0 when the deadline passed, CM_T_HANGUP or CM_T_IO
     */
    long (*read)(cm_transport *t, uint8_t *buf, size_t n, int timeout_ms);
    /**
     * Write all n bytes within timeout_ms.
     * @return n, 0 when the deadline passed first (some bytes may have gone), CM_T_HANGUP or CM_T_IO
     */
    long (*write)(cm_transport *t, const uint8_t *buf, size_t n, int timeout_ms);
    /** Release the device and restore whatever open changed (tty settings); safe to call twice. */
    void (*close)(cm_transport *t);
    /** For log lines: "serial /dev/ttyUSB0 115200", "usb 1209:0001". */
    char name[96];
    /** The last failure as one line of text ("" if none). */
    char err[192];
};

#endif /* CM_TRANSPORT_H */
