#!/usr/bin/env bash
# check_old_files.sh CMZ CMZ_DECODE DIR - files written by an earlier version (DIR: tests/data/old_formats,
# see its README.md) decode to the very GLB that version's terminal decoder made (DIR/expected.sha256),
# with the terminal's cmz-decode and the workstation's cmz decode.  TAP; ends with "N passed, N failed".
set -u
cmz=$1 decode=$2 dir=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
n=0 fail=0
t() { n=$((n + 1)); if [ "$1" = ok ]; then echo "ok $n - $2"; else echo "not ok $n - $2"; fail=$((fail + 1)); fi; }
[ -s "$dir/expected.sha256" ] || { echo "not ok 1 - no $dir/expected.sha256"; echo "0 passed, 1 failed"; exit 1; }
while read -r want glb; do
    name=${glb%.glb}
    for tool in terminal workstation; do
        if [ $tool = terminal ]; then out=$("$decode" "$dir/$name.cmz" -o "$tmp/$glb" 2>&1); rc=$?
        else out=$("$cmz" decode "$dir/$name.cmz" -o "$tmp/$glb" 2>&1); rc=$?; fi
        got=$([ $rc -eq 0 ] && sha256sum "$tmp/$glb" | cut -d' ' -f1)
        if [ $rc -eq 0 ] && [ "$got" = "$want" ]; then
            t ok "$name.cmz ($tool): the GLB of the version that wrote it"
        else
            t fail "$name.cmz ($tool): rc $rc, sha256 ${got:-none}, expected $want: $(tail -n 1 <<<"$out")"
        fi
        rm -f "$tmp/$glb"
    done
done < "$dir/expected.sha256"
[ $n -gt 0 ] || t fail "no files listed in $dir/expected.sha256"
echo "$((n - fail)) passed, $fail failed"
[ $fail -eq 0 ]
