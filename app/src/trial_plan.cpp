// The trials of a bench or a suite: see trial_plan.hpp.
#include "trial_plan.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "aerotrack/rt/input_file.hpp"

namespace aerotrack::app {
namespace {

constexpr const char* kPlanFormat = "aerotrack-trial-plan-1";
/// plan.json of the largest plan (100 000 trials of one cell, or thousands of cells) stays far below.
constexpr std::size_t kMaxPlanBytes = std::size_t{64} << 20;

nlohmann::json suiteToJson(const SuiteSpec& s) {
  nlohmann::json json = suiteHeaderJson(s);
  json["cells"] = nlohmann::json::array();
  for (const SuiteCell& c : s.cells) json["cells"].push_back(cellJson(c));
  return json;
}

SuiteSpec suiteFromJson(const nlohmann::json& j) {
  SuiteSpec s;
  s.name = j.at("name").get<std::string>();
  s.source = j.at("source").get<std::string>();
  s.first_seed = j.at("seeds").at(0).get<std::int64_t>();
  s.last_seed = j.at("seeds").at(1).get<std::int64_t>();
  const auto target = [](const nlohmann::json& t) {
    return t.is_null() ? std::optional<double>() : std::optional<double>(t.get<double>());
  };
  s.targets.followed_rate = target(j.at("targets").at("followed_rate"));
  s.targets.success_rate = target(j.at("targets").at("success_rate"));
  s.targets.visible_ratio = target(j.at("targets").at("visible_ratio"));
  for (const nlohmann::json& c : j.at("cells")) {
    auto cell = cellFromJson(c);
    if (!cell) throw std::runtime_error(cell.error().message);
    s.cells.push_back(*cell);
  }
  return s;
}

/// Writes `text` to `path` through a temporary file and a rename: a reader never sees half of it.
rt::Status writeAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  std::ofstream out(tmp, std::ios::trunc);
  out << text;
  out.close();
  if (!out) return rt::Error{path + ": write failed"};
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) return rt::Error{path + ": cannot replace: " + ec.message()};
  return rt::ok();
}

/// The last line of a file that starts with `prefix` ("aerotrack"), or empty. Reads at most the
/// file's last 64 kB: a log may be large.
std::string lastLineStarting(const std::string& path, const std::string& prefix) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "";
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(std::max<std::streamoff>(0, size - 65536));
  std::string line, found;
  while (std::getline(in, line))
    if (line.rfind(prefix, 0) == 0) found = line;
  return found;
}

bool fileContains(const std::string& path, const std::string& needle) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::string line;
  std::size_t read = 0;
  while (std::getline(in, line) && read < (std::size_t{1} << 20)) {
    read += line.size();
    if (line.find(needle) != std::string::npos) return true;
  }
  return false;
}

}  // namespace

void planTrials(TrialPlan& plan) {
  plan.trials.clear();
  for (std::size_t c = 0; c < plan.suite.cells.size(); ++c) {
    if (c < plan.cell_errors.size() && !plan.cell_errors[c].empty()) continue;
    for (std::int64_t seed = plan.suite.first_seed; seed <= plan.suite.last_seed; ++seed)
      plan.trials.push_back({c, seed, trialDir(plan.out_dir, plan.suite.cells[c], seed)});
  }
}

std::vector<std::string> trialCommand(const TrialPlan& plan, std::size_t index) {
  const PlannedTrial& t = plan.trials.at(index);
  std::vector<std::string> argv{plan.binary, "sim"};
  for (std::string& a : trialArgs(plan.suite.cells[t.cell], t.seed, t.dir)) argv.push_back(std::move(a));
  return argv;
}

std::string shellQuote(const std::string& text) {
  std::string out = "'";
  for (const char c : text) {
    if (c == '\'') {
      out += "'\\''";
    } else {
      out += c;
    }
  }
  return out + "'";
}

rt::Status writePlan(const TrialPlan& plan) {
  nlohmann::json sweep = nlohmann::json::array();
  for (const SweepKey& k : plan.sweep) sweep.push_back({{"key", k.key}, {"values", k.values}});
  nlohmann::json slurm(nullptr);
  if (plan.slurm)
    slurm = {{"partition", plan.slurm->partition},
             {"time_limit_min", plan.slurm->time_limit_min},
             {"memory_mb", plan.slurm->memory_mb},
             {"max_running", plan.slurm->max_running},
             {"options", plan.slurm->options}};
  const nlohmann::json json = {{"format", kPlanFormat},
                               {"kind", plan.kind},
                               {"out_dir", plan.out_dir},
                               {"binary", plan.binary},
                               {"suite", suiteToJson(plan.suite)},
                               {"cell_errors", plan.cell_errors},
                               {"sweep", sweep},
                               {"bench", plan.bench},
                               {"slurm", slurm},
                               {"trials", plan.trials.size()}};
  // One line per trial: the folder made, an old result removed (a trial that fails must not leave the
  // last run's summary to be merged), the program's output in the folder's log.txt.
  std::string lines;
  for (std::size_t i = 0; i < plan.trials.size(); ++i) {
    const std::string& dir = plan.trials[i].dir;
    lines += "mkdir -p " + shellQuote(dir) + " && rm -f " + shellQuote(dir + "/summary.json") + " && exec";
    for (const std::string& a : trialCommand(plan, i)) lines += " " + shellQuote(a);
    lines += " > " + shellQuote(dir + "/log.txt") + " 2>&1\n";
  }
  const std::string script =
      "#!/bin/sh\n"
      "# Runs trial INDEX (0-based) of " +
      plan.out_dir +
      "/plan.json: line INDEX + 1 of trials.txt.\n"
      "# Written by `aerotrack bench`; any batch engine can call it (docs/scale-out.md).\n"
      "# usage: run_trial.sh INDEX\n"
      "set -eu\n"
      "case ${1:-} in ''|*[!0-9]*) echo \"run_trial.sh: expected a trial index, got '${1:-}'\" >&2; exit 2 ;; esac\n"
      "line=$(sed -n \"$(( $1 + 1 ))p\" " +
      shellQuote(plan.out_dir + "/trials.txt") +
      ")\n"
      "[ -n \"$line\" ] || { echo \"run_trial.sh: no trial $1 in " +
      plan.out_dir +
      "/trials.txt\" >&2; exit 2; }\n"
      "exec sh -c \"$line\"\n";
  if (auto s = writeAtomically(plan.out_dir + "/trials.txt", lines); !s) return s;
  if (auto s = writeAtomically(plan.out_dir + "/run_trial.sh", script); !s) return s;
  std::error_code ec;
  std::filesystem::permissions(plan.out_dir + "/run_trial.sh", std::filesystem::perms::owner_exec,
                               std::filesystem::perm_options::add, ec);
  return writeAtomically(plan.out_dir + "/plan.json", json.dump(1) + "\n");
}

rt::Expected<TrialPlan> readPlan(const std::string& dir) {
  const std::string path = dir + "/plan.json";
  auto text = rt::readBoundedFile(path, kMaxPlanBytes);
  if (!text) return text.error();
  const nlohmann::json json = nlohmann::json::parse(*text, nullptr, /*allow_exceptions=*/false);
  if (json.is_discarded()) return rt::Error{path + ": not valid JSON (cut off?)"};
  if (!json.is_object() || json.value("format", "") != kPlanFormat)
    return rt::Error{path + ": not a trial plan of this version (format " + std::string(kPlanFormat) + ")"};
  try {
    TrialPlan plan;
    plan.kind = json.at("kind").get<std::string>();
    if (plan.kind != "bench" && plan.kind != "suite") return rt::Error{path + ": kind: expected bench or suite"};
    plan.out_dir = json.at("out_dir").get<std::string>();
    plan.binary = json.at("binary").get<std::string>();
    plan.suite = suiteFromJson(json.at("suite"));
    plan.cell_errors = json.at("cell_errors").get<std::vector<std::string>>();
    for (const nlohmann::json& k : json.at("sweep"))
      plan.sweep.push_back({k.at("key").get<std::string>(), k.at("values").get<std::vector<std::string>>()});
    plan.bench = json.at("bench");
    if (const nlohmann::json& s = json.at("slurm"); !s.is_null())
      plan.slurm = SlurmSettings{s.at("partition").get<std::string>(), s.at("time_limit_min").get<int>(),
                                 s.at("memory_mb").get<int>(), s.at("max_running").get<int>(),
                                 s.at("options").get<std::vector<std::string>>()};
    planTrials(plan);
    if (plan.trials.size() != json.at("trials").get<std::size_t>())
      return rt::Error{path + ": trials: " + std::to_string(json.at("trials").get<std::size_t>()) +
                       " written, but its cells make " + std::to_string(plan.trials.size())};
    // The plan may have moved with its folder (a copy from the cluster): trials live under `dir`.
    if (std::filesystem::weakly_canonical(dir) != std::filesystem::weakly_canonical(plan.out_dir)) {
      plan.out_dir = std::filesystem::absolute(dir).lexically_normal().string();
      planTrials(plan);
    }
    return plan;
  } catch (const std::exception& e) {
    return rt::Error{path + ": " + e.what()};
  }
}

TrialState trialState(const std::string& trial_dir, const std::string& engine_log) {
  if (trialComplete(trial_dir)) return {true, ""};
  // What the batch engine says about the trial comes first: it knows why a process vanished.
  if (!engine_log.empty()) {
    if (fileContains(engine_log, "DUE TO TIME LIMIT"))
      return {false, "killed by Slurm: time limit (" + engine_log + ")"};
    if (fileContains(engine_log, "memory limit") || fileContains(engine_log, "oom-kill"))
      return {false, "killed by Slurm: out of memory (" + engine_log + ")"};
    if (fileContains(engine_log, "CANCELLED")) return {false, "cancelled (" + engine_log + ")"};
  }
  std::error_code ec;
  if (!std::filesystem::exists(trial_dir, ec)) return {false, "not started"};
  const std::string summary = trial_dir + "/summary.json";
  if (std::filesystem::exists(summary, ec)) {
    std::ifstream in(summary);
    const nlohmann::json s = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
    if (s.is_object() && s.value("interrupted", false))
      return {false, "interrupted before the end (stopped by a signal; summary.json says so)"};
    return {false, "summary.json is incomplete or not a summary (the trial was killed while writing it?)"};
  }
  if (const std::string error = lastLineStarting(trial_dir + "/log.txt", "aerotrack"); !error.empty())
    return {false, "failed: " + error};
  if (std::filesystem::exists(trial_dir + "/log.txt", ec))
    return {false, "no summary.json: still running, or killed (see " + trial_dir + "/log.txt)"};
  return {false, "no summary.json and no log.txt"};
}

}  // namespace aerotrack::app
