#!/usr/bin/env bash
# `aerotrack sim --mode truth_flight` is a paired measure: the drone and the gimbal fly from the truth, so
# two configurations of the estimator see the same flight. Runs the crowd (keypoint camera, seed 1) twice,
# the second with a different measurement noise, and checks that the flight tasks are gone, that the
# estimates differ, and that everything the drone's path decides (distances, clearance, visibility) does not.
# usage: truth_flight.sh AEROTRACK OUT_DIR
# Prints "truth_flight ok: <the fields compared>" when all holds.
set -u
bin=$1 out=$2
rm -rf "$out"
"$bin" sim --scenario crowd --seed 1 --mode truth_flight --out "$out/a" >/dev/null || exit $?
"$bin" sim --scenario crowd --seed 1 --mode truth_flight --set estimation.measurement_std_per_m=0.08 \
  --out "$out/b" >/dev/null || exit $?
exec /usr/bin/python3 - "$out/a/summary.json" "$out/b/summary.json" <<'PY'
import json
import sys

a, b = (json.load(open(path)) for path in sys.argv[1:3])
for run in (a, b):
    tasks = set(run["tasks"])
    if "baseline_follow" not in tasks or tasks & {"planning", "gimbal_control", "supervisor", "trajectory_server"}:
        sys.exit(f"tasks: expected baseline_follow in place of the flight tasks, got {sorted(tasks)}")
    if not run["controller"].startswith("truth_flight"):
        sys.exit(f"controller: {run['controller']}")
if a["estimation"]["position_error_mean_m"] == b["estimation"]["position_error_mean_m"]:
    sys.exit("the two estimators gave the same estimates: the comparison tests nothing")
fields = ["distance_mean_m", "distance_max_m", "final_distance_m", "min_clearance_m", "visible_ratio"]
for field in fields:
    if a[field] != b[field]:
        sys.exit(f"{field}: {a[field]} against {b[field]}: the estimator moved the drone or the gimbal")
print("truth_flight ok: " + ", ".join(fields))
PY
