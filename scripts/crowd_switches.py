#!/usr/bin/python3
"""Sorts a bench or suite folder's identity switches by kind (issue 22, item 2; docs/benchmarks.md, "The kept
track looked at, and the crowd's worlds sorted"). Reads every trial's summary.json under FOLDER and prints:
  - the trials without a switch, with the Wilson 95 % interval;
  - the trials with a switch, by their first switch: the look-alike (who wears the person's clothes) or another
    bystander, and how far apart the two stood then (<= 0.5 m: two bodies of 0.25 m overlapping; 0.5-1.0 m;
    farther);
  - the trials by the world: the look-alike's closest approach to the person (<= 0.5 m or farther), and how many
    of each kept the right person.
The fields are summary.json's `identity_switch_events` and `closest_approach_m` (docs/command-line.md).
KEYPOINT_FOLDER, if given, supplies closest_approach_m for trials that lack it (the walkers do not react to the
drone: a seed's world is the same in either camera mode), matched by seed.
--against OTHER compares FOLDER with another bench seed by seed (the pair is meaningful where the two saw the
same flights: `--mode truth_flight`, docs/modules/closed-loop.md): the seeds that only one of them kept free of
switches, and the exact two-sided McNemar test on those discordant seeds (a binomial test at one half), which a
comparison of two rates cannot give.
usage: crowd_switches.py FOLDER [KEYPOINT_FOLDER] [--against OTHER]
"""
import json
import math
import os
import sys

OVERLAP_M = 0.5  # two bodies of 0.25 m radius (the simulator's kPersonBodyRadiusM) touch
NEAR_M = 1.0


def wilson(k, n, z=1.96):
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return (c - h, c + h)


def trials(root):
    """seed -> summary of every summary.json under root; exits with one line on a bad folder or file."""
    if not os.path.isdir(root):
        sys.exit(f"crowd_switches.py: {root}: not a folder")
    found = {}
    for folder, _, files in os.walk(root):
        if "summary.json" not in files:
            continue
        path = os.path.join(folder, "summary.json")
        try:
            with open(path, encoding="utf-8") as f:
                s = json.load(f)
        except (OSError, ValueError) as e:
            sys.exit(f"crowd_switches.py: {path}: {e}")
        if not isinstance(s, dict) or not isinstance(s.get("seed"), int):
            sys.exit(f"crowd_switches.py: {path}: no integer 'seed'")
        found[s["seed"]] = s
    if not found:
        sys.exit(f"crowd_switches.py: {root}: no summary.json under it")
    return found


def kind(event):
    who = "the look-alike" if event.get("look_alike") else "another bystander"
    apart = float(event.get("separation_m", math.inf))
    reach = (f"<= {OVERLAP_M} m apart" if apart <= OVERLAP_M else
             f"{OVERLAP_M}-{NEAR_M} m apart" if apart <= NEAR_M else f"> {NEAR_M} m apart")
    return f"{who}, {reach}"


def mcnemar_exact(only_a, only_b):
    """Two-sided exact McNemar p-value: twice the smaller binomial tail at one half, at most 1."""
    n = only_a + only_b
    if n == 0:
        return 1.0
    tail = sum(math.comb(n, i) for i in range(min(only_a, only_b) + 1)) / 2 ** n
    return min(1.0, 2 * tail)


def paired(a_root, a, b_root, b):
    shared = sorted(seed for seed in set(a) & set(b)
                    if isinstance(a[seed].get("identity_switches"), int)
                    and isinstance(b[seed].get("identity_switches"), int))
    if not shared:
        sys.exit(f"crowd_switches.py: {a_root} and {b_root} share no seed that reports identity_switches")
    clean = lambda s: s["identity_switches"] == 0  # noqa: E731
    only_a = [seed for seed in shared if clean(a[seed]) and not clean(b[seed])]
    only_b = [seed for seed in shared if clean(b[seed]) and not clean(a[seed])]
    print(f"paired on {len(shared)} seeds: without a switch {sum(clean(a[x]) for x in shared)} here, "
          f"{sum(clean(b[x]) for x in shared)} against; only here: {len(only_a)} (seeds "
          f"{', '.join(map(str, only_a)) or '-'}), only against: {len(only_b)} (seeds "
          f"{', '.join(map(str, only_b)) or '-'}); exact McNemar p = {mcnemar_exact(len(only_a), len(only_b)):.3f}")


def main(argv):
    against = None
    if "--against" in argv:
        k = argv.index("--against")
        if k + 1 >= len(argv):
            sys.exit("usage: crowd_switches.py FOLDER [KEYPOINT_FOLDER] [--against OTHER]")
        against = argv[k + 1]
        argv = argv[:k] + argv[k + 2:]
    if len(argv) not in (2, 3):
        sys.exit("usage: crowd_switches.py FOLDER [KEYPOINT_FOLDER] [--against OTHER]")
    image = trials(argv[1])
    worlds = trials(argv[2]) if len(argv) == 3 else {}
    with_identity = {seed: s for seed, s in image.items() if isinstance(s.get("identity_switches"), int)}
    if not with_identity:
        sys.exit(f"crowd_switches.py: {argv[1]}: no trial reports identity_switches")
    n = len(with_identity)
    clean = sum(1 for s in with_identity.values() if s["identity_switches"] == 0)
    low, high = wilson(clean, n)
    print(f"{clean}/{n} trials without an identity switch, Wilson 95 % [{low:.2f}, {high:.2f}]")

    kinds = {}
    for seed, s in sorted(with_identity.items()):
        if s["identity_switches"] == 0:
            continue
        events = s.get("identity_switch_events")
        label = kind(events[0]) if events else "not described (a summary.json before identity_switch_events)"
        kinds.setdefault(label, []).append(seed)
    for label, seeds in sorted(kinds.items()):
        print(f"  first switch to or from {label}: {len(seeds)} trials (seeds {', '.join(map(str, seeds))})")

    groups = {f"<= {OVERLAP_M} m": [], f"> {OVERLAP_M} m": [], "unknown": []}
    for seed, s in sorted(with_identity.items()):
        approach = s.get("closest_approach_m") or (worlds.get(seed) or {}).get("closest_approach_m") or {}
        closest = approach.get("look_alike")
        if not isinstance(closest, (int, float)):
            groups["unknown"].append(s)
        else:
            groups[f"<= {OVERLAP_M} m" if closest <= OVERLAP_M else f"> {OVERLAP_M} m"].append(s)
    for label, group in groups.items():
        if not group:
            continue
        k = sum(1 for s in group if s["identity_switches"] == 0)
        low, high = wilson(k, len(group))
        print(f"  the look-alike's closest approach {label}: {k}/{len(group)} without a switch "
              f"[{low:.2f}, {high:.2f}]")
    if against is not None:
        paired(argv[1], image, against, trials(against))


if __name__ == "__main__":
    main(sys.argv)
