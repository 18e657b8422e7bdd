#!/usr/bin/env bash
# gate_selftest.sh CC NM STACK_CHECK TMPDIR - prove the gates can fail.
#
# A gate that never fails asserts nothing: compile fixtures with recursion,
# an oversized frame, malloc and printf, and require check_stack and
# check_noheap.sh to reject them, naming the culprit.
set -u
cc=$1 nm=$2 stack=$3 tmp=$4
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$tmp"
fail=0
(cd "$tmp" && $cc -std=c11 -O0 -fcallgraph-info=su -c "$here/fixtures/bad_recursion.c" -o bad_recursion.o) || exit 1
out=$("$stack" --fn-max 8192 --budget 65536 "$tmp/bad_recursion.ci")
if [ $? -eq 0 ]; then echo "stack gate accepted recursion"; fail=1; fi
grep -q 'recursion: fixture_depth' <<<"$out" || { echo "stack gate did not name the recursion: $out"; fail=1; }
grep -Eq 'fixture_big uses (19|20)[0-9]{3} bytes' <<<"$out" || { echo "stack gate did not name the big frame: $out"; fail=1; }
# an indirect call: refused unless a table says where it goes; then its deepest callee counts; a table
# line for a caller that calls through no pointer is stale
(cd "$tmp" && $cc -std=c11 -O0 -fcallgraph-info=su -c "$here/fixtures/bad_indirect.c" -o bad_indirect.o) || exit 1
out=$("$stack" --fn-max 8192 --budget 65536 "$tmp/bad_indirect.ci")
if [ $? -eq 0 ]; then echo "stack gate accepted an indirect call"; fail=1; fi
grep -q 'fixture_caller makes an indirect call' <<<"$out" || { echo "stack gate did not name the indirect call: $out"; fail=1; }
printf 'fixture_caller: fixture_small fixture_deep\n' > "$tmp/indirect.txt"
out=$("$stack" --fn-max 8192 --budget 4096 --indirect "$tmp/indirect.txt" "$tmp/bad_indirect.ci")
if [ $? -eq 0 ]; then echo "stack gate missed the indirect callee's frame"; fail=1; fi
grep -q 'fixture_caller([0-9]*) fixture_deep(' <<<"$out" && grep -q 'exceeds CM_STACK_BUDGET 4096' <<<"$out" || { echo "stack gate did not count the callee: $out"; fail=1; }
printf 'fixture_small: fixture_deep\n' > "$tmp/indirect.txt"
out=$("$stack" --fn-max 8192 --budget 65536 --indirect "$tmp/indirect.txt" "$tmp/bad_indirect.ci")
if [ $? -eq 0 ]; then echo "stack gate accepted a stale indirect table"; fail=1; fi
grep -q 'fixture_small makes no indirect call' <<<"$out" || { echo "stack gate did not name the stale line: $out"; fail=1; }
# static RAM over its budget: named with its size
$cc -std=c11 -O2 "$here/fixtures/bad_ram.c" -o "$tmp/bad_ram" || exit 1
out=$("$here/check_ram.sh" size "$nm" 0 100000 "$tmp/bad_ram")
if [ $? -eq 0 ]; then echo "ram gate accepted 300 kB over a 100 kB budget"; fail=1; fi
grep -q "not ok 1 - $tmp/bad_ram: data + bss 3[0-9]\{5\} bytes" <<<"$out" || { echo "ram gate did not name the program's size: $out"; fail=1; }
$cc -std=c11 -O2 -c "$here/fixtures/bad_heap.c" -o "$tmp/bad_heap.o" || exit 1
rm -f "$tmp/bad_heap.a" && ar rcs "$tmp/bad_heap.a" "$tmp/bad_heap.o"
out=$("$here/check_noheap.sh" "$nm" "$tmp/bad_heap.a" "$here/noheap_allow.txt")
if [ $? -eq 0 ]; then echo "no-heap gate accepted malloc"; fail=1; fi
grep -qx '  malloc' <<<"$out" || { echo "no-heap gate did not name malloc: $out"; fail=1; }
grep -Eqx '  (printf|puts)' <<<"$out" || { echo "no-heap gate did not name stdio: $out"; fail=1; }
# the runner: a test failing two suites deep, above 60 lines of other output, is still named in the
# final "failures:" list (a full gate once ended "1532 passed, 1 failed" naming only the gate)
printf '%s\n' 'echo "ok 1 - fine"' 'echo "not ok 2 - the deeply nested test"' \
    'for i in $(seq 60); do echo "# other output $i"; done' 'echo "1 passed, 1 failed"' 'exit 1' > "$tmp/inner.sh"
out=$("$here/run_suites.sh" "gate:outer:$here/sum_suites.sh --parallel \"$here/sum_suites.sh 'bash $tmp/inner.sh'\"")
if [ $? -eq 0 ]; then echo "runner passed a failing nested test"; fail=1; fi
sed -n '/^failures:/,$p' <<<"$out" | grep -q 'gate outer: 2 - the deeply nested test' ||
    { echo "runner did not name the nested failing test: $out"; fail=1; }
[ $fail -eq 0 ] && echo "gate self-test: recursion, 20 kB frame, an unresolved or stale indirect call, static RAM over its budget, malloc and stdio are all rejected; a nested failure is named"
exit $fail
