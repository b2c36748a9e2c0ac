#!/usr/bin/env bash
# Runs `aerotrack run` the way systemd runs the service (tools/systemd/aerotrack.service: Type=notify,
# WatchdogSec): a listener stands in for systemd's notification socket, and the run must send
# READY=1 first, then WATCHDOG=1 about every half timeout, then STOPPING=1.
# usage: systemd_notify.sh AEROTRACK CONFIG
set -euo pipefail
bin=$1 config=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
/usr/bin/python3 - "$dir/notify" > "$dir/received" <<'PY' &
import socket, sys
s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
s.bind(sys.argv[1])
s.settimeout(30)
while True:
    m = s.recv(4096).decode()
    print(m.replace("\n", "|"), flush=True)
    if m.startswith("STOPPING=1"):
        break
PY
listener=$!
for _ in $(seq 1 100); do [[ -S "$dir/notify" ]] && break; sleep 0.05; done
NOTIFY_SOCKET="$dir/notify" WATCHDOG_USEC=400000 "$bin" run --config "$config" --duration-s 2 > /dev/null 2>&1
wait "$listener"
first=$(head -n 1 "$dir/received")
pings=$(grep -c '^WATCHDOG=1$' "$dir/received" || true)
last=$(tail -n 1 "$dir/received")
# 2 s at one ping per 0.2 s: about 10; at least half of them, or the watchdog would fire.
if [[ "$first" == READY=1* && "$pings" -ge 5 && "$last" == "STOPPING=1" ]]; then
  echo "systemd notify: READY=1, $pings watchdog pings, STOPPING=1"
else
  echo "systemd notify: unexpected sequence: $(tr '\n' ' ' < "$dir/received")"
  exit 1
fi
