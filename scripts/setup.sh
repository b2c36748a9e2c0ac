#!/usr/bin/env bash
# Installs what aerotrack needs on Debian 12: the packages listed in scripts/deps/ (with --dev,
# also the test tools). Idempotent: it asks dpkg first and runs apt only for what is missing,
# so it takes well under a second when everything is there.
# usage: scripts/setup.sh [--dev]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

lists=(scripts/deps/debian-build.txt)
[[ ${1:-} == --dev ]] && lists+=(scripts/deps/debian-dev.txt)
mapfile -t wanted < <(sed 's/#.*//; s/[[:space:]]//g; /^$/d' "${lists[@]}")

# dpkg-query exits 1 when any package is unknown to dpkg (never installed): that is the answer we
# want, not an error, so the pipeline must not trip pipefail.
installed=$({ dpkg-query -W -f='${Package} ${db:Status-Status}\n' "${wanted[@]}" 2>/dev/null || true; } | awk '$2 == "installed" {print $1}')
missing=()
for p in "${wanted[@]}"; do
  grep -qx "$p" <<<"$installed" || missing+=("$p")
done

if ((${#missing[@]})); then
  sudo=()
  [[ $(id -u) -ne 0 ]] && sudo=(sudo)
  echo "setup: installing ${missing[*]}"
  "${sudo[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The MoveNet models in models/: fetched and converted once, checked against their sha256 sums.
scripts/models/provision.sh
# Foxglove's message schemas (the flight log's .proto files) and the MCAP reader of the tests, from npm.
tools/foxglove/provision.sh
