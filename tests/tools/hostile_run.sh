#!/usr/bin/env bash
# hostile_run.sh CMZ CMZ_DECODE MUTATE OUTDIR TRIES [--tap]
#
# The hostile-input run of README ("Hostile input"): every family of tests/tools/mutate.c, TRIES
# variants of each seed model, each answered by the workstation (`cmz encode` for IGES, `cmz decode`
# for .cmz) and, for .cmz, by the terminal's decoder (`cmz-decode`, terminal profile).  Every run
# has 30 s (a hang is a failure).  Each answer is one of:
#   accepted   exit 0, and the output is a whole file (magic and length check out)
#   clean      exit 1-4 with a message that names the place in the input (IGES: "line N" or "DE N";
#              .cmz: "byte N"); "unplaced" counts the clean errors that name no place
#   crash      a signal, a sanitizer report or any other exit status
#   hang       still running after 30 s
#   data lost  the previous output file was changed by a failed run, or a temporary file was left
# Prints a Markdown table; exits 1 if there is any crash, hang or lost data.  --tap: TAP lines too.
set -u
CMZ=$1 DEC=$2 MUT=$3 OUT=$4 TRIES=$5 TAP=${6:-}
here=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$OUT"
rm -rf "${OUT:?}"/run && mkdir -p "$OUT/run"
LIMIT=30

iges_seeds=("$here"/tests/fuzz/corpus_iges/box_hole_144.igs "$here"/tests/fuzz/corpus_iges/box_hole_186.igs
    "$here"/tests/fuzz/corpus_iges/split_cylinder_144.igs "$here"/tests/fuzz/corpus_iges/bicubic_128_inch.igs
    "$here"/tests/data/geo_example.igs "$here"/tests/data/as1_pe_203.igs)
[ -n "${HOSTILE_SEEDS:-}" ] && read -r -a iges_seeds <<< "$HOSTILE_SEEDS"
cmz_seeds=()
for s in "${iges_seeds[@]}"; do
    c="$OUT/$(basename "${s%.*}").cmz"
    if ! "$CMZ" encode -q "$s" -o "$c" > /dev/null 2>&1; then
        echo "hostile_run: the seed $s does not encode" >&2
        exit 1
    fi
    cmz_seeds+=("$c")
done

SENTINEL="previous output: must survive a failed run"
declare -A tries accepted clean unplaced crash hang lost slowest
fail=0 kept=0

# whole_file KIND PATH: 0 if PATH is a complete output of its kind (a .cmz: its magic, and its last 4
# bytes the CRC-32 of all before them, as every format's trailer is)
whole_file() {
    case $1 in
    cmz) python3 -c 'import sys, zlib
b = open(sys.argv[1], "rb").read()
sys.exit(0 if len(b) >= 8 and b[:4] == b"\x89CMZ" and zlib.crc32(b[:-4]) == int.from_bytes(b[-4:], "little") else 1)' "$2" ;;
    glb) [ "$(head -c 4 "$2")" = "glTF" ] && [ "$(od -An -tu4 -j8 -N4 "$2" | tr -d ' ')" = "$(stat -c %s "$2")" ] ;;
    esac
}

# judge FAMILY TOOL INPUT KIND PLACE_RE CMD...: one run, counted under FAMILY/TOOL
judge() {
    local fam=$1 tool=$2 input=$3 kind=$4 place=$5
    shift 5
    local key="$fam|$tool" out="$OUT/run/out.$kind"
    printf '%s' "$SENTINEL" > "$out"
    local t0 t1 rc
    t0=$(date +%s%N)
    timeout -s KILL $LIMIT "$@" > "$OUT/run/stdout" 2> "$OUT/run/stderr"
    rc=$?
    t1=$(date +%s%N)
    local secs
    secs=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", (b - a) / 1e9 }')
    tries[$key]=$((${tries[$key]:-0} + 1))
    awk -v s="$secs" -v m="${slowest[$key]:-0}" 'BEGIN { exit !(s > m) }' && slowest[$key]=$secs
    local verdict
    if [ $rc -eq 137 ]; then
        verdict=hang
    elif grep -q -e 'runtime error' -e 'AddressSanitizer' -e 'LeakSanitizer' "$OUT/run/stderr"; then
        verdict=crash
    elif [ $rc -eq 0 ]; then
        if whole_file "$kind" "$out"; then verdict=accepted; else verdict=lost; fi
    elif [ $rc -ge 1 ] && [ $rc -le 4 ] && [ -s "$OUT/run/stderr" ]; then
        if [ "$(cat "$out")" != "$SENTINEL" ]; then
            verdict=lost
        else
            verdict=clean
            grep -Eq "$place" "$OUT/run/stderr" || unplaced[$key]=$((${unplaced[$key]:-0} + 1))
        fi
    else
        verdict=crash
    fi
    # nothing half-written may stay behind
    if [ -n "$(find "$OUT/run" -mindepth 1 ! -name stdout ! -name stderr ! -name "out.$kind" | head -1)" ]; then
        verdict=lost
    fi
    case $verdict in
    accepted) accepted[$key]=$((${accepted[$key]:-0} + 1)) ;;
    clean) clean[$key]=$((${clean[$key]:-0} + 1)) ;;
    crash) crash[$key]=$((${crash[$key]:-0} + 1)) ;;
    hang) hang[$key]=$((${hang[$key]:-0} + 1)) ;;
    lost) lost[$key]=$((${lost[$key]:-0} + 1)) ;;
    esac
    if [ "$verdict" = crash ] || [ "$verdict" = hang ] || [ "$verdict" = lost ]; then
        fail=1
        mkdir -p "$OUT/failures"
        cp "$input" "$OUT/failures/$fam-${tool// /_}-$((++kept))-$(basename "$input")"
        echo "hostile_run: $verdict: $fam $tool $(basename "$input") (exit $rc, ${secs}s): $(head -c 300 "$OUT/run/stderr")" >&2
    fi
    rm -f "$OUT"/run/*
}

IGES_FAMILIES=(iges-truncate iges-flip iges-number iges-pointer iges-directory iges-lines)
CMZ_FAMILIES=(cmz-truncate cmz-flip cmz-flip-crc cmz-header cmz-table cmz-needs)
order=()
seed=0
for fam in "${IGES_FAMILIES[@]}"; do
    order+=("$fam|cmz encode")
    for s in "${iges_seeds[@]}"; do
        for ((i = 0; i < TRIES; i++)); do
            seed=$((seed + 1))
            in="$OUT/mut.igs"
            "$MUT" "$fam" $seed "$s" "$in" || exit 1
            judge "$fam" "cmz encode" "$in" cmz 'line [0-9]+|DE [0-9]+' "$CMZ" encode -q "$in" -o "$OUT/run/out.cmz"
        done
    done
done
for fam in "${CMZ_FAMILIES[@]}"; do
    order+=("$fam|cmz decode" "$fam|cmz-decode")
    for s in "${cmz_seeds[@]}"; do
        for ((i = 0; i < TRIES; i++)); do
            seed=$((seed + 1))
            in="$OUT/mut.cmz"
            "$MUT" "$fam" $seed "$s" "$in" || exit 1
            judge "$fam" "cmz decode" "$in" glb 'byte [0-9]+' "$CMZ" decode -q "$in" -o "$OUT/run/out.glb"
            judge "$fam" "cmz-decode" "$in" glb 'byte [0-9]+' "$DEC" "$in" -o "$OUT/run/out.glb"
        done
    done
done

echo "| family | tool | tries | accepted | clean errors | naming no place | crashes | hangs | data lost | slowest |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"
for key in "${order[@]}"; do
    fam=${key%%|*} tool=${key#*|}
    printf '| %s | `%s` | %d | %d | %d | %d | %d | %d | %d | %s s |\n' "$fam" "$tool" "${tries[$key]:-0}" \
        "${accepted[$key]:-0}" "${clean[$key]:-0}" "${unplaced[$key]:-0}" "${crash[$key]:-0}" "${hang[$key]:-0}" \
        "${lost[$key]:-0}" "${slowest[$key]:-0}"
done
if [ "$TAP" = --tap ]; then
    np=0 nf=0
    for key in "${order[@]}"; do
        fam=${key%%|*} tool=${key#*|}
        bad=$((${crash[$key]:-0} + ${hang[$key]:-0} + ${lost[$key]:-0}))
        if [ $bad -eq 0 ]; then
            echo "ok - hostile $fam ($tool): ${tries[$key]:-0} tries, no crash, hang or lost data"
            np=$((np + 1))
        else
            nf=$((nf + 1))
            echo "not ok - hostile $fam ($tool): $bad crashes, hangs or lost outputs (inputs kept in $OUT/failures)"
        fi
    done
    echo "$np passed, $nf failed"
fi
exit $fail
