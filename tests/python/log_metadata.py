#!/usr/bin/env python3
"""Prints what a bearingd MCAP log says about itself, read with Python `mcap`'s strict reader:

    log_metadata.py FILE.mcap

JSON on stdout: {"metadata": {name: [record, ...]}, "first_log_time": ns, "last_log_time": ns,
"messages": n}. Exit status 1 when the file does not read strictly.
"""

import json
import sys

from mcap.reader import make_reader


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1], "rb") as f:
        reader = make_reader(f)
        metadata = {}
        for record in reader.iter_metadata():
            metadata.setdefault(record.name, []).append(dict(record.metadata))
        stats = reader.get_summary().statistics
        print(
            json.dumps(
                {
                    "metadata": metadata,
                    "first_log_time": stats.message_start_time,
                    "last_log_time": stats.message_end_time,
                    "messages": stats.message_count,
                }
            )
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
