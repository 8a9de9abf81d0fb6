#!/usr/bin/env python3
"""Reads the numbers docs/MCAP.md states about a daemon's log and compares them with a log the
daemon just wrote (`bearingd run --fast --duration 60` of the embedded default):

    mcap_doc_numbers.py MCAP.md LOG.mcap

- the raw block: "one block per S s (N samples at F kHz)";
- the spectrum: "one per S s of sample time", "N bins of B Hz"; the indicators: "one per S s";
- the size table: the log file (within 10 %: twin fits vary with the machine's speed), raw
  blocks alone and with a float32 `g` field (within 2 %, measured here as the doc says: zstd
  level 3 over each second of encoded blocks), each day column = 1440 x the 60 s column, and
  the hours the default disk budget keeps with and without `g`.

Prints a JSON summary; exit status 1 on the first number that does not hold.
"""

import json
import os
import re
import statistics
import sys

import numpy
import zstandard
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoderFactory

SECONDS = 60
PER_DAY = 1440
BUDGET_BYTES = 4096 * 1024 * 1024


class Failed(Exception):
    pass


def find(pattern, text, what):
    m = re.search(pattern, text)
    if m is None:
        raise Failed(f"MCAP.md does not state {what} (looked for /{pattern}/)")
    return [g.replace(",", "") for g in m.groups()]


def close(stated, measured, tolerance, what):
    if abs(measured - stated) > tolerance * abs(stated):
        raise Failed(f"{what}: MCAP.md says {stated}, the log has {measured}")
    return {"what": what, "doc": stated, "log": measured}


def varint(n):
    out = bytearray()
    while True:
        low, n = n & 0x7F, n >> 7
        if n == 0:
            out.append(low)
            return bytes(out)
        out.append(low | 0x80)


def raw_bytes(blocks, with_g):
    """Compressed bytes of the raw blocks, zstd level 3 over each second (10 blocks), as the
    log's chunks are flushed; with `with_g`, each block carries field 6, packed float32 g."""
    compressor = zstandard.ZstdCompressor(level=3)
    total, chunk, per_second = 0, b"", max(1, round(1.0 / blocks[0][1]))
    for i, (data, _, counts, scale) in enumerate(blocks):
        chunk += data
        if with_g:
            g = (numpy.array(counts, dtype=numpy.float64) * scale).astype("<f4").tobytes()
            chunk += b"\x32" + varint(len(g)) + g
        if i % per_second == per_second - 1 or i == len(blocks) - 1:
            total += len(compressor.compress(chunk))
            chunk = b""
    return total


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1]) as f:
        doc = f.read()
    log = sys.argv[2]
    blocks, ends = [], {}
    with open(log, "rb") as f:
        reader = make_reader(f, decoder_factories=[ProtobufDecoderFactory()])
        for schema, channel, message in reader.iter_messages():
            if channel.topic.startswith("/raw/"):
                pb = ProtobufDecoderFactory().decoder_for("protobuf", schema)(message.data)
                duration = len(pb.counts) / pb.sample_rate_hz
                blocks.append((message.data, duration, list(pb.counts), pb.scale_g_per_count))
                fs = pb.sample_rate_hz
            elif schema.encoding == "jsonschema":
                value = json.loads(message.data)
                ends.setdefault(channel.topic.split("/")[1], []).append(value)
    checked = []
    try:
        s, n, khz = find(r"one block per ([\d.]+) s \(([\d,]+) samples at ([\d.]+) kHz\)", doc,
                         "the raw block's length")
        checked.append(close(float(s), statistics.median(b[1] for b in blocks), 1e-9, "block s"))
        checked.append(close(int(n), statistics.median(len(b[2]) for b in blocks), 0, "samples"))
        checked.append(close(float(khz), fs / 1000, 1e-9, "kHz"))

        def spacing(topic):
            e = [m["end_sample"] for m in ends[topic]]
            return statistics.median(b - a for a, b in zip(e, e[1:])) / fs

        (s,) = find(r"\| `/spectrum/<sensor>/<axis>` \|[^\n]*?\| one per ([\d.]+) s of sample time", doc, "spectrum rate")
        checked.append(close(float(s), spacing("spectrum"), 1e-9, "spectrum every s"))
        bins, bin_hz = find(r"([\d,]+) bins of ([\d.]+) Hz", doc, "the spectrum's bins")
        spectra = ends["spectrum"]
        checked.append(close(int(bins), statistics.median(len(m["amplitude"]) for m in spectra),
                             0, "bins"))
        checked.append(close(float(bin_hz), spectra[0]["bin_hz"], 1e-9, "bin Hz"))
        (s,) = find(r"\| `/indicators/<sensor>/<axis>` \|[^\n]*?\| one per ([\d.]+) s", doc, "indicators rate")
        checked.append(close(float(s), spacing("indicators"), 1e-9, "indicators every s"))

        size = os.path.getsize(log)
        rows = {}
        for label in ("the log file", "raw blocks alone", "raw blocks with a float32 g field"):
            b, gb = find(r"\| " + label + r"[^|]*\| ([\d,]+) B \| ([\d.]+) GB \|", doc, label)
            rows[label] = int(b)
            checked.append(close(float(gb), int(b) * PER_DAY / 1e9, 0.006, f"{label} per day"))
        checked.append(close(rows["the log file"], size, 0.10, "log bytes per 60 s"))
        checked.append(close(rows["raw blocks alone"], raw_bytes(blocks, False), 0.02, "raw"))
        checked.append(close(rows["raw blocks with a float32 g field"], raw_bytes(blocks, True),
                             0.02, "raw with g"))
        hours, hours_g = find(r"keeps about ([\d.]+) h of such a log, and with `g` about ([\d.]+) h",
                              doc, "the hours the budget keeps")
        per_hour = rows["the log file"] * 60
        extra = (rows["raw blocks with a float32 g field"] - rows["raw blocks alone"]) * 60
        checked.append(close(float(hours), BUDGET_BYTES / per_hour, 0.03, "hours kept"))
        checked.append(close(float(hours_g), BUDGET_BYTES / (per_hour + extra), 0.03,
                             "hours kept with g"))
    except Failed as e:
        print(f"mcap_doc_numbers.py: {e}", file=sys.stderr)
        return 1
    print(json.dumps(checked, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
