#!/usr/bin/env bash
# Recorded times that lie (issue 23 items 3 and 10): a manifest end far past the data, an offset past
# the end, and a recording whose recorder was killed with SIGKILL. Prints one line per check that
# failed, or "hostile replay ok". usage: hostile_replay.sh AEROTRACK SCENARIO_FILE
set -u
bin=$1 scenario=$2
fail() { echo "FAIL: $*"; exit 1; }
rm -rf hr-rec hr-kill hr-out*
"$bin" sim --scenario "$scenario" --out hr-sim --record hr-rec > /dev/null || fail "recording"

# An end_ns an hour past the last record: replayed to the last record, identical, with a note.
sed -i 's/^end_ns: .*/end_ns: 3604000000000/' hr-rec/manifest.yaml
out=$(timeout 60 "$bin" replay hr-rec --compare --out hr-out1 2>&1) || fail "end_ns an hour late: exit $?: $(tail -1 <<<"$out")"
grep -q "the manifest's end_ns lies 3600.0 s past the last record; replaying to the last record" <<<"$out" || fail "no note"
grep -q "^replay identical to the recording$" <<<"$out" || fail "end_ns an hour late: not identical"

# An end_ns of 9e18: refused before replaying anything.
sed -i 's/^end_ns: .*/end_ns: 9000000000000000000/' hr-rec/manifest.yaml
out=$(timeout 60 "$bin" replay hr-rec --out hr-out2 2>&1)
[[ $? -eq 1 ]] || fail "end_ns 9e18: not refused"
grep -q "end_ns: lies more than 21600 s after start_ns" <<<"$out" || fail "end_ns 9e18: $out"
sed -i 's/^end_ns: .*/end_ns: 4000000000/' hr-rec/manifest.yaml

# An offset past the end of the recording.
out=$(timeout 60 "$bin" replay hr-rec --offset-s 1000 --out hr-out3 2>&1)
[[ $? -eq 1 ]] || fail "offset past the end: not refused"
grep -q "offset_s 1000.0 s is past the recording's last record" <<<"$out" || fail "offset: $out"

# A lockstep recording killed with SIGKILL mid-run (no end_ns, streams cut at different records):
# every recorded record replays identically; what the replay produced after them is not a difference.
# Killed once a second of odometry is on disk (a fixed delay raced a slow start on a loaded machine).
"$bin" sim --scenario sharp_turn --out hr-ksim --record hr-kill > /dev/null 2>&1 &
pid=$!
for _ in $(seq 1 600); do  # up to 60 s
  [[ -f hr-kill/odometry.csv && $(wc -l < hr-kill/odometry.csv) -gt 100 ]] && break
  sleep 0.1
done
kill -KILL "$pid"
wait "$pid" 2> /dev/null
grep -q "^end_ns" hr-kill/manifest.yaml && fail "the killed recording has an end"
out=$(timeout 120 "$bin" replay hr-kill --compare --out hr-out4 2>&1) || fail "killed recording: exit $?: $(tail -1 <<<"$out")"
grep -q "^replay identical to the recording$" <<<"$out" || fail "killed recording: not identical"
echo "hostile replay ok"
