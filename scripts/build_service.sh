#!/usr/bin/env bash
# The edge box's build of the service binary: target/service/bearingd, with its symbols (9.6 MiB
# on x86-64); `strip` it before `make install-service BIN=target/service/bearingd`, which installs
# it as it is (7.9 MiB stripped; docs/PERFORMANCE.md "Service binary").
# Extra arguments go to cargo: `--target aarch64-unknown-linux-gnu` (then
# target/aarch64-unknown-linux-gnu/service/bearingd), `--no-default-features --features can,shm`.
#
# Why not plain `cargo build --profile service`: the profile compiles the daemon's edges (the
# bearingd library, bearing-signal and every dependency) at opt-level `z` and the sans-IO core
# and the FFT at 3 (Cargo.toml). With fat LTO the whole program's last optimisation (inlining
# across crates, unrolling, vectorisation) runs once, at the opt-level of the crate being
# linked: the binary's, which cargo gives its package's `z`. `cargo rustc` passes
# `-C opt-level=3` to that one crate: the core's loops are optimised for speed as in a release
# build, while the functions compiled at `z` keep their size attributes and stay small. Plain
# `cargo build --profile service` still works: about 80 KB smaller, and the window path and the
# HW model measurably slower (docs/PERFORMANCE.md).
set -euo pipefail
cd "$(dirname "$0")/.."
exec cargo rustc --profile service -p bearingd --bin bearingd --locked "$@" -- -C opt-level=3
