#!/usr/bin/env bash
# The checks CI adds to the test suite. Each step prints its own time.
#   format  clang-format finds nothing to change
#   asan    a build with AddressSanitizer + UBSan runs the unit, integration and CLI tests
#   tsan    a build with ThreadSanitizer runs the concurrency tests
#   vcan    the CAN gimbal driver over real SocketCAN (vcan0) in QEMU (scripts/vcan_test.sh, ~10 s
#           once the kernel is cached; the first run downloads Debian's kernel package, 70 MB)
#   tidy    clang-tidy (.clang-tidy) on the production sources, warnings are errors
# usage: scripts/check.sh [format|vcan|asan|tsan|tidy|all]...   (default: all)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
jobs=$(nproc)
steps=("$@")
((${#steps[@]})) || steps=(all)
[[ ${steps[*]} == all ]] && steps=(format vcan asan tsan tidy)

sources() { git ls-files "$@"; }

sanitized_build() {  # dir, sanitizers, targets...
  local dir=$1 sanitize=$2
  shift 2
  if [[ ! -f $dir/build.ninja ]]; then
    cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DAEROTRACK_WERROR=ON \
      -DAEROTRACK_SANITIZE="$sanitize" -DAEROTRACK_BUILD_BENCHMARKS=OFF >/dev/null
  fi
  cmake --build "$dir" -j "$jobs" --target "$@"
}

for step in "${steps[@]}"; do
  start=$SECONDS
  case $step in
    format)
      sources '*.cpp' '*.hpp' | xargs clang-format --dry-run --Werror
      ;;
    vcan)
      [[ -x build/bin/hal_real_can_vcan_tests ]] || scripts/build.sh
      scripts/vcan_test.sh build/bin/hal_real_can_vcan_tests
      ;;
    asan)
      sanitized_build build-asan address,undefined all
      ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
        ctest --test-dir build-asan -j "$jobs" --output-on-failure -L 'unit|integration|cli'
      ;;
    tsan)
      sanitized_build build-tsan thread rt_executor_tests rt_stress_tests sim_world_concurrency_tests sim_realtime_tests \
        hal_recorder_tests
      # GCC 12's TSan cannot map its shadow memory under a high mmap ASLR entropy (Linux >= 6.5
      # defaults): run without address randomisation.
      # Third-party false positives are suppressed by name in tests/sanitizers/tsan.supp.
      TSAN_OPTIONS="halt_on_error=1 suppressions=$PWD/tests/sanitizers/tsan.supp" setarch "$(uname -m)" -R \
        ctest --test-dir build-tsan -j "$jobs" --output-on-failure -L concurrency
      ;;
    tidy)
      [[ -f build/compile_commands.json ]] || scripts/build.sh
      # clang-tidy counts the (suppressed) warnings of system headers on stderr: drop that line.
      # Only what this build compiles: an optional driver whose SDK is not installed (librealsense2) is
      # not in the compile database, and clang-tidy cannot check it without its headers.
      compiled=$(grep -o '"file": "[^"]*"' build/compile_commands.json | sed "s#\"file\": \"$PWD/##; s#\"\$##" | sort -u)
      sources 'rt/*.cpp' 'hal/*.cpp' 'modules/*.cpp' 'app/*.cpp' | grep -Fx -f <(echo "$compiled") |
        xargs -P "$jobs" -n 1 clang-tidy -p build --quiet --extra-arg=-Wno-unknown-warning-option 2>&1 |
        { grep -v ' warnings generated\.$' || true; }
      ;;
    *)
      echo "check.sh: unknown step '$step' (format, vcan, asan, tsan, tidy, all)" >&2
      exit 1
      ;;
  esac
  echo "check.sh: $step passed in $((SECONDS - start)) s"
done
