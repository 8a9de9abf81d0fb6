#!/usr/bin/env bash
# Makes a shipped learned model from nothing but the simulators: the two synthetic data sets
# (signal model and physics twin) of one bearing, and the training, seeded. Usage:
#   scripts/train_model.sh [OUT [BEARING]]
# Without BEARING: the SKF 6205-2RS of the specs (default OUT: models/skf-6205-2rs.safetensors).
# With BEARING (a catalog name): the same specs and training for that bearing, e.g.
#   scripts/train_model.sh models/skf-6203-2rs.safetensors skf-6203-2rs
# About two minutes on two cores. CI runs it for the 6205 into target/ and
# scripts/check_model.py checks the result is the committed model: byte for byte on a machine
# like the one that made it, the same card, accuracy, verdicts and weights within a measured
# tolerance on another CPU (whose SIMD kernels round sums in another order). The test `learned::every_shipped_model_…` checks each
# model of models/ is made by these specs for its bearing and names fresh records of it.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-models/skf-6205-2rs.safetensors}
BEARING=()
if [ -n "${2:-}" ]; then BEARING=(--bearing "$2"); fi
# Data sets and training are lab commands: the lab binary (cargo build --release -p bearingd-lab).
LAB=${BEARINGD_LAB:-target/release/bearingd-lab}
WORK=target/learned-train
rm -rf "$WORK" && mkdir -p "$WORK" "$(dirname "$OUT")"
"$LAB" dataset --spec config/learned-train.toml "${BEARING[@]}" --out "$WORK/signal"
"$LAB" dataset --spec config/learned-train-physics.toml "${BEARING[@]}" --out "$WORK/physics"
"$LAB" train --dataset "$WORK/signal" --dataset "$WORK/physics" --epochs 30 --seed 1 --out "$OUT"
