#!/usr/bin/env bash
# `aerotrack bench --executor slurm` and `bench merge` against a stand-in Slurm (fake_slurm/: sbatch
# runs the array's tasks at once; MaxArraySize 3), on the short open-field scenario swept over one
# key: 2 values x 2 seeds = 4 trials, so two job arrays, the second after the first. Then a trial
# killed by its time limit (its result removed, Slurm's line in its log): the merge names it and exits
# 1; --resubmit-missing runs only that one and the merge is whole again. Then the bad inputs: a
# partition that does not exist, a second array refused after the first went in, no sbatch on PATH.
# usage: bench_slurm.sh AEROTRACK SCENARIO.yaml OUT_DIR
# Prints "slurm executor: 2 arrays, 1 resubmitted, errors named" when all holds.
set -u
bin=$1 scenario=$2 out=$3
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$out" "$out.state"
mkdir -p "$out.state"
export FAKE_SLURM_DIR=$out.state
fail() { echo "$*"; exit 1; }
PATH=$here/fake_slurm:$PATH "$bin" bench --scenario "$scenario" --trials 2 --out "$out" --executor slurm --jobs 2 \
  --slurm-partition debug --slurm-time 5 --slurm-mem 512 --slurm-option=--qos=low \
  --set planning.goal.tracking_distance_m=2,3 >"$out.log" 2>&1 || fail "bench exited $?: $(tail -3 "$out.log")"
[[ $(wc -l <"$out.state/sbatch.args") == 2 ]] || fail "expected 2 sbatch calls: $(cat "$out.state/sbatch.args")"
grep -q -- '--array=0-2%2 .*--time=5 --mem=512 .*--partition=debug --qos=low ' <(head -1 "$out.state/sbatch.args") ||
  fail "first array: $(head -1 "$out.state/sbatch.args")"
grep -q -- '--array=0%2 .*AEROTRACK_TRIAL_BASE=3 .*--dependency=afterany:101 ' <(tail -1 "$out.state/sbatch.args") ||
  fail "second array: $(tail -1 "$out.state/sbatch.args")"
for d in planning.goal.tracking_distance_m=2 planning.goal.tracking_distance_m=3; do
  [[ -s $out/$d/bench.json && -s $out/$d/trial-2/summary.json ]] || fail "no $out/$d/bench.json"
done
[[ -s $out/sweep-planning.goal.tracking_distance_m.png && -s $out/report.md ]] || fail "no sweep plot or report"
grep -q '"planning.goal.tracking_distance_m": "3"' "$out/planning.goal.tracking_distance_m=3/trial-1/summary.json" ||
  fail "the trial's summary lacks the value it ran with"

# Trial 3 (the second value's seed 2, the second array's task 0) killed by its time limit.
victim=$out/planning.goal.tracking_distance_m=3/trial-2
rm "$victim/summary.json"
echo "slurmstepd: error: *** JOB 102 ON node CANCELLED AT 2026-11-27T10:00:00 DUE TO TIME LIMIT ***" \
  >>"$out/slurm/logs/job102-task0.log"
"$bin" bench merge "$out" >"$out.merge" 2>&1
[[ $? == 1 ]] || fail "merge with a trial missing: expected exit status 1"
grep -q "^  trial 3 (seed 2 of planning.goal.tracking_distance_m=3): killed by Slurm: time limit" "$out.merge" ||
  fail "merge: $(cat "$out.merge")"
grep -q "^3 planning.goal.tracking_distance_m=3 2 $victim: killed by Slurm: time limit" "$out/missing.txt" ||
  fail "missing.txt: $(cat "$out/missing.txt")"
PATH=$here/fake_slurm:$PATH "$bin" bench merge "$out" --resubmit-missing >"$out.resubmit" 2>&1 ||
  fail "resubmit exited $?: $(tail -3 "$out.resubmit")"
grep -q -- '--array=0%2 .*AEROTRACK_TRIAL_BASE=3 ' <(tail -1 "$out.state/sbatch.args") ||
  fail "resubmitted: $(tail -1 "$out.state/sbatch.args")"
[[ $(wc -l <"$out.state/sbatch.args") == 3 && -s $victim/summary.json && ! -e $out/missing.txt ]] ||
  fail "resubmission did not complete the merge"
grep -q "^merge: all 4 trials have a result$" "$out.resubmit" || fail "resubmit: $(tail -3 "$out.resubmit")"

err=$(PATH=$here/fake_slurm:$PATH "$bin" bench --scenario "$scenario" --trials 1 --out "$out-bad" --executor slurm \
  --slurm-partition nosuch 2>&1 >/dev/null)
[[ $err == "aerotrack bench: sbatch failed (exit status 1): sbatch: error: invalid partition specified: nosuch" ]] ||
  fail "bad partition: $err"
err=$(FAKE_SLURM_REFUSE_BASE=3 PATH=$here/fake_slurm:$PATH "$bin" bench --scenario "$scenario" --trials 2 \
  --out "$out-bad" --executor slurm --set planning.goal.tracking_distance_m=2,3 2>&1 >/dev/null)
[[ $err =~ ^"aerotrack bench: sbatch failed (exit status 1): sbatch: error: Batch job submission failed: Job violates accounting/QOS policy (already submitted: job "[0-9]+"; scancel them, or merge what they finish)"$ ]] ||
  fail "a refused second array: $err"
mkdir -p "$out.state/empty"
err=$(PATH=$out.state/empty "$bin" bench --scenario "$scenario" --trials 1 --out "$out-bad" --executor slurm 2>&1 >/dev/null)
[[ $err == "aerotrack bench: sbatch: not found on PATH (is Slurm's client installed? or use --executor local)" ]] ||
  fail "no sbatch: $err"
echo "slurm executor: 2 arrays, 1 resubmitted, errors named"
