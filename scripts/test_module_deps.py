#!/usr/bin/env python3
"""Tests of scripts/module_deps.py on tiny fake crates: it finds a cycle and names it, it sees
`use crate::{a, b}` groups, it ignores comments and strings, and it refuses an upward arrow of
the layout in lib.rs. Run: python3 scripts/test_module_deps.py"""

import sys
import tempfile
import unittest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import module_deps  # noqa: E402


def tree(files: dict) -> Path:
    root = Path(tempfile.mkdtemp(prefix="module-deps-test-"))
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return root


class ModuleDeps(unittest.TestCase):
    def test_a_cycle_is_found_and_named(self):
        src = tree({
            "lib.rs": "pub mod a;\npub mod b;\npub mod c;\n",
            "a/mod.rs": "use crate::b::Thing;\n",
            "b.rs": "pub fn f() { crate::c::g(); }\n",
            "c/deep/inner.rs": "use crate::{a::X, d};\n",
            "d.rs": "",
        })
        problems = module_deps.check(src)
        self.assertEqual(len(problems), 1, problems)
        self.assertIn("import cycle: a -> b -> c -> a", problems[0])
        self.assertIn("c/deep/inner.rs:1", problems[0])
        self.assertEqual(module_deps.dependencies(src)["c"].keys(), {"a", "d"})

    def test_no_cycle_passes(self):
        src = tree({
            "lib.rs": "",
            "a.rs": "use crate::b::X;\nuse crate::c;\n",
            "b.rs": "use crate::c::Y;\n",
            "c.rs": "use std::fmt;\n",
        })
        self.assertEqual(module_deps.check(src), [])
        self.assertEqual(module_deps.dependencies(src)["a"].keys(), {"b", "c"})

    def test_comments_strings_and_unknown_names_are_not_dependencies(self):
        src = tree({
            "lib.rs": "",
            "a.rs": "use crate::b::X;\n",
            "b.rs": '// see crate::a::X\n/* crate::a */\nconst S: &str = "crate::a::X";\n'
                    "const R: &str = r#\"crate::a\"#;\nconst C: char = '\"';\nfn f() { crate::nope::g() }\n",
        })
        self.assertEqual(module_deps.check(src), [])
        self.assertEqual(dict(module_deps.dependencies(src)["b"]), {})

    def test_an_upward_arrow_of_the_layout_is_refused(self):
        src = tree({
            "lib.rs": "//! # Layout\n//!\n//! - [`top`]: uses low.\n//! - [`low`]: uses nothing above.\n",
            "top.rs": "use crate::low::X;\n",
            "low.rs": "pub fn f() { crate::top::g(); }\n",
        })
        problems = module_deps.check(src)
        self.assertTrue(any(p.startswith("upward arrow: low uses top") for p in problems), problems)
        self.assertTrue(any(p.startswith("import cycle: low -> top -> low") for p in problems), problems)

    def test_depth_two_finds_a_cycle_between_the_files_of_a_module(self):
        src = tree({
            "lib.rs": "pub mod a;\n",
            "a/mod.rs": "mod b;\nmod c;\nmod d;\n",
            "a/b.rs": "use super::c::X;\n",
            "a/c/mod.rs": "use crate::a::{b::Y, b};\nuse crate::other::Q;\n",
            "a/d.rs": "use super::b::Z;\n#[cfg(test)]\nmod tests {\n    use super::super::c::W;\n}\n",
        })
        self.assertEqual(module_deps.check(src, depth=1), [])
        problems = module_deps.check(src, depth=2)
        self.assertEqual(len(problems), 1, problems)
        self.assertIn("import cycle: a::b -> a::c -> a::b", problems[0])
        inner = module_deps.submodule_dependencies(src, "a")
        self.assertEqual(inner["c"].keys(), {"b"})
        # d's test module uses c: not counted (a unit test may call the module above it).
        self.assertEqual(inner["d"].keys(), {"b"})


if __name__ == "__main__":
    unittest.main()
