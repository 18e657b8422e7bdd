#!/usr/bin/env bash
# bench_view.sh CMZ_VIEW OUTDIR [AARCH64_CMZ_VIEW] - the viewer's frame cost (issue 17) on the
# models `make bench` encoded into OUTDIR: each .cmz the terminal decodes is drawn by cmz-view at
# 800 x 480 (iso, with edges), and callgrind counts the instructions of the drawing alone
# (cm_view_*: camera, triangles, edges; not the decode, nor the PNG file), stable where wall time is
# not.  Prints a Markdown table (README's "The viewer's frame cost") with the instructions per frame
# and per triangle; writes OUTDIR/view.tsv.  With the aarch64 build, the 100 k-triangle frames are
# also timed under qemu-aarch64 (cmz-view --frames 5: the mean wall time of drawing alone), a rough
# guide to a board's (qemu-user translates each instruction; a real core is faster).
set -u
view=$1 out=$2 arm=${3:-}
qemu=()
if [ -n "$arm" ]; then
    if ! command -v qemu-aarch64 > /dev/null || [ ! -x "$arm" ]; then
        echo "bench_view.sh: no qemu-aarch64 or no $arm: the frames are not timed on aarch64" >&2
        arm=
    elif [ -e /usr/lib/aarch64-linux-gnu/libc.so.6 ]; then qemu=(qemu-aarch64); else qemu=(qemu-aarch64 -L /usr/aarch64-linux-gnu); fi
fi
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

# The issue's yardstick: a frame of 100 k triangles.  Each model drawn again from a finer chordal
# tolerance (--tess MM, refined until the frame has 95 to 110 k triangles, at most eight tries, else
# the try with the fewest from 95 to 130 k: some models' counts jump; a model whose triangles do not
# grow, all planes, is left out), its instructions counted the same way, and scaled to 100 k
# triangles (per triangle x 100 000: the counts are near it).
echo
if [ -n "$arm" ]; then
    echo "| model | --tess mm | triangles | instructions per frame | per 100 k triangles | qemu-aarch64 ms a frame |"
    echo "|---|---:|---:|---:|---:|---:|"
else
    echo "| model | --tess mm | triangles | instructions per frame | per 100 k triangles |"
    echo "|---|---:|---:|---:|---:|"
fi
tsv100=$out/view100k.tsv
printf 'model\ttess\ttriangles\tframe_instr\tqemu_aarch64_ms\n' > "$tsv100"
for c in "$out"/*.cmz; do
    name=$(basename "${c%.cmz}")
    case "$name" in *.j1 | *.j2 | *.terminal | link-*) continue ;; esac
    # (the triangles go as a power of the tolerance, about -1 for curved faces: each try aims at
    # 102 k along the power measured between the last two, within [-2, -0.3])
    t=0.1 tris= lastt= lastn= bestt= bestn=
    for try in 1 2 3 4 5 6 7 8; do
        line=$("$view" "$c" --tess "$t" --png "$out/view.png" 2> /dev/null) || { tris=; break; }
        tris=$(sed -n 's/.*, \([0-9]*\) triangles (.*/\1/p' <<< "$line")
        [ -n "$tris" ] && [ "$tris" -gt 0 ] || { tris=; break; }
        if [ "$tris" -ge 95000 ] && [ "$tris" -le 130000 ] && { [ -z "$bestn" ] || [ "$tris" -lt "$bestn" ]; }; then
            bestt=$t bestn=$tris
        fi
        [ "$tris" -ge 95000 ] && [ "$tris" -le 110000 ] && break
        # (a tenfold finer tolerance that adds under a tenth: planes, or the curves already fine)
        if [ -n "$lastn" ] && [ "$tris" -lt $((lastn + lastn / 10)) ] && [ "$tris" -lt 95000 ] &&
            awk -v a="$t" -v b="$lastt" 'BEGIN { exit !(a < b / 5) }'; then tris=; break; fi
        nt=$(awk -v t="$t" -v n="$tris" -v pt="$lastt" -v pn="$lastn" 'BEGIN {
            k = -1
            if (pt != "" && pn > 0 && pt != t && pn != n) k = log(n / pn) / log(t / pt)
            k = k > -0.3 ? -0.3 : (k < -2 ? -2 : k)
            f = exp(log(102000 / n) / k); f = f < 0.01 ? 0.01 : (f > 100 ? 100 : f)
            printf "%.6g", t * f }')
        lastt=$t lastn=$tris t=$nt
    done
    [ -n "$bestn" ] || continue
    t=$bestt tris=$bestn
    instr=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null --toggle-collect='cm_view_*' \
        "$view" "$c" --tess "$t" --png "$out/view.png" 2>&1 | sed -n 's/.*Collected : \([0-9]*\).*/\1/p')
    [ -n "$instr" ] || continue
    ms=
    if [ -n "$arm" ]; then
        ms=$("${qemu[@]}" "$arm" "$c" --tess "$t" --png "$out/view.png" --frames 5 2> /dev/null |
            sed -n 's/.*, \([0-9.]*\) ms a frame (mean of .*/\1/p')
    fi
    printf '%s\t%s\t%s\t%s\t%s\n' "$name" "$t" "$tris" "$instr" "$ms" >> "$tsv100"
    awk -v n="$name" -v s="$t" -v t="$tris" -v i="$instr" -v a="$arm" -v ms="$ms" \
        'BEGIN { printf "| %s | %s | %d | %.1f M | %.1f M |", n, s, t, i / 1e6, i / t * 1e5 / 1e6
                 if (a != "") printf " %s |", (ms == "" ? "-" : ms); printf "\n" }'
done
rm -f "$out/view.png"
# (the median of the qemu times, where there are any)
msmed=$(awk -F'\t' 'NR > 1 && $5 != "" { print $5 }' "$tsv100" | sort -g |
    awk '{ r[NR] = $1 } END { if (NR) printf "%.1f", (NR % 2 ? r[(NR + 1) / 2] : (r[NR / 2] + r[NR / 2 + 1]) / 2) }')
awk -F'\t' 'NR > 1 { print $4 / $3 * 1e5 / 1e6 }' "$tsv100" | sort -g |
    awk -v a="$arm" -v ms="$msmed" '{ r[NR] = $1 } END { if (NR) printf "| **median** (%d models), **worst** | | | | %.1f M, %.1f M |%s\n", NR, (NR % 2 ? r[(NR + 1) / 2] : (r[NR / 2] + r[NR / 2 + 1]) / 2), r[NR], (a != "" ? " " (ms == "" ? "-" : ms) " |" : "") }'
