#!/usr/bin/env bash
# Installs Debian's npm when there is no npm command (the provisioning steps fetch from the npm
# registry: scripts/models/provision.sh, tools/foxglove/provision.sh). Idempotent; quiet when npm is there.
# usage: scripts/ensure_npm.sh
set -euo pipefail
command -v npm >/dev/null && exit 0
sudo=()
[[ $(id -u) -ne 0 ]] && sudo=(sudo)
echo "provision: installing npm (Debian package)"
"${sudo[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends npm >/dev/null
