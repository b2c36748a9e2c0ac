// Running a built System to an end time on either executor, for the commands that do (sim, replay):
// lockstep on a ManualClock (deterministic, as fast as the CPU allows; RunInfo gets the trace hash)
// or at 1x on the real-time executor.
#pragma once

#include <atomic>

#include "aerotrack/rt/clock.hpp"
#include "aerotrack/rt/lockstep_executor.hpp"
#include "aerotrack/rt/realtime_executor.hpp"
#include "sim_report.hpp"
#include "system.hpp"

namespace aerotrack::app {

/// Runs every task of system on the lockstep executor until end_ns (or stop); fills info's times,
/// timings and trace hash. A configured task overrun (sim.faults.task_overrun) stalls its task there.
rt::Status runLockstep(System& system, rt::ManualClock& clock, rt::TimeNs end_ns, const std::atomic<bool>& stop,
                       RunInfo& info);

/// The configured task overrun (sim.faults.task_overrun), if any, as a stall of its task on the executor
/// (with its tasks added, before it runs); start_ns: the run's time origin (the sim's fault windows').
/// Lockstep: the stall's missed deadlines also reach the supervisor's overrun-storm counter.
rt::Status applyTaskOverrun(System& system, rt::LockstepExecutor& executor, rt::TimeNs start_ns);
rt::Status applyTaskOverrun(System& system, rt::RealtimeExecutor& executor, rt::TimeNs start_ns);

/// Runs every task of system on the real-time executor from now until end_ns (or stop).
rt::Status runRealtime(System& system, const rt::MonotonicClock& clock, rt::TimeNs start_ns, rt::TimeNs end_ns,
                       const std::atomic<bool>& stop, RunInfo& info, const char* command);

}  // namespace aerotrack::app
