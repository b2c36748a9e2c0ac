#!/usr/bin/env bash
# `aerotrack bench --executor slurm` against a real Slurm (issue 25 item 3): starts a single-node cluster
# from Debian's slurm-wlm and munge (scripts/slurm_cluster.sh: slurmctld, slurmd and munged on this
# machine, loopback only), runs a small suite through it -- one cell of the short open-field scenario,
# 2 seeds, swept over 2 values of a key: 4 trials, one array with at most 1 running -- cancels one pending
# trial (scancel), merges (the trial is named as missing), resubmits the missing one, merges again; then
# runs the same suite locally and compares every trial's summary with scripts/compare_trials.py
# (identical apart from wall-clock fields); checks that a partition that does not exist is one line; and
# stops the cluster. Prints its time. Installs slurm-wlm and munge when missing (apt, as root).
# usage: scripts/slurm_test.sh [AEROTRACK]   (default build/bin/aerotrack)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
start=$SECONDS
bin=$(realpath "${1:-build/bin/aerotrack}")
if ! command -v sbatch >/dev/null || ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  echo "slurm_test: installing slurm-wlm and munge"
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi
work=$(mktemp -d /tmp/aerotrack-slurm.XXXXXX)
cluster=$work/cluster
stop_cluster() { scripts/slurm_cluster.sh stop "$cluster" >/dev/null 2>&1 || true; }
trap stop_cluster EXIT
scripts/slurm_cluster.sh start "$cluster" >"$work/cluster.log" 2>&1 || { cat "$work/cluster.log"; exit 1; }
export SLURM_CONF=$cluster/slurm.conf
fail() { echo "slurm_test: FAILED: $*"; exit 1; }

cat >"$work/suite.yaml" <<SUITE
name: slurm-test
seeds: 2
cells:
  - {scenario: $PWD/tests/data/short.yaml, modes: [proposed]}
SUITE
sweep=(--set "planning.goal.tracking_distance_m=2,3")

# Submit held (an extra sbatch option), one trial running at a time, without waiting; cancel the last
# trial while it cannot have started, then release the rest.
"$bin" bench --suite "$work/suite.yaml" --out "$work/slurm" "${sweep[@]}" --executor slurm --jobs 1 \
  --slurm-time 5 --slurm-mem 1024 --slurm-option=--hold --no-wait >"$work/submit.log" 2>&1 ||
  fail "submit: $(tail -3 "$work/submit.log")"
job=$(sed -n 's/^slurm: 4 trials submitted as job \([0-9]*\) .*/\1/p' "$work/submit.log")
[[ -n $job ]] || fail "no job id in: $(cat "$work/submit.log")"
scancel "${job}_3"
scontrol release "$job"
wait_for() {  # wait_for JOB: until Slurm lists it no more
  for _ in $(seq 1 120); do
    [[ -z $(squeue -h -o %F | grep -x "$1" || true) ]] && return
    sleep 1
  done
  fail "job $1 still queued after 120 s"
}
wait_for "$job"
set +e
"$bin" bench merge "$work/slurm" >"$work/merge1.log" 2>&1
status=$?
set -e
[[ $status == 1 ]] || fail "merge with a cancelled trial: exit status $status, expected 1"
grep -q '^  trial 3 (seed 2 of short-own-proposed-keypoints-planning.goal.tracking_distance_m=3): ' "$work/merge1.log" ||
  fail "merge did not name trial 3: $(tail -5 "$work/merge1.log")"
# The plan keeps its sbatch options (--hold too): resubmit without waiting, release, wait, merge.
"$bin" bench merge "$work/slurm" --resubmit-missing --no-wait >"$work/resubmit.log" 2>&1 ||
  fail "resubmit: $(tail -5 "$work/resubmit.log")"
job=$(sed -n 's/^slurm: 1 trials submitted as job \([0-9]*\) .*/\1/p' "$work/resubmit.log")
[[ -n $job ]] || fail "resubmit: $(head -3 "$work/resubmit.log")"
scontrol release "$job"
wait_for "$job"
"$bin" bench merge "$work/slurm" >"$work/merge2.log" 2>&1 || fail "merge after resubmit: $(tail -3 "$work/merge2.log")"
grep -q '^merge: all 4 trials have a result$' "$work/merge2.log" || fail "merge after resubmit: $(tail -3 "$work/merge2.log")"
cp "$work/slurm/suite.json" "$work/suite.first.json"
"$bin" bench merge "$work/slurm" >"$work/merge3.log" 2>&1 || fail "merging again failed"
cmp -s "$work/slurm/suite.json" "$work/suite.first.json" || fail "merging again changed suite.json"
ls "$work/slurm/slurm/logs/"*.log >/dev/null || fail "no Slurm log per trial"

# The same suite on local processes: the same trials.
"$bin" bench --suite "$work/suite.yaml" --out "$work/local" "${sweep[@]}" --jobs 2 >"$work/local.log" 2>&1 ||
  fail "local suite: $(tail -3 "$work/local.log")"
scripts/compare_trials.py "$work/local" "$work/slurm" || fail "Slurm's trials differ from the local ones"

set +e
err=$("$bin" bench --suite "$work/suite.yaml" --out "$work/bad" --executor slurm --slurm-partition nosuch 2>&1 >/dev/null)
set -e
[[ $err == "aerotrack bench: sbatch failed (exit status 1): sbatch: error: invalid partition specified: nosuch" ]] ||
  fail "bad partition: $err"
stop_cluster
trap - EXIT
rm -rf "$work"
echo "slurm_test: passed in $((SECONDS - start)) s (a real single-node Slurm: submit, scancel, merge, resubmit, same as local)"
