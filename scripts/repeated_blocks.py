#!/usr/bin/env python3
"""Fails when a block of more than N (default 10) consecutive code lines appears twice in the
Rust sources under SRC (default `src`).

Lines are compared with their indentation stripped; blank lines, comment-only lines and lines of
only brackets or punctuation (`}`, `);`) are skipped, so a repeat cannot hide behind them nor be
made of them. Each repeat is reported once, as its first two places. For the finer picture
(also blocks of the same shape with other names) use a duplicate-code finder; this is the
check CI can run on a fresh machine with only python3.

Usage: scripts/repeated_blocks.py [--src SRC] [--max-lines N]
"""

import argparse
import re
import sys
from pathlib import Path

TRIVIAL = re.compile(r"^[\s{}()\[\];,.]*$")


def code_lines(path: Path):
    """(line number, stripped text) of each line that counts."""
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        text = line.strip()
        if not text or text.startswith("//") or TRIVIAL.match(text):
            continue
        yield number, text


def repeats(src: Path, block: int):
    first_seen = {}
    found = {}
    for path in sorted(src.rglob("*.rs")):
        lines = list(code_lines(path))
        for i in range(len(lines) - block + 1):
            key = tuple(text for _, text in lines[i:i + block])
            place = (path, lines[i][0], lines[i + block - 1][0])
            if key in first_seen:
                other = first_seen[key]
                # Overlapping windows of one long repeat: keep only the first window.
                if not any(p[0] == other[0] and p[1] <= other[1] <= p[2] + 1 for p, _ in found.values()):
                    found[key] = (other, place)
            else:
                first_seen[key] = place
    return list(found.values())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--src", default="src", type=Path)
    parser.add_argument("--max-lines", default=10, type=int, help="longest repeat allowed")
    args = parser.parse_args()
    pairs = repeats(args.src, args.max_lines + 1)
    for (a, a0, a1), (b, b0, b1) in pairs:
        print(f"repeated block of more than {args.max_lines} lines: {a}:{a0}-{a1} and {b}:{b0}-{b1}; "
              "make it one function (or one macro) both places call")
    if pairs:
        return 1
    print(f"{args.src}: no block of more than {args.max_lines} code lines appears twice")
    return 0


if __name__ == "__main__":
    sys.exit(main())
