// `aerotrack run --config FILE [--print-config] [--duration-s S]`: the onboard executable. Devices
// from config, every task on the real-time executor, until SIGINT/SIGTERM (or the duration). Under
// systemd (tools/systemd/aerotrack.service) it reports READY=1 once the tasks run and pings the watchdog
// only while every periodic task keeps stepping: a wedged task gets the service restarted.
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "aerotrack/rt/realtime_executor.hpp"
#include "commands.hpp"
#include "report.hpp"
#include "run_executors.hpp"
#include "signals.hpp"
#include "sim_report.hpp"
#include "system.hpp"
#include "systemd_notify.hpp"

namespace aerotrack::app {

int runCommand(const ParsedArgs& args) {
  const auto overrides = configOverrides(args);
  if (!overrides) return failCommand("run", overrides.error().message);
  auto config = loadAppConfig(args.values.at("config"), *overrides);
  if (config) {
    config->record_dir = args.valueOr("record", "");
    config->mcap_path = args.valueOr("mcap", "");
    config->mcap_compression = args.valueOr("mcap-compression", "zstd");
    config->live_address = args.valueOr("live", "");
    config->hal.replay.start_at_first_use = true;  // a replayed device starts with the tasks, not at build
  }
  if (!config) {
    std::fprintf(stderr, "aerotrack run: %s\n", config.error().message.c_str());
    return 1;
  }
  if (args.flags.count("print-config") != 0) {
    std::fputs(toYaml(*config).c_str(), stdout);
    return 0;
  }
  double duration_s = 0.0;  // 0: until a signal
  if (args.has("duration-s")) {
    const auto d = parseDouble("duration-s", args.values.at("duration-s"), 0.0, 1e7);
    if (!d) {
      std::fprintf(stderr, "aerotrack run: %s\n", d.error().message.c_str());
      return 1;
    }
    duration_s = *d;
  }

  std::atomic<bool> stop{false};
  SignalWatcher signals(stop);  // before any thread starts
  const rt::MonotonicClock clock;
  std::optional<hal::sim::ScenarioInstance> trial;
  if (config->hal.usesSim()) {
    auto loaded = loadTrial(config->sim.scenario, config->sim.seed, std::nullopt);
    if (!loaded) {
      std::fprintf(stderr, "aerotrack run: %s\n", loaded.error().message.c_str());
      return 1;
    }
    trial = std::move(loaded.value());
  }
  const rt::TimeNs start_ns = clock.now();  // the simulation's origin (its fault windows count from it)
  auto system = System::build(*config, trial ? &*trial : nullptr, start_ns);
  if (!system) {
    std::fprintf(stderr, "aerotrack run: %s\n", system.error().message.c_str());
    return 1;
  }
  rt::RealtimeExecutor executor(clock, (*system)->realtimeOptions());
  for (const rt::TaskBinding& b : (*system)->bindings()) {
    if (const rt::Status s = executor.add(b); !s) {
      std::fprintf(stderr, "aerotrack run: %s\n", s.error().message.c_str());
      return 1;
    }
  }
  (*system)->watchTimings(executor.stats());
  if (const rt::Status s = applyTaskOverrun(**system, executor, start_ns); !s) {
    std::fprintf(stderr, "aerotrack run: %s\n", s.error().message.c_str());
    return 1;
  }
  const auto warnings = executor.start();
  if (!warnings) {
    std::fprintf(stderr, "aerotrack run: %s\n", warnings.error().message.c_str());
    return 1;
  }
  for (const std::string& w : *warnings) std::fprintf(stderr, "aerotrack run: warning: %s\n", w.c_str());
  std::fprintf(stderr, "aerotrack run: %zu tasks running (%s); Ctrl-C stops\n", (*system)->bindings().size(),
               config->source.c_str());

  const SystemdNotifier systemd = SystemdNotifier::fromEnvironment(
      std::getenv("NOTIFY_SOCKET"), std::getenv("WATCHDOG_USEC"), std::getenv("WATCHDOG_PID"), ::getpid());
  const rt::DurationNs ping_period_ns = systemd.watchdogTimeoutNs() / 2;
  // The tasks the watchdog watches: periodic ones that step at least twice between pings.
  std::vector<const rt::TimingStats*> watched;
  for (const rt::TaskSet::NamedStats& s : executor.stats()) {
    for (const rt::TaskBinding& b : (*system)->bindings())
      if (b.spec.name == s.name && b.spec.rate_hz * rt::nsToSeconds(ping_period_ns) >= 2.0) watched.push_back(s.stats);
  }
  TaskLiveness liveness;
  const auto counts = [&watched] {
    std::vector<std::uint64_t> c;
    c.reserve(watched.size());
    for (const rt::TimingStats* s : watched) c.push_back(s->execution().count());
    return c;
  };
  liveness.allAdvanced(counts());
  if (const rt::Status s = systemd.notify("READY=1\nSTATUS=tasks running"); !s)
    std::fprintf(stderr, "aerotrack run: warning: %s\n", s.error().message.c_str());

  const rt::TimeNs end_ns = duration_s > 0.0 ? clock.now() + rt::secondsToNs(duration_s) : 0;
  rt::TimeNs next_ping_ns = clock.now() + ping_period_ns;
  while (!stop.load() && (end_ns == 0 || clock.now() < end_ns)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (ping_period_ns > 0 && clock.now() >= next_ping_ns) {
      next_ping_ns += ping_period_ns;
      if (liveness.allAdvanced(counts())) {
        (void)systemd.notify("WATCHDOG=1");  // a lost ping is what the watchdog is for
      } else {
        std::fprintf(stderr, "aerotrack run: a periodic task has stopped stepping: no watchdog ping\n");
      }
    }
  }
  (void)systemd.notify("STOPPING=1");
  executor.requestStop();
  executor.join();

  std::fputs(timingTable(snapshotTimings(executor.stats())).c_str(), stdout);
  std::fputs(deviceHealthReport((*system)->devices(), clock.now()).c_str(), stdout);
  if (auto recorded = (*system)->finishRecording(clock.now()); !recorded) {
    std::fprintf(stderr, "aerotrack run: %s\n", recorded.error().message.c_str());
  } else if (!recorded->empty()) {
    std::printf("%s\n", recorded->c_str());
  }
  if (const std::string logged = (*system)->finishFlightLog(); !logged.empty()) std::printf("%s\n", logged.c_str());
  if (signals.received() == 0) return 0;
  std::fprintf(stderr, "aerotrack run: stopped by signal %d\n", signals.received());
  return signals.stoppedStatus();  // systemd's unit lists 143 as a clean stop (SuccessExitStatus)
}

}  // namespace aerotrack::app
