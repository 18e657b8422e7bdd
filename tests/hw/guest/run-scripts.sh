#!/usr/bin/env bash
# run-scripts.sh SCRIPT... - runs INSIDE the test VM: each tests/hw/vm-*.sh
# in turn, under its own timeout, renumbering their TAP lines into one
# stream ("ok 7 - vm-gpio: ...").  Everything else a script prints becomes a
# "# " comment.  A script that exits non-zero without a "not ok" line, or
# times out, adds one failure, so a crash or a hang is never silent.
# Env: HW_SCRIPT_TIMEOUT (seconds per script, default 120).
set -u
limit=${HW_SCRIPT_TIMEOUT:-120}
n=0
for script in "$@"; do
    name=$(basename "$script" .sh)
    echo "# ---- $name"
    start=$(date +%s%N)
    failed_here=0
    exec 3< <(timeout -k 5 "$limit" bash "$script" 2>&1; echo "HW-SCRIPT-EXIT $?")
    rc=125
    while IFS= read -r line <&3; do
        case $line in
        "HW-SCRIPT-EXIT "*) rc=${line#HW-SCRIPT-EXIT } ;;
        "ok "[0-9]* | "not ok "[0-9]*)
            n=$((n + 1))
            status=${line%%[0-9]*}               # "ok " or "not ok "
            rest=${line#"$status"}
            rest=${rest#"${rest%%[!0-9]*}"}       # drop the script's own number
            rest=${rest# }
            case $rest in
            "# "* | "#"*) echo "${status}${n} ${rest}" ;;  # "ok N # SKIP ..."
            *) echo "${status}${n} - $name: ${rest#- }" ;;
            esac
            [ "$status" = "ok " ] || failed_here=1
            ;;
        "#"*) echo "$line" ;;
        *) echo "# $line" ;;
        esac
    done
    exec 3<&-
    ms=$(( ($(date +%s%N) - start) / 1000000 ))
    if [ "$rc" = 124 ] || [ "$rc" = 137 ]; then
        n=$((n + 1)); echo "not ok $n - $name: timed out after $limit s (killed)"
    elif [ "$rc" != 0 ] && [ $failed_here = 0 ]; then
        n=$((n + 1)); echo "not ok $n - $name: exited with status $rc without reporting a failure"
    fi
    echo "# $name took $ms ms"
done
