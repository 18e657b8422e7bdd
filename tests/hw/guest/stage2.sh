#!/bin/bash
# PID 1 of the test VM once /init has switched to overlay(host / read-only +
# tmpfs).  Sets up what a booted Debian would have, runs the command that
# run-in-vm.sh left in the run directory (HW_SHARE, a writable 9p share),
# stores its exit status there and powers off.  From the kernel command
# line: HW_SHARE, HW_VMB (make-vm.sh's build directory), HW_GUEST.
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
export HOME=/root TERM=dumb LANG=C.UTF-8
K=$(uname -r)
power_off() { sync; echo o > /proc/sysrq-trigger; sleep 10; }
opts=trans=virtio,version=9p2000.L,msize=262144

# fresh tmpfs over the scratch directories, except one that holds the checkout or the run directory
# (a clone under /tmp): a tmpfs there would hide the VM's modules (HW_VMB) and the run directory, and
# the overlay root is writable anyway
for d in /tmp /run /var/tmp /dev/shm; do
    mkdir -p "$d"
    case "$HW_VMB/" in "$d"/*) continue ;; esac
    case "$HW_SHARE/" in "$d"/*) continue ;; esac
    mount -t tmpfs tmpfs "$d"
done
mkdir -p /dev/pts
mount -t devpts -o gid=5,mode=620,ptmxmode=666 devpts /dev/pts
[ -e /dev/fd ] || ln -s /proc/self/fd /dev/fd
[ -e /dev/stdin ] || { ln -s fd/0 /dev/stdin; ln -s fd/1 /dev/stdout; ln -s fd/2 /dev/stderr; }
# `modprobe X` and the kernel's own request_module() must find the VM kernel's modules.  The host
# may have a /lib/modules/$K of its own (linux-headers puts a build link there): replace it.
rm -rf "/lib/modules/$K"
mkdir -p /lib/modules
ln -s "$HW_VMB/kroot/lib/modules/$K" "/lib/modules/$K"
modprobe configfs && mount -t configfs configfs /sys/kernel/config
mount -t debugfs debugfs /sys/kernel/debug 2>/dev/null

mount -t 9p -o "$opts" share "$HW_SHARE" || { echo "vm stage2: cannot mount the run directory $HW_SHARE"; power_off; }
# host directories the caller wants writable (run-in-vm.sh VM_RW): "TAG DIR" lines
if [ -f "$HW_SHARE/rw-mounts" ]; then
    while read -r tag dir; do
        mkdir -p "$dir" && mount -t 9p -o "$opts" "$tag" "$dir" || echo "vm stage2: cannot mount $dir writable"
    done < "$HW_SHARE/rw-mounts"
fi
hostname hw-vm
ip link set lo up 2>/dev/null
echo "vm stage2: ready after $(cut -d' ' -f1 /proc/uptime) s of guest uptime"

cd "$(cat "$HW_SHARE/cwd")" 2>/dev/null || cd /
bash "$HW_SHARE/cmd.sh" < /dev/null
rc=$?
echo "$rc" > "$HW_SHARE/rc"
echo "vm stage2: command exited with status $rc after $(cut -d' ' -f1 /proc/uptime) s of guest uptime"
umount "$HW_SHARE" 2>/dev/null
power_off
