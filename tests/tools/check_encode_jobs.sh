#!/usr/bin/env bash
# check_encode_jobs.sh CMZ [MODELS_DIR]
#
# `cmz encode -j N` gives the bytes and the --report of `-j 1` on every model of the shared corpus
# (IGES and STEP), here with three processes on however many cores.  The surfaces are built, the
# methods chosen and the tessellation's needs measured on worker processes; a face whose G1FIT trial asked which faces before it keep their surfaces is
# chosen again in order where one does (choose_methods.c).  The bundled models never need that (the
# unit test test_encode_jobs covers them and dying workers); asitus__Pieza1 does: without the
# second choice its file differs.  One TAP line per model.
set -u
cmz=$1 dir=${2:-../shared/models}
if [ ! -d "$dir/iges" ]; then
    echo "# SKIP: $dir not found (the shared corpus is not beside this checkout)"
    echo "ok 1 - encode -j skipped"
    exit 0
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
n=0 bad=0
for f in "$dir"/iges/* "$dir"/step/*; do
    case "$f" in *.igs | *.iges | *.IGS | *.IGES | *.stp | *.step | *.STP | *.STEP) ;; *) continue ;; esac
    n=$((n + 1))
    b=$(basename "$f")
    "$cmz" encode -q "$f" -o "$tmp/one.cmz" --report "$tmp/one.tsv" -j 1 > "$tmp/one.log" 2>&1
    r1=$?
    "$cmz" encode -q "$f" -o "$tmp/three.cmz" --report "$tmp/three.tsv" -j 3 > "$tmp/three.log" 2>&1
    r3=$?
    if [ "$r1" != "$r3" ]; then
        echo "not ok $n - $b: exit status $r1 with -j 1, $r3 with -j 3"
        bad=$((bad + 1))
    elif [ "$r1" = 0 ] && ! cmp -s "$tmp/one.cmz" "$tmp/three.cmz"; then
        echo "not ok $n - $b: -j 3 wrote $(stat -c %s "$tmp/three.cmz") other bytes than -j 1's $(stat -c %s "$tmp/one.cmz")"
        bad=$((bad + 1))
    elif [ "$r1" = 0 ] && ! cmp -s "$tmp/one.tsv" "$tmp/three.tsv"; then
        echo "not ok $n - $b: the --report differs: $(diff "$tmp/one.tsv" "$tmp/three.tsv" | head -n 3 | tr '\n' ' ')"
        bad=$((bad + 1))
    else
        echo "ok $n - $b: the same file and report with -j 1 and -j 3"
    fi
    rm -f "$tmp/one.cmz" "$tmp/three.cmz" "$tmp/one.tsv" "$tmp/three.tsv"
done
[ "$n" -gt 0 ] || { echo "not ok 1 - no model found under $dir"; exit 1; }
echo "1..$n"
exit $((bad > 0))
