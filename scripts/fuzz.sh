#!/usr/bin/env bash
# Builds the fuzz tree (scripts/build.sh --tree fuzz: clang, libFuzzer, ASan + UBSan) and runs each
# fuzz target for SECONDS on a corpus seeded from the repository's own files (tests/fuzz/README.md).
# A crash, a leak, undefined behaviour, a timeout (10 s on one input) or more than 2 GB of memory is a
# failure: the input is kept in build-fuzz/crashes/ and the script exits 1. Prints one line per
# target with its executions.
# usage: scripts/fuzz.sh [SECONDS (default 60)] [TARGET...]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
seconds=${1:-60}
shift || true
targets=("$@")
((${#targets[@]})) || targets=(yaml_config scenario csv_streams calibration_csv protocols image_decode)

scripts/build.sh --tree fuzz "${targets[@]/#/fuzz_}" >/dev/null

# The seed corpus of each target: what the repository itself holds of that kind of input.
seeds() {
  case $1 in
    yaml_config) ls config/*.yaml config/suites/*.yaml config/calibration/*.yaml tests/data/real/*.yaml ;;
    scenario) ls config/scenarios/*.yaml tests/data/*.yaml ;;
    calibration_csv) ls tests/data/*.csv ;;
  esac
  [[ ! -d tests/fuzz/seeds/$1 ]] || find tests/fuzz/seeds/"$1" -type f
}

mkdir -p build-fuzz/crashes
failed=0
for t in "${targets[@]}"; do
  corpus=build-fuzz/corpus/$t
  mkdir -p "$corpus"
  seeds "$t" | xargs -r cp -t "$corpus"
  log=build-fuzz/fuzz_$t.log
  if build-fuzz/fuzz/fuzz_"$t" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix=build-fuzz/crashes/"$t"- >"$log" 2>&1; then
    status=ok
  else
    status=FAILED
    failed=1
  fi
  runs=$(awk '/stat::number_of_executed_units/ {print $2}' "$log")
  echo "fuzz: $t: ${runs:-?} executions in $seconds s, $status$([[ $status == ok ]] || echo " (see $log)")"
done
exit "$failed"
