#!/usr/bin/env bash
# check_bundled_roundtrip.sh CMZ CMZ_DECODE MESH_CHECK CMZ_HEADER MODEL.igs... - the product end to end on the
# models bundled in tests/data (make test's quick round trip; the shared corpus is make check's):
# cmz encode -> the terminal build's cmz-decode -> GLB and STL, the mesh welded and closed where
# the model is (mesh_check), every rebuilt face within its tolerance (cmz eval), and the triangles
# the terminal made exactly those the header declares (the MAX_TRIS need the encoder measured with
# the same code: a decoder bounds a model's work by it); and the output written as a whole, fsynced
# before its rename only with --sync (strace, from make deps, watches), the same bytes either way.
# One TAP line per model; stands alone without ../shared.
set -u
cmz=$1 decode=$2 mesh_check=$3 cmz_header=$4
shift 4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
n=0 fail=0
size() { stat -c %s "$1" 2>/dev/null || echo 0; }
# MAX_TRIS's id: its line in --limits (the need table's order); its need read from the header by
# cmz_header (tests/tools/cmz_header.c: the header of any format, 4.6's stream with the reader's code)
tris_id=$("$cmz" --limits | awk 'NR > 2 && $1 == "MAX_TRIS" { print NR - 3; exit }')
declared_tris() { "$cmz_header" need "$1" "$tris_id"; }
for f in "$@"; do
    n=$((n + 1))
    b=$(basename "$f")
    why=""
    if ! "$cmz" encode -q "$f" -o "$tmp/m.cmz" > "$tmp/enc" 2>&1; then
        why="encode: $(tail -n 1 "$tmp/enc")"
    elif ! "$decode" "$tmp/m.cmz" -o "$tmp/m.glb" > "$tmp/dec" 2>&1 ||
         ! "$decode" "$tmp/m.cmz" -o "$tmp/m.stl" >> "$tmp/dec" 2>&1; then
        why="cmz-decode: $(tail -n 1 "$tmp/dec")"
    elif made=$(sed -n 's/.* \([0-9]*\) triangles.*/\1/p' "$tmp/dec" | head -n 1) &&
         [ "$made" != "$(declared_tris "$tmp/m.cmz")" ]; then
        why="the terminal made ${made:-no} triangles, the header declares $(declared_tris "$tmp/m.cmz") (MAX_TRIS)"
    elif [ "$(size "$tmp/m.glb")" -eq 0 ] || [ "$(size "$tmp/m.stl")" -lt 284 ]; then
        why="empty output (glb $(size "$tmp/m.glb") bytes, stl $(size "$tmp/m.stl"))"
    elif ! topo=$("$mesh_check" "$tmp/m.cmz" 2>&1); then
        why="mesh_check: $(tail -n 1 <<<"$topo")"
    elif ! ev=$("$cmz" eval -q "$f" "$tmp/m.cmz" 2>&1); then
        why="cmz eval: $(grep -m 2 'eval\|FAILED' <<<"$ev" | tr '\n' ' ')"
    elif ! command -v strace > /dev/null; then
        why="no strace to watch the output's fsync (make deps installs it)"
    elif ! strace -f -e trace=fsync,fdatasync -o "$tmp/sync.0" "$decode" "$tmp/m.cmz" -o "$tmp/n.glb" > /dev/null 2>&1 ||
         ! strace -f -e trace=fsync,fdatasync -o "$tmp/sync.1" "$decode" "$tmp/m.cmz" -o "$tmp/s.glb" --sync > /dev/null 2>&1; then
        why="cmz-decode under strace failed"
    elif grep -q sync "$tmp/sync.0" || ! grep -q '^[0-9]* *fsync(' "$tmp/sync.1"; then
        why="fsync calls: $(grep -c sync "$tmp/sync.0") without --sync, $(grep -c sync "$tmp/sync.1") with (want 0 and 1)"
    elif ! cmp -s "$tmp/m.glb" "$tmp/n.glb" || ! cmp -s "$tmp/m.glb" "$tmp/s.glb"; then
        why="--sync changed the output's bytes"
    fi
    if [ -z "$why" ]; then
        echo "ok $n - $b: encoded $(size "$tmp/m.cmz") bytes, decoded by the terminal build, mesh and rebuild checked"
    else
        echo "not ok $n - $b: $why"
        fail=$((fail + 1))
    fi
done
[ "$n" -gt 0 ] || { echo "not ok 1 - no models given"; n=1; fail=1; }
echo "$((n - fail)) passed, $fail failed"
[ "$fail" -eq 0 ]
