#!/usr/bin/env python3
"""Reads a bearingd MCAP log the way a user would: Python `mcap`'s strict `make_reader`, the
protobuf decoder of `mcap-protobuf-support`, and a small JSON decoder factory.

    check_mcap.py FILE.mcap [EXPECTED.json]

Prints a JSON summary (messages per topic, schema names and encodings). With EXPECTED.json (a
list of {"topic", "log_time", "publish_time", "message"}), every decoded message must equal the
expected one, in order: integers exactly, floats exactly (both sides parse the same decimal).
Exit status 0 on success, 1 on any mismatch or decoding failure.
"""

import json
import sys

from mcap.decoder import DecoderFactory
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoderFactory


class JsonDecoderFactory(DecoderFactory):
    """Decodes channels with message encoding `json` whose schema is a JSON Schema."""

    def decoder_for(self, message_encoding, schema):
        if message_encoding != "json":
            return None
        if schema is not None and schema.encoding != "jsonschema":
            return None
        if schema is not None:
            json.loads(schema.data)  # the schema itself must be valid JSON
        return lambda data: json.loads(data)


def raw_block_to_dict(m):
    return {
        "channel": {"sensor": m.channel.sensor, "axis": m.channel.axis},
        "first_sample": m.first_sample,
        "sample_rate_hz": m.sample_rate_hz,
        "scale_g_per_count": m.scale_g_per_count,
        "counts": list(m.counts),
    }


def main():
    if len(sys.argv) not in (2, 3):
        print(__doc__, file=sys.stderr)
        return 2
    path = sys.argv[1]
    expected = None
    if len(sys.argv) == 3:
        with open(sys.argv[2]) as f:
            expected = json.load(f)

    decoded = []
    schemas = {}
    with open(path, "rb") as f:
        reader = make_reader(
            f, decoder_factories=[ProtobufDecoderFactory(), JsonDecoderFactory()]
        )
        summary = reader.get_summary()
        if summary is None:
            print(f"{path}: no summary section", file=sys.stderr)
            return 1
        for schema, channel, message, value in reader.iter_decoded_messages(
            log_time_order=False
        ):
            if schema is None:
                print(f"{path}: {channel.topic} has no schema", file=sys.stderr)
                return 1
            schemas[channel.topic] = [schema.name, schema.encoding, channel.message_encoding]
            if schema.encoding == "protobuf":
                value = raw_block_to_dict(value)
            decoded.append(
                {
                    "topic": channel.topic,
                    "log_time": message.log_time,
                    "publish_time": message.publish_time,
                    "message": value,
                }
            )

    topics = {}
    for d in decoded:
        topics[d["topic"]] = topics.get(d["topic"], 0) + 1
    print(json.dumps({"messages": len(decoded), "topics": topics, "schemas": schemas}))

    if expected is not None:
        if len(expected) != len(decoded):
            print(f"expected {len(expected)} messages, decoded {len(decoded)}", file=sys.stderr)
            return 1
        for i, (e, d) in enumerate(zip(expected, decoded)):
            if e != d:
                print(f"message {i} differs:\n expected {e}\n decoded  {d}", file=sys.stderr)
                return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
