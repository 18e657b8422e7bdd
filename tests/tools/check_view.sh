#!/usr/bin/env bash
# check_view.sh CMZ CMZ_VIEW [ARM_CMZ_VIEW] - what the terminal shows (issue 17), on the bundled models.
#
# Each bundled model is encoded and drawn by cmz-view from every direction (orthographic) and in
# perspective: the PNG must be valid (chunk CRCs, the zlib stream), of the size asked, show the
# model inside the frame's margin (the fitted camera leaves a 6 % border empty) and, orthographic,
# with its outline spanning the room across or down (the fit), and come out the same twice.  With
# ARM_CMZ_VIEW (the aarch64 build, run under qemu-user), the same pixels on ARM, byte for byte.
# The GLB `cmz decode` writes draws the .cmz's pixels without the edges (cmz-view MODEL.glb).
# A frame beyond the build's is refused with exit 2 and the limit named, and nothing is written.
# One TAP line per check; "N passed, N failed" last.
set -u
cmz=$1 view=$2 arm=${3:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ -e /usr/lib/aarch64-linux-gnu/libc.so.6 ]; then qemu=(qemu-aarch64); else qemu=(qemu-aarch64 -L /usr/aarch64-linux-gnu); fi
n=0 fail=0
ok() { n=$((n + 1)); echo "ok $n - $*"; }
bad() { n=$((n + 1)); fail=$((fail + 1)); echo "not ok $n - $*"; }

# the share of pixels that are not the background (white), the border's pixels being background:
# from the PNG's stored deflate blocks (tests/tools/png_stats.py-free: the PNG is ours, rows
# unfiltered)
png_stats() {
    python3 - "$1" <<'EOF'
import struct, sys, zlib
d = open(sys.argv[1], 'rb').read()
assert d[:8] == b'\x89PNG\r\n\x1a\n'
at, idat, w, h = 8, b'', 0, 0
while at < len(d):
    n, t = struct.unpack('>I4s', d[at:at + 8])
    body = d[at + 8:at + 8 + n]
    assert zlib.crc32(t + body) == struct.unpack('>I', d[at + 8 + n:at + 12 + n])[0], 'crc'
    if t == b'IHDR':
        w, h = struct.unpack('>II', body[:8])
    if t == b'IDAT':
        idat += body
    at += 12 + n
raw = zlib.decompress(idat)
assert len(raw) == h * (1 + 3 * w)
fg = border = 0
m = int(0.06 * min(w, h)) - 1
x0, y0, x1, y1 = w, h, -1, -1
for y in range(h):
    row = raw[y * (1 + 3 * w) + 1:(y + 1) * (1 + 3 * w)]
    for x in range(w):
        if row[3 * x:3 * x + 3] != b'\xff\xff\xff':
            fg += 1
            x0, y0, x1, y1 = min(x0, x), min(y0, y), max(x1, x), max(y1, y)
            if x < m or y < m or x >= w - m or y >= h - m:
                border += 1
# the outline's extent across and down (pixels), against the room the fitted camera gives it
room_x, room_y = w - 2 * 0.06 * min(w, h), h - 2 * 0.06 * min(w, h)
fits = abs((x1 - x0 + 1) - room_x) <= 3 or abs((y1 - y0 + 1) - room_y) <= 3
print(w, h, fg, border, x1 - x0 + 1, y1 - y0 + 1, 1 if fits else 0)
EOF
}

for m in tests/data/*.igs; do
    b=$(basename "${m%.*}")
    if ! "$cmz" encode -q "$m" -o "$tmp/$b.cmz" > /dev/null 2> "$tmp/err"; then
        bad "$b: encode failed: $(tail -n 1 "$tmp/err")"
        continue
    fi
    for v in iso front back left right top bottom iso-p; do
        args=(--view "${v%-p}" --size 320x200)
        [ "$v" = iso-p ] && args+=(--perspective)
        if ! "$view" "$tmp/$b.cmz" --png "$tmp/x.png" "${args[@]}" > /dev/null 2> "$tmp/err"; then
            bad "$b $v: cmz-view failed: $(cat "$tmp/err")"
            continue
        fi
        fits=
        read -r w h fg border bw bh fits < <(png_stats "$tmp/x.png" 2> "$tmp/perr") || true
        if [ -z "${fits:-}" ]; then
            bad "$b $v: not a valid PNG: $(tail -n 1 "$tmp/perr")"
            continue
        fi
        # orthographic: the outline spans the room across or down; perspective: it shows, inside
        if [ "$w $h" != "320 200" ]; then
            bad "$b $v: a $w x $h PNG, asked for 320 x 200"
        elif [ "$fg" -gt 0 ] && [ "$border" -eq 0 ] && { [ "$v" = iso-p ] || [ "$fits" = 1 ]; }; then
            ok "$b $v: $fg pixels of model, its outline $bw x $bh, none in the border"
        else
            bad "$b $v: $fg pixels of model, its outline $bw x $bh (fits the room: $fits), $border in the border"
        fi
        "$view" "$tmp/$b.cmz" --png "$tmp/y.png" "${args[@]}" > /dev/null 2>&1
        cmp -s "$tmp/x.png" "$tmp/y.png" || bad "$b $v: a second run gives other bytes"
        if [ -n "$arm" ]; then
            if ! "${qemu[@]}" "$arm" "$tmp/$b.cmz" --png "$tmp/a.png" "${args[@]}" > /dev/null 2> "$tmp/err"; then
                bad "$b $v: cmz-view on aarch64 failed: $(cat "$tmp/err")"
            elif cmp -s "$tmp/x.png" "$tmp/a.png"; then
                ok "$b $v: the same pixels on aarch64"
            else
                bad "$b $v: aarch64 draws other pixels ($(cmp "$tmp/x.png" "$tmp/a.png" | head -n 1))"
            fi
        fi
    done
done

# assembly steps: the summary counts the parts; the last step shows the whole model's outline (its
# colours changed: the last part highlighted, the rest dimmed), the first no more than that, and a
# step beyond the parts is refused
for m in tests/data/*.igs; do
    b=$(basename "${m%.*}")
    parts=$("$view" "$tmp/$b.cmz" --png "$tmp/s0.png" --size 320x200 | sed -n 's/.* \([0-9]*\) parts.*/\1/p')
    if [ -z "$parts" ] || [ "$parts" -lt 1 ]; then
        bad "$b steps: no part count in the summary"
        continue
    fi
    "$view" "$tmp/$b.cmz" --png "$tmp/sl.png" --size 320x200 --step "$parts" > /dev/null 2>&1
    "$view" "$tmp/$b.cmz" --png "$tmp/s1.png" --size 320x200 --step 1 > /dev/null 2>&1
    read -r _ _ fg0 _ bw0 bh0 _ < <(png_stats "$tmp/s0.png")
    read -r _ _ fgl _ bwl bhl _ < <(png_stats "$tmp/sl.png")
    read -r _ _ fg1 _ _ _ _ < <(png_stats "$tmp/s1.png")
    if [ "$fg0 $bw0 $bh0" = "$fgl $bwl $bhl" ] && ! cmp -s "$tmp/s0.png" "$tmp/sl.png" && [ "$fg1" -le "$fg0" ] && [ "$fg1" -gt 0 ]; then
        ok "$b steps: $parts parts; step $parts covers the model's $fg0 pixels in other colours, step 1 $fg1"
    else
        bad "$b steps: $parts parts; step 0 $fg0 pixels ($bw0 x $bh0), step $parts $fgl ($bwl x $bhl), step 1 $fg1"
    fi
    "$view" "$tmp/$b.cmz" --png "$tmp/sx.png" --size 320x200 --step $((parts + 1)) > /dev/null 2> "$tmp/err"
    st=$?
    if [ $st -eq 2 ] && grep -q "has $parts parts" "$tmp/err" && [ ! -e "$tmp/sx.png" ]; then
        ok "$b steps: step $((parts + 1)) refused: $(cat "$tmp/err")"
    else
        bad "$b steps: step $((parts + 1)): exit $st, $(cat "$tmp/err")"
    fi
done

# the GLB `cmz decode` writes of each bundled model draws as its .cmz does without the curve mesh's
# edges (--no-edges: a GLB has none), pixel for pixel, from three directions and in perspective (on
# aarch64 too); a GLB cut short is refused, nothing written
for m in tests/data/*.igs; do
    b=$(basename "${m%.*}")
    if ! "$cmz" decode "$tmp/$b.cmz" -o "$tmp/$b.glb" > /dev/null 2> "$tmp/err"; then
        bad "$b glb: cmz decode failed: $(tail -n 1 "$tmp/err")"
        continue
    fi
    for v in iso front top iso-p; do
        args=(--view "${v%-p}" --size 320x200 --no-edges)
        [ "$v" = iso-p ] && args+=(--perspective)
        "$view" "$tmp/$b.cmz" --png "$tmp/c.png" "${args[@]}" > /dev/null 2>&1
        if ! "$view" "$tmp/$b.glb" --png "$tmp/g.png" "${args[@]}" > "$tmp/out" 2> "$tmp/err"; then
            bad "$b glb $v: cmz-view failed: $(cat "$tmp/err")"
        elif cmp -s "$tmp/c.png" "$tmp/g.png"; then
            ok "$b glb $v: the GLB draws the .cmz's pixels ($(sed -n 's/.*: \(.*\)/\1/p' "$tmp/out"))"
        else
            bad "$b glb $v: the GLB draws other pixels than the .cmz"
        fi
        if [ -n "$arm" ] && [ "$v" = iso ]; then
            if "${qemu[@]}" "$arm" "$tmp/$b.glb" --png "$tmp/a.png" "${args[@]}" > /dev/null 2> "$tmp/err" &&
                cmp -s "$tmp/g.png" "$tmp/a.png"; then
                ok "$b glb $v: the same pixels on aarch64"
            else
                bad "$b glb $v: aarch64: $(cat "$tmp/err")"
            fi
        fi
    done
    # the same model as one primitive of all its triangles (as other tools write a part), larger than
    # the terminal's mesh window: drawn in runs of triangles, the same pixels
    python3 - "$tmp/$b.glb" "$tmp/one.glb" <<'PY'
import json, struct, sys
d = open(sys.argv[1], 'rb').read()
jl = struct.unpack_from('<I', d, 12)[0]
j = json.loads(d[20:20 + jl])
bin_ = d[20 + jl + 8:]
def acc(i):
    a = j['accessors'][i]
    v = j['bufferViews'][a['bufferView']]
    off, n = v.get('byteOffset', 0) + a.get('byteOffset', 0), a['count']
    if a['type'] == 'VEC3':
        st = v.get('byteStride', 12)
        return [struct.unpack_from('<3f', bin_, off + k * st) for k in range(n)]
    return list(struct.unpack_from('<%dI' % n, bin_, off))
pos, nrm, idx = [], [], []
for p in j['meshes'][0]['primitives']:
    base = len(pos)
    pos += acc(p['attributes']['POSITION'])
    nrm += acc(p['attributes']['NORMAL'])
    idx += [base + k for k in acc(p['indices'])]
blob = b''.join(struct.pack('<3f', *v) for v in pos) + b''.join(struct.pack('<3f', *v) for v in nrm) + \
    struct.pack('<%dI' % len(idx), *idx)
n = len(pos)
out = {'asset': {'version': '2.0'}, 'scene': 0, 'scenes': [{'nodes': [0]}],
       'nodes': [{'mesh': 0, 'matrix': j['nodes'][0]['matrix']}],
       'meshes': [{'primitives': [{'attributes': {'POSITION': 0, 'NORMAL': 1}, 'indices': 2}]}],
       'buffers': [{'byteLength': len(blob)}],
       'bufferViews': [{'buffer': 0, 'byteOffset': 0, 'byteLength': 12 * n},
                       {'buffer': 0, 'byteOffset': 12 * n, 'byteLength': 12 * n},
                       {'buffer': 0, 'byteOffset': 24 * n, 'byteLength': 4 * len(idx)}],
       'accessors': [{'bufferView': 0, 'componentType': 5126, 'count': n, 'type': 'VEC3'},
                     {'bufferView': 1, 'componentType': 5126, 'count': n, 'type': 'VEC3'},
                     {'bufferView': 2, 'componentType': 5125, 'count': len(idx), 'type': 'SCALAR'}]}
js = json.dumps(out).encode()
js += b' ' * (-len(js) % 4)
blob += b'\0' * (-len(blob) % 4)
g = struct.pack('<4sII', b'glTF', 2, 12 + 8 + len(js) + 8 + len(blob)) + struct.pack('<I4s', len(js), b'JSON') + js + \
    struct.pack('<I4s', len(blob), b'BIN\0') + blob
open(sys.argv[2], 'wb').write(g)
print(n, len(idx) // 3)
PY
    "$view" "$tmp/$b.cmz" --png "$tmp/c.png" --size 320x200 --no-edges > /dev/null 2>&1
    if ! "$view" "$tmp/one.glb" --png "$tmp/o.png" --size 320x200 --no-edges > "$tmp/out" 2> "$tmp/err"; then
        bad "$b glb as one primitive: cmz-view failed: $(cat "$tmp/err")"
    elif cmp -s "$tmp/c.png" "$tmp/o.png"; then
        ok "$b glb as one primitive: the .cmz's pixels ($(sed -n 's/.*: \(.*\)/\1/p' "$tmp/out"))"
    else
        bad "$b glb as one primitive: other pixels than the .cmz"
    fi
    head -c 5000 "$tmp/$b.glb" > "$tmp/cut.glb"
    "$view" "$tmp/cut.glb" --png "$tmp/cutg.png" > /dev/null 2> "$tmp/err"
    st=$?
    if [ $st -eq 1 ] && [ ! -e "$tmp/cutg.png" ] && grep -q "glTF\|GLB" "$tmp/err"; then
        ok "$b glb: a GLB cut short is refused: $(head -c 200 "$tmp/err")"
    else
        bad "$b glb: a GLB cut short: exit $st, $(cat "$tmp/err")"
    fi
done

# --frames N: the same picture (the frame drawn N times over), the summary saying its mean time;
# a count out of range refused by name
m=$(ls tests/data/*.igs | head -n 1)
b=$(basename "${m%.*}")
"$view" "$tmp/$b.cmz" --png "$tmp/once.png" -q
line=$("$view" "$tmp/$b.cmz" --png "$tmp/thrice.png" --frames 3)
"$view" "$tmp/$b.cmz" --png "$tmp/none.png" --frames 0 > /dev/null 2> "$tmp/err"
st=$?
if cmp -s "$tmp/once.png" "$tmp/thrice.png" && grep -Eq ', [0-9]+\.[0-9]{3} ms a frame \(mean of 3\)$' <<< "$line" &&
    [ $st -eq 2 ] && grep -q "from 1 to 10000" "$tmp/err" && [ ! -e "$tmp/none.png" ]; then
    ok "--frames 3 draws the same picture and times it: ${line##*, }"
else
    bad "--frames: '$line', --frames 0 exit $st $(cat "$tmp/err")"
fi

# format 4.12: a step's part named as the file names it (the placed boxes' subfigure "BOX"); a 4.11
# file names none
pb=tests/fuzz/corpus_iges/placed_boxes_144.igs
"$cmz" encode -q "$pb" -o "$tmp/pb.cmz" > /dev/null && "$cmz" encode -q --format 4.11 "$pb" -o "$tmp/pb411.cmz" > /dev/null
named=$("$view" "$tmp/pb.cmz" --png "$tmp/pb.png" --step 2 2>&1)
plain=$("$view" "$tmp/pb411.cmz" --png "$tmp/pb411.png" --step 2 2>&1)
if grep -q "(step 2: BOX)" <<< "$named" && grep -q "(step 2)" <<< "$plain" && cmp -s "$tmp/pb.png" "$tmp/pb411.png"; then
    ok "a step's part is named as the file names it: $(grep -o "(step 2: BOX)" <<< "$named"), a 4.11 file's not"
else
    bad "part names: '$named' / '$plain'"
fi

# a frame beyond the build's: refused by name, exit 2, nothing written
m=$(ls tests/data/*.igs | head -n 1)
b=$(basename "${m%.*}")
"$view" "$tmp/$b.cmz" --png "$tmp/big.png" --size 100000x100 > /dev/null 2> "$tmp/err"
st=$?
if [ $st -eq 2 ] && grep -q "within 1x1" "$tmp/err" && [ ! -e "$tmp/big.png" ]; then
    ok "a frame beyond the build's is refused: $(cat "$tmp/err")"
else
    bad "a frame beyond the build's: exit $st, $(cat "$tmp/err")"
fi
# a damaged file: exit 1, nothing written
head -c 300 "$tmp/$b.cmz" > "$tmp/cut.cmz"
"$view" "$tmp/cut.cmz" --png "$tmp/cut.png" > /dev/null 2> "$tmp/err"
st=$?
if [ $st -eq 1 ] && [ ! -e "$tmp/cut.png" ] && [ -z "$(ls "$tmp" | grep '\.part')" ]; then
    ok "a truncated file is refused: $(head -c 200 "$tmp/err")"
else
    bad "a truncated file: exit $st, $(cat "$tmp/err")"
fi
echo "$((n - fail)) passed, $fail failed"
[ $fail -eq 0 ]
