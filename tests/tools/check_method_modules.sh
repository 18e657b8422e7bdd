#!/usr/bin/env bash
# check_method_modules.sh [ROOT] - a face method is known in its module only (issue 12).
#
# A method (KEEP, PLANE, GREGORY, and the ones to come) is one file in
# decoder/methods/ plus the encoder's half, host_tools/encode/enc_NAME.c;
# everything else dispatches through the table (cm_method.h).  This gate
# fails on any CM_METHOD_KEEP, _PLANE, _GREGORY, _GREGORY_EXACT or _GREGORY_FIT in
# product code outside those files and the two that define the numbers
# (cm_format.h: the wire numbers, cm_method.h: the fallback), so that a
# switch on a method cannot creep back into the decoder, the tessellation,
# the reports or the link.  Tests may name methods.
set -u
root=${1:-.}
cd "$root" || exit 2
hits=$(grep -rn --include='*.c' --include='*.h' -E 'CM_METHOD_(KEEP|PLANE|GREGORY|GREGORY_EXACT|GREGORY_FIT)\b' decoder host_tools platform fixedcfg |
    grep -v -E '^decoder/methods/[a-z_]+\.c:|^host_tools/encode/enc_[a-z]+\.c:|^decoder/include/cm/cm_format\.h:|^decoder/src/cm/cm_method\.h:')
if [ -n "$hits" ]; then
    echo "a face method is named outside its module (dispatch through cm_method.h instead):"
    echo "$hits"
    exit 1
fi
n=$(ls decoder/methods/*.c | wc -l)
echo "methods named only in their modules ($n files in decoder/methods/)"
