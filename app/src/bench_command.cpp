// `aerotrack bench`: seeds of a scenario (--scenario NAME|FILE --trials N), or a suite's matrix
// (--suite FILE, resumable: trials with a complete summary.json are kept), optionally swept over config
// keys (--set KEY=V1,V2,...), as separate `aerotrack sim` processes. The trials are written down first
// (trial_plan.hpp: DIR/plan.json, trials.txt, run_trial.sh); then an executor runs them -- local
// processes, J at a time (--executor local, the default), or Slurm job arrays (--executor slurm,
// slurm_executor.hpp) -- and the merge step (bench_merge.hpp) reads their folders and writes the
// reports. `aerotrack bench merge DIR [--resubmit-missing] [--no-wait]` runs the merge alone, after a
// `--no-wait` submission or an engine of one's own (DESIGN.md, "Scale beyond one machine").
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include "app_config.hpp"
#include "bench_merge.hpp"
#include "commands.hpp"
#include "paths.hpp"
#include "signals.hpp"
#include "slurm_executor.hpp"
#include "suite.hpp"
#include "trial_plan.hpp"

namespace aerotrack::app {
namespace {

/// Starts `self sim ARGS...` with its output in dir/log.txt; returns the pid or -1.
pid_t launchTrial(const std::string& self, std::vector<std::string> argv, const std::string& dir) {
  argv.insert(argv.begin(), {self, "sim"});
  const std::string log = dir + "/log.txt";
  const pid_t pid = fork();
  if (pid != 0) return pid;
  // Child: only async-signal-safe work until exec.
  FILE* out = std::freopen(log.c_str(), "w", stdout);
  if (out == nullptr || dup2(fileno(stdout), fileno(stderr)) < 0) _exit(127);
  sigset_t none;
  sigemptyset(&none);
  pthread_sigmask(SIG_SETMASK, &none, nullptr);  // the parent's watcher blocked SIGINT/SIGTERM
  std::vector<char*> raw;
  raw.reserve(argv.size() + 1);
  for (std::string& a : argv) raw.push_back(a.data());
  raw.push_back(nullptr);
  execv(self.c_str(), raw.data());
  _exit(127);
}

/// One trial: the `sim` options and its result folder.
struct TrialJob {
  std::vector<std::string> args;
  std::string dir;
};

/// Runs the jobs, `jobs` at a time, until done or `stop` (then the running ones get SIGTERM). Returns
/// each started job's exit status by index (128 + signal when killed); false if a process could
/// not be started or a folder created (`error` says which).
bool runTrials(const std::string& self, const std::vector<TrialJob>& trials, std::int64_t jobs,
               const std::atomic<bool>& stop, std::map<std::size_t, int>& exit_status, std::string& error) {
  std::map<pid_t, std::size_t> running;
  std::size_t next = 0;
  bool told_to_stop = false;
  while ((next < trials.size() && !stop.load()) || !running.empty()) {
    while (!stop.load() && next < trials.size() && static_cast<std::int64_t>(running.size()) < jobs) {
      std::error_code ec;
      std::filesystem::create_directories(trials[next].dir, ec);
      if (ec) {
        error = trials[next].dir + ": cannot create directory: " + ec.message();
        return false;
      }
      // The last run's result must not stand for this one if this one fails.
      std::filesystem::remove(trials[next].dir + "/summary.json", ec);
      const pid_t pid = launchTrial(self, trials[next].args, trials[next].dir);
      if (pid < 0) {
        error = "cannot start a trial process";
        return false;
      }
      running[pid] = next++;
    }
    // Poll, so that a stop request reaches the running trials at once rather than when the next one
    // ends (an image-mode trial runs about as long as it simulates). Each trial is told once.
    int status = 0;
    const pid_t done = waitpid(-1, &status, WNOHANG);
    if (done < 0) break;
    if (stop.load() && !told_to_stop) {
      for (const auto& [pid, index] : running) kill(pid, SIGTERM);
      told_to_stop = true;
    }
    if (done == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    exit_status[running[done]] = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    running.erase(done);
  }
  return true;
}

constexpr std::size_t kMaxPlanCells = 10000;
constexpr std::size_t kMaxPlanTrials = 100000;

/// A path as every node sees it: absolute. A scenario name (no '/', no .yaml) stays a name.
std::string absolutePath(const std::string& path) {
  return std::filesystem::absolute(path).lexically_normal().string();
}

std::string absoluteScenario(const std::string& scenario) {
  return resolveScenario(scenario) == scenario ? absolutePath(scenario) : scenario;
}

/// The cells of `bench --scenario`: one, or one per sweep point.
rt::Expected<SuiteSpec> benchCells(const ParsedArgs& args) {
  if (!args.has("scenario") || !args.has("trials"))
    return rt::Error{"needs --scenario NAME|FILE and --trials N, or --suite FILE"};
  SuiteCell cell;
  cell.scenario = absoluteScenario(args.values.at("scenario"));
  cell.mode = args.valueOr("mode", "proposed");
  if (const std::string bad = badModeError(cell.mode); !bad.empty()) return rt::Error{bad};
  cell.camera = args.valueOr("camera", "");
  if (!cell.camera.empty() && cell.camera != "keypoints" && cell.camera != "image")
    return rt::Error{"--camera: expected keypoints or image, got '" + cell.camera + "'"};
  const auto trials = parseInt("trials", args.values.at("trials"), 1, 100000);
  if (!trials) return trials.error();
  if (args.has("speed")) {
    const auto s = parseDouble("speed", args.values.at("speed"), 0.05, 20.0);
    if (!s) return s.error();
    cell.speed_mps = *s;
  }
  if (args.has("config")) cell.config = absolutePath(args.values.at("config"));
  SuiteSpec suite;
  suite.name = std::filesystem::path(args.values.at("scenario")).stem().string();
  suite.source = "aerotrack bench --scenario " + args.values.at("scenario");
  suite.first_seed = 1;
  suite.last_seed = *trials;
  suite.cells.push_back(cell);
  return suite;
}

/// Checks every sweep point of every config the plan uses with the config's own parser, before a
/// trial starts: a misspelt key or a value out of range is one line here, not N failed trials.
rt::Status checkSweep(const SuiteSpec& suite, const std::vector<SweepPoint>& points) {
  std::vector<std::string> configs;
  for (const SuiteCell& c : suite.cells) {
    const std::string config = c.config.empty() ? configDir() + "/sim.yaml" : c.config;
    if (std::find(configs.begin(), configs.end(), config) == configs.end()) configs.push_back(config);
  }
  for (const std::string& config : configs)
    for (const SweepPoint& point : points) {
      if (point.empty()) continue;
      if (auto loaded = loadAppConfig(config, point); !loaded) return loaded.error();
    }
  return rt::ok();
}

rt::Expected<SlurmSettings> slurmSettings(const ParsedArgs& args, std::int64_t jobs) {
  SlurmSettings s;
  s.partition = args.valueOr("slurm-partition", "");
  const auto time = parseInt("slurm-time", args.valueOr("slurm-time", "30"), 1, 525600);
  if (!time) return time.error();
  const auto mem = parseInt("slurm-mem", args.valueOr("slurm-mem", "2048"), 16, 16777216);
  if (!mem) return mem.error();
  s.time_limit_min = static_cast<int>(*time);
  s.memory_mb = static_cast<int>(*mem);
  s.max_running = static_cast<int>(args.has("jobs") ? jobs : 16);
  s.options = args.listOf("slurm-option");
  for (const std::string& o : s.options)
    if (o.rfind("--", 0) != 0)
      return rt::Error{"--slurm-option: expected an sbatch option (--name=value), got '" + o + "'"};
  return s;
}

/// Submits `indices` to Slurm, then waits and merges, or returns (--no-wait).
int runOnSlurm(const TrialPlan& plan, const std::vector<std::size_t>& indices, bool wait, const char* command);

/// Prints the merge's outcome and turns it into the exit status.
int mergeAndReport(const TrialPlan& plan, const char* command) {
  const auto merged = mergeTrials(plan);
  if (!merged) return failCommand(command, merged.error().message);
  return merged->missing.empty() && merged->error_cells == 0 ? 0 : 1;
}

std::vector<std::size_t> incompleteTrials(const TrialPlan& plan) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < plan.trials.size(); ++i)
    if (!trialComplete(plan.trials[i].dir)) out.push_back(i);
  return out;
}

int runOnSlurm(const TrialPlan& plan, const std::vector<std::size_t>& indices, bool wait, const char* command) {
  if (indices.empty()) {
    std::printf("slurm: nothing to submit: every trial has a result\n");
    return mergeAndReport(plan, command);
  }
  const auto jobs = submitToSlurm(plan, indices);
  if (!jobs) return failCommand(command, jobs.error().message);
  std::string ids;
  for (const std::string& id : *jobs) ids += (ids.empty() ? "" : ",") + id;
  std::printf("slurm: %zu trials submitted as job%s %s (logs in %s/slurm/logs)\n", indices.size(),
              jobs->size() > 1 ? "s" : "", ids.c_str(), plan.out_dir.c_str());
  if (!wait) {
    std::printf("slurm: not waiting; `aerotrack bench merge %s` merges what has finished, `scancel %s` stops it\n",
                plan.out_dir.c_str(), ids.c_str());
    return 0;
  }
  std::fflush(stdout);
  std::atomic<bool> stop{false};
  SignalWatcher signals(stop);
  if (auto waited = waitForSlurm(plan, *jobs, indices, stop); !waited)
    return failCommand(command, waited.error().message);
  if (stop.load()) {
    std::printf(
        "slurm: stopped waiting; job%s %s run%s on (`scancel %s` stops %s); `aerotrack bench merge %s` merges\n",
        jobs->size() > 1 ? "s" : "", ids.c_str(), jobs->size() > 1 ? "" : "s", ids.c_str(),
        jobs->size() > 1 ? "them" : "it", plan.out_dir.c_str());
    return signals.stoppedStatus();
  }
  return mergeAndReport(plan, command);
}

}  // namespace

int benchCommand(const ParsedArgs& args) {
  const auto jobs = parseInt(
      "jobs", args.valueOr("jobs", std::to_string(std::max(1U, std::thread::hardware_concurrency()))), 1, 1024);
  if (!jobs) return failCommand("bench", jobs.error().message);
  const std::string executor = args.valueOr("executor", "local");
  if (executor != "local" && executor != "slurm" && executor != "none")
    return failCommand("bench", "--executor: expected local, slurm or none, got '" + executor + "'");
  if (executor != "slurm")
    for (const char* slurm_only : {"no-wait", "slurm-partition", "slurm-time", "slurm-mem", "slurm-option"})
      if (args.has(slurm_only))
        return failCommand("bench", std::string("--") + slurm_only + " goes with --executor slurm");
  std::error_code ec;
  const std::string self = std::filesystem::read_symlink("/proc/self/exe", ec).string();
  if (ec) return failCommand("bench", "cannot find the aerotrack binary: " + ec.message());

  TrialPlan plan;
  plan.binary = self;
  if (args.has("suite")) {
    for (const char* other : {"scenario", "trials", "speed", "camera", "mode", "config"})
      if (args.has(other))
        return failCommand("bench", std::string("--") + other + " does not go with --suite (the suite file sets it)");
    auto suite = loadSuite(args.values.at("suite"));
    if (!suite) return failCommand("bench", suite.error().message);
    for (SuiteCell& c : suite->cells) {
      c.scenario = absoluteScenario(c.scenario);
      if (!c.config.empty()) c.config = absolutePath(c.config);
    }
    plan.kind = "suite";
    plan.suite = *suite;
    plan.out_dir = absolutePath(args.valueOr("out", "out/suite-" + suite->name));
  } else {
    auto suite = benchCells(args);
    if (!suite) return failCommand("bench", suite.error().message);
    plan.kind = "bench";
    plan.suite = *suite;
    plan.out_dir = absolutePath(args.valueOr("out", "out/bench-" + suite->name));
    plan.bench = {{"scenario", args.values.at("scenario")}, {"speed", args.valueOr("speed", "")}};
  }
  for (const std::string& option : args.listOf("set")) {
    auto key = parseSweepOption(option);
    if (!key) return failCommand("bench", key.error().message);
    plan.sweep.push_back(*key);
  }
  const auto points = sweepPoints(plan.sweep, 10000);
  if (!points) return failCommand("bench", points.error().message);
  if (auto checked = checkSweep(plan.suite, *points); !checked) return failCommand("bench", checked.error().message);
  applySweep(plan.suite, *points);
  // Bounds on what one plan may hold (plan.json and trials.txt stay tens of MB, a merge minutes).
  const auto seeds = static_cast<std::size_t>(plan.suite.last_seed - plan.suite.first_seed + 1);
  if (plan.suite.cells.size() > kMaxPlanCells)
    return failCommand("bench", std::to_string(plan.suite.cells.size()) + " cells with the sweep; at most " +
                                    std::to_string(kMaxPlanCells) + " in one plan");
  if (plan.suite.cells.size() * seeds > kMaxPlanTrials)
    return failCommand("bench", std::to_string(plan.suite.cells.size() * seeds) + " trials; at most " +
                                    std::to_string(kMaxPlanTrials) + " in one plan (split it into several)");
  if (executor == "slurm") {
    auto settings = slurmSettings(args, *jobs);
    if (!settings) return failCommand("bench", settings.error().message);
    plan.slurm = *settings;
  }
  std::filesystem::create_directories(plan.out_dir, ec);
  if (ec) return failCommand("bench", plan.out_dir + ": cannot create directory: " + ec.message());
  // A cell whose scenario (or config) file is missing is an error line in the report, not an abort:
  // the other cells still run.
  for (const SuiteCell& cell : plan.suite.cells) {
    plan.cell_errors.push_back(cellError(cell));
    if (!plan.cell_errors.back().empty())
      std::fprintf(stderr, "aerotrack bench: cell %s: %s; skipped\n", cell.id.c_str(), plan.cell_errors.back().c_str());
  }
  if (plan.kind == "bench" && !plan.cell_errors.front().empty()) return failCommand("bench", plan.cell_errors.front());
  planTrials(plan);
  if (auto written = writePlan(plan); !written) return failCommand("bench", written.error().message);
  // A suite resumes: its complete trials are kept. A bench runs every trial again.
  std::vector<std::size_t> to_run;
  if (plan.kind == "suite") {
    to_run = incompleteTrials(plan);
  } else {
    for (std::size_t i = 0; i < plan.trials.size(); ++i) to_run.push_back(i);
  }
  std::printf("%s %s: %zu cells, %zu trials complete already, %zu to run, %s\n", plan.kind.c_str(),
              plan.suite.name.c_str(), plan.suite.cells.size(), plan.trials.size() - to_run.size(), to_run.size(),
              executor == "slurm"  ? "as Slurm job arrays"
              : executor == "none" ? "by another engine"
                                   : (std::to_string(*jobs) + " at a time").c_str());
  std::printf("plan: %s/plan.json (trials.txt: one command per trial; run_trial.sh INDEX runs one)\n",
              plan.out_dir.c_str());
  std::fflush(stdout);
  if (executor == "slurm") return runOnSlurm(plan, to_run, !args.has("no-wait"), "bench");
  if (executor == "none") {  // another engine runs the plan (docs/scale-out.md)
    std::printf(
        "not run: %s/run_trial.sh INDEX runs trial INDEX (0 to %zu trials - 1); then `aerotrack bench merge %s`\n",
        plan.out_dir.c_str(), plan.trials.size(), plan.out_dir.c_str());
    return 0;
  }

  std::vector<TrialJob> trial_jobs;
  for (const std::size_t i : to_run) {
    std::vector<std::string> argv = trialCommand(plan, i);
    trial_jobs.push_back({std::vector<std::string>(argv.begin() + 2, argv.end()), plan.trials[i].dir});
  }
  std::atomic<bool> stop{false};
  SignalWatcher signals(stop);
  std::map<std::size_t, int> exit_status;
  std::string run_error;
  if (!runTrials(self, trial_jobs, *jobs, stop, exit_status, run_error)) return failCommand("bench", run_error);
  const int merged = mergeAndReport(plan, "bench");
  if (stop.load()) return signals.stoppedStatus();
  return merged;
}

int benchMergeCommand(const ParsedArgs& args) {
  const std::string dir = *args.positional;
  auto plan = readPlan(dir);
  if (!plan) return failCommand("bench merge", plan.error().message);
  if (!args.has("resubmit-missing")) {
    if (args.has("no-wait")) return failCommand("bench merge", "--no-wait goes with --resubmit-missing");
    return mergeAndReport(*plan, "bench merge");
  }
  if (!plan->slurm)
    return failCommand("bench merge",
                       "--resubmit-missing: " + dir +
                           " was run by local processes; run the same `aerotrack bench` again (a suite keeps its "
                           "finished trials)");
  return runOnSlurm(*plan, incompleteTrials(*plan), !args.has("no-wait"), "bench merge");
}

}  // namespace aerotrack::app
