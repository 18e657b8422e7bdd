#!/usr/bin/env bash
# vm-display.sh - runs INSIDE the test VM (tests/hw/run-hw-tests.sh boots it): cmz-view --fb on a
# real kernel framebuffer, the kernel's virtual one (vfb: the fbdev ioctls and mmap of any board's
# /dev/fb0, over memory).  For a 32-bit and a 16-bit screen of 320 x 200 (vfb's channels run blue,
# green, red from the top: the layout the driver reports is the one used):
#   1. cmz-view draws the model at the screen's size on /dev/fb0 (no --size), exit 0;
#   2. the screen's memory, read back from /dev/fb0, holds the PNG's pixels cmz-view writes of the
#      same frame, in the screen's format (16-bit: each channel's top bits);
#   3. a frame smaller than the screen is centred, the rest of the screen the background;
#   4. cmz-terminal --display: a model sent to it (cmz send over pipes) ends on the screen, with the
#      status line the terminal gives it;
#   5. a status line alone (cmz-view --fb --status: the terminal's receiving and refusal notes)
#      changes only the screen's last rows;
#   6. the operator's buttons on gpio-sim lines (cmz-view --gpio-rotate/-next/-prev/-reset): each
#      press draws the frame `cmz-view --png` draws with the same --turn/--step and the status line
#      "step k of N"; a second viewer asking for a held line is refused by name (exit 4); SIGTERM
#      ends the viewer (exit 0);
#   7. the idle turntable (--turntable 3 --idle 1): the screen goes to --turn 1, then --turn 2;
#   8. cmz-terminal passes the options after -- to the viewer of each model: a press shows step 1
#      under the terminal's status line, and the viewer goes when the daemon is stopped.
# Env: HW_VIEW (cmz-view; default this checkout's terminal build), HW_TERMINAL, HW_CMZ, HW_MODELS
# (the .cmz files, encoded on the host).  Prints TAP lines; exit 0 iff all passed.
set -u
triplet=$(gcc -dumpmachine)
view=${HW_VIEW:-build/$triplet-terminal/cmz-view}
terminal=${HW_TERMINAL:-build/$triplet-terminal/cmz-terminal}
cmz=${HW_CMZ:-build/$triplet-host/cmz}
model=${HW_MODELS:-build/hw-models}/as1_pe_203.cmz
T=$(mktemp -d /tmp/vm-display.XXXXXX)
n=0 failed=0
pass() { n=$((n + 1)); echo "ok $n - $1"; }
fail() { n=$((n + 1)); failed=$((failed + 1)); echo "not ok $n - $1${2:+: $2}"; }
bail() { fail "$1" "$2"; echo "# vm-display: cannot go on"; exit 1; }
[ -x "$view" ] || bail "cmz-view is built" "no executable $view"
[ -f "$model" ] || bail "the model is encoded" "no $model"

# the framebuffer console (fbcon) takes a new framebuffer and blinks its cursor in the corner: a
# terminal's screen belongs to the viewer (on a board: fbcon=map:9 or vt.global_cursor_default=0)
release_console() {
    local vc
    for vc in /sys/class/vtconsole/vtcon*; do
        grep -qi "frame buffer" "$vc/name" 2> /dev/null && echo 0 > "$vc/bind" 2> /dev/null
    done
    return 0
}

# compare the framebuffer dump $1 (bpp $2, 320 x 200, stride 320 * bpp / 8) with the PNG $3 placed
# at ($4, $5), background $6 round it; prints the first difference.  With a seventh argument
# `write`: write to $1 the screen's memory that frame should make, and compare nothing
compare() {
    python3 - "$@" <<'PY'
import struct, sys, zlib
dump, bpp, png, x0, y0, bg = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4]), int(sys.argv[5]), int(sys.argv[6], 16)
d = open(png, 'rb').read()
at, idat, w, h = 8, b'', 0, 0
while at < len(d):
    n, t = struct.unpack('>I4s', d[at:at + 8])
    if t == b'IHDR':
        w, h = struct.unpack('>II', d[at + 8:at + 16])
    if t == b'IDAT':
        idat += d[at + 8:at + 8 + n]
    at += 12 + n
raw = zlib.decompress(idat)
B = bpp // 8
# the channels' bit offsets and lengths as the driver reports them (FBIOGET_VSCREENINFO: struct
# fb_var_screeninfo, red/green/blue after eight fields); vfb lays out B,G,R from the top
import fcntl
with open('/dev/fb0', 'rb') as f:
    var = struct.unpack('40I', fcntl.ioctl(f.fileno(), 0x4600, bytes(160)))
(ro, rl), (go, gl), (bo, bl) = (var[8], var[9]), (var[11], var[12]), (var[14], var[15])
def want(x, y):
    fx, fy = x - x0, y - y0
    if 0 <= fx < w and 0 <= fy < h:
        o = fy * (1 + 3 * w) + 1 + 3 * fx
        r, g, b = raw[o], raw[o + 1], raw[o + 2]
    else:
        r, g, b = bg >> 16, (bg >> 8) & 255, bg & 255
    return ((r >> (8 - rl)) << ro) | ((g >> (8 - gl)) << go) | ((b >> (8 - bl)) << bo)
if len(sys.argv) > 7 and sys.argv[7] == 'write':
    open(dump, 'wb').write(b''.join(want(x, y).to_bytes(B, 'little') for y in range(200) for x in range(320)))
    sys.exit(0)
fb = open(dump, 'rb').read()
bad = 0
for y in range(200):
    for x in range(320):
        o = (y * 320 + x) * B
        got = int.from_bytes(fb[o:o + B], 'little') & (0xffffff if bpp == 32 else 0xffff)
        if got != want(x, y):
            if bad == 0:
                print('first difference at (%d, %d): %06x, expected %06x' % (x, y, got, want(x, y)))
            bad += 1
print('%d pixels differ, channels at %d/%d/%d' % (bad, ro, go, bo))
sys.exit(1 if bad else 0)
PY
}

for bpp in 32 16; do
    rmmod vfb 2> /dev/null
    if ! modprobe vfb vfb_enable=1 mode_option=320x200-$bpp > "$T/modprobe" 2>&1 || [ ! -c /dev/fb0 ]; then
        fail "$bpp-bit: vfb gives /dev/fb0" "$(cat "$T/modprobe")"
        continue
    fi
    release_console
    got=$(cat /sys/class/graphics/fb0/bits_per_pixel 2> /dev/null)
    [ "$got" = "$bpp" ] || { fail "$bpp-bit: vfb's mode" "bits_per_pixel $got"; continue; }
    # 1. the model at the screen's size, the PNG of the same frame beside it
    if out=$("$view" "$model" --fb /dev/fb0 --png "$T/a.png" 2> "$T/err"); then
        pass "$bpp-bit: cmz-view --fb /dev/fb0 shows the model ($out)"
    else
        fail "$bpp-bit: cmz-view --fb /dev/fb0" "$(cat "$T/err")"
        continue
    fi
    # 2. the screen's memory holds those pixels
    dd if=/dev/fb0 of="$T/fb" bs=$((320 * bpp / 8)) count=200 2> /dev/null
    if res=$(compare "$T/fb" "$bpp" "$T/a.png" 0 0 ffffff); then
        pass "$bpp-bit: the screen holds the frame's pixels ($res)"
    else
        fail "$bpp-bit: the screen holds the frame's pixels" "$res"
    fi
    # 2b. --fb auto, with no DRM device about: the framebuffer
    if [ "$bpp" = 32 ]; then
        if out=$("$view" "$model" --fb auto --png "$T/auto.png" 2> "$T/err") && [[ $out == *"and /dev/fb0:"* ]]; then
            dd if=/dev/fb0 of="$T/fb" bs=$((320 * bpp / 8)) count=200 2> /dev/null
            if res=$(compare "$T/fb" "$bpp" "$T/auto.png" 0 0 ffffff); then
                pass "$bpp-bit: --fb auto without a DRM device takes /dev/fb0 ($res)"
            else
                fail "$bpp-bit: --fb auto takes /dev/fb0" "$res"
            fi
        else
            fail "$bpp-bit: --fb auto without a DRM device" "${out:-} $(cat "$T/err")"
        fi
    fi
    # 3. a smaller frame, centred on a dark background
    if "$view" "$model" --fb /dev/fb0 --png "$T/b.png" --size 200x100 --background 203040 > /dev/null 2> "$T/err"; then
        dd if=/dev/fb0 of="$T/fb" bs=$((320 * bpp / 8)) count=200 2> /dev/null
        if res=$(compare "$T/fb" "$bpp" "$T/b.png" 60 50 203040); then
            pass "$bpp-bit: a 200 x 100 frame centred, the background round it ($res)"
        else
            fail "$bpp-bit: a 200 x 100 frame centred" "$res"
        fi
    else
        fail "$bpp-bit: cmz-view --size 200x100 --fb" "$(cat "$T/err")"
    fi
done
# 4. the terminal shows what it receives: cmz send -> cmz-terminal --display /dev/fb0 (frames over a
#    pair of pipes), which runs cmz-view on the stored model; the screen then holds the pixels
#    cmz-view draws of that model, and the terminal's log names no viewer failure
rmmod vfb 2> /dev/null
if modprobe vfb vfb_enable=1 mode_option=320x200-32 > "$T/modprobe" 2>&1 && [ -c /dev/fb0 ] &&
        [ -x "$terminal" ] && [ -x "$cmz" ]; then
    release_console
    mkdir -p "$T/store"
    coproc TERMINAL { "$terminal" --stdio --out "$T/store" --once --display /dev/fb0 --viewer "$view" 2> "$T/term.log"; }
    timeout 60 "$cmz" send "$model" --stdio <&"${TERMINAL[0]}" >&"${TERMINAL[1]}" 2> "$T/send.log"
    st=$?
    wait "$TERMINAL_PID"
    tst=$?
    dd if=/dev/fb0 of="$T/fb" bs=1280 count=200 2> /dev/null
    # the status line the terminal gave the viewer: what it logged of the model
    text=$(sed -n 's/.*event=decoded name="[^"]*" //p' "$T/term.log" | tail -n 1)
    "$view" "$T/store/current/model.cmz" --png "$T/t.png" --size 320x200 --status "$text" > /dev/null 2>&1
    if [ $st -ne 0 ] || [ $tst -ne 0 ]; then
        fail "cmz-terminal --display: send and decode" "send $st, terminal $tst: $(tail -n 3 "$T/send.log" "$T/term.log")"
    elif grep -q "event=display" "$T/term.log"; then
        fail "cmz-terminal --display: the viewer ran" "$(grep event=display "$T/term.log")"
    elif res=$(compare "$T/fb" 32 "$T/t.png" 0 0 ffffff); then
        pass "cmz-terminal --display /dev/fb0: the received model on the screen, '$text' below it ($res)"
    else
        fail "cmz-terminal --display /dev/fb0: the received model on the screen" "$res"
    fi
    # 5. a status line alone (what the terminal shows while receiving, or a refusal): the screen's
    #    last rows change, the model above them stays
    cp "$T/fb" "$T/before"
    if "$view" --fb /dev/fb0 --status "refused: MAX_FACES" 2> "$T/err"; then
        dd if=/dev/fb0 of="$T/fb" bs=1280 count=200 2> /dev/null
        if res=$(python3 - "$T/before" "$T/fb" <<'PY'
import sys
a, b = open(sys.argv[1], 'rb').read(), open(sys.argv[2], 'rb').read()
rows = [y for y in range(200) if a[y * 1280:(y + 1) * 1280] != b[y * 1280:(y + 1) * 1280]]
print('rows %d..%d changed' % (rows[0], rows[-1]) if rows else 'nothing changed')
sys.exit(0 if rows and rows[0] >= 200 - 11 else 1)
PY
        ); then
            pass "cmz-view --status alone: only the status line's rows change ($res)"
        else
            fail "cmz-view --status alone: only the status line's rows change" "$res"
        fi
    else
        fail "cmz-view --fb --status" "$(cat "$T/err")"
    fi
else
    fail "cmz-terminal --display: vfb and the programs" "$(cat "$T/modprobe"); terminal $terminal, cmz $cmz"
fi

# ---- 6-8: the operator's buttons (gpio-sim) and the turntable, on a 320 x 200 32-bit screen ----
# the screen's expected memory for the PNG $1 (a whole-screen frame), written to $2 (compare's)
expected_dump() { compare "$2" 32 "$1" 0 0 ffffff write; }
# screen_becomes WHAT TIMEOUT VIEW-OPTION...: the screen shows `cmz-view --png` of those options
screen_becomes() {
    local what=$1 secs=$2
    shift 2
    if ! "$view" "$model" --png "$T/e.png" --size 320x200 "$@" > /dev/null 2> "$T/err"; then
        fail "$what" "cmz-view --png $*: $(cat "$T/err")"
        return 1
    fi
    expected_dump "$T/e.png" "$T/e.raw"
    local end=$((SECONDS + secs))
    while :; do
        dd if=/dev/fb0 of="$T/fb" bs=1280 count=200 2> /dev/null
        # (the unused fourth byte of each 32-bit pixel: vfb keeps what was written, the viewer 0)
        if python3 -c 'import sys; a = open(sys.argv[1], "rb").read(); b = open(sys.argv[2], "rb").read()
sys.exit(0 if all(x == y for i, (x, y) in enumerate(zip(a, b)) if i % 4 != 3) and len(a) == len(b) else 1)' \
                "$T/fb" "$T/e.raw"; then
            pass "$what"
            return 0
        fi
        [ $SECONDS -lt $end ] || break
        sleep 0.2
    done
    fail "$what" "the screen does not show cmz-view --png $* within $secs s"
    return 1
}
rmmod vfb 2> /dev/null
G=/sys/kernel/config/gpio-sim/cm-view
label=cm-view-sim
if ! modprobe vfb vfb_enable=1 mode_option=320x200-32 > "$T/modprobe" 2>&1 || [ ! -c /dev/fb0 ]; then
    fail "buttons: vfb gives /dev/fb0" "$(cat "$T/modprobe")"
elif ! modprobe gpio-sim || ! mkdir "$G" "$G/bank0"; then
    fail "buttons: a gpio-sim chip" "modprobe gpio-sim or mkdir $G failed"
else
    release_console
    echo 4 > "$G/bank0/num_lines"
    echo "$label" > "$G/bank0/label"
    names=(rotate next prev reset)
    for i in 0 1 2 3; do mkdir "$G/bank0/line$i" && echo "${names[$i]}" > "$G/bank0/line$i/name"; done
    echo 1 > "$G/live"
    sim=/sys/devices/platform/$(cat "$G/dev_name")/$(cat "$G/bank0/chip_name")
    press() { echo pull-up > "$sim/sim_gpio$1/pull"; sleep 0.05; echo pull-down > "$sim/sim_gpio$1/pull"; }
    buttons=(--gpio-rotate "$label:rotate" --gpio-next "$label:next" --gpio-prev "$label:prev" --gpio-reset "$label:reset")
    # 6. the buttons
    "$view" "$model" --fb /dev/fb0 "${buttons[@]}" > "$T/v.out" 2> "$T/v.err" &
    vpid=$!
    for _ in $(seq 300); do grep -q "waiting for the buttons" "$T/v.out" && break; sleep 0.1; done
    parts=$(sed -n 's/.*: \([0-9]*\) parts, waiting for the buttons$/\1/p' "$T/v.out")
    if [ -z "$parts" ]; then
        fail "buttons: cmz-view waits for its buttons" "$(cat "$T/v.out" "$T/v.err")"
    else
        pass "buttons: cmz-view --fb with four buttons draws the model and waits ($parts parts)"
        out=$("$view" "$model" --fb /dev/fb0 --gpio-next "$label:next" 2>&1)
        st=$?
        if [ $st = 4 ] && [[ $out == *"gpio next=$label:next: line is used by 'cmz-view'"* ]]; then
            pass "buttons: a second viewer asking for a held line is refused by name (exit 4)"
        else
            fail "buttons: a second viewer asking for a held line is refused by name" "exit $st: $out"
        fi
        press 1
        screen_becomes "buttons: next shows step 1 of $parts" 30 --step 1 --status "step 1 of $parts"
        press 0
        screen_becomes "buttons: rotate turns it 15 degrees" 30 --step 1 --turn 1 --status "step 1 of $parts"
        press 2
        screen_becomes "buttons: prev from step 1 shows the whole model" 30 --turn 1
        press 2
        screen_becomes "buttons: prev from the whole model shows the last step" 30 --turn 1 --step "$parts" \
            --status "step $parts of $parts"
        press 3
        screen_becomes "buttons: reset goes back to the first view" 30
    fi
    kill -TERM "$vpid" 2> /dev/null
    for _ in $(seq 100); do kill -0 "$vpid" 2> /dev/null || break; sleep 0.1; done
    wait "$vpid"
    st=$?
    [ $st = 0 ] && pass "buttons: SIGTERM ends the viewer (exit 0)" ||
        fail "buttons: SIGTERM ends the viewer" "exit $st: $(cat "$T/v.err")"
    # 7. the idle turntable
    "$view" "$model" --fb /dev/fb0 --turntable 3 --idle 1 > /dev/null 2> "$T/v.err" &
    vpid=$!
    screen_becomes "turntable: after a second idle the model turns a step" 60 --turn 1 &&
        screen_becomes "turntable: and another three seconds later" 60 --turn 2
    kill -TERM "$vpid" 2> /dev/null
    wait "$vpid"
    # 8. cmz-terminal -- VIEWER-OPTIONS: the viewer of the received model has the next button
    if [ -x "$terminal" ] && [ -x "$cmz" ]; then
        rm -rf "$T/store2" && mkdir -p "$T/store2"
        coproc TERM2 { exec "$terminal" --stdio --out "$T/store2" --display /dev/fb0 --viewer "$view" \
            -- --gpio-next "$label:next" 2> "$T/term2.log"; }
        term_pid=$TERM2_PID
        timeout 60 "$cmz" send "$model" --stdio <&"${TERM2[0]}" >&"${TERM2[1]}" 2> "$T/send2.log"
        text=$(sed -n 's/.*event=decoded name="[^"]*" //p' "$T/term2.log" | tail -n 1)
        if screen_becomes "terminal: the received model on the screen" 60 --status "$text"; then
            # (the viewer asks for its line once the picture is up: a press before that is not seen)
            for _ in $(seq 100); do grep -q "cmz-view" /sys/kernel/debug/gpio 2> /dev/null && break; sleep 0.1; done
            press 1
            screen_becomes "terminal -- --gpio-next: a press shows step 1 under the terminal's status" 30 \
                --step 1 --status "$text  -  step 1 of $parts"
        fi
        kill -TERM "$term_pid" 2> /dev/null
        for _ in $(seq 100); do kill -0 "$term_pid" 2> /dev/null || break; sleep 0.1; done
        if kill -0 "$term_pid" 2> /dev/null; then
            fail "terminal: stops with its viewer on SIGTERM" "still running after 10 s"
            kill -KILL "$term_pid"
        elif pgrep -f "cmz-view.*--gpio-next" > /dev/null; then
            fail "terminal: stops with its viewer on SIGTERM" "the viewer is still running"
        else
            pass "terminal: stops with its viewer on SIGTERM"
        fi
    fi
    echo 0 > "$G/live"
    rmdir "$G"/bank0/line* "$G/bank0" "$G"
fi
rmmod vfb 2> /dev/null
rm -rf "$T"
[ $failed -eq 0 ]
