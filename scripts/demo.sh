#!/usr/bin/env bash
# The main job: install what is missing, build, and fly a closed-loop trial in the built-in
# simulator (lockstep): the paper's sharp-turn benchmark. Results and pictures land in out/demo/.
# usage: scripts/demo.sh [extra `aerotrack sim` options, e.g. --seed 3]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
scripts/setup.sh
scripts/build.sh
build/bin/aerotrack sim --scenario sharp_turn --out out/demo "$@"
