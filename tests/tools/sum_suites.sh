#!/usr/bin/env bash
# sum_suites.sh [--parallel] "CMD1" "CMD2" ... - run TAP suites, show their lines and end with one
# "N passed, N failed" over all of them (what run_suites.sh counts for a gate).  --parallel runs
# them at the same time (their lines still come out in order): for suites that mostly wait (ptys
# paced like a serial line) next to one that computes (the TCG test VM).
set -u
parallel=0
if [ "${1:-}" = --parallel ]; then
    parallel=1
    shift
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
i=0
for cmd in "$@"; do
    i=$((i + 1))
    if [ $parallel -eq 1 ]; then
        { bash -c "$cmd" > "$tmp/$i.out" 2>&1; echo $? > "$tmp/$i.rc"; } &
    else
        bash -c "$cmd" > "$tmp/$i.out" 2>&1
        echo $? > "$tmp/$i.rc"
    fi
done
wait
pass=0 fail=0 i=0
for cmd in "$@"; do
    i=$((i + 1))
    out=$(cat "$tmp/$i.out")
    rc=$(cat "$tmp/$i.rc")
    grep -vE '^[0-9]+ passed, [0-9]+ failed$' <<<"$out"
    s=$(grep -E '^[0-9]+ passed, [0-9]+ failed$' <<<"$out" | tail -n 1)
    f=0
    if [ -n "$s" ]; then
        p=${s%% *} f=${s#*, }
        f=${f%% *}
        pass=$((pass + p)) fail=$((fail + f))
    fi
    if [ "$rc" -ne 0 ] && [ "$f" = 0 ]; then
        echo "not ok - '$cmd' exited with status $rc"
        fail=$((fail + 1))
    fi
done
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
