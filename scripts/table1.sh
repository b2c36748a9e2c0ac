#!/usr/bin/env bash
# The paper's Table I, measured: sharp turn at 0.85 and 1.5 m/s, proposed vs baseline, and the forest
# at 3 m/s (proposed), TRIALS seeds per cell (default 20), with `aerotrack bench`. Writes
# out/table1/TABLE.md (and each cell's bench.json under out/table1/). Usage: scripts/table1.sh [TRIALS] [JOBS]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
trials="${1:-20}"
jobs="${2:-$(nproc)}"
bin=build/bin/aerotrack
[[ -x "$bin" ]] || { echo "table1: build first (scripts/demo.sh or scripts/test.sh)" >&2; exit 1; }
out=out/table1
mkdir -p "$out"
rows=()
run_cell() {  # scenario speed mode
  local dir="$out/$1-$2-$3"
  local row
  row=$("$bin" bench --scenario "$1" --speed "$2" --mode "$3" --trials "$trials" --jobs "$jobs" --out "$dir" | grep '^| ' || true)
  rows+=("$row")
  echo "$row"
}
run_cell sharp_turn 0.85 proposed
run_cell sharp_turn 0.85 baseline
run_cell sharp_turn 1.5 proposed
run_cell sharp_turn 1.5 baseline
run_cell forest 3.0 proposed
{
  echo "| scenario | person speed | mode | success | person visible | losses of sight (all trials) | hidden a run: behind obstacles / out of image | mean distance | planning p50 / p99 (max over trials) | collisions |"
  echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
  printf '%s\n' "${rows[@]}"
} > "$out/TABLE.md"
echo "table1: $out/TABLE.md"
