#!/usr/bin/env bash
# vm-usb-transport.sh [USB_ECHO] - the USB back ends of cm_transport against real kernel drivers.
# Runs INSIDE a throw-away VM as root (it loads modules and creates a gadget), from the top of the
# source tree:   run-in-vm.sh -t 300 -- bash tests/hw/vm-usb-transport.sh
#
# dummy_hcd gives the VM a USB host controller wired to a device controller.  The workstation's
# side (cmz-usb-gadget.sh + cm_ffs in `usb_echo --gadget`) and the terminal's side (cm_usb in
# `usb_echo --host`) talk through it.  Checks: enumeration and the endpoint layout, echo of edge
# sizes and throughput, serial matching, the permission message, write deadlines under back-pressure on both sides, the host seeing CM_T_HANGUP within its deadline when the
# gadget process dies mid-transfer and when the UDC is unbound mid-transfer, re-opening after
# each, the aarch64 build under qemu-aarch64 when present, tearing the gadget down, and the same
# echo at super speed (dummy_hcd is_super_speed=1).
# Prints TAP lines and "N passed, N failed"; exit 0 iff nothing failed.
set -u
cd "$(dirname "$0")/../.." || exit 1
ECHO=${1:-build/$(cc -dumpmachine)-host/tests/platform/usb_echo}
ECHO_ARM64=${USB_ECHO_ARM64:-build/aarch64-linux-gnu-host/tests/platform/usb_echo}
GADGET=host_tools/scripts/cmz-usb-gadget.sh
MNT=/tmp/ffs-curvemesh
SERIAL=CMZ-VM-0001
DEV=1209:0001
G=/sys/kernel/config/usb_gadget/curvemesh
T=$(mktemp -d /tmp/vm-usb.XXXXXX)

n=0 failed=0
ok() { n=$((n + 1)); echo "ok $n - $*"; }
not_ok() { n=$((n + 1)); failed=$((failed + 1)); echo "not ok $n - $*"; }
check() { local what=$1; shift; if "$@" > "$T/check.log" 2>&1; then ok "$what"; else not_ok "$what: $(tail -n 3 "$T/check.log" | tr '\n' ' ')"; fi; }
finish() { echo "$((n - failed)) passed, $failed failed"; [ "$failed" -eq 0 ]; exit $?; }
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }'; }
wait_for() { local i; for ((i = 0; i < $1 * 10; i++)); do eval "$2" && return 0; sleep 0.1; done; return 1; }

# run usb_echo --host and re-number its TAP lines into ours
host_run() { # label args...
    local label=$1 line rc
    shift
    "$@" > "$T/host.out" 2>&1
    rc=$?
    while IFS= read -r line; do
        case "$line" in
        "ok "*) ok "$label: ${line#ok * - }" ;;
        "not ok "*) not_ok "$label: ${line#not ok * - }" ;;
        "#"*) echo "$line" ;;
        esac
    done < "$T/host.out"
    if [ "$rc" -ne 0 ] && ! grep -q '^not ok' "$T/host.out"; then
        not_ok "$label: exit $rc: $(tail -n 3 "$T/host.out" | tr '\n' ' ')"
    fi
    return "$rc"
}

start_gadget() {
    "$ECHO" --gadget "$MNT" > "$T/gadget.out" 2>> "$T/gadget.err" &
    GPID=$!
    wait_for 10 "grep -q READY '$T/gadget.out'"
}

[ -x "$ECHO" ] || { not_ok "usb_echo built ($ECHO missing: make usb-tools)"; finish; }
[ "$(id -u)" -eq 0 ] || { not_ok "running as root (this script belongs in a VM)"; finish; }

for m in dummy_hcd libcomposite usb_f_fs; do
    check "modprobe $m" modprobe "$m"
done
check "a UDC exists ($(ls /sys/class/udc 2>/dev/null | tr '\n' ' '))" test -n "$(ls /sys/class/udc 2>/dev/null)"

# a gadget left by an earlier script (its own test says so) would hold the only UDC: not this one's fault
if [ -e "$G" ]; then
    echo "# a gadget was left set up before this script: taking it down first"
    timeout 30 "$GADGET" down --force 2>&1 | sed 's/^/# /'
fi
check "cmz-usb-gadget.sh up" "$GADGET" up --serial "$SERIAL" "$MNT"
if ! start_gadget; then
    not_ok "usb_echo --gadget wrote its descriptors: $(cat "$T/gadget.err")"
    finish
fi
ok "usb_echo --gadget wrote its descriptors ($(cat "$T/gadget.out"))"
t0=$(now)
check "cmz-usb-gadget.sh bind" "$GADGET" bind
if ! command -v lsusb > /dev/null; then
    echo "# SKIP lsusb checks: usbutils not installed (usb_echo --host waits for the device itself)"
elif wait_for 10 "lsusb -d $DEV > /dev/null 2>&1"; then
    ok "enumerated in $(elapsed "$t0") s: $(lsusb -d $DEV)"
else
    not_ok "gadget did not enumerate"
fi
"$GADGET" status | sed 's/^/# /'
lsusb -v -d $DEV 2> /dev/null | grep -E 'iSerial|bInterfaceClass|iInterface|bEndpointAddress|Transfer Type|wMaxPacketSize' | sed 's/^ */# /'

# ---- echo: edge sizes and throughput ----
host_run "echo 16 KiB" "$ECHO" --host "$DEV:$SERIAL" 300 16384
grep '^# interface' "$T/host.out" > "$T/layout" || true
host_run "echo 512 B (one packet)" "$ECHO" --host "$DEV" 1000 512
host_run "echo 1 B" "$ECHO" --host "$DEV" 300 1
host_run "echo 64 KiB" "$ECHO" --host "$DEV" 100 65536
host_run "back-pressure" "$ECHO" --host "$DEV" 20 16384 --stall
if "$ECHO" --host "$DEV:NO-SUCH-SERIAL" 1 1 --wait 300 > "$T/wrong.out" 2>&1; then
    not_ok "a wrong serial is refused"
else
    grep -q 'not within' "$T/wrong.out" && ok "a wrong serial is refused (no such device)" ||
        not_ok "a wrong serial is refused: $(tail -n 2 "$T/wrong.out" | tr '\n' ' ')"
fi

# an unprivileged user: the open fails and the message points at a udev rule
if command -v setpriv > /dev/null; then
    if setpriv --reuid=65534 --regid=65534 --clear-groups "$ECHO" --host "$DEV" 1 1 --wait 2000 > "$T/perm.out" 2>&1; then
        not_ok "an unprivileged user cannot open the device (it could: mode $(stat -c %a /dev/bus/usb/*/* | tr '\n' ' '))"
    elif grep -q 'udev rule' "$T/perm.out"; then
        ok "an unprivileged user is told what to do: $(grep -o 'usb 1209.*' "$T/perm.out" | head -n 1)"
    else
        not_ok "an unprivileged user is told what to do: $(tail -n 2 "$T/perm.out" | tr '\n' ' ')"
    fi
else
    echo "# SKIP permission message: no setpriv"
fi

# ---- the aarch64 build of the terminal's side, under qemu-user (USBDEVFS ioctls are translated) ----
if [ -x "$ECHO_ARM64" ] && command -v qemu-aarch64 > /dev/null; then
    host_run "aarch64 under qemu-aarch64" qemu-aarch64 "$ECHO_ARM64" --host "$DEV" 100 16384
else
    echo "# SKIP aarch64 build: $ECHO_ARM64 or qemu-aarch64 missing"
fi

# ---- unplug 1: the gadget process dies mid-transfer (closing ep0 unbinds the gadget) ----
"$ECHO" --host "$DEV" 1000000 16384 --deadline 2000 --expect-hangup > "$T/cut1.out" 2>&1 &
hpid=$!
sleep 1.5
t0=$(now)
kill -KILL "$GPID"
wait "$GPID" 2> /dev/null
if wait_for 10 "! kill -0 $hpid 2> /dev/null"; then
    wait "$hpid"
    rc=$?
    dt=$(elapsed "$t0")
    line=$(grep -E '^(not )?ok .*link cut' "$T/cut1.out" | sed 's/^\(not \)\{0,1\}ok [0-9]* - //')
    if [ "$rc" -eq 0 ]; then ok "gadget killed: host returned in $dt s: $line"; else not_ok "gadget killed: rc $rc: $line $(tail -n 2 "$T/cut1.out" | tr '\n' ' ')"; fi
else
    kill -KILL "$hpid" 2> /dev/null
    not_ok "gadget killed: the host side hung (> 10 s)"
fi
if start_gadget && "$GADGET" bind > /dev/null; then
    host_run "after the gadget restarted" "$ECHO" --host "$DEV" 50 16384 --wait 10000
else
    not_ok "gadget restarted and bound again: $(tail -n 3 "$T/gadget.err" | tr '\n' ' ')"
fi

# ---- unplug 2: the UDC is unbound mid-transfer; the gadget process stays and serves the rebind ----
"$ECHO" --host "$DEV" 1000000 16384 --deadline 2000 --expect-hangup > "$T/cut2.out" 2>&1 &
hpid=$!
sleep 1.5
t0=$(now)
(echo "" > "$G/UDC") 2> "$T/unbind.err" &
upid=$!
if ! wait_for 20 "! kill -0 $upid 2> /dev/null"; then
    not_ok "unbinding the UDC mid-transfer returned (it hangs in the kernel)"
    finish
fi
ok "unbinding the UDC mid-transfer returned in $(elapsed "$t0") s"
if wait_for 10 "! kill -0 $hpid 2> /dev/null"; then
    wait "$hpid"
    rc=$?
    dt=$(elapsed "$t0")
    line=$(grep -E '^(not )?ok .*link cut' "$T/cut2.out" | sed 's/^\(not \)\{0,1\}ok [0-9]* - //')
    if [ "$rc" -eq 0 ]; then ok "UDC unbound: host returned in $dt s: $line"; else not_ok "UDC unbound: rc $rc: $line"; fi
else
    kill -KILL "$hpid" 2> /dev/null
    not_ok "UDC unbound: the host side hung (> 10 s)"
fi
if kill -0 "$GPID" 2> /dev/null; then ok "the gadget process survived the unbind"; else not_ok "the gadget process died on unbind: $(tail -n 3 "$T/gadget.err" | tr '\n' ' ')"; fi
check "cmz-usb-gadget.sh bind again (same gadget process)" "$GADGET" bind
host_run "after rebinding" "$ECHO" --host "$DEV" 50 16384 --wait 10000
grep -c 'went away' "$T/gadget.err" | sed 's/^/# gadget side saw CM_T_HANGUP (host went away) this many times: /'

# ---- teardown: stop the sender first, then down ----
check "cmz-usb-gadget.sh down refuses while the sender runs" bash -c "! '$GADGET' down"
kill -TERM "$GPID"
wait "$GPID"
grc=$?
[ "$grc" -eq 0 ] && ok "usb_echo --gadget exits 0 on SIGTERM ($(tail -n 1 "$T/gadget.err"))" || not_ok "usb_echo --gadget exit $grc: $(tail -n 3 "$T/gadget.err" | tr '\n' ' ')"
check "cmz-usb-gadget.sh down" "$GADGET" down
check "the gadget is gone from configfs" test ! -e "$G"
check "functionfs is unmounted" bash -c "! grep -q ' $MNT functionfs ' /proc/mounts"
sort "$T/gadget.err" | uniq -c | sed 's/^/# gadget stderr: /'
cat "$T/layout" 2>/dev/null

# ---- super speed (1024-byte packets: the super speed descriptors and the ZLP rule at that size) ----
if rmmod dummy_hcd 2> /dev/null && modprobe dummy_hcd is_super_speed=1; then
    : > "$T/gadget.err"
    if "$GADGET" up --serial "$SERIAL" "$MNT" > /dev/null && start_gadget && "$GADGET" bind > /dev/null; then
        host_run "super speed" "$ECHO" --host "$DEV" 100 16384 --wait 10000
        grep -q 'wMaxPacketSize 1024' "$T/host.out" && ok "super speed: 1024-byte packets ($(grep '^# interface' "$T/host.out"))" ||
            not_ok "super speed: 1024-byte packets: $(grep '^# interface' "$T/host.out")"
    else
        not_ok "super speed gadget up: $(tail -n 3 "$T/gadget.err" | tr '\n' ' ')"
    fi
    kill -TERM "$GPID" 2> /dev/null
    wait "$GPID" 2> /dev/null
    check "cmz-usb-gadget.sh down (super speed)" "$GADGET" down
else
    echo "# SKIP super speed: dummy_hcd could not be reloaded with is_super_speed=1"
fi
finish
