#!/bin/sh
# /init of the power-loss VM (see power_loss_vm_test.sh): mounts the virtio disk (ext4) at
# /data, runs `bearingd run` on the simulated sensor with its logs on that disk, and after
# CUT_AFTER seconds resets the machine at once (sysrq b: no sync, no unmount), as a power cut
# does. The kernel is told not to write dirty pages back on its own, so what reaches the disk
# is what bearingd forced there (fsync) or what a file system commit took.
export PATH=/bin
mount -t proc proc /proc; mount -t sysfs sysfs /sys; mount -t devtmpfs devtmpfs /dev
mount -t tmpfs tmpfs /tmp
mkdir -p /dev/shm; mount -t tmpfs tmpfs /dev/shm
case=$(sed -n 's/.*case=\([^ ]*\).*/\1/p' /proc/cmdline)
cut_after=$(sed -n 's/.*cut_after=\([^ ]*\).*/\1/p' /proc/cmdline)
echo "INIT: case $case, userspace up at $(cut -d' ' -f1 /proc/uptime)s kernel $(uname -r)"
for m in virtio_ring virtio virtio_pci_modern_dev virtio_pci_legacy_dev virtio_pci virtio_blk \
  crc32c_generic crc16 mbcache jbd2 ext4; do
  [ -f /lib/modules/$m.ko ] && { insmod /lib/modules/$m.ko || echo "INIT: insmod $m FAILED"; }
done
echo 0 > /proc/sys/vm/dirty_writeback_centisecs
echo 360000 > /proc/sys/vm/dirty_expire_centisecs
n=0
while [ ! -b /dev/vda ] && [ $n -lt 50 ]; do sleep 0.1; n=$((n + 1)); done
mkdir -p /data
mount -t ext4 -o commit=300 /dev/vda /data || { echo "POWERTEST: FAIL no /data"; echo o > /proc/sysrq-trigger; }
echo 1 > /proc/sys/kernel/sysrq
t0=$(cut -d' ' -f1 /proc/uptime)
bearingd run --config /etc/power-$case.toml > /tmp/run.out 2>&1 &
sleep "$cut_after"
t1=$(cut -d' ' -f1 /proc/uptime)
grep -a ' t=' /tmp/run.out | tail -n 1 | sed 's/^/LASTSTATUS /'
grep -a -v ' t=' /tmp/run.out | head -n 20 | sed 's/^/RUN /'
echo "POWERCUT started=$t0 cut=$t1"
# Let the serial console send the lines above before the reset: a reset right after the echo
# lost the POWERCUT line once, which the host then read as "never reached the cut". The
# daemon runs on for that second; the control case still loses everything since its last
# writeback (dirty pages expire after an hour), and the synced case can only keep more.
sleep 1
echo b > /proc/sysrq-trigger
