#!/usr/bin/env bash
# bench.sh CMZ CMZ_DECODE OUTDIR MODEL... - size, speed and memory of the whole job per model.
#
# For every model: the IGES size, what gzip -9 and xz -9 make of it, the .cmz size and the
# ratios; faces by method (plane / gregory / gregory-exact / gregory-fit / g1fit / nfill / kept) and the share whose surface was deleted; the
# largest §12 error ratio over rebuilt faces and the worst G1 angle on their tangent edges (from
# the encoder's --report, which measures with the decoder's code); encode time (workstation, host profile); decode time of the
# terminal's decoder (terminal profile, to .glb; best of 3 runs, tests/tools/wall_min); its peak resident memory;
# triangles; and, with BENCH_CALLGRIND=1, the decoder's instruction count under callgrind
# (stable where wall time is noisy).  Times on a shared machine are noisy: compare ratios
# within one run.  Writes OUTDIR/bench.tsv and prints a Markdown table (README's).
set -u
cmz=$1 dec=$2 out=$3
shift 3
mkdir -p "$out"
tsv=$out/bench.tsv
printf 'model\tiges_bytes\tgzip9\txz9\tcmz_bytes\tx_iges\tx_gzip\tx_xz\tfaces\tplane\tkeep\tenc_s\tdec_s\tdec_rss_kib\ttriangles\tdec_instr\tterminal\tgregory\tdeleted_pct\tmax_ratio_pct\tg1_worst_deg\tgregory_exact\tgregory_fit\tnfill\tg1fit\n' > "$tsv"
now() { date +%s.%N; } # encode times (seconds: the shell's few ms do not matter there)
wall_min=${WALL_MIN:-}
[ -x "$wall_min" ] || { echo "bench: WALL_MIN (tests/tools/wall_min) not built (make bench builds it)" >&2; exit 2; }
for m in "$@"; do
    name=$(basename "${m%.*}")
    # a model in both forms (o3dv__as1_pe_203.igs and .stp) gets two names: their outputs must not meet
    case "${m##*.}" in stp|STP|step|STEP) name=${name}.stp ;; esac
    c=$out/$name.cmz g=$out/$name.glb
    t0=$(now)
    if ! enc=$("$cmz" encode -q "$m" -o "$c" --report "$out/$name.faces.tsv" 2>&1); then
        echo "# $name: encode failed: $(tail -n 1 <<<"$enc")" >&2
        continue
    fi
    t1=$(now)
    # the terminal's decoder; a model over its limits is refused before its body is read: then the
    # workstation's decoder (host profile, same code) stands in for the timings, and the table says why
    term=ok
    run=("$dec")
    if ! decout=$("$dec" "$c" -o "$g" 2>&1); then
        term=$(sed -n 's/.*needs \([A-Z_]*=[0-9]*\), this build (profile terminal) has \([0-9]*\).*/\1 > \2/p' <<<"$decout")
        [ -n "$term" ] || term="failed"
        run=("$cmz" decode)
        # encoded for the terminal instead (--profile: curves and surfaces re-fitted, a coarser
        # recommended tolerance): does the terminal load that file?
        tc=$out/$name.terminal.cmz
        if "$cmz" encode -q "$m" -o "$tc" --profile terminal > /dev/null 2>&1 && "$dec" "$tc" -o "$out/$name.terminal.glb" > /dev/null 2>&1; then
            term="$term; --profile terminal: loads, $(stat -c %s "$tc") bytes"
        else
            term="$term; --profile terminal: refused"
        fi
    fi
    if ! decout=$("${run[@]}" "$c" -o "$g" 2>&1); then
        echo "# $name: decode failed: $decout" >&2
        continue
    fi
    # the best of 3 wall times, fork to wait (tests/tools/wall_min: no shell `date` inside the time)
    best=$("$wall_min" 3 -- "${run[@]}" "$c" -o "$g") || { echo "# $name: decode failed when timed" >&2; continue; }
    rss=-
    if [ -x /usr/bin/time ]; then
        rss=$(/usr/bin/time -f %M "${run[@]}" "$c" -o "$g" 2>&1 >/dev/null | tail -n 1)
    fi
    instr=-
    if [ "${BENCH_CALLGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
        instr=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null "${run[@]}" "$c" -o "$g" 2>&1 |
                sed -n 's/.*Collected : \([0-9]*\).*/\1/p')
        [ -n "$instr" ] || instr=-
    fi
    igs=$(stat -c %s "$m") gz=$(gzip -9 -c "$m" | wc -c) xz=$(xz -9 -c "$m" | wc -c) cz=$(stat -c %s "$c")
    # the summary line counts faces by method in the table's order: read each by its name
    # (a method's count ends at ',' or ')', and "N kept" at ';' where the parts follow: format 4.11)
    count() { sed -n "s/.*[(,] *\([0-9]*\) $1[,;)].*/\1/p" <<<"$enc"; }
    faces=$(sed -n 's/.*: \([0-9]*\) faces (.*/\1/p' <<<"$enc")
    [ -z "$faces" ] || faces="$faces $(count plane) $(count kept) $(count gregory) $(count gregory-exact) $(count gregory-fit) $(count nfill) $(count g1fit)"
    # over the rebuilt faces: the largest ratio (column 9) and the worst G1 angle (column 13)
    read -r mr g1 < <(awk -F'\t' 'NR > 1 && $5 != "keep" { if ($9 > r) r = $9; if ($13 > g) g = $13 }
                                  END { printf "%.4g %.3g\n", 100 * r, g }' "$out/$name.faces.tsv")
    tris=$(sed -n 's/.*faces\( ([^)]*)\)\{0,1\}, \([0-9]*\) triangles.*/\2/p' <<<"$decout")
    read -r nf np nk ng ne nfit nfill ng1 <<<"$faces"
    [ -n "$nf" ] || { echo "bench: cannot read the summary of $name: $enc" >&2; exit 1; }
    awk -v n="$name" -v i="$igs" -v g="$gz" -v x="$xz" -v c="$cz" -v nf="$nf" -v np="$np" -v nk="$nk" -v ng="$ng" -v ne="$ne" -v nfit="$nfit" -v nfill="$nfill" -v ng1="$ng1" \
        -v mr="$mr" -v g1="$g1" \
        -v te="$(echo "$t1 - $t0" | bc)" -v td="$best" -v rss="$rss" -v tr="$tris" -v ins="$instr" -v term="$term" 'BEGIN {
        printf "%s\t%d\t%d\t%d\t%d\t%.1f\t%.1f\t%.1f\t%d\t%d\t%d\t%.3f\t%.3f\t%s\t%d\t%s\t%s\t%d\t%.1f\t%s\t%s\t%d\t%d\t%d\t%d\n",
               n, i, g, x, c, i / c, g / c, x / c, nf, np, nk, te, td, rss, tr, ins, term, ng,
               (nf > 0 ? 100 * (nf - nk) / nf : 0), mr, g1, ne, nfit, nfill, ng1 }' >> "$tsv"
done
# the Markdown table
awk -F'\t' 'NR == 1 {
        print "| model | IGES | gzip -9 | xz -9 | .cmz | ×IGES | ×gzip | ×xz | faces (plane/gregory/exact/fit/g1fit/nfill/kept) | deleted | max ratio | worst G1 | encode s | decode s | decode RSS MiB | triangles | terminal profile |" (ENVIRON["BENCH_CALLGRIND"] == 1 ? " decode Minstr |" : "")
        print "|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---|" (ENVIRON["BENCH_CALLGRIND"] == 1 ? "---:|" : "")
        next }
    { rss = $14 == "-" ? "-" : sprintf("%.1f", $14 / 1024)
      ins = $16 == "-" ? "" : sprintf(" %.1f |", $16 / 1e6)
      printf "| %s | %d | %d | %d | %d | %.1f | %.1f | %.1f | %d (%d/%d/%d/%d/%d/%d/%d) | %.0f %% | %s %% | %s° | %.2f | %.3f | %s | %d | %s |%s\n",
             $1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $18, $22, $23, $25, $24, $11, $19, $20, $21, $12, $13, rss, $15, ($17 == "ok" ? "loads" : "refused: " $17 " (host decoder timed)"), ins
      si += $2; sg += $3; sx += $4; sc += $5; d[++n] = $19 }
    END { for (a = 2; a <= n; a++) for (b = a; b > 1 && d[b] < d[b - 1]; b--) { t = d[b]; d[b] = d[b - 1]; d[b - 1] = t }
          med = n % 2 ? d[(n + 1) / 2] : (d[n / 2] + d[n / 2 + 1]) / 2
          if (sc > 0) printf "| **all** | %d | %d | %d | %d | %.1f | %.1f | %.1f | | median %.0f %% | | | | | | | |\n", si, sg, sx, sc, si / sc, sg / sc, sx / sc, med }' "$tsv"
echo "(written to $tsv)"

# one model on two cores (cmz encode -j 2, issue 15.4): each model encoded with one process and with
# two, paired, without --report (the table above times the encode with its per-face mesh measure);
# the files must be the same bytes
echo
echo "| model | encode -j 1 s | encode -j 2 s | -j 1 / -j 2 | same bytes |"
echo "|---|---:|---:|---:|---|"
s1=0 s2=0
for m in "$@"; do
    name=$(basename "${m%.*}")
    case "${m##*.}" in stp|STP|step|STEP) name=${name}.stp ;; esac
    t0=$(now)
    "$cmz" encode -q "$m" -o "$out/$name.j1.cmz" -j 1 > /dev/null 2>&1 || continue
    t1=$(now)
    "$cmz" encode -q "$m" -o "$out/$name.j2.cmz" -j 2 > /dev/null 2>&1 || continue
    t2=$(now)
    same=yes
    cmp -s "$out/$name.j1.cmz" "$out/$name.j2.cmz" || same="**no**"
    a=$(echo "$t1 - $t0" | bc) b=$(echo "$t2 - $t1" | bc)
    s1=$(echo "$s1 + $a" | bc) s2=$(echo "$s2 + $b" | bc)
    awk -v n="$name" -v a="$a" -v b="$b" -v s="$same" 'BEGIN { printf "| %s | %.2f | %.2f | %.2f | %s |\n", n, a, b, a / b, s }'
done
awk -v a="$s1" -v b="$s2" 'BEGIN { if (b > 0) printf "| **all** | %.1f | %.1f | %.2f | |\n", a, b, a / b }'

