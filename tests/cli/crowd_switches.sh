#!/usr/bin/env bash
# scripts/crowd_switches.py on a made-up bench folder whose answers are known: four trials, two with a switch (one
# to the look-alike 0.3 m from the person, one to another bystander 1.4 m away), the look-alike within 0.5 m of
# the person in two of the worlds; --against a second bench whose four trials are all free of switches (seeds 2
# and 3 discordant: exact McNemar p = 2 x 1/4); a summary.json that is not JSON is one line naming it.
# usage: crowd_switches.sh SCRIPT
# Prints "crowd_switches ok" on success; otherwise the output that differed, and exits 1.
set -u
script=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
trial() {  # seed switches events look_alike_closest [folder]
  local folder=${5:-bench}
  mkdir -p "$work/$folder/trial-$1"
  printf '{"seed": %s, "identity_switches": %s, "identity_switch_events": %s, "closest_approach_m": {"bystander": 0.2, "look_alike": %s}}\n' \
    "$1" "$2" "$3" "$4" >"$work/$folder/trial-$1/summary.json"
}
trial 1 0 '[]' 0.4
trial 2 1 '[{"t_s": 20.0, "from": 0, "to": 3, "separation_m": 0.3, "look_alike": true}]' 0.3
trial 3 2 '[{"t_s": 9.0, "from": 0, "to": 2, "separation_m": 1.4, "look_alike": false}, {"t_s": 9.5, "from": 2, "to": 0, "separation_m": 1.3, "look_alike": false}]' 2.5
trial 4 0 '[]' 3.0
out=$(/usr/bin/python3 "$script" "$work/bench" 2>&1)
expected='2/4 trials without an identity switch, Wilson 95 % [0.15, 0.85]
  first switch to or from another bystander, > 1.0 m apart: 1 trials (seeds 3)
  first switch to or from the look-alike, <= 0.5 m apart: 1 trials (seeds 2)
  the look-alike'"'"'s closest approach <= 0.5 m: 1/2 without a switch [0.09, 0.91]
  the look-alike'"'"'s closest approach > 0.5 m: 1/2 without a switch [0.09, 0.91]'
if [ "$out" != "$expected" ]; then
  printf 'unexpected output:\n%s\n' "$out"
  exit 1
fi
for seed in 1 2 3 4; do trial $seed 0 '[]' 1.0 other; done
out=$(/usr/bin/python3 "$script" "$work/bench" --against "$work/other" 2>&1 | tail -n 1)
expected='paired on 4 seeds: without a switch 2 here, 4 against; only here: 0 (seeds -), only against: 2 (seeds 2, 3); exact McNemar p = 0.500'
if [ "$out" != "$expected" ]; then
  printf 'unexpected paired output:\n%s\n' "$out"
  exit 1
fi
echo 'not json' >"$work/bench/trial-4/summary.json"
if out=$(/usr/bin/python3 "$script" "$work/bench" 2>&1) || [[ "$out" != *"trial-4/summary.json: Expecting value"* ]]; then
  printf 'a broken summary.json: unexpected output or status:\n%s\n' "$out"
  exit 1
fi
echo "crowd_switches ok"
