#!/usr/bin/env bash
# Power loss in a qemu VM (issue 11): `bearingd run` writes its logs to an ext4 file system on
# a virtio disk, and the VM is reset mid-run with sysrq b (no sync, no unmount), as a power cut
# does. The disk is opened by qemu with cache=directsync, so a write the guest's kernel made
# is on the image, and what sat in the guest's page cache is lost, as with a real cut. The
# guest's periodic writeback is turned off and ext4 commits every 300 s, so only what bearingd
# forced to the disk survives: the test measures what `outputs.mcap_fsync_interval_s` keeps.
#
# Two cases, each a fresh 256 MiB ext4 image and a boot:
#   synced   mcap_fsync_interval_s = 2: the log up to at most the interval plus the open chunk
#            before the cut survives and reads (asserted: at most 4 s lost, at least 5 s logged)
#   control  mcap_fsync_interval_s = 3600 (never within the run): without fsync the log is lost
#            (asserted: at least 10 s lost), which shows the cut is a real one
# What survived is copied out of the image with e2fsck (the journal replayed, as the next
# mount does) and debugfs (no mount needed), and read on the host
# by `bearingd replay --json`, which reads an unfinished file up to its last complete chunk, as
# recovery does at the next start.
#
# usage: tests/vm/power_loss_vm_test.sh [workdir]   (default target/power-vm)
set -euo pipefail
export PATH=$PATH:/usr/sbin:/sbin
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
WORK=${1:-$ROOT/target/power-vm}
CUT_AFTER=${POWER_CUT_AFTER:-20}
mkdir -p "$WORK"
WORK=$(cd "$WORK" && pwd)
export DEBIAN_FRONTEND=noninteractive
NAME=power-vm
. "$ROOT/tests/vm/common.sh"

# 1. Host tools (e2fsprogs: the file system, the journal replay and the copy out of the image).
vm_host_tools mkfs.ext4:e2fsprogs e2fsck:e2fsprogs debugfs:e2fsprogs strip:binutils
python=${PYTHON:-$ROOT/.venv/bin/python}
"$python" -c 'import mcap' 2>/dev/null ||
  missing "the Python package mcap" "pip install -r scripts/requirements-ci.txt (.ci/run makes .venv)"

# 2. Kernel and busybox.
vm_kernel

# 3. The test step's bearingd (common.sh): in the VM, and on the host to replay the logs.
vm_binaries
HOSTBIN=$HOST_BIN/bearingd

# 4. initramfs: busybox, the block and ext4 modules, bearingd, one config per case.
say "initramfs"
IR=$WORK/initramfs
rm -rf "$IR"; mkdir -p "$IR"/{bin,proc,sys,dev,tmp,etc,lib/modules}
cp "$BB" "$IR/bin/busybox"
for a in sh mount insmod cat echo cut uname sleep sed grep head tail mkdir; do
  ln -s busybox "$IR/bin/$a"
done
for m in virtio_ring virtio virtio_pci_modern_dev virtio_pci_legacy_dev virtio_pci virtio_blk \
  crc32c_generic crc16 mbcache jbd2 ext4; do
  found=$(find "$MODDIR" -name "$m.ko" | head -n 1)
  # Built into this kernel when absent (the init skips it).
  [ -n "$found" ] && cp "$found" "$IR/lib/modules/"
done
vm_install_binary "$HOSTBIN" "$IR"
for case in synced control; do
  case $case in synced) every=2;; control) every=3600;; esac
  "$HOSTBIN" config default |
    sed -e 's|^state_dir = .*|state_dir = "/data/state"|' \
        -e 's|^mcap_dir = .*|mcap_dir = "/data/mcap"|' \
        -e 's|^iceoryx2_root = .*|iceoryx2_root = "/dev/shm/bearingd"|' \
        -e 's|^status_interval_s = .*|status_interval_s = 0.5|' \
        -e "s|^mcap_fsync_interval_s = .*|mcap_fsync_interval_s = $every|" > "$IR/etc/power-$case.toml"
  grep -q "^mcap_fsync_interval_s = $every\$" "$IR/etc/power-$case.toml" ||
    { echo "power-vm: the default config has no mcap_fsync_interval_s line to set"; exit 1; }
done
cp "$ROOT/tests/vm/power_init.sh" "$IR/init"
chmod +x "$IR/init"
(cd "$IR" && find . | "$BB" cpio -o -H newc 2>/dev/null | gzip -1) > "$WORK/initramfs.cpio.gz"
cp "$WORK/kroot/boot/vmlinuz-$KVER" "$WORK/vmlinuz"

# 5. One boot per case, each on a fresh disk; what survived is read on the host.
status=0
for case in synced control; do
  img=$WORK/$case.img
  rm -f "$img"
  truncate -s 256M "$img"
  mkfs.ext4 -q -F "$img"
  say "boot $KVER under qemu TCG: case $case, power cut after ${CUT_AFTER} s"
  timeout 300 qemu-system-x86_64 -accel tcg -m 1024 -smp 2 \
    -nodefaults -no-user-config -display none -serial stdio -no-reboot \
    -kernel "$WORK/vmlinuz" -initrd "$WORK/initramfs.cpio.gz" \
    -drive "file=$img,format=raw,if=virtio,cache=directsync" \
    -append "console=ttyS0 quiet panic=-1 case=$case cut_after=$CUT_AFTER" \
    > "$WORK/serial-$case.log" 2>&1 || say "qemu exit $?"
  grep -a -E '^(INIT|LASTSTATUS|RUN|POWERCUT|POWERTEST)' "$WORK/serial-$case.log" || true
  cut_line=$(grep -a '^POWERCUT' "$WORK/serial-$case.log" | tr -d '\r' || true)
  if [ -z "$cut_line" ]; then
    echo "power-vm: case $case: the VM never reached the power cut (see $WORK/serial-$case.log)"
    status=1; continue
  fi
  # The signal the daemon had when the power went: the sample time of its last status line
  # (the analysis' position; the sensor had sent at most a status interval more).
  analysed=$(grep -a '^LASTSTATUS' "$WORK/serial-$case.log" | sed -n 's/.* t=\([0-9.]*\)s.*/\1/p' | tail -n 1)
  analysed=${analysed:-0}
  out=$WORK/survived-$case
  rm -rf "$out"; mkdir -p "$out"
  # The journal replayed as the next mount would (e2fsck; debugfs alone reads the image as the
  # cut left it, without the metadata committed to the journal), then the logs copied out.
  e2fsck -fy "$img" > "$WORK/e2fsck-$case.log" 2>&1 || true
  debugfs -R "rdump /mcap $out" "$img" > "$WORK/debugfs-$case.log" 2>&1 || true
  files=$(find "$out" -name 'bearingd-*.mcap' | wc -l)
  logged=0
  if [ "$files" -gt 0 ]; then
    replay_json=$("$HOSTBIN" replay --quiet --json --out "$WORK/replay-$case" \
      $(find "$out" -name 'bearingd-*.mcap' | sort) 2> "$WORK/replay-$case.err" || true)
    logged=$(printf '%s' "$replay_json" | "$python" -c \
      'import json,sys; print(json.load(sys.stdin).get("sample_seconds", 0))' 2>/dev/null || echo 0)
  fi
  lost=$("$python" -c "print(round(max(0.0, $analysed - $logged), 2))")
  echo "POWER $case: signal at the cut ${analysed} s, read back ${logged} s, lost ${lost} s ($files file(s) on the disk)"
  case $case in
    synced) verdict=$("$python" -c "print('PASS' if $lost <= 4.0 and $logged >= 5.0 else 'FAIL')");;
    control) verdict=$("$python" -c "print('PASS' if $lost >= 10.0 else 'FAIL')");;
  esac
  echo "POWERTEST $case: $verdict"
  [ "$verdict" = PASS ] || status=1
done
say "total wall time $(( $(date +%s) - started )) s"
if [ $status = 0 ]; then echo "POWER LOSS VM TEST: PASS"; else echo "POWER LOSS VM TEST: FAIL"; fi
exit $status
