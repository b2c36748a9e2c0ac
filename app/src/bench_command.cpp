// `aerotrack bench --scenario NAME|FILE --trials N [--speed MPS] [--out DIR] [--jobs J] [--config FILE]`:
// runs seeds 1..N of a scenario as separate `aerotrack sim` processes, J at a time, then merges
// their summary.json files into DIR/bench.json and prints a table. Each trial is a pure function
// of (scenario, seed, config) writing one result folder (DIR/trial-SEED), so any batch system can
// run the same trials unchanged and this merge step reads them (DESIGN.md, "Scale beyond one
// machine").
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include "commands.hpp"
#include "signals.hpp"

#include <nlohmann/json.hpp>

namespace aerotrack::app {
namespace {

/// Starts `self sim ...` for one seed with its output in dir/log.txt; returns the pid or -1.
pid_t launchTrial(const std::string& self, const ParsedArgs& args, std::int64_t seed, const std::string& dir) {
  std::vector<std::string> argv{
      self, "sim", "--scenario", args.values.at("scenario"), "--seed", std::to_string(seed), "--out", dir};
  for (const char* passthrough : {"speed", "camera", "config", "mode"})
    if (args.values.count(passthrough) != 0) {
      argv.push_back(std::string("--") + passthrough);
      argv.push_back(args.values.at(passthrough));
    }
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

}  // namespace

int benchCommand(const ParsedArgs& args) {
  const std::string mode = args.valueOr("mode", "proposed");
  if (mode != "proposed" && mode != "baseline")
    return failCommand("bench", "--mode: expected proposed or baseline, got '" + mode + "'");
  const auto trials = parseInt("trials", args.values.at("trials"), 1, 100000);
  if (!trials) return failCommand("bench", trials.error().message);
  const auto jobs = parseInt(
      "jobs", args.valueOr("jobs", std::to_string(std::max(1U, std::thread::hardware_concurrency()))), 1, 1024);
  if (!jobs) return failCommand("bench", jobs.error().message);
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
  std::map<pid_t, std::int64_t> running;
  std::map<std::int64_t, int> exit_status;
  std::int64_t next_seed = 1;
  while ((next_seed <= *trials && !stop.load()) || !running.empty()) {
    while (!stop.load() && next_seed <= *trials && static_cast<std::int64_t>(running.size()) < *jobs) {
      const std::string dir = out_dir + "/trial-" + std::to_string(next_seed);
      std::filesystem::create_directories(dir, ec);
      const pid_t pid = launchTrial(self, args, next_seed, dir);
      if (pid < 0) return failCommand("bench", "cannot start a trial process");
      running[pid] = next_seed++;
    }
    int status = 0;
    const pid_t done = waitpid(-1, &status, 0);
    if (done < 0) break;
    if (stop.load())
      for (const auto& [pid, seed] : running) kill(pid, SIGTERM);
    exit_status[running[done]] = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    running.erase(done);
  }

  nlohmann::json per_trial = nlohmann::json::array();
  int successes = 0, failed_runs = 0, collisions = 0;
  double visible_sum = 0.0, distance_sum = 0.0, rtf_sum = 0.0, plan_p50_sum = 0.0, plan_p99_max = 0.0;
  double occluded_sum_s = 0.0, out_of_image_sum_s = 0.0, longest_loss_max_s = 0.0;
  long long losses = 0;
  int planned_trials = 0;
  std::printf("%6s %8s %8s %10s %9s %9s %9s  %s\n", "seed", "success", "visible", "long_loss", "dist_m", "clear_m",
              "rt_x", "failure");
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
    std::printf("%6lld %8s %7.0f%% %9.1fs %9.2f %9.2f %9.0f  %s\n", static_cast<long long>(seed), ok ? "yes" : "NO",
                100.0 * s.value("visible_ratio", 0.0), s.value("longest_loss_s", 0.0), s.value("distance_mean_m", 0.0),
                s["min_clearance_m"].is_number() ? s["min_clearance_m"].get<double>() : std::nan(""),
                s.value("realtime_factor", 0.0),
                s["failure_reason"].is_string() ? s["failure_reason"].get<std::string>().c_str() : "");
  }
  const double n = std::max<double>(1.0, static_cast<double>(per_trial.size()));
  const nlohmann::json bench = {
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
  std::ofstream file(out_dir + "/bench.json");
  file << bench.dump(2) << "\n";
  file.close();
  if (!file) return failCommand("bench", out_dir + "/bench.json: write failed");
  std::printf("%s: %d/%lld successful (%.0f%%), %d collisions, person visible %.0f%% on average; %s/bench.json\n",
              args.values.at("scenario").c_str(), successes, static_cast<long long>(*trials),
              100.0 * successes / static_cast<double>(*trials), collisions, 100.0 * visible_sum / n, out_dir.c_str());
  // One row of the paper's Table I, in markdown (scripts/table1.sh collects them).
  std::printf(
      "| %s | %s | %s | %d/%lld | %.1f %% | %lld, longest %.1f s | %.2f / %.2f s | %.2f m | %.2f / %.2f ms | %d |\n",
      scenario_tag.c_str(), args.has("speed") ? (args.values.at("speed") + " m/s").c_str() : "scenario's",
      args.valueOr("mode", "proposed").c_str(), successes, static_cast<long long>(*trials), 100.0 * visible_sum / n,
      losses, longest_loss_max_s, occluded_sum_s / n, out_of_image_sum_s / n, distance_sum / n,
      planned_trials > 0 ? plan_p50_sum / planned_trials : 0.0, plan_p99_max, collisions);
  if (stop.load()) return 130;
  return failed_runs == 0 ? 0 : 1;
}

}  // namespace aerotrack::app
