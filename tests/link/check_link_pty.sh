#!/usr/bin/env bash
# check_link_pty.sh CMZ TERMINAL RELAY CMZ_DECODE [ITERATIONS]
#
# `cmz send` -> `cmz-terminal` over real ptys (the kernel's n_tty line
# discipline at both ends) joined by tests/tools/pty_relay, a bad cable:
#   1. ITERATIONS (50) transfers through 1 % dropped and 1 % corrupted bytes
#      each way, alternating two models: every one arrives byte-identical
#      (model.cmz) and decoded (model.glb identical to CMZ_DECODE's);
#   2. a hang-up mid-transfer (the terminal's pty goes away and comes back):
#      the transfer resumes from the offset the terminal had acknowledged;
#   3. kill -9 of the terminal mid-transfer: the previous model stays intact,
#      a restarted terminal resumes the transfer from its synced prefix;
#   4. `cmz send MODEL.igs` encodes for the limits the terminal announced,
#      through a line that inserts garbage bytes;
#   5. a model over the terminal's limits is refused on the workstation,
#      naming the limit (the tiny profile's terminal, when built); a file of
#      a newer minor version than the terminal reads likewise (5b);
#   6. sigterm_mid_transfer: `kill -TERM` of `cmz send` mid-transfer on a
#      2400 baud line: it exits within a second with 143, and the next send
#      resumes from what the terminal kept;
#   7. the transfer's progress on the status line (`--display`, issue 17): a viewer standing in for
#      cmz-view records what the terminal asks it to draw while a model comes in at 9600 baud:
#      "receiving", then "receiving N %" rising in steps of 10, at most once a second, then the
#      model.
# Waits are measured (poll for the state, with a wide deadline), not fixed
# sleeps: the suite must pass on a machine busy with another build.
# TERMINAL may be prefixed by an emulator through $TERMINAL_EMU (qemu-aarch64).
set -u
cmz=$1 term=$2 relay=$3 dec=$4 iters=${5:-50}
emu=${TERMINAL_EMU:-}
tmp=$(mktemp -d)
pids=()
cleanup() {
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
    wait 2>/dev/null
    rm -rf "$tmp"
}
trap cleanup EXIT
n=0 fail=0
ok() { n=$((n + 1)); echo "ok $n - $*"; }
nok() { n=$((n + 1)); fail=$((fail + 1)); echo "not ok $n - $*"; }

# two small models, and what the terminal's decoder makes of them
for m in tests/data/geo_example.igs tests/data/as1_pe_203.igs; do
    b=$(basename "$m" .igs)
    "$cmz" encode -q "$m" -o "$tmp/$b.cmz" > /dev/null || { nok "encode $m"; exit 1; }
    "$dec" "$tmp/$b.cmz" -o "$tmp/$b.glb" > /dev/null || { nok "decode $m"; exit 1; }
done
models=(geo_example as1_pe_203)

start_relay() { # start_relay NAME ARGS...: ptys at $tmp/NAME.a (workstation) and $tmp/NAME.b (terminal)
    local name=$1
    shift
    "$relay" --link-a "$tmp/$name.a" --link-b "$tmp/$name.b" "$@" 2> "$tmp/$name.relay.log" &
    relay_pid=$!
    pids+=("$relay_pid")
    for _ in $(seq 400); do [ -e "$tmp/$name.b" ] && [ -e "$tmp/$name.a" ] && return 0; sleep 0.05; done
    return 1
}
start_term() { # start_term LINK OUTDIR [extra args]
    local link=$1 out=$2
    shift 2
    mkdir -p "$out"
    $emu "$term" --serial "$link" --out "$out" --name pty-test "$@" 2>> "$out.log" &
    term_pid=$!
    pids+=("$term_pid")
}
same() { cmp -s "$1" "$2"; }

# ---- 1. a noisy line, ITERATIONS times ----
start_relay noisy --drop 0.01 --flip 0.01 --seed 7 || { nok "pty relay did not start"; exit 1; }
start_term "$tmp/noisy.b" "$tmp/out1"
t0=$(date +%s.%N)
for i in $(seq 1 "$iters"); do
    m=${models[$((i % 2))]}
    # the sender paces itself to the baud it is given and the relay does not pace: 4000000 baud
    # (only the sender's native pty is told; the terminal, maybe under qemu-user, keeps 115200)
    if ! out=$("$cmz" send "$tmp/$m.cmz" --serial "$tmp/noisy.a:4000000" --timeout 30 2>&1); then
        nok "noisy transfer $i ($m): cmz send failed: $(tail -n 2 <<<"$out" | tr '\n' ' ')"
    elif ! same "$tmp/out1/model.cmz" "$tmp/$m.cmz"; then
        nok "noisy transfer $i ($m): model.cmz differs from the file sent"
    elif ! same "$tmp/out1/model.glb" "$tmp/$m.glb"; then
        nok "noisy transfer $i ($m): model.glb differs from cmz-decode's"
    else
        ok "noisy transfer $i ($m): identical and decoded; $(sed -n 's/.*delivered in \([0-9.]* s\) (\([^)]*\)).*/\1, \2/p' <<<"$out")"
    fi
done
t1=$(date +%s.%N)
echo "# $iters transfers in $(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }') s; relay: $(tail -n 1 "$tmp/noisy.relay.log")"
kill "$term_pid" "$relay_pid" 2>/dev/null
wait "$term_pid" 2>/dev/null
rc=$?
[ $rc -eq 0 ] && ok "terminal stops cleanly on SIGTERM (exit 0)" || nok "terminal exit status $rc after SIGTERM"
grep -q 'level=info event=decoded' "$tmp/out1.log" && ok "terminal log has one-line 'event=decoded' records" ||
    nok "terminal log lacks decoded events"

# ---- 2. hang-up mid-transfer: the terminal's side of the cable goes away and comes back ----
# halfway through the file, whatever its size (a fixed 4000 bytes passed the whole of a file that
# format 4.4 made 2540 bytes long, and the hang-up never came)
hup_at=$(( $(wc -c < "$tmp/as1_pe_203.cmz") / 2 ))
start_relay hup --hangup-after "$hup_at" --reopen-ms 300 --baud 115200 || { nok "relay (hang-up) did not start"; exit 1; }
start_term "$tmp/hup.b" "$tmp/out2"
out=$("$cmz" send "$tmp/as1_pe_203.cmz" --serial "$tmp/hup.a" --timeout 30 2>&1)
rc=$?
# Resumed from what the terminal had acknowledged: either the sender reconnected and the terminal
# accepted it mid-file ("resumed at N"), or the sender never lost it and only resent the chunks
# that were not acknowledged; never a second start from byte 0.
at=$(sed -n 's/.*resumed at \([0-9]*\).*/\1/p' <<<"$out" | tail -n 1)
starts=$(grep -c 'event=receiving .* from=0 ' "$tmp/out2.log")
if [ $rc -ne 0 ]; then
    nok "hang-up: cmz send failed ($rc): $(tail -n 2 <<<"$out" | tr '\n' ' ')"
elif ! same "$tmp/out2/model.cmz" "$tmp/as1_pe_203.cmz"; then
    nok "hang-up: model.cmz differs"
elif ! grep -q 'event=link-down' "$tmp/out2.log"; then
    nok "hang-up: the terminal never saw the hang-up (relay: $(tail -n 1 "$tmp/hup.relay.log"))"
elif [ "$starts" -ne 1 ] || { [ -n "$at" ] && [ "$at" -eq 0 ]; }; then
    nok "hang-up: the transfer started again from byte 0 ($starts starts): $(tr '\n' ' ' <<<"$out")"
else
    ok "hang-up after $hup_at bytes: the terminal reopened its line and kept its prefix; ${at:+resumed at byte $at, }file identical and decoded ($(sed -n 's/.*(\([0-9]* chunks, [0-9]* sent again, [0-9]* reconnects\).*/\1/p' <<<"$out"))"
fi
kill "$term_pid" "$relay_pid" 2>/dev/null
wait 2>/dev/null

# ---- 3. kill -9 of the terminal mid-transfer ----
start_relay k9 --baud 19200 || { nok "relay (kill) did not start"; exit 1; }
start_term "$tmp/k9.b" "$tmp/out3"
"$cmz" send "$tmp/geo_example.cmz" --serial "$tmp/k9.a" --timeout 30 > /dev/null 2>&1 ||
    nok "kill -9: first model not delivered"
"$cmz" send "$tmp/as1_pe_203.cmz" --serial "$tmp/k9.a" --timeout 60 > "$tmp/k9.send" 2>&1 &
send_pid=$!
# mid-transfer: a quarter of the file in the part file (at 19200 baud about a second; up to 30 s on
# a busy machine), not a fixed sleep that a slow start would turn into "after the transfer"
for _ in $(seq 600); do [ "$(stat -c %s "$tmp/out3/.incoming.part" 2>/dev/null || echo 0)" -ge 1850 ] && break; sleep 0.05; done
kill -9 "$term_pid"
wait "$term_pid" 2>/dev/null
if same "$tmp/out3/model.cmz" "$tmp/geo_example.cmz" && same "$tmp/out3/model.glb" "$tmp/geo_example.glb"; then
    ok "kill -9 mid-transfer: the previous model.cmz and model.glb are intact"
else
    nok "kill -9 mid-transfer: the previous model was damaged"
fi
part=$(stat -c %s "$tmp/out3/.incoming.part" 2>/dev/null || echo 0)
start_term "$tmp/k9.b" "$tmp/out3"
wait "$send_pid"
rc=$?
resumed=$(sed -n 's/.*event=resumable bytes=\([0-9]*\).*/\1/p' "$tmp/out3.log" | tail -n 1)
if [ $rc -ne 0 ]; then
    nok "kill -9: the transfer did not complete after the restart: $(tail -n 2 "$tmp/k9.send" | tr '\n' ' ')"
elif ! same "$tmp/out3/model.cmz" "$tmp/as1_pe_203.cmz" || ! same "$tmp/out3/model.glb" "$tmp/as1_pe_203.glb"; then
    nok "kill -9: the new model differs after the resume"
else
    ok "kill -9 after $part bytes: restarted terminal resumed from byte ${resumed:-0}, new model identical and decoded"
fi
kill "$term_pid" "$relay_pid" 2>/dev/null
wait 2>/dev/null

# ---- 4. an IGES model, encoded for the terminal's announced limits, over a line inserting garbage ----
start_relay ins --insert 0.01 --drop 0.005 --seed 11 || { nok "relay (garbage) did not start"; exit 1; }
start_term "$tmp/ins.b" "$tmp/out5"
out=$("$cmz" send tests/data/as1_pe_203.igs --serial "$tmp/ins.a" --timeout 30 2>&1)
rc=$?
if [ $rc -eq 0 ] && same "$tmp/out5/model.cmz" "$tmp/as1_pe_203.cmz" && same "$tmp/out5/model.glb" "$tmp/as1_pe_203.glb" &&
    grep -q "encoded for 'pty-test'" <<<"$out"; then
    ok "cmz send MODEL.igs: encoded for the terminal's limits, sent through 1 % inserted garbage, identical and decoded"
else
    nok "cmz send MODEL.igs: rc $rc, $(tail -n 3 <<<"$out" | tr '\n' ' ')"
fi
kill "$term_pid" "$relay_pid" 2>/dev/null
wait 2>/dev/null

# ---- 5. over the terminal's limits: refused on the workstation, naming the limit ----
tiny=${TINY_TERMINAL:-}
if [ -n "$tiny" ] && [ -x "$tiny" ]; then
    start_relay lim || { nok "relay (limits) did not start"; exit 1; }
    term_save=$term emu_save=$emu
    term=$tiny emu= # the tiny terminal is this machine's build (the limits are the profile's, not the arch's)
    start_term "$tmp/lim.b" "$tmp/out4"
    term=$term_save emu=$emu_save
    out=$("$cmz" send "$tmp/as1_pe_203.cmz" --serial "$tmp/lim.a" --timeout 20 2>&1)
    rc=$?
    lim=$(grep -o 'needs MAX_[A-Z_]*' <<<"$out" | head -n 1)
    # the hint fits the limit: only the tessellation's own limits shrink with a coarser --tess
    hint_ok=1
    case "$lim" in
    *MAX_TRIS | *MAX_TESS_POINTS | *MAX_EDGE_SAMPLES) grep -q -- '--tess' <<<"$out" || hint_ok=0 ;;
    *) ! grep -q -- '--tess' <<<"$out" || hint_ok=0 ;;
    esac
    if [ $rc -eq 1 ] && [ $hint_ok -eq 1 ] && grep -q 'needs MAX_[A-Z_]*=[0-9]*, terminal .* has [0-9]*' <<<"$out" &&
        [ ! -e "$tmp/out4/model.cmz" ]; then
        ok "over the limits of the tiny terminal: refused before sending ($(grep -o 'needs MAX_[A-Z_]*=[0-9]*, terminal .* has [0-9]*' <<<"$out"))"
    else
        nok "over the limits: rc $rc, $(tr '\n' ' ' <<<"$out")"
    fi
    kill "$term_pid" "$relay_pid" 2>/dev/null
    wait 2>/dev/null
else
    # always run (issue 11): a skip here once hid the limit refusal from the aarch64 run
    nok "over the limits: no tiny-profile terminal given (TINY_TERMINAL=${tiny:-unset}): build it with make PROFILE=tiny"
fi
# ---- 5b. a newer minor version than the terminal reads: refused on the workstation ----
# (a 2.5 terminal would leave a 2.6 file's turning faces out; here the file claims minor 99 of its
#  major version, the terminal's own)
start_relay ver || { nok "relay (version) did not start"; exit 1; }
start_term "$tmp/ver.b" "$tmp/outv"
cp "$tmp/as1_pe_203.cmz" "$tmp/newer.cmz"
printf '\143' | dd of="$tmp/newer.cmz" bs=1 seek=5 conv=notrunc 2> /dev/null
out=$("$cmz" send "$tmp/newer.cmz" --serial "$tmp/ver.a" --timeout 20 2>&1)
rc=$?
if [ $rc -ne 0 ] && grep -q "format [0-9]\.99, terminal 'pty-test' reads" <<<"$out" && [ ! -e "$tmp/outv/model.cmz" ]; then
    ok "a newer minor version than the terminal reads: refused before sending ($(grep -o 'format [0-9]\.99.*reads [0-9.x ]*to [0-9.]*' <<<"$out"))"
else
    nok "a newer minor version: rc $rc, $(tr '\n' ' ' <<<"$out")"
fi
kill "$term_pid" "$relay_pid" 2>/dev/null
wait 2>/dev/null

# ---- 6. sigterm_mid_transfer: SIGTERM to cmz send on a slow line ----
start_relay sig --baud 2400 || { nok "relay (sigterm) did not start"; exit 1; }
start_term "$tmp/sig.b" "$tmp/out6"
"$cmz" send "$tmp/as1_pe_203.cmz" --serial "$tmp/sig.a:2400" --timeout 30 > "$tmp/sig.send" 2>&1 &
send_pid=$!
# about 1000 bytes in (4 s at 2400 baud; up to 60 s on a busy machine): the first 1000 bytes in
# place, not the file's size, which a later chunk written at its offset reaches while an earlier one
# is still to be sent again (then nothing contiguous is held and there is nothing to resume)
for _ in $(seq 1200); do cmp -s -n 1000 "$tmp/out6/.incoming.part" "$tmp/as1_pe_203.cmz" && break; sleep 0.05; done
t0=$(date +%s%N)
kill -TERM "$send_pid"
# it must be gone within a second; give it 3 s before calling it stuck (and killing it)
for _ in $(seq 60); do kill -0 "$send_pid" 2> /dev/null || break; sleep 0.05; done
t1=$(date +%s%N)
kill -0 "$send_pid" 2> /dev/null && kill -9 "$send_pid"
wait "$send_pid"
rc=$?
ms=$(((t1 - t0) / 1000000))
out=$("$cmz" send "$tmp/as1_pe_203.cmz" --serial "$tmp/sig.a:2400" --timeout 30 2>&1)
rc2=$?
at=$(sed -n 's/.*resumed at \([0-9]*\).*/\1/p' <<<"$out" | tail -n 1)
if [ $rc -ne 143 ] || [ $ms -gt 1000 ]; then
    nok "sigterm_mid_transfer: cmz send exited $rc after $ms ms (want 143 within 1000 ms): $(tail -n 1 "$tmp/sig.send")"
elif [ $rc2 -ne 0 ] || [ -z "$at" ] || [ "$at" -eq 0 ] || ! same "$tmp/out6/model.cmz" "$tmp/as1_pe_203.cmz"; then
    nok "sigterm_mid_transfer: the next send did not resume (rc $rc2): $(tr '\n' ' ' <<<"$out")"
else
    ok "sigterm_mid_transfer: SIGTERM at 2400 baud: exit 143 after $ms ms; the next send resumed at byte $at, file identical"
fi
kill "$term_pid" "$relay_pid" 2>/dev/null
wait 2>/dev/null

# ---- 7. progress on the status line ----
cat > "$tmp/fakeview.sh" <<EOF
#!/bin/sh
# what the terminal asks the viewer to draw, one line a call, with the time in ms
echo "\$(date +%s%3N) \$*" >> "$tmp/view.calls"
EOF
chmod +x "$tmp/fakeview.sh"
start_relay prog --baud 9600 || { nok "relay (progress) did not start"; exit 1; }
start_term "$tmp/prog.b" "$tmp/out7" --display /dev/fb-test --viewer "$tmp/fakeview.sh"
if ! out=$("$cmz" send "$tmp/geo_example.cmz" --serial "$tmp/prog.a:9600" --timeout 60 2>&1); then
    nok "progress: cmz send at 9600 baud failed: $(tail -n 1 <<<"$out")"
else
    for _ in $(seq 200); do grep -q "model.cmz" "$tmp/view.calls" 2> /dev/null && break; sleep 0.05; done
    # the percentages in order, and the calls' times
    pcts=$(sed -n 's/.*--status geo_example.cmz: receiving \([0-9]*\) %.*/\1/p' "$tmp/view.calls" | tr '\n' ' ')
    if ! grep -q -- "--status geo_example.cmz: receiving\$" "$tmp/view.calls"; then
        nok "progress: no 'receiving' status at the start: $(tr '\n' '|' < "$tmp/view.calls")"
    elif ! awk -v p="$pcts" 'BEGIN { n = split(p, a, " "); if (n < 2) exit 1
            for (i = 1; i <= n; i++) if (a[i] % 10 || a[i] >= 100 || (i > 1 && a[i] <= a[i - 1])) exit 1 }'; then
        nok "progress: want two or more rising multiples of 10 below 100, got '$pcts': $(tr '\n' '|' < "$tmp/view.calls")"
    elif ! awk '/receiving [0-9]+ %/ { if (last != "" && $1 - last < 990) bad = 1; last = $1 } END { exit bad }' "$tmp/view.calls"; then
        nok "progress: two progress statuses less than a second apart: $(tr '\n' '|' < "$tmp/view.calls")"
    elif ! tail -n 1 "$tmp/view.calls" | grep -q "current/model.cmz"; then
        nok "progress: the model is not drawn last: $(tail -n 1 "$tmp/view.calls")"
    else
        ok "progress: 'receiving', then ${pcts}% at least a second apart, then the model"
    fi
fi
kill "$term_pid" "$relay_pid" 2>/dev/null
wait 2>/dev/null

echo "$((n - fail)) passed, $fail failed"
[ $fail -eq 0 ]
