#!/usr/bin/env bash
# make-vm.sh - prepare the throw-away test VM that `make check-hw` boots.
#
# The VM runs Debian's own kernel (the linux-image-amd64 of the apt lists)
# under qemu TCG, with this machine's root file system shared read-only over
# virtio-9p, so every host tool and every binary of the checkout runs in it
# unchanged (tests/hw/run-in-vm.sh).  Debian builds that kernel without
# gpio-sim and irq_sim, so both are compiled here, out of tree, from the
# linux-source package of exactly the same version.
#
# Output in $VM_BUILD (default build/vm of this checkout):
#   kver                   the kernel ABI (6.1.0-NN-amd64)
#   kroot/boot/vmlinuz-K   the kernel; vmlinux-pvh its uncompressed ELF (boots ~2 s faster)
#   kroot/lib/modules/K    Debian's modules + extra/{irq_sim,gpio-sim}.ko, depmod'ed
#   initrd.gz              busybox + the modules that mount the 9p root and the overlay
#   stamp                  written last: all of the above is complete
# Idempotent: a second run only checks the stamp (well under a second).
# Env: VM_BUILD, VM_KVER (skip the apt lookup), VM_NO_APT=1 (install nothing),
#      VM_FORCE=1 (rebuild everything).
# Exit: 0 ready; 1 failed; 3 qemu-system-x86_64 cannot be installed (callers skip).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
REPO=$(cd "$HERE/../.." && pwd)
B=${VM_BUILD:-$REPO/build/vm}
export DEBIAN_FRONTEND=noninteractive
START=$(date +%s.%N)
say() { printf '[make-vm %5.1fs] %s\n' "$(awk -v s="$START" -v n="$(date +%s.%N)" 'BEGIN{print n-s}')" "$*"; }
die() { echo "make-vm: $*" >&2; exit 1; }

# The stamp records what the VM was built from; a change of kernel or of the
# guest scripts rebuilds the initramfs (the modules survive a guest change).
guest_sum() { cat "$HERE/guest/init" | cksum | cut -d' ' -f1; }
if [ "${VM_FORCE:-0}" != 1 ] && [ -f "$B/stamp" ] && [ -f "$B/initrd.gz" ] &&
   [ "$(cat "$B/stamp")" = "$(cat "$B/kver" 2>/dev/null) $(guest_sum)" ] &&
   command -v qemu-system-x86_64 >/dev/null; then
    say "VM is up to date in $B (kernel $(cat "$B/kver"))"
    exit 0
fi
rm -f "$B/stamp"
mkdir -p "$B"

APT_GET=(apt-get -o DPkg::Lock::Timeout=600 -q)
apt_updated=0
apt_update() {
    [ $apt_updated = 0 ] || return 0
    apt_updated=1
    # a mirror caught mid-sync makes update exit 100 although what we need installs: retry, then go on
    "${APT_GET[@]}" update >/dev/null 2>&1 || { sleep 5; "${APT_GET[@]}" update >/dev/null 2>&1; } ||
        say "warning: apt-get update failed, using the lists we have"
}
installed() { [[ "$(dpkg-query -W -f='${db:Status-Abbrev}' "$1" 2>/dev/null)" == ii* ]]; }
need() {  # install the Debian packages of "$@" that are missing
    local missing=() p
    for p in "$@"; do installed "$p" || missing+=("$p"); done
    [ ${#missing[@]} -eq 0 ] && return 0
    [ "${VM_NO_APT:-0}" != 1 ] || die "missing packages (VM_NO_APT=1): ${missing[*]}"
    [ "$(id -u)" = 0 ] || die "missing packages, run as root: apt-get install ${missing[*]}"
    say "installing ${missing[*]}"
    "${APT_GET[@]}" install -y --no-install-recommends "${missing[@]}" >/dev/null ||
        { apt_update; "${APT_GET[@]}" install -y --no-install-recommends "${missing[@]}" >/dev/null; }
}

# ---- 1. qemu first: without it there is nothing to do (exit 3 = skip) ----
if ! command -v qemu-system-x86_64 >/dev/null; then
    need qemu-system-x86 || { echo "make-vm: qemu-system-x86 cannot be installed" >&2; exit 3; }
fi
need busybox-static cpio kmod xz-utils make gcc libc6-dev

# ---- 2. which kernel: the one linux-image-amd64 points to (headers and source must match it) ----
kernel_abi() { apt-cache depends linux-image-amd64 2>/dev/null |
    awk '/Depends: linux-image-[0-9]/ { sub("linux-image-", "", $2); print $2; exit }'; }
K=${VM_KVER:-$(kernel_abi)}
if [ -z "$K" ]; then apt_update; K=$(kernel_abi); fi
[ -n "$K" ] || die "cannot tell the kernel version: apt-cache knows no linux-image-amd64"
V=$(apt-cache show "linux-image-$K" 2>/dev/null | awk '/^Version:/ { print $2; exit }')
[ -n "$V" ] || die "apt-cache has no linux-image-$K"
KMM=$(echo "$K" | cut -d. -f1,2)
if [ "$(cat "$B/kver" 2>/dev/null)" != "$K" ]; then
    # another kernel than last time: nothing built for the old one is reusable
    rm -rf "$B/kroot" "$B/vmlinux-pvh" "$B/gpiomod" "$B/initrd.gz" "$B/debs"
fi
say "kernel $K ($V), gpio-sim from linux-source-$KMM"
need "linux-headers-$K"

mkdir -p "$B/debs"
fetch() {  # fetch PACKAGE=VERSION into debs/ unless a .deb of it is there
    local name=${1%%=*}
    ls "$B/debs/${name}_"*.deb >/dev/null 2>&1 && return 0
    (cd "$B/debs" && apt-get download -qq "$1" 2>&1 | grep -v -e unsandboxed -e '^Get:' -e '^Fetched' >&2) || true
    ls "$B/debs/${name}_"*.deb >/dev/null 2>&1 || { apt_update; (cd "$B/debs" && apt-get download -q "$1" >/dev/null 2>&1) || true; }
    ls "$B/debs/${name}_"*.deb >/dev/null 2>&1 || die "cannot download $1"
}

# ---- 3. the kernel and its modules ----
KR="$B/kroot"
if [ ! -f "$KR/boot/vmlinuz-$K" ] || [ ! -f "$KR/.keeps-kms" ]; then
    fetch "linux-image-$K=$V"
    rm -rf "$KR"
    dpkg-deb -x "$B/debs/linux-image-${K}_"*.deb "$KR"
    # Trees no test of a terminal's devices will load (graphics, sound, media, radios, network
    # cards, storage fabrics): about half of the 400 MB of modules.  Of the graphics drivers only
    # the DRM core and bochs stay: the KMS driver of qemu's bochs-display, the screen
    # tests/hw/vm-drm.sh draws on (Debian's kernel has no vkms).
    M="$KR/lib/modules/$K/kernel"
    find "$M/drivers/gpu" -name '*.ko*' ! -name 'bochs.ko*' ! -name 'drm.ko*' ! -name 'drm_kms_helper.ko*' \
        ! -name 'drm_vram_helper.ko*' ! -name 'drm_ttm_helper.ko*' ! -name 'ttm.ko*' \
        ! -name 'drm_panel_orientation_quirks.ko*' -delete 2> /dev/null
    : > "$KR/.keeps-kms"
    rm -rf "$M/drivers/media" "$M/drivers/net/wireless" "$M/drivers/net/ethernet" \
        "$M/drivers/infiniband" "$M/drivers/staging" "$M/sound" "$M/drivers/bluetooth" \
        "$M/net/wireless" "$M/net/mac80211" "$M/net/bluetooth" "$M/drivers/iio" "$M/drivers/isdn" \
        "$M/drivers/scsi/qla2xxx" "$M/drivers/scsi/lpfc" "$M/drivers/scsi/bfa" "$M/drivers/scsi/mpt3sas" \
        "$M/drivers/md" "$M/fs/btrfs" "$M/fs/xfs" "$M/fs/ocfs2" "$M/fs/gfs2" "$M/fs/ceph" "$M/fs/nfs" "$M/fs/nfsd"
    rm -f "$B/debs/linux-image-"*.deb
fi
if [ ! -f "$B/vmlinux-pvh" ]; then
    # The bzImage carries an xz-compressed ELF vmlinux with a PVH entry note; qemu -kernel
    # starts that directly in protected mode (no SeaBIOS real-mode loader, no decompression).
    off=$(LC_ALL=C grep -obUaP '\xfd7zXZ\x00' "$KR/boot/vmlinuz-$K" | head -n 1 | cut -d: -f1)
    if [ -n "$off" ]; then
        tail -c +$((off + 1)) "$KR/boot/vmlinuz-$K" | xz -dcq > "$B/vmlinux-pvh.tmp" 2>/dev/null || true
    fi
    if [ "$(head -c 4 "$B/vmlinux-pvh.tmp" 2>/dev/null | tail -c 3)" = ELF ]; then
        mv "$B/vmlinux-pvh.tmp" "$B/vmlinux-pvh"
    else
        rm -f "$B/vmlinux-pvh.tmp"; say "no PVH vmlinux inside the bzImage: the VM boots through SeaBIOS"
    fi
fi
say "kernel unpacked"

# ---- 4. gpio-sim + irq_sim, out of tree, from the same kernel version's source ----
G="$B/gpiomod"
if [ ! -f "$G/gpio-sim.ko" ] || [ ! -f "$G/irq_sim.ko" ]; then
    fetch "linux-source-$KMM=$V"
    rm -rf "$G"; mkdir -p "$G"
    dpkg-deb --fsys-tarfile "$B/debs/linux-source-${KMM}_"*.deb |
        tar -xO "./usr/src/linux-source-$KMM.tar.xz" |
        tar -xJ -C "$G" --strip-components=3 \
            "linux-source-$KMM/drivers/gpio/gpio-sim.c" "linux-source-$KMM/drivers/gpio/gpiolib.h" \
            "linux-source-$KMM/kernel/irq/irq_sim.c"
    # irq_sim is built-in-only upstream: irq_to_desc() is not exported to modules, and the
    # simulated irqchip's flow handler is handle_simple_irq, which generic_handle_irq() calls.
    sed -i 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq(irqnum);/' "$G/irq_sim.c"
    grep -q 'generic_handle_irq(irqnum);' "$G/irq_sim.c" || die "irq_sim.c changed upstream: the patch no longer applies"
    printf '\nMODULE_LICENSE("GPL");\nMODULE_DESCRIPTION("irq_sim, built as a module for the test VM");\n' >> "$G/irq_sim.c"
    echo 'obj-m += irq_sim.o gpio-sim.o' > "$G/Kbuild"
    make -s -C "/usr/src/linux-headers-$K" M="$G" -j2 modules 2>&1 | grep -v 'Skipping BTF' >&2 || true
    [ -f "$G/gpio-sim.ko" ] && [ -f "$G/irq_sim.ko" ] || die "building gpio-sim/irq_sim failed"
    rm -f "$B/debs/linux-source-"*.deb   # 139 MB, only 3 files of it were needed
    find "$G" -type f ! -name '*.ko' ! -name '*.c' ! -name '*.h' ! -name Kbuild -delete
fi
mkdir -p "$KR/lib/modules/$K/extra"
cp "$G/irq_sim.ko" "$G/gpio-sim.ko" "$KR/lib/modules/$K/extra/"
depmod -b "$KR" "$K"
say "gpio-sim and irq_sim built"

# ---- 5. the initramfs: busybox and what it needs to mount the host's / ----
I="$B/initramfs"
rm -rf "$I"; mkdir -p "$I"/{bin,dev,proc,sys,modules,ro,rw,root}
cp "$(command -v busybox)" "$I/bin/busybox"
file_of() { modprobe -d "$KR" -S "$K" --show-depends "$1" | awk '$1 == "insmod" { print $2 }'; }
: > "$I/modules.order"
for m in virtio_pci 9pnet_virtio 9p overlay; do file_of "$m"; done | awk '!seen[$0]++' |
while read -r f; do
    cp "$f" "$I/modules/"; basename "$f" >> "$I/modules.order"
done
cp "$HERE/guest/init" "$I/init"; chmod 755 "$I/init"
(cd "$I" && find . | cpio -o -H newc --quiet | gzip -1 > "$B/initrd.gz.tmp") && mv "$B/initrd.gz.tmp" "$B/initrd.gz"
rm -rf "$I"
echo "$K" > "$B/kver"
echo "$K $(guest_sum)" > "$B/stamp"
say "done: $(du -sh "$B" | cut -f1) in $B"
