/*
 * cm_transport_usb.h - the terminal's end of the USB cable: libusb-1.0 bulk
 * endpoints of the workstation's gadget (cm_transport_ffs.h is the other end).
 *
 * The terminal is the USB host.  The device is found by VID:PID and, when
 * several are plugged in, by its iSerialNumber string.  The interface is the
 * first one with a vendor-class (0xff) alternate setting that has one bulk IN
 * and one bulk OUT endpoint; the endpoint addresses and packet sizes come
 * from the descriptors (the UDC chooses them, not us).
 *
 * No heap in this file: the receive buffer lives in the struct, which the
 * caller owns (static on the terminal), and the two libusb transfers are
 * allocated at open.  libusb also allocates inside itself (context, handle,
 * and its Linux back end's URBs per submission); that is libusb's, not ours.
 *
 * A pulled cable makes read/write return CM_T_HANGUP: close, then
 * cm_usb_wait() for the device to come back, then cm_usb_open() again.
 */
#ifndef CM_TRANSPORT_USB_H
#define CM_TRANSPORT_USB_H

#include <stddef.h>
#include <stdint.h>

#include "cm_transport.h"

/*
 * Receive buffer: one bulk IN transfer asks for this many bytes.  It must be
 * a multiple of wMaxPacketSize (64 full speed, 512 high speed, 1024 super
 * speed): a request shorter than the packet the device sends fails with
 * LIBUSB_ERROR_OVERFLOW, and the data of that packet is lost.
 */
#define CM_USB_RX_BUF 16384u
/* iSerialNumber strings longer than this are not matched (USB allows 126 characters) */
#define CM_USB_SERIAL_MAX 128u

typedef struct cm_usb {
    cm_transport t;          /* first member: a cm_usb * is a cm_transport * */
    void *ctx, *handle;      /* libusb_context *, libusb_device_handle * (NULL when closed) */
    uint8_t ep_in, ep_out;   /* endpoint addresses from the descriptors */
    uint16_t mps_in, mps_out; /* their wMaxPacketSize */
    int iface;               /* the link's interface number, -1 before one was found */
    int alt;                 /* its alternate setting */
    int claimed;             /* 1: iface is claimed, release on close */
    int driver_detached;     /* 1: we detached a kernel driver from iface, reattach on close */
    uint16_t vid, pid;
    void *rx_xfer, *tx_xfer; /* struct libusb_transfer *, allocated at open */
    int rx_done, tx_done;    /* set by the transfers' completion callbacks */
    size_t rx_pos, rx_len;   /* rx[rx_pos..rx_len) is received but not yet handed out */
    uint8_t rx[CM_USB_RX_BUF];
} cm_usb;

/* results of cm_usb_parse (negative) */
enum {
    CM_USB_PARSE_EMPTY = -1,   /* no text */
    CM_USB_PARSE_VID = -2,     /* VID is not 1-4 hex digits */
    CM_USB_PARSE_PID = -3,     /* PID is not 1-4 hex digits */
    CM_USB_PARSE_SERIAL = -4,  /* serial empty, too long for the buffer, or not printable ASCII */
    CM_USB_PARSE_ZERO = -5     /* VID 0000 is not a device */
};

/**
 * Parse "VID:PID" or "VID:PID:SERIAL" (VID and PID hex, 1-4 digits, an
 * optional 0x prefix), e.g. "1209:0001" or "1209:0001:CMZ-0042".
 * @param serial  receives the serial ("" when none); cap bytes including the NUL
 * @return 0, or a CM_USB_PARSE_* code (text: cm_usb_parse_strerror)
 */
int cm_usb_parse(const char *spec, uint16_t *vid, uint16_t *pid, char *serial, size_t cap);

/** One line explaining a cm_usb_parse result ("" for 0). */
const char *cm_usb_parse_strerror(int rc);

/**
 * Find the device, claim its vendor bulk interface and fill in u->t.
 * Detaches a kernel driver bound to that interface (reattached by close).
 * @param serial  iSerialNumber to match, or NULL / "" for the first VID:PID device
 * @return 0, or -1 with u->t.err naming the device, the libusb error and what to do
 *         (u is then closed: calling u->t.close is harmless)
 */
int cm_usb_open(cm_usb *u, uint16_t vid, uint16_t pid, const char *serial);

/**
 * Wait for a VID:PID[:serial] device to be present (after a re-plug), polling
 * every 100 ms without a busy loop.  Each poll enumerates afresh (a new libusb
 * context): without a running udevd a long-lived context never hears of new
 * devices.
 * @return 1 when present, 0 when timeout_ms passed first, -1 if libusb cannot start
 */
int cm_usb_wait(uint16_t vid, uint16_t pid, const char *serial, int timeout_ms);

#endif /* CM_TRANSPORT_USB_H */
