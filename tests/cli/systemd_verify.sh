#!/usr/bin/env bash
# Checks the systemd units in tools/systemd/ with `systemd-analyze verify`, pointed at this build's
# binary and this tree's config (verify requires the ExecStart binary to exist). Any message fails:
# verify exits 0 on an unknown key, and a misspelt WatchdogSec= would leave the service unwatched.
# usage: systemd_verify.sh AEROTRACK_BINARY SOURCE_DIR
set -euo pipefail
bin=$1 src=$2
if ! command -v systemd-analyze > /dev/null; then
  echo "systemd_verify: systemd-analyze not found (Debian package systemd; scripts/setup.sh --dev installs it)"
  exit 1
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
sed -e "s#/usr/local/bin/aerotrack#$bin#" -e "s#/usr/local/share/aerotrack/config#$src/config#" \
  "$src/tools/systemd/aerotrack.service" > "$dir/aerotrack.service"
cp "$src/tools/systemd/aerotrack-can.service" "$dir/"
test -f "$src/config/drone.yaml" || { echo "systemd_verify: $src/config/drone.yaml is missing"; exit 1; }
"$bin" run --config "$src/config/drone.yaml" --print-config > /dev/null
messages=$(cd "$dir" && systemd-analyze verify "$dir/aerotrack.service" "$dir/aerotrack-can.service" 2>&1) || {
  echo "systemd_verify: $(echo "$messages" | head -n 1)"
  exit 1
}
if [[ -n "$messages" ]]; then
  echo "systemd_verify: $(echo "$messages" | head -n 1)"
  exit 1
fi
echo "systemd units verified: aerotrack.service aerotrack-can.service"
