#!/usr/bin/env bash
# Runs a command and checks its exit status and that its output (stdout+stderr) matches a regex.
# usage: expect.sh EXPECTED_STATUS REGEX COMMAND [ARGS...]   (EXPECT_TIMEOUT_S: limit, default 60 s)
set -u
expected=$1 pattern=$2
shift 2
output=$(timeout "${EXPECT_TIMEOUT_S:-60}" "$@" 2>&1 </dev/null)
status=$?
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
