#!/usr/bin/env python3
"""Reads the velocity detectors' channels of bearingd MCAP logs with Python `mcap`'s strict
reader.

    velocity_log.py FILE.mcap...

Prints one JSON object: `velocity` (every `/velocity/<sensor>/<axis>` message, in log order),
`velocity_flags` (every `/velocity_flags/...` message), `machine` and `machine_flags` (the
machine-fault detector's `/machine/...` and `/machine_flags/...`) and `fault_flags` (every
`/flags/...`), each message as decoded plus its `topic`; and `schemas` (topic -> schema name and
encoding).
Exit status 1 when a file cannot be read strictly or a channel lacks its JSON Schema.
"""

import json
import sys

from mcap.reader import make_reader


def main():
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    families = {
        "/velocity/": "velocity",
        "/velocity_flags/": "velocity_flags",
        "/machine/": "machine",
        "/machine_flags/": "machine_flags",
        "/flags/": "fault_flags",
    }
    out = {family: [] for family in families.values()}
    out["schemas"] = {}
    for path in sys.argv[1:]:
        with open(path, "rb") as f:
            for schema, channel, message in make_reader(f).iter_messages(log_time_order=True):
                family = next((v for k, v in families.items() if channel.topic.startswith(k)), None)
                if family is None:
                    continue
                if schema is None or schema.encoding != "jsonschema" or channel.message_encoding != "json":
                    print(f"{path}: {channel.topic} has no JSON Schema", file=sys.stderr)
                    return 1
                json.loads(schema.data)
                out["schemas"][channel.topic] = {"name": schema.name, "encoding": schema.encoding}
                decoded = json.loads(message.data)
                decoded["topic"] = channel.topic
                out[family].append(decoded)
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
