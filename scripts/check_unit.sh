#!/usr/bin/env bash
# Checks systemd/bearingd.service on a build machine, where /usr/bin/bearingd does not exist:
#
# 1. `systemd-analyze verify` on the unit exactly as shipped, inside a throw-away root
#    (--root) that holds the built binary as /usr/bin/bearingd and a copy of the host's unit
#    tree (verify needs sysinit.target & co. there). verify exits 0 on warnings such as an
#    unknown key or an unparsable value, so ANY output on stderr fails the check too.
# 2. `systemd-analyze security --offline=true`: prints the exposure score and the settings that
#    cost points; fails if the score rises above MAX_EXPOSURE (tenths: 20 = 2.0), so a
#    weakened unit does not slip through.
#
# Usage: scripts/check_unit.sh [UNIT]   (default systemd/bearingd.service)
# Needs: systemd-analyze (systemd >= 250) and target/release/bearingd (cargo build --release).
set -euo pipefail
cd "$(dirname "$0")/.."
unit=${1:-systemd/bearingd.service}
binary=${BEARINGD_BINARY:-target/release/bearingd}
max_exposure=${MAX_EXPOSURE:-20}

if [ ! -x "$binary" ]; then
  echo "check_unit: $binary missing; build it first (cargo build --release)" >&2
  exit 1
fi
if ! command -v systemd-analyze >/dev/null; then
  echo "check_unit: systemd-analyze not found (apt-get install systemd)" >&2
  exit 1
fi
units_dir=
for candidate in /usr/lib/systemd/system /lib/systemd/system; do
  if [ -f "$candidate/sysinit.target" ]; then units_dir=$candidate; break; fi
done
if [ -z "$units_dir" ]; then
  echo "check_unit: no systemd unit tree (sysinit.target) on this machine" >&2
  exit 1
fi

root=$(mktemp -d)
trap 'rm -rf "$root"' EXIT
mkdir -p "$root/usr/bin" "$root/usr/lib/systemd" "$root/etc/systemd/system"
cp -a "$units_dir" "$root/usr/lib/systemd/system"
# A hard link when possible (the release binary is large), else a copy.
ln "$binary" "$root/usr/bin/bearingd" 2>/dev/null || cp "$binary" "$root/usr/bin/bearingd"
name=$(basename "$unit")
cp "$unit" "$root/etc/systemd/system/$name"

echo "== systemd-analyze verify $unit"
status=0
errors=$(systemd-analyze verify --root="$root" --man=no --generators=no "$name" 2>&1 >/dev/null) || status=$?
if [ "$status" -ne 0 ] || [ -n "$errors" ]; then
  printf '%s\n' "$errors" | sed "s|$root||g" >&2
  echo "check_unit: FAILED: verify exited $status and wrote the above to stderr" >&2
  exit 1
fi
echo "ok: no warnings"

echo "== systemd-analyze security --offline=true $unit"
status=0
report=$(systemd-analyze security --offline=true --root="$root" --threshold="$max_exposure" \
  "$name" 2>&1) || status=$?
# The settings that cost points, then the overall score.
printf '%s\n' "$report" | grep -E '^✗|Overall exposure' || true
if [ "$status" -ne 0 ]; then
  echo "check_unit: FAILED: exposure above $((max_exposure / 10)).$((max_exposure % 10)) (or security failed, exit $status)" >&2
  exit 1
fi
