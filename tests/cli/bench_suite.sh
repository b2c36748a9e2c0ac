#!/usr/bin/env bash
# `aerotrack bench --suite` end to end on the short open-field scenario (tests/data/short.yaml): a
# suite of one real cell (2 seeds) and one whose scenario does not exist. The missing one must be an
# error line in report.md while the real cell runs; a second run must find both trials complete and
# run nothing (resume).
# usage: bench_suite.sh AEROTRACK SCENARIO.yaml OUT_DIR
# Prints "suite resumed: 2 complete, 0 run, report.md has the error line" when all holds.
set -u
bin=$1 scenario=$2 out=$3
rm -rf "$out"
mkdir -p "$out"
cat >"$out.yaml" <<SUITE
name: short
seeds: 2
cells:
  - {scenario: $scenario, modes: [proposed]}
  - {scenario: no_such_scenario, modes: [baseline]}
SUITE
"$bin" bench --suite "$out.yaml" --out "$out" --jobs 2
[[ $? == 1 ]] || { echo "expected exit status 1 (a cell in error)"; exit 1; }
for f in suite.json report.md plot-short.png short-own-proposed-keypoints/trial-2/summary.json; do
  [[ -s $out/$f ]] || { echo "no $out/$f"; exit 1; }
done
grep -q '^- \*\*error\*\* no_such_scenario-own-baseline-keypoints: scenario file .*no_such_scenario.yaml does not exist$' \
  "$out/report.md" || { echo "report.md lacks the error line"; exit 1; }
second=$("$bin" bench --suite "$out.yaml" --out "$out" --jobs 2 2>/dev/null | head -1)
[[ $second == "suite short: 2 cells, 2 trials complete already, 0 to run, 2 at a time" ]] ||
  { echo "second run: $second"; exit 1; }
echo "suite resumed: 2 complete, 0 run, report.md has the error line"
