#!/usr/bin/env bash
# check_noheap.sh NM ARCHIVE ALLOWLIST - no-heap gate, layer (a).
#
# Every symbol the decoder/kernel archive needs from outside itself must be
# on the allowlist (libm, mem* and compiler support).  That rejects the
# allocator and stdio, and also libc calls that allocate inside (qsort,
# printf), which the --wrap=malloc layer cannot see.
set -u
nm=$1 ar=$2 allow=$3
defined=$("$nm" --defined-only "$ar" 2>/dev/null | awk 'NF>=3 {print $3}' | sort -u)
undef=$("$nm" -u "$ar" | awk 'NF>=2 && $1=="U" {print $2}' | sort -u)
external=$(comm -23 <(echo "$undef") <(echo "$defined"))
bad=$(comm -23 <(echo "$external" | grep -v '^$') <(grep -v '^#' "$allow" | grep -v '^$' | sort -u))
if [ -n "$bad" ]; then
    echo "check-noheap: $ar uses symbols outside the allowlist ($allow):"
    echo "$bad" | sed 's/^/  /'
    exit 1
fi
echo "check-noheap: $ar calls only: $(echo $external)"
