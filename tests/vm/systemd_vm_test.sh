#!/usr/bin/env bash
# bearingd as a real systemd service, end to end, in a qemu VM.
#
# A Debian 12 root (debootstrap minbase + systemd, cached under the work directory) gets
# bearingd through `make install-service DESTDIR=<root> BIN=<the test build's binary>`, its user through
# systemd-sysusers, a config whose only sensor is the in-process simulated one (outer-race
# fault from 2 s of sample time), and `systemctl enable bearingd`. The root is booted as an
# initramfs with systemd as PID 1 (rdinit=/lib/systemd/systemd) under qemu TCG. A oneshot probe
# unit (tests/vm/systemd_probe.sh) then checks, each ending in "VMTEST <name>: PASS|FAIL ...":
#   active     bearingd reached "active" (Type=notify: READY=1 sent) and reports STATUS=
#   cpu-latency  bearingd holds /dev/cpu_dma_latency open (outputs.cpu_wakeup_latency_us = 50)
#              through the unit's sandbox, the device's group set by the installed tmpfiles.d
#   heap-pages systemd passes the unit's GLIBC_TUNABLES (the heap in huge pages) to bearingd,
#              which says nothing of 4 KiB pages
#   alert-root-refused  `bearingd alerts` started as root exits 2 with the runuser fix
#   alert      `bearingd alerts --json --count 1`, as user bearingd, received the outer-race
#              alert, state "raised"
#   alert-history  a late `bearingd alerts` as user bearingd got the active alert from history
#   status-flag  the flag shows in the STATUS= line bearingd sends systemd
#   stop       `systemctl stop bearingd`: inactive, Result=success, main process exited 0
#   mcap-sent  the MCAP file(s) of /var/log/bearingd were sent to the host over a second serial
#              port (base64 between markers, with size and sha256)
# and on the host:
#   install    make install put every file in place (the learned models too), created no config
#              over an existing one
#   mcap       each file arrived intact; Python mcap's strict reader reads it with its summary,
#              it holds the /flags/ message of the fault, and every twin fit the opinion of the
#              installed 6205 model (the config names /usr/share/bearingd/models;
#              tests/vm/check_vm_mcap.py)
# Any FAIL or missing line fails the test. On failure the probe prints `systemctl status` and
# the journal of bearingd to the serial log ($WORK/serial.log).
#
# usage: tests/vm/systemd_vm_test.sh [workdir]   (default target/systemd-vm). Needs root
# (debootstrap, chroot; apt-get for missing tools); with CI=true a missing piece is a failure,
# never a skip.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
WORK=${1:-$ROOT/target/systemd-vm}
mkdir -p "$WORK"
WORK=$(cd "$WORK" && pwd)
export DEBIAN_FRONTEND=noninteractive
NAME=systemd-vm
. "$ROOT/tests/vm/common.sh"
SENSOR=vm-sim

# 1. Host tools.
[ "$(id -u)" = 0 ] || missing "root" "run as root (debootstrap and chroot need it)"
vm_host_tools debootstrap:debootstrap make:make strip:binutils
python=${PYTHON:-$ROOT/.venv/bin/python}
[ -x "$python" ] || python=python3
"$python" -c 'import mcap.reader' 2>/dev/null ||
  missing "the Python package mcap (1.6)" "pip install -r scripts/requirements-ci.txt (.ci/run makes .venv)"

# 2. Kernel and busybox (for cpio).
vm_kernel

# 3. The Debian root: debootstrap once, then reused (delete $WORK/base to refresh it).
if [ ! -x "$WORK/base/lib/systemd/systemd" ]; then
  # The mirror this machine's apt already uses.
  mirror=$(awk '/^URIs:/{print $2; exit}' /etc/apt/sources.list.d/debian.sources 2>/dev/null || true)
  [ -n "$mirror" ] || mirror=$(awk '/^deb /{print $2; exit}' /etc/apt/sources.list 2>/dev/null || true)
  [ -n "$mirror" ] || missing "a Debian mirror in /etc/apt/sources.list(.d)" "configure apt"
  say "debootstrap bookworm (minbase + systemd) from $mirror"
  t=$(date +%s)
  rm -rf "$WORK/base.tmp"
  timeout 900 debootstrap --variant=minbase --include=systemd,systemd-sysv bookworm \
    "$WORK/base.tmp" "$mirror" > "$WORK/debootstrap.log" 2>&1 ||
    { tail -20 "$WORK/debootstrap.log"; missing "a debootstrap'ed root" "see $WORK/debootstrap.log"; }
  mv "$WORK/base.tmp" "$WORK/base"
  say "debootstrap took $(( $(date +%s) - t )) s"
fi

# 4. The test step's bearingd (common.sh), with iceoryx2 (alerts) and SocketCAN; the VM's
#    root is Debian 12 as the host, so its C library is there. Stripped for the VM: the
#    release profile keeps debug info, which would only fatten the root.
vm_binaries
strip -o "$WORK/bearingd" "$HOST_BIN/bearingd"

# 5. The VM's root: a fresh copy of the base, then installed as an administrator would.
say "make install-service DESTDIR=<root> BIN=<the test build's binary>"
R=$WORK/root
rm -rf "$R"
cp -a "$WORK/base" "$R"
make -s -C "$ROOT" install-service DESTDIR="$R" BIN="$WORK/bearingd" > "$WORK/install.log"
install_ok=PASS install_detail=
check_installed() {
  if [ ! -e "$R$1" ]; then install_ok=FAIL; install_detail+=" missing $1;"; fi
}
for f in /usr/bin/bearingd /usr/lib/systemd/system/bearingd.service \
  /usr/lib/sysusers.d/bearingd.conf /usr/lib/tmpfiles.d/bearingd.conf /usr/share/doc/bearingd/SYSTEMD.md /etc/bearingd/bearingd.toml \
  /usr/share/man/man1/bearingd.1 /usr/share/man/man1/bearingd-run.1 \
  /usr/share/bash-completion/completions/bearingd /usr/share/zsh/vendor-completions/_bearingd \
  /usr/share/fish/vendor_completions.d/bearingd.fish /usr/share/bearingd/models/skf-6205-2rs.safetensors; do
  check_installed "$f"
done
cmp -s "$ROOT/config/bearingd.toml" "$R/etc/bearingd/bearingd.toml" ||
  { install_ok=FAIL; install_detail+=" /etc/bearingd/bearingd.toml is not the default config;"; }
cmp -s "$ROOT/systemd/bearingd.service" "$R/usr/lib/systemd/system/bearingd.service" ||
  { install_ok=FAIL; install_detail+=" the unit differs from systemd/bearingd.service with PREFIX=/usr;"; }
# The user, as a package's postinst would create it (the root's own systemd-sysusers).
chroot "$R" systemd-sysusers
chroot "$R" getent passwd bearingd > "$WORK/passwd.line" ||
  { install_ok=FAIL; install_detail+=" systemd-sysusers created no user bearingd;"; }
chroot "$R" getent group bearingd > /dev/null ||
  { install_ok=FAIL; install_detail+=" no group bearingd;"; }

# The test config: the simulated sensor only, fault early; everything else the defaults (the
# unit's directories). 12.8 kHz keeps the emulated CPU's load and the MCAP file small.
cat > "$WORK/test.toml" <<EOF
# systemd VM test (tests/vm/systemd_vm_test.sh): one simulated sensor, outer-race fault at 2 s.
[[sensors]]
id = "$SENSOR"
transport = "sim"
sample_rate_hz = 12800
bearing = "skf-6205-2rs"
[sensors.speed]
rpm = 1772
[sensors.sim]
fault = "outer"
onset_s = 2.0
[analysis]
band_period_s = 5.0
[thresholds]
on_delay_s = 1.0
[twin]
# The installed models (make install), read by the service's user under the unit's sandbox;
# every re-fit logs the 6205 model's opinion (check_vm_mcap.py).
learned_model = "/usr/share/bearingd/models"
refit_period_s = 3.0
[outputs]
status_interval_s = 2.0
# Not 0: polling idle vCPUs would slow the emulated machine; the cap's path is what is tested.
cpu_wakeup_latency_us = 50
EOF
install -m 0644 "$WORK/test.toml" "$R/etc/bearingd/bearingd.toml"
# A second install (an upgrade) must keep the administrator's config.
make -s -C "$ROOT" install-service DESTDIR="$R" BIN="$WORK/bearingd" >> "$WORK/install.log"
cmp -s "$WORK/test.toml" "$R/etc/bearingd/bearingd.toml" ||
  { install_ok=FAIL; install_detail+=" a second make install overwrote /etc/bearingd/bearingd.toml;"; }
echo "VMTEST install: $install_ok ${install_detail:-binary, unit, sysusers.d, doc, models, man pages, completions, config in place; config kept on re-install; user $(cat "$WORK/passwd.line" 2>/dev/null)}" \
  | tee "$WORK/host-verdicts.log"

# The probe: a oneshot unit after bearingd that reports on ttyS0 and powers the VM off.
install -m 0755 "$ROOT/tests/vm/systemd_probe.sh" "$R/usr/local/bin/vmtest-probe"
cat > "$R/etc/systemd/system/vmtest-probe.service" <<EOF
[Unit]
Description=bearingd VM test probe (tests/vm/systemd_probe.sh)
After=bearingd.service multi-user.target
Wants=bearingd.service
[Service]
Type=oneshot
Environment=SENSOR=$SENSOR
ExecStart=/usr/local/bin/vmtest-probe
StandardOutput=tty
StandardError=tty
TTYPath=/dev/ttyS0
TTYReset=no
TTYVHangup=no
# The probe's own checks time out well before this; past it, the VM is powered off anyway.
TimeoutStartSec=480
ExecStopPost=/bin/systemctl poweroff --no-block
[Install]
WantedBy=multi-user.target
EOF
chroot "$R" systemctl enable bearingd.service vmtest-probe.service 2> "$WORK/enable.log"
chroot "$R" systemctl mask serial-getty@ttyS0.service getty@tty1.service \
  systemd-timesyncd.service 2>> "$WORK/enable.log"
echo "bearingd-vm" > "$R/etc/hostname"

# 6. initramfs of the whole root (busybox cpio: no cpio on the image).
say "initramfs"
(cd "$R" && find . -xdev | "$BB" cpio -o -H newc 2>/dev/null | gzip -1) > "$WORK/root.cpio.gz"
cp "$WORK/kroot/boot/vmlinuz-$KVER" "$WORK/vmlinuz"
say "initramfs $(( $(stat -c %s "$WORK/root.cpio.gz") / 1048576 )) MiB"

# 7. Boot under TCG (never -accel kvm: /dev/kvm exists on these machines but hangs). ttyS0 is
#    the console and the probe's output; ttyS1 carries the MCAP file(s) to $WORK/mcap.b64.
say "boot $KVER with systemd as PID 1 under qemu TCG"
rm -f "$WORK/serial.log" "$WORK/mcap.b64"
boot=$(date +%s)
qemu_rc=0
timeout 600 qemu-system-x86_64 -accel tcg -m 2048 -smp 2 \
  -nodefaults -no-user-config -display none -no-reboot \
  -serial "file:$WORK/serial.log" -serial "file:$WORK/mcap.b64" \
  -kernel "$WORK/vmlinuz" -initrd "$WORK/root.cpio.gz" \
  -append 'console=ttyS0 panic=-1 quiet rdinit=/lib/systemd/systemd systemd.show_status=error' \
  > "$WORK/qemu.log" 2>&1 || qemu_rc=$?
say "VM boot to power-off: $(( $(date +%s) - boot )) s (qemu exit $qemu_rc)"
[ "$qemu_rc" = 0 ] || { say "qemu failed or timed out:"; cat "$WORK/qemu.log"; }
tr -d '\r' < "$WORK/serial.log" > "$WORK/serial.txt"
grep -a -E '^(PROBE|VMTEST|VMINFO|DIAG|ALERT)' "$WORK/serial.txt" || true

# 8. The MCAP file(s), from ttyS1, checked with the strict Python reader.
rm -rf "$WORK/mcap"; mkdir -p "$WORK/mcap"
mcap_ok=PASS mcap_detail=
if ! "$python" - "$WORK/mcap.b64" "$WORK/mcap" > "$WORK/mcap-extract.log" 2>&1 <<'PY'
# Splits "MCAP-BEGIN name size sha256" / base64 / "MCAP-END name" into files; checks each.
import base64, hashlib, os, sys
src, out = sys.argv[1], sys.argv[2]
cur, lines, ok, n = None, [], True, 0
for raw in open(src, "rb").read().decode("ascii", "replace").splitlines():
    line = raw.strip()
    if line.startswith("MCAP-BEGIN "):
        cur, lines = line.split()[1:4], []
    elif line.startswith("MCAP-END ") and cur:
        name, size, digest = cur
        data = base64.b64decode("".join(lines))
        good = len(data) == int(size) and hashlib.sha256(data).hexdigest() == digest
        print(f"{name}: {len(data)} bytes (sent {size}), sha256 {'ok' if good else 'MISMATCH'}")
        ok &= good
        n += 1
        with open(os.path.join(out, os.path.basename(name)), "wb") as f:
            f.write(data)
        cur = None
    elif cur:
        lines.append(line)
if n == 0:
    print("no complete MCAP-BEGIN ... MCAP-END block on the second serial port")
sys.exit(0 if ok and n else 1)
PY
then
  mcap_ok=FAIL mcap_detail="transfer: $(tr '\n' ' ' < "$WORK/mcap-extract.log")"
else
  for f in "$WORK"/mcap/*.mcap; do
    if ! "$python" "$ROOT/tests/vm/check_vm_mcap.py" "$f" "$SENSOR" outer_race > "$f.check" 2>&1; then
      mcap_ok=FAIL mcap_detail+=" $(basename "$f"): $(tr '\n' ' ' < "$f.check");"
    fi
    sed 's/^/  /' "$f.check"
  done
  # The flag is in one of the files (there is one unless the log rotated).
  grep -q '^flag message:' "$WORK"/mcap/*.check ||
    { mcap_ok=FAIL mcap_detail+=" no file holds the flag;"; }
  grep -q '^learned opinion:' "$WORK"/mcap/*.check ||
    { mcap_ok=FAIL mcap_detail+=" no twin fit holds the installed model's opinion;"; }
  [ "$mcap_ok" = FAIL ] || mcap_detail="$(ls "$WORK"/mcap/*.mcap | wc -l) file(s), $(tr '\n' ' ' < "$WORK/mcap-extract.log")strict reader: summary present, every message read, /flags/$SENSOR/... holds outer_race, every /twin fit the installed model's opinion"
fi
echo "VMTEST mcap: $mcap_ok $mcap_detail" | tee -a "$WORK/host-verdicts.log"

# 9. Verdict: every expected line present, none failed.
status=0
cat "$WORK/host-verdicts.log" >> "$WORK/serial.txt"
for check in install active cpu-latency heap-pages alert-root-refused alert alert-history status-flag stop mcap-sent mcap; do
  line=$(grep -a -m1 "^VMTEST $check: " "$WORK/serial.txt" || true)
  case "$line" in
    "VMTEST $check: PASS"*) ;;
    "") echo "systemd-vm: no VMTEST $check line (see $WORK/serial.log)"; status=1 ;;
    *) echo "systemd-vm: $check failed"; status=1 ;;
  esac
done
if grep -a -q '^VMTEST .*: FAIL' "$WORK/serial.txt"; then status=1; fi
say "total wall time $(( $(date +%s) - started )) s"
if [ $status = 0 ]; then echo "SYSTEMD VM TEST: PASS"; else echo "SYSTEMD VM TEST: FAIL (serial log: $WORK/serial.log)"; fi
exit $status
