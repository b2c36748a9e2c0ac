// The merge step of `aerotrack bench`: see bench_merge.hpp.
#include "bench_merge.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include "bench_plot.hpp"
#include "bench_stats.hpp"
#include "slurm_executor.hpp"

#include <nlohmann/json.hpp>

namespace aerotrack::app {
namespace {

std::string formatInterval(const nlohmann::json& ci) {
  char text[48];
  std::snprintf(text, sizeof(text), "[%.2f, %.2f]", ci[0].get<double>(), ci[1].get<double>());
  return text;
}

/// One cell of a bench: the table of its trials, DIR/<cell>/bench.json and bench.png, the verdict
/// lines and the Table I row. `reasons_by_dir`: why each trial without a result has none.
rt::Status benchCellReport(const TrialPlan& plan, const SuiteCell& cell,
                           const std::map<std::string, std::string>& reasons_by_dir) {
  const std::string cell_dir = plan.out_dir + (cell.id.empty() ? "" : "/" + cell.id);
  const std::string scenario = plan.bench.value("scenario", cell.scenario);
  const std::string speed = plan.bench.value("speed", "");
  const std::string scenario_tag = std::filesystem::path(scenario).stem().string();
  const std::int64_t trials = plan.suite.last_seed - plan.suite.first_seed + 1;
  if (!cell.sets.empty()) std::printf("\n%s:\n", sweepPointLabel(cell.sets).c_str());
  nlohmann::json per_trial = nlohmann::json::array();
  int successes = 0, failed_runs = 0, collisions = 0;
  double visible_sum = 0.0, distance_sum = 0.0, rtf_sum = 0.0, plan_p50_sum = 0.0, plan_p99_max = 0.0;
  double occluded_sum_s = 0.0, out_of_image_sum_s = 0.0, longest_loss_max_s = 0.0;
  long long losses = 0;
  int planned_trials = 0;
  std::printf("%6s %8s %8s %8s %10s %9s %9s %7s %7s %9s  %s\n", "seed", "success", "followed", "visible", "long_loss",
              "dist_m", "clear_m", "id_sw", "top_mps", "rt_x", "failure (ours; the paper's)");
  for (std::int64_t seed = plan.suite.first_seed; seed <= plan.suite.last_seed; ++seed) {
    const std::string dir = trialDir(plan.out_dir, cell, seed);
    if (!trialComplete(dir)) {
      const auto reason = reasons_by_dir.find(dir);  // absent: its result went away while the merge ran
      std::printf("%6lld   (no result: %s)\n", static_cast<long long>(seed),
                  reason == reasons_by_dir.end() ? "its summary.json went away" : reason->second.c_str());
      ++failed_runs;
      continue;
    }
    std::ifstream in(dir + "/summary.json");
    const nlohmann::json s = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
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
      {"set", cellJson(cell)["set"]},
      {"scenario", scenario},
      {"speed_mps", !speed.empty() ? nlohmann::json(std::stod(speed)) : nlohmann::json(nullptr)},
      {"trials", trials},
      {"completed", per_trial.size()},
      {"runs_without_result", failed_runs},
      {"successes", successes},
      {"success_rate", successes / static_cast<double>(trials)},
      {"collisions", collisions},
      {"visible_ratio_mean", visible_sum / n},
      {"losses", losses},
      {"longest_loss_s_max", longest_loss_max_s},
      {"hidden_s_mean", {{"occluded", occluded_sum_s / n}, {"out_of_image", out_of_image_sum_s / n}}},
      {"distance_mean_m", distance_sum / n},
      {"realtime_factor_mean", rtf_sum / n},
      {"mode", cell.mode},
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
  std::ofstream file(cell_dir + "/bench.json");
  file << bench.dump(2) << "\n";
  file.close();
  if (!file) return rt::Error{cell_dir + "/bench.json: write failed"};
  BenchPlotData plot;
  plot.title = scenario + ", " + std::to_string(per_trial.size()) + " trials" +
               (!speed.empty() ? ", " + speed + " m/s" : "") + " (" + cell.mode + ")";
  plot.verdict = "ours " + std::to_string(successes) + "/" + std::to_string(trials) + " " +
                 formatInterval(stats["success_ci95"]) + ", followed all the way " +
                 std::to_string(stats["followed_all_the_way"].get<int>()) + " " +
                 formatInterval(stats["followed_ci95"]);
  for (const nlohmann::json& s : per_trial) {
    plot.visible_ratio.push_back(s.value("visible_ratio", std::nan("")));
    plot.distance_mean_m.push_back(s.value("distance_mean_m", std::nan("")));
  }
  if (const rt::Status drawn = writeBenchPlot(cell_dir + "/bench.png", plot); !drawn) return drawn.error();
  std::printf("%s: %d/%lld successful (%.0f%%), %d collisions, person visible %.0f%% on average; %s/bench.json\n",
              scenario.c_str(), successes, static_cast<long long>(trials),
              100.0 * successes / static_cast<double>(trials), collisions, 100.0 * visible_sum / n, cell_dir.c_str());
  const nlohmann::json& identity = stats["identity"];
  std::printf(
      "verdicts over %d completed trials (95 %% Wilson): ours %d %s, followed all the way %d %s; identity: %s; "
      "person top speed %.2f m/s (mean over trials), mean %.2f m/s\n",
      stats["completed"].get<int>(), successes, formatInterval(stats["success_ci95"]).c_str(),
      stats["followed_all_the_way"].get<int>(), formatInterval(stats["followed_ci95"]).c_str(),
      identity["trials_reported"].get<int>() > 0
          ? (std::to_string(identity["trials_without_switch"].get<int>()) + "/" +
             std::to_string(identity["trials_reported"].get<int>()) + " trials without a switch" +
             (identity["trials_without_switch_nearest"].is_number()
                  ? " (" + std::to_string(identity["trials_without_switch_nearest"].get<int>()) +
                        " by the nearest match)"
                  : std::string()) +
             ", " + std::to_string(identity["time_on_wrong_person_s_mean"].get<double>()) +
             " s on a wrong person on average")
                .c_str()
          : "not reported",
      stats["person_top_speed_mps_mean"].is_number() ? stats["person_top_speed_mps_mean"].get<double>() : 0.0,
      stats["person_mean_speed_mps_mean"].is_number() ? stats["person_mean_speed_mps_mean"].get<double>() : 0.0);
  // One row of the paper's Table I, in markdown (scripts/table1.sh collects them).
  std::printf(
      "| %s | %s | %s | %d/%lld | %.1f %% | %lld, longest %.1f s | %.2f / %.2f s | %.2f m | %.2f / %.2f ms | %d |\n",
      scenario_tag.c_str(), !speed.empty() ? (speed + " m/s").c_str() : "scenario's", cell.mode.c_str(), successes,
      static_cast<long long>(trials), 100.0 * visible_sum / n, losses, longest_loss_max_s, occluded_sum_s / n,
      out_of_image_sum_s / n, distance_sum / n, planned_trials > 0 ? plan_p50_sum / planned_trials : 0.0, plan_p99_max,
      collisions);
  return rt::ok();
}

/// The suite's (or a swept bench's) suite.json, report.md and plots.
rt::Expected<int> suiteReports(const TrialPlan& plan) {
  const std::string& out_dir = plan.out_dir;
  const SuiteSpec* suite = &plan.suite;
  const std::vector<std::string>& errors = plan.cell_errors;
  const std::vector<CellResult> results = collectResults(out_dir, *suite, errors);
  std::ofstream json_file(out_dir + (plan.kind == "suite" ? "/suite.json" : "/sweep.json"));
  nlohmann::json suite_json = suiteJson(*suite, results);
  nlohmann::json sweep = nlohmann::json::array();
  for (const SweepKey& k : plan.sweep) sweep.push_back({{"key", k.key}, {"values", k.values}});
  suite_json["sweep"] = sweep;
  json_file << suite_json.dump(2) << "\n";
  json_file.close();
  if (!json_file) return rt::Error{out_dir + "/suite.json: write failed"};
  const auto plots = writeSuitePlots(out_dir, *suite, results);
  if (!plots) return plots.error();
  const auto sweep_plots = writeSweepPlots(out_dir, *suite, plan.sweep, results);
  if (!sweep_plots) return sweep_plots.error();
  std::ofstream report(out_dir + "/report.md");
  report << suiteReport(*suite, results, *plots);
  if (!sweep_plots->empty()) {
    report << "\n## Sweeps\n\nThe figures of merit against each swept key (`--set`), a series per cell of the rest.\n";
    for (const std::string& file : *sweep_plots) report << "\n![" << file << "](" << file << ")\n";
  }
  report.close();
  if (!report) return rt::Error{out_dir + "/report.md: write failed"};

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
  std::printf("%s %s: %s/report.md, %s/%s; %d trial(s) without a result, %d cell(s) in error\n", plan.kind.c_str(),
              suite->name.c_str(), out_dir.c_str(), out_dir.c_str(), plan.kind == "suite" ? "suite.json" : "sweep.json",
              missing, error_cells);
  return error_cells;
}

/// The engine's log of each trial, where an engine keeps one (Slurm).
std::map<std::size_t, std::string> engineLogs(const TrialPlan& plan) {
  return plan.slurm ? slurmLogs(plan) : std::map<std::size_t, std::string>{};
}

}  // namespace

rt::Expected<MergeOutcome> mergeTrials(const TrialPlan& plan) {
  MergeOutcome outcome;
  const std::map<std::size_t, std::string> logs = engineLogs(plan);
  std::map<std::string, std::string> reasons_by_dir;
  std::string missing_text, missing_lines;
  for (std::size_t i = 0; i < plan.trials.size(); ++i) {
    const PlannedTrial& t = plan.trials[i];
    const auto log = logs.find(i);
    const TrialState state = trialState(t.dir, log == logs.end() ? "" : log->second);
    if (state.complete) continue;
    outcome.missing.push_back(i);
    reasons_by_dir[t.dir] = state.reason;
    const std::string& cell = plan.suite.cells[t.cell].id;
    missing_text += std::to_string(i) + " " + (cell.empty() ? "-" : cell) + " " + std::to_string(t.seed) + " " + t.dir +
                    ": " + state.reason + "\n";
    missing_lines += "  trial " + std::to_string(i) + " (seed " + std::to_string(t.seed) +
                     (cell.empty() ? "" : " of " + cell) + "): " + state.reason + "\n";
  }
  std::error_code ec;
  const std::string missing_path = plan.out_dir + "/missing.txt";
  if (missing_text.empty()) {
    std::filesystem::remove(missing_path, ec);
  } else {
    std::ofstream out(missing_path, std::ios::trunc);
    out << missing_text;
    if (!out) return rt::Error{missing_path + ": write failed"};
  }
  if (plan.kind == "bench") {
    for (const SuiteCell& cell : plan.suite.cells)
      if (auto s = benchCellReport(plan, cell, reasons_by_dir); !s) return s.error();
  }
  if (plan.kind == "suite" || !plan.sweep.empty()) {
    const auto error_cells = suiteReports(plan);
    if (!error_cells) return error_cells.error();
    outcome.error_cells = *error_cells;
  }
  if (!outcome.missing.empty()) {
    std::printf("merge: %zu of %zu trials without a result (all in %s):\n", outcome.missing.size(), plan.trials.size(),
                missing_path.c_str());
    std::size_t shown = 0;
    std::size_t start = 0;
    while (start < missing_lines.size() && shown < 20) {
      const std::size_t end = missing_lines.find('\n', start);
      std::printf("%s\n", missing_lines.substr(start, end - start).c_str());
      start = end + 1;
      ++shown;
    }
    if (outcome.missing.size() > shown) std::printf("  ... and %zu more\n", outcome.missing.size() - shown);
  } else {
    std::printf("merge: all %zu trials have a result\n", plan.trials.size());
  }
  return outcome;
}

}  // namespace aerotrack::app
