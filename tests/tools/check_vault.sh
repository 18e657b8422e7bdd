#!/usr/bin/env bash
# check_vault.sh CMZ TEST_LEAVE_OUT SMALL.igs SLOW.igs - `cmz encode FOLDER|--list FILE -o OUT` (cmd_vault.c)
# over a vault made of the bundled models: outputs mirror the tree and equal a single model's encode,
# one bad model is named in the summary and the exit status while the rest encode, a second run
# skips what is up to date and encodes again what changed (the model, the options, --force), a
# model past --timeout is stopped and leaves nothing, shards split the models without overlap and
# name them as the whole run does, a list may name folders and missing files, and an interrupt
# writes the summary and keeps what the last run knew.  TAP.
set -u
CMZ=$1 LEAVE_OUT=$2 SMALL=$3 SLOW=$4
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
n=0 bad=0
t() { n=$((n + 1)); if [ "$1" = ok ]; then echo "ok $n - $2"; else echo "not ok $n - $2"; bad=$((bad + 1)); fi; }
check() { if eval "$1"; then t ok "$2"; else t no "$2${3:+: $3}"; fi; }
col() { # col TSV INPUT COLUMN: the value of COLUMN (by its header name) in the row of INPUT
    awk -F'\t' -v inp="$2" -v c="$3" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == c) k = i; next }
        $1 == inp && k { print $k }' "$1"
}
mtime() { stat -c %Y.%y "$1" 2>/dev/null; }

# the vault: two models in a tree, the same model under two extensions' stems, a damaged file, a
# hidden folder and a file that is no model
V=$W/vault
mkdir -p "$V/a/b" "$V/.cache" "$V/c"
LEAVE_OUT_SAVE="$V/a/b/leave_out.igs" "$LEAVE_OUT" > /dev/null 2>&1
cp "$SMALL" "$V/a/part.igs"
cp "$SMALL" "$V/a/part.iges"
printf 'not an IGES file\n' > "$V/c/broken.igs"
cp "$SMALL" "$V/.cache/hidden.igs"
echo notes > "$V/a/readme.txt"
[ -s "$V/a/b/leave_out.igs" ] || { echo "not ok 1 - $LEAVE_OUT wrote no model"; echo "0 passed, 1 failed"; exit 1; }

O=$W/out S=$O/cmz-vault.tsv
out=$("$CMZ" encode "$V" -o "$O" -j 2 2>&1)
rc=$?
check '[ $rc -eq 1 ]' "a vault with a damaged model exits 1" "exit $rc: $out"
check 'grep -q "^cmz: failed: $V/c/broken.igs" <<<"$out"' "the damaged model is named" "$out"
check 'grep -q "4 models: 3 encoded, 0 up to date, 1 failed" <<<"$out"' "the summary line counts the models" "$out"
check '[ -s "$O/a/b/leave_out.cmz" ] && [ -s "$O/a/part.igs.cmz" ] && [ -s "$O/a/part.iges.cmz" ] && [ ! -e "$O/c/broken.cmz" ]' \
    "outputs mirror the tree, one stem of two models keeps the extensions, the failed one has none" "$(find "$O" | sort)"
check '[ ! -e "$O/.cache" ] && [ ! -e "$O/a/readme.cmz" ]' "hidden folders and other files are not models"
check '[ -s "$O/c/broken.cmz.log" ] && [ -s "$O/a/b/leave_out.cmz.log" ] && grep -q "warning: face of entity 144" "$O/a/b/leave_out.cmz.log"' \
    "each model's messages are in its log (the failure, the face left out)"
check '[ "$(wc -l < "$S")" -eq 5 ]' "the summary has a header and a row per model" "$(cat "$S" 2>&1)"
check '[ "$(col "$S" "$V/a/part.igs" status)" = encoded ] && [ "$(col "$S" "$V/c/broken.igs" status)" = failed ]' \
    "statuses in the summary"
check '[ "$(col "$S" "$V/a/part.igs" cmz_bytes)" = "$(stat -c %s "$O/a/part.igs.cmz")" ]' "cmz_bytes is the output's size"
check '[ "$(col "$S" "$V/a/b/leave_out.igs" left_out)" = 1 ] && [ "$(col "$S" "$V/a/b/leave_out.igs" warnings)" -ge 1 ]' \
    "the face left out is counted in the summary"
d=$(col "$S" "$V/a/part.igs" deleted_pct)
check 'awk -v d="$d" "BEGIN { exit !(d > 0 && d <= 100) }"' "deleted_pct is a share" "$d"
check 'grep -q "line has 16 columns" <<<"$(col "$S" "$V/c/broken.igs" message)"' "the failure's message is in the summary" \
    "$(col "$S" "$V/c/broken.igs" message)"
"$CMZ" encode -q "$SMALL" -o "$W/single.cmz" > /dev/null 2>&1
check 'cmp -s "$W/single.cmz" "$O/a/part.igs.cmz"' "a vault's output is the single model's encode, byte for byte"

# a second run: nothing to do but the failed model
before=$(mtime "$O/a/part.igs.cmz")
out=$("$CMZ" encode "$V" -o "$O" -j 2 -q 2>&1)
check 'grep -q "4 models: 0 encoded, 3 up to date, 1 failed" <<<"$out"' "a second run skips what is up to date" "$out"
check '[ "$before" = "$(mtime "$O/a/part.igs.cmz")" ] && [ "$(col "$S" "$V/a/part.igs" status)" = up-to-date ]' \
    "an up-to-date output is not written again and its row says so"
check '[ "$(col "$S" "$V/a/part.igs" cmz_bytes)" = "$(stat -c %s "$O/a/part.igs.cmz")" ]' "an up-to-date row keeps its numbers"
sleep 1.1
touch "$V/a/part.iges"
out=$("$CMZ" encode "$V" -o "$O" -q 2>&1)
check 'grep -q "1 encoded, 2 up to date, 1 failed" <<<"$out" && [ "$(col "$S" "$V/a/part.iges" status)" = encoded ]' \
    "a model newer than its output is encoded again" "$out"
cp "$O/a/b/leave_out.cmz" "$W/keep.cmz"
printf 'x' >> "$O/a/b/leave_out.cmz"
out=$("$CMZ" encode "$V" -o "$O" -q 2>&1)
check 'grep -q "1 encoded, 2 up to date, 1 failed" <<<"$out" && cmp -s "$W/keep.cmz" "$O/a/b/leave_out.cmz"' \
    "an output of another size than recorded is encoded again" "$out"
out=$("$CMZ" encode "$V" -o "$O" -q --tol 0.002 2>&1)
check 'grep -q "3 encoded, 0 up to date, 1 failed" <<<"$out" && [ "$(col "$S" "$V/a/part.igs" options)" = "--tol 0.002" ]' \
    "other options encode everything again" "$out"
out=$("$CMZ" encode "$V" -o "$O" -q --tol 0.002 --force 2>&1)
check 'grep -q "3 encoded, 0 up to date, 1 failed" <<<"$out"' "--force encodes everything again" "$out"

# a model past --timeout is stopped and named; nothing of it stays but its log
mkdir -p "$W/slow"
cp "$SLOW" "$W/slow/slow.igs"
cp "$V/a/b/leave_out.igs" "$W/slow/quick.igs"
out=$("$CMZ" encode "$W/slow" -o "$W/slow_out" --timeout 1 -q 2>&1)
rc=$?
check '[ $rc -eq 1 ] && grep -q "failed: $W/slow/slow.igs: took longer than --timeout 1 s" <<<"$out"' \
    "a model past --timeout is stopped and named" "exit $rc: $out"
check '[ -s "$W/slow_out/quick.cmz" ] && [ -z "$(ls "$W/slow_out" | grep -v -e "^quick.cmz" -e "^slow.cmz.log$" -e "^cmz-vault.tsv$")" ]' \
    "the rest encodes and the stopped model leaves no output nor temporary file" "$(ls "$W/slow_out")"

# a timeout says nothing of the model: an earlier output of it stays
"$CMZ" encode "$W/slow" -o "$W/slow_out" -q > /dev/null 2>&1
cp "$W/slow_out/slow.cmz" "$W/slow_good.cmz" 2>/dev/null
out=$("$CMZ" encode "$W/slow" -o "$W/slow_out" --force --timeout 1 -q 2>&1)
check 'cmp -s "$W/slow_good.cmz" "$W/slow_out/slow.cmz" && [ "$(col "$W/slow_out/cmz-vault.tsv" "$W/slow/slow.igs" status)" = failed ]' \
    "a model stopped by --timeout keeps its earlier output (its row says failed)" "$out"

# workers are waited for even when SIGCHLD comes ignored (an inherited SIG_IGN let the kernel reap them)
out=$( (trap '' CHLD; exec timeout 120 "$CMZ" encode "$V/a/b" -o "$W/chld" -q) 2>&1)
rc=$?
check '[ $rc -eq 0 ] && grep -q "1 models: 1 encoded" <<<"$out"' "a vault started with SIGCHLD ignored ends" "exit $rc: $out"

# one output folder however -o is spelled
out=$("$CMZ" encode "$V/a/b" -o "$W/chld/" -q 2>&1; "$CMZ" encode "$V/a/b" -o "$W/./chld" -q 2>&1)
check '[ "$(grep -c "0 encoded, 1 up to date" <<<"$out")" -eq 2 ]' "-o OUT/ and -o ./OUT are OUT" "$out"

# shards: each model in exactly one, named as in the whole run
for k in 0 1 2; do "$CMZ" encode "$V" -o "$W/sh" --shard $k/3 -q > /dev/null 2>&1; done
rows=$(cat "$W"/sh/cmz-vault.*-of-3.tsv | grep -v '^input' | cut -f1 | sort)
check '[ "$rows" = "$(cut -f1 "$S" | grep -v "^input" | sort)" ]' "three shards cover every model once" "$rows"
check '[ -s "$W/sh/a/part.igs.cmz" ] && [ -s "$W/sh/a/part.iges.cmz" ]' "a shard names outputs as the whole run does"

# a list: comments, a folder, a missing file, a model listed twice
printf '# the release\n%s\n\n%s\n/nonexistent/model.igs\n%s/./a//part.igs\n' "$V/a/b" "$V/a/part.igs" "$V" > "$W/list.txt"
out=$("$CMZ" encode --list "$W/list.txt" -o "$W/lo" 2>&1)
rc=$?
check '[ $rc -eq 1 ] && grep -q "3 models: 2 encoded, 0 up to date, 1 failed" <<<"$out" && grep -q "failed: /nonexistent/model.igs: cannot open" <<<"$out"' \
    "a list's folder is walked, a missing file is named" "exit $rc: $out"
check '[ -s "$W/lo$V/a/b/leave_out.cmz" ] && grep -q "listed again" <<<"$out"' "a list mirrors its paths; a model listed twice is encoded once" \
    "$(find "$W/lo" -name '*.cmz') $out"

# an interrupt: the summary is written, models not reached keep what the last run knew
"$CMZ" encode "$W/slow" -o "$W/int" -q > /dev/null 2>&1 # slow.igs and quick.igs both encoded
"$CMZ" encode "$W/slow" -o "$W/int" -q --force > "$W/int.txt" 2>&1 &
pid=$!
sleep 1
kill -INT $pid
wait $pid
rc=$?
out=$(cat "$W/int.txt")
check '[ $rc -eq 130 ] && grep -q "not run (interrupted)" <<<"$out"' "an interrupt stops the run, exit 130" "exit $rc: $out"
"$CMZ" encode "$W/slow" -o "$W/int_term" -q --force > /dev/null 2>&1 &
pid=$!
sleep 1
kill -TERM $pid
wait $pid
rc=$?
check '[ $rc -eq 143 ] && [ -s "$W/int_term/cmz-vault.tsv" ]' "SIGTERM stops it too, exit 143, the summary written" "exit $rc"
check '[ "$(col "$W/int/cmz-vault.tsv" "$W/slow/slow.igs" status)" = not-run ] && [ -z "$(ls "$W/int" | grep tmp)" ]' \
    "the interrupted model is not run and leaves nothing" "$(cat "$W/int/cmz-vault.tsv")"
check '[ "$(col "$W/int/cmz-vault.tsv" "$W/slow/slow.igs" cmz_bytes)" = "$(stat -c %s "$W/int/slow.cmz")" ]' \
    "its row keeps what the last run built" "$(cat "$W/int/cmz-vault.tsv")"
out=$("$CMZ" encode "$W/slow" -o "$W/int" -q 2>&1)
check 'grep -q "0 encoded, 2 up to date" <<<"$out"' "the next run skips it: the model has not changed since its output" "$out"

# names: three models whose outputs would clash, a tab in a name, a leading dash, links
Q=$W/quick
mkdir -p "$Q/sub"
for f in part.igs part.iges part.igs.iges "tab	name.igs" -dash.igs; do cp "$V/a/b/leave_out.igs" "$Q/$f"; done
mkdir -p "$W/elsewhere"
cp "$V/a/b/leave_out.igs" "$W/elsewhere/model.igs"
ln -s "$W/elsewhere/model.igs" "$Q/sub/linked.igs"
ln -s "$Q/nothing.igs" "$Q/sub/dangling.igs"
ln -s "$Q" "$W/quick_link"
out=$("$CMZ" encode "$W/quick_link" -o "$W/qo" -q 2>&1)
rc=$?
check '[ -s "$W/qo/part.igs.cmz" ] && [ -s "$W/qo/part.iges.cmz" ] && [ -s "$W/qo/part.igs~2.cmz" ]' \
    "models whose outputs would clash get one each" "$(ls "$W/qo") $out"
check '[ -s "$W/qo/tab	name.cmz" ] && [ -s "$W/qo/-dash.cmz" ] && [ -s "$W/qo/sub/linked.cmz" ]' \
    "a tab and a leading dash in a name, a link to a model; the folder given as a link" "$(ls -R "$W/qo") $out"
check '[ $rc -eq 1 ] && grep -q "failed: $W/quick_link/sub/dangling.igs: a symbolic link to nothing" <<<"$out"' \
    "a link to nothing is named" "exit $rc: $out"
check '[ "$(awk -F"\t" "NR > 1" "$W/qo/cmz-vault.tsv" | wc -l)" -eq 7 ] && grep -qF "tab\\tname.igs" "$W/qo/cmz-vault.tsv"' \
    "the summary has a row per model, a tab in a name escaped" "$(cat "$W/qo/cmz-vault.tsv")"
out=$("$CMZ" encode "$W/quick_link" -o "$W/qo" -q 2>&1)
check 'grep -q "7 models: 0 encoded, 6 up to date, 1 failed" <<<"$out"' "every name is found up to date again" "$out"
# a model replaced by another one carrying an older time (a restore, rsync -a) is encoded again
cp "$SMALL" "$Q/part.iges"
touch -d @1000000000 "$Q/part.iges"
out=$("$CMZ" encode "$W/quick_link" -o "$W/qo" -q 2>&1)
check 'grep -q "1 encoded, 5 up to date, 1 failed" <<<"$out"' "a model replaced by an older-dated one is encoded again" "$out"
# a model that no longer encodes loses its old output (it would not be this model)
printf 'junk\n' > "$Q/part.iges"
out=$("$CMZ" encode "$W/quick_link" -o "$W/qo" -q 2>&1)
check '[ ! -e "$W/qo/part.iges.cmz" ] && grep -q "failed: $W/quick_link/part.iges" <<<"$out"' \
    "a model that fails now leaves no earlier output" "$(ls "$W/qo") $out"

# usage
"$CMZ" encode "$SMALL" -o "$W/x.cmz" --force > /dev/null 2>&1
rc1=$?
"$CMZ" encode "$V" -o "$W/single.cmz" > /dev/null 2>&1
rc2=$?
check '[ $rc1 -eq 2 ] && [ $rc2 -eq 2 ]' "--force on one model and a file for the output folder are usage errors" "$rc1 $rc2"
# -j on one model: its faces on N processes (cmz encode -j), the vault's file
"$CMZ" encode "$SMALL" -o "$W/x.cmz" -j 2 > /dev/null 2>&1
rc1=$?
check '[ $rc1 -eq 0 ] && cmp -s "$W/x.cmz" "$W/single.cmz"' \
    "-j 2 on one model writes the file of -j 1 (a vault's, above)" "$rc1"
echo "$((n - bad)) passed, $bad failed"
[ $bad -eq 0 ]
