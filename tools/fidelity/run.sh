#!/usr/bin/env bash
# End-to-end fidelity check of the MoveNet detector: the original tfjs graph (reference.mjs, the
# pure-JS CPU backend of TensorFlow.js) against `aerotrack detect --json` on real photos from
# Debian's opencv-doc (messi5, basketball1, frames 0/200/400 of vtest), for each model. The images
# are letterboxed once into S x S PNGs so that both sides see identical pixels; keypoints (and for
# multipose the box and person score) are compared in normalised coordinates (pixels / S) and
# scores, each detected person against the closest tfjs person; the run fails beyond 1e-4.
# With --python the candidate is tools/fidelity/fidelity.py's decoder (OpenCV DNN on the ONNX file
# plus a numpy transcription of the decoding in scripts/models/README.md) instead of the C++ one,
# and every output value is compared, all 6 multipose rows included.
# Needs node/npm (installs tools/fidelity's pinned packages with `npm ci` when missing),
# opencv-doc, and the models (scripts/models/provision.sh --tfjs, run here).
# usage: tools/fidelity/run.sh [--python] [lightning|thunder|multipose]...
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
readonly HERE=tools/fidelity PYTHON=/usr/bin/python3 DATA=/usr/share/doc/opencv-doc/examples/data

fail() { echo "fidelity: $*" >&2; exit 1; }

candidate=detect
[[ ${1:-} == --python ]] && { candidate=python; shift; }
variants=("$@")
((${#variants[@]})) || variants=(lightning thunder multipose)

command -v node >/dev/null || fail "node is missing (install Debian's npm, or run scripts/models/provision.sh)"
[[ -d $DATA ]] || fail "$DATA is missing (apt-get install opencv-doc)"
[[ $candidate == python || -x build/bin/aerotrack ]] || fail "build/bin/aerotrack is missing: run scripts/build.sh, or use --python"
scripts/models/provision.sh --tfjs
if [[ ! -d $HERE/node_modules ]]; then
  (cd "$HERE" && npm ci --no-audit --no-fund --ignore-scripts --silent) || fail "npm ci in $HERE failed"
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Inputs: one set of letterboxed PNGs per input size.
declare -A size
for v in "${variants[@]}"; do
  [[ -f models/movenet-$v.decode.json ]] || fail "unknown model $v"
  size[$v]=$("$PYTHON" -c 'import json, sys; print(json.load(open(sys.argv[1]))["input_size"])' "models/movenet-$v.decode.json")
  if [[ ! -f $work/inputs-${size[$v]} ]]; then
    "$PYTHON" $HERE/fidelity.py inputs --size "${size[$v]}" --out "$work/${size[$v]}" \
      "$DATA/messi5.jpg" "$DATA/basketball1.png" "$DATA/vtest.avi" >"$work/inputs-${size[$v]}"
  fi
done

# The reference: tfjs's JavaScript convolutions take seconds per image, so one process per
# (model, image), as many at a time as there are cores.
reference_jobs() {  # lines of: tfjs model, PNG, result file
  local v png
  for v in "${variants[@]}"; do
    while read -r png; do
      echo ".cache/models/tfjs/movenet-$v.json $png $work/reference-$v-${png##*/}.json"
    done <"$work/inputs-${size[$v]}"
  done
}
# shellcheck disable=SC2016  # the quoted script is expanded by sh -c, once per job
reference_jobs | xargs -P "$(nproc)" -L 1 sh -c \
  'node tools/fidelity/reference.mjs --model "$0" "$1" >"$2" 2>"$2.log" || { cat "$2.log" >&2; exit 255; }' \
  || fail "reference.mjs failed"

failed=0
for v in "${variants[@]}"; do
  mapfile -t pngs <"$work/inputs-${size[$v]}"
  for png in "${pngs[@]}"; do cat "$work/reference-$v-${png##*/}.json"; done >"$work/reference-$v"
  if [[ $candidate == python ]]; then
    "$PYTHON" $HERE/fidelity.py decode --model "models/movenet-$v.onnx" "${pngs[@]}" >"$work/candidate-$v"
    format=identity
  else
    for png in "${pngs[@]}"; do
      build/bin/aerotrack detect "$png" --model "$v" --json
    done >"$work/candidate-$v"
    format=detect
  fi
  "$PYTHON" $HERE/fidelity.py compare --reference "$work/reference-$v" --candidate "$work/candidate-$v" \
    --format "$format" --size "${size[$v]}" --label "$v ($candidate)" || failed=1
done
echo "fidelity: ${#variants[@]} models in $SECONDS s"
exit "$failed"
