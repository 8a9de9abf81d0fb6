#!/usr/bin/env bash
# Issue 12, item 6: iceoryx2 ingest across two processes, measured (not asserted).
#
# 1. Throughput: `firmware-sim` publishes 16 streams (4 nodes x 4 axes, CAN FD frames, 25.6 kHz)
#    as fast as it can; `bearingd ingest --shm --block-when-full` receives (decoding in place
#    from the loaned samples) and reports samples/s while data arrived, gaps and drops.
# 2. Loss at N x real time: `bearingd run` with one iceoryx2 sensor (the whole pipeline, MCAP
#    log included) while `firmware-sim` sends 60 s of one 25.6 kHz node at FACTORS x real time;
#    the daemon's summary line must end at t=60.0s with no GAPS.
#
# Usage: scripts/bench_iox_ingest.sh   (release builds of bearingd and firmware-sim first:
#        cargo build --release -p bearingd -p firmware-sim). BIN=dir of the binaries,
#        FACTORS="8 20" speed factors, SECONDS_SENT=20 for the throughput run.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-target/release}
FACTORS=${FACTORS:-"8 20"}
SECONDS_SENT=${SECONDS_SENT:-20}
# iceoryx2's root must not be under /tmp (the daemon's config refuses it).
WORK=$(mktemp -d -p "$PWD/target" iox-bench.XXXXXX)
trap 'rm -rf "$WORK"' EXIT
PREFIX="bdbench$$_"
echo "load: $(uptime)"

echo "== throughput: 4 nodes x 4 axes, FD, ${SECONDS_SENT} s of 25.6 kHz, as fast as possible"
"$BIN/bearingd" ingest --shm bench --iox-prefix "$PREFIX" --iox-root "$WORK" \
    --until-idle 3 --block-when-full --expect-gaps 0 --expect-streams 16 \
    --expect-samples $((SECONDS_SENT * 25600)) > "$WORK/ingest.out" &
INGEST=$!
"$BIN/firmware-sim" --transport shm --sensor bench --fd --nodes 4 --axes 4 \
    --speed-factor 0 --duration "$SECONDS_SENT" --fs 25600 --speed-every 0 --loop-after 1 \
    --iox-prefix "$PREFIX" --iox-root "$WORK" --wait-ready 20 | tail -1
wait "$INGEST" || true
grep -E "^ingest:|RESULT|gaps|dropped" "$WORK/ingest.out" | grep -v "^stream" | head -5

for factor in $FACTORS; do
    echo "== bearingd run, one iceoryx2 node, 60 s of 25.6 kHz at ${factor}x real time"
    run="$WORK/run-$factor"
    mkdir -p "$run"
    cat > "$run/node.toml" <<TOML
[[sensors]]
id = "node1"
transport = "shm"
sample_rate_hz = 25600
scale_g_per_count = 0.00048828125
axes = ["radial"]
bearing = "skf-6205-2rs"
[sensors.speed]
source = "can"
max_rpm = 2500

[outputs]
state_dir = "$run/state"
mcap_dir = "$run/mcap"
iceoryx2_root = "$WORK"
TOML
    wall=$(python3 -c "print(60 / $factor + 8)")
    BEARINGD_IOX_PREFIX="${PREFIX}r${factor}_" "$BIN/bearingd" run --config "$run/node.toml" \
        --duration "$wall" --quiet > "$run/daemon.out" 2>&1 &
    DAEMON=$!
    "$BIN/firmware-sim" --transport shm --sensor node1 --node 1 --fault outer --onset 20 \
        --rpm 1772 --fs 25600 --duration 60 --speed-factor "$factor" --seed 3 --noise 0.1 \
        --iox-prefix "${PREFIX}r${factor}_" --iox-root "$WORK" --wait-ready 20 | tail -1
    wait "$DAEMON" || true
    grep -E "^summary|node1/radial t=" "$run/daemon.out" | head -2
done
