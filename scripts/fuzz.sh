#!/usr/bin/env bash
# Builds the fuzz tree (scripts/build.sh --tree fuzz: clang, libFuzzer, ASan + UBSan) and runs each
# fuzz target for SECONDS on a corpus seeded from the repository's own files (tests/fuzz/README.md), as
# many targets at once as there are cores.
# A crash, a leak, undefined behaviour, a timeout (10 s on one input) or more than 2 GB of memory is a
# failure: the input is kept in build-fuzz/crashes/ and the script exits 1. Prints one line per
# target with its executions. With --runs N each target instead runs N inputs (the long runs of
# tests/fuzz/README.md: --runs 1000000), however long that takes.
# The default targets are CI's; app_config (the whole application's configuration: a long build in
# this tree) runs only when named.
# usage: scripts/fuzz.sh [--fast] [SECONDS (default 60) | --runs N] [TARGET...]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
tree=fuzz  # --fast: the UBSan-only tree (3-4x faster, no ASan), for runs of 1e6 inputs; same corpora
if [[ ${1:-} == --fast ]]; then
  tree=fuzz-fast
  shift
fi
if [[ ${1:-} == --runs ]]; then
  [[ ${2:-} =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: --runs needs a positive count" >&2; exit 2; }
  limit=(-runs="$2")
  shift 2
else
  seconds=${1:-60}
  [[ $seconds =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: SECONDS must be a positive number, got '$seconds'" >&2; exit 2; }
  limit=(-max_total_time="$seconds")
  shift || true
fi
targets=("$@")
((${#targets[@]})) || targets=(yaml_config scenario csv_streams calibration_csv protocols image_decode)

scripts/build.sh --tree "$tree" "${targets[@]/#/fuzz_}" >/dev/null
out=build-$tree

# The seed corpus of each target: what the repository itself holds of that kind of input.
seeds() {
  case $1 in
    yaml_config) ls config/*.yaml config/suites/*.yaml config/calibration/*.yaml tests/data/real/*.yaml ;;
    app_config) ls config/*.yaml tests/data/real/*.yaml ;;
    scenario) ls config/scenarios/*.yaml tests/data/*.yaml ;;
    calibration_csv) ls tests/data/*.csv ;;
  esac
  [[ ! -d tests/fuzz/seeds/$1 ]] || find tests/fuzz/seeds/"$1" -type f
}

mkdir -p build-fuzz/crashes
# fuzz_one TARGET: fuzzes one target and prints its line; exits 1 if it failed.
fuzz_one() {
  local t=$1 corpus=build-fuzz/corpus/$1 log=$out/fuzz_$1.log status=ok runs secs
  mkdir -p "$corpus"
  seeds "$t" | xargs -r cp -t "$corpus"
  "$out"/fuzz/fuzz_"$t" "$corpus" "${limit[@]}" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix=build-fuzz/crashes/"$t"- >"$log" 2>&1 || status=FAILED
  runs=$(awk '/stat::number_of_executed_units/ {print $2}' "$log")
  secs=$(awk '/^Done [0-9]+ runs in/ {print $5}' "$log")
  echo "fuzz: $t: ${runs:-?} executions in ${secs:-?} s, $status$([[ $status == ok ]] || echo " (see $log)")"
  [[ $status == ok ]]
}

# libFuzzer runs on one core: as many targets at once as there are cores (CI's 2-core machine: 3 rounds of 2
# instead of 6 one after the other), each line printed when its round ends.
jobs=$(nproc)
failed=0
for ((i = 0; i < ${#targets[@]}; i += jobs)); do
  pids=()
  for t in "${targets[@]:i:jobs}"; do
    fuzz_one "$t" >"$out/fuzz_$t.line" &
    pids+=($!)
  done
  for j in "${!pids[@]}"; do
    wait "${pids[j]}" || failed=1
  done
  for t in "${targets[@]:i:jobs}"; do cat "$out/fuzz_$t.line"; done
done
exit "$failed"
