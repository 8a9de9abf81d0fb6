#!/usr/bin/env python3
"""Checks an MCAP file that bearingd wrote under systemd in the VM (tests/vm/systemd_vm_test.sh):

    check_vm_mcap.py FILE.mcap SENSOR FAULT

- the file is finished cleanly: Python `mcap`'s strict `make_reader` opens it, its summary
  section is there (a killed writer leaves none) with statistics, and `iter_messages()` reads
  every message the statistics announce;
- it holds a `/flags/SENSOR/<axis>` message whose JSON says FAULT rose from `ok`;
- every `/twin/SENSOR/<axis>` fit carries the learned model's opinion with no problem (the VM's
  config names the installed models); each such opinion is printed as "learned opinion: ...".

Prints one line per finding; exit status 0 if all hold, 1 otherwise.
"""

import json
import sys

from mcap.reader import make_reader


def main():
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    path, sensor, fault = sys.argv[1:]
    try:
        return check(path, sensor, fault)
    except Exception as e:  # the strict reader raises on an unfinished or corrupt file
        print(f"{path}: the strict reader failed: {type(e).__name__}: {e}")
        return 1


def check(path, sensor, fault):
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        if summary is None or summary.statistics is None:
            print(f"{path}: no summary section (or no statistics): not a cleanly finished file")
            return 1
        topics = {}
        flags = []
        twins = []
        count = 0
        for _schema, channel, message in reader.iter_messages(log_time_order=False):
            count += 1
            topics[channel.topic] = topics.get(channel.topic, 0) + 1
            if channel.topic.startswith(f"/flags/{sensor}/"):
                flags.append(json.loads(message.data))
            elif channel.topic.startswith(f"/twin/{sensor}/"):
                twins.append(json.loads(message.data))
    announced = summary.statistics.message_count
    print(f"{path}: summary present, {count} messages read, {announced} announced, "
          f"{len(summary.chunk_indexes)} chunks; topics {json.dumps(topics, sort_keys=True)}")
    ok = True
    if count != announced or count == 0:
        print(f"read {count} messages but the statistics announce {announced}")
        ok = False
    rises = [m for m in flags if m.get("fault") == fault and m.get("from") == "ok"]
    for m in flags:
        print(f"flag message: {json.dumps(m, sort_keys=True)}")
    if not rises:
        print(f"no /flags/{sensor}/... message in which {fault} rises from ok")
        ok = False
    for m in twins:
        learned = m.get("learned")
        if not learned or learned.get("problem") is not None or learned.get("segments", 0) < 1:
            print(f"a twin fit at sample {m.get('end_sample')} has no learned opinion: "
                  f"{json.dumps(learned)}")
            ok = False
        else:
            top = learned["probabilities"][0]
            print(f"learned opinion: sample {m['end_sample']}, {learned['segments']} segments, "
                  f"top {top}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
