#!/usr/bin/env python3
"""Check config/bearingd.dbc against frames that bearing-wire really encodes.

tests/data/example_frames.txt is written by the Rust test tests/dbc.rs (the real encoder) with
the raw signal values each frame holds. This script loads the DBC with cantools (strict), then
for every example:

  * finds the message by CAN id and checks its length and FD flag against the frame,
  * decodes the bytes and compares every signal with the expected raw value,
  * re-encodes the decoded signals with cantools and checks it gives the same bytes back.

Needs `pip install cantools`. Prints one line per frame and a closing "N passed, M failed" line;
exits non-zero on any failure.

Usage: python3 firmware-sim/core/tests/check_dbc.py [DBC] [EXAMPLES]
"""

import json
import struct
import sys
from pathlib import Path

import cantools

HERE = Path(__file__).resolve().parent
DEFAULT_DBC = HERE.parent.parent.parent / "config" / "bearingd.dbc"
DEFAULT_EXAMPLES = HERE / "data" / "example_frames.txt"


def as_f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def check_frame(db, can_id, data, expected):
    """Returns a list of problems (empty when the frame checks out)."""
    problems = []
    msg = db.get_message_by_frame_id(can_id)
    fd = len(data) > 8
    if msg.is_fd != fd:
        problems.append(f"is_fd {msg.is_fd}, frame has {len(data)} bytes")
    # A classic data frame with one sample is 6 bytes; the DBC describes the full 8.
    truncated = len(data) < msg.length
    if len(data) > msg.length:
        problems.append(f"frame has {len(data)} bytes, DBC length {msg.length}")
    got = msg.decode(
        data, decode_choices=False, scaling=False, allow_truncated=truncated
    )
    for name, want in expected.items():
        if name not in got:
            problems.append(f"signal {name} missing from decode")
            continue
        value = got[name]
        if isinstance(want, float) or isinstance(value, float):
            ok = as_f32(float(want)) == value
        else:
            ok = value == want
        if not ok:
            problems.append(f"{name}: decoded {value!r}, expected {want!r}")
    extra = set(got) - set(expected)
    if extra:
        problems.append(f"unexpected signals {sorted(extra)}")
    if not truncated:
        again = msg.encode(got, scaling=False, strict=True)
        if bytes(again) != data:
            problems.append(f"re-encode gives {bytes(again).hex()}, frame is {data.hex()}")
    return problems


def main(argv):
    dbc = Path(argv[1]) if len(argv) > 1 else DEFAULT_DBC
    examples = Path(argv[2]) if len(argv) > 2 else DEFAULT_EXAMPLES
    db = cantools.database.load_file(str(dbc), strict=True)
    print(f"{dbc}: {len(db.messages)} messages")
    passed = failed = 0
    for lineno, line in enumerate(examples.read_text().splitlines(), 1):
        if not line.strip() or line.startswith("#"):
            continue
        id_hex, data_hex, rest = line.split(" ", 2)
        can_id, data, expected = int(id_hex, 16), bytes.fromhex(data_hex), json.loads(rest)
        try:
            problems = check_frame(db, can_id, data, expected)
        except Exception as e:  # a cantools error is a failed check, not a crash
            problems = [f"{type(e).__name__}: {e}"]
        try:
            name = db.get_message_by_frame_id(can_id).name
        except KeyError:
            name = "?"
        if problems:
            failed += 1
            print(f"FAIL {examples.name}:{lineno} 0x{can_id:03x} {name}: " + "; ".join(problems))
        else:
            passed += 1
            print(f"ok   0x{can_id:03x} {name} ({len(data)} bytes)")
    if passed + failed == 0:
        print(f"no example frames in {examples}")
        return 1
    print(f"dbc: {passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
