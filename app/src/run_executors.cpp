// Executor runners: see run_executors.hpp.
#include "run_executors.hpp"

#include <chrono>
#include <cstdio>
#include <thread>

#include "aerotrack/rt/lockstep_executor.hpp"
#include "aerotrack/rt/realtime_executor.hpp"
#include "report.hpp"

namespace aerotrack::app {
namespace {

rt::Status addAll(System& system, auto& executor) {
  for (const rt::TaskBinding& b : system.bindings())
    if (rt::Status s = executor.add(b); !s) return s;
  system.watchTimings(executor.stats());
  return rt::ok();
}

/// The fault matrix's task overrun (issue 23): the named task's releases in the window (seconds since
/// start_ns, as the sim's fault windows) take run_ms each, or one stall of the window's length. Only
/// the drone's own tasks: stalling the simulated world would stop physics, not the drone.
rt::Status stallTask(System& system, auto& executor, rt::TimeNs start_ns) {
  const hal::SimConfig::TaskOverrun& overrun = system.config().sim.task_overrun;
  if (overrun.task.empty() || !system.config().hal.usesSim()) return rt::ok();
  if (overrun.task == "sim_world")
    return rt::Error{"sim.faults.task_overrun.task: sim_world is the simulated world, not a task of the drone"};
  const rt::TimeNs from_ns = start_ns + rt::secondsToNs(overrun.window.begin_s);
  const rt::TimeNs until_ns = start_ns + rt::secondsToNs(overrun.window.end_s);
  const rt::DurationNs run_ns = overrun.run_ms > 0.0 ? rt::secondsToNs(overrun.run_ms / 1000.0) : until_ns - from_ns;
  const rt::Status s = executor.stall(overrun.task, from_ns, until_ns, run_ns);
  return s ? s : rt::Status{rt::Error{"sim.faults.task_overrun: " + s.error().message}};
}

}  // namespace

rt::Status applyTaskOverrun(System& system, rt::LockstepExecutor& executor, rt::TimeNs start_ns) {
  executor.countMissedDeadlinesIn(system.realtimeOptions().deadline_misses);
  return stallTask(system, executor, start_ns);
}

rt::Status applyTaskOverrun(System& system, rt::RealtimeExecutor& executor, rt::TimeNs start_ns) {
  return stallTask(system, executor, start_ns);
}

rt::Status runLockstep(System& system, rt::ManualClock& clock, rt::TimeNs end_ns, const std::atomic<bool>& stop,
                       RunInfo& info) {
  const rt::MonotonicClock wall;
  rt::LockstepExecutor executor(clock, wall);
  if (rt::Status s = addAll(system, executor); !s) return s;
  if (rt::Status s = applyTaskOverrun(system, executor, clock.now()); !s) return s;
  const rt::TimeNs wall_start = wall.now();
  const rt::TimeNs sim_start = clock.now();
  if (rt::Status s = executor.runUntil(end_ns, &stop); !s) return s;
  info.wall_time_s = rt::nsToSeconds(wall.now() - wall_start);
  info.sim_time_s = rt::nsToSeconds(clock.now() - sim_start);
  info.timings = snapshotTimings(executor.stats());
  char hash[32];
  std::snprintf(hash, sizeof(hash), "%016llx", static_cast<unsigned long long>(executor.traceHash()));
  info.trace_hash = hash;
  return rt::ok();
}

rt::Status runRealtime(System& system, const rt::MonotonicClock& clock, rt::TimeNs start_ns, rt::TimeNs end_ns,
                       const std::atomic<bool>& stop, RunInfo& info, const char* command) {
  rt::RealtimeExecutor executor(clock, system.realtimeOptions());
  if (rt::Status s = addAll(system, executor); !s) return s;
  if (rt::Status s = applyTaskOverrun(system, executor, start_ns); !s) return s;
  const auto warnings = executor.start();
  if (!warnings) return warnings.error();
  for (const std::string& w : *warnings) std::fprintf(stderr, "aerotrack %s: warning: %s\n", command, w.c_str());
  while (!stop.load() && clock.now() < end_ns) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  executor.requestStop();
  executor.join();
  info.sim_time_s = rt::nsToSeconds(clock.now() - start_ns);
  info.wall_time_s = info.sim_time_s;
  info.timings = snapshotTimings(executor.stats());
  return rt::ok();
}

}  // namespace aerotrack::app
