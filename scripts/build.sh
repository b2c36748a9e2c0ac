#!/usr/bin/env bash
# Configures (once) and builds one of the project's build trees; warnings are errors in all of them.
#   release  build/       Release: what flies and what the demo runs (build/bin/aerotrack)
#   asan     build-asan/  AddressSanitizer + UndefinedBehaviorSanitizer: the whole test suite (scripts/test.sh)
#   tsan     build-tsan/  ThreadSanitizer: the concurrency tests (scripts/check.sh tsan)
#   fuzz     build-fuzz/  clang, libFuzzer + ASan + UBSan: the fuzz targets of tests/fuzz (scripts/fuzz.sh)
#   fuzz-fast build-fuzz-fast/  the same with UBSan only (scripts/fuzz.sh --fast: the long runs)
# Every tree is a CMake unity build (AEROTRACK_UNITY_BUILD, docs/testing.md: about half the cold build
# time). ccache is used when it is installed (scripts/setup.sh --dev installs it); nothing depends on it.
# Incremental: a second run with nothing changed takes about a second.
# usage: scripts/build.sh [--tree release|asan|tsan|fuzz|fuzz-fast] [-DOPTION=VALUE...] [TARGET...]
#   TARGETs default to `aerotrack` for release and to everything for asan and tsan; -D options apply to
#   the first configure of a tree only.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

tree=release
options=()       # the tree's own
user_options=()  # -D options given on the command line
targets=()
while (($#)); do
  case $1 in
    --tree) tree=${2:?--tree needs release, asan or tsan}; shift 2 ;;
    -D*) user_options+=("$1"); shift ;;
    *) targets+=("$1"); shift ;;
  esac
done

# The sanitizer trees: line tables (-g1) are all the sanitizers' stack traces need, and full debug info
# of the Eigen-heavy translation units costs a fifth of their compile time. UBSan's checks make -O2 twice
# as slow to compile as ASan alone, so the ASan + UBSan tree is built at -O1 (what ASan's documentation
# recommends): a third less compile time for the suite's largest build (docs/testing.md, "CI time budget").
# Not the TSan tree: at -O1 it compiles 14 % faster, but GCC 12's -Wnull-dereference then reports Eigen's
# fixed-size constructors inlined into hal/sim/geometry.hpp (a false positive; CI of 2026-12-07).
# The ASan + UBSan tree is compiled by clang 16 (GCC builds the Release and TSan trees, so both compilers'
# warnings stay errors): its compiles take a fifth less time than GCC 12's with the same sanitizers (the suite's
# largest build, docs/testing.md "CI time budget"), and lld links its ~45 test binaries of up to 170 MB in half
# the time of GNU ld. The fuzz trees use the same clang (libFuzzer is clang's).
# Benchmarks measure optimised code; the sanitizer trees have no use for them.
clang=(-DCMAKE_CXX_COMPILER=clang++-16 -DCMAKE_EXE_LINKER_FLAGS=-fuse-ld=lld)
case $tree in
  release) dir=build; options+=(-DCMAKE_BUILD_TYPE=Release) ;;
  asan)
    dir=build-asan
    options+=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DAEROTRACK_SANITIZE=address,undefined -DAEROTRACK_BUILD_BENCHMARKS=OFF
      "${clang[@]}" "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG")
    ;;
  tsan)
    dir=build-tsan
    options+=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DAEROTRACK_SANITIZE=thread -DAEROTRACK_BUILD_BENCHMARKS=OFF
      "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG")
    ;;
  fuzz)  # clang: libFuzzer is clang's. No tests or benchmarks: the fuzz targets only.
    dir=build-fuzz
    options+=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DAEROTRACK_SANITIZE=address,undefined -DAEROTRACK_FUZZ=ON
      -DBUILD_TESTING=OFF -DAEROTRACK_BUILD_BENCHMARKS=OFF "${clang[@]}"
      "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG")
    ;;
  fuzz-fast)  # the fuzz targets with UBSan only, -O2: 3-4x the executions a second, for the long runs
    dir=build-fuzz-fast
    options+=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DAEROTRACK_SANITIZE=undefined -DAEROTRACK_FUZZ=ON
      -DBUILD_TESTING=OFF -DAEROTRACK_BUILD_BENCHMARKS=OFF "${clang[@]}"
      "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG")
    ;;
  *) echo "build.sh: unknown tree '$tree' (release, asan, tsan, fuzz, fuzz-fast)" >&2; exit 1 ;;
esac
# A tree configured with other options of its own (an older build.sh: another compiler or other flags) is
# configured afresh: CMake keeps a tree's first compiler and cache, so it would not take the new ones.
stamp=$dir/aerotrack-build-options.txt
if [[ -f $dir/build.ninja && $(cat "$stamp" 2>/dev/null) != "${options[*]}" ]]; then
  echo "build.sh: $dir was configured with other options: configuring it afresh" >&2
  rm -rf "$dir/CMakeCache.txt" "$dir/CMakeFiles" "$dir/build.ninja"  # what it holds besides (a fuzz corpus) stays
fi
if [[ ! -f $dir/build.ninja ]]; then
  launcher=()
  if command -v ccache >/dev/null; then  # CCACHE_DISABLE=1 turns it off for a cold measurement
    launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  fi
  cmake -S . -B "$dir" -G Ninja -DAEROTRACK_WERROR=ON "${options[@]}" "${launcher[@]}" "${user_options[@]}" >/dev/null
  echo "${options[*]}" >"$stamp"
fi
if ((${#targets[@]})); then
  cmake --build "$dir" -j "$(nproc)" --target "${targets[@]}"
elif [[ $tree == release ]]; then
  cmake --build "$dir" -j "$(nproc)" --target aerotrack
else
  cmake --build "$dir" -j "$(nproc)"
fi
