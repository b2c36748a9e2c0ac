#!/usr/bin/env bash
# Our MAVLink frames decoded by node-mavlink (issue 11 item 4): installs node-mavlink from
# package-lock.json once (npm ci into tools/mavlink/node_modules, git-ignored), then pipes the frames
# of FRAMES_BINARY (tests/tools/mavlink_frames.cpp) through check.js. One line out; status 1 on any
# disagreement, or if node/npm or the registry is missing.
# usage: tools/mavlink/check.sh FRAMES_BINARY [COUNT_PER_MESSAGE]
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
frames=$1 count=${2:-200}
command -v node > /dev/null || { echo "mavlink check: node not found (Debian package nodejs)"; exit 1; }
if [[ ! -f $here/node_modules/node-mavlink/package.json ]]; then
  command -v npm > /dev/null || { echo "mavlink check: npm not found (Debian package npm)"; exit 1; }
  if ! npm ci --prefix "$here" --loglevel error --no-audit --no-fund > "$here/npm.log" 2>&1; then
    echo "mavlink check: npm ci failed (registry unreachable?): $(grep -m1 -i 'err' "$here/npm.log" || true)"
    exit 1
  fi
  rm -f "$here/npm.log"
fi
"$frames" "$count" | node "$here/check.js"
