#!/usr/bin/env python3
"""The dependencies between the top-level modules of a Rust crate, and a check that they form no
cycle and only go down the house's layer order.

Reads every `.rs` file under SRC (default `src`), strips comments, string and char literals, and
collects the `crate::NAME` paths each top-level module uses (also inside `use crate::{a, b::c}`
groups). `src/foo.rs` and `src/foo/**.rs` belong to module `foo`; `lib.rs` and `main.rs` are the
crate root and are not checked.

Fails (exit 1) naming each import cycle between top-level modules, and each arrow that goes up
the layer order given by the `# Layout` section of SRC/lib.rs (the order its `- [`name`]` items
are listed in, top to bottom: a module may use only modules listed after it). A module the
layout does not list is only checked for cycles, and reported.

With `--depth 2` it also checks, inside each top-level module that is a directory, that its
files and sub-directories (`src/a/b.rs`, `src/a/b/**`: node `a::b`) form no import cycle, seen
through `crate::a::b`, `super::b` and `use super::{b, c}` paths (`a/mod.rs` is that module's
root and is not a node). Code inside `#[cfg(test)] mod NAME { ... }` is not counted there: a
unit test may call the module above it (a measurement through the whole analysis).

Usage: scripts/module_deps.py [--src SRC] [--depth 1|2] [--graph]
"""

import argparse
import re
import sys
from pathlib import Path

PATH_RE = re.compile(r"(?<![\w$])crate\s*::\s*(\{|[A-Za-z_]\w*)")
SUB_PATH_RE = re.compile(r"(?<![\w$])(crate\s*::\s*\w+|super(?:\s*::\s*super)*)\s*::\s*(\{|[A-Za-z_]\w*)")
LAYOUT_ITEM_RE = re.compile(r"^//!\s*-\s*\[`(\w+)`\]")


def strip_code(text: str) -> str:
    """The text with comments, string literals and char literals blanked out."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif text.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif c == "r" and re.match(r'r#*"', text[i:i + 300]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            hashes = re.match(r'r(#*)"', text[i:]).group(1)
            end = text.find('"' + hashes, i + 2 + len(hashes))
            i = n if end < 0 else end + 1 + len(hashes)
            out.append('""')
        elif c == '"':
            i += 1
            while i < n and text[i] != '"':
                i += 2 if text[i] == "\\" else 1
            i += 1
            out.append('""')
        elif c == "'":
            # A char literal ('a', '\n', '\u{..}'), not a lifetime ('a).
            m = re.match(r"'(\\.[^']*|[^\\'])'", text[i:i + 12])
            if m:
                i += m.end()
                out.append("' '")
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def group_names(text: str, start: int) -> list:
    """The first path segments inside the `{...}` that starts at `start`."""
    depth, i, names, segment_start = 0, start, [], True
    while i < len(text):
        c = text[i]
        if c == "{":
            depth += 1
            segment_start = depth == 1
        elif c == "}":
            depth -= 1
            if depth == 0:
                break
        elif c == "," and depth == 1:
            segment_start = True
        elif depth == 1 and segment_start and (c.isalpha() or c == "_"):
            m = re.match(r"\w+", text[i:])
            names.append(m.group(0))
            i += m.end()
            segment_start = False
            continue
        elif not c.isspace() and depth == 1:
            segment_start = False
        i += 1
    return names


def module_of(src: Path, path: Path):
    rel = path.relative_to(src)
    if len(rel.parts) == 1:
        name = rel.stem
        return None if name in ("lib", "main") else name
    return rel.parts[0]


def dependencies(src: Path) -> dict:
    """{module: {used module: first file:line that uses it}}"""
    deps = {}
    for path in sorted(src.rglob("*.rs")):
        module = module_of(src, path)
        if module is None:
            continue
        deps.setdefault(module, {})
        code = strip_code(path.read_text(encoding="utf-8"))
        for m in PATH_RE.finditer(code):
            names = group_names(code, m.start(1)) if m.group(1) == "{" else [m.group(1)]
            line = code.count("\n", 0, m.start()) + 1
            for name in names:
                if name not in (module, "self", "super", "crate"):
                    deps[module].setdefault(name, f"{path}:{line}")
    known = set(deps)
    return {m: {d: at for d, at in used.items() if d in known} for m, used in deps.items()}


TEST_MOD_RE = re.compile(r"#\[cfg\(test\)\]\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+\w+\s*\{")


def without_test_modules(code: str) -> str:
    """`code` (already stripped of comments and literals) with every `#[cfg(test)] mod x { }`
    body blanked, newlines kept so that line numbers stay right."""
    out, i = [], 0
    for m in TEST_MOD_RE.finditer(code):
        if m.start() < i:
            continue
        depth, j = 1, m.end()
        while j < len(code) and depth:
            depth += {"{": 1, "}": -1}.get(code[j], 0)
            j += 1
        out.append(code[i:m.start()])
        out.append(re.sub(r"[^\n]", " ", code[m.start():j]))
        i = j
    out.append(code[i:])
    return "".join(out)


def submodule_dependencies(src: Path, top: str) -> dict:
    """{submodule: {used submodule: first file:line}} inside the directory module `top`."""
    root = src / top
    deps = {}
    for path in sorted(root.rglob("*.rs")):
        rel = path.relative_to(root)
        if rel.parts == ("mod.rs",):
            continue
        node = rel.parts[0][:-3] if len(rel.parts) == 1 else rel.parts[0]
        # The module `super` names: for src/top/b.rs it is `top`; for src/top/b/c.rs it is
        # `top::b` (and `super::super` is `top`); a deeper file's `mod.rs` is its directory.
        inner = list(rel.with_suffix("").parts)
        if inner[-1] == "mod":
            inner.pop()
        deps.setdefault(node, {})
        code = without_test_modules(strip_code(path.read_text(encoding="utf-8")))
        for m in SUB_PATH_RE.finditer(code):
            head = re.sub(r"\s", "", m.group(1))
            if head.startswith("crate"):
                if head.split("::")[1] != top:
                    continue
                base = []
            else:
                ups = head.count("super")
                base = inner[:-ups] if ups <= len(inner) else None
                if base is None:
                    continue
            names = group_names(code, m.start(2)) if m.group(2) == "{" else [m.group(2)]
            line = code.count("\n", 0, m.start()) + 1
            for name in names:
                used = base[0] if base else name
                if used not in (node, "self", "super", "crate"):
                    deps[node].setdefault(used, f"{path}:{line}")
    known = set(deps)
    return {m: {d: at for d, at in used.items() if d in known} for m, used in deps.items()}


def cycles(deps: dict) -> list:
    """The import cycles: for every strongly connected component with more than one module
    (Tarjan), a shortest cycle through each of its modules, without repeats."""
    index, low, stack, on_stack, comps = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(deps.get(v, {})):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                comps.append(sorted(comp))

    for v in sorted(deps):
        if v not in index:
            visit(v)
    found, seen = [], set()
    for comp in comps:
        for start in comp:
            cycle = shortest_cycle(deps, start, set(comp))
            key = frozenset(zip(cycle, cycle[1:]))
            if key not in seen:
                seen.add(key)
                found.append(cycle)
    return found


def shortest_cycle(deps: dict, start: str, members: set) -> list:
    """A shortest cycle from `start` back to it within `members` (breadth-first)."""
    previous, queue = {start: None}, [start]
    while queue:
        v = queue.pop(0)
        for w in sorted(deps[v]):
            if w not in members:
                continue
            if w == start:
                path = [v]
                while previous[path[-1]] is not None:
                    path.append(previous[path[-1]])
                return list(reversed(path)) + [start]
            if w not in previous:
                previous[w] = v
                queue.append(w)
    return [start, start]


def layout_order(src: Path) -> list:
    lib = src / "lib.rs"
    if not lib.exists():
        return []
    order = []
    for line in lib.read_text(encoding="utf-8").splitlines():
        m = LAYOUT_ITEM_RE.match(line)
        if m and m.group(1) not in order:
            order.append(m.group(1))
    return order


def cycle_problems(deps: dict, prefix: str = "") -> list:
    problems = []
    for cycle in cycles(deps):
        named = [prefix + m for m in cycle]
        arrows = [f"{prefix}{a} -> {prefix}{b} ({deps[a][b]})" for a, b in zip(cycle, cycle[1:])]
        problems.append("import cycle: " + " -> ".join(named) + "\n    " + "\n    ".join(arrows))
    return problems


def check(src: Path, show_graph: bool = False, depth: int = 1) -> list:
    """The problems found (empty: none); prints the graph when asked."""
    deps = dependencies(src)
    problems = cycle_problems(deps)
    if depth >= 2:
        for top in sorted(deps):
            if (src / top).is_dir():
                problems += cycle_problems(submodule_dependencies(src, top), f"{top}::")
    order = layout_order(src)
    rank = {m: i for i, m in enumerate(order)}
    for module in sorted(deps):
        for used, at in sorted(deps[module].items()):
            if module in rank and used in rank and rank[used] < rank[module]:
                problems.append(
                    f"upward arrow: {module} uses {used} ({at}), but lib.rs's # Layout lists "
                    f"{used} above {module}; move the shared part down or the module up"
                )
    unlisted = sorted(set(deps) - set(rank))
    if order and unlisted:
        print(f"note: not in lib.rs's # Layout (checked for cycles only): {', '.join(unlisted)}")
    if show_graph:
        for module in sorted(deps, key=lambda m: rank.get(m, len(rank))):
            print(f"{module} -> {', '.join(sorted(deps[module], key=lambda m: rank.get(m, len(rank)))) or '-'}")
    return problems


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--src", default="src", type=Path)
    parser.add_argument("--graph", action="store_true", help="print every module's dependencies")
    parser.add_argument("--depth", type=int, choices=(1, 2), default=1,
                        help="2: also no cycle between the files of each top-level module")
    args = parser.parse_args()
    problems = check(args.src, args.graph, args.depth)
    for problem in problems:
        print(problem)
    if problems:
        print(f"{len(problems)} problem(s) in the module graph of {args.src}")
        return 1
    inside = " (nor inside a top-level module)" if args.depth >= 2 else ""
    print(f"module graph of {args.src}: no cycle{inside}, every arrow goes down the layout")
    return 0


if __name__ == "__main__":
    sys.exit(main())
