#!/usr/bin/env bash
# Makes the fuzz targets' committed inputs from bearingd's own outputs, never from
# ../shared/data (a recording there is not ours to commit):
#   fuzz/corpus/<target>/         seeds the bounded runs start from (scripts/fuzz_ci.sh)
#   fuzz/regressions/mcap_*/      issue 32's hostile MCAP files (a 4 GiB string in a string
#                                 map, a 4 GiB record, the magic then random bytes, a cut log)
#   fuzz/dict/config.dict         every key and table name of the documented default config
# Run by hand from anywhere after `cargo build --release -p bearingd`; needs .venv (scipy) for
# the .mat seeds. Deterministic except the MCAP logs' timestamps. Crash inputs the fuzzer finds
# are added to fuzz/regressions/<target>/ by hand, next to the fix (fuzz/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."
bearingd=target/release/bearingd
python=.venv/bin/python
[ -x "$bearingd" ] || { echo "build bearingd first: cargo build --release -p bearingd" >&2; exit 1; }
[ -x "$python" ] || { echo "make the venv first (.ci/run's python step): $python is missing" >&2; exit 1; }

work=target/fuzz-seeds
corpus=fuzz/corpus
rm -rf "$work" "$corpus"
mkdir -p "$work/iox" "$corpus"/{can_frames,iox_payloads,recordings,mcap_read,mcap_recover,config_toml} \
  fuzz/regressions/mcap_read fuzz/regressions/mcap_recover fuzz/dict
chmod 700 "$work/iox"

# config_toml: the documented default, and the same with a CAN and an iceoryx2 source.
"$bearingd" config default > "$corpus/config_toml/default.toml"
cp tests/vm/run.toml "$corpus/config_toml/vm-run.toml"
sed -n 's/^#\? *\([a-z_][a-z0-9_]*\) *=.*/\1/p; s/^#\? *\[\[*\([a-z_.]*\)\]*\].*/\1/p' \
  "$corpus/config_toml/default.toml" | sort -u | sed 's/.*/"&"/' > fuzz/dict/config.dict

# can_frames: what a node sends (metadata, speed, two axes), in both layouts.
cargo run -q --release -p bearing-wire --example seed_frames -- fd 300 > "$corpus/can_frames/fd.bin"
cargo run -q --release -p bearing-wire --example seed_frames -- classic 60 > "$corpus/can_frames/classic.bin"

# A 1 s log of the embedded default (its iceoryx2 root outside /tmp, as the config requires),
# then the recordings' raw material: simulated CSV and WAV, .mat files made from the CSV.
"$bearingd" config default | sed "s#\"/run/bearingd/iceoryx2\"#\"$PWD/$work/iox\"#" > "$work/config.toml"
"$bearingd" run --config "$work/config.toml" --data-dir "$work/data" --fast --quiet --duration 1 >/dev/null
"$bearingd" simulate --fault outer --duration 0.02 --fs 12000 --out "$work/sim.csv" >/dev/null
"$bearingd" simulate --fault inner --duration 0.02 --fs 12000 --out "$work/sim.wav" >/dev/null
"$python" tests/python/make_mat.py mfpt "$work/sim.csv" "$work/mfpt.mat" 12000 1772
"$python" tests/python/make_mat.py nested "$work/sim.csv" "$work/nested.mat" 12000 1772

"$python" - "$work" "$corpus" <<'EOF'
"""Writes the seeds that are packed bytes (iceoryx2 payloads, recordings with the target's
two leading bytes) and the MCAP regression inputs."""
import glob
import random
import struct
import sys
from pathlib import Path

work, corpus = Path(sys.argv[1]), Path(sys.argv[2])

# iox_payloads: the FD frames as FrameBatch samples (#[repr(C)], little-endian), and an Alert.
frames, raw = [], (corpus / "can_frames/fd.bin").read_bytes()
while raw:
    can_id, length = struct.unpack_from("<IB", raw)
    frames.append((can_id, raw[5:5 + length]))
    raw = raw[5 + length:]
def batch(part):
    out = struct.pack("<II", 1, len(part))
    for can_id, data in part + [(0, b"")] * (64 - len(part)):
        out += struct.pack("<IB3x", can_id, len(data)) + data.ljust(64, b"\0")
    return out
(corpus / "iox_payloads/batches.bin").write_bytes(batch(frames[:64]) + batch(frames[64:128]))
alert = struct.pack("<QQQQdddddIBBBB32s32s", 3, 1_764_000_000_000_000_000, 512_000, 1_764_000_001_000_000_000,
                    25_600.0, 105.9, 4.2, 0.93, float("nan"), 1, 1, 1, 2, 0, b"motor-de", b"radial")
assert len(alert) == 144
(corpus / "iox_payloads/alert.bin").write_bytes(alert)

# recordings: [name index][channel index][content]; the indices are NAMES and CHANNELS of
# fuzz/fuzz_targets/recordings.rs (0 .mat, 1 table.csv, 2 acc_00001.csv, 3 .wav, 4 .txt,
# 5 IMS name, 6 no extension; channel 0 none, 1 "1", 4 "horizontal", 5 "B1x").
samples = [float(line) for line in (work / "sim.csv").read_text().splitlines()[1:] if line.strip()]
def recording(name, channel, content, file):
    (corpus / "recordings" / file).write_bytes(bytes([name, channel]) + content)
recording(0, 0, (work / "mfpt.mat").read_bytes(), "mfpt.mat.bin")
recording(0, 0, (work / "nested.mat").read_bytes(), "nested.mat.bin")
recording(6, 0, (work / "nested.mat").read_bytes(), "nested-no-extension.bin")
recording(1, 0, (work / "sim.csv").read_bytes(), "sim.csv.bin")
recording(3, 0, (work / "sim.wav").read_bytes(), "sim.wav.bin")
table = "time,de,fe\n" + "".join(f"{i / 12000:.6f},{x:.5f},{x / 2:.5f}\n" for i, x in enumerate(samples[:60]))
recording(4, 1, table.encode(), "table.txt.bin")
pronostia = "".join(f"9,39,39,{65664 + 39 * i},{x:.3f},{-x:.3f}\n" for i, x in enumerate(samples[:60]))
recording(2, 4, pronostia.encode(), "acc.csv.bin")
ims = "".join("\t".join(f"{x * k:.3f}" for k in (1, -1, 0.5, 2, 1, 1, -0.5, 0.25)) + "\r\n" for x in samples[:60])
recording(5, 5, ims.encode(), "ims.bin")
recording(6, 0, ims.encode(), "ims-no-extension.bin")

# mcap_read, mcap_recover: the 1 s log whole and cut inside a chunk.
log = Path(sorted(glob.glob(str(work / "data/mcap/*.mcap")))[0]).read_bytes()
for target in ("mcap_read", "mcap_recover"):
    (corpus / target / "run-1s.mcap").write_bytes(log)
    (corpus / target / "run-1s-cut.mcap").write_bytes(log[: len(log) // 2])

# Issue 32's hostile files, the regressions of both MCAP targets (tests/suite/hostile_logs.rs
# makes the same for the CLI).
MAGIC = b"\x89MCAP0\r\n"
def record(opcode, declared_len, body):
    return bytes([opcode]) + struct.pack("<Q", declared_len) + body
def string(text):
    return struct.pack("<I", len(text)) + text
header = string(b"") + string(b"hostile")
start = MAGIC + record(0x01, len(header), header)
key_4gib = struct.pack("<I", 0xFFFFFFFF) + b"abc"
metadata = string(b"bearingd.run") + struct.pack("<I", len(key_4gib)) + key_4gib
hostile = {
    "string-map-key-4gib.mcap": start + record(0x0C, len(metadata), metadata),
    "record-4gib.mcap": start + record(0x0C, 4 << 30, bytes(64)),
    "magic-then-random.mcap": MAGIC + random.Random(7).randbytes(20_000),
    "cut-inside-a-chunk.mcap": log[: len(log) // 2],
}
for target in ("mcap_read", "mcap_recover"):
    for name, content in hostile.items():
        (Path("fuzz/regressions") / target / name).write_bytes(content)
EOF
du -sh "$corpus" fuzz/regressions
