#!/usr/bin/env bash
# Runs a command and checks its exit status and that its output (stdout+stderr) matches a regex.
# usage: expect.sh EXPECTED_STATUS REGEX COMMAND [ARGS...]   (EXPECT_TIMEOUT_S: limit, default 180 s)
set -u
expected=$1 pattern=$2
shift 2
# The command runs in a process group of its own, its output in a file rather than a pipe: whatever
# it leaves behind (a child stuck past the limit, as a hung `sim` under signal_stop.sh once was) is
# killed with the group, and neither holds this script up nor runs on, slowing every later test.
out=$(mktemp)
trap 'rm -f "$out"' EXIT
setsid timeout -k 10 "${EXPECT_TIMEOUT_S:-180}" "$@" > "$out" 2>&1 < /dev/null &
group=$!
wait "$group"
status=$?
kill -KILL -- "-$group" 2> /dev/null || true
output=$(cat "$out")
if [[ $status -ne $expected ]]; then
  printf 'expected exit status %s, got %s\noutput:\n%s\n' "$expected" "$status" "$output"
  exit 1
fi
if ! grep -Eq -- "$pattern" <<<"$output"; then
  printf 'output does not match /%s/:\n%s\n' "$pattern" "$output"
  exit 1
fi
# Errors are one line: a command failing with status 1 or 2 prints exactly one line. (Status 3,
# `replay --compare` finding differences, is a result with its report.)
if [[ ($expected -eq 1 || $expected -eq 2) && $(wc -l <<<"$output") -ne 1 ]]; then
  printf 'expected a one-line error, got:\n%s\n' "$output"
  exit 1
fi
exit 0
