#!/usr/bin/env python3
"""Tests of scripts/long_files.py on a tiny fake tree: a file over the limit is named with its
length, one at the limit passes, target/ is not looked into, a missing directory is an error.
Run: python3 scripts/test_long_files.py"""

import sys
import tempfile
import unittest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import long_files  # noqa: E402


def tree(files: dict) -> Path:
    root = Path(tempfile.mkdtemp(prefix="long-files-test-"))
    for name, lines in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("// x\n" * lines, encoding="utf-8")
    return root


class LongFiles(unittest.TestCase):
    def test_only_files_over_the_limit_are_named_longest_first(self):
        root = tree({"a.rs": 10, "b/c.rs": 11, "b/d/e.rs": 12, "notes.md": 99})
        found = long_files.too_long([root], 10)
        self.assertEqual([(n, p.relative_to(root).as_posix()) for n, p in found],
                         [(12, "b/d/e.rs"), (11, "b/c.rs")])

    def test_build_directories_are_not_looked_into(self):
        root = tree({"target/release/build/out.rs": 50, "src/ok.rs": 5})
        self.assertEqual(long_files.too_long([root], 10), [])

    def test_exit_codes(self):
        root = tree({"ok.rs": 3, "long.rs": 4})
        self.assertEqual(long_files.main(["--max", "4", str(root)]), 0)
        self.assertEqual(long_files.main(["--max", "3", str(root)]), 1)
        self.assertEqual(long_files.main([str(root / "missing")]), 2)


if __name__ == "__main__":
    unittest.main()
