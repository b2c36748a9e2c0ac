// Executors: periodic timing on the manual clock, ordering rules, event tasks, lockstep
// determinism (two runs, identical trace hash), and the real-time executor's start/stop and
// overrun accounting.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <random>
#include <thread>
#include <vector>

#include "aerotrack/rt/doorbell.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/lockstep_executor.hpp"
#include "aerotrack/rt/realtime_executor.hpp"
#include "aerotrack/rt/spsc_queue.hpp"

namespace aerotrack::rt {
namespace {

/// Records the times it ran at, and optionally calls a hook.
class RecordingTask final : public Task {
 public:
  explicit RecordingTask(std::vector<std::pair<int, TimeNs>>* log = nullptr, int id = 0) : log_(log), id_(id) {}
  void step(TimeNs now_ns) override {
    times.push_back(now_ns);
    if (log_ != nullptr) log_->push_back({id_, now_ns});
  }
  std::vector<TimeNs> times;

 private:
  std::vector<std::pair<int, TimeNs>>* log_;
  int id_;
};

TaskSpec periodic(const std::string& name, double rate_hz, int priority = 0) {
  TaskSpec s;
  s.name = name;
  s.rate_hz = rate_hz;
  s.budget_ms = 1.0;
  s.priority = priority;
  return s;
}

TaskSpec event(const std::string& name, const std::string& trigger) {
  TaskSpec s;
  s.name = name;
  s.trigger = trigger;
  s.budget_ms = 1.0;
  return s;
}

TEST(TaskSpecValidation, RejectsInconsistentRows) {
  EXPECT_TRUE(validate(periodic("a", 10)));
  TaskSpec both = periodic("a", 10);
  both.trigger = "x";
  EXPECT_FALSE(validate(both));
  TaskSpec neither = periodic("a", 0);
  EXPECT_FALSE(validate(neither));
  TaskSpec no_budget = periodic("a", 10);
  no_budget.budget_ms = 0;
  EXPECT_FALSE(validate(no_budget));
  TaskSpec bad_priority = periodic("a", 10, 100);
  EXPECT_FALSE(validate(bad_priority));
  EXPECT_FALSE(validate(std::vector<TaskSpec>{periodic("a", 10), periodic("a", 20)}));
}

TEST(LockstepExecutor, GivenPeriodicTaskWhenRunOneSecondThenReleasedAtEveryPeriodIncludingEnd) {
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  RecordingTask task;
  ASSERT_TRUE(ex.add({periodic("t", 200), &task, nullptr}));
  ASSERT_TRUE(ex.runUntil(kNsPerSecond));
  ASSERT_EQ(task.times.size(), 201U);  // 0, 5 ms, ..., 1000 ms
  for (std::size_t i = 0; i < task.times.size(); ++i) EXPECT_EQ(task.times[i], static_cast<TimeNs>(i) * 5'000'000);
  EXPECT_EQ(clock.now(), kNsPerSecond);
}

TEST(LockstepExecutor, GivenRunInTwoCallsThenSameStepsAsOneCall) {
  ManualClock clock_a(0), clock_b(0);
  MonotonicClock wall;
  LockstepExecutor a(clock_a, wall), b(clock_b, wall);
  RecordingTask ta, tb;
  ASSERT_TRUE(a.add({periodic("t", 30), &ta, nullptr}));
  ASSERT_TRUE(b.add({periodic("t", 30), &tb, nullptr}));
  ASSERT_TRUE(a.runUntil(2 * kNsPerSecond));
  ASSERT_TRUE(b.runUntil(700'000'000));
  ASSERT_TRUE(b.runUntil(2 * kNsPerSecond));
  EXPECT_EQ(ta.times, tb.times);
  EXPECT_EQ(a.traceHash(), b.traceHash());
}

TEST(LockstepExecutor, GivenSimultaneousReleasesThenHigherPriorityFirstThenTableOrder) {
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  std::vector<std::pair<int, TimeNs>> log;
  RecordingTask low(&log, 1), high(&log, 2), low2(&log, 3);
  ASSERT_TRUE(ex.add({periodic("low", 10, 1), &low, nullptr}));
  ASSERT_TRUE(ex.add({periodic("high", 10, 50), &high, nullptr}));
  ASSERT_TRUE(ex.add({periodic("low2", 10, 1), &low2, nullptr}));
  ASSERT_TRUE(ex.runUntil(0));
  ASSERT_EQ(log.size(), 3U);
  EXPECT_EQ(log[0].first, 2);
  EXPECT_EQ(log[1].first, 1);
  EXPECT_EQ(log[2].first, 3);
}

/// Pushes a counter into a queue each step (the producer of an event chain).
class ProducerTask final : public Task {
 public:
  explicit ProducerTask(SpscQueue<int>& q) : q_(q) {}
  void step(TimeNs) override { q_.try_push(counter_++); }

 private:
  SpscQueue<int>& q_;
  int counter_ = 0;
};

class ConsumerTask final : public Task {
 public:
  explicit ConsumerTask(SpscQueue<int>& q) : q_(q) {}
  void step(TimeNs now_ns) override {
    int v = 0;
    while (q_.try_pop(v)) received.push_back({v, now_ns});
  }
  std::vector<std::pair<int, TimeNs>> received;

 private:
  SpscQueue<int>& q_;
};

TEST(LockstepExecutor, GivenEventTaskWhenProducerPushesThenConsumerRunsAtTheSameInstant) {
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  SpscQueue<int> q(8, OverflowPolicy::kDropNewest);
  Doorbell bell;
  q.attachDoorbell(&bell);
  ProducerTask producer(q);
  ConsumerTask consumer(q);
  ASSERT_TRUE(ex.add({periodic("producer", 10), &producer, nullptr}));
  ASSERT_TRUE(ex.add({event("consumer", "q"), &consumer, &bell}));
  ASSERT_TRUE(ex.runUntil(kNsPerSecond / 2));
  ASSERT_EQ(consumer.received.size(), 6U);  // releases at 0, 100, ..., 500 ms
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(consumer.received[static_cast<std::size_t>(i)].first, i);
    EXPECT_EQ(consumer.received[static_cast<std::size_t>(i)].second, i * 100'000'000LL);
  }
}

TEST(LockstepExecutor, GivenEventTaskWithoutDoorbellThenAddFails) {
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  RecordingTask t;
  EXPECT_FALSE(ex.add({event("e", "x"), &t, nullptr}));
  EXPECT_FALSE(ex.add({periodic("p", 10), nullptr, nullptr}));
  ASSERT_TRUE(ex.add({periodic("p", 10), &t, nullptr}));
  EXPECT_FALSE(ex.add({periodic("p", 20), &t, nullptr}));
}

/// An event task that rings its own doorbell: never quiescent.
class SelfRingingTask final : public Task {
 public:
  explicit SelfRingingTask(Doorbell& bell) : bell_(bell) {}
  void step(TimeNs) override { bell_.ring(); }

 private:
  Doorbell& bell_;
};

TEST(LockstepExecutor, GivenEventTasksThatNeverSettleThenErrorInsteadOfHang) {
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  Doorbell bell;
  SelfRingingTask task(bell);
  RecordingTask tick;
  ASSERT_TRUE(ex.add({periodic("tick", 10), &tick, nullptr}));
  ASSERT_TRUE(ex.add({event("loop", "self"), &task, &bell}));
  bell.ring();
  const Status s = ex.runUntil(kNsPerSecond);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("kept triggering"), std::string::npos);
}

TEST(LockstepExecutor, GivenStopFlagThenReturnsBeforeTheEnd) {
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  RecordingTask t;
  ASSERT_TRUE(ex.add({periodic("t", 100), &t, nullptr}));
  std::atomic<bool> stop{true};
  ASSERT_TRUE(ex.runUntil(kNsPerSecond, &stop));
  EXPECT_TRUE(t.times.empty());
}

/// A little pipeline with seeded randomness: a sensor at 30 Hz with random values into a queue,
/// a filter triggered by it writing a latest slot, a controller at 100 Hz reading the slot.
struct Pipeline {
  explicit Pipeline(unsigned seed) : rng(seed) {}
  std::mt19937_64 rng;
  SpscQueue<double> measurements{4, OverflowPolicy::kDropOldest};
  Doorbell bell;
  LatestSlot<double> estimate;
  std::uint64_t output_hash = 1469598103934665603ULL;

  struct Sensor final : Task {
    explicit Sensor(Pipeline& pipeline) : p(pipeline) {}
    void step(TimeNs) override { p.measurements.try_push(std::uniform_real_distribution<double>(-1, 1)(p.rng)); }
    Pipeline& p;
  };
  struct Filter final : Task {
    explicit Filter(Pipeline& pipeline) : p(pipeline) {}
    void step(TimeNs) override {
      double m = 0;
      while (p.measurements.try_pop(m)) state = 0.8 * state + 0.2 * m;
      p.estimate.write(state);
    }
    Pipeline& p;
    double state = 0;
  };
  struct Controller final : Task {
    explicit Controller(Pipeline& pipeline) : p(pipeline) {}
    void step(TimeNs now_ns) override {
      const double e = p.estimate.read().value_or(0.0);
      std::uint64_t bits = 0;
      std::memcpy(&bits, &e, sizeof(bits));
      p.output_hash = (p.output_hash ^ bits ^ static_cast<std::uint64_t>(now_ns)) * 1099511628211ULL;
    }
    Pipeline& p;
  };
};

std::pair<std::uint64_t, std::uint64_t> runPipeline(unsigned seed) {
  Pipeline p(seed);
  p.measurements.attachDoorbell(&p.bell);
  Pipeline::Sensor sensor(p);
  Pipeline::Filter filter(p);
  Pipeline::Controller controller(p);
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  EXPECT_TRUE(ex.add({periodic("controller", 100, 10), &controller, nullptr}));
  EXPECT_TRUE(ex.add({periodic("sensor", 30, 5), &sensor, nullptr}));
  EXPECT_TRUE(ex.add({event("filter", "measurements"), &filter, &p.bell}));
  EXPECT_TRUE(ex.runUntil(20 * kNsPerSecond));
  return {ex.traceHash(), p.output_hash};
}

TEST(LockstepExecutor, GivenSameSeedWhenRunTwiceThenIdenticalTraceAndOutputs) {
  const auto a = runPipeline(7);
  const auto b = runPipeline(7);
  EXPECT_EQ(a.first, b.first);
  EXPECT_EQ(a.second, b.second);
  const auto c = runPipeline(8);
  EXPECT_EQ(a.first, c.first);    // the schedule does not depend on the data
  EXPECT_NE(a.second, c.second);  // the outputs do
}

class CountingTask final : public Task {
 public:
  explicit CountingTask(std::chrono::microseconds work = std::chrono::microseconds(0)) : work_(work) {}
  void step(TimeNs) override {
    if (work_.count() > 0) std::this_thread::sleep_for(work_);
    runs.fetch_add(1);
  }
  std::atomic<int> runs{0};

 private:
  std::chrono::microseconds work_;
};

RealtimeOptions unprivileged() {
  RealtimeOptions o;
  o.use_realtime_priority = false;
  o.lock_memory = false;
  o.stop_poll_ns = 5 * kNsPerMillisecond;
  return o;
}

TEST(RealtimeExecutor, GivenPeriodicAndEventTasksWhenRunThenBothRunAndStopPromptly) {
  MonotonicClock clock;
  RealtimeExecutor ex(clock, unprivileged());
  CountingTask ticker;
  CountingTask listener;
  Doorbell bell;
  ASSERT_TRUE(ex.add({periodic("ticker", 200), &ticker, nullptr}));
  ASSERT_TRUE(ex.add({event("listener", "bell"), &listener, &bell}));
  const auto warnings = ex.start();
  ASSERT_TRUE(warnings);
  EXPECT_TRUE(warnings->empty());
  for (int i = 0; i < 5; ++i) {
    bell.ring();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const TimeNs stop_at = clock.now();
  ex.requestStop();
  ex.join();
  EXPECT_LT(clock.now() - stop_at, 500 * kNsPerMillisecond);
  EXPECT_GT(ticker.runs.load(), 5);  // ~20 expected in 100 ms; loose for a loaded machine
  EXPECT_GE(listener.runs.load(), 1);
  EXPECT_LE(listener.runs.load(), 5);
  EXPECT_EQ(ex.stats()[0].stats->snapshot().runs, static_cast<std::uint64_t>(ticker.runs.load()));
}

TEST(RealtimeExecutor, GivenTaskSlowerThanItsPeriodThenOverrunsAndMissedDeadlinesCounted) {
  MonotonicClock clock;
  std::atomic<std::uint64_t> misses_seen_by_supervisor{0};
  RealtimeOptions options = unprivileged();
  options.deadline_misses = &misses_seen_by_supervisor;
  RealtimeExecutor ex(clock, options);
  CountingTask slow(std::chrono::microseconds(12'000));  // 12 ms of work at 200 Hz (5 ms period)
  TaskSpec spec = periodic("slow", 200);
  spec.budget_ms = 2.0;
  ASSERT_TRUE(ex.add({spec, &slow, nullptr}));
  ASSERT_TRUE(ex.start());
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ex.requestStop();
  ex.join();
  const TimingSnapshot s = ex.stats()[0].stats->snapshot();
  EXPECT_GE(s.runs, 2U);
  EXPECT_EQ(s.overruns, s.runs);
  EXPECT_GE(s.missed_deadlines, 2 * s.runs - 2);                    // each run spans at least two more periods
  EXPECT_EQ(misses_seen_by_supervisor.load(), s.missed_deadlines);  // the sink sees every one
}

TEST(RealtimeExecutor, GivenAddAfterStartThenRefused) {
  MonotonicClock clock;
  RealtimeExecutor ex(clock, unprivileged());
  CountingTask t;
  ASSERT_TRUE(ex.add({periodic("a", 10), &t, nullptr}));
  ASSERT_TRUE(ex.start());
  EXPECT_FALSE(ex.add({periodic("b", 10), &t, nullptr}));
  EXPECT_FALSE(ex.start());
}

}  // namespace
}  // namespace aerotrack::rt
