#!/usr/bin/env bash
# Capacity and memory of `bearingd run` (docs/PERFORMANCE.md, issue 12 item 5, issue 13 item 3):
# N simulated sensors at 25.6 kHz in real time, MCAP logging, alerts, twin re-fits and the HW
# model on, for D seconds, optionally pinned to one core. Prints the daemon's own summary
# (fits made and dropped) and /usr/bin/time's maximum RSS and CPU.
#
#   scripts/bench_capacity.sh [CHANNELS=64] [SECONDS=40] [CORE=0|none]
#
# BIN overrides the binary (default target/release/bearingd); HW=off turns the online
# Hammerstein–Wiener model off (twin.hw_enabled = false), to see what it costs. The daemon runs
# with the systemd unit's GLIBC_TUNABLES (its heap in huge pages), as installed; HEAP=4k runs
# it with the environment as it is.
set -euo pipefail
cd "$(dirname "$0")/.."
channels="${1:-64}" seconds="${2:-40}" core="${3:-0}"
bin="${BIN:-target/release/bearingd}"
[ -x "$bin" ] || { echo "no $bin: build it with cargo build --release"; exit 1; }
[ -x /usr/bin/time ] || { echo "no /usr/bin/time: apt-get install time"; exit 1; }
# Not under /tmp: the config check refuses an iceoryx2 root there (systemd's PrivateTmp).
mkdir -p target
dir=$(mktemp -d "$PWD/target/bench-capacity.XXXXXX")
[ -n "${KEEP:-}" ] || trap 'rm -rf "$dir"' EXIT
echo "dir: $dir"
{
  for i in $(seq 0 $((channels - 1))); do
    printf '[[sensors]]\nid = "s%02d"\ntransport = "sim"\nsample_rate_hz = 25600\nbearing = "skf-6205-2rs"\n' "$i"
    printf '[sensors.speed]\nsource = "fixed"\nrpm = 1772\n'
    # A fault starting at staggered times, so that flags, alerts and re-fits all happen.
    printf '[sensors.sim]\nfault = "outer"\nonset_s = %s\nseverity = 1.5\nseed = %d\n\n' \
      "$(awk "BEGIN{print 2 + ($i % 16) * 2.5}")" $((i + 1))
  done
  if [ "${HW:-on}" = off ]; then printf '[twin]\nhw_enabled = false\n'; fi
  printf '[outputs]\nstate_dir = "%s/state"\nmcap_dir = "%s/mcap"\niceoryx2_root = "%s/iox"\nalerts_service = "bearingd/capacity-%d/alerts"\n' \
    "$dir" "$dir" "$dir" "$$"
} > "$dir/config.toml"
"$bin" validate "$dir/config.toml" >/dev/null
if [ "${HEAP:-huge}" != 4k ]; then
  GLIBC_TUNABLES=$(sed -n 's/^Environment=GLIBC_TUNABLES=//p' systemd/bearingd.service)
  export GLIBC_TUNABLES
fi
pin=()
[ "$core" != none ] && pin=(taskset -c "$core")
echo "== $channels channels × 25.6 kHz, HW model ${HW:-on}, heap ${HEAP:-huge}, $seconds s of signal, core ${core}, load $(cut -d' ' -f1-3 /proc/loadavg)"
"${pin[@]}" /usr/bin/time -v "$bin" run --config "$dir/config.toml" --duration "$seconds" --quiet \
  2> "$dir/stderr" > "$dir/stdout" || { tail -20 "$dir/stderr"; exit 1; }
grep -iE "fit|dropped|summary" "$dir/stderr" "$dir/stdout" | sed 's/^[^:]*://' | tail -8
grep -E "Maximum resident|User time|System time|Elapsed \(wall|Percent of CPU" "$dir/stderr"
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg); log: $(du -sh "$dir/mcap" | cut -f1)"
