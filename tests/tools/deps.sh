#!/usr/bin/env bash
# deps.sh PKG... - install the Debian packages curvemesh needs, if any is missing.
#
# Root: adds the foreign architectures in $DEPS_ARCHS, runs `apt-get update`
# (retried: a mirror caught mid-sync makes it exit 100 although everything
# needed still installs) and `apt-get install`.  Not root: prints the exact
# commands to run and fails.  Does nothing when everything is installed.
set -u
missing=()
for p in "$@"; do
    status=$(dpkg-query -W -f='${db:Status-Abbrev}' "$p" 2>/dev/null)
    [[ "$status" == ii* ]] || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

need_archs=()
for a in ${DEPS_ARCHS:-}; do
    dpkg --print-foreign-architectures | grep -qx "$a" || need_archs+=("$a")
done

if [ "$(id -u)" -ne 0 ]; then
    echo "make deps: missing Debian packages: ${missing[*]}" >&2
    echo "run as root:" >&2
    for a in "${need_archs[@]}"; do echo "  dpkg --add-architecture $a" >&2; done
    echo "  apt-get update && apt-get install -y --no-install-recommends ${missing[*]}" >&2
    exit 1
fi

echo "make deps: installing ${missing[*]}"
for a in "${need_archs[@]}"; do dpkg --add-architecture "$a" || exit 1; done
export DEBIAN_FRONTEND=noninteractive
apt_update() {
    for i in 1 2 3; do
        apt-get -o DPkg::Lock::Timeout=600 -q update && return 0
        echo "make deps: apt-get update failed (attempt $i), retrying" >&2
        sleep $((i * 5))
    done
    echo "make deps: apt-get update still failing; trying to install from the lists we have" >&2
}
apt_update
for i in 1 2; do
    apt-get -o DPkg::Lock::Timeout=600 -q install -y --no-install-recommends "${missing[@]}" && exit 0
    echo "make deps: apt-get install failed (attempt $i)" >&2
    apt_update
done
echo "make deps: could not install: ${missing[*]}" >&2
exit 1
