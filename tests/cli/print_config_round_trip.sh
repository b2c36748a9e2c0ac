#!/usr/bin/env bash
# `aerotrack run --print-config` round trip: the printed configuration, loaded again from another
# folder, prints the same bytes (the printout is a fixed point: every effective value, paths made
# absolute, nothing dropped or defaulted differently), and it has every top-level section of the
# source file. Runs in a fresh temporary folder, so a path left relative to the source file's folder
# would not resolve there.
# usage: print_config_round_trip.sh AEROTRACK CONFIG.yaml
# Prints "print-config round trip: NAME: N sections, identical after reloading" on success; otherwise
# what differs, and exits 1.
set -u
bin=$1 config=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
name=$(basename "$config")

if ! "$bin" run --config "$config" --print-config >printed.yaml 2>error.txt; then
  printf 'printing %s failed: %s\n' "$config" "$(cat error.txt)"
  exit 1
fi
if ! "$bin" run --config printed.yaml --print-config >printed2.yaml 2>error.txt; then
  printf 'the printout of %s does not load again: %s\n' "$name" "$(cat error.txt)"
  exit 1
fi
if ! cmp -s printed.yaml printed2.yaml; then
  printf 'the printout of %s changes when loaded and printed again:\n' "$name"
  diff printed.yaml printed2.yaml
  exit 1
fi
sections=$(grep -E '^[a-z_]+:' "$config" | cut -d: -f1)
count=0
for section in $sections; do
  if ! grep -q "^$section:" printed.yaml; then
    printf 'the printout of %s has no section %s\n' "$name" "$section"
    exit 1
  fi
  count=$((count + 1))
done
if [[ $count -eq 0 ]]; then
  printf '%s has no top-level section\n' "$config"
  exit 1
fi
printf 'print-config round trip: %s: %d sections, identical after reloading\n' "$name" "$count"
