#!/usr/bin/env bash
# Every test: install what is missing (with the test tools), build the whole project once with
# AddressSanitizer + UndefinedBehaviorSanitizer (build-asan/), and run the whole ctest suite there in
# parallel -- unit, integration, command-line and concurrency tests, each one also a memory and UB check.
# CI runs this first (.ci/run), then scripts/check.sh (format, the Release tree and the tests that need an
# unsanitized malloc, vcan, TSan, clang-tidy). docs/testing.md says what each step costs.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
start=$SECONDS
scripts/setup.sh --dev
echo "test.sh: set-up done in $((SECONDS - start)) s"
step=$SECONDS
scripts/build.sh --tree asan
echo "test.sh: ASan + UBSan build done in $((SECONDS - step)) s"
step=$SECONDS
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-asan -j "$(nproc)" --output-on-failure --no-tests=error --timeout 300
echo "test.sh: tests done in $((SECONDS - step)) s (total $((SECONDS - start)) s)"
