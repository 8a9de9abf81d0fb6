#!/usr/bin/env python3
"""What the service binary carries: the crates in the normal dependency tree of a package (the
one systemd starts), which of the laboratory's crates are among them and through which path,
and how big a built binary is once stripped.

Why: the daemon runs unattended on small edge computers; every crate it links is build time,
memory and attack surface (issue 31). The numbers here are the ones docs/PERFORMANCE.md
"Service binary" reports, made by one command.

Report only by default; with --max-crates, --forbid-fails or --max-mib it fails (exit 1) when
the package is over the limit, naming each crate that must not be there with the path that
pulls it in.

Usage: scripts/service_deps.py [--package bearingd] [--binary PATH] [--max-crates N]
                               [--forbid-fails] [--max-mib M]
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile

# The laboratory's heavy crates: none is needed to monitor a bearing (issue 31 item 1).
LAB_CRATES = ("candle-core", "candle-nn", "tokenizers", "ode_solvers", "rayon", "ndarray",
              "tiny-skia")
LINE_RE = re.compile(r"^(\d+)(\S+) v(\S+)")


def dependency_tree(package: str) -> list:
    """[(depth, name, version)] of `cargo tree -e normal` (host target), in tree order."""
    out = subprocess.run(
        ["cargo", "tree", "-p", package, "-e", "normal", "--prefix", "depth"],
        check=True, capture_output=True, text=True,
    ).stdout
    rows = []
    for line in out.splitlines():
        m = LINE_RE.match(line)
        if m:
            rows.append((int(m.group(1)), m.group(2), m.group(3)))
    return rows


def first_paths(rows: list, wanted: tuple) -> dict:
    """{crate: "a -> b -> crate"}: the first path in the tree that reaches each wanted crate."""
    stack, paths = [], {}
    for depth, name, _ in rows:
        del stack[depth:]
        stack.append(name)
        if name in wanted and name not in paths:
            paths[name] = " -> ".join(stack)
    return paths


def stripped_size(binary: str) -> int:
    with tempfile.TemporaryDirectory() as tmp:
        copy = os.path.join(tmp, "stripped")
        subprocess.run(["strip", "-o", copy, binary], check=True)
        return os.path.getsize(copy)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--package", default="bearingd")
    parser.add_argument("--binary", help="a built binary whose stripped size to report")
    parser.add_argument("--max-crates", type=int, help="fail above this many crates")
    parser.add_argument("--forbid-fails", action="store_true",
                        help="fail when a laboratory crate is in the tree")
    parser.add_argument("--max-mib", type=float, help="fail when the stripped binary is larger")
    args = parser.parse_args()

    rows = dependency_tree(args.package)
    crates = {(name, version) for _, name, version in rows}
    problems = []
    print(f"{args.package}: {len(crates)} crates in its normal dependency tree (host target)")
    if args.max_crates is not None and len(crates) > args.max_crates:
        problems.append(f"{len(crates)} crates, more than {args.max_crates}")
    paths = first_paths(rows, LAB_CRATES)
    for crate in LAB_CRATES:
        if crate in paths:
            print(f"  laboratory crate {crate}: {paths[crate]}")
    if not paths:
        print(f"  no laboratory crate ({', '.join(LAB_CRATES)})")
    elif args.forbid_fails:
        problems.append(f"laboratory crates in the tree: {', '.join(sorted(paths))}; move the "
                        "code that uses them to the lab crate")
    if args.binary:
        size = stripped_size(args.binary)
        line = f"{args.binary}: {size:,} bytes stripped ({size / 2**20:.2f} MiB)"
        if args.max_mib is not None:
            limit = int(args.max_mib * 2**20)
            if size <= limit:
                line += f", {limit - size:,} bytes under the {args.max_mib:g} MiB limit"
            else:
                problems.append(
                    f"{size:,} bytes stripped, {size - limit:,} more than {args.max_mib:g} MiB; "
                    "docs/PERFORMANCE.md \"Service binary\" lists what takes the room and the "
                    "levers measured (the profile's opt-levels, crate features)")
        print(line)
    for problem in problems:
        print(f"problem: {problem}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
