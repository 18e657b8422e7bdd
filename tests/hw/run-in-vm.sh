#!/usr/bin/env bash
# run-in-vm.sh - run one command as root in a fresh test VM and return its
# exit status.
#
#   tests/hw/run-in-vm.sh [-t SECONDS] [-m MiB] [--] COMMAND [ARGS...]
#
# The VM (made by tests/hw/make-vm.sh) boots Debian's kernel under qemu TCG
# with one CPU and sees this machine's / read-only under a tmpfs overlay: the
# command runs in the same directory, with the same tools and binaries, and
# can change nothing of the host except the directories in VM_RW.  Its
# output, and the guest's console, come to our stdout (lines end in \r\n).
# qemu always runs under `timeout`: a guest that hangs is killed after
# SECONDS (default 300).
#
# Env: VM_BUILD (default build/vm of this checkout), VM_RW='DIR...' (host
#      directories mounted writable at the same path), VM_QEMU_ARGS (extra qemu
#      arguments, word-split), VM_ACCEL=tcg|kvm (default tcg: see below),
#      VM_KEEP=1 (keep the run directory).  Variables named HW_* are passed
#      on to the command.
# Exit: the command's status; 124 the VM timed out; 125 the VM failed before
#       the command finished (no status came back).
set -uo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
REPO=$(cd "$HERE/../.." && pwd)
B=${VM_BUILD:-$REPO/build/vm}
timeout_s=300 mem=1024
while [ $# -gt 0 ]; do
    case $1 in
    -t) timeout_s=$2; shift 2 ;;
    -m) mem=$2; shift 2 ;;
    --) shift; break ;;
    -*) echo "run-in-vm: unknown option $1" >&2; exit 125 ;;
    *) break ;;
    esac
done
[ $# -gt 0 ] || { sed -n '2,23p' "$0" >&2; exit 125; }
[ -f "$B/stamp" ] || { echo "run-in-vm: no VM in $B: run tests/hw/make-vm.sh first" >&2; exit 125; }
K=$(cat "$B/kver")

# TCG, one CPU.  The /dev/kvm on these machines is kvm_pvm, which boots only PVM guest kernels
# (Debian's kernel dies in the decompressor or on an emulation failure), and under TCG -smp 2
# boots slower than -smp 1 on a 2-core host.
# shellcheck disable=SC2054
case ${VM_ACCEL:-tcg} in
kvm) accel=(-accel kvm -cpu host,-arch-capabilities) ;;
*) accel=(-accel tcg,thread=multi -cpu max) ;;
esac
kernel=$B/kroot/boot/vmlinuz-$K
[ -f "$B/vmlinux-pvh" ] && kernel=$B/vmlinux-pvh

mkdir -p "$B/runs"
run=$(mktemp -d "$B/runs/run.XXXXXX") || exit 125
[ "${VM_KEEP:-0}" = 1 ] || trap 'rm -rf "$run"' EXIT
pwd > "$run/cwd"
{
    echo "set -o pipefail"
    declare -px | grep -E '^declare -x HW_[A-Za-z0-9_]*=' || true
    printf '%q ' "$@"
    echo
} > "$run/cmd.sh"

rw=() n=0
for d in ${VM_RW:-}; do
    d=$(cd "$d" && pwd) || exit 125
    rw+=(-virtfs "local,path=$d,mount_tag=rw$n,security_model=none,multidevs=remap")
    echo "rw$n $d" >> "$run/rw-mounts"
    n=$((n + 1))
done

start=$(date +%s.%N)
# --foreground: qemu keeps the terminal's signals; -k: a qemu that ignores SIGTERM gets SIGKILL;
# bochs-display: a PCI display a KMS driver (bochs) drives, for tests/hw/vm-drm.sh (nothing shows it:
# -display none; the guest loads its driver only when a test asks)
timeout --foreground -k 5 "$timeout_s" qemu-system-x86_64 "${accel[@]}" -smp 1 -m "$mem" \
    -nodefaults -no-user-config -no-reboot -display none -monitor none -serial stdio -device bochs-display \
    -kernel "$kernel" -initrd "$B/initrd.gz" \
    -append "console=ttyS0 quiet loglevel=3 panic=-1 HW_GUEST=$HERE/guest HW_VMB=$B HW_SHARE=$run" \
    -virtfs local,path=/,mount_tag=hostroot,security_model=none,readonly=on,multidevs=remap \
    -virtfs "local,path=$run,mount_tag=share,security_model=none,multidevs=remap" \
    "${rw[@]}" ${VM_QEMU_ARGS:-} < /dev/null
qrc=$?
wall=$(awk -v s="$start" -v e="$(date +%s.%N)" 'BEGIN { printf "%.1f", e - s }')
if [ -f "$run/rc" ]; then
    rc=$(cat "$run/rc")
elif [ $qrc = 124 ] || [ $qrc = 137 ]; then
    rc=124
    echo "run-in-vm: the VM did not finish within ${timeout_s} s and was killed" >&2
else
    rc=125
    echo "run-in-vm: the VM stopped (qemu status $qrc) before the command finished" >&2
fi
echo "run-in-vm: ${wall} s, qemu status $qrc, command status $rc" >&2
exit "$rc"
