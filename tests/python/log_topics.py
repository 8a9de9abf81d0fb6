#!/usr/bin/env python3
"""Lists the messages of a bearingd MCAP log in log-time order, read with Python `mcap`'s
strict reader (summary, chunk indexes, CRCs):

    log_topics.py FILE.mcap

JSON on stdout: {"messages": [{"topic", "log_time", "publish_time", "json"}...]}, where
"json" is the decoded message for the low-rate JSON topics (/log, /state, /twin, /flags,
/health, /velocity_flags, /trend) and null for the others (raw, spectra, indicators: too
many to print).
Exit status 1 when the file does not read strictly.
"""

import json
import sys

from mcap.reader import make_reader

DECODED = ("/log", "/state", "/twin/", "/flags/", "/health/", "/velocity_flags/", "/trend/")


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    out = []
    with open(sys.argv[1], "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        for _schema, channel, message in reader.iter_messages(log_time_order=True):
            decoded = None
            if channel.message_encoding == "json" and channel.topic.startswith(DECODED):
                decoded = json.loads(message.data)
            out.append(
                {
                    "topic": channel.topic,
                    "log_time": message.log_time,
                    "publish_time": message.publish_time,
                    "json": decoded,
                }
            )
    print(json.dumps({"messages": out}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
