#!/usr/bin/env bash
# readme_tables.sh [--check] BUILD_ROOT TRIPLET - regenerate README's generated tables.
#
# The limits and error tables in README.md are produced from the X-macro
# lists (fixedcfg/cm_limits_list.h, decoder/include/cm/cm_error.h) through
# the cm-limits tool of each profile, between the markers
#   <!-- generated:limits -->  ...  <!-- /generated:limits -->
#   <!-- generated:errors -->  ...  <!-- /generated:errors -->
# so no number is written twice by hand.  --check fails if README is stale.
set -eu
check=0
if [ "${1:-}" = --check ]; then check=1; shift; fi
root=$1 triplet=$2
tool() { echo "$root/$triplet-$1/cm-limits"; }
limits=$(
    echo "| limit | terminal | host | tiny | hard max | unit | meaning |"
    echo "|---|---:|---:|---:|---:|---|---|"
    paste <("$(tool terminal)" --tsv) <("$(tool host)" --tsv | cut -f2) <("$(tool tiny)" --tsv | cut -f2) |
        awk -F'\t' '{printf "| `%s` | %s | %s | %s | %s | %s | %s |\n", $1, $2, $6, $7, $3, $4, $5}'
)
errors=$("$(tool terminal)" --errors)
replace() { # marker content file
    awk -v m="$1" -v content="$2" '
        $0 == "<!-- generated:" m " -->" { print; print content; skip = 1; next }
        $0 == "<!-- /generated:" m " -->" { skip = 0 }
        !skip { print }' "$3"
}
new=$(replace limits "$limits" README.md)
new=$(replace errors "$errors" <(printf '%s\n' "$new"))
if [ $check -eq 1 ]; then
    if ! diff -u README.md <(printf '%s\n' "$new") >/dev/null; then
        diff -u README.md <(printf '%s\n' "$new") | head -n 30
        echo "README.md tables are stale: run 'make readme'"
        exit 1
    fi
    echo "README.md tables match the X-macro lists"
else
    printf '%s\n' "$new" > README.md
fi
