#!/usr/bin/env bash
# bench_link.sh CMZ TERMINAL RELAY OUTDIR MODEL.cmz... - how fast the link moves a model: `cmz send`
# -> cmz-terminal over two ptys joined by tests/tools/pty_relay, per model and line:
#   pty        unpaced, the sender told 4000000 baud (what the protocol and the processes cost),
#   115200     paced like a real 115200 baud line (10 bits a byte: 11520 B/s at most),
#   115200+2%  the same with 1 % dropped and 1 % corrupted bytes each way.
# Reports seconds, payload bytes per second and, on the paced lines, the share of the line rate
# that was payload.  Times on a shared machine are noisy: compare within one run.
set -u
cmz=$1 term=$2 relay=$3 out=$4
shift 4
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null; wait 2>/dev/null; rm -rf "$tmp"' EXIT
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
        rm -f "$tmp/a" "$tmp/b"
        "$relay" --link-a "$tmp/a" --link-b "$tmp/b" "${args[@]}" > /dev/null 2>&1 &
        rp=$!
        for _ in $(seq 100); do [ -e "$tmp/b" ] && break; sleep 0.05; done
        mkdir -p "$tmp/out"
        "$term" --serial "$tmp/b" --out "$tmp/out" -q 2> /dev/null &
        tp=$!
        t0=$(date +%s.%N)
        spec=$tmp/a
        [ "$line" = pty ] && spec=$tmp/a:4000000 # the sender paces itself to the baud it is told
        res=$("$cmz" send "$m" --serial "$spec" --timeout 30 2>&1)
        rc=$?
        t1=$(date +%s.%N)
        kill $tp $rp 2>/dev/null
        wait $tp $rp 2>/dev/null
        chunks=$(sed -n 's/.*(\([0-9]*\) chunks, \([0-9]*\) sent again.*/\1 (\2)/p' <<<"$res")
        final=$(grep -o 'chunk size now [0-9]*' <<<"$res" | tail -n 1 | grep -o '[0-9]*$')
        [ $rc -eq 0 ] || chunks="failed: $(tail -n 1 <<<"$res")"
        awk -v n="$(basename "$m" .cmz)" -v s="$size" -v l="$line" -v a="$t0" -v b="$t1" -v c="$chunks" -v f="${final:-1024}" 'BEGIN {
            t = b - a; r = s / t
            share = (l == "pty") ? "-" : sprintf("%.0f %%", 100 * r / 11520)
            printf "| %s | %d | %s | %.2f | %.0f | %s | %s | %s |\n", n, s, l, t, r, share, c, f }'
    done
done | tee "$out/link.md"
