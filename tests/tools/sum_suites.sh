#!/usr/bin/env bash
# sum_suites.sh "CMD1" "CMD2" ... - run TAP suites one after the other, show their lines and end
# with one "N passed, N failed" over all of them (what run_suites.sh counts for a gate).
set -u
pass=0 fail=0
for cmd in "$@"; do
    out=$(bash -c "$cmd" 2>&1)
    rc=$?
    grep -vE '^[0-9]+ passed, [0-9]+ failed$' <<<"$out"
    s=$(grep -E '^[0-9]+ passed, [0-9]+ failed$' <<<"$out" | tail -n 1)
    if [ -n "$s" ]; then
        p=${s%% *} f=${s#*, }
        pass=$((pass + p)) fail=$((fail + ${f%% *}))
    fi
    if [ $rc -ne 0 ] && { [ -z "$s" ] || [ "${f%% *}" = 0 ]; }; then
        echo "not ok - '$cmd' exited with status $rc"
        fail=$((fail + 1))
    fi
done
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
