#!/usr/bin/env python3
"""Decode frames captured from a (virtual) CAN bus with cantools and config/bearingd.dbc.

The capture files are what `bearingd ingest --capture` wrote inside the test VM, in
`candump -l` format, read here with cantools' own log parser. For each file this checks that
every frame is a message of the DBC and decodes, that the metadata says the expected sample
rate and data-frame kind, and that each data stream is contiguous as the DBC decodes it
(first_sample advances by the frame's sample count, sequence by one).

Usage: check_capture.py DBC FILE:SAMPLE_RATE:classic|fd ...
Exits non-zero on any problem; prints one line per file.
"""

import sys

import cantools
from cantools.logreader import Parser


def check(db, path, rate, kind):
    problems = []
    frames = 0
    data_frames = 0
    metadata_rates = set()
    metadata_kinds = set()
    streams = {}
    with open(path) as f:
        for frame in Parser(f):
            if frame is None:
                continue
            frames += 1
            try:
                msg = db.get_message_by_frame_id(frame.frame_id)
            except KeyError:
                problems.append(f"id {frame.frame_id:#05x} is not in the DBC")
                continue
            truncated = len(frame.data) < msg.length
            try:
                signals = msg.decode(
                    frame.data, decode_choices=False, scaling=False, allow_truncated=truncated
                )
            except Exception as e:  # noqa: BLE001 - report any decoder failure
                problems.append(f"{msg.name}: {e}")
                continue
            if msg.name.startswith("METADATA"):
                if signals.get("page") == 0:
                    metadata_rates.add(signals["sample_rate_hz"])
                    metadata_kinds.add(signals["data_kind"])
            elif msg.name.startswith("DATA"):
                data_frames += 1
                if kind == "fd":
                    count, seq_mod, idx_mod = signals["sample_count"], 1 << 16, 1 << 32
                else:
                    count, seq_mod, idx_mod = (len(frame.data) - 4) // 2, 1 << 8, 1 << 24
                seq, first = signals["sequence"], signals["first_sample"]
                last = streams.get(frame.frame_id)
                if last is not None:
                    want_seq = (last[0] + 1) % seq_mod
                    want_first = (last[1] + last[2]) % idx_mod
                    if (seq, first) != (want_seq, want_first):
                        problems.append(
                            f"{msg.name}: sequence {seq} first_sample {first}, "
                            f"expected {want_seq} {want_first}"
                        )
                streams[frame.frame_id] = (seq, first, count)
    want_kind = 1 if kind == "fd" else 0
    if frames < 100 or data_frames < 90:
        problems.append(f"only {frames} frames ({data_frames} data) captured")
    if metadata_rates != {rate}:
        problems.append(f"metadata sample rates {sorted(metadata_rates)}, expected {rate}")
    if metadata_kinds != {want_kind}:
        problems.append(f"metadata data kinds {sorted(metadata_kinds)}, expected {want_kind}")
    return frames, data_frames, problems


def main():
    db = cantools.database.load_file(sys.argv[1], strict=True)
    failed = False
    for spec in sys.argv[2:]:
        path, rate, kind = spec.rsplit(":", 2)
        frames, data_frames, problems = check(db, path, int(rate), kind)
        verdict = "PASS" if not problems else "FAIL"
        print(f"cantools capture {path}: {frames} frames, {data_frames} data frames: {verdict}")
        for p in problems[:20]:
            print(f"  {p}")
        failed |= bool(problems)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
