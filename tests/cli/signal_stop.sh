#!/usr/bin/env bash
# Starts the given command, sends it SIGTERM once it is running, and exits with its status.
# The command must stop in order and flush its statistics (checked by the caller's regex).
# "Running" is when the process blocks SIGTERM (its signal watcher is installed: SigBlk bit 14 in
# /proc/PID/status), then half a second more; a fixed delay alone raced a slow start (sanitizer
# builds on a loaded machine), which the default action of SIGTERM then killed.
"$@" &
pid=$!
for _ in $(seq 1 400); do  # up to 20 s
  mask=$(awk '/^SigBlk:/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
  [[ -n "$mask" ]] && (( (16#$mask >> 14) & 1 )) && break
  sleep 0.05
done
sleep 0.5
kill -TERM "$pid"
wait "$pid"
