#!/usr/bin/env bash
# cmz-usb-gadget.sh - make the workstation a USB device for the terminal: a configfs gadget with
# one FunctionFS function (vendor class, one bulk IN and one bulk OUT endpoint, served by the
# sender through platform/cm_transport_ffs.c).  Run as root.
#
#   cmz-usb-gadget.sh up [--vid 1209] [--pid 0001] [--serial S] [--udc NAME] [--name curvemesh] MOUNTDIR
#       create the gadget and mount its functionfs at MOUNTDIR (not bound yet)
#   cmz-usb-gadget.sh bind [--udc NAME] [--name curvemesh] [--wait SECONDS]
#       attach the gadget to a USB device controller: the terminal then sees the device.  Start the
#       sender first: the kernel binds only once the sender has written its descriptors to
#       MOUNTDIR/ep0 (bind waits up to --wait seconds, default 10, for that)
#   cmz-usb-gadget.sh unbind [--name curvemesh]
#       detach from the controller (the terminal sees an unplug); the gadget stays set up
#   cmz-usb-gadget.sh down [--name curvemesh] [--force]
#       unbind, unmount, remove the gadget.  Stop the sender first (a FunctionFS daemon blocked in a
#       transfer while the UDC is unbound has deadlocked the 6.1 kernel on arm64); without --force,
#       down refuses while a process holds the functionfs files
#   cmz-usb-gadget.sh status [--name curvemesh]
#
# Defaults: VID:PID 1209:0001 (pid.codes test ids: replace with your own allocation before
# shipping), serial = this machine's hostname, the first controller in /sys/class/udc.
set -euo pipefail

prog=cmz-usb-gadget.sh
die() { echo "$prog: $*" >&2; exit 1; }
say() { echo "$prog: $*"; }

CONFIGFS=/sys/kernel/config
NAME=curvemesh VID=1209 PID=0001 SERIAL='' UDC='' WAIT=10 FORCE=0
STATE_DIR=/run/cmz-usb-gadget

usage() { sed -n '2,24p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }

cmd=${1:-}
[ -n "$cmd" ] || usage
shift
MOUNTDIR=
while [ $# -gt 0 ]; do
    case "$1" in
    --vid) VID=${2:?--vid needs a value}; shift 2 ;;
    --pid) PID=${2:?--pid needs a value}; shift 2 ;;
    --serial) SERIAL=${2:?--serial needs a value}; shift 2 ;;
    --udc) UDC=${2:?--udc needs a value}; shift 2 ;;
    --name) NAME=${2:?--name needs a value}; shift 2 ;;
    --wait) WAIT=${2:?--wait needs a value}; shift 2 ;;
    --force) FORCE=1; shift ;;
    -h | --help) usage ;;
    -*) die "unknown option $1 (see --help)" ;;
    *) [ -z "$MOUNTDIR" ] || die "one MOUNTDIR only"; MOUNTDIR=$1; shift ;;
    esac
done
case "$NAME" in *[!A-Za-z0-9_-]* | "") die "--name '$NAME': use letters, digits, '-' and '_'" ;; esac
G=$CONFIGFS/usb_gadget/$NAME
FUNC=ffs.$NAME

hex16() { # normalise a 1-4 digit hex id to 0xNNNN
    local v=${1#0x}
    [[ "$v" =~ ^[0-9A-Fa-f]{1,4}$ ]] || die "$2 '$1' is not 1-4 hex digits (e.g. 1209)"
    printf '0x%04x' "0x$v"
}

need_root() { [ "$(id -u)" -eq 0 ] || die "$cmd needs root (configfs and mount)"; }

# configfs mounted and the gadget part of it (libcomposite) present, with clear reasons when not
need_gadget_configfs() {
    if ! grep -qs " $CONFIGFS configfs " /proc/mounts; then
        mount -t configfs none "$CONFIGFS" 2>/dev/null ||
            die "configfs is not mounted at $CONFIGFS and mounting it failed (kernel without CONFIG_CONFIGFS_FS?)"
    fi
    if [ ! -d "$CONFIGFS/usb_gadget" ]; then
        modprobe libcomposite 2>/dev/null || true
        [ -d "$CONFIGFS/usb_gadget" ] ||
            die "no $CONFIGFS/usb_gadget: the kernel has no USB gadget configfs (module libcomposite, CONFIG_USB_CONFIGFS)"
    fi
}

# where functionfs instance NAME is mounted ("" if nowhere)
ffs_mountpoint() { awk -v dev="$NAME" '$1 == dev && $3 == "functionfs" { print $2; exit }' /proc/mounts; }

bound_udc() { [ -f "$G/UDC" ] && cat "$G/UDC" || true; }

pick_udc() { # the --udc given, the one saved by up, or the first controller
    local u=$UDC
    [ -n "$u" ] || u=$(cat "$STATE_DIR/$NAME.udc" 2>/dev/null || true)
    [ -n "$u" ] || u=$(ls /sys/class/udc 2>/dev/null | head -n 1)
    [ -n "$u" ] || die "no USB device controller in /sys/class/udc: this machine cannot act as a USB device on any port (for a test without hardware: modprobe dummy_hcd)"
    [ -e "/sys/class/udc/$u" ] || die "no USB device controller '$u' (have: $(ls /sys/class/udc | tr '\n' ' '))"
    echo "$u"
}

holders() { # pids with a file of MOUNTDIR open
    local mp=$1 p f
    for p in /proc/[0-9]*; do
        for f in "$p"/fd/*; do
            case "$(readlink "$f" 2>/dev/null)" in "$mp"/*) echo "${p#/proc/}"; break ;; esac
        done
    done 2>/dev/null | sort -u | tr '\n' ' '
}

do_up() {
    need_root
    [ -n "$MOUNTDIR" ] || die "up needs MOUNTDIR (where to mount functionfs, e.g. /dev/ffs-cmz)"
    local vid pid
    vid=$(hex16 "$VID" --vid); pid=$(hex16 "$PID" --pid)
    [ -n "$SERIAL" ] || SERIAL=$(hostname 2>/dev/null || echo curvemesh)
    need_gadget_configfs
    [ ! -e "$G" ] || die "gadget $G exists already ('$prog down --name $NAME' first)"
    if [ -n "$UDC" ]; then pick_udc > /dev/null
    elif [ -z "$(ls /sys/class/udc 2>/dev/null)" ]; then
        say "warning: no USB device controller in /sys/class/udc yet: 'bind' will need one"
    fi
    mkdir "$G"
    echo "$vid" > "$G/idVendor"
    echo "$pid" > "$G/idProduct"
    echo 0x0200 > "$G/bcdUSB"
    echo 0x0100 > "$G/bcdDevice"
    mkdir "$G/strings/0x409"
    echo "curvemesh" > "$G/strings/0x409/manufacturer"
    echo "curvemesh workstation link" > "$G/strings/0x409/product"
    echo "$SERIAL" > "$G/strings/0x409/serialnumber"
    mkdir -p "$G/configs/c.1/strings/0x409"
    echo "bulk link" > "$G/configs/c.1/strings/0x409/configuration"
    echo 250 > "$G/configs/c.1/MaxPower"
    if ! mkdir "$G/functions/$FUNC" 2>/dev/null; then
        rmdir "$G/configs/c.1/strings/0x409" "$G/configs/c.1" "$G/strings/0x409" "$G" 2>/dev/null || true
        die "cannot create function $FUNC: the kernel has no FunctionFS (module usb_f_fs, CONFIG_USB_CONFIGFS_F_FS)"
    fi
    ln -s "$G/functions/$FUNC" "$G/configs/c.1/"
    mkdir -p "$MOUNTDIR"
    mount -t functionfs "$NAME" "$MOUNTDIR" || die "mount -t functionfs $NAME $MOUNTDIR failed"
    mkdir -p "$STATE_DIR"
    if [ -n "$UDC" ]; then echo "$UDC" > "$STATE_DIR/$NAME.udc"; else rm -f "$STATE_DIR/$NAME.udc"; fi
    say "gadget $NAME ($vid:$pid, serial $SERIAL) ready, functionfs at $MOUNTDIR"
    say "next: start the sender on $MOUNTDIR, then '$prog bind${UDC:+ --udc $UDC}'"
}

do_bind() {
    need_root
    [ -d "$G" ] || die "no gadget $NAME ('$prog up MOUNTDIR' first)"
    local cur mp udc i
    cur=$(bound_udc)
    [ -z "$cur" ] || { say "already bound to $cur"; return 0; }
    udc=$(pick_udc)
    mp=$(ffs_mountpoint)
    [ -n "$mp" ] || die "functionfs '$NAME' is not mounted ('$prog up MOUNTDIR' first)"
    # the sender's descriptors make the endpoint files appear
    for ((i = 0; i < WAIT * 10; i++)); do [ -e "$mp/ep1" ] && break; sleep 0.1; done
    [ -e "$mp/ep1" ] || die "nothing has written descriptors to $mp/ep0 within ${WAIT}s: start the sender on $mp first"
    if ! echo "$udc" > "$G/UDC" 2>/dev/null; then
        die "binding to $udc failed: is the controller used by another gadget ($(grep -l "^$udc\$" "$CONFIGFS"/usb_gadget/*/UDC 2>/dev/null | tr '\n' ' '))? did the sender exit?"
    fi
    say "bound to $udc"
}

do_unbind() {
    need_root
    [ -d "$G" ] || die "no gadget $NAME"
    [ -n "$(bound_udc)" ] || { say "not bound"; return 0; }
    # ENODEV: the sender closed ep0, which already unbound the gadget
    echo "" > "$G/UDC" 2>/dev/null || true
    say "unbound"
}

do_down() {
    need_root
    local mp pids
    mp=$(ffs_mountpoint)
    if [ -n "$mp" ]; then
        pids=$(holders "$mp")
        if [ -n "$pids" ] && [ "$FORCE" != 1 ]; then
            die "processes $pids still have $mp open: stop the sender first (or --force)"
        fi
    fi
    if [ -d "$G" ] && [ -n "$(bound_udc)" ]; then echo "" > "$G/UDC" 2>/dev/null || true; fi
    if [ -n "$mp" ]; then
        # a process killed a moment ago may still hold the mount while the kernel tears it down:
        # try for a few seconds; with --force, detach it lazily in the end (it goes when they do)
        local i
        for ((i = 0; i < 50; i++)); do umount "$mp" 2> /dev/null && break; sleep 0.1; done
        if grep -q " $mp functionfs " /proc/mounts; then
            if [ "$FORCE" = 1 ]; then
                umount -l "$mp" || die "umount -l $mp failed"
                say "$mp was still in use (pids $(holders "$mp")): detached lazily"
            else
                die "umount $mp failed (still in use by pids $(holders "$mp"))"
            fi
        fi
    fi
    if [ -d "$G" ]; then
        # configfs: links out of configs, then configs' strings, configs, functions, strings, gadget
        rm -f "$G/configs/c.1/$FUNC"
        rmdir "$G/configs/c.1/strings/0x409" 2>/dev/null || true
        rmdir "$G/configs/c.1" 2>/dev/null || true
        rmdir "$G/functions/$FUNC" 2>/dev/null || true
        rmdir "$G/strings/0x409" 2>/dev/null || true
        rmdir "$G" || die "could not remove $G (something left inside: $(ls "$G" 2>/dev/null | tr '\n' ' '))"
    fi
    rm -f "$STATE_DIR/$NAME.udc"
    say "gadget $NAME removed"
}

do_status() {
    if [ ! -d "$G" ]; then echo "gadget $NAME: not set up"; return 0; fi
    local udc mp
    udc=$(bound_udc); mp=$(ffs_mountpoint)
    echo "gadget $NAME: $(cat "$G/idVendor"):$(cat "$G/idProduct") serial $(cat "$G/strings/0x409/serialnumber")"
    echo "  functionfs: ${mp:-not mounted}$([ -n "$mp" ] && [ -e "$mp/ep1" ] && echo ' (descriptors written)')"
    echo "  UDC: ${udc:-not bound}$([ -n "$udc" ] && echo " (state $(cat "/sys/class/udc/$udc/state" 2>/dev/null), speed $(cat "/sys/class/udc/$udc/current_speed" 2>/dev/null))")"
}

case "$cmd" in
up) do_up ;;
bind) do_bind ;;
unbind) do_unbind ;;
down) do_down ;;
status) do_status ;;
*) usage ;;
esac
