#!/usr/bin/env bash
# vm-gpio.sh - runs INSIDE the test VM (tests/hw/run-hw-tests.sh boots it):
# the terminal's GPIO back end (platform/cm_gpio_gpiod.c, through
# tests/platform/gpio_probe) against a real kernel GPIO chip, gpio-sim.
#
# gpio-sim gives each line a sysfs view of the "hardware" side:
# sim_gpioN/value is the level an output drives, and writing pull-up or
# pull-down to sim_gpioN/pull sets what an input reads (the button).
# Prints TAP lines; exit 0 iff all passed.
# Env: HW_GPIO_PROBE (path of gpio_probe; default: the terminal build's).
set -u
probe=${HW_GPIO_PROBE:-build/$(gcc -dumpmachine)-terminal/tests/platform/gpio_probe}
label=curvemesh-sim
n=0 failed=0
pass() { n=$((n + 1)); echo "ok $n - $1"; }
fail() { n=$((n + 1)); failed=$((failed + 1)); echo "not ok $n - $1${2:+: $2}"; }
# expect DESCRIPTION ACTUAL EXPECTED
expect() { if [ "$2" = "$3" ]; then pass "$1"; else fail "$1" "got '$2', expected '$3'"; fi; }
bail() { fail "$1" "$2"; echo "# vm-gpio: cannot go on"; exit 1; }

[ -x "$probe" ] || bail "gpio_probe is built" "no executable $probe (make gpio-probe)"

# ---- a simulated chip: 8 lines, the first four named as the terminal's config names them ----
modprobe gpio-sim || bail "gpio-sim module loads" "modprobe gpio-sim failed"
G=/sys/kernel/config/gpio-sim/cm-test
mkdir "$G" "$G/bank0" || bail "gpio-sim configfs chip" "cannot create $G"
echo 8 > "$G/bank0/num_lines"
echo "$label" > "$G/bank0/label"
names=(busy ready error request)
for i in 0 1 2 3; do
    mkdir "$G/bank0/line$i" && echo "${names[$i]}" > "$G/bank0/line$i/name"
done
echo 1 > "$G/live" || bail "gpio-sim chip goes live" "writing 1 to $G/live failed"
chip=$(cat "$G/bank0/chip_name")
sim=/sys/devices/platform/$(cat "$G/dev_name")/$chip
[ -c "/dev/$chip" ] && [ -d "$sim" ] || bail "gpio-sim chip appears" "no /dev/$chip or $sim"
pass "gpio-sim chip /dev/$chip [$label] with lines busy, ready, error, request"
level() { cat "$sim/sim_gpio$1/value"; }
button() { echo "pull-$1" > "$sim/sim_gpio3/pull"; }  # up = pressed, down = released

# a build without libgpiod has nothing to test here
if out=$("$probe" --busy "$label:busy" quit 2>&1) || true; [[ $out == *"no GPIO support"* ]]; then
    echo "ok $((n + 1)) # SKIP gpio_probe was built without libgpiod (install libgpiod-dev, rebuild)"
    exit 0
fi

# ---- the probe as a coprocess: one command in, one answer line out ----
# each line named a different way: label:name, chip:offset, !path:name (active-low), label:name
coproc PROBE { exec "$probe" --busy "$label:busy" --ready "$chip:1" --error "!/dev/$chip:error" \
    --request "$label:request" 2>&1; }
probe_pid=$PROBE_PID
ask() {  # ask COMMAND... -> $reply
    reply="(no answer: gpio_probe exited)"
    [ -n "${PROBE[1]:-}" ] || return 0
    { echo "$*" >&"${PROBE[1]}"; } 2>/dev/null || return 0
    IFS= read -r -t 10 reply <&"${PROBE[0]}" || reply="(no answer within 10 s)"
}
ask sleep 0
expect "cm_gpio_open requests busy (label:name), ready (chip:offset), !error (path:name), request" "$reply" "slept 0"
expect "outputs start inactive: busy=0 ready=0, active-low error high" "$(level 0)$(level 1)$(level 2)" "001"
grep -q "gpio_probe" /sys/kernel/debug/gpio 2>/dev/null && pass "the lines carry the consumer name (debugfs gpio)" ||
    fail "the lines carry the consumer name" "$(grep -A5 "$chip" /sys/kernel/debug/gpio 2>&1 | head -n 6 | tr '\n' '|')"

ask set busy 1
expect "set busy 1 drives the busy line high" "$reply $(level 0)" "set busy 1 1"
ask set ready 1
expect "set ready 1 drives the ready line high" "$reply $(level 1)" "set ready 1 1"
ask set error 1
expect "set error 1 drives the active-low error line low" "$reply $(level 2)" "set error 1 0"
ask set busy 0
ask set error 0
expect "set busy 0 / error 0 return them to inactive" "$(level 0)$(level 2)" "01"

ask pressed
expect "no press reported before the button moves" "$reply" "no press"
t0=$(date +%s%N)
{ sleep 0.3; button up; } &
presser=$!
ask wait-press 5000
wait "$presser"
expect "a rising edge on request (pull-up) wakes wait-press" "$reply" "pressed"
echo "# button press seen after $(( ($(date +%s%N) - t0) / 1000000 )) ms (0.3 s of it the test's own delay)"
ask pressed
expect "the press is consumed: a second check sees none" "$reply" "no press"
button down
ask wait-press 300
expect "releasing the button (falling edge) is not a press" "$reply" "no press"
button up
sleep 0.1
ask pressed
expect "a press made while nobody waited is still reported (the fd queues it)" "$reply" "pressed"
button down
ask quit
expect "quit closes cleanly" "$reply" "bye"
wait "$probe_pid" 2>/dev/null
expect "gpio_probe exit status" "$?" "0"

# ---- released on close: the same lines can be requested again ----
out=$("$probe" --busy "$label:busy" --ready "$label:ready" --error "$label:error" --request "$label:request" \
    set busy 1 quit 2>&1)
expect "after close every line can be requested again" "$out" "$(printf 'set busy 1\nbye')"

# ---- what the outputs did, level by level: the kernel's gpio_value tracepoint ----
# (gpio-sim's sysfs cannot show it: a released line falls back to its pull at once)
T=/sys/kernel/tracing
[ -d "$T/events" ] || mount -t tracefs nodev "$T" 2>/dev/null
base=$(sed -n "s/^$chip: GPIOs \([0-9]*\)-.*/\1/p" /sys/kernel/debug/gpio 2>/dev/null)
if [ -n "$base" ] && echo 1 > "$T/events/gpio/gpio_value/enable" 2>/dev/null; then
    echo > "$T/trace"
    "$probe" --busy "$label:busy" --error "!$label:error" set busy 1 set error 1 quit > /dev/null 2>&1
    echo 0 > "$T/events/gpio/gpio_value/enable"
    levels() { awk -v g="$1" '$0 ~ ("gpio_value: " g " set ") { printf "%s%s", s, $NF; s = " " }' "$T/trace"; }
    expect "busy: requested inactive, set active, driven inactive before release (0 1 0)" "$(levels "$base")" "0 1 0"
    expect "active-low error: the same seen as levels (1 0 1)" "$(levels $((base + 2)))" "1 0 1"
else
    echo "ok $((n + 1)) # SKIP no gpio_value tracepoint (tracefs) in this kernel"
    n=$((n + 1))
fi

# ---- errors name the line spec and the cause ----
# msg OPTIONS... -> what gpio_probe says on stderr (its stdout is dropped)
# shellcheck disable=SC2069
msg() { "$probe" "$@" quit 2>&1 >/dev/null; }
expect "unknown line name" "$(msg --busy "$label:busy-led")" \
    "gpio_probe: gpio busy=$label:busy-led: no line named 'busy-led' on chip $chip [$label]"
expect "unknown chip" "$(msg --ready nosuchchip:1)" \
    "gpio_probe: gpio ready=nosuchchip:1: no GPIO chip named or labelled 'nosuchchip' (gpiodetect lists them)"
expect "offset past the last line" "$(msg --error "$chip:8")" \
    "gpio_probe: gpio error=$chip:8: chip $chip [$label] has 8 lines, no offset 8"
expect "missing :LINE" "$(msg --request "$label")" \
    "gpio_probe: gpio request=$label: expected CHIP:LINE (e.g. gpiochip0:busy-led or !decoder-sim:3)"

coproc HOLDER { exec "$probe" --consumer holder --busy "$label:busy" 2>&1; }
holder_pid=$HOLDER_PID
echo "sleep 0" >&"${HOLDER[1]}"
IFS= read -r -t 10 held <&"${HOLDER[0]}" || held="(no answer)"
expect "another program (consumer 'holder') holds busy" "$held" "slept 0"
expect "a line held by another consumer names it" "$(msg --busy "$chip:0")" \
    "gpio_probe: gpio busy=$chip:0: line is used by 'holder'"
echo quit >&"${HOLDER[1]}"
wait "$holder_pid" 2>/dev/null

# a failed open gives back the lines it had already requested
msg --ready "$label:ready" --error "$label:no-such-line" > /dev/null
out=$("$probe" --ready "$label:ready" set ready 1 quit 2>&1)
expect "a failed open releases the lines it had requested" "$out" "$(printf 'set ready 1\nbye')"

# command-line mode: wait-press without a press ends with status 2
"$probe" --request "$label:request" wait-press 200 > /dev/null 2>&1
expect "wait-press from the command line times out with status 2" "$?" "2"

echo 0 > "$G/live"
rmdir "$G"/bank0/line* "$G/bank0" "$G"
echo "# vm-gpio: $((n - failed)) passed, $failed failed"
[ "$failed" = 0 ]
