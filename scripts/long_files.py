#!/usr/bin/env python3
"""Fails when a Rust file under one of the given directories has more than N (default 800)
lines, naming each such file with its length, longest first.

Why: a file past a few hundred lines is read by scrolling and searching, not as one idea; the
house rule is to split it into a directory module (one file per idea, its tests beside it)
before it gets there. Every line counts (comments and tests too): what a newcomer scrolls
through is the whole file.

Usage: scripts/long_files.py [--max N] DIR [DIR ...]
"""

import argparse
import sys
from pathlib import Path

SKIPPED_DIRS = {"target", ".git", ".venv", "node_modules"}


def rust_files(root: Path):
    """The `.rs` files under `root` (or `root` itself), build and tool directories left out."""
    if root.is_file():
        yield root
        return
    for path in sorted(root.rglob("*.rs")):
        if not SKIPPED_DIRS.intersection(path.relative_to(root).parts):
            yield path


def line_count(path: Path) -> int:
    with path.open("rb") as f:
        return sum(1 for _ in f)


def too_long(roots, max_lines: int):
    """[(lines, path)] of the files over `max_lines`, longest first."""
    found = []
    for root in roots:
        for path in rust_files(root):
            lines = line_count(path)
            if lines > max_lines:
                found.append((lines, path))
    return sorted(found, key=lambda f: (-f[0], str(f[1])))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--max", type=int, default=800, help="most lines a file may have")
    parser.add_argument("dirs", nargs="+", type=Path, help="directories (or files) to check")
    args = parser.parse_args(argv)
    missing = [d for d in args.dirs if not d.exists()]
    if missing:
        print(f"long_files: no such directory: {', '.join(map(str, missing))}", file=sys.stderr)
        return 2
    found = too_long(args.dirs, args.max)
    for lines, path in found:
        print(
            f"{path}: {lines} lines, more than {args.max}; split it into a directory module "
            "(one file per idea, its tests beside it)",
            file=sys.stderr,
        )
    if not found:
        print(f"long_files: no Rust file over {args.max} lines in {' '.join(map(str, args.dirs))}")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
