/*
 * cm_transport_ffs.h - the workstation's end of the USB cable: a Linux USB
 * gadget function over FunctionFS (cm_transport_usb.h is the terminal's end).
 *
 * The function is one vendor-class (0xff) interface, string "curvemesh
 * link", with a bulk IN endpoint (ep1, to the host) and a bulk OUT endpoint
 * (ep2, from the host), full and high speed (64/512-byte packets; super
 * speed descriptors too, 1024-byte packets).  The gadget around it (VID:PID,
 * serial, configuration) is made with configfs by
 * host_tools/scripts/cmz-usb-gadget.sh:
 *
 *   cmz-usb-gadget.sh up /dev/ffs-cmz    # gadget + functionfs mount
 *   (the sender calls cm_ffs_open("/dev/ffs-cmz"), which writes the descriptors)
 *   cmz-usb-gadget.sh bind               # attach to the UDC: the host enumerates us
 *
 * Transfers use kernel AIO on the endpoint files so that every call keeps its
 * deadline (a plain read() on a FunctionFS endpoint cannot time out) while
 * the ep0 events (BIND, ENABLE, DISABLE, UNBIND, SETUP) are served.  A read
 * request left queued at a deadline stays queued for the next call: no byte
 * is lost.
 *
 * CM_T_HANGUP means the host went away or reset the link (DISABLE, UNBIND,
 * or a new configuration).  Unlike the other back ends the handle stays
 * usable: the next calls wait for the host to configure the function again.
 * Closing it releases ep0, and the kernel then unbinds the gadget from the
 * UDC, so after a close + open run `cmz-usb-gadget.sh bind` again.
 */
#ifndef CM_TRANSPORT_FFS_H
#define CM_TRANSPORT_FFS_H

#include <stddef.h>
#include <stdint.h>

#include "cm_transport.h"

/* one read request asks for this much: a multiple of every bulk packet size (64, 512, 1024) */
#define CM_FFS_BUF 16384u

typedef struct cm_ffs {
    cm_transport t;          /* first member: a cm_ffs * is a cm_transport * */
    int ep0, ep_in, ep_out;  /* ep0 (control, events), ep1 (bulk IN), ep2 (bulk OUT); -1 when closed */
    int efd;                 /* eventfd signalled by AIO completions */
    uint64_t aio;            /* aio_context_t, 0 when none */
    int enabled;             /* the host configured the function (ENABLE seen, no DISABLE since) */
    int bound;               /* the gadget is bound to a UDC (BIND seen, no UNBIND since) */
    int hangup;              /* a session ended: the next read or write says CM_T_HANGUP once */
    unsigned session;        /* counts ENABLEs: completions of older sessions are dropped */
    int rx_busy, tx_busy;    /* an AIO request is queued on ep_out / ep_in */
    int tx_cancelled;        /* the queued write was cancelled by us (its ECONNRESET is no hangup) */
    uint16_t mps_in;         /* wMaxPacketSize of ep1 at the speed the host enabled us with */
    unsigned rx_session, tx_session;
    int rx_errno;            /* a read request failed with this (not a hangup) */
    int64_t tx_result;       /* result of the last completed write request */
    size_t rx_pos, rx_len;   /* rx[rx_pos..rx_len) is received but not yet handed out */
    uint64_t iocb_rx[8], iocb_tx[8]; /* struct iocb storage: the kernel names a request by its address */
    uint8_t rx[CM_FFS_BUF];
} cm_ffs;

/**
 * Write the function's descriptors and strings to DIR/ep0 (before the UDC is
 * bound: the kernel refuses to bind a FunctionFS function that has none),
 * then open ep1 and ep2.
 * @param ffs_mount_dir  where functionfs is mounted (cmz-usb-gadget.sh up DIR)
 * @return 0, or -1 with f->t.err naming the directory, the cause and what to do
 */
int cm_ffs_open(cm_ffs *f, const char *ffs_mount_dir);

#endif /* CM_TRANSPORT_FFS_H */
