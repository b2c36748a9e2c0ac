#!/usr/bin/env bash
# The flight log end to end (issue 24): `sim --mcap` on a short scenario, read back by @mcap/core
# (tools/foxglove/check_mcap.js: summary, indexes, CRCs, every message decoded with its own schema),
# every topic the simulator can fill present; the lockstep trace hash and the flight's results the
# same with and without the log; a replay of a recording logs too, and `export-mcap` turns the
# recording into the same kind of file (a corrupt frame skipped and counted); and a disk that fills mid-run
# (a file size limit) stops the log with a counted error while the flight goes on.
# One line out: "flight log ok: ..." or what is wrong (status 1).
# usage: tests/cli/flight_log.sh AEROTRACK_BINARY SCENARIO_YAML
set -uo pipefail
bin=$1 scenario=$2
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
check=$here/../../tools/foxglove/check_mcap.js
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "flight log: $*"; exit 1; }
[[ -f $(dirname "$check")/node_modules/@mcap/core/package.json ]] || fail "run tools/foxglove/provision.sh first"

"$bin" sim --scenario "$scenario" --out "$work/plain" > "$work/plain.log" 2>&1 || fail "sim failed: $(tail -1 "$work/plain.log")"
"$bin" sim --scenario "$scenario" --out "$work/logged" --mcap "$work/run.mcap" > "$work/logged.log" 2>&1 \
  || fail "sim --mcap failed: $(tail -1 "$work/logged.log")"
grep -q '^flight log .*run.mcap: [1-9][0-9]* messages' "$work/logged.log" || fail "no flight log line: $(tail -1 "$work/logged.log")"
# The flight is the same flight: its trace and everything but the wall-clock figures.
strip() { /usr/bin/python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
for k in ("wall_time_s", "realtime_factor", "tasks", "map", "planning"): d.pop(k, None)
print(json.dumps(d, sort_keys=True))' "$1"; }
[[ $(strip "$work/plain/summary.json") == "$(strip "$work/logged/summary.json")" ]] \
  || fail "the run with --mcap differs from the run without (trace hash or results)"
counts=$(node "$check" "$work/run.mcap" --json) || fail "$counts"
missing=$(/usr/bin/python3 -c '
import json, sys
topics = json.loads(sys.argv[1])["topics"]
want = ["/tf", "/gimbal_camera/calibration", "/gimbal_camera/detections", "/depth_camera/points", "/person/estimate",
        "/person/estimate/values", "/setpoint", "/timing", "/health", "/planning/trajectory", "/planning/plan", "/planning/cycle", "/drone/path",
        "/map/occupied", "/supervisor", "/sim/obstacles", "/sim/truth", "/sim/truth/values"]
print(" ".join(t for t in want if topics.get(t, {}).get("count", 0) == 0))' "$counts")
[[ -z $missing ]] || fail "topics without messages: $missing"
messages=$(/usr/bin/python3 -c 'import json, sys; print(json.loads(sys.argv[1])["messages"])' "$counts")
# Every topic the Foxglove layout shows is one the log has.
unknown=$(/usr/bin/python3 -c '
import json, sys
topics = json.loads(sys.argv[1])["topics"]
layout = json.load(open(sys.argv[2]))
named = set()
for config in layout["configById"].values():
    named.update(config.get("topics", {}))
    mode = config.get("imageMode", {})
    named.update(t for t in (mode.get("imageTopic"), mode.get("calibrationTopic")) if t)
    named.update(mode.get("annotations", {}))
    named.update(p["value"].split(".")[0] for p in config.get("paths", []))
    if "topicPath" in config: named.add(config["topicPath"].split(".")[0])
print(" ".join(sorted(t for t in named if t not in topics)))' "$counts" "$here/../../tools/foxglove/layout.json")
[[ -z $unknown ]] || fail "tools/foxglove/layout.json shows topics the log lacks: $unknown"

# A replay of a recording logs the same way.
"$bin" sim --scenario "$scenario" --out "$work/recorded" --record "$work/rec" > "$work/record.log" 2>&1 || fail "sim --record failed"
"$bin" replay "$work/rec" --mcap "$work/replay.mcap" > "$work/replay.log" 2>&1 || fail "replay --mcap failed: $(tail -1 "$work/replay.log")"
node "$check" "$work/replay.mcap" > /dev/null || fail "replay log: $(node "$check" "$work/replay.mcap")"

# The recording exported: the same file format, read back; a corrupt depth frame is skipped and counted.
first_depth=$(ls "$work/rec/depth_camera/"*.png | head -1)
printf 'not a png' > "$first_depth"
"$bin" export-mcap "$work/rec" --out "$work/export.mcap" > "$work/export.log" 2>&1 || fail "export-mcap failed: $(tail -1 "$work/export.log")"
grep -q 'flight log .*export.mcap: [1-9][0-9]* messages.*(0 bad rows and 1 unreadable frames skipped)' "$work/export.log" \
  || fail "export-mcap did not count the corrupt frame: $(tail -1 "$work/export.log")"
exported=$(node "$check" "$work/export.mcap" --json) || fail "export: $exported"
missing=$(/usr/bin/python3 -c '
import json, sys
topics = json.loads(sys.argv[1])["topics"]
want = ["/tf", "/gimbal_camera/detections", "/depth_camera/points", "/person/estimate", "/planning/trajectory",
        "/drone/path", "/setpoint", "/gimbal/command"]
print(" ".join(t for t in want if topics.get(t, {}).get("count", 0) == 0))' "$exported")
[[ -z $missing ]] || fail "exported topics without messages: $missing"

# A full disk mid-run (the file size limit: EFBIG after the first chunk): the flight ends as usual.
(ulimit -f 400; trap '' XFSZ; "$bin" sim --scenario "$scenario" --out "$work/full" --mcap "$work/full.mcap") > "$work/full.log" 2>&1 \
  || fail "the flight failed with the disk full: $(tail -1 "$work/full.log")"
grep -q 'stopped early, [1-9][0-9]* messages not written: .*File too large' "$work/full.log" \
  || fail "no counted error with the disk full: $(grep 'flight log' "$work/full.log")"
node "$check" "$work/full.mcap" > /dev/null || node "$check" "$work/full.mcap" --cut > /dev/null \
  || fail "the log cut by a full disk does not read: $(node "$check" "$work/full.mcap" --cut)"
echo "flight log ok: $messages messages read back by @mcap/core, trace hash unchanged, replay logged, recording exported, full disk survived"
