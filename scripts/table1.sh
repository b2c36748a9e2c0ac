#!/usr/bin/env bash
# The paper's Table I, measured: the suite config/suites/table1.yaml (sharp turn at 0.85 and 1.5 m/s,
# proposed vs baseline, 20 seeds per cell) with `aerotrack bench --suite`, both verdicts (the paper's
# followed_all_the_way and ours) with 95 % Wilson intervals. Writes out/table1/report.md, suite.json
# and the plots; resumable (run it again after an interruption).
# Usage: scripts/table1.sh [JOBS]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
jobs="${1:-$(nproc)}"
bin=build/bin/aerotrack
[[ -x "$bin" ]] || { echo "table1: build first (scripts/demo.sh or scripts/test.sh)" >&2; exit 1; }
"$bin" bench --suite config/suites/table1.yaml --jobs "$jobs" --out out/table1
echo "table1: out/table1/report.md"
