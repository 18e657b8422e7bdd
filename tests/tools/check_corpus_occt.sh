#!/usr/bin/env bash
# check_corpus_occt.sh CMZ ORACLE [MODELS_DIR] - the import, checked by an independent kernel.
#
# For every IGES model: `cmz sample` puts points on every trimmed face
# (inside its outer loop, outside its holes); Open CASCADE reads the same
# file and measures each point's distance to its trimmed faces.  A model
# passes when every face got points and every point is within 1e-6 of the
# model's bounding-box diagonal.  About 4000 points per model (at least
# one per face) keep the run short.  Prints one TAP line per model.
set -u
cmz=$1 oracle=$2 dir=${3:-../shared/models}/iges
if [ ! -d "$dir" ]; then
    echo "# SKIP: $dir not found (the shared corpus is not beside this checkout)"
    echo "ok 1 - corpus check skipped"
    exit 0
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# one model: its TAP line, numbered n, on stdout
one() {
    local n=$1 f=$2 w=$tmp/$1 b faces per out rc summary
    mkdir -p "$w"
    b=$(basename "$f")
    faces=$("$cmz" info -q --json "$f" | sed -n 's/.*"total": \([0-9]*\), "trimmed_144".*/\1/p')
    per=$(( faces > 0 ? 4000 / faces : 1 ))
    [ "$per" -lt 1 ] && per=1
    [ "$per" -gt 20 ] && per=20
    if ! "$cmz" sample -q "$f" -o "$w/p.xyz" --per-face "$per" 2> "$w/err"; then
        echo "not ok $n - $b: cmz sample failed: $(head -c 300 "$w/err")"
        return
    fi
    out=$("$oracle" points "$f" "$w/p.xyz" --tol-rel 1e-6 2>&1)
    rc=$?
    summary=$(grep -E '^(points|max_dist|over_tol) ' <<<"$out" | tr '\n' ' ')
    if [ $rc -eq 0 ]; then
        echo "ok $n - $b: $faces faces, $summary"
    else
        echo "not ok $n - $b: $summary"
        grep -E '^(face |# worst)' <<<"$out" | head -n 5 | sed 's/^/#   /'
    fi
}
# two models at a time (2 cores, each model one single-threaded pipeline), printed in corpus order
jobs_max=${OCCT_JOBS:-2}
n=0
for f in "$dir"/*; do
    n=$((n + 1))
    while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n; done
    one "$n" "$f" > "$tmp/$n.out" 2>&1 &
done
wait
fail=0
for i in $(seq 1 "$n"); do
    cat "$tmp/$i.out"
    grep -q '^ok ' "$tmp/$i.out" || fail=$((fail + 1))
done
echo "$((n - fail)) passed, $fail failed"
[ $fail -eq 0 ]
