#!/usr/bin/env bash
# bench_link.sh CMZ TERMINAL RELAY OUTDIR MODEL.cmz... - how fast and how reliably the link moves a
# model: `cmz send` -> cmz-terminal over two ptys joined by tests/tools/pty_relay.
#
# 1. Speed, per model and line:
#      pty        unpaced, the sender told 4000000 baud (what the protocol and the processes cost),
#      115200     paced like a real 115200 baud line (10 bits a byte: 11520 B/s at most),
#      115200+2%  the same with 1 % dropped and 1 % corrupted bytes each way.
#    Reports seconds, payload bytes per second and, on the paced lines, the share of the line rate
#    that was payload; final chunk: the size the sender last changed to ("-": it kept its first one:
#    1024 on a clean serial line, 16 or 32 when the HELLO already came through damaged frames).
# 2. The fault matrix: BENCH_LINK_RUNS (10) transfers per row, the models in turn, unpaced, each one
#    a fresh `cmz send` to a terminal restarted on the same output directory (as after a reboot):
#      rows      0 %, 1 %, 5 % dropped and as many corrupted bytes each way (relay --drop P --flip P),
#                and a hang-up of the terminal's line mid-transfer (a different byte each run,
#                plugged in again after 300 ms)
#      columns   intact (exit 0, model.cmz identical to the file sent), failed (cmz send exit != 0),
#                wrong model stored (model.cmz neither the file sent nor, after a failure, the
#                previous one: must be 0), median seconds of the intact ones
#    About 3 minutes on a 2-core machine, most of it the 5 % row.
# Times on a shared machine are noisy: compare within one run.  Both tables go to OUTDIR/link.md.
set -u
cmz=$1 term=$2 relay=$3 out=$4
shift 4
runs=${BENCH_LINK_RUNS:-10}
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null; wait 2>/dev/null; rm -rf "$tmp"' EXIT

# start_pair ARGS...: a relay with ARGS and a terminal on $tmp/out; sets rp, tp (0: the relay did not come up)
start_pair() {
    rm -f "$tmp/a" "$tmp/b"
    "$relay" --link-a "$tmp/a" --link-b "$tmp/b" --timeout 600 "$@" > /dev/null 2> "$tmp/relay.log" &
    rp=$!
    for _ in $(seq 400); do [ -e "$tmp/b" ] && [ -e "$tmp/a" ] && break; sleep 0.05; done
    mkdir -p "$tmp/out"
    "$term" --serial "$tmp/b" --out "$tmp/out" -q 2>> "$tmp/term.log" &
    tp=$!
    [ -e "$tmp/b" ]
}
stop_pair() {
    kill "$tp" "$rp" 2> /dev/null
    wait "$tp" "$rp" 2> /dev/null
}

{
echo "| model | bytes | line | seconds | payload B/s | of the line rate | chunks sent (again) | final chunk |"
echo "|---|---:|---|---:|---:|---:|---:|---:|"
for m in "$@"; do
    size=$(stat -c %s "$m")
    for line in pty 115200 115200+2%; do
        args=()
        case $line in
        115200) args=(--baud 115200) ;;
        115200+2%) args=(--baud 115200 --drop 0.01 --flip 0.01 --seed 5) ;;
        esac
        rm -rf "$tmp/out"
        start_pair "${args[@]}"
        t0=$(date +%s.%N)
        spec=$tmp/a
        [ "$line" = pty ] && spec=$tmp/a:4000000 # the sender paces itself to the baud it is told
        res=$("$cmz" send "$m" --serial "$spec" --timeout 30 2>&1)
        rc=$?
        t1=$(date +%s.%N)
        stop_pair
        chunks=$(sed -n 's/.*(\([0-9]*\) chunks, \([0-9]*\) sent again.*/\1 (\2)/p' <<<"$res")
        final=$(grep -o 'chunk size now [0-9]*' <<<"$res" | tail -n 1 | grep -o '[0-9]*$')
        [ $rc -eq 0 ] || chunks="failed: $(tail -n 1 <<<"$res")"
        awk -v n="$(basename "$m" .cmz)" -v s="$size" -v l="$line" -v a="$t0" -v b="$t1" -v c="$chunks" -v f="${final:--}" 'BEGIN {
            t = b - a; r = s / t
            share = (l == "pty") ? "-" : sprintf("%.0f %%", 100 * r / 11520)
            printf "| %s | %d | %s | %.2f | %.0f | %s | %s | %s |\n", n, s, l, t, r, share, c, f }'
    done
done

models=("$@")
echo
echo "| line (each way) | transfers | intact | failed | wrong model stored | median s (intact) |"
echo "|---|---:|---:|---:|---:|---:|"
for row in 0 1 5 hangup; do
    rm -rf "$tmp/out"
    prev=
    intact=0 failed=0 wrong=0
    : > "$tmp/times"
    for i in $(seq 1 "$runs"); do
        m=${models[$(((i - 1) % ${#models[@]}))]}
        size=$(stat -c %s "$m")
        case $row in
        hangup) args=(--hangup-after $((size * (i % 9 + 1) / 10)) --reopen-ms 300) ;;
        *) p=$(awk -v r="$row" 'BEGIN { printf "%.2f", r / 100 }'); args=(--drop "$p" --flip "$p" --seed "$i") ;;
        esac
        if ! start_pair "${args[@]}"; then
            failed=$((failed + 1))
            stop_pair
            continue
        fi
        t0=$(date +%s.%N)
        timeout 300 "$cmz" send "$m" --serial "$tmp/a:4000000" --timeout 30 -q > "$tmp/send.log" 2>&1
        rc=$?
        t1=$(date +%s.%N)
        stop_pair
        got=$tmp/out/model.cmz
        if [ $rc -eq 0 ] && cmp -s "$got" "$m"; then
            intact=$((intact + 1))
            awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f\n", b - a }' >> "$tmp/times"
            prev=$m
        elif [ $rc -eq 0 ]; then
            wrong=$((wrong + 1)) # it said delivered, and the terminal shows something else
        else
            failed=$((failed + 1))
            echo "# $row, run $i ($(basename "$m")): exit $rc: $(tail -n 1 "$tmp/send.log")" >&2
            # a failed send leaves the model shown before it, or none yet: never a third one
            if [ -e "$got" ] && ! cmp -s "$got" "$m" && { [ -z "$prev" ] || ! cmp -s "$got" "$prev"; }; then
                wrong=$((wrong + 1))
            fi
            cmp -s "$got" "$m" && prev=$m # stored and shown, though the sender did not hear it
        fi
    done
    median=$(sort -n "$tmp/times" | awk '{ v[NR] = $1 } END { if (NR == 0) print "-"; else if (NR % 2) print v[(NR + 1) / 2]; else printf "%.2f\n", (v[NR / 2] + v[NR / 2 + 1]) / 2 }')
    case $row in
    hangup) label="hang-up mid-transfer, plugged in after 0.3 s" ;;
    *) label="$row % dropped + $row % corrupted" ;;
    esac
    echo "| $label | $runs | $intact | $failed | $wrong | $median |"
done
} | tee "$out/link.md"
