#!/usr/bin/env bash
# bench_view.sh CMZ_VIEW OUTDIR - the viewer's frame cost (issue 17) on the models `make bench`
# encoded into OUTDIR: each .cmz the terminal decodes is drawn by cmz-view at 800 x 480 (iso, with
# edges), and callgrind counts the instructions of the drawing alone (cm_view_*: camera, triangles,
# edges; not the decode, nor the PNG file), stable where wall time is not.  Prints a Markdown
# table (README's "The viewer's frame cost") with the instructions per frame and per triangle;
# writes OUTDIR/view.tsv.
set -u
view=$1 out=$2
tsv=$out/view.tsv
printf 'model\ttriangles\tframe_instr\n' > "$tsv"
echo "| model | triangles | instructions per frame | per triangle |"
echo "|---|---:|---:|---:|"
for c in "$out"/*.cmz; do
    name=$(basename "${c%.cmz}")
    case "$name" in *.j1 | *.j2 | *.terminal | link-*) continue ;; esac
    line=$("$view" "$c" --png "$out/view.png" 2> /dev/null) || continue # (over the terminal's limits)
    tris=$(sed -n 's/.*, \([0-9]*\) triangles (.*/\1/p' <<< "$line")
    instr=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null --toggle-collect='cm_view_*' \
        "$view" "$c" --png "$out/view.png" 2>&1 | sed -n 's/.*Collected : \([0-9]*\).*/\1/p')
    [ -n "$tris" ] && [ -n "$instr" ] || continue
    printf '%s\t%s\t%s\n' "$name" "$tris" "$instr" >> "$tsv"
    awk -v n="$name" -v t="$tris" -v i="$instr" 'BEGIN { printf "| %s | %d | %.1f M | %.0f |\n", n, t, i / 1e6, (t > 0 ? i / t : 0) }'
done
rm -f "$out/view.png"
awk -F'\t' 'NR > 1 && $2 > 0 { print $3 / $2 }' "$tsv" | sort -g |
    awk '{ r[NR] = $1 } END { if (NR) printf "| **median** (%d models) | | | %.0f |\n", NR, (NR % 2 ? r[(NR + 1) / 2] : (r[NR / 2] + r[NR / 2 + 1]) / 2) }'
