#!/usr/bin/env python3
"""Reads the Hammerstein–Wiener channels of a bearingd MCAP log with Python `mcap`'s strict
reader and checks each model's time residual against the raw samples of the same log.

    hw_log.py FILE.mcap

For every `/hw/<sensor>/<axis>` message with a model: the raw samples it was identified on
are taken from the `/raw/<sensor>/<axis>` blocks (protobuf, `mcap-protobuf-support`), from
`first_sample` on; for order 0 the measured output is the median (width 5, the window
shrinking at the ends) of those samples, normalised by the message's `output_mean` and
`output_scale`; the accuracy `100·(1 − ‖residual‖/‖y − mean(y)‖)` recomputed from the logged
simulation residual must equal the logged `accuracy_simulation` (within 0.5 points: the daemon
works on the f32 samples it received).

Prints one JSON object: `hw` (per message: end_sample, first_sample, residual length, logged
and recomputed accuracy, baseline_fits, drifts, problem), `schema` (name and encoding).
Exit status 1 when the log cannot be read strictly, a channel lacks its JSON Schema, or a
recomputed accuracy disagrees.
"""

import json
import sys

import numpy as np
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoderFactory


def median5(x):
    n = len(x)
    out = np.empty(n)
    for k in range(n):
        reach = min(2, k, n - 1 - k)
        out[k] = np.median(x[k - reach : k + reach + 1])
    return out


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    path = sys.argv[1]
    raw = {}  # channel -> {first_sample: samples}
    hw = []
    schema_seen = None
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[ProtobufDecoderFactory()])
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            topic = channel.topic
            if topic.startswith("/raw/"):
                block = ProtobufDecoderFactory().decoder_for("protobuf", schema)(message.data)
                samples = np.array(block.counts, dtype=float) * block.scale_g_per_count
                raw.setdefault(topic[len("/raw/") :], {})[block.first_sample] = samples
            elif topic.startswith("/hw/"):
                if schema is None or schema.encoding != "jsonschema" or channel.message_encoding != "json":
                    print(f"{path}: {topic} has no JSON Schema", file=sys.stderr)
                    return 1
                json.loads(schema.data)
                schema_seen = {"name": schema.name, "encoding": schema.encoding}
                decoded = json.loads(message.data)
                decoded["key"] = topic[len("/hw/") :]
                hw.append(decoded)

    out = []
    bad = 0
    for m in hw:
        row = {
            k: m[k]
            for k in (
                "end_sample",
                "first_sample",
                "order",
                "accuracy_simulation",
                "baseline_fits",
                "residual_drift_sigma",
                "parameter_drift",
                "problem",
                "warm_start",
            )
        }
        row["residual_len"] = len(m["residual_simulation"])
        row["one_step_len"] = len(m["residual_one_step"])
        if m["problem"] is None and m["order"] == 0:
            blocks = raw.get(m["key"], {})
            signal = np.concatenate([blocks[s] for s in sorted(blocks)]) if blocks else np.array([])
            start = min(blocks) if blocks else 0
            cut = signal[m["first_sample"] - start : m["end_sample"] - start]
            n = row["residual_len"]
            y = (median5(cut)[:n] - m["output_mean"]) / m["output_scale"]
            r = np.array(m["residual_simulation"], dtype=float)
            if len(y) != n:
                print(f"{path}: {m['key']} at {m['end_sample']}: {len(y)} raw samples for {n} residuals", file=sys.stderr)
                bad += 1
                continue
            recomputed = 100.0 * (1.0 - np.linalg.norm(r) / np.linalg.norm(y - y.mean()))
            row["recomputed_accuracy"] = recomputed
            if abs(recomputed - m["accuracy_simulation"]) > 0.5:
                print(f"{path}: {m['key']} at {m['end_sample']}: logged accuracy {m['accuracy_simulation']:.3f}, recomputed {recomputed:.3f}", file=sys.stderr)
                bad += 1
        out.append(row)
    print(json.dumps({"hw": out, "schema": schema_seen}))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
