#!/usr/bin/env bash
# `aerotrack bench` on the short open-field scenario (tests/data/short.yaml: a person walking 2 m,
# no obstacles): every trial must succeed without a collision -- a trial lost there is a regression,
# not noise -- and bench.json must be written with the same counts, and bench.png beside it.
# usage: bench_short.sh AEROTRACK SCENARIO.yaml OUT_DIR TRIALS
# Prints bench's own output, then "bench.json: TRIALS of TRIALS successful, 0 collisions" when
# bench.json agrees; the caller's regex checks bench's summary line and this one.
set -u
bin=$1 scenario=$2 out=$3 trials=$4
rm -rf "$out"
"$bin" bench --scenario "$scenario" --trials "$trials" --jobs 2 --out "$out" || exit $?
json=$out/bench.json
if [[ ! -s $json ]]; then
  printf 'no %s\n' "$json"
  exit 1
fi
for field in completed successes; do
  if ! grep -Eq "^  \"$field\": $trials,\$" "$json"; then
    printf '%s: expected "%s": %s, got: %s\n' "$json" "$field" "$trials" "$(grep -E "^  \"$field\":" "$json")"
    exit 1
  fi
done
if ! grep -Eq '^  "collisions": 0,$' "$json"; then
  printf '%s: expected "collisions": 0, got: %s\n' "$json" "$(grep -E '^  "collisions":' "$json")"
  exit 1
fi
if [[ ! -s $out/bench.png ]]; then
  printf 'no %s (the distributions of visibility and distance)\n' "$out/bench.png"
  exit 1
fi
printf 'bench.json: %s of %s successful, 0 collisions\n' "$trials" "$trials"
