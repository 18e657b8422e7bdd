#!/usr/bin/env bash
# check_three.sh CMZ CMZ_VIEW SHARED_MODELS - what the terminal shows against an independent glTF
# renderer (issue 17): each model is encoded, decoded to GLB by `cmz decode`, drawn by cmz-view
# (iso, 800 x 480, --camera, faces only) and by three.js in headless Chromium with the same camera
# (tests/tools/three_check.py): the silhouettes must overlap (intersection over union >= 0.98) and
# each face region's mean colour match the face's colour.  The bundled models always; with the
# shared corpus, models with colours, placed copies and B-spline hulls too.  A negative control
# runs first: the same picture against three.js turned upside down (the camera's right and up
# reversed) must fail, so that a comparison that cannot fail is caught.  Needs chromium and
# libjs-three (Debian; `make deps`).  One TAP line per check; "N passed, N failed" last.
set -u
cmz=$1 view=$2 shared=${3:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
here=$(dirname "$0")
n=0 fail=0
ok() { n=$((n + 1)); echo "ok $n - $*"; }
bad() { n=$((n + 1)); fail=$((fail + 1)); echo "not ok $n - $*"; }
if ! command -v chromium > /dev/null || [ ! -f /usr/share/javascript/three/three.min.js ]; then
    bad "chromium and three.js (Debian packages chromium, libjs-three) are not installed: make deps"
    echo "$((n - fail)) passed, $fail failed"
    exit 1
fi
models=(tests/data/as1_pe_203.igs tests/data/geo_example.igs)
if [ -n "$shared" ] && [ -d "$shared" ]; then
    for m in asitus___C1G0B0O__CDB0.IGS elif__Motor_case_back.IGS ovt__ship_kvlcc2.igs; do
        [ -f "$shared/iges/$m" ] && models+=("$shared/iges/$m")
    done
else
    echo "# ../shared/models absent: the bundled models only"
fi
first=1
for m in "${models[@]}"; do
    name=$(basename "${m%.*}")
    w=$tmp/$name
    mkdir -p "$w"
    if ! "$cmz" encode -q "$m" -o "$w/m.cmz" > "$w/log" 2>&1 || ! "$cmz" decode "$w/m.cmz" -o "$w/m.glb" >> "$w/log" 2>&1; then
        bad "$name: encode or decode failed: $(tail -n 1 "$w/log")"
        continue
    fi
    # (without the edge lines: three.js draws the GLB's triangles only, and a line along a thin
    # model's outline widens it by a pixel: geo_example's silhouettes overlapped 0.97 with them)
    if ! cam=$("$view" "$w/m.cmz" --png "$w/ours.png" --camera --no-edges -q 2>&1); then
        bad "$name: cmz-view failed: $cam"
        continue
    fi
    if [ $first = 1 ]; then
        first=0
        # the negative control: right and up reversed (the picture turned half round)
        flipped=$(awk '{ for (i = 8; i <= 13; i++) $i = -$i; print }' <<< "$cam")
        out=$(python3 "$here/three_check.py" "$w/m.glb" "$w/ours.png" "$flipped" "$w" 2>&1)
        rc=$?
        if [ $rc = 1 ]; then
            ok "$name: a picture turned upside down does not pass ($(head -n 1 <<< "$out"))"
        else
            bad "$name: the upside-down control passed or did not run (status $rc): $(tr '\n' ' ' <<< "$out")"
        fi
    fi
    out=$(python3 "$here/three_check.py" "$w/m.glb" "$w/ours.png" "$cam" "$w" 2>&1)
    if [ $? = 0 ]; then
        ok "$name: cmz-view and three.js agree: $(head -n 2 <<< "$out" | tr '\n' ' ')"
    else
        bad "$name: $(tr '\n' ' ' <<< "$out")"
    fi
done
echo "$((n - fail)) passed, $fail failed"
[ $fail -eq 0 ]
