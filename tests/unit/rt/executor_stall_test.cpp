// LockstepExecutor::stall (issue 23's fault matrix: a task overrunning its budget): when the stalled
// task runs, when its outputs appear, what it misses meanwhile, and that a stall is as deterministic
// as the rest of the lockstep run.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "aerotrack/rt/doorbell.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/lockstep_executor.hpp"
#include "aerotrack/rt/realtime_executor.hpp"

// Its own namespace: the unity build joins this file with executor_test.cpp's anonymous namespace.
namespace aerotrack::rt::stall_test {
namespace {

constexpr TimeNs kMs = kNsPerMillisecond;

/// Records the time each step is given and the simulated clock's time when it runs.
class RecordingTask final : public Task {
 public:
  explicit RecordingTask(const Clock& clock) : clock_(clock) {}
  void step(TimeNs now_ns) override {
    times.push_back(now_ns);
    clock_at_step.push_back(clock_.now());
  }
  std::vector<TimeNs> times;
  std::vector<TimeNs> clock_at_step;

 private:
  const Clock& clock_;
};

/// Gathers its release time, publishes it: what its readers see is the release their data is from.
class StampTask final : public OverlappedTask {
 public:
  explicit StampTask(LatestSlot<TimeNs>& out) : out_(out) {}
  bool gather(TimeNs now_ns) override {
    gathered_ns_ = now_ns;
    return true;
  }
  void work() override {}
  void publish(TimeNs publish_ns) override {
    out_.write(gathered_ns_);
    published.push_back({gathered_ns_, publish_ns});
  }
  std::vector<std::pair<TimeNs, TimeNs>> published;  // (gathered at, published at)

 private:
  LatestSlot<TimeNs>& out_;
  TimeNs gathered_ns_ = 0;
};

TaskSpec spec(const std::string& name, double rate_hz) {
  TaskSpec s;
  s.name = name;
  s.rate_hz = rate_hz;
  s.budget_ms = 1.0;
  return s;
}

std::uint64_t missed(const LockstepExecutor& ex, const std::string& name) {
  for (const TaskSet::NamedStats& s : ex.stats())
    if (s.name == name) return s.stats->snapshot().missed_deadlines;
  return ~0ULL;
}

TEST(LockstepStall, GivenAPlainTaskStalledTwoSecondsThenItsStepRunsAtTheStallsEndAndItsPeriodsAreMissedWhenItRuns) {
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  RecordingTask task(clock);
  RecordingTask other(clock);
  std::atomic<std::uint64_t> misses{0};
  ASSERT_TRUE(ex.add({spec("planner", 10), &task, nullptr}));
  ASSERT_TRUE(ex.add({spec("other", 100), &other, nullptr}));
  ex.countMissedDeadlinesIn(&misses);
  ASSERT_TRUE(ex.stall("planner", 250 * kMs, 2250 * kMs, 2000 * kMs));  // the release at 300 ms takes 2 s
  ASSERT_TRUE(ex.runUntil(2200 * kMs));
  EXPECT_EQ(misses.load(), 0U);  // counted when the late step returns, as on the real-time executor
  ASSERT_TRUE(ex.runUntil(2600 * kMs));
  // The late step carries its release's time (300 ms) and runs when the stall ends.
  EXPECT_EQ(task.times, (std::vector<TimeNs>{0, 100 * kMs, 200 * kMs, 300 * kMs, 2400 * kMs, 2500 * kMs, 2600 * kMs}));
  EXPECT_EQ(task.clock_at_step[3], 2300 * kMs);
  EXPECT_EQ(missed(ex, "planner"), 19U);  // 400 ... 2200 ms went unserved
  EXPECT_EQ(misses.load(), 19U);
  EXPECT_EQ(missed(ex, "other"), 0U);
  EXPECT_EQ(other.times.size(), 261U);  // the other task never waited
}

TEST(LockstepStall, GivenAPlainTaskSlowedInAWindowThenEachReleaseInItRunsLateAndTheRestOnTime) {
  // 10 Hz; releases in [200, 600) ms take 150 ms each: 200 runs at 350, the grid shifts to 450, which runs
  // at 600; from 700 on, on time.
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  RecordingTask task(clock);
  ASSERT_TRUE(ex.add({spec("planning", 10), &task, nullptr}));
  ASSERT_TRUE(ex.stall("planning", 200 * kMs, 600 * kMs, 150 * kMs));
  ASSERT_TRUE(ex.runUntil(800 * kMs));
  EXPECT_EQ(task.times, (std::vector<TimeNs>{0, 100 * kMs, 200 * kMs, 450 * kMs, 700 * kMs, 800 * kMs}));
  EXPECT_EQ(task.clock_at_step, (std::vector<TimeNs>{0, 100 * kMs, 350 * kMs, 600 * kMs, 700 * kMs, 800 * kMs}));
  EXPECT_EQ(missed(ex, "planning"), 2U);  // 300 and 500 ms
}

TEST(LockstepStall, GivenAnOverlappedTaskStalledThenItsOldResultAppearsLateAndItsGridResumes) {
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  LatestSlot<TimeNs> slot;
  StampTask mapper(slot);
  TaskSpec s = spec("mapping", 10);
  s.budget_ms = 20.0;
  s.latency_ms = 10.0;
  ASSERT_TRUE(ex.add({s, &mapper, nullptr}));
  ASSERT_TRUE(ex.stall("mapping", 200 * kMs, 650 * kMs, 450 * kMs));
  ASSERT_TRUE(ex.runUntil(1000 * kMs));
  const std::vector<std::pair<TimeNs, TimeNs>> expected{
      {0, 10 * kMs},          {100 * kMs, 110 * kMs}, {200 * kMs, 650 * kMs},   // gathered at 200, out 450 ms later
      {700 * kMs, 710 * kMs}, {800 * kMs, 810 * kMs}, {900 * kMs, 910 * kMs}};  // back on the grid
  EXPECT_EQ(mapper.published, expected);
  EXPECT_EQ(missed(ex, "mapping"), 4U);  // 300 ... 600 ms
}

TEST(LockstepStall, GivenATriggeredTaskStalledThenRingsDuringTheStallAreServedAtItsEnd) {
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  LatestSlot<TimeNs> slot;
  Doorbell bell;
  slot.attachDoorbell(&bell);
  class Writer final : public Task {
   public:
    explicit Writer(LatestSlot<TimeNs>& out) : out_(out) {}
    void step(TimeNs now_ns) override { out_.write(now_ns); }

   private:
    LatestSlot<TimeNs>& out_;
  } writer(slot);
  RecordingTask reader(clock);
  TaskSpec r;
  r.name = "target";
  r.trigger = "slot";
  r.budget_ms = 1.0;
  ASSERT_TRUE(ex.add({spec("writer", 20), &writer, nullptr}));
  ASSERT_TRUE(ex.add({r, &reader, &bell}));
  ASSERT_TRUE(ex.stall("target", 100 * kMs, 220 * kMs, 120 * kMs));  // the run at 100 ms takes until 220 ms
  ASSERT_TRUE(ex.runUntil(300 * kMs));
  EXPECT_EQ(reader.times, (std::vector<TimeNs>{0, 50 * kMs, 100 * kMs, 250 * kMs, 300 * kMs}));
  EXPECT_EQ(reader.clock_at_step, (std::vector<TimeNs>{0, 50 * kMs, 220 * kMs, 250 * kMs, 300 * kMs}));
}

TEST(LockstepStall, GivenTheSameStallThenTwoRunsAreIdenticalAndDifferFromNoStall) {
  auto trace = [](bool with_stall) {
    ManualClock clock(0);
    MonotonicClock wall;
    LockstepExecutor ex(clock, wall);
    RecordingTask a(clock);
    RecordingTask b(clock);
    EXPECT_TRUE(ex.add({spec("a", 30), &a, nullptr}));
    EXPECT_TRUE(ex.add({spec("b", 100), &b, nullptr}));
    if (with_stall) {
      EXPECT_TRUE(ex.stall("a", 500 * kMs, 1277 * kMs, 777 * kMs));
    }
    EXPECT_TRUE(ex.runUntil(3 * kNsPerSecond));
    return ex.traceHash();
  };
  EXPECT_EQ(trace(true), trace(true));
  EXPECT_NE(trace(true), trace(false));
}

TEST(LockstepStall, GivenAnUnknownTaskOrANonPositiveTimeOrASecondStallThenOneLineErrors) {
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  RecordingTask a(clock);
  ASSERT_TRUE(ex.add({spec("planning", 10), &a, nullptr}));
  const Status unknown = ex.stall("planer", 0, kMs, kMs);
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error().message, "stall: no task named 'planer' (tasks: planning)");
  EXPECT_FALSE(ex.stall("planning", 0, kMs, 0));
  EXPECT_FALSE(ex.stall("planning", kMs, kMs, kMs));
  EXPECT_TRUE(ex.stall("planning", 0, kMs, kMs));
  EXPECT_FALSE(ex.stall("planning", 5 * kMs, 6 * kMs, kMs));
}

TEST(RealtimeStall, GivenAPeriodicTaskStalledThenItsStepKeepsItsWakeTimeAndItsOverrunIsCountedMissed) {
  // 20 Hz, the release at or after 100 ms held up 300 ms. Wall-clock: only bounds a slow machine keeps.
  const MonotonicClock clock;
  std::atomic<std::uint64_t> misses{0};
  RealtimeOptions options;
  options.use_realtime_priority = false;
  options.use_affinity = false;
  options.lock_memory = false;
  options.deadline_misses = &misses;
  RealtimeExecutor ex(clock, options);
  RecordingTask task(clock);
  ASSERT_TRUE(ex.add({spec("planning", 20), &task, nullptr}));
  const TimeNs start_ns = clock.now();
  ASSERT_TRUE(ex.stall("planning", start_ns + 100 * kMs, start_ns + 400 * kMs, 300 * kMs));
  EXPECT_FALSE(ex.stall("planning", start_ns, start_ns + kMs, kMs));  // one stall a task
  EXPECT_FALSE(ex.stall("mapping", start_ns, start_ns + kMs, kMs));
  ASSERT_TRUE(ex.start());
  while (clock.now() < start_ns + 700 * kMs) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ex.requestStop();
  ex.join();
  std::size_t stalled = task.times.size();
  for (std::size_t i = 0; i < task.times.size(); ++i) {
    if (task.clock_at_step[i] - task.times[i] >= 300 * kMs) {
      stalled = i;
      break;
    }
  }
  ASSERT_LT(stalled, task.times.size()) << "no step ran 300 ms after its wake-up";
  EXPECT_GE(task.times[stalled], start_ns + 100 * kMs);
  for (std::size_t i = 0; i < task.times.size(); ++i) {
    if (i != stalled) {
      EXPECT_LT(task.clock_at_step[i] - task.times[i], 300 * kMs) << "only one stall";
    }
  }
  EXPECT_GE(misses.load(), 5U);                                       // 300 ms of a 50 ms period
  EXPECT_FALSE(ex.stall("planning", start_ns, start_ns + kMs, kMs));  // not after start()
}

}  // namespace
}  // namespace aerotrack::rt::stall_test
