#!/usr/bin/env bash
# demo.sh CMZ CMZ_DECODE MODEL.igs OUTDIR - the main job on one model, as a user runs it
# (writes OUTDIR/demo.cmz, OUTDIR/demo.glb and OUTDIR/demo.faces.tsv):
# the workstation compresses the IGES file, the terminal's decoder (heap-free, terminal
# profile) rebuilds it into a binary glTF a viewer opens.  Prints what happened and the sizes.
set -euo pipefail
cmz=$1 dec=$2 model=$3 out=$4
mkdir -p "$out"
name=demo
cmzfile=$out/$name.cmz glb=$out/$name.glb
echo "== 1. workstation: cmz encode (IGES -> curve mesh -> .cmz, refused if a terminal could not load it)"
"$cmz" encode "$model" -o "$cmzfile" --profile terminal --report "$out/$name.faces.tsv"
echo "== 2. terminal: cmz-decode (.cmz -> surfaces -> triangles -> glTF), profile terminal"
"$dec" "$cmzfile" -o "$glb"
igs=$(stat -c %s "$model")
gz=$(gzip -9 -c "$model" | wc -c)
xz=$(xz -9 -c "$model" | wc -c)
cz=$(stat -c %s "$cmzfile")
echo "== 3. sizes"
awk -v i="$igs" -v g="$gz" -v x="$xz" -v c="$cz" 'BEGIN {
    printf "  %-22s %10d bytes\n", "IGES", i
    printf "  %-22s %10d bytes  (%.1fx)\n", "gzip -9 of the IGES", g, i / g
    printf "  %-22s %10d bytes  (%.1fx)\n", "xz -9 of the IGES", x, i / x
    printf "  %-22s %10d bytes  (%.1fx; %.1fx smaller than xz)\n", ".cmz", c, i / c, x / c }'
echo "== output: $glb (open it in any glTF viewer, e.g. https://gltf-viewer.donmccurdy.com)"
