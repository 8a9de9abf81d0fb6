#!/usr/bin/env bash
# The fuzzing step of CI (issue 32 item 7): for each cargo-fuzz target, first every committed
# regression input (fuzz/regressions/<target>/) is run once, then the fuzzer runs for SECONDS
# (default 30) from the committed seeds (fuzz/corpus/<target>/, read only; what it adds goes to
# target/fuzz-corpus/<target>/). Prints the executions per target and fails on any crash,
# panic, timeout, out-of-memory or over-budget allocation, printing the input that caused it.
#
# Usage: scripts/fuzz_ci.sh [SECONDS] [TARGET...]
# Expects the targets built by `cargo fuzz build -s none --dev --target-dir target/fuzz`
# (stable toolchain, no sanitizer; .ci/run does both). fuzz/README.md says how to reproduce.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-30}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(can_frames iox_payloads recordings mcap_read mcap_recover config_toml)
bin_dir=target/fuzz/x86_64-unknown-linux-gnu/debug

# The largest input each target is given: a little above its largest seed.
max_len() {
  case "$1" in
    can_frames) echo 4096 ;;
    iox_payloads) echo 16384 ;;
    recordings) echo 8192 ;;
    mcap_read | mcap_recover) echo 65536 ;;
    config_toml) echo 32768 ;;
    *) echo "unknown fuzz target $1" >&2; exit 2 ;;
  esac
}

dict() {
  case "$1" in
    mcap_read | mcap_recover) echo "-dict=fuzz/dict/mcap.dict" ;;
    config_toml) echo "-dict=fuzz/dict/config.dict" ;;
  esac
}

# Prints what libFuzzer left (crash-, timeout-, oom-, leak-, slow-unit-); the step then fails.
report_failure() {
  local target="$1" log="$2" artifacts="$3"
  echo "FUZZ FAILURE in $target; the fuzzer's last lines:"
  tail -n 40 "$log"
  local artifact
  for artifact in "$artifacts"/*; do
    [ -f "$artifact" ] || continue
    echo "input: $artifact ($(stat -c %s "$artifact") bytes); reproduce with"
    echo "  $bin_dir/$target $artifact"
    if [ "$(stat -c %s "$artifact")" -le 4096 ]; then
      echo "base64:"
      base64 -w 100 "$artifact"
    fi
  done
  failures=1
}

# One target, in the background: the regression inputs, then the bounded run. Leaves its
# execution count in target/fuzz-logs/<target>.runs; fails on any finding.
fuzz_one() {
  local target="$1" bin="$bin_dir/$1"
  local artifacts="target/fuzz-artifacts/$target" new_inputs="target/fuzz-corpus/$target"
  local log="target/fuzz-logs/$target.log"
  rm -rf "$artifacts" "target/fuzz-logs/$target.runs"
  mkdir -p "$artifacts" "$new_inputs"
  local common=(-timeout=10 -rss_limit_mb=2048 "-max_len=$(max_len "$target")" "-artifact_prefix=$artifacts/")
  local regressions=()
  if [ -d "fuzz/regressions/$target" ]; then
    mapfile -t regressions < <(find "fuzz/regressions/$target" -type f | sort)
  fi
  : >"$log"
  if [ ${#regressions[@]} -gt 0 ]; then
    "$bin" "${common[@]}" "${regressions[@]}" >>"$log" 2>&1 || return 1
  fi
  # shellcheck disable=SC2046
  "$bin" "${common[@]}" $(dict "$target") -max_total_time="$seconds" -print_final_stats=1 \
    "$new_inputs" "fuzz/corpus/$target" >>"$log" 2>&1 || return 1
  local runs
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  [ -n "$runs" ] || { echo "no execution count in $log" >>"$log"; return 1; }
  printf '%s %s\n' "$runs" "${#regressions[@]}" >"target/fuzz-logs/$target.runs"
}

# Two targets at a time (CI has 2 cores and nothing else running in this step): each still
# gets its SECONDS of fuzzing.
parallel="${FUZZ_JOBS:-2}"
mkdir -p target/fuzz-logs
for target in "${targets[@]}"; do
  max_len "$target" >/dev/null
  [ -x "$bin_dir/$target" ] || { echo "$bin_dir/$target is missing: build with cargo fuzz build -s none --dev --target-dir target/fuzz" >&2; exit 1; }
done
total=0
failures=0
for ((i = 0; i < ${#targets[@]}; i += parallel)); do
  batch=("${targets[@]:i:parallel}")
  pids=()
  for target in "${batch[@]}"; do
    fuzz_one "$target" &
    pids+=($!)
  done
  failed=()
  for j in "${!batch[@]}"; do
    wait "${pids[$j]}" || failed+=("${batch[$j]}")
  done
  for target in "${batch[@]}"; do
    [ -f "target/fuzz-logs/$target.runs" ] || continue
    read -r runs replayed <"target/fuzz-logs/$target.runs"
    total=$((total + runs))
    printf '%-14s %9s executions in %ss, %s regression inputs replayed\n' \
      "$target" "$runs" "$seconds" "$replayed"
  done
  for target in "${failed[@]}"; do
    report_failure "$target" "target/fuzz-logs/$target.log" "target/fuzz-artifacts/$target"
  done
done
if [ "$failures" -ne 0 ]; then
  echo "fuzzing FAILED: fix each finding in src with a test, add its input to fuzz/regressions/<target>/"
  exit 1
fi
printf 'fuzzing: %s executions over %s targets, 0 crashes, 0 timeouts, 0 over-budget allocations\n' \
  "$total" "${#targets[@]}"
