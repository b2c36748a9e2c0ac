#!/usr/bin/env bash
# Configures (once) and builds aerotrack into build/ (Release, warnings are errors); the binary is
# build/bin/aerotrack. Incremental: a second run with nothing changed takes about a second.
# usage: scripts/build.sh [extra cmake -D options for the first configure]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
if [[ ! -f build/build.ninja ]]; then
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DAEROTRACK_WERROR=ON "$@" >/dev/null
fi
cmake --build build -j "$(nproc)"
