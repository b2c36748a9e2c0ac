// Slurm job arrays: see slurm_executor.hpp.
#include "slurm_executor.hpp"

#include <pwd.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include "subprocess.hpp"

namespace aerotrack::app {
namespace {

/// Slurm's default MaxArraySize (slurm.conf(5)); used when scontrol cannot say.
constexpr std::size_t kDefaultMaxArraySize = 1001;

std::string slurmDir(const TrialPlan& plan) {
  return plan.out_dir + "/slurm";
}

/// MaxArraySize from `scontrol show config`, or Slurm's default.
std::size_t maxArraySize() {
  const auto shown = runProcess({"scontrol", "show", "config"});
  if (!shown || shown->exit_status != 0) return kDefaultMaxArraySize;
  std::istringstream lines(shown->out);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind("MaxArraySize", 0) != 0) continue;
    const std::size_t eq = line.find('=');
    if (eq == std::string::npos) break;
    const std::size_t value = std::strtoull(line.c_str() + eq + 1, nullptr, 10);
    return value > 1 ? value : kDefaultMaxArraySize;
  }
  return kDefaultMaxArraySize;
}

rt::Status writeArrayScript(const TrialPlan& plan) {
  const std::string path = slurmDir(plan) + "/array.sh";
  std::ofstream out(path, std::ios::trunc);
  out << "#!/bin/bash\n"
         "# One trial of "
      << plan.out_dir
      << "/plan.json per Slurm array task (written by `aerotrack bench --executor slurm`).\n"
         "# The trial index is AEROTRACK_TRIAL_BASE + SLURM_ARRAY_TASK_ID (an array's task ids stay below\n"
         "# MaxArraySize; DIR/slurm/jobs.txt lists each array's base and trials).\n"
         "set -eu\n"
         "index=$(( ${AEROTRACK_TRIAL_BASE:-0} + SLURM_ARRAY_TASK_ID ))\n"
         "echo \"aerotrack trial $index: job ${SLURM_ARRAY_JOB_ID:-?} task ${SLURM_ARRAY_TASK_ID} on $(hostname)\"\n"
         "exec /bin/sh "
      << shellQuote(plan.out_dir + "/run_trial.sh") << " \"$index\"\n";
  out.close();
  if (!out) return rt::Error{path + ": write failed"};
  return rt::ok();
}

std::string currentUser() {
  std::vector<char> buffer(16384);
  passwd entry{};
  passwd* found = nullptr;
  if (getpwuid_r(getuid(), &entry, buffer.data(), buffer.size(), &found) == 0 && found != nullptr)
    return found->pw_name;
  return std::to_string(getuid());
}

}  // namespace

std::string compressIndices(const std::vector<std::size_t>& indices) {
  std::string out;
  for (std::size_t i = 0; i < indices.size();) {
    std::size_t j = i;
    while (j + 1 < indices.size() && indices[j + 1] == indices[j] + 1) ++j;
    if (!out.empty()) out += ',';
    out += std::to_string(indices[i]);
    if (j > i) out += "-" + std::to_string(indices[j]);
    i = j + 1;
  }
  return out;
}

std::vector<std::pair<std::size_t, std::vector<std::size_t>>> splitIntoArrays(const std::vector<std::size_t>& indices,
                                                                              std::size_t max_array_size) {
  std::vector<std::pair<std::size_t, std::vector<std::size_t>>> arrays;
  for (const std::size_t index : indices) {
    if (arrays.empty() || index - arrays.back().first >= max_array_size) arrays.push_back({index, {}});
    arrays.back().second.push_back(index - arrays.back().first);
  }
  return arrays;
}

rt::Expected<std::vector<std::string>> submitToSlurm(const TrialPlan& plan, const std::vector<std::size_t>& indices) {
  if (!plan.slurm) return rt::Error{"the plan has no Slurm settings"};
  const SlurmSettings& s = *plan.slurm;
  std::error_code ec;
  std::filesystem::create_directories(slurmDir(plan) + "/logs", ec);
  if (ec) return rt::Error{slurmDir(plan) + "/logs: cannot create directory: " + ec.message()};
  if (auto written = writeArrayScript(plan); !written) return written.error();
  std::vector<std::string> jobs;
  std::string previous;
  for (const auto& [base, task_ids] : splitIntoArrays(indices, maxArraySize())) {
    std::vector<std::string> argv{"sbatch",
                                  "--parsable",
                                  "--job-name=aerotrack-" + plan.suite.name,
                                  "--array=" + compressIndices(task_ids) + "%" + std::to_string(s.max_running),
                                  "--output=" + slurmDir(plan) + "/logs/job%A-task%a.log",
                                  "--time=" + std::to_string(s.time_limit_min),
                                  "--mem=" + std::to_string(s.memory_mb),
                                  "--cpus-per-task=1",
                                  "--export=ALL,AEROTRACK_TRIAL_BASE=" + std::to_string(base)};
    if (!s.partition.empty()) argv.push_back("--partition=" + s.partition);
    if (!previous.empty()) argv.push_back("--dependency=afterany:" + previous);
    argv.insert(argv.end(), s.options.begin(), s.options.end());  // after ours: sbatch takes the last
    argv.push_back(slurmDir(plan) + "/array.sh");
    // An array after the first that cannot be submitted leaves the earlier ones running: say which.
    std::string earlier;
    for (const std::string& j : jobs) earlier += (earlier.empty() ? " (already submitted: job " : ", ") + j;
    if (!earlier.empty()) earlier += "; scancel them, or merge what they finish)";
    const auto ran = runProcess(argv);
    if (!ran)
      return rt::Error{ran.error().message + " (is Slurm's client installed? or use --executor local)" + earlier};
    if (ran->exit_status != 0) {
      std::string said = firstLine(ran->err);
      if (said.empty()) said = firstLine(ran->out);
      std::string message = "sbatch failed (exit status " + std::to_string(ran->exit_status) + "): ";
      message += said;
      message += earlier;
      return rt::Error{message};
    }
    std::string id = firstLine(ran->out);
    id = id.substr(0, id.find(';'));  // "JOBID;CLUSTER" on a federation
    if (id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
      return rt::Error{"sbatch: expected a job id, got '" + firstLine(ran->out) + "'"};
    std::ofstream record(slurmDir(plan) + "/jobs.txt", std::ios::app);
    record << id << " " << base << " ";
    for (std::size_t i = 0; i < task_ids.size(); ++i) record << (i > 0 ? "," : "") << base + task_ids[i];
    record << "\n";
    if (!record) return rt::Error{slurmDir(plan) + "/jobs.txt: write failed (job " + id + " was submitted)"};
    jobs.push_back(id);
    previous = id;
  }
  return jobs;
}

rt::Status waitForSlurm(const TrialPlan& plan, const std::vector<std::string>& jobs,
                        const std::vector<std::size_t>& indices, const std::atomic<bool>& stop) {
  const std::set<std::string> ours(jobs.begin(), jobs.end());
  const std::string user = currentUser();
  int failures = 0;
  std::size_t reported = SIZE_MAX;
  // Each poll looks only at the submitted trials not yet seen finished: a finished summary is parsed once,
  // not once every two seconds for every trial of a large plan.
  std::vector<std::size_t> pending = indices;
  std::size_t finished = 0;
  while (!stop.load()) {
    const auto listed = runProcess({"squeue", "-h", "-u", user, "-o", "%F"});
    if (!listed || listed->exit_status != 0) {
      // A controller restarting is brief; one that stays away for a minute is an error.
      if (++failures >= 30)
        return rt::Error{"squeue keeps failing (" + (listed ? firstLine(listed->err) : listed.error().message) +
                         "); the jobs may still run: `aerotrack bench merge " + plan.out_dir +
                         "` merges what finished"};
    } else {
      failures = 0;
      bool queued = false;
      std::istringstream lines(listed->out);
      std::string line;
      while (std::getline(lines, line) && !queued) queued = ours.count(line.substr(0, line.find_first_of(" \t"))) != 0;
      const auto done = std::remove_if(pending.begin(), pending.end(),
                                       [&](std::size_t i) { return trialComplete(plan.trials.at(i).dir); });
      finished += static_cast<std::size_t>(pending.end() - done);
      pending.erase(done, pending.end());
      if (finished != reported) {
        std::printf("slurm: %zu/%zu submitted trials finished\n", finished, indices.size());
        std::fflush(stdout);
        reported = finished;
      }
      if (!queued) return rt::ok();
    }
    for (int i = 0; i < 20 && !stop.load(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return rt::ok();
}

std::map<std::size_t, std::string> slurmLogs(const TrialPlan& plan) {
  std::map<std::size_t, std::string> logs;
  std::ifstream in(slurmDir(plan) + "/jobs.txt");
  std::string job, list;
  std::size_t base = 0;
  while (in >> job >> base >> list) {
    std::istringstream items(list);
    std::string item;
    while (std::getline(items, item, ',')) {
      const std::size_t index = std::strtoull(item.c_str(), nullptr, 10);
      logs[index] = slurmDir(plan) + "/logs/job" + job + "-task" + std::to_string(index - base) + ".log";
    }
  }
  return logs;
}

}  // namespace aerotrack::app
