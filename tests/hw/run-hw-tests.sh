#!/usr/bin/env bash
# run-hw-tests.sh - `make check-hw`: the terminal's device back ends against
# real kernel drivers (gpio-sim, dummy_hcd + USB gadgets) in a test VM.
#
# Makes the VM (tests/hw/make-vm.sh, fast once made), then boots it ONCE and
# runs every tests/hw/vm-*.sh in it in turn (tests/hw/guest/run-scripts.sh),
# and prints their TAP lines, numbered, ending with "N passed, N failed".
# Where the VM cannot run (no qemu-system-x86_64 and no way to install it,
# not an x86-64 machine, a qemu without virtio-9p) it prints "# SKIP: why"
# and "ok 1 - hw tests skipped" and exits 0.  A VM that hangs is killed by
# the timeout and counted as a failure.
#
# A vm-*.sh script runs as root in the guest, in the checkout's root directory (read-only,
# with a tmpfs over it), with every HW_* variable of this environment; it prints TAP lines
# ("ok N - what", "not ok N - what: why", "ok N # SKIP why"), and exits 0 iff all passed.
#
# Env: HW_GPIO_PROBE (gpio_probe to test; mk/hw.mk sets it), HW_GPIO_PROBE_NONE (a gpio_probe
#      linked with cm_gpio_none.c, checked on the host), HW_SCRIPT_TIMEOUT (s per script,
#      default 120), HW_VM_TIMEOUT (s for the whole boot, default 60 + 120 per script),
#      HW_SCRIPTS (the scripts to run, default tests/hw/vm-*.sh), HW_VM_MEM (MiB, default 3072:
#      `cmz` maps 1.5 GiB of static decoder buffers), VM_BUILD (see make-vm.sh).
set -u
HERE=$(cd "$(dirname "$0")" && pwd)
REPO=$(cd "$HERE/../.." && pwd)
cd "$REPO" || exit 1
t_start=$(date +%s.%N)
seconds_since() { awk -v s="$1" -v e="$(date +%s.%N)" 'BEGIN { printf "%.1f", e - s }'; }

skip() {
    echo "# SKIP: $*"
    echo "ok 1 - hw tests skipped"
    exit 0
}
n=0 failed=0
pass() { n=$((n + 1)); echo "ok $n - $1"; }
fail() { n=$((n + 1)); failed=$((failed + 1)); echo "not ok $n - $1${2:+: $2}"; }
finish() {
    echo "# check-hw took $(seconds_since "$t_start") s"
    echo "$((n - failed)) passed, $failed failed"
    [ "$failed" = 0 ]
    exit
}

# ---- can a VM run here at all? ----
[ "$(uname -m)" = x86_64 ] || skip "the test VM is x86-64 (Debian's amd64 kernel under qemu), this is $(uname -m)"
if ! command -v qemu-system-x86_64 >/dev/null; then
    [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null ||
        skip "qemu-system-x86_64 is not installed and this user cannot install it (apt-get install qemu-system-x86)"
fi
[ -c /dev/null ] && [ -r /dev/urandom ] || skip "/dev/null or /dev/urandom is missing (qemu needs them)"

# ---- host-side checks that need no VM ----
if [ -n "${HW_GPIO_PROBE_NONE:-}" ]; then
    out=$("$HW_GPIO_PROBE_NONE" --busy gpiochip0:busy quit 2>&1)
    rc=$?
    want="gpio_probe: gpio busy=gpiochip0:busy: this build has no GPIO support (libgpiod 1.6 was not found at build time)"
    if [ $rc = 1 ] && [ "$out" = "$want" ]; then pass "host: a build without libgpiod refuses a configured line, saying why"
    else fail "host: a build without libgpiod refuses a configured line" "status $rc, '$out'"; fi
    out=$("$HW_GPIO_PROBE_NONE" set busy 1 quit 2>&1)
    if [ $? = 0 ] && [ "$out" = "$(printf 'set busy 1\nbye')" ]; then pass "host: a build without libgpiod runs when no line is configured"
    else fail "host: a build without libgpiod runs when no line is configured" "'$out'"; fi
fi

# ---- the VM ----
t0=$(date +%s.%N)
make_log=$(mktemp)
"$HERE/make-vm.sh" > "$make_log" 2>&1
rc=$?
sed 's/^/# /' "$make_log" | tail -n 30
rm -f "$make_log"
case $rc in
0) ;;
3) skip "qemu-system-x86_64 is not installed and apt-get could not install qemu-system-x86" ;;
*) fail "make-vm.sh prepares the test VM" "exit status $rc (output above)"; finish ;;
esac
echo "# make-vm.sh took $(seconds_since "$t0") s"
qemu-system-x86_64 -device help 2>/dev/null | grep -q virtio-9p ||
    skip "this qemu-system-x86_64 has no virtio-9p device (the VM's root file system comes over 9p)"

if [ -n "${HW_SCRIPTS:-}" ]; then read -ra scripts <<< "$HW_SCRIPTS"; else scripts=(tests/hw/vm-*.sh); fi
[ -e "${scripts[0]}" ] || { fail "tests/hw/vm-*.sh scripts exist" "none found"; finish; }
export HW_SCRIPT_TIMEOUT=${HW_SCRIPT_TIMEOUT:-120}
vm_timeout=${HW_VM_TIMEOUT:-$((60 + HW_SCRIPT_TIMEOUT * ${#scripts[@]}))}
echo "# booting the test VM for ${scripts[*]} (timeout $vm_timeout s)"

t0=$(date +%s.%N)
# the guest's console ends lines in \r\n; the TAP lines are renumbered into this run's count
while IFS= read -r line; do
    line=${line%$'\r'}
    if [[ $line =~ ^(not\ )?ok\ [0-9]+\ ?(.*)$ ]]; then
        n=$((n + 1))
        [ -z "${BASH_REMATCH[1]}" ] || failed=$((failed + 1))
        echo "${BASH_REMATCH[1]}ok $n ${BASH_REMATCH[2]}"
        continue
    fi
    case $line in
    "HW-VM-STATUS "*) vm_rc=${line#HW-VM-STATUS } ;;
    "") ;;
    "#"*) echo "$line" ;;
    *) echo "# $line" ;;
    esac
done < <("$HERE/run-in-vm.sh" -t "$vm_timeout" -m "${HW_VM_MEM:-3072}" -- bash tests/hw/guest/run-scripts.sh "${scripts[@]}" 2>&1
         echo "HW-VM-STATUS $?")
vm_rc=${vm_rc:-125}
echo "# VM boot + tests took $(seconds_since "$t0") s"
case $vm_rc in
0) ;;
124) fail "the test VM finished" "it hung and was killed after $vm_timeout s" ;;
125) fail "the test VM finished" "it stopped before the tests had run (console output above)" ;;
*) fail "the VM test runner finished" "exit status $vm_rc" ;;
esac
finish
