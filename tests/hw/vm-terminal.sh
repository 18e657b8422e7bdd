#!/usr/bin/env bash
# vm-terminal.sh - runs INSIDE the test VM (tests/hw/run-hw-tests.sh boots it): the whole product
# over real kernel drivers.  The workstation side is `cmz send --gadget` on a FunctionFS gadget
# (dummy_hcd + libcomposite, set up by cmz-usb-gadget.sh); the terminal side is cmz-terminal --usb
# (libusb) with its busy/ready/error lines and request button on a gpio-sim chip.
#   1. the model arrives over USB byte-identical and is decoded into model.glb;
#   2. the busy line was high while receiving and decoding, ready pulsed after, error stayed low
#      (read from gpio-sim's sysfs, the "hardware" side of the lines);
#   3. pressing the request button (gpio-sim pull-up) makes the terminal ask, and `cmz send --stay`
#      sends the model again: a second decode;
#   4. SIGTERM stops the terminal with status 0 and its lines go inactive.
# Env: HW_CMZ, HW_TERMINAL (default: this checkout's builds), HW_MODELS (the .cmz files, encoded
# on the host).  Prints TAP lines.
set -u
triplet=$(gcc -dumpmachine)
cmz=${HW_CMZ:-build/$triplet-host/cmz}
term=${HW_TERMINAL:-build/$triplet-terminal/cmz-terminal}
gadget=host_tools/scripts/cmz-usb-gadget.sh
label=curvemesh-term
mnt=/tmp/ffs-cmz-term
T=$(mktemp -d /tmp/vm-term.XXXXXX)
n=0 failed=0
pass() { n=$((n + 1)); echo "ok $n - $1"; }
fail() { n=$((n + 1)); failed=$((failed + 1)); echo "not ok $n - $1${2:+: $2}"; }
bail() { fail "$1" "$2"; show_logs; cleanup; echo "# vm-terminal: cannot go on"; exit 1; }
pids=()
cleanup() {
    # the sender must be gone before the gadget is unbound (hw-testing NOTES pitfall 6)
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
    local p i
    for p in "${pids[@]}"; do
        for ((i = 0; i < 50; i++)); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$p" 2>/dev/null
        wait "$p" 2>/dev/null
    done
    timeout 30 "$gadget" down --force >> "$T/gadget.log" 2>&1
}
show_logs() {
    for f in term.log send.log gadget.log; do
        [ -s "$T/$f" ] && sed "s/^/# $f: /" "$T/$f" | tail -n 8
    done
}
wait_for() { local i; for ((i = 0; i < $1 * 10; i++)); do eval "$2" && return 0; sleep 0.1; done; return 1; }

[ -x "$cmz" ] && [ -x "$term" ] || bail "cmz and cmz-terminal are built" "missing $cmz or $term"
"$term" --help | grep -q -- '--usb' || bail "cmz-terminal has USB" "built without libusb"

# ---- the terminal's lines: a gpio-sim chip ----
modprobe gpio-sim || bail "gpio-sim loads" "modprobe gpio-sim failed"
G=/sys/kernel/config/gpio-sim/cm-term
mkdir "$G" "$G/bank0" && echo 4 > "$G/bank0/num_lines" && echo "$label" > "$G/bank0/label" ||
    bail "gpio-sim chip" "cannot create $G"
names=(busy ready error request)
for i in 0 1 2 3; do mkdir "$G/bank0/line$i" && echo "${names[$i]}" > "$G/bank0/line$i/name"; done
echo 1 > "$G/live" || bail "gpio-sim chip goes live" "write to $G/live failed"
chip=$(cat "$G/bank0/chip_name")
sim=/sys/devices/platform/$(cat "$G/dev_name")/$chip
level() { local v; read -r v < "$sim/sim_gpio$1/value"; echo "$v"; }
# record every change of busy/ready/error as "n busy ready error" (builtins only: a fork costs
# ~50 ms in this VM, longer than a decode)
( last="" k=0; while :; do read -r a < "$sim/sim_gpio0/value"; read -r b < "$sim/sim_gpio1/value"
    read -r c < "$sim/sim_gpio2/value"; v="$a$b$c"; k=$((k + 1))
    if [ "$v" != "$last" ]; then echo "$k $v"; last=$v; fi; done ) > "$T/lines" 2>/dev/null &
pids+=($!)

# ---- the workstation: a USB gadget, cmz send serving it ----
modprobe dummy_hcd && modprobe libcomposite || bail "dummy_hcd and libcomposite load" "modprobe failed"
"$gadget" up --serial CMZ-TERM-1 "$mnt" > "$T/gadget.log" 2>&1 || bail "cmz-usb-gadget.sh up" "$(tail -n 2 "$T/gadget.log")"
# the models are encoded on the host (HW_MODELS): the encoder's verification needs more memory
# than the VM has
models=${HW_MODELS:-build/hw-models}
for m in as1_pe_203 geo_example; do
    cp "$models/$m.cmz" "$T/$m.cmz" 2>/dev/null || bail "model $m" "no $models/$m.cmz (make check-hw encodes it)"
done
"$cmz" send "$T/as1_pe_203.cmz" --gadget "$mnt" --stay --timeout 60 > "$T/send.log" 2>&1 &
send_pid=$!
pids+=($send_pid)
"$gadget" bind --wait 10 >> "$T/gadget.log" 2>&1 || bail "gadget binds once cmz send wrote its descriptors" "$(tail -n 2 "$T/gadget.log")"
pass "cmz send --gadget serves a FunctionFS gadget, bound to dummy_udc"

# ---- the terminal ----
mkdir -p "$T/out"
"$term" --usb 1209:0001 --out "$T/out" --name vm-terminal --gpio-busy "$label:busy" --gpio-ready "$label:ready" \
    --gpio-error "$label:error" --gpio-request "$label:request" --ready-pulse-ms 1000 2> "$T/term.log" &
term_pid=$!
pids+=($term_pid)
if wait_for 30 '[ -s "$T/out/model.glb" ]' && wait_for 5 'grep -q "event=decoded" "$T/term.log"'; then
    if cmp -s "$T/out/model.cmz" "$T/as1_pe_203.cmz"; then
        pass "over USB (FunctionFS gadget -> libusb): model.cmz identical, decoded into model.glb ($(stat -L -c %s "$T/out/model.glb") bytes)"
    else
        fail "over USB: model.cmz identical" "it differs"
    fi
else
    fail "over USB: the model arrives and is decoded" "terminal: $(tail -n 5 "$T/term.log" | tr '\n' '|') sender: $(tail -n 5 "$T/send.log" | tr '\n' '|')"; bail "cannot go on" "no model"
fi
sleep 1.2 # the ready pulse (1 s) ends
grep -q ' 1[01]0$' "$T/lines" && pass "the busy line was high while receiving/decoding (gpio-sim sysfs)" ||
    fail "busy line seen high" "$(tr '\n' ' ' < "$T/lines")"
grep -q ' 010$' "$T/lines" && pass "the ready line pulsed after the model was decoded" ||
    fail "ready pulse seen" "$(tr '\n' ' ' < "$T/lines")"
! grep -q ' ..1$' "$T/lines" && pass "the error line stayed low" || fail "error line stayed low" "$(tr '\n' ' ' < "$T/lines")"

# ---- the request button asks for the model again ----
echo pull-up > "$sim/sim_gpio3/pull"
if wait_for 30 '[ "$(grep -c "event=decoded" "$T/term.log")" -ge 2 ]'; then
    grep -q 'event=request' "$T/term.log" && grep -q 'asks for the model again' "$T/send.log" &&
        pass "request button (gpio-sim pull-up): the terminal asked, cmz send --stay sent again, decoded again" ||
        fail "request button" "log lines missing: $(grep -c request "$T/term.log") $(tr '\n' '|' < "$T/send.log")"
else
    fail "request button: a second transfer" "terminal: $(tail -n 3 "$T/term.log" | tr '\n' '|')"
fi
echo pull-down > "$sim/sim_gpio3/pull"

# ---- clean stop ----
kill -TERM "$term_pid"
wait "$term_pid"
rc=$?
sleep 0.2
[ $rc -eq 0 ] && [ "$(level 0)$(level 1)$(level 2)" = 000 ] && pass "SIGTERM: exit status 0, every line inactive" ||
    fail "SIGTERM" "status $rc, lines $(level 0)$(level 1)$(level 2)"
kill "$send_pid" 2>/dev/null
wait "$send_pid" 2>/dev/null
grep '^cmz-terminal: ' "$T/term.log" | sed 's/^/# /' | head -n 12
cleanup
# what this script set up is gone: a gadget left behind holds the only UDC and fails the next script
[ ! -e /sys/kernel/config/usb_gadget/curvemesh ] && pass "the gadget is taken down (cmz-usb-gadget.sh down --force)" ||
    fail "the gadget is taken down" "$(tail -n 2 "$T/gadget.log" | tr '\n' ' ')"
echo "$((n - failed)) passed, $failed failed"
[ $failed -eq 0 ]
