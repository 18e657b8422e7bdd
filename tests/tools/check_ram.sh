#!/usr/bin/env bash
# check_ram.sh SIZE NM DECODE_BUDGET PROGRAM_BUDGET PROGRAM... - the static RAM of the terminal's
# programs (issue 15.3): each program's data + bss within CM_DECODE_STATE_BUDGET (its one decode
# state) + CM_PROGRAM_STATIC_BUDGET (everything else: link, transports, store, I/O chunks).  Prints
# each program's total, what is not the decode state, and its five largest static objects; exits 1
# when one is over, naming it.  cmz-view's budget is CM_VIEW_BUDGET (CM_VIEW_STATIC_BUDGET) more.  With CM_TEXT_BUDGET set (the aarch64 build: CM_PROGRAM_TEXT_BUDGET),
# also each program's text (code, read-only data and tables, as `size` counts it) within it.  TAP.
set -u
text_budget=${CM_TEXT_BUDGET:-}
size=$1 nm=$2 decode=$3 program=$4
shift 4
view_budget=${CM_VIEW_BUDGET:-0}
n=0 bad=0
for bin in "$@"; do
    n=$((n + 1))
    # cmz-view also holds the viewer's frame: CM_VIEW_STATIC_BUDGET more
    own_budget=$program
    [ "$(basename "$bin")" = cmz-view ] && own_budget=$((program + view_budget))
    budget=$((decode + own_budget))
    read -r data bss < <("$size" -B "$bin" | awk 'NR == 2 { print $2, $3 }')
    if [ -z "${data:-}" ] || [ -z "${bss:-}" ]; then
        echo "not ok $n - $bin: $size gave no data and bss"
        bad=$((bad + 1))
        continue
    fi
    total=$((data + bss))
    state=$("$nm" -S -t d "$bin" | awk '$4 == "state" && ($3 == "b" || $3 == "B") { print $2 + 0 }' | head -1)
    own=$((total - ${state:-0}))
    largest=$("$nm" -S -t d --size-sort "$bin" | awk '$3 ~ /^[bBdD]$/ { printf "%s %d; ", $4, $2 + 0 }' |
        tr ';' '\n' | sed '/^ *$/d' | tail -n 5 | tac | tr '\n' ';')
    msg="$bin: data + bss $total bytes (decode state ${state:-0}, the program's own $own), budget $budget"
    if [ "$total" -le "$budget" ] && [ "$own" -le "$own_budget" ]; then
        echo "ok $n - $msg; largest:$largest"
    else
        echo "not ok $n - $msg: over CM_DECODE_STATE_BUDGET + CM_PROGRAM_STATIC_BUDGET ($decode + $own_budget); largest:$largest"
        bad=$((bad + 1))
    fi
    if [ -n "$text_budget" ]; then
        n=$((n + 1))
        text=$("$size" -B "$bin" | awk 'NR == 2 { print $1 }')
        if [ -n "$text" ] && [ "$text" -le "$text_budget" ]; then
            echo "ok $n - $bin: text $text bytes, budget $text_budget (CM_PROGRAM_TEXT_BUDGET)"
        else
            echo "not ok $n - $bin: text ${text:-?} bytes, over CM_PROGRAM_TEXT_BUDGET ($text_budget)"
            bad=$((bad + 1))
        fi
    fi
    # --limits names the program's own storage part by part: what it leaves unnamed stays small (a new
    # buffer of 32 KiB or more must have its row); a foreign binary (a cross build) is not run
    if named=$("$bin" --limits 2>/dev/null | awk '/^program.s own/ { print $3 }') && [ -n "$named" ]; then
        n=$((n + 1))
        if [ "$named" -le "$own" ] && [ $((own - named)) -lt 32768 ]; then
            echo "ok $n - $bin --limits names $named of its own $own bytes"
        else
            echo "not ok $n - $bin --limits names $named of its own $own bytes: a static buffer of 32 KiB or more has no row"
            bad=$((bad + 1))
        fi
    else
        echo "# $bin --limits not run here (a cross build): its rows are checked natively"
    fi
done
echo "$((n - bad)) passed, $bad failed"
[ $bad -eq 0 ]
