#!/usr/bin/env bash
# Starts the given command, sends it SIGTERM after half a second, and exits with its status.
# The command must stop in order and flush its statistics (checked by the caller's regex).
"$@" &
pid=$!
sleep 0.5
kill -TERM "$pid"
wait "$pid"
