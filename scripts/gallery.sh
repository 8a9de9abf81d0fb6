#!/usr/bin/env bash
# The gallery of analyze figures (docs/gallery, issue 33 item 6): the built-in demo and four
# real records (CWRU outer race, inner race and ball at 12 kHz, drive end; FEMTO/PRONOSTIA
# Bearing1_2 at the end of its life), each drawn by `bearingd-lab analyze --plot`.
#
#   scripts/gallery.sh [DATA_DIR]
#
# DATA_DIR holds the downloaded data sets (cwru/, femto/; default ../shared/data beside the
# repository); the data is read, never copied here. LAB overrides the binary (default
# $CARGO_TARGET_DIR/release/bearingd-lab, else target/release/bearingd-lab). Each record is
# analysed from inside its data set's directory so that the figure's title names the file, not
# this machine's paths.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
data=$(cd "${1:-../shared/data}" 2>/dev/null && pwd) || {
  echo "gallery: no data directory ${1:-../shared/data}: give the directory holding cwru/ and femto/" >&2
  exit 2
}
lab="${LAB:-${CARGO_TARGET_DIR:-target}/release/bearingd-lab}"
[ -x "$lab" ] || { echo "gallery: no $lab: build it with cargo build --release -p bearingd-lab, or set LAB" >&2; exit 2; }
lab=$(cd "$(dirname "$lab")" && pwd)/$(basename "$lab")
out="$root/docs/gallery"
mkdir -p "$out"

# name, data set directory, record (relative to it)
records=(
  "cwru-outer-race cwru 12k_Drive_End_OR007@6_0_130.mat"
  "cwru-inner-race cwru 12k_Drive_End_IR007_0_105.mat"
  "cwru-ball cwru 12k_Drive_End_B007_0_118.mat"
  "femto-bearing1_2-end-of-life femto Bearing1_2/acc_00871.csv"
)
for entry in "${records[@]}"; do
  read -r name set file <<<"$entry"
  [ -f "$data/$set/$file" ] || {
    echo "gallery: no $data/$set/$file: download the $set data set into $data/$set" >&2
    exit 2
  }
done

echo "demo"
"$lab" analyze --demo --plot "$out/demo.png" >/dev/null
for entry in "${records[@]}"; do
  read -r name set file <<<"$entry"
  echo "$name: $set/$file"
  (cd "$data/$set" && "$lab" analyze "$file" --plot "$out/$name.png" >/dev/null)
done
ls -l "$out"/*.png
