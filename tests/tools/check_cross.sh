#!/usr/bin/env bash
# check_cross.sh BUILD_ROOT NATIVE_VECTORS PREFIX... - cross-architecture gate.
#
# For each cross prefix (aarch64-linux-gnu-, arm-linux-gnueabihf-): run the
# unit tests of that build (host and terminal profiles) under qemu-user,
# and diff its kernel_vectors output against this machine's, which must be
# bit-identical (spec §2: encoder on x86-64, decoder on ARM).
# qemu runs without -L when the target's multiarch libc is installed (the
# cross sysroot's ld.so mixed with the multiarch libc spins forever), with
# -L /usr/<triplet> otherwise.
set -u
root=$1 native=$2
shift 2
here=$(cd "$(dirname "$0")" && pwd)
suites=()
native_out=$(mktemp)
trap 'rm -f "$native_out" "$native_out".*' EXIT
"$native" > "$native_out" || { echo "check-cross: native kernel_vectors failed"; exit 1; }
for prefix in "$@"; do
    triplet=${prefix%-}
    case "$triplet" in
    aarch64-*) qemu=qemu-aarch64 ;;
    arm-*) qemu=qemu-arm ;;
    *) echo "check-cross: no qemu known for $triplet"; exit 1 ;;
    esac
    command -v "$qemu" >/dev/null || { echo "check-cross: $qemu not installed (make deps)"; exit 1; }
    if [ -e "/usr/lib/$triplet/libc.so.6" ]; then runner="$qemu"; else runner="$qemu -L /usr/$triplet"; fi
    for prof in host terminal; do
        dir="$root/$triplet-$prof/tests/unit"
        suites+=("$triplet-$prof:$dir")
    done
    vec="$root/$triplet-host/tests/unit/kernel_vectors"
    suites+=("gate:bit-identical-$triplet:$runner $vec > $native_out.$triplet && diff -u $native_out $native_out.$triplet")
    export "RUNNER_$(echo "$triplet" | tr -c 'a-z0-9\n' '_')=$runner"
done
# each architecture's suites under its own emulator, the architectures side by side (qemu-user is
# single-threaded and these are minutes each); the output in the order given
run_arch() { # triplet: its suites, one summary line each
    local t=$1 s out summary label var
    for s in "${suites[@]}"; do
        case "$s" in
        gate:bit-identical-$t:*) out=$("$here/run_suites.sh" --quiet "$s") ;;
        "$t"-host:* | "$t"-terminal:*)
            var="RUNNER_$(echo "$t" | tr -c 'a-z0-9\n' '_')"
            out=$(RUNNER="${!var}" "$here/run_suites.sh" --quiet "$s")
            ;;
        *) continue ;;
        esac
        summary=$(tail -n 1 <<<"$out")
        echo "$out" | sed '$d'
        label=${s#gate:}
        echo "  ${label%%:*}: $summary"
    done
}
triplets=()
for prefix in "$@"; do triplets+=("${prefix%-}"); done
for t in "${triplets[@]}"; do run_arch "$t" > "$native_out.run.$t" 2>&1 & done
wait
pass=0
fail=0
for t in "${triplets[@]}"; do
    cat "$native_out.run.$t"
    while read -r p f; do
        pass=$((pass + p)); fail=$((fail + f))
    done < <(sed -n 's/^  [^ ]*: \([0-9]*\) passed, \([0-9]*\) failed$/\1 \2/p' "$native_out.run.$t")
done
# a suite that printed no summary (crashed runner) counts as a failure
expected=${#suites[@]}
got=$(cat "${triplets[@]/#/$native_out.run.}" | grep -cE '^  [^ ]*: [0-9]+ passed, [0-9]+ failed$')
[ "$got" -eq "$expected" ] || { echo "check-cross: $((expected - got)) suite(s) gave no summary"; fail=$((fail + expected - got)); }
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
