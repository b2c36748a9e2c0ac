// The trials of a bench or a suite, written down before any runs (issue 25): DIR/plan.json (what
// every trial is and what the merge needs), DIR/trials.txt (line i + 1: the shell command of trial i)
// and DIR/run_trial.sh INDEX (runs one line). Any batch engine runs the same trials from these: local
// processes (`bench`), a Slurm job array (`bench --executor slurm`), GNU parallel over ssh, a
// Kubernetes Indexed Job (docs/scale-out.md). Each trial is a pure function of (scenario, seed,
// config, --set) that writes one folder; `bench merge DIR` reads the folders, whatever ran them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "aerotrack/rt/expected.hpp"
#include "suite.hpp"
#include "sweep.hpp"

namespace aerotrack::app {

/// The Slurm settings of a plan (`bench --executor slurm`), kept for `merge --resubmit-missing`.
struct SlurmSettings {
  std::string partition;             ///< Empty: the cluster's default partition.
  int time_limit_min = 30;           ///< Per array task (one trial).
  int memory_mb = 2048;              ///< Per array task.
  int max_running = 16;              ///< The array's concurrency limit (--array=...%N).
  std::vector<std::string> options;  ///< More sbatch options, as given (--account=..., --qos=...).
};

struct PlannedTrial {
  std::size_t cell = 0;  ///< Index into the plan's suite.cells.
  std::int64_t seed = 1;
  std::string dir;  ///< Absolute.
};

struct TrialPlan {
  std::string kind;                      ///< "bench" (one scenario, DIR/bench.json per cell) or "suite".
  std::string out_dir;                   ///< Absolute.
  std::string binary;                    ///< The aerotrack binary every trial runs (absolute; on a shared filesystem).
  SuiteSpec suite;                       ///< The cells (a bench is a one-scenario matrix), sweep applied.
  std::vector<std::string> cell_errors;  ///< Per cell: why it cannot run, or empty.
  std::vector<SweepKey> sweep;
  nlohmann::json bench = nlohmann::json::object();  ///< kind bench: the options as given, for bench.json.
  std::optional<SlurmSettings> slurm;
  std::vector<PlannedTrial> trials;  ///< Every trial of every cell without an error; index = trial index.
};

/// Fills plan.trials from plan.suite (seeds first_seed..last_seed of each cell, in cell order).
void planTrials(TrialPlan& plan);

/// The full command of a trial: binary, "sim", its options.
std::vector<std::string> trialCommand(const TrialPlan& plan, std::size_t index);

/// 'text' quoted for a POSIX shell.
std::string shellQuote(const std::string& text);

/// Writes DIR/plan.json (replacing it atomically), DIR/trials.txt and DIR/run_trial.sh.
rt::Status writePlan(const TrialPlan& plan);

/// Reads DIR/plan.json. One-line error naming the file if it is missing, cut off or not a plan.
rt::Expected<TrialPlan> readPlan(const std::string& dir);

/// Whether a trial is done, and if not, why (for the merge's list of missing trials).
struct TrialState {
  bool complete = false;
  std::string reason;  ///< Empty when complete.
};

/// Looks at a trial's folder (summary.json, log.txt) and, when given, the batch engine's log of it.
TrialState trialState(const std::string& trial_dir, const std::string& engine_log);

}  // namespace aerotrack::app
