// Wake-up jitter of the real-time executor: one periodic task at 200 Hz for 5 s; counters give
// how late the task woke relative to its absolute release time (p50, p99, max, microseconds)
// and the missed deadlines. Without SCHED_FIFO permission the thread runs at normal priority
// (the warning is printed), which is what a shared CI machine measures.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "aerotrack/rt/realtime_executor.hpp"

namespace {

using namespace aerotrack::rt;

class Nop final : public Task {
 public:
  void step(TimeNs now_ns) override { benchmark::DoNotOptimize(now_ns); }
};

void BM_RealtimeExecutorJitter200Hz(benchmark::State& state) {
  for (auto _ : state) {
    MonotonicClock clock;
    RealtimeOptions options;
    options.lock_memory = false;
    RealtimeExecutor executor(clock, options);
    Nop task;
    TaskSpec spec;
    spec.name = "jitter";
    spec.rate_hz = 200.0;
    spec.budget_ms = 1.0;
    spec.priority = 80;
    if (!executor.add({spec, &task, nullptr})) state.SkipWithError("add failed");
    const auto warnings = executor.start();
    if (!warnings) state.SkipWithError(warnings.error().message.c_str());
    for (const auto& w : *warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    std::this_thread::sleep_for(std::chrono::seconds(5));
    executor.requestStop();
    executor.join();
    const TimingStats& s = *executor.stats()[0].stats;
    state.counters["wakeups"] = static_cast<double>(s.wakeLatency().count());
    state.counters["p50_us"] = s.wakeLatency().quantileNs(0.50) / 1e3;
    state.counters["p99_us"] = s.wakeLatency().quantileNs(0.99) / 1e3;
    state.counters["max_us"] = s.wakeLatency().maxNs() / 1e3;
    state.counters["missed"] = static_cast<double>(s.snapshot().missed_deadlines);
  }
}
BENCHMARK(BM_RealtimeExecutorJitter200Hz)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace
