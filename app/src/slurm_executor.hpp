// `aerotrack bench --executor slurm` (issue 25 item 2): a plan's trials as Slurm job arrays. One
// array task runs one trial through the plan's run_trial.sh; the binary, the configs and the results
// folder are on a filesystem every node shares (docs/scale-out.md). Files, under DIR/slurm/:
//   array.sh                 the batch script (the trial index = AEROTRACK_TRIAL_BASE + the task id)
//   jobs.txt                 one line per submitted array: "JOBID BASE INDEX,INDEX,..."
//   logs/jobJ-taskT.log      Slurm's log of each array task (a trial's own output is in its log.txt)
// An array holds at most the cluster's MaxArraySize task ids, so a large plan is several arrays, each
// starting after the one before (afterany): the concurrency limit holds across them.
#pragma once

#include <atomic>
#include <map>
#include <string>
#include <vector>

#include "aerotrack/rt/expected.hpp"
#include "trial_plan.hpp"

namespace aerotrack::app {

/// "0-3,7,9-10" for sorted, distinct numbers.
std::string compressIndices(const std::vector<std::size_t>& indices);

/// Splits sorted trial indices into arrays: each a base (its first index) and task ids (index - base)
/// below max_array_size.
std::vector<std::pair<std::size_t, std::vector<std::size_t>>> splitIntoArrays(const std::vector<std::size_t>& indices,
                                                                              std::size_t max_array_size);

/// Submits the trials `indices` (sorted) of the plan with sbatch, as the plan's slurm settings say.
/// Returns the job ids. One-line errors: sbatch missing or failing (its own message: a partition that
/// does not exist, a limit refused), an unreadable answer.
rt::Expected<std::vector<std::string>> submitToSlurm(const TrialPlan& plan, const std::vector<std::size_t>& indices);

/// Waits until none of the jobs is in squeue, printing how many of the submitted trials (`indices`)
/// have finished as it changes. Returns early when `stop` is set (the jobs run on). Error if squeue keeps
/// failing (the controller is gone).
rt::Status waitForSlurm(const TrialPlan& plan, const std::vector<std::string>& jobs,
                        const std::vector<std::size_t>& indices, const std::atomic<bool>& stop);

/// The Slurm log of each trial's latest array task, by trial index (from DIR/slurm/jobs.txt).
std::map<std::size_t, std::string> slurmLogs(const TrialPlan& plan);

}  // namespace aerotrack::app
