#!/usr/bin/env bash
# The live view end to end (issue 24 items 2-3): `sim --realtime --live PORT` watched by
# @foxglove/ws-protocol's client (tools/foxglove/check_live.js: server info, advertised channels, every
# message decoded with its schema), the run's summary line counting the client; no listening socket
# without --live; and the bad cases as one-line errors: a port in use, a bad address, --live without
# --realtime. One line out: "live view ok: ..." or what is wrong (status 1).
# usage: tests/cli/live_view.sh AEROTRACK_BINARY SCENARIO_YAML
set -uo pipefail
bin=$1 scenario=$2
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
check=$here/../../tools/foxglove/check_live.js
work=$(mktemp -d)
pids=()
trap 'kill "${pids[@]}" 2>/dev/null; rm -rf "$work"' EXIT
fail() { echo "live view: $*"; exit 1; }
[[ -f $(dirname "$check")/node_modules/@foxglove/ws-protocol/package.json ]] || fail "run tools/foxglove/provision.sh first"
free_port() { /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
listening() { ss -Hltnp 2>/dev/null | grep -c "pid=$1,"; }

# Without --live: no listening socket.
"$bin" sim --scenario "$scenario" --realtime --out "$work/quiet" > "$work/quiet.log" 2>&1 &
pid=$!
pids+=("$pid")
sleep 1.5
[[ $(listening "$pid") -eq 0 ]] || fail "sim --realtime without --live listens: $(ss -Hltnp | grep "pid=$pid,")"
wait "$pid" || fail "sim --realtime failed: $(tail -1 "$work/quiet.log")"

port=$(free_port)
"$bin" sim --scenario "$scenario" --realtime --live "$port" --out "$work/live" > "$work/live.log" 2>&1 &
pid=$!
pids+=("$pid")
# On the loopback only, checked while the run is on (the watch below lasts until the run ends).
for _ in $(seq 100); do
  [[ $(ss -Hltn "sport = :$port" | grep -c .) -ge 1 ]] && break
  sleep 0.1
done
[[ $(ss -Hltn "sport = :$port" | grep -c .) -eq 1 && $(ss -Hltn "sport = :$port" | grep -c '127.0.0.1') -eq 1 ]] \
  || fail "--live $port does not listen on the loopback only: $(ss -Hltn "sport = :$port")"
watched=$(node "$check" "127.0.0.1:$port" 20 /tf /person/estimate /supervisor /gimbal_camera/detections /planning/plan /setpoint) \
  || fail "$watched"
wait "$pid" || fail "sim --live failed: $(tail -1 "$work/live.log")"
grep -q "^live view on ws://127.0.0.1:$port: 1 clients, [1-9][0-9]* messages sent" "$work/live.log" \
  || fail "no live view line: $(grep 'live view' "$work/live.log")"

# A port in use, a bad address, no --realtime: one line each, exit status 1. A port of its own: the run above
# closed its connection first, so its port may wait in TIME_WAIT.
port=$(free_port)
/usr/bin/python3 -c 'import socket, sys, time; s = socket.socket(); s.bind(("127.0.0.1", int(sys.argv[1]))); s.listen(); time.sleep(20)' "$port" &
pids+=($!)
sleep 0.3
expect_error() {
  local pattern=$1
  shift
  local out status
  out=$("$@" 2>&1)
  status=$?
  [[ $status -eq 1 && $(wc -l <<<"$out") -eq 1 ]] && grep -Eq -- "$pattern" <<<"$out" || fail "expected one line /$pattern/, status 1; got $status: $out"
}
expect_error "^aerotrack sim: --live: 127.0.0.1:$port: cannot listen: .*" "$bin" sim --scenario "$scenario" --realtime --live "$port" --out "$work/busy"
expect_error "^aerotrack sim: --live: 'x:y': expected PORT or HOST:PORT" "$bin" sim --scenario "$scenario" --realtime --live x:y --out "$work/bad"
expect_error "^aerotrack sim: --live: needs --realtime" "$bin" sim --scenario "$scenario" --live "$port" --out "$work/lockstep"
echo "live view ok: $watched"
