#!/usr/bin/env bash
# check_decode_cross.sh CMZ BUILD_ROOT MODELS_DIR - the terminal's decoder on ARM, and its limits.
#
# 1. Every model of the bundled set and the shared corpus is encoded on this
#    machine and decoded to GLB by cmz-decode built for x86-64 and for aarch64
#    (run under qemu-user) with the terminal profile, and by `cmz decode` for
#    both (the host profile: the same decoder, the workstation's limits): the
#    GLB files must be byte-identical (spec §2: binary64 and no contraction
#    everywhere), and a model the terminal refuses must be refused the same
#    way on both.  The terminal decoder built at -O0 must give the same bytes
#    too.  Each decoder checks every GREGORY face's checksum against the one
#    the x86-64 -O2 encoder wrote (spec §17 T11): a differing rebuild fails.
# 2. The tiny profile must refuse a real model within its header (at a byte
#    offset below 200) with CM_E_LIMIT naming the limit, the need and the
#    build's value, and write nothing.
# One TAP line per check; "N passed, N failed" last.
set -u
cmz=$1 root=$2 dir=${3:-../shared/models}/iges
native=$(cc -dumpmachine)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ -e /usr/lib/aarch64-linux-gnu/libc.so.6 ]; then qemu=(qemu-aarch64); else qemu=(qemu-aarch64 -L /usr/aarch64-linux-gnu); fi
n=0 fail=0
ok() { n=$((n + 1)); echo "ok $n - $*"; }
bad() { n=$((n + 1)); fail=$((fail + 1)); echo "not ok $n - $*"; }

models=(tests/data/*.igs)
if [ -d "$dir" ]; then models+=("$dir"/*); else echo "# $dir not found: bundled models only"; fi
# one model in its own directory: its result lines ("ok - ..."/"not ok - ...") in $w/out
one_model() {
    local m=$1 w=$2 b xs as prof x86 arm
    mkdir -p "$w"
    exec > "$w/out" 2>&1
    ok() { echo "ok - $*"; }
    bad() { echo "not ok - $*"; }
    b=$(basename "${m%.*}")
    if ! "$cmz" encode -q "$m" -o "$w/$b.cmz" > /dev/null 2> "$w/err"; then
        bad "$b: encode failed: $(tail -n 1 "$w/err")"
        return
    fi
    for prof in terminal host; do
        if [ $prof = terminal ]; then
            x86=("$root/$native-terminal/cmz-decode") arm=("${qemu[@]}" "$root/aarch64-linux-gnu-terminal/cmz-decode")
        else
            x86=("$root/$native-host/cmz" decode -q) arm=("${qemu[@]}" "$root/aarch64-linux-gnu-host/cmz" decode -q)
        fi
        "${x86[@]}" "$w/$b.cmz" -o "$w/x.glb" > /dev/null 2> "$w/xe"
        xs=$?
        "${arm[@]}" "$w/$b.cmz" -o "$w/a.glb" > /dev/null 2> "$w/ae"
        as=$?
        if [ $xs -ne $as ]; then
            bad "$b ($prof): exit $xs on x86-64, $as on aarch64: $(cat "$w/ae")"
        elif [ $xs -ne 0 ]; then
            if [ "$prof" = terminal ] && grep -q CM_E_LIMIT "$w/xe" && cmp -s "$w/xe" "$w/ae"; then
                ok "$b ($prof): refused alike: $(sed 's/.*(CM_E_LIMIT): //' "$w/xe")"
            else
                bad "$b ($prof): decode failed: $(cat "$w/xe")"
            fi
        elif [ $prof = terminal ] && ! "$root/O0/$native-terminal/cmz-decode" "$w/$b.cmz" -o "$w/o.glb" \
                > /dev/null 2> "$w/oe"; then
            bad "$b ($prof): the -O0 build failed: $(cat "$w/oe")"
        elif [ $prof = terminal ] && ! cmp -s "$w/x.glb" "$w/o.glb"; then
            bad "$b ($prof): GLB differs between -O2 and -O0 ($(cmp "$w/x.glb" "$w/o.glb" | head -n 1))"
        elif cmp -s "$w/x.glb" "$w/a.glb"; then
            ok "$b ($prof): GLB byte-identical on aarch64$([ $prof = terminal ] && echo " and at -O0") ($(stat -c %s "$w/x.glb") bytes)"
        else
            bad "$b ($prof): GLB differs between x86-64 and aarch64 ($(cmp "$w/x.glb" "$w/a.glb" | head -n 1))"
        fi
        rm -f "$w/x.glb" "$w/a.glb" "$w/o.glb"
    done
}
# two models at a time (2 cores; each is a serial pipeline of one encode and five decodes, two of
# them under qemu), the lines numbered in the corpus order
jobs_max=${DECODE_CROSS_JOBS:-2}
k=0
for m in "${models[@]}"; do
    k=$((k + 1))
    while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n; done
    one_model "$m" "$tmp/m$k" &
done
wait
for i in $(seq 1 "$k"); do
    while IFS= read -r line; do
        case $line in
        "ok - "*) ok "${line#ok - }" ;;
        "not ok - "*) bad "${line#not ok - }" ;;
        *) echo "# $line" ;;
        esac
    done < "$tmp/m$i/out"
    grep -qE '^(not )?ok - ' "$tmp/m$i/out" || bad "$(basename "${models[$((i - 1))]}"): no result (the check crashed)"
done

# the tiny profile refuses a real model before its body, naming the limit
tiny=$root/$native-tiny/cmz-decode
"$cmz" encode -q tests/data/as1_pe_203.igs -o "$tmp/as1.cmz" > /dev/null 2>&1
rm -f "$tmp/t.glb"
"$tiny" "$tmp/as1.cmz" -o "$tmp/t.glb" > /dev/null 2> "$tmp/te"
st=$?
msg=$(cat "$tmp/te")
if [ $st -eq 1 ] && grep -q 'CM_E_LIMIT' <<<"$msg" && grep -q 'this build (profile tiny) has' <<<"$msg" &&
   grep -Eq 'byte ([0-9]|[1-9][0-9]|1[0-9][0-9]):' <<<"$msg" && [ ! -e "$tmp/t.glb" ]; then
    ok "tiny profile refuses as1_pe_203 after its header: $msg"
else
    bad "tiny profile: exit $st, '$msg'"
fi
echo "$((n - fail)) passed, $fail failed"
[ $fail -eq 0 ]
