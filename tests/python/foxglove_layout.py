#!/usr/bin/env python3
"""Checks the Foxglove layout against a log the daemon wrote: every topic and message path the
layout names must exist in that log's messages, resolved against the decoded messages as
Foxglove's message-path syntax reads them (`/topic{field=="value"}.field.sub[:]`).

    foxglove_layout.py LAYOUT.json LOG.mcap USER_SCRIPT.ts

- The layout's User Scripts (`userNodes`) are run first, by `tests/foxglove/run_user_script.cjs`
  (Node.js with TypeScript from `npm ci --prefix tests/foxglove`: a strict type check, then the
  script on every message of its inputs); their outputs count as the log's messages. The one
  script must be USER_SCRIPT.ts, byte for byte, and its `g` must be `counts x scale_g_per_count`
  and its `t_s` the samples' times, for every raw block.
- A path without a filter must resolve in every message of its topic; a filtered one in every
  message the filter keeps, and when the log has none, the filter's value must be one its
  field's JSON Schema allows. Plot paths must end in numbers; an XY plot's x and y arrays must
  have the same length in every message.
- The spectra must all have bins, and a frequency per bin (`frequency_hz[i] = i x bin_hz`).

Prints a JSON summary; exit status 1 on the first failed check.
"""

import json
import math
import os
import re
import subprocess
import sys

import numpy
from mcap.decoder import DecoderFactory
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoderFactory

HERE = os.path.dirname(os.path.abspath(__file__))
RUNNER = os.path.join(HERE, "..", "foxglove", "run_user_script.cjs")


class JsonDecoderFactory(DecoderFactory):
    def decoder_for(self, message_encoding, schema):
        return json.loads if message_encoding == "json" else None


class Failed(Exception):
    pass


def check(condition, what):
    if not condition:
        raise Failed(what)


def raw_to_dict(m):
    return {
        "channel": {"sensor": m.channel.sensor, "axis": m.channel.axis},
        "first_sample": m.first_sample,
        "sample_rate_hz": m.sample_rate_hz,
        "scale_g_per_count": m.scale_g_per_count,
        "counts": list(m.counts),
    }


def read_log(path):
    """Messages per topic (decoded to plain JSON values, with log_time) and JSON schemas."""
    messages, schemas = {}, {}
    with open(path, "rb") as f:
        reader = make_reader(
            f, decoder_factories=[ProtobufDecoderFactory(), JsonDecoderFactory()]
        )
        for schema, channel, message, value in reader.iter_decoded_messages():
            if schema is not None and schema.encoding == "jsonschema":
                schemas[channel.topic] = json.loads(schema.data)
            else:
                value = raw_to_dict(value)
            messages.setdefault(channel.topic, []).append((message.log_time, value))
    return messages, schemas


# ---- message paths ------------------------------------------------------------------------

FILTER = r"\{\s*([A-Za-z_][A-Za-z0-9_]*)\s*==\s*(\"[^\"]*\"|'[^']*'|-?[0-9.]+|true|false)\s*\}"
SEGMENT = re.compile(r"\.([A-Za-z_][A-Za-z0-9_]*)(?:" + FILTER + r")?(?:\[(:|-?[0-9]+)\])?")
TOPIC = re.compile(r"(/[^.{\s]+)(?:" + FILTER + r")?")


def literal(text):
    if text[0] in "\"'":
        return text[1:-1]
    if text in ("true", "false"):
        return text == "true"
    return float(text)


def parse_path(path):
    """(topic, topic filter or None, [(field, filter or None, slice or None)])."""
    m = TOPIC.match(path)
    check(m is not None, f"not a message path: {path!r}")
    topic = m.group(1)
    topic_filter = (m.group(2), literal(m.group(3))) if m.group(2) else None
    rest, segments = path[m.end():], []
    while rest:
        s = SEGMENT.match(rest)
        check(s is not None, f"cannot parse {rest!r} in {path!r}")
        seg_filter = (s.group(2), literal(s.group(3))) if s.group(2) else None
        segments.append((s.group(1), seg_filter, s.group(4)))
        rest = rest[s.end():]
    check(segments, f"{path!r} names a topic but no field")
    return topic, topic_filter, segments


def matches(value, flt):
    return flt is None or (isinstance(value, dict) and value.get(flt[0]) == flt[1])


def resolve(value, segments, path):
    """The leaves `segments` reach in `value`; raises Failed where a field is missing."""
    if not segments:
        return [value]
    (field, flt, sl), rest = segments[0], segments[1:]
    check(isinstance(value, dict) and field in value, f"{path}: no field {field!r} in {value!r:.200}")
    inner = value[field]
    if sl == ":" and flt is None and not rest:
        check(isinstance(inner, list), f"{path}: {field!r} is not an array")
        return inner
    if sl is None:
        items = [inner]
    else:
        check(isinstance(inner, list), f"{path}: {field!r} is not an array")
        items = inner if sl == ":" else inner[int(sl):int(sl) + 1]
    leaves = []
    for item in items:
        if matches(item, flt):
            leaves.extend(resolve(item, rest, path))
    return leaves


def schema_allows(schema, field, value):
    """Whether the top-level property `field` of a JSON Schema admits `value` (enum or const)."""
    prop = (schema or {}).get("properties", {}).get(field)
    check(prop is not None, f"the schema has no property {field!r}")
    options = prop.get("oneOf") or prop.get("anyOf") or [prop]
    allowed = []
    for option in options:
        allowed += option.get("enum", [])
        if "const" in option:
            allowed.append(option["const"])
    return value in allowed, allowed


def check_path(path, messages, schemas, numeric):
    topic, topic_filter, segments = parse_path(path)
    check(topic in messages, f"{path}: topic {topic} is not in the log")
    kept = [v for _, v in messages[topic] if matches(v, topic_filter)]
    if topic_filter is not None:
        for _, v in messages[topic]:
            check(topic_filter[0] in v, f"{path}: filter field {topic_filter[0]!r} missing")
        if not kept:
            ok, allowed = schema_allows(schemas.get(topic), *topic_filter)
            check(ok, f"{path}: filter value {topic_filter[1]!r} is none of {allowed}")
    leaves = 0
    lengths = []
    for v in kept:
        values = resolve(v, segments, path)
        lengths.append(len(values))
        kinds = {type(leaf) for leaf in values}
        check(not kinds & {dict, list}, f"{path}: ends in a structure, not a value")
        if numeric:
            # null is how the log writes a non-finite number
            check(kinds <= {int, float, type(None)}, f"{path}: not all numbers ({kinds})")
        leaves += len(values)
    check(topic_filter is not None or leaves > 0, f"{path}: resolves to nothing in the log")
    return {"path": path, "messages": len(kept), "values": leaves}, lengths


def layout_paths(layout):
    """(panel id, path, numeric, x-axis path of the same panel or None) for every path named."""
    out = []
    for panel, config in layout["configById"].items():
        kind = panel.split("!")[0]
        numeric = kind == "Plot"
        x = (config.get("xAxisPath") or {}).get("value")
        if x and config.get("xAxisVal") in ("custom", "currentCustom"):
            out.append((panel, x, True, None))
        for series in config.get("paths", []):
            out.append((panel, series["value"], numeric, x))
        if "path" in config:
            out.append((panel, config["path"], False, None))
        if "topicPath" in config:
            out.append((panel, config["topicPath"], False, None))
    return out


# ---- user scripts -------------------------------------------------------------------------


def run_user_scripts(layout, messages, script_file):
    scripts = list(layout.get("userNodes", {}).values())
    check(len(scripts) == 1, f"expected one User Script, found {len(scripts)}")
    source = scripts[0]["sourceCode"]
    with open(script_file) as f:
        check(f.read() == source, f"the layout's User Script differs from {script_file}")
    lines = []
    for topic, items in messages.items():
        if topic.startswith("/raw/"):
            for log_time, v in items:
                lines.append(json.dumps({"topic": topic, "log_time": str(log_time),
                                         "message": {**v, "first_sample": str(v["first_sample"])}}))
    out = subprocess.run(
        ["node", RUNNER, script_file], input="\n".join(lines) + "\n",
        capture_output=True, text=True,
    )
    check(out.returncode == 0, f"the User Script failed:\n{out.stderr}")
    produced = {}
    for line in out.stdout.splitlines():
        event = json.loads(line)
        produced.setdefault(event["topic"], []).append((int(event["log_time"]), event["message"]))
    check(len(produced) == 1, f"the User Script published on {sorted(produced)}")
    (topic, outputs), = produced.items()
    check(topic.startswith("/studio_script/"), f"{topic}: Foxglove wants /studio_script/…")
    raw_topic = "/raw/" + topic.split("/", 3)[3]
    raws = messages.get(raw_topic, [])
    check(raws and len(outputs) == len(raws), f"{len(outputs)} outputs for {len(raws)} raw blocks")
    for (t_raw, raw), (t_out, g) in zip(raws, outputs):
        check(t_raw == t_out, "an output is not at its raw block's log time")
        fs, scale, first = raw["sample_rate_hz"], raw["scale_g_per_count"], raw["first_sample"]
        check(len(g["g"]) == len(raw["counts"]) == len(g["t_s"]), "lengths differ")
        counts = numpy.array(raw["counts"], dtype=float)
        check(numpy.allclose(g["g"], counts * scale, rtol=1e-12, atol=1e-15),
              f"g is not counts x {scale} at first_sample {first}")
        times = (first + numpy.arange(len(counts))) / fs
        check(numpy.allclose(g["t_s"], times, rtol=1e-12, atol=0),
              f"t_s is not the samples' times at first_sample {first}")
    messages[topic] = outputs
    return {"topic": topic, "messages": len(outputs)}


def check_spectra(messages):
    count = 0
    for topic, items in messages.items():
        if not topic.startswith("/spectrum/"):
            continue
        for _, v in items:
            count += 1
            amp, freq = v["amplitude"], v.get("frequency_hz")
            check(amp, f"{topic}: an empty spectrum at end_sample {v['end_sample']}")
            check(freq is not None, f"{topic}: no frequency_hz")
            check(len(freq) == len(amp), f"{topic}: {len(freq)} frequencies, {len(amp)} bins")
            for i, f in enumerate(freq):
                check(math.isclose(f, i * v["bin_hz"], rel_tol=1e-6, abs_tol=1e-6),
                      f"{topic}: frequency_hz[{i}] = {f}, bin_hz {v['bin_hz']}")
    check(count > 0, "no spectrum in the log")
    return count


def main():
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    layout_file, log_file, script_file = sys.argv[1:]
    with open(layout_file) as f:
        layout = json.load(f)
    try:
        for key in ("configById", "layout", "userNodes", "globalVariables", "playbackConfig"):
            check(key in layout, f"the layout has no {key!r}")
        messages, schemas = read_log(log_file)
        summary = {"user_script": run_user_scripts(layout, messages, script_file)}
        summary["spectra"] = check_spectra(messages)
        checked, lengths = [], {}
        for panel, path, numeric, x in layout_paths(layout):
            result, per_message = check_path(path, messages, schemas, numeric)
            checked.append({"panel": panel, **result})
            lengths[(panel, path)] = per_message
            if x is not None:
                check(per_message == lengths[(panel, x)],
                      f"{panel}: {path} and its x axis {x} differ in length")
        panels = {p.split("!")[0] for p in layout["configById"]}
        check({"Plot", "StateTransitions", "Indicator"} <= panels, f"panels: {sorted(panels)}")
        summary["paths"] = checked
    except Failed as e:
        print(f"foxglove_layout.py: {e}", file=sys.stderr)
        return 1
    print(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
