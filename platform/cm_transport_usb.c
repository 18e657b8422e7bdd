/*
 * cm_transport_usb.c - cm_transport over libusb-1.0 bulk endpoints (the
 * terminal is the USB host).  The only file that includes <libusb.h>.
 *
 * Two transfers, allocated at open, are submitted and waited for the way
 * libusb's synchronous calls do it: every call carries its deadline as the
 * transfer's timeout, and the bytes that moved before a timeout
 * (actual_length, libusb_bulk_transfer's `transferred`) are kept.  Own
 * transfers rather than libusb_bulk_transfer because that allocates one per
 * call and cannot append a zero-length packet.  Debian 12 ships libusb 1.0.26
 * (LIBUSB_API_VERSION 0x01000109); newer calls are behind version checks.
 */
#define _POSIX_C_SOURCE 200809L

#include "cm_transport_usb.h"

#include <errno.h>
#include <libusb.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "cm_clock.h"

/* libusb_init_context() replaced libusb_init() in 1.0.27 (API 0x0100010A) */
#if defined(LIBUSB_API_VERSION) && LIBUSB_API_VERSION >= 0x0100010A
#define CM_LIBUSB_INIT(ctxp) libusb_init_context((ctxp), NULL, 0)
#else
#define CM_LIBUSB_INIT(ctxp) libusb_init(ctxp)
#endif

/* one bulk OUT call moves at most this much, so the deadline is re-checked between calls */
#define CM_USB_TX_CHUNK (1u << 20)
/* cm_usb_wait's polling period */
#define CM_USB_POLL_MS 100

_Static_assert(CM_USB_RX_BUF % 1024u == 0, "CM_USB_RX_BUF must be a multiple of every bulk wMaxPacketSize");
_Static_assert(CM_USB_RX_BUF <= INT_MAX, "libusb takes int lengths");

/* t is the first member of a cm_usb (via void *, in case cm_usb is ever more aligned than cm_transport) */
static cm_usb *usb_of(cm_transport *t)
{
    return (cm_usb *)(void *)t;
}

/* libusb reads a timeout of 0 as "forever": the shortest real wait is 1 ms */
static unsigned int libusb_timeout(int64_t deadline)
{
    int64_t left = deadline - cm_clock_ms();
    if (left < 1)
        return 1;
    if (left > INT_MAX)
        return INT_MAX;
    return (unsigned int)left;
}

__attribute__((format(printf, 2, 3))) static void set_err(cm_usb *u, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(u->t.err, sizeof u->t.err, fmt, ap);
    va_end(ap);
}

/* "LIBUSB_ERROR_ACCESS (Access denied (insufficient permissions))" */
static const char *usb_error_text(int rc, char *buf, size_t cap)
{
    snprintf(buf, cap, "%s (%s)", libusb_error_name(rc), libusb_strerror(rc));
    return buf;
}

/* what the operator should do about an open/claim failure */
static const char *usb_error_advice(int rc)
{
    switch (rc) {
    case LIBUSB_ERROR_ACCESS:
        return "no permission on the device node: add a udev rule for the VID:PID (MODE=\"0660\", "
               "GROUP=\"plugdev\") or run as root";
    case LIBUSB_ERROR_BUSY:
        return "another program holds the interface (a second cmz-terminal?)";
    case LIBUSB_ERROR_NO_DEVICE:
        return "the device went away: check the cable";
    case LIBUSB_ERROR_NO_MEM:
        return "out of memory";
    default:
        return "check the cable and the workstation's gadget (cmz-usb-gadget.sh)";
    }
}

static int is_hangup(int rc)
{
    /* NO_DEVICE: unplugged; IO: the transfer died with the link; PIPE: the
     * gadget stalled the endpoint (its function was torn down) */
    return rc == LIBUSB_ERROR_NO_DEVICE || rc == LIBUSB_ERROR_IO || rc == LIBUSB_ERROR_PIPE;
}

/*
 * Open the first device with this VID:PID (and iSerialNumber, when given).
 * With want_handle 0 and no serial nothing is opened: only presence counts.
 * @param n_match  receives how many devices had the VID:PID
 * @param out      receives the open handle (want_handle 1)
 * @return 0, LIBUSB_ERROR_NOT_FOUND, or the error of opening a candidate
 */
static int open_matching(libusb_context *ctx, uint16_t vid, uint16_t pid, const char *serial, int want_handle,
                         libusb_device_handle **out, int *n_match)
{
    libusb_device **list = NULL;
    ssize_t n = libusb_get_device_list(ctx, &list);
    int result = LIBUSB_ERROR_NOT_FOUND;
    *n_match = 0;
    if (out)
        *out = NULL;
    if (n < 0)
        return (int)n;
    for (ssize_t i = 0; i < n; i++) {
        struct libusb_device_descriptor dd;
        if (libusb_get_device_descriptor(list[i], &dd) != 0 || dd.idVendor != vid || dd.idProduct != pid)
            continue;
        (*n_match)++;
        if (!want_handle && !serial) {
            result = 0;
            break;
        }
        libusb_device_handle *h = NULL;
        int rc = libusb_open(list[i], &h);
        if (rc != 0) {
            result = rc; /* remember why; a later candidate may still open */
            continue;
        }
        if (serial) {
            unsigned char s[CM_USB_SERIAL_MAX] = "";
            rc = dd.iSerialNumber ? libusb_get_string_descriptor_ascii(h, dd.iSerialNumber, s, sizeof s) : -1;
            if (rc < 0 || strcmp((const char *)s, serial) != 0) {
                libusb_close(h);
                continue;
            }
        }
        result = 0;
        if (want_handle)
            *out = h;
        else
            libusb_close(h);
        break;
    }
    libusb_free_device_list(list, 1);
    return result;
}

/*
 * Pick the first interface with a vendor-class alternate setting that has a
 * bulk IN and a bulk OUT endpoint.
 * @return 0, or -1 when the configuration has none
 */
static int find_bulk_interface(cm_usb *u, const struct libusb_config_descriptor *cfg)
{
    for (int i = 0; i < cfg->bNumInterfaces; i++) {
        const struct libusb_interface *itf = &cfg->interface[i];
        for (int a = 0; a < itf->num_altsetting; a++) {
            const struct libusb_interface_descriptor *id = &itf->altsetting[a];
            uint8_t in = 0, out = 0;
            uint16_t mps_in = 0, mps_out = 0;
            if (id->bInterfaceClass != LIBUSB_CLASS_VENDOR_SPEC)
                continue;
            for (int e = 0; e < id->bNumEndpoints; e++) {
                const struct libusb_endpoint_descriptor *ed = &id->endpoint[e];
                if ((ed->bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) != LIBUSB_TRANSFER_TYPE_BULK)
                    continue;
                /* bits 10..0 are the packet size (high-bandwidth bits only matter for iso/interrupt) */
                uint16_t mps = (uint16_t)(ed->wMaxPacketSize & 0x7ff);
                if ((ed->bEndpointAddress & LIBUSB_ENDPOINT_DIR_MASK) == LIBUSB_ENDPOINT_IN) {
                    if (!in) {
                        in = ed->bEndpointAddress;
                        mps_in = mps;
                    }
                } else if (!out) {
                    out = ed->bEndpointAddress;
                    mps_out = mps;
                }
            }
            if (in && out && mps_in && mps_out) {
                u->iface = id->bInterfaceNumber;
                u->alt = id->bAlternateSetting;
                u->ep_in = in;
                u->ep_out = out;
                u->mps_in = mps_in;
                u->mps_out = mps_out;
                return 0;
            }
        }
    }
    return -1;
}

static long usb_read(cm_transport *t, uint8_t *buf, size_t n, int timeout_ms);
static long usb_write(cm_transport *t, const uint8_t *buf, size_t n, int timeout_ms);
static void usb_close(cm_transport *t);

int cm_usb_open(cm_usb *u, uint16_t vid, uint16_t pid, const char *serial)
{
    char e[128];
    int rc;
    if (serial && !serial[0])
        serial = NULL;
    u->t.read = usb_read;
    u->t.write = usb_write;
    u->t.close = usb_close;
    u->t.err[0] = '\0';
    if (serial)
        snprintf(u->t.name, sizeof u->t.name, "usb %04x:%04x:%s", vid, pid, serial);
    else
        snprintf(u->t.name, sizeof u->t.name, "usb %04x:%04x", vid, pid);
    u->ctx = u->handle = NULL;
    u->iface = -1;
    u->alt = 0;
    u->claimed = 0;
    u->driver_detached = 0;
    u->vid = vid;
    u->pid = pid;
    u->ep_in = u->ep_out = 0;
    u->mps_in = u->mps_out = 0;
    u->rx_xfer = u->tx_xfer = NULL;
    u->rx_done = u->tx_done = 0;
    u->rx_pos = u->rx_len = 0;

    libusb_context *ctx = NULL;
    rc = CM_LIBUSB_INIT(&ctx);
    if (rc != 0) {
        set_err(u, "%s: libusb_init: %s: is usbfs available (/dev/bus/usb)?", u->t.name,
                usb_error_text(rc, e, sizeof e));
        return -1;
    }
    u->ctx = ctx;

    libusb_device_handle *h = NULL;
    int n_match = 0;
    rc = open_matching(ctx, vid, pid, serial, 1, &h, &n_match);
    if (rc == LIBUSB_ERROR_NOT_FOUND && n_match == 0) {
        set_err(u, "%s: no such device on the bus: check the cable and that the workstation's gadget is bound "
                "(cmz-usb-gadget.sh bind)", u->t.name);
        goto fail;
    }
    if (rc == LIBUSB_ERROR_NOT_FOUND) {
        set_err(u, "%s: %d device(s) %04x:%04x present, none with serial \"%s\"", u->t.name, n_match, vid, pid,
                serial);
        goto fail;
    }
    if (rc == LIBUSB_ERROR_ACCESS) {
        set_err(u, "%s: open: LIBUSB_ERROR_ACCESS: no permission on the device node: add a udev rule "
                "SUBSYSTEM==\"usb\", ATTR{idVendor}==\"%04x\", MODE=\"0660\", GROUP=\"plugdev\" (or run as root)",
                u->t.name, vid);
        goto fail;
    }
    if (rc != 0) {
        set_err(u, "%s: open: %s: %s", u->t.name, libusb_error_name(rc), usb_error_advice(rc));
        goto fail;
    }
    u->handle = h;

    libusb_device *dev = libusb_get_device(h);
    struct libusb_config_descriptor *cfg = NULL;
    rc = libusb_get_active_config_descriptor(dev, &cfg);
    if (rc == LIBUSB_ERROR_NOT_FOUND) {
        /* unconfigured (no kernel driver chose a configuration): take the first */
        rc = libusb_get_config_descriptor(dev, 0, &cfg);
        if (rc == 0)
            rc = libusb_set_configuration(h, cfg->bConfigurationValue);
    }
    if (rc != 0) {
        set_err(u, "%s: configuration: %s", u->t.name, usb_error_text(rc, e, sizeof e));
        if (cfg)
            libusb_free_config_descriptor(cfg);
        goto fail;
    }
    int found = find_bulk_interface(u, cfg);
    libusb_free_config_descriptor(cfg);
    if (found != 0) {
        set_err(u, "%s: no vendor-class (0xff) interface with a bulk IN and a bulk OUT endpoint: "
                "not a curvemesh link (wrong VID:PID?)", u->t.name);
        goto fail;
    }

    rc = libusb_kernel_driver_active(h, u->iface);
    if (rc == 1) {
        rc = libusb_detach_kernel_driver(h, u->iface);
        if (rc != 0) {
            set_err(u, "%s: detach kernel driver from interface %d: %s: %s", u->t.name, u->iface,
                    libusb_error_name(rc), usb_error_advice(rc));
            goto fail;
        }
        u->driver_detached = 1;
    } else if (rc < 0 && rc != LIBUSB_ERROR_NOT_SUPPORTED) {
        set_err(u, "%s: kernel driver of interface %d: %s: %s", u->t.name, u->iface, libusb_error_name(rc),
                usb_error_advice(rc));
        goto fail;
    }
    rc = libusb_claim_interface(h, u->iface);
    if (rc != 0) {
        set_err(u, "%s: claim interface %d: %s: %s", u->t.name, u->iface, libusb_error_name(rc),
                usb_error_advice(rc));
        goto fail;
    }
    u->claimed = 1;
    u->rx_xfer = libusb_alloc_transfer(0);
    u->tx_xfer = libusb_alloc_transfer(0);
    if (!u->rx_xfer || !u->tx_xfer) {
        set_err(u, "%s: libusb_alloc_transfer: out of memory", u->t.name);
        goto fail;
    }
    if (u->alt != 0) {
        rc = libusb_set_interface_alt_setting(h, u->iface, u->alt);
        if (rc != 0) {
            set_err(u, "%s: alternate setting %d of interface %d: %s", u->t.name, u->alt, u->iface,
                    usb_error_text(rc, e, sizeof e));
            goto fail;
        }
    }
    return 0;

fail:
    usb_close(&u->t);
    return -1;
}

static void usb_close(cm_transport *t)
{
    cm_usb *u = usb_of(t);
    /* no transfer is in flight here: read and write wait for theirs to finish */
    if (u->rx_xfer)
        libusb_free_transfer(u->rx_xfer);
    if (u->tx_xfer)
        libusb_free_transfer(u->tx_xfer);
    u->rx_xfer = u->tx_xfer = NULL;
    if (u->handle) {
        libusb_device_handle *h = u->handle;
        if (u->claimed)
            libusb_release_interface(h, u->iface);
        if (u->driver_detached)
            libusb_attach_kernel_driver(h, u->iface);
        libusb_close(h);
    }
    u->handle = NULL;
    u->iface = -1;
    u->claimed = 0;
    u->driver_detached = 0;
    if (u->ctx)
        libusb_exit(u->ctx);
    u->ctx = NULL;
    u->rx_pos = u->rx_len = 0;
}

static long hand_out(cm_usb *u, uint8_t *buf, size_t n)
{
    size_t k = u->rx_len - u->rx_pos;
    if (k > n)
        k = n;
    memcpy(buf, u->rx + u->rx_pos, k);
    u->rx_pos += k;
    if (u->rx_pos == u->rx_len)
        u->rx_pos = u->rx_len = 0;
    return (long)k;
}

static long transfer_failed(cm_usb *u, const char *what, uint8_t ep, int rc)
{
    char e[128];
    if (is_hangup(rc)) {
        set_err(u, "%s: bulk %s 0x%02x: %s: the cable was pulled or the workstation went away (reopen)", u->t.name,
                what, ep, usb_error_text(rc, e, sizeof e));
        return CM_T_HANGUP;
    }
    set_err(u, "%s: bulk %s 0x%02x: %s", u->t.name, what, ep, usb_error_text(rc, e, sizeof e));
    return CM_T_IO;
}

static void LIBUSB_CALL transfer_done(struct libusb_transfer *x)
{
    *(int *)x->user_data = 1;
}

/*
 * One bulk transfer with the deadline as its libusb timeout (libusb's own
 * synchronous calls work this way, but allocate a transfer per call and
 * cannot add a zero-length packet).
 * @param actual  receives the bytes that moved, also when the result is a timeout
 * @return 0 or a LIBUSB_ERROR_* code (LIBUSB_ERROR_TIMEOUT at the deadline)
 */
static int run_transfer(cm_usb *u, struct libusb_transfer *x, int *done, uint8_t ep, unsigned char *buf, int len,
                        uint8_t flags, int64_t deadline, int *actual)
{
    *done = 0;
    *actual = 0;
    libusb_fill_bulk_transfer(x, u->handle, ep, buf, len, transfer_done, done, libusb_timeout(deadline));
    x->flags = flags;
    int rc = libusb_submit_transfer(x);
    if (rc != 0)
        return rc;
    while (!*done) {
        rc = libusb_handle_events_completed(u->ctx, done);
        if (rc != 0 && rc != LIBUSB_ERROR_INTERRUPTED) {
            /* we cannot wait for it any longer: cancel, and let libusb finish with the buffer */
            libusb_cancel_transfer(x);
            for (int tries = 0; !*done && tries < 100; tries++)
                libusb_handle_events_completed(u->ctx, done);
            break;
        }
    }
    *actual = x->actual_length;
    switch (x->status) {
    case LIBUSB_TRANSFER_COMPLETED:
        return 0;
    case LIBUSB_TRANSFER_TIMED_OUT:
        return LIBUSB_ERROR_TIMEOUT;
    case LIBUSB_TRANSFER_CANCELLED:
        return rc != 0 ? rc : LIBUSB_ERROR_INTERRUPTED;
    case LIBUSB_TRANSFER_STALL:
        return LIBUSB_ERROR_PIPE;
    case LIBUSB_TRANSFER_NO_DEVICE:
        return LIBUSB_ERROR_NO_DEVICE;
    case LIBUSB_TRANSFER_OVERFLOW:
        return LIBUSB_ERROR_OVERFLOW;
    default:
        return LIBUSB_ERROR_IO;
    }
}

static long usb_read(cm_transport *t, uint8_t *buf, size_t n, int timeout_ms)
{
    cm_usb *u = usb_of(t);
    if (!u->handle) {
        set_err(u, "%s: read on a closed link", u->t.name);
        return CM_T_IO;
    }
    if (n == 0)
        return 0;
    if (u->rx_pos < u->rx_len)
        return hand_out(u, buf, n);
    int64_t deadline = cm_clock_ms() + (timeout_ms > 0 ? timeout_ms : 0);
    for (;;) {
        int got = 0;
        /* always the whole buffer (a multiple of wMaxPacketSize), never n: a
         * shorter request would overflow on a full packet */
        int rc = run_transfer(u, u->rx_xfer, &u->rx_done, u->ep_in, u->rx, (int)sizeof u->rx, 0, deadline, &got);
        if (got > 0) { /* kept even when rc is LIBUSB_ERROR_TIMEOUT */
            u->rx_pos = 0;
            u->rx_len = (size_t)got;
            return hand_out(u, buf, n);
        }
        if (rc == LIBUSB_ERROR_TIMEOUT)
            return 0;
        if (rc != 0 && rc != LIBUSB_ERROR_INTERRUPTED)
            return transfer_failed(u, "IN", u->ep_in, rc);
        /* a zero-length packet (the end of a transfer that filled our previous
         * request exactly) or an interrupted wait: keep waiting */
        if (cm_clock_ms() >= deadline)
            return 0;
    }
}

static long usb_write(cm_transport *t, const uint8_t *buf, size_t n, int timeout_ms)
{
    cm_usb *u = usb_of(t);
    if (!u->handle) {
        set_err(u, "%s: write on a closed link", u->t.name);
        return CM_T_IO;
    }
    if (n == 0)
        return 0;
    if (n > LONG_MAX) {
        set_err(u, "%s: write of %zu bytes is too long", u->t.name, n);
        return CM_T_IO;
    }
    int64_t deadline = cm_clock_ms() + (timeout_ms > 0 ? timeout_ms : 0);
    /* libusb takes a non-const buffer for both directions; OUT transfers only read it */
    unsigned char *p = (unsigned char *)buf;
    /*
     * A transfer whose length is a multiple of the packet size ends with a
     * full packet, so the gadget's read (a 16 KiB request) would wait for
     * more: a zero-length packet ends it now.  usbfs appends it to the last
     * URB (LIBUSB_TRANSFER_ADD_ZERO_PACKET), else we send it separately.
     */
    int zlp = n % u->mps_out == 0;
    size_t done = 0;
    while (done < n) {
        size_t chunk = n - done < CM_USB_TX_CHUNK ? n - done : CM_USB_TX_CHUNK;
        uint8_t flags = zlp && done + chunk == n ? LIBUSB_TRANSFER_ADD_ZERO_PACKET : 0;
        int sent = 0;
        int rc = run_transfer(u, u->tx_xfer, &u->tx_done, u->ep_out, p + done, (int)chunk, flags, deadline, &sent);
        if (rc == LIBUSB_ERROR_NOT_SUPPORTED && flags) {
            rc = run_transfer(u, u->tx_xfer, &u->tx_done, u->ep_out, p + done, (int)chunk, 0, deadline, &sent);
            if (rc == 0 && sent == (int)chunk)
                rc = run_transfer(u, u->tx_xfer, &u->tx_done, u->ep_out, p, 0, 0, deadline, &(int){0});
        }
        if (sent > 0)
            done += (size_t)sent;
        if (rc == LIBUSB_ERROR_TIMEOUT)
            return 0;
        if (rc != 0 && rc != LIBUSB_ERROR_INTERRUPTED)
            return transfer_failed(u, "OUT", u->ep_out, rc);
        if (done < n && cm_clock_ms() >= deadline)
            return 0;
    }
    return (long)n;
}

int cm_usb_wait(uint16_t vid, uint16_t pid, const char *serial, int timeout_ms)
{
    if (serial && !serial[0])
        serial = NULL;
    int64_t deadline = cm_clock_ms() + (timeout_ms > 0 ? timeout_ms : 0);
    for (;;) {
        libusb_context *ctx = NULL;
        if (CM_LIBUSB_INIT(&ctx) != 0)
            return -1;
        int n_match = 0;
        int rc = open_matching(ctx, vid, pid, serial, 0, NULL, &n_match);
        libusb_exit(ctx);
        /* present but not openable (permissions) still counts: cm_usb_open explains */
        if (rc == 0 || (rc != LIBUSB_ERROR_NOT_FOUND && n_match > 0))
            return 1;
        int64_t left = deadline - cm_clock_ms();
        if (left <= 0)
            return 0;
        if (left > CM_USB_POLL_MS)
            left = CM_USB_POLL_MS;
        struct timespec ts = {.tv_sec = 0, .tv_nsec = (long)left * 1000000L};
        while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
        }
    }
}

/* 1-4 hex digits, optional 0x; stops at ':' or the end */
static int parse_hex16(const char **s, uint16_t *out)
{
    const char *p = *s;
    unsigned v = 0;
    int digits = 0;
    if (p[0] == '0' && (p[1] == 'x' || p[1] == 'X'))
        p += 2;
    for (; *p && *p != ':'; p++) {
        int d;
        if (*p >= '0' && *p <= '9')
            d = *p - '0';
        else if (*p >= 'a' && *p <= 'f')
            d = *p - 'a' + 10;
        else if (*p >= 'A' && *p <= 'F')
            d = *p - 'A' + 10;
        else
            return -1;
        if (++digits > 4)
            return -1;
        v = v * 16u + (unsigned)d;
    }
    if (digits == 0)
        return -1;
    *out = (uint16_t)v;
    *s = p;
    return 0;
}

int cm_usb_parse(const char *spec, uint16_t *vid, uint16_t *pid, char *serial, size_t cap)
{
    if (serial && cap)
        serial[0] = '\0';
    if (!spec || !spec[0])
        return CM_USB_PARSE_EMPTY;
    const char *p = spec;
    uint16_t v, d;
    if (parse_hex16(&p, &v) != 0 || *p != ':')
        return CM_USB_PARSE_VID;
    p++;
    if (parse_hex16(&p, &d) != 0)
        return CM_USB_PARSE_PID;
    if (v == 0)
        return CM_USB_PARSE_ZERO;
    size_t len = 0;
    if (*p == ':') {
        p++;
        len = strlen(p);
        if (len == 0 || !serial || len >= cap || len >= CM_USB_SERIAL_MAX)
            return CM_USB_PARSE_SERIAL;
        for (size_t i = 0; i < len; i++)
            if (p[i] < 0x20 || p[i] > 0x7e)
                return CM_USB_PARSE_SERIAL;
        memcpy(serial, p, len + 1);
    }
    *vid = v; /* outputs only on success */
    *pid = d;
    return 0;
}

const char *cm_usb_parse_strerror(int rc)
{
    switch (rc) {
    case 0:
        return "";
    case CM_USB_PARSE_EMPTY:
        return "empty USB device: give VID:PID[:SERIAL], e.g. 1209:0001";
    case CM_USB_PARSE_VID:
        return "bad USB vendor id: VID:PID[:SERIAL] wants VID as 1-4 hex digits followed by ':', e.g. 1209:0001";
    case CM_USB_PARSE_PID:
        return "bad USB product id: VID:PID[:SERIAL] wants PID as 1-4 hex digits, e.g. 1209:0001";
    case CM_USB_PARSE_SERIAL:
        return "bad USB serial: after VID:PID: give a non-empty printable ASCII serial of at most 127 characters";
    case CM_USB_PARSE_ZERO:
        return "USB vendor id 0000 is not a device";
    default:
        return "bad USB device specification";
    }
}
