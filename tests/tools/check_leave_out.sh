#!/usr/bin/env bash
# check_leave_out.sh CMZ TEST_LEAVE_OUT WORKDIR - one bad face never sinks a model, seen from the
# command line: a model with one face that cannot be triangulated (test_leave_out writes it) encodes
# with a warning naming the face's entity and a summary that counts it, `--strict` refuses it and
# writes nothing, `cmz eval` finds the same face left out and passes, and `cmz decode` rebuilds the rest.
set -u
CMZ=$1 T=$2 W=$3
mkdir -p "$W"
n=0 bad=0
ok() { n=$((n + 1)); echo "ok $n - $1"; }
no() { n=$((n + 1)); bad=$((bad + 1)); echo "not ok $n - $1"; }
LEAVE_OUT_SAVE="$W/leave_out.igs" "$T" > /dev/null 2>&1
[ -s "$W/leave_out.igs" ] || { echo "not ok 1 - $T wrote no model"; echo "0 passed, 1 failed"; exit 1; }
rm -f "$W/leave_out.cmz"
out=$("$CMZ" encode "$W/leave_out.igs" -o "$W/leave_out.cmz" 2>&1)
rc=$?
[ $rc -eq 0 ] && ok "encode succeeds" || no "encode succeeds (exit $rc: $out)"
grep -Eq 'warning: face of entity 144 \(DE [0-9]+\): left out: its boundary cannot be triangulated' <<<"$out" &&
    ok "the warning names the face's entity and why" || no "the warning names the face's entity and why: $out"
grep -q '7 faces (.*1 left out (see warnings))' <<<"$out" && ok "the summary counts it" || no "the summary counts it: $out"
rm -f "$W/strict.cmz"
out=$("$CMZ" encode --strict "$W/leave_out.igs" -o "$W/strict.cmz" 2>&1)
rc=$?
[ $rc -eq 1 ] && [ ! -e "$W/strict.cmz" ] && grep -q 'cannot be sent.*(--strict) (nothing written)' <<<"$out" &&
    ok "--strict refuses the model and writes nothing" || no "--strict refuses the model (exit $rc: $out)"
out=$("$CMZ" eval "$W/leave_out.igs" "$W/leave_out.cmz" 2>&1)
rc=$?
[ $rc -eq 0 ] && grep -q '^1 faces left out by the encoder' <<<"$out" && grep -q '^ok: every rebuilt face' <<<"$out" &&
    ok "cmz eval matches the faces and passes" || no "cmz eval matches the faces and passes (exit $rc: $out)"
out=$("$CMZ" decode "$W/leave_out.cmz" -o "$W/leave_out.glb" 2>&1)
rc=$?
[ $rc -eq 0 ] && grep -q ': 7 faces' <<<"$out" && ok "the rest decodes" || no "the rest decodes (exit $rc: $out)"
echo "$((n - bad)) passed, $bad failed"
[ $bad -eq 0 ]
