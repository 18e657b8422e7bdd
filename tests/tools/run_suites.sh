#!/usr/bin/env bash
# run_suites.sh [--quiet] SUITE... - run test suites, count results, print "N passed, N failed".
#
# SUITE is one of
#   LABEL:DIR            every DIR/test_* binary (cmocka, TAP output); with
#                        $RUNNER set (e.g. qemu-aarch64) they run under it
#   gate:NAME:COMMAND    one shell command that passes when it exits 0
# A test binary that crashes or exits non-zero without reporting a failure
# counts as one failure, so a crash is never silent.  Exit status: 0 iff
# nothing failed.  --quiet prints only failures and the summary line
# (used by nested runs, whose summary the outer run parses).
set -u
quiet=0
if [ "${1:-}" = --quiet ]; then quiet=1; shift; fi
pass=0
fail=0
skipped=0
failed_names=()
say() { [ $quiet -eq 1 ] || echo "$@"; }

run_binary() { # label path
    local label=$1 bin=$2 out rc np nf
    out=$(CMOCKA_MESSAGE_OUTPUT=TAP ${RUNNER:-} "$bin" 2>&1)
    rc=$?
    np=$(grep -c '^ok ' <<<"$out")
    # cmocka reports skip() as "not ok N # SKIP name": neither a pass nor a failure
    ns=$(grep -c '^not ok [0-9]* # SKIP' <<<"$out")
    nf=$(( $(grep -c '^not ok ' <<<"$out") - ns ))
    skipped=$((skipped + ns))
    if [ "$rc" -ne 0 ] && [ "$nf" -eq 0 ]; then
        nf=1
        failed_names+=("$label/$(basename "$bin") (exit $rc)")
        echo "$out" | tail -n 20
    fi
    if [ "$nf" -gt 0 ]; then
        while read -r l; do failed_names+=("$label/$(basename "$bin"): ${l#not ok }"); done \
            < <(grep '^not ok ' <<<"$out" | grep -v '^not ok [0-9]* # SKIP')
        grep -B2 -A8 '^not ok ' <<<"$out" | head -n 60
    fi
    pass=$((pass + np))
    fail=$((fail + nf))
    say "  $label/$(basename "$bin"): $np passed, $nf failed$([ "$ns" -gt 0 ] && echo ", $ns skipped")"
}

for s in "$@"; do
    case "$s" in
    gate:*)
        rest=${s#gate:}
        name=${rest%%:*}
        cmd=${rest#*:}
        say "== gate $name"
        t0=$SECONDS
        if out=$(bash -c "$cmd" 2>&1); then
            # a nested suite reports its own counts; a plain gate counts as one test
            if summary=$(grep -E '^[0-9]+ passed, [0-9]+ failed$' <<<"$out" | tail -n 1) && [ -n "$summary" ]; then
                pass=$((pass + ${summary%% *}))
            else
                pass=$((pass + 1))
            fi
            [ $quiet -eq 1 ] || echo "$out" | grep -vE '^[0-9]+ passed, [0-9]+ failed$' | tail -n 15
            say "  gate $name: ok ($((SECONDS - t0)) s)"
        else
            if summary=$(grep -E '^[0-9]+ passed, [0-9]+ failed$' <<<"$out" | tail -n 1) && [ -n "$summary" ]; then
                p=${summary%% *}; f=${summary#*, }; f=${f%% *}
                pass=$((pass + p)); fail=$((fail + (f > 0 ? f : 1)))
            else
                fail=$((fail + 1))
            fi
            failed_names+=("gate $name")
            # name every failing test inside the gate, however deep its suites nest and however
            # long its output: the last lines alone often show only a summary (issue 11)
            nested=$(grep -E '^not ok ' <<<"$out" | grep -vE '^not ok [0-9]* *# SKIP')
            if [ -n "$nested" ]; then
                while read -r l; do failed_names+=("  gate $name: ${l#not ok }"); done <<<"$nested"
                echo "$nested" | sed 's/^/  /'
                echo "  ..."
            fi
            echo "$out" | tail -n 40
            echo "  gate $name: FAILED ($((SECONDS - t0)) s)"
        fi
        ;;
    *:*)
        label=${s%%:*}
        dir=${s#*:}
        say "== $label ($dir)"
        found=0
        for bin in "$dir"/test_*; do
            [ -x "$bin" ] && [ -f "$bin" ] || continue
            case "$bin" in *.o | *.d | *.su | *.ci) continue ;; esac
            found=1
            run_binary "$label" "$bin"
        done
        if [ $found -eq 0 ]; then
            fail=$((fail + 1))
            failed_names+=("$label: no test binaries in $dir")
        fi
        ;;
    esac
done

if [ ${#failed_names[@]} -gt 0 ]; then
    echo "failures:"
    printf '  %s\n' "${failed_names[@]}"
fi
[ "$skipped" -gt 0 ] && echo "$skipped skipped (see SKIP lines above)"
[ $quiet -eq 1 ] || echo "# took $SECONDS s"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
