/*
 * cm_transport_ffs.c - cm_transport over FunctionFS bulk endpoints (the
 * workstation is the USB gadget).  The only file that includes the kernel's
 * FunctionFS and AIO headers.
 *
 * Why kernel AIO: a read() or write() on a FunctionFS endpoint file blocks
 * until the USB request completes (poll() on it always says "ready"), so it
 * cannot honour a deadline.  An AIO request signals an eventfd when it
 * completes; poll() then waits on that eventfd and on ep0 (the function's
 * events) together, with the deadline as its timeout.  The raw syscalls are
 * used (no libaio).
 */
#define _DEFAULT_SOURCE

#include "cm_transport_ffs.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <linux/aio_abi.h>
#include <linux/usb/ch9.h>
#include <linux/usb/functionfs.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <sys/eventfd.h>
#include <sys/ioctl.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include "cm_clock.h"

#define CM_FFS_INTERFACE_STRING "curvemesh link"
/* the smallest bulk packet size (full speed), used if the enabled endpoint's cannot be read */
#define CM_FFS_MIN_MPS 64u
/* after a write is cancelled at its deadline, how long to wait for the kernel to confirm */
#define CM_FFS_CANCEL_MS 1000

enum { TAG_RX = 1, TAG_TX = 2 };

_Static_assert(sizeof(struct iocb) <= sizeof(((cm_ffs *)0)->iocb_rx), "struct iocb does not fit cm_ffs.iocb_rx");
_Static_assert(CM_FFS_BUF % 1024u == 0, "CM_FFS_BUF must be a multiple of every bulk packet size");

/* ---- small helpers ---- */

static int ms_left(int64_t deadline)
{
    int64_t left = deadline - cm_clock_ms();
    if (left < 0)
        return 0;
    return left > INT_MAX ? INT_MAX : (int)left;
}

__attribute__((format(printf, 2, 3))) static void set_err(cm_ffs *f, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(f->t.err, sizeof f->t.err, fmt, ap);
    va_end(ap);
}

/* t is the first member of a cm_ffs (via void *: cm_ffs is more aligned than cm_transport on 32-bit ARM) */
static cm_ffs *ffs_of(cm_transport *t)
{
    return (cm_ffs *)(void *)t;
}

static struct iocb *iocb_at(uint64_t *storage)
{
    return (struct iocb *)(void *)storage;
}

/* ---- descriptors (built at run time: glibc's htole32() is not a constant expression) ---- */

static uint8_t *put_le16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v & 0xff);
    p[1] = (uint8_t)(v >> 8);
    return p + 2;
}

static uint8_t *put_le32(uint8_t *p, uint32_t v)
{
    p = put_le16(p, (uint16_t)(v & 0xffff));
    return put_le16(p, (uint16_t)(v >> 16));
}

static uint8_t *put_interface(uint8_t *p)
{
    *p++ = USB_DT_INTERFACE_SIZE;
    *p++ = USB_DT_INTERFACE;
    *p++ = 0; /* bInterfaceNumber: FunctionFS renumbers within the configuration */
    *p++ = 0; /* bAlternateSetting */
    *p++ = 2; /* bNumEndpoints */
    *p++ = USB_CLASS_VENDOR_SPEC;
    *p++ = 0; /* bInterfaceSubClass */
    *p++ = 0; /* bInterfaceProtocol */
    *p++ = 1; /* iInterface: the first string, "curvemesh link" */
    return p;
}

static uint8_t *put_bulk_endpoint(uint8_t *p, uint8_t address, uint16_t max_packet)
{
    *p++ = USB_DT_ENDPOINT_SIZE;
    *p++ = USB_DT_ENDPOINT;
    *p++ = address; /* the UDC may give another number; the host reads it from the descriptors */
    *p++ = USB_ENDPOINT_XFER_BULK;
    p = put_le16(p, max_packet);
    *p++ = 0; /* bInterval: unused for bulk */
    return p;
}

static uint8_t *put_ss_companion(uint8_t *p)
{
    *p++ = USB_DT_SS_EP_COMP_SIZE;
    *p++ = USB_DT_SS_ENDPOINT_COMP;
    *p++ = 0; /* bMaxBurst: one packet */
    *p++ = 0; /* bmAttributes: no streams */
    return put_le16(p, 0); /* wBytesPerInterval: periodic endpoints only */
}

/* one speed's descriptors: interface, IN endpoint (ep1), OUT endpoint (ep2) */
static uint8_t *put_speed(uint8_t *p, uint16_t max_packet, int super_speed)
{
    p = put_interface(p);
    p = put_bulk_endpoint(p, 1 | USB_DIR_IN, max_packet);
    if (super_speed)
        p = put_ss_companion(p);
    p = put_bulk_endpoint(p, 2 | USB_DIR_OUT, max_packet);
    if (super_speed)
        p = put_ss_companion(p);
    return p;
}

/* FunctionFS v2 descriptor blob; returns its length */
static size_t build_descriptors(uint8_t *buf)
{
    uint8_t *p = buf;
    p = put_le32(p, FUNCTIONFS_DESCRIPTORS_MAGIC_V2);
    uint8_t *length = p;
    p = put_le32(p, 0); /* length, patched below */
    p = put_le32(p, FUNCTIONFS_HAS_FS_DESC | FUNCTIONFS_HAS_HS_DESC | FUNCTIONFS_HAS_SS_DESC);
    p = put_le32(p, 3); /* full speed: interface + 2 endpoints */
    p = put_le32(p, 3); /* high speed */
    p = put_le32(p, 5); /* super speed: interface + 2 x (endpoint + companion) */
    p = put_speed(p, 64, 0);
    p = put_speed(p, 512, 0);
    p = put_speed(p, 1024, 1);
    put_le32(length, (uint32_t)(p - buf));
    return (size_t)(p - buf);
}

static size_t build_strings(uint8_t *buf)
{
    uint8_t *p = buf;
    p = put_le32(p, FUNCTIONFS_STRINGS_MAGIC);
    uint8_t *length = p;
    p = put_le32(p, 0);
    p = put_le32(p, 1);      /* str_count */
    p = put_le32(p, 1);      /* lang_count */
    p = put_le16(p, 0x0409); /* US English */
    memcpy(p, CM_FFS_INTERFACE_STRING, sizeof CM_FFS_INTERFACE_STRING);
    p += sizeof CM_FFS_INTERFACE_STRING;
    put_le32(length, (uint32_t)(p - buf));
    return (size_t)(p - buf);
}

/* ---- AIO ---- */

static int submit(cm_ffs *f, uint64_t *storage, int fd, int tag, void *buf, size_t n, int write)
{
    struct iocb cb;
    memset(&cb, 0, sizeof cb);
    cb.aio_data = (uint64_t)tag;
    cb.aio_lio_opcode = write ? IOCB_CMD_PWRITE : IOCB_CMD_PREAD;
    cb.aio_fildes = (uint32_t)fd;
    cb.aio_buf = (uint64_t)(uintptr_t)buf;
    cb.aio_nbytes = n;
    cb.aio_flags = IOCB_FLAG_RESFD;
    cb.aio_resfd = (uint32_t)f->efd;
    memcpy(storage, &cb, sizeof cb);
    struct iocb *list[1] = {iocb_at(storage)};
    long r = syscall(SYS_io_submit, (aio_context_t)f->aio, 1L, list);
    if (r != 1) {
        set_err(f, "%s: io_submit on %s: %s", f->t.name, write ? "ep1" : "ep2", strerror(r < 0 ? errno : EAGAIN));
        return -1;
    }
    return 0;
}

static void end_session(cm_ffs *f)
{
    if (f->enabled)
        f->hangup = 1;
    f->enabled = 0;
    f->rx_pos = f->rx_len = 0; /* bytes of the old session must not reach the next one */
}

/* is a failed request's errno the endpoint going away? */
static int is_link_gone(int64_t res)
{
    return res == -ESHUTDOWN || res == -ECONNRESET || res == -EAGAIN || res == -ENODEV;
}

/*
 * Is the endpoint enabled right now?  FUNCTIONFS_ENDPOINT_DESC fails with
 * EAGAIN on a non-blocking endpoint file while the endpoint is disabled, and
 * otherwise returns its descriptor for the current speed (mps: its packet size).
 */
static int ep_enabled(int fd, uint16_t *mps)
{
    struct usb_endpoint_descriptor d;
    memset(&d, 0, sizeof d);
    if (ioctl(fd, FUNCTIONFS_ENDPOINT_DESC, &d) != 0)
        return 0;
    if (mps) {
        const uint8_t *w = (const uint8_t *)&d.wMaxPacketSize; /* little-endian on the wire */
        *mps = (uint16_t)((w[0] | (w[1] << 8)) & 0x7ff);
    }
    return 1;
}

/*
 * A request failed as if the endpoint went away.  The DISABLE event says so
 * too, but the kernel keeps only the latest state event, so ask the
 * endpoint; if it is still enabled the failure was a race with a reset that
 * an ENABLE event will report.
 */
static void request_link_gone(cm_ffs *f, int fd)
{
    if (!ep_enabled(fd, NULL))
        end_session(f);
}

static void reap(cm_ffs *f)
{
    for (;;) {
        struct io_event ev[4];
        struct timespec zero = {0, 0};
        long r = syscall(SYS_io_getevents, (aio_context_t)f->aio, 0L, 4L, ev, &zero);
        if (r <= 0)
            return;
        for (long i = 0; i < r; i++) {
            int64_t res = ev[i].res;
            if (ev[i].data == TAG_RX) {
                f->rx_busy = 0;
                int current = f->enabled && f->rx_session == f->session;
                if (!current)
                    continue; /* a request of a session that already ended */
                if (res > 0) {
                    f->rx_pos = 0;
                    f->rx_len = (size_t)res;
                } else if (res < 0 && is_link_gone(res)) {
                    request_link_gone(f, f->ep_out);
                } else if (res < 0) {
                    f->rx_errno = (int)-res;
                }
                /* res == 0: a zero-length packet, nothing to hand out */
            } else if (ev[i].data == TAG_TX) {
                f->tx_busy = 0;
                f->tx_result = res;
                int cancelled = f->tx_cancelled;
                f->tx_cancelled = 0;
                if (res < 0 && is_link_gone(res) && !cancelled && f->enabled && f->tx_session == f->session)
                    request_link_gone(f, f->ep_in);
            }
        }
    }
}

/* ---- ep0: the function's events ---- */

static int serve_ep0(cm_ffs *f)
{
    struct usb_functionfs_event ev[4];
    ssize_t r = read(f->ep0, ev, sizeof ev);
    if (r < 0) {
        if (errno == EINTR || errno == EAGAIN || errno == EIDRM)
            return 0; /* EIDRM: a SETUP was cancelled by the host before we answered */
        set_err(f, "%s: ep0 events: %s", f->t.name, strerror(errno));
        return -1;
    }
    for (size_t i = 0; i < (size_t)r / sizeof ev[0]; i++) {
        switch (ev[i].type) {
        case FUNCTIONFS_BIND:
            f->bound = 1;
            break;
        case FUNCTIONFS_UNBIND:
            f->bound = 0;
            end_session(f);
            break;
        case FUNCTIONFS_ENABLE:
            /* DISABLE + ENABLE may arrive merged into one ENABLE (the kernel
             * keeps only the latest state event): a new session either way */
            end_session(f);
            f->enabled = 1;
            f->session++;
            if (!ep_enabled(f->ep_in, &f->mps_in) || f->mps_in == 0)
                f->mps_in = CM_FFS_MIN_MPS;
            break;
        case FUNCTIONFS_DISABLE:
            end_session(f);
            break;
        case FUNCTIONFS_SETUP: {
            /* we define no class or vendor requests: stall.  FunctionFS stalls
             * when the data stage goes the wrong way: read() for a
             * device-to-host request, write() for a host-to-device one (the
             * call then fails with EL2HLT, which is the expected result). */
            uint8_t none[1];
            ssize_t s;
            if (ev[i].u.setup.bRequestType & USB_DIR_IN)
                s = read(f->ep0, none, 0);
            else
                s = write(f->ep0, none, 0);
            (void)s;
            break;
        }
        default: /* SUSPEND, RESUME: the link is idle, not gone */
            break;
        }
    }
    return 0;
}

/*
 * Keep one read request of the whole buffer queued while the buffer is
 * empty.  It survives the deadline of the call that queued it, so nothing is
 * lost between calls; every service() round queues it, in writes too, so
 * the host can send while we send (one buffer of read-ahead).
 */
static int queue_rx(cm_ffs *f)
{
    if (!f->enabled || f->rx_busy || f->rx_pos < f->rx_len)
        return 0;
    if (submit(f, f->iocb_rx, f->ep_out, TAG_RX, f->rx, sizeof f->rx, 0) < 0)
        return -1;
    f->rx_busy = 1;
    f->rx_session = f->session;
    return 0;
}

/* wait up to wait_ms for ep0 events or AIO completions and handle them; -1 on a fatal error */
static int service(cm_ffs *f, int wait_ms)
{
    struct pollfd p[2] = {{.fd = f->ep0, .events = POLLIN}, {.fd = f->efd, .events = POLLIN}};
    int r = poll(p, 2, wait_ms);
    if (r < 0) {
        if (errno == EINTR)
            return 0;
        set_err(f, "%s: poll: %s", f->t.name, strerror(errno));
        return -1;
    }
    if (p[0].revents & POLLIN) {
        if (serve_ep0(f) < 0)
            return -1;
    }
    if (p[1].revents & POLLIN) {
        uint64_t count;
        if (read(f->efd, &count, sizeof count) < 0 && errno != EAGAIN) {
            set_err(f, "%s: eventfd: %s", f->t.name, strerror(errno));
            return -1;
        }
        reap(f);
    }
    return queue_rx(f);
}

/* ---- the cm_transport operations ---- */

static long hand_out(cm_ffs *f, uint8_t *buf, size_t n)
{
    size_t k = f->rx_len - f->rx_pos;
    if (k > n)
        k = n;
    memcpy(buf, f->rx + f->rx_pos, k);
    f->rx_pos += k;
    if (f->rx_pos == f->rx_len)
        f->rx_pos = f->rx_len = 0;
    return (long)k;
}

static long ffs_read(cm_transport *t, uint8_t *buf, size_t n, int timeout_ms)
{
    cm_ffs *f = ffs_of(t);
    if (f->ep0 < 0) {
        set_err(f, "%s: read on a closed link", f->t.name);
        return CM_T_IO;
    }
    if (n == 0)
        return 0;
    int64_t deadline = cm_clock_ms() + (timeout_ms > 0 ? timeout_ms : 0);
    int wait = 0;
    for (;;) {
        if (service(f, wait) < 0)
            return CM_T_IO;
        if (f->hangup) {
            f->hangup = 0;
            snprintf(f->t.err, sizeof f->t.err, "%s: the host went away or reset the link", f->t.name);
            return CM_T_HANGUP;
        }
        if (f->rx_pos < f->rx_len)
            return hand_out(f, buf, n);
        if (f->rx_errno) {
            set_err(f, "%s: ep2 (bulk OUT) read: %s", f->t.name, strerror(f->rx_errno));
            f->rx_errno = 0;
            return CM_T_IO;
        }
        wait = ms_left(deadline);
        if (wait == 0)
            return 0;
    }
}

/* wait until the queued write completes or the deadline passes; 1 done, 0 deadline, -1 fatal */
static int wait_tx(cm_ffs *f, int64_t deadline)
{
    while (f->tx_busy) {
        int left = ms_left(deadline);
        if (left == 0)
            return 0;
        if (service(f, left) < 0)
            return -1;
    }
    return 1;
}

static void cancel_tx(cm_ffs *f)
{
    struct io_event ev;
    /* the completion (-ECONNRESET, or the bytes if it won the race) is posted to the eventfd */
    f->tx_cancelled = 1;
    (void)syscall(SYS_io_cancel, (aio_context_t)f->aio, iocb_at(f->iocb_tx), &ev);
    (void)wait_tx(f, cm_clock_ms() + CM_FFS_CANCEL_MS);
}

static long ffs_write(cm_transport *t, const uint8_t *buf, size_t n, int timeout_ms)
{
    cm_ffs *f = ffs_of(t);
    if (f->ep0 < 0) {
        set_err(f, "%s: write on a closed link", f->t.name);
        return CM_T_IO;
    }
    if (n == 0)
        return 0;
    if (n > LONG_MAX) {
        set_err(f, "%s: write of %zu bytes is too long", f->t.name, n);
        return CM_T_IO;
    }
    int64_t deadline = cm_clock_ms() + (timeout_ms > 0 ? timeout_ms : 0);
    /*
     * Zero-length packet: the terminal reads with a 16 KiB request, which ends
     * on a short packet or when full.  A write that is a multiple of the
     * packet size ends on a full packet, so the terminal would sit on the
     * data until its deadline: a zero-length packet after it completes the
     * terminal's read at once.  The packet size is the enabled endpoint's
     * (read at ENABLE, it depends on the bus speed).  We do not wait for the
     * ZLP: the next write, or close, does.
     */
    int zlp = -1; /* -1: not decided until the host has enabled us */
    size_t done = 0;
    for (;;) {
        if (service(f, 0) < 0)
            return CM_T_IO;
        if (f->hangup) {
            f->hangup = 0;
            snprintf(f->t.err, sizeof f->t.err, "%s: the host went away or reset the link", f->t.name);
            return CM_T_HANGUP;
        }
        if (!f->enabled || f->tx_busy) {
            /* not configured yet, or the previous write's zero-length packet
             * (or a cancelled request) still in the kernel */
            int left = ms_left(deadline);
            if (left == 0) {
                if (f->tx_busy)
                    cancel_tx(f);
                return 0;
            }
            if (service(f, left) < 0)
                return CM_T_IO;
            continue;
        }
        if (zlp < 0)
            zlp = n % f->mps_in == 0;
        if (done == n && !zlp)
            return (long)n;
        size_t chunk = n - done < CM_FFS_BUF ? n - done : CM_FFS_BUF;
        /* the kernel copies the bytes at submission: buf need not outlive the request */
        if (submit(f, f->iocb_tx, f->ep_in, TAG_TX, (void *)(uintptr_t)(buf + done), chunk, 1) < 0)
            return CM_T_IO;
        f->tx_busy = 1;
        f->tx_session = f->session;
        if (chunk == 0)
            return (long)n; /* the ZLP is queued */
        int w = wait_tx(f, deadline);
        if (w < 0)
            return CM_T_IO;
        if (w == 0) {
            cancel_tx(f);
            return 0;
        }
        if (f->tx_result < 0) {
            /* ESHUTDOWN and the like can complete the write before ep0's UNBIND/DISABLE event is
               read (seen in check-hw): the link is gone either way */
            if (f->hangup || is_link_gone(f->tx_result)) {
                f->hangup = 0;
                snprintf(f->t.err, sizeof f->t.err, "%s: the host went away during a write", f->t.name);
                return CM_T_HANGUP;
            }
            set_err(f, "%s: ep1 (bulk IN) write: %s", f->t.name, strerror((int)-f->tx_result));
            return CM_T_IO;
        }
        done += (size_t)f->tx_result;
    }
}

static void ffs_close(cm_transport *t)
{
    cm_ffs *f = ffs_of(t);
    if (f->aio) {
        /* cancels what is queued and waits for it: rx must not be written after this */
        (void)syscall(SYS_io_destroy, (aio_context_t)f->aio);
        f->aio = 0;
    }
    int *fds[] = {&f->efd, &f->ep_in, &f->ep_out, &f->ep0}; /* ep0 last: closing it unbinds the gadget */
    for (size_t i = 0; i < sizeof fds / sizeof fds[0]; i++) {
        if (*fds[i] >= 0)
            close(*fds[i]);
        *fds[i] = -1;
    }
    f->enabled = f->bound = f->hangup = 0;
    f->rx_busy = f->tx_busy = 0;
    f->rx_pos = f->rx_len = 0;
}

static int open_ep(cm_ffs *f, const char *dir, const char *name, int flags)
{
    char path[PATH_MAX];
    if ((size_t)snprintf(path, sizeof path, "%s/%s", dir, name) >= sizeof path) {
        set_err(f, "%s: path too long", f->t.name);
        return -1;
    }
    int fd = open(path, flags | O_CLOEXEC);
    if (fd < 0) {
        int e = errno;
        if (e == ENOENT && strcmp(name, "ep0") == 0)
            set_err(f, "%s: no %s: is functionfs mounted there? (cmz-usb-gadget.sh up %s)", f->t.name, path, dir);
        else
            set_err(f, "%s: open %s: %s", f->t.name, path, strerror(e));
    }
    return fd;
}

int cm_ffs_open(cm_ffs *f, const char *dir)
{
    f->t.read = ffs_read;
    f->t.write = ffs_write;
    f->t.close = ffs_close;
    f->t.err[0] = '\0';
    snprintf(f->t.name, sizeof f->t.name, "ffs %s", dir);
    f->ep0 = f->ep_in = f->ep_out = f->efd = -1;
    f->aio = 0;
    f->enabled = f->bound = f->hangup = 0;
    f->session = f->rx_session = f->tx_session = 0;
    f->rx_busy = f->tx_busy = f->tx_cancelled = 0;
    f->mps_in = CM_FFS_MIN_MPS;
    f->rx_errno = 0;
    f->tx_result = 0;
    f->rx_pos = f->rx_len = 0;

    f->ep0 = open_ep(f, dir, "ep0", O_RDWR);
    if (f->ep0 < 0)
        return -1;
    uint8_t blob[256];
    size_t len = build_descriptors(blob);
    if (write(f->ep0, blob, len) != (ssize_t)len) {
        int e = errno;
        set_err(f, "%s: writing the descriptors to ep0: %s%s", f->t.name, strerror(e),
                e == EBUSY || e == EINVAL ? " (another sender already uses this function? or remount it)" : "");
        goto fail;
    }
    len = build_strings(blob);
    if (write(f->ep0, blob, len) != (ssize_t)len) {
        set_err(f, "%s: writing the strings to ep0: %s", f->t.name, strerror(errno));
        goto fail;
    }
    /* non-blocking: a request on a not yet enabled endpoint fails with EAGAIN instead of sleeping in io_submit */
    f->ep_in = open_ep(f, dir, "ep1", O_RDWR | O_NONBLOCK);
    if (f->ep_in < 0)
        goto fail;
    f->ep_out = open_ep(f, dir, "ep2", O_RDWR | O_NONBLOCK);
    if (f->ep_out < 0)
        goto fail;
    f->efd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (f->efd < 0) {
        set_err(f, "%s: eventfd: %s", f->t.name, strerror(errno));
        goto fail;
    }
    aio_context_t ctx = 0;
    if (syscall(SYS_io_setup, 4L, &ctx) != 0) {
        set_err(f, "%s: io_setup: %s (is the kernel built with CONFIG_AIO?)", f->t.name, strerror(errno));
        goto fail;
    }
    f->aio = (uint64_t)ctx;
    return 0;

fail:
    ffs_close(&f->t);
    return -1;
}
