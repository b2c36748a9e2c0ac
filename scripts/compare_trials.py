#!/usr/bin/python3
"""Compares the per-trial summaries of two bench or suite folders (issue 25 item 3): every
trial's summary.json under A must exist under B at the same relative path and be identical, apart
from the wall-clock fields (the run's wall time and real-time factor, the tasks' and modules' timing
statistics: every key that ends in _ms or contains _ms_, `tasks`, `wall_time_s`, `realtime_factor`).
A trial is a pure function of (scenario, seed, config, --set), so whoever ran it, the rest is the same,
the lockstep trace hash included.
usage: compare_trials.py A B     prints "N trials identical apart from wall-clock fields" or the differences
"""
import json
import os
import re
import sys

WALL_CLOCK = re.compile(r"(_ms$|_ms_|^tasks$|^wall_time_s$|^realtime_factor$)")


def strip(value):
    if isinstance(value, dict):
        return {k: strip(v) for k, v in value.items() if not WALL_CLOCK.search(k)}
    if isinstance(value, list):
        return [strip(v) for v in value]
    return value


def differences(a, b, path=""):
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            yield from differences(a.get(key), b.get(key), f"{path}.{key}")
    elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (u, v) in enumerate(zip(a, b)):
            yield from differences(u, v, f"{path}[{i}]")
    elif a != b:
        yield f"{path}: {a!r} != {b!r}"


def summaries(root):
    found = {}
    for folder, _, files in os.walk(root):
        if "summary.json" in files:
            found[os.path.relpath(folder, root)] = os.path.join(folder, "summary.json")
    return found


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: compare_trials.py A B")
    a, b = summaries(sys.argv[1]), summaries(sys.argv[2])
    problems = [f"{t}: only in {sys.argv[1]}" for t in sorted(set(a) - set(b))]
    problems += [f"{t}: only in {sys.argv[2]}" for t in sorted(set(b) - set(a))]
    for trial in sorted(set(a) & set(b)):
        with open(a[trial]) as fa, open(b[trial]) as fb:
            for d in differences(strip(json.load(fa)), strip(json.load(fb))):
                problems.append(f"{trial}: {d}")
    if not a:
        problems.append(f"no summary.json under {sys.argv[1]}")
    if problems:
        print("\n".join(problems[:40]))
        sys.exit(1)
    print(f"{len(a)} trials identical apart from wall-clock fields")


if __name__ == "__main__":
    main()
