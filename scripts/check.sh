#!/usr/bin/env bash
# The checks CI adds to the test suite (scripts/test.sh, which runs every test under ASan + UBSan). Each
# step prints its own time; docs/testing.md keeps the budget.
#   format   clang-format finds nothing to change
#   release  the Release tree (build/): the binary, the benchmarks (compiled, not run: they are measured by
#            hand) and the vcan test binary; runs the tests labelled `unit-unsanitized` -- they count mallocs, and
#            a sanitizer owns malloc, so under test.sh they skip
#   vcan     the CAN gimbal driver over real SocketCAN (vcan0) in QEMU (scripts/vcan_test.sh, ~10 s once the
#            kernel is cached; the first run downloads Debian's kernel package, 70 MB)
#   slurm    `bench --executor slurm` against a real single-node Slurm from Debian's packages (scripts/slurm_test.sh,
#            ~10 s; installs slurm-wlm and munge when missing)
#   tsan     a build with ThreadSanitizer runs the concurrency tests
#   tidy     clang-tidy (.clang-tidy) on every production source, warnings are errors
# usage: scripts/check.sh [format|release|vcan|slurm|tsan|tidy|all]...   (default: all)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
jobs=$(nproc)
steps=("$@")
((${#steps[@]})) || steps=(all)
[[ ${steps[*]} == all ]] && steps=(format release vcan slurm tsan tidy)

sources() { git ls-files "$@"; }

for step in "${steps[@]}"; do
  start=$SECONDS
  case $step in
    format)
      sources '*.cpp' '*.hpp' | xargs clang-format --dry-run --Werror
      ;;
    release)
      scripts/build.sh --tree release aerotrack aerotrack_benchmarks hal_real_can_vcan_tests unsanitized_tests
      ctest --test-dir build -j "$jobs" --output-on-failure --timeout 300 --no-tests=error -L unsanitized
      ;;
    vcan)
      scripts/build.sh --tree release hal_real_can_vcan_tests
      scripts/vcan_test.sh build/bin/hal_real_can_vcan_tests
      ;;
    slurm)
      scripts/build.sh --tree release aerotrack
      scripts/slurm_test.sh build/bin/aerotrack
      ;;
    tsan)
      scripts/build.sh --tree tsan rt_executor_tests rt_stress_tests sim_world_concurrency_tests sim_realtime_tests \
        hal_recorder_tests
      # GCC 12's TSan cannot map its shadow memory under a high mmap ASLR entropy (Linux >= 6.5
      # defaults): run without address randomisation.
      # Third-party false positives are suppressed by name in tests/sanitizers/tsan.supp.
      TSAN_OPTIONS="halt_on_error=1 suppressions=$PWD/tests/sanitizers/tsan.supp" setarch "$(uname -m)" -R \
        ctest --test-dir build-tsan -j "$jobs" --output-on-failure --no-tests=error -L concurrency
      ;;
    tidy)
      # clang-tidy reads the Release tree's compile database, whose translation units are the unity files
      # of the build (each #includes a batch of one target's sources): every production source is checked
      # once, with every check, and the headers the batch shares are parsed and matched once per batch
      # instead of once per source -- a third of the time. Diagnostics are kept for .cpp/.h/.hpp files only
      # (--line-filter): the unity files' own `#include "x.cpp"` lines are how the build works, not code.
      # (Production = the rt, hal, modules and app trees, as unity files or as sources a target keeps out of
      # its unity files; an optional driver whose SDK is not installed,
      # librealsense2, is not compiled, so it is not in the database and is not checked.)
      [[ -f build/compile_commands.json ]] || scripts/build.sh --tree release aerotrack
      units=$(grep -o '"file": "[^"]*"' build/compile_commands.json | sed 's#"file": "##; s#"$##' |
        grep -E "^$PWD/(build/)?(rt|hal|modules|app)/" | sort -u)
      [[ -n $units ]] || { echo "check.sh: tidy: no production translation unit in build/compile_commands.json" >&2; exit 1; }
      echo "tidy: $(wc -l <<<"$units") translation units"
      # clang-tidy counts the (suppressed) warnings of system headers on stderr: drop that line.
      xargs -P "$jobs" -n 1 clang-tidy -p build --quiet --extra-arg=-Wno-unknown-warning-option \
        --line-filter='[{"name":".cpp"},{"name":".hpp"},{"name":".h"}]' <<<"$units" 2>&1 |
        { grep -v ' warnings generated\.$' || true; }
      ;;
    *)
      echo "check.sh: unknown step '$step' (format, release, vcan, slurm, tsan, tidy, all)" >&2
      exit 1
      ;;
  esac
  echo "check.sh: $step passed in $((SECONDS - start)) s"
done
