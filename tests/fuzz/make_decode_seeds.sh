#!/usr/bin/env bash
# make_decode_seeds.sh CMZ - rewrite tests/fuzz/corpus_decode from the IGES seeds (see README.md)
# (the *_chunk*.cmzf seeds only; found_* and crc_* are fuzzers' finds: after a format change, refind
# them with make fuzz-decode / make fuzz-decode-crc)
set -euo pipefail
cmz=${1:?usage: make_decode_seeds.sh path/to/cmz}
here=$(cd "$(dirname "$0")" && pwd)
out=$here/corpus_decode
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out"
for f in "$here"/corpus_iges/box_hole_144.igs "$here"/corpus_iges/box_hole_186.igs \
         "$here"/corpus_iges/half_cylinder_120.igs "$here"/corpus_iges/bicubic_128_inch.igs \
         "$here"/corpus_iges/split_cylinder_144.igs "$here"/corpus_iges/bump_128.igs \
         "$here"/corpus_iges/t_vertex_cylinder_144.igs "$here"/corpus_iges/l_shape_144.igs \
         "$here"/corpus_iges/dome_square_hole_144.igs "$here"/corpus_iges/placed_boxes_144.igs \
         "$here"/../data/as1_pe_203.igs "$here"/../data/geo_example.igs \
         "$here"/corpus_step/band_no_seam_turned.stp; do
    # (the STEP band's cut meets its top circle half a turn round: a corner hint, format 4.13)
    b=$(basename "$f"); b=${b%.*}
    "$cmz" encode -q "$f" -o "$tmp/$b.cmz"
    # the two sampled methods: these faces are G1FIT by default, NFILL without it
    case $b in l_shape_144|dome_square_hole_144) "$cmz" encode -q --no-g1fit "$f" -o "$tmp/${b}_nfill.cmz" ;; esac
    # and the same in format 4.13 (K7 for every Gregory side), 4.12 (no corner hints), 4.11 (parts without names), 4.10 (no parts after the colours), 4.9 (GREGORY patches scaled as before
    # 4.10), 4.8 (kept faces meshed as before 4.9), 4.7 (the refinement before
    # 4.8's predictions), 4.6 (the refinement before 4.7's), 4.5 (the varint header, a stream per
    # section), 4.4 (edge uses named by `back`), 4.2 (no placed copies), 4.1 (no net corrections),
    # 4.0's header, format 3's fixed one and format 2's coding (format 4.14 is the default): every
    # reader's path
    "$cmz" encode -q --format 4.13 "$f" -o "$tmp/${b}_v413.cmz"
    "$cmz" encode -q --format 4.12 "$f" -o "$tmp/${b}_v412.cmz"
    "$cmz" encode -q --format 4.11 "$f" -o "$tmp/${b}_v411.cmz"
    "$cmz" encode -q --format 4.10 "$f" -o "$tmp/${b}_v410.cmz"
    "$cmz" encode -q --format 4.9 "$f" -o "$tmp/${b}_v49.cmz"
    "$cmz" encode -q --format 4.8 "$f" -o "$tmp/${b}_v48.cmz"
    "$cmz" encode -q --format 4.7 "$f" -o "$tmp/${b}_v47.cmz"
    "$cmz" encode -q --format 4.6 "$f" -o "$tmp/${b}_v46.cmz"
    "$cmz" encode -q --format 4.5 "$f" -o "$tmp/${b}_v45.cmz"
    "$cmz" encode -q --format 4.4 "$f" -o "$tmp/${b}_v44.cmz"
    "$cmz" encode -q --format 4.2 "$f" -o "$tmp/${b}_v42.cmz"
    "$cmz" encode -q --format 4.1 "$f" -o "$tmp/${b}_v41.cmz"
    "$cmz" encode -q --format 4.0 "$f" -o "$tmp/${b}_v40.cmz"
    "$cmz" encode -q --format 3 "$f" -o "$tmp/${b}_v3.cmz"
    "$cmz" encode -q --format 2.6 "$f" -o "$tmp/${b}_v2.cmz"
    for c in "$tmp/$b.cmz" "$tmp/${b}_nfill.cmz" "$tmp/${b}_v413.cmz" "$tmp/${b}_v412.cmz" "$tmp/${b}_v411.cmz" "$tmp/${b}_v410.cmz" "$tmp/${b}_v49.cmz" "$tmp/${b}_v48.cmz" "$tmp/${b}_v47.cmz" "$tmp/${b}_v46.cmz" "$tmp/${b}_v45.cmz" "$tmp/${b}_v44.cmz" "$tmp/${b}_v42.cmz" "$tmp/${b}_v41.cmz" "$tmp/${b}_v40.cmz" "$tmp/${b}_v3.cmz" "$tmp/${b}_v2.cmz"; do
        [ -f "$c" ] || continue
        for sel in 0 200; do
            { printf "\\x$(printf %02x $sel)"; cat "$c"; } > "$out/$(basename "$c" .cmz)_chunk$sel.cmzf"
        done
    done
done
