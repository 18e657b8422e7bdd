#!/usr/bin/env bash
# vm-drm.sh - runs INSIDE the test VM (tests/hw/run-hw-tests.sh boots it): cmz-view on a real DRM/KMS
# device: qemu's bochs-display (run-in-vm.sh adds it) under the kernel's bochs driver (a CRTC, a
# virtual connector preferring 1024 x 768, dumb buffers in the device's memory: the ioctls a board's
# KMS driver answers; Debian's kernel has no vkms):
#   1. cmz-view MODEL --fb auto takes /dev/dri/card0 (not the driver's emulated /dev/fb0), finds
#      the connected screen, shows the model and stays ("until SIGTERM");
#   2. the buffer the CRTC scans out (read back through the kernel: GETCRTC, GETFB, MAP_DUMB, as
#      root) holds the PNG's pixels of the same frame (800 x 480, the build's largest) centred on
#      the screen, the background round it;
#   3. a second viewer while the first holds the screen is refused by name (exit 3);
#   4. SIGTERM ends the viewer (exit 0) and the kernel takes its buffer off the screen (the
#      driver's console buffer comes back);
#   5. a status line alone (--status) is drawn on the screen's last rows;
#   6. cmz-terminal --display on the device: one serving viewer (cmz-view --serve) shows the model
#      it receives under the terminal's status line, and goes with the daemon.
# Env: HW_VIEW, HW_TERMINAL, HW_CMZ, HW_MODELS.  Prints TAP lines; exit 0 iff all passed.
set -u
triplet=$(gcc -dumpmachine)
view=${HW_VIEW:-build/$triplet-terminal/cmz-view}
terminal=${HW_TERMINAL:-build/$triplet-terminal/cmz-terminal}
cmz=${HW_CMZ:-build/$triplet-host/cmz}
model=${HW_MODELS:-build/hw-models}/as1_pe_203.cmz
T=$(mktemp -d /tmp/vm-drm.XXXXXX)
n=0 failed=0
pass() { n=$((n + 1)); echo "ok $n - $1"; }
fail() { n=$((n + 1)); failed=$((failed + 1)); echo "not ok $n - $1${2:+: $2}"; }
bail() { fail "$1" "$2"; echo "# vm-drm: cannot go on"; exit 1; }
[ -x "$view" ] || bail "cmz-view is built" "no executable $view"
[ -f "$model" ] || bail "the model is encoded" "no $model"
modprobe bochs > "$T/modprobe" 2>&1
card=
for _ in $(seq 1 50); do
    for c in /dev/dri/card*; do [ -c "$c" ] && card=$c; done
    [ -n "$card" ] && break
    sleep 0.1
done
[ -n "$card" ] || bail "bochs gives a DRM device" "$(cat "$T/modprobe"; ls -l /dev/dri 2>&1; lspci 2>&1 | head -5)"
pass "bochs gives $card"
# the driver's console (fbcon on its emulated framebuffer) leaves the screen to the viewer
for vc in /sys/class/vtconsole/vtcon*; do
    grep -qi "frame buffer" "$vc/name" 2> /dev/null && echo 0 > "$vc/bind" 2> /dev/null
done

# the scanout of the first CRTC, as raw XRGB8888 rows (or "off" when no buffer is shown): through the
# kernel's ioctls (drm.h, drm_mode.h: _IOWR('d', nr, size))
grab() {
    python3 - "$card" "$1" <<'PY'
import ctypes, fcntl, mmap, os, struct, sys
def iowr(nr, size): return (3 << 30) | (size << 16) | (ord('d') << 8) | nr
fd = os.open(sys.argv[1], os.O_RDWR)
res = bytearray(64)  # struct drm_mode_card_res: the counts first, then the CRTCs' ids
fcntl.ioctl(fd, iowr(0xA0, 64), res, True)
ncrtc = struct.unpack_from('I', res, 36)[0]
cb = (ctypes.c_uint32 * max(ncrtc, 1))()
struct.pack_into('QQQQ', res, 0, 0, ctypes.addressof(cb), 0, 0)
struct.pack_into('IIII', res, 32, 0, ncrtc, 0, 0)
fcntl.ioctl(fd, iowr(0xA0, 64), res, True)
crtc = bytearray(104)
struct.pack_into('I', crtc, 12, cb[0])
fcntl.ioctl(fd, iowr(0xA1, 104), crtc, True)
fb_id = struct.unpack_from('I', crtc, 16)[0]
if fb_id == 0:
    open(sys.argv[2], 'w').write('off')
    sys.exit(0)
open(sys.argv[2] + '.id', 'w').write(str(fb_id))
fb = bytearray(28)
struct.pack_into('I', fb, 0, fb_id)
fcntl.ioctl(fd, iowr(0xAD, 28), fb, True)
_, w, h, pitch, bpp, depth, handle = struct.unpack('7I', fb)
md = bytearray(16)
struct.pack_into('I', md, 0, handle)
fcntl.ioctl(fd, iowr(0xB3, 16), md, True)
off = struct.unpack_from('Q', md, 8)[0]
m = mmap.mmap(fd, pitch * h, mmap.MAP_SHARED, mmap.PROT_READ, offset=off)
with open(sys.argv[2], 'wb') as f:
    f.write(struct.pack('III', w, h, bpp))
    for y in range(h):
        f.write(m[y * pitch:y * pitch + 4 * w])
PY
}

# compare a grab ($1) with the PNG $2 centred on it, background $3 round it; or (bottom) the PNG's
# last rows $4 on the screen's last rows
compare() {
    python3 - "$@" <<'PY'
import struct, sys, zlib
grab, png, bg = sys.argv[1], sys.argv[2], int(sys.argv[3], 16)
bottom = int(sys.argv[4]) if len(sys.argv) > 4 else 0
g = open(grab, 'rb').read()
W, H, bpp = struct.unpack_from('III', g, 0)
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
x0, y0 = (W - w) // 2, (H - h) // 2
bad = 0
rows = range(H - bottom, H) if bottom else range(H)
for y in rows:
    for x in range(W if not bottom else min(W, w)):
        if bottom:
            fx, fy = x, h - (H - y)
        else:
            fx, fy = x - x0, y - y0
        if 0 <= fx < w and 0 <= fy < h:
            o = fy * (1 + 3 * w) + 1 + 3 * fx
            want = (raw[o] << 16) | (raw[o + 1] << 8) | raw[o + 2]
        else:
            want = bg
        got = struct.unpack_from('<I', g, 12 + 4 * (y * W + x))[0] & 0xffffff
        if got != want:
            if bad == 0:
                print('first difference at (%d, %d): %06x, expected %06x' % (x, y, got, want))
            bad += 1
print('%d x %d screen, %d bits, %d pixels differ' % (W, H, bpp, bad))
sys.exit(1 if bad else 0)
PY
}

# 1. shown, and the viewer stays (--fb auto: the DRM device with a screen, before the framebuffer
#    the driver's fbdev emulation also offers)
"$view" "$model" --fb auto --png "$T/a.png" > "$T/out" 2> "$T/err" &
pid=$!
for _ in $(seq 1 100); do grep -q "until SIGTERM" "$T/out" 2> /dev/null && break; sleep 0.1; done
if grep -q "until SIGTERM" "$T/out" && grep -q "and $card:" "$T/out" && kill -0 $pid 2> /dev/null; then
    pass "cmz-view --fb auto takes $card, shows the model and stays ($(cat "$T/out"))"
else
    fail "cmz-view --fb auto" "$(cat "$T/out" "$T/err")"
fi
# 2. the scanout holds the frame, centred
if grab "$T/g" 2> "$T/gerr" && res=$(compare "$T/g" "$T/a.png" ffffff); then
    pass "the screen scans out the frame's pixels, centred ($res)"
else
    fail "the screen scans out the frame's pixels" "$(cat "$T/gerr") ${res:-}"
fi
# 3. another viewer cannot take the screen from it
"$view" "$model" --fb "$card" > /dev/null 2> "$T/err2"
st=$?
if [ $st -eq 3 ] && grep -q "another program holds the screen" "$T/err2"; then
    pass "a second viewer is refused while the first holds the screen: $(cat "$T/err2")"
else
    fail "a second viewer while the first holds the screen" "exit $st, $(cat "$T/err2")"
fi
# 4. SIGTERM: the viewer ends, and its buffer leaves the screen with it
kill -TERM $pid
wait $pid
st=$?
rm -f "$T/g2.id"
grab "$T/g2" 2> /dev/null
if [ $st -eq 0 ] && [ "$(cat "$T/g2.id" 2> /dev/null || echo off)" != "$(cat "$T/g.id")" ]; then
    pass "SIGTERM ends the viewer (exit 0), its buffer off the screen (framebuffer $(cat "$T/g.id") -> $(cat "$T/g2.id" 2> /dev/null || echo none))"
else
    fail "SIGTERM" "exit $st, the screen still shows framebuffer $(cat "$T/g2.id" 2> /dev/null)"
fi
# 5. a status line alone, on the screen's last rows (the bar of a frame of the build's largest size:
#    22 rows at 480; the PNG of a model with the same status line has it as its last rows)
"$view" --fb "$card" --status "receiving 40 %" > /dev/null 2> "$T/err" &
pid=$!
"$view" "$model" --png "$T/s.png" --size 800x480 --status "receiving 40 %" > /dev/null 2>&1
sleep 1
if grab "$T/g3" 2> /dev/null && res=$(compare "$T/g3" "$T/s.png" ffffff 22); then
    pass "a status line alone on the screen's last rows ($res)"
else
    fail "a status line alone" "$(cat "$T/err") ${res:-}"
fi
kill -TERM $pid 2> /dev/null
wait $pid 2> /dev/null
# 6. cmz-terminal --display on the DRM device: one viewer serves the run (cmz-view --serve); a model
#    sent to it (cmz send over pipes) ends on the screen with the status line the terminal gives it,
#    and the viewer goes with the daemon
if [ -x "$terminal" ] && [ -x "$cmz" ]; then
    mkdir -p "$T/store"
    # (the file's name, which the terminal shows on its status line, tries to start a command of its
    # own in the serving viewer's input: it must stay text)
    evil="$T/a"$'\n'"model etc-hostname"$'\t'"x.cmz"
    cp "$model" "$evil"
    coproc TERMINAL { exec "$terminal" --stdio --out "$T/store" --display "$card" --viewer "$view" 2> "$T/term.log"; }
    timeout 60 "$cmz" send "$evil" --stdio <&"${TERMINAL[0]}" >&"${TERMINAL[1]}" 2> "$T/send.log"
    st=$?
    # (the status line the terminal gave the viewer: the decode's counts it logged; the name with its
    # newline splits that log line)
    text=$(grep -o '[0-9]* faces, [0-9]* triangles[^"]*$' "$T/term.log" | tail -n 1)
    "$view" "$T/store/current/model.cmz" --png "$T/t.png" --size 800x480 --status "$text" > /dev/null 2>&1
    res="no picture"
    end=$((SECONDS + 20)) # (a compare of the whole screen takes a second or two under TCG)
    while [ $SECONDS -lt $end ]; do
        grab "$T/g4" 2> /dev/null && res=$(compare "$T/g4" "$T/t.png" ffffff) && break
        sleep 0.2
    done
    serving=$(pgrep -f -- "--serve" | head -n 1)
    if grep -q "cmz-view: .*etc-hostname\|does not know" "$T/term.log"; then
        fail "cmz-terminal --display $card: a name with a newline stays text" "$(grep "cmz-view" "$T/term.log" | head -n 3)"
    elif [ $st -eq 0 ] && [ -n "$text" ] && compare "$T/g4" "$T/t.png" ffffff > /dev/null; then
        pass "cmz-terminal --display $card: the received model on the screen, '$text' below it, a name with a newline kept text ($res)"
    else
        fail "cmz-terminal --display $card" "send $st, '$text': $res; $(tail -n 3 "$T/send.log" "$T/term.log")"
    fi
    kill -TERM "$TERMINAL_PID" 2> /dev/null
    wait "$TERMINAL_PID" 2> /dev/null
    sleep 0.5
    if [ -n "$serving" ] && ! kill -0 "$serving" 2> /dev/null; then
        pass "the serving viewer goes with the daemon"
    else
        fail "the serving viewer goes with the daemon" "pid ${serving:-none} $(ps 2> /dev/null | grep -- --serve)"
    fi
else
    fail "cmz-terminal --display: the programs" "terminal $terminal, cmz $cmz"
fi

# the VM as it was for the scripts after this one (their framebuffer is vfb's /dev/fb0)
rmmod bochs drm_vram_helper drm_ttm_helper ttm 2> /dev/null
rm -rf "$T"
echo "# vm-drm: $((n - failed)) of $n passed"
[ $failed -eq 0 ]
