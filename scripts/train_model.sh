#!/usr/bin/env bash
# Makes the shipped learned model from nothing but the simulators: the two synthetic data sets
# (signal model and physics twin) and the training, seeded. Usage:
#   scripts/train_model.sh [OUT]      (default OUT: models/skf-6205-2rs.safetensors)
# About a minute on two cores. CI runs it into target/ and scripts/check_model.py checks the
# result is the committed model: byte for byte on a machine like the one that made it, the same
# card, accuracy and verdicts on another CPU (whose SIMD kernels round sums in another order).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-models/skf-6205-2rs.safetensors}
# Data sets and training are lab commands: the lab binary (cargo build --release -p bearingd-lab).
LAB=${BEARINGD_LAB:-target/release/bearingd-lab}
WORK=target/learned-train
rm -rf "$WORK" && mkdir -p "$WORK" "$(dirname "$OUT")"
"$LAB" dataset --spec config/learned-train.toml --out "$WORK/signal"
"$LAB" dataset --spec config/learned-train-physics.toml --out "$WORK/physics"
"$LAB" train --dataset "$WORK/signal" --dataset "$WORK/physics" --epochs 30 --seed 1 --out "$OUT"
