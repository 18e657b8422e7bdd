#!/usr/bin/env bash
# output_hashes.sh CMZ [MODELS_DIR] > hashes.txt
#
# The bytes the product ships, one line per model: sha256 of the .cmz that
# `cmz encode` writes and of the GLB that `cmz decode` rebuilds from it, for
# every IGES of the shared corpus and every bundled model in tests/data.  A
# refactor that must not change output (issue 12) is proved by running this
# before and after and diffing the two lists.
set -u
cmz=$1 dir=${2:-../shared/models}/iges
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
files=$(ls tests/data/*.igs 2>/dev/null)
if [ -d "$dir" ]; then files="$files $(ls "$dir"/*)"; else echo "# $dir not found: bundled models only" >&2; fi
for f in $files; do
    b=$(basename "$f")
    if ! "$cmz" encode -q "$f" -o "$tmp/m.cmz" > "$tmp/log" 2>&1; then
        echo "$b encode-failed $(tail -n 1 "$tmp/log")"; continue
    fi
    if ! "$cmz" decode -q "$tmp/m.cmz" -o "$tmp/m.glb" > "$tmp/log" 2>&1; then
        echo "$b $(sha256sum < "$tmp/m.cmz" | cut -c1-16) decode-failed"; continue
    fi
    echo "$b $(sha256sum < "$tmp/m.cmz" | cut -c1-16) $(sha256sum < "$tmp/m.glb" | cut -c1-16) $(stat -c %s "$tmp/m.cmz")"
done
