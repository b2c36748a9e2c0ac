// `aerotrack bench --scenario NAME|FILE --trials N [--speed MPS] [--out DIR] [--jobs J] [--config FILE]`:
// runs seeds 1..N of a scenario as separate `aerotrack sim` processes, J at a time, then merges
// their summary.json files into DIR/bench.json and prints a table. Each trial is a pure function
// of (scenario, seed, config) writing one result folder (DIR/trial-SEED), so any batch system can
// run the same trials unchanged and this merge step reads them (DESIGN.md, "Scale beyond one
// machine").
// `aerotrack bench --suite FILE [--out DIR] [--jobs J]` runs a suite's matrix the same way (suite.hpp),
// skipping trials whose summary.json is complete, so an interrupted suite resumes where it stopped.
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

#include "bench_plot.hpp"
#include "bench_stats.hpp"
#include "commands.hpp"
#include "signals.hpp"
#include "suite.hpp"

#include <nlohmann/json.hpp>

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

std::string formatInterval(const nlohmann::json& ci) {
  char text[48];
  std::snprintf(text, sizeof(text), "[%.2f, %.2f]", ci[0].get<double>(), ci[1].get<double>());
  return text;
}

int suiteCommand(const ParsedArgs& args, const std::string& self, std::int64_t jobs);

}  // namespace

int benchCommand(const ParsedArgs& args) {
  const auto jobs = parseInt(
      "jobs", args.valueOr("jobs", std::to_string(std::max(1U, std::thread::hardware_concurrency()))), 1, 1024);
  if (!jobs) return failCommand("bench", jobs.error().message);
  if (args.has("suite")) {
    for (const char* other : {"scenario", "trials", "speed", "camera", "mode", "config"})
      if (args.has(other))
        return failCommand("bench", std::string("--") + other + " does not go with --suite (the suite file sets it)");
    std::error_code ec;
    const std::string self = std::filesystem::read_symlink("/proc/self/exe", ec).string();
    if (ec) return failCommand("bench", "cannot find the aerotrack binary: " + ec.message());
    return suiteCommand(args, self, *jobs);
  }
  if (!args.has("scenario") || !args.has("trials"))
    return failCommand("bench", "needs --scenario NAME|FILE and --trials N, or --suite FILE");
  const std::string mode = args.valueOr("mode", "proposed");
  if (mode != "proposed" && mode != "baseline")
    return failCommand("bench", "--mode: expected proposed or baseline, got '" + mode + "'");
  const auto trials = parseInt("trials", args.values.at("trials"), 1, 100000);
  if (!trials) return failCommand("bench", trials.error().message);
  if (args.has("speed")) {
    if (const auto s = parseDouble("speed", args.values.at("speed"), 0.05, 20.0); !s)
      return failCommand("bench", s.error().message);
  }
  std::error_code ec;
  const std::string self = std::filesystem::read_symlink("/proc/self/exe", ec).string();
  if (ec) return failCommand("bench", "cannot find the aerotrack binary: " + ec.message());
  std::string scenario_tag = std::filesystem::path(args.values.at("scenario")).stem().string();
  const std::string out_dir = args.valueOr("out", "out/bench-" + scenario_tag);
  std::filesystem::create_directories(out_dir, ec);
  if (ec) return failCommand("bench", out_dir + ": cannot create directory: " + ec.message());

  std::atomic<bool> stop{false};
  SignalWatcher signals(stop);
  std::vector<TrialJob> trial_jobs;
  for (std::int64_t seed = 1; seed <= *trials; ++seed) {
    TrialJob job{{"--scenario", args.values.at("scenario"), "--seed", std::to_string(seed), "--out",
                  out_dir + "/trial-" + std::to_string(seed)},
                 out_dir + "/trial-" + std::to_string(seed)};
    for (const char* passthrough : {"speed", "camera", "config", "mode"})
      if (args.values.count(passthrough) != 0) {
        job.args.push_back(std::string("--") + passthrough);
        job.args.push_back(args.values.at(passthrough));
      }
    trial_jobs.push_back(std::move(job));
  }
  std::map<std::size_t, int> status_by_index;
  std::string run_error;
  if (!runTrials(self, trial_jobs, *jobs, stop, status_by_index, run_error)) return failCommand("bench", run_error);
  std::map<std::int64_t, int> exit_status;
  for (const auto& [index, code] : status_by_index) exit_status[static_cast<std::int64_t>(index) + 1] = code;

  nlohmann::json per_trial = nlohmann::json::array();
  int successes = 0, failed_runs = 0, collisions = 0;
  double visible_sum = 0.0, distance_sum = 0.0, rtf_sum = 0.0, plan_p50_sum = 0.0, plan_p99_max = 0.0;
  double occluded_sum_s = 0.0, out_of_image_sum_s = 0.0, longest_loss_max_s = 0.0;
  long long losses = 0;
  int planned_trials = 0;
  std::printf("%6s %8s %8s %8s %10s %9s %9s %7s %7s %9s  %s\n", "seed", "success", "followed", "visible", "long_loss",
              "dist_m", "clear_m", "id_sw", "top_mps", "rt_x", "failure (ours; the paper's)");
  for (const auto& [seed, code] : exit_status) {
    const std::string path = out_dir + "/trial-" + std::to_string(seed) + "/summary.json";
    std::ifstream in(path);
    nlohmann::json s;
    try {
      in >> s;
    } catch (const nlohmann::json::exception&) {
      std::printf("%6lld   (no result: exit status %d, see %s/trial-%lld/log.txt)\n", static_cast<long long>(seed),
                  code, out_dir.c_str(), static_cast<long long>(seed));
      ++failed_runs;
      continue;
    }
    per_trial.push_back(s);
    const bool ok = s.value("success", false);
    successes += ok ? 1 : 0;
    collisions += s.value("collisions", 0);
    visible_sum += s.value("visible_ratio", 0.0);
    distance_sum += s.value("distance_mean_m", 0.0);
    rtf_sum += s.value("realtime_factor", 0.0);
    losses += s.value("losses", 0LL);
    longest_loss_max_s = std::max(longest_loss_max_s, s.value("longest_loss_s", 0.0));
    if (s.contains("hidden_s") && s["hidden_s"].is_object()) {
      occluded_sum_s += s["hidden_s"].value("occluded", 0.0);
      out_of_image_sum_s += s["hidden_s"].value("out_of_image", 0.0);
    }
    if (s.contains("planning") && s["planning"].is_object()) {
      ++planned_trials;
      plan_p50_sum += s["planning"].value("cycle_ms_p50", 0.0);
      plan_p99_max = std::max(plan_p99_max, s["planning"].value("cycle_ms_p99", 0.0));
    }
    const bool followed = s.value("followed_all_the_way", false);
    std::string reasons = s["failure_reason"].is_string() ? s["failure_reason"].get<std::string>() : "";
    if (s.contains("follow_failure_reason") && s["follow_failure_reason"].is_string())
      reasons += "; " + s["follow_failure_reason"].get<std::string>();
    std::printf("%6lld %8s %8s %7.0f%% %9.1fs %9.2f %9.2f %7s %7.2f %9.0f  %s\n", static_cast<long long>(seed),
                ok ? "yes" : "NO", followed ? "yes" : "NO", 100.0 * s.value("visible_ratio", 0.0),
                s.value("longest_loss_s", 0.0), s.value("distance_mean_m", 0.0),
                s["min_clearance_m"].is_number() ? s["min_clearance_m"].get<double>() : std::nan(""),
                s.contains("identity_switches") && s["identity_switches"].is_number()
                    ? std::to_string(s["identity_switches"].get<int>()).c_str()
                    : "-",
                s.value("person_top_speed_mps", 0.0), s.value("realtime_factor", 0.0), reasons.c_str());
  }
  const double n = std::max<double>(1.0, static_cast<double>(per_trial.size()));
  const nlohmann::json stats = aggregateSummaries(std::vector<nlohmann::json>(per_trial.begin(), per_trial.end()));
  nlohmann::json bench = {
      {"scenario", args.values.at("scenario")},
      {"speed_mps", args.has("speed") ? nlohmann::json(std::stod(args.values.at("speed"))) : nlohmann::json(nullptr)},
      {"trials", *trials},
      {"completed", per_trial.size()},
      {"runs_without_result", failed_runs},
      {"successes", successes},
      {"success_rate", successes / static_cast<double>(*trials)},
      {"collisions", collisions},
      {"visible_ratio_mean", visible_sum / n},
      {"losses", losses},
      {"longest_loss_s_max", longest_loss_max_s},
      {"hidden_s_mean", {{"occluded", occluded_sum_s / n}, {"out_of_image", out_of_image_sum_s / n}}},
      {"distance_mean_m", distance_sum / n},
      {"realtime_factor_mean", rtf_sum / n},
      {"mode", args.valueOr("mode", "proposed")},
      {"planning_cycle_ms_p50_mean", planned_trials > 0 ? plan_p50_sum / planned_trials : 0.0},
      {"planning_cycle_ms_p99_max", plan_p99_max},
      {"summaries", per_trial},
  };
  // Both verdicts with 95 % Wilson intervals, identity metrics and the person's measured speed (over
  // the completed trials; bench_stats.hpp).
  for (const char* key :
       {"completed", "success_ci95", "followed_all_the_way", "followed_rate", "followed_ci95", "min_clearance_m",
        "identity", "person_top_speed_mps_mean", "person_top_speed_mps_max", "person_mean_speed_mps_mean"})
    bench[key] = stats[key];
  std::ofstream file(out_dir + "/bench.json");
  file << bench.dump(2) << "\n";
  file.close();
  if (!file) return failCommand("bench", out_dir + "/bench.json: write failed");
  BenchPlotData plot;
  plot.title = args.values.at("scenario") + ", " + std::to_string(per_trial.size()) + " trials" +
               (args.has("speed") ? ", " + args.values.at("speed") + " m/s" : "") + " (" +
               args.valueOr("mode", "proposed") + ")";
  plot.verdict = "ours " + std::to_string(successes) + "/" + std::to_string(*trials) + " " +
                 formatInterval(stats["success_ci95"]) + ", followed all the way " +
                 std::to_string(stats["followed_all_the_way"].get<int>()) + " " +
                 formatInterval(stats["followed_ci95"]);
  for (const nlohmann::json& s : per_trial) {
    plot.visible_ratio.push_back(s.value("visible_ratio", std::nan("")));
    plot.distance_mean_m.push_back(s.value("distance_mean_m", std::nan("")));
  }
  if (const rt::Status drawn = writeBenchPlot(out_dir + "/bench.png", plot); !drawn)
    return failCommand("bench", drawn.error().message);
  std::printf("%s: %d/%lld successful (%.0f%%), %d collisions, person visible %.0f%% on average; %s/bench.json\n",
              args.values.at("scenario").c_str(), successes, static_cast<long long>(*trials),
              100.0 * successes / static_cast<double>(*trials), collisions, 100.0 * visible_sum / n, out_dir.c_str());
  const nlohmann::json& identity = stats["identity"];
  std::printf(
      "verdicts over %d completed trials (95 %% Wilson): ours %d %s, followed all the way %d %s; identity: %s; "
      "person top speed %.2f m/s (mean over trials), mean %.2f m/s\n",
      stats["completed"].get<int>(), successes, formatInterval(stats["success_ci95"]).c_str(),
      stats["followed_all_the_way"].get<int>(), formatInterval(stats["followed_ci95"]).c_str(),
      identity["trials_reported"].get<int>() > 0
          ? (std::to_string(identity["trials_without_switch"].get<int>()) + "/" +
             std::to_string(identity["trials_reported"].get<int>()) + " trials without a switch, " +
             std::to_string(identity["time_on_wrong_person_s_mean"].get<double>()) + " s on a wrong person on average")
                .c_str()
          : "not reported",
      stats["person_top_speed_mps_mean"].is_number() ? stats["person_top_speed_mps_mean"].get<double>() : 0.0,
      stats["person_mean_speed_mps_mean"].is_number() ? stats["person_mean_speed_mps_mean"].get<double>() : 0.0);
  // One row of the paper's Table I, in markdown (scripts/table1.sh collects them).
  std::printf(
      "| %s | %s | %s | %d/%lld | %.1f %% | %lld, longest %.1f s | %.2f / %.2f s | %.2f m | %.2f / %.2f ms | %d |\n",
      scenario_tag.c_str(), args.has("speed") ? (args.values.at("speed") + " m/s").c_str() : "scenario's",
      args.valueOr("mode", "proposed").c_str(), successes, static_cast<long long>(*trials), 100.0 * visible_sum / n,
      losses, longest_loss_max_s, occluded_sum_s / n, out_of_image_sum_s / n, distance_sum / n,
      planned_trials > 0 ? plan_p50_sum / planned_trials : 0.0, plan_p99_max, collisions);
  if (stop.load()) return signals.stoppedStatus();
  return failed_runs == 0 ? 0 : 1;
}

namespace {

int suiteCommand(const ParsedArgs& args, const std::string& self, std::int64_t jobs) {
  const auto suite = loadSuite(args.values.at("suite"));
  if (!suite) return failCommand("bench", suite.error().message);
  const std::string out_dir = args.valueOr("out", "out/suite-" + suite->name);
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) return failCommand("bench", out_dir + ": cannot create directory: " + ec.message());

  // A cell whose scenario (or config) file is missing is an error line in the report, not an abort:
  // the other cells still run.
  std::vector<std::string> errors;
  std::vector<TrialJob> trial_jobs;
  std::size_t done_before = 0;
  for (const SuiteCell& cell : suite->cells) {
    errors.push_back(cellError(cell));
    if (!errors.back().empty()) {
      std::fprintf(stderr, "aerotrack bench: cell %s: %s; skipped\n", cell.id.c_str(), errors.back().c_str());
      continue;
    }
    const std::vector<std::int64_t> seeds = remainingSeeds(out_dir, cell, suite->first_seed, suite->last_seed);
    done_before += static_cast<std::size_t>(suite->last_seed - suite->first_seed + 1) - seeds.size();
    for (const std::int64_t seed : seeds) {
      const std::string dir = trialDir(out_dir, cell, seed);
      TrialJob job{{"--scenario", cell.scenario, "--seed", std::to_string(seed), "--out", dir, "--mode", cell.mode,
                    "--camera", cell.camera},
                   dir};
      if (cell.speed_mps) {
        char speed[32];
        std::snprintf(speed, sizeof(speed), "%.17g", *cell.speed_mps);
        job.args.insert(job.args.end(), {"--speed", speed});
      }
      if (!cell.config.empty()) job.args.insert(job.args.end(), {"--config", cell.config});
      trial_jobs.push_back(std::move(job));
    }
  }
  std::printf("suite %s: %zu cells, %zu trials complete already, %zu to run, %lld at a time\n", suite->name.c_str(),
              suite->cells.size(), done_before, trial_jobs.size(), static_cast<long long>(jobs));
  std::fflush(stdout);

  std::atomic<bool> stop{false};
  SignalWatcher signals(stop);
  std::map<std::size_t, int> exit_status;
  std::string run_error;
  if (!runTrials(self, trial_jobs, jobs, stop, exit_status, run_error)) return failCommand("bench", run_error);

  const std::vector<CellResult> results = collectResults(out_dir, *suite, errors);
  std::ofstream json_file(out_dir + "/suite.json");
  json_file << suiteJson(*suite, results).dump(2) << "\n";
  json_file.close();
  if (!json_file) return failCommand("bench", out_dir + "/suite.json: write failed");
  const auto plots = writeSuitePlots(out_dir, *suite, results);
  if (!plots) return failCommand("bench", plots.error().message);
  std::ofstream report(out_dir + "/report.md");
  report << suiteReport(*suite, results, *plots);
  report.close();
  if (!report) return failCommand("bench", out_dir + "/report.md: write failed");

  int missing = 0, error_cells = 0;
  std::printf("%-44s %12s %22s %22s %8s\n", "cell", "trials", "followed [95% CI]", "ours [95% CI]", "visible");
  for (const CellResult& r : results) {
    if (!r.error.empty()) {
      ++error_cells;
      std::printf("%-44s error: %s\n", r.cell.id.c_str(), r.error.c_str());
      continue;
    }
    missing += static_cast<int>(r.missing_seeds.size());
    const nlohmann::json stats = aggregateSummaries(r.summaries);
    char followed[48], ours[48], trials[24];
    std::snprintf(followed, sizeof(followed), "%d %s", stats["followed_all_the_way"].get<int>(),
                  formatInterval(stats["followed_ci95"]).c_str());
    std::snprintf(ours, sizeof(ours), "%d %s", stats["successes"].get<int>(),
                  formatInterval(stats["success_ci95"]).c_str());
    std::snprintf(trials, sizeof(trials), "%d/%lld", stats["completed"].get<int>(),
                  static_cast<long long>(suite->last_seed) - static_cast<long long>(suite->first_seed) + 1);
    std::printf("%-44s %12s %22s %22s %7.0f%%\n", r.cell.id.c_str(), trials, followed, ours,
                stats["visible_ratio_mean"].is_number() ? 100.0 * stats["visible_ratio_mean"].get<double>() : 0.0);
  }
  std::printf("suite %s: %s/report.md, %s/suite.json; %d trial(s) without a result, %d cell(s) in error\n",
              suite->name.c_str(), out_dir.c_str(), out_dir.c_str(), missing, error_cells);
  if (stop.load()) return signals.stoppedStatus();
  return missing == 0 && error_cells == 0 ? 0 : 1;
}

}  // namespace

}  // namespace aerotrack::app
