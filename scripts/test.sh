#!/usr/bin/env bash
# Every test: install what is missing (with the test tools), build once, run the whole ctest
# suite in parallel. CI runs this first (.ci/run), then scripts/check.sh.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
scripts/setup.sh --dev
scripts/build.sh
ctest --test-dir build -j "$(nproc)" --output-on-failure --timeout 300
