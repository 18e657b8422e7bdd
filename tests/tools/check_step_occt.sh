#!/usr/bin/env bash
# check_step_occt.sh CMZ ORACLE [MODELS_DIR] - the STEP import, checked by an independent kernel.
#
# For every STEP model of MODELS_DIR/step, against Open CASCADE's STEPControl_Reader
# (occt_oracle info / points):
#   1. the same number of faces as OCCT reads;
#   2. `cmz sample` points on every face (inside its outer loop, outside its holes) lie on
#      OCCT's faces within 1e-6 of the model's diagonal, or within OCCT's own largest edge
#      tolerance (max_tol) where the file's edges lie farther than that from their surfaces
#      (then no reader can place a boundary more exactly than the file does);
#   3. no more free edges than OCCT finds (a closed solid pairs all its edges);
#   4. the same diagonal within 1 % (units, placements of assembly parts).
# One TAP line per model.
set -u
cmz=$1 oracle=$2 dir=${3:-../shared/models}/step
if [ ! -d "$dir" ]; then
    echo "# SKIP: $dir not found (the shared corpus is not beside this checkout)"
    echo "ok 1 - STEP corpus check skipped"
    exit 0
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
one() {
    local n=$1 f=$2 w=$tmp/$1 b faces ofaces diag odiag maxtol free ofree per out rc tolrel why=""
    mkdir -p "$w"
    b=$(basename "$f")
    if ! "$cmz" info -q --json "$f" > "$w/info.json" 2> "$w/err"; then
        echo "not ok $n - $b: cmz info failed: $(head -c 300 "$w/err")"
        return
    fi
    faces=$(sed -n 's/.*"total": \([0-9]*\), "trimmed_144".*/\1/p' "$w/info.json")
    free=$(sed -n 's/.*"edges": {"total": [0-9]*, "shared": [0-9]*, "free": \([0-9]*\),.*/\1/p' "$w/info.json")
    diag=$(sed -n 's/.*"diagonal": \([0-9.e+-]*\)}.*/\1/p' "$w/info.json")
    if ! "$oracle" info "$f" > "$w/occt" 2>&1; then
        echo "not ok $n - $b: OCCT cannot read it: $(tail -n 1 "$w/occt")"
        return
    fi
    ofaces=$(awk '$1 == "faces" { print $2 }' "$w/occt")
    odiag=$(awk '$1 == "diag" { print $2 }' "$w/occt")
    maxtol=$(awk '$1 == "max_tol" { print $2 }' "$w/occt")
    ofree=$(awk '$1 == "free_edges" { print $2 }' "$w/occt")
    if [ -z "$faces" ] || [ -z "$ofaces" ] || [ -z "$free" ] || [ -z "$ofree" ] || [ -z "$diag" ]; then
        echo "not ok $n - $b: a count is missing (cmz: faces '$faces' free '$free' diag '$diag'; OCCT: faces '$ofaces' free '$ofree')"
        return
    fi
    [ "$faces" -eq "$ofaces" ] || why="$why faces $faces, OCCT $ofaces;"
    [ "$free" -le "$ofree" ] || why="$why $free free edges, OCCT $ofree;"
    # the same model in the same place: 1 % of the diagonal (ours is the box of the boundary curves,
    # OCCT's also takes in a face bulging past its boundary: ec_soapbox's lid, 1.1 mm of 136; a
    # wrong unit or a part placed wrong or left out is far more)
    awk -v a="$diag" -v b="$odiag" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= 1e-2 * b) }' ||
        why="$why diagonal $diag mm, OCCT $odiag mm;"
    per=$(( faces > 0 ? 4000 / faces : 1 ))
    [ "$per" -lt 1 ] && per=1
    [ "$per" -gt 20 ] && per=20
    if ! "$cmz" sample -q "$f" -o "$w/p.xyz" --per-face "$per" 2> "$w/err"; then
        echo "not ok $n - $b: cmz sample failed: $(head -c 300 "$w/err")"
        return
    fi
    tolrel=$(awk -v t="$maxtol" -v d="$odiag" 'BEGIN { r = t / d; printf "%.9g", (r > 1e-6 ? r : 1e-6) }')
    out=$("$oracle" points "$f" "$w/p.xyz" --tol-rel "$tolrel" 2>&1)
    rc=$?
    [ $rc -eq 0 ] || why="$why points off OCCT's faces;"
    summary=$(grep -E '^(points|max_dist|over_tol) ' <<<"$out" | tr '\n' ' ')
    if [ -z "$why" ]; then
        echo "ok $n - $b: $faces faces as OCCT, $free free edges (OCCT $ofree), diagonal $diag mm, tol-rel $tolrel, $summary"
    else
        echo "not ok $n - $b:$why $summary"
        grep -E '^(face |# worst)' <<<"$out" | head -n 5 | sed 's/^/#   /'
    fi
}
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
