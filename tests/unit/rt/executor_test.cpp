// Executors: periodic timing on the manual clock, ordering rules, event tasks, lockstep
// determinism (two runs, identical trace hash), and the real-time executor's start/stop and
// overrun accounting.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
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
  TaskSpec both = periodic("a", 10);  // triggered, with a periodic fallback
  both.trigger = "x";
  EXPECT_TRUE(validate(both));
  both.min_period_ms = 100.0;  // the cap may equal the fallback period
  EXPECT_TRUE(validate(both));
  both.min_period_ms = 101.0;  // but not exceed it
  EXPECT_FALSE(validate(both));
  both.min_period_ms = -1.0;
  EXPECT_FALSE(validate(both));
  TaskSpec capped_timer = periodic("a", 10);  // a cap without a trigger means nothing
  capped_timer.min_period_ms = 5.0;
  EXPECT_FALSE(validate(capped_timer));
  TaskSpec capped_event = event("a", "x");
  capped_event.min_period_ms = 5000.0;
  EXPECT_TRUE(validate(capped_event));
  TaskSpec neither = periodic("a", 0);
  EXPECT_FALSE(validate(neither));
  TaskSpec no_budget = periodic("a", 10);
  no_budget.budget_ms = 0;
  EXPECT_FALSE(validate(no_budget));
  TaskSpec bad_priority = periodic("a", 10, 100);
  EXPECT_FALSE(validate(bad_priority));
  EXPECT_FALSE(validate(std::vector<TaskSpec>{periodic("a", 10), periodic("a", 20)}));
  TaskSpec late = periodic("a", 10);
  late.budget_ms = 50.0;
  late.latency_ms = 50.0;
  EXPECT_TRUE(validate(late));
  late.latency_ms = 60.0;  // beyond its budget
  EXPECT_FALSE(validate(late));
  late.budget_ms = 200.0;
  late.latency_ms = 150.0;  // beyond its 100 ms period
  EXPECT_FALSE(validate(late));
  late.latency_ms = -1.0;
  EXPECT_FALSE(validate(late));
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

struct Result {
  TimeNs release_ns;
  std::uint64_t value;
};

/// Overlapped: gather() takes the release time, work() computes from it (slowly, and for a random
/// while, so the worker finishes at unpredictable wall times), publish() writes the result.
class SlowSquareTask final : public OverlappedTask {
 public:
  SlowSquareTask(LatestSlot<Result>& out, unsigned seed) : out_(out), rng_(seed) {}
  bool gather(TimeNs now_ns) override {
    input_ns_ = now_ns;
    return true;
  }
  void work() override {
    std::this_thread::sleep_for(std::chrono::microseconds(rng_() % 2000));
    std::uint64_t x = static_cast<std::uint64_t>(input_ns_);
    for (int i = 0; i < 1000; ++i) x = x * 6364136223846793005ULL + 1442695040888963407ULL;
    result_ = x;
  }
  void publish(TimeNs publish_ns) override {
    out_.write({input_ns_, result_});
    publish_times.push_back(publish_ns);
  }
  std::vector<TimeNs> publish_times;

 private:
  LatestSlot<Result>& out_;
  std::mt19937 rng_;
  TimeNs input_ns_ = 0;
  std::uint64_t result_ = 0;
};

/// Every millisecond: which release's result it sees.
class WatcherTask final : public Task {
 public:
  explicit WatcherTask(const LatestSlot<Result>& in) : in_(in) {}
  void step(TimeNs now_ns) override {
    const auto v = in_.read();
    seen.push_back({now_ns, v ? v->release_ns : -1});
    results += v ? v->value : 0;
  }
  std::vector<std::pair<TimeNs, TimeNs>> seen;  // (when, the release whose result it saw)
  std::uint64_t results = 0;

 private:
  const LatestSlot<Result>& in_;
};

struct OverlapRun {
  std::uint64_t trace;
  std::vector<std::pair<TimeNs, TimeNs>> seen;
  std::uint64_t results;
  std::vector<TimeNs> publish_times;
};

OverlapRun runOverlapped(double latency_ms, unsigned seed) {
  ManualClock clock(0);
  MonotonicClock stats;
  LockstepExecutor ex(clock, stats);
  LatestSlot<Result> slot;
  SlowSquareTask mapper(slot, seed);
  WatcherTask watcher(slot);
  TaskSpec spec = periodic("mapper", 10, 50);
  spec.budget_ms = 40.0;
  spec.latency_ms = latency_ms;
  EXPECT_TRUE(ex.add({spec, &mapper, nullptr}));
  EXPECT_TRUE(ex.add({periodic("watcher", 1000, 10), &watcher, nullptr}));
  EXPECT_TRUE(ex.runUntil(kNsPerSecond / 2));
  EXPECT_TRUE(ex.runUntil(kNsPerSecond));  // in two calls: a publication due after the first end waits
  return {ex.traceHash(), watcher.seen, watcher.results, mapper.publish_times};
}

TEST(LockstepExecutor, GivenAnObserverAddedLastThenTheTraceHashIsTheRunsWithoutIt) {
  // The overlapped pipeline of runOverlapped, with and without a 1 kHz observer reading its slot.
  auto run = [](bool with_observer) {
    ManualClock clock(0);
    MonotonicClock stats;
    LockstepExecutor ex(clock, stats);
    LatestSlot<Result> slot;
    SlowSquareTask mapper(slot, 3);
    WatcherTask watcher(slot);
    WatcherTask observer(slot);
    TaskSpec spec = periodic("mapper", 10, 50);
    spec.budget_ms = 40.0;
    spec.latency_ms = 30.0;
    EXPECT_TRUE(ex.add({spec, &mapper, nullptr}));
    EXPECT_TRUE(ex.add({periodic("watcher", 1000, 10), &watcher, nullptr}));
    if (with_observer) {
      TaskSpec o = periodic("recorder", 1000, 0);
      o.observer = true;
      EXPECT_TRUE(ex.add({o, &observer, nullptr}));
    }
    EXPECT_TRUE(ex.runUntil(kNsPerSecond / 2));
    EXPECT_EQ(observer.seen.size(), with_observer ? 501U : 0U);  // it ran, at every release
    return std::make_pair(ex.traceHash(), watcher.seen);
  };
  const auto without = run(false);
  const auto with = run(true);
  EXPECT_EQ(without.first, with.first);
  EXPECT_EQ(without.second, with.second);
}

TEST(LockstepExecutor, GivenAnOverlappedTaskThenItsResultsAppearExactlyItsLatencyAfterTheRelease) {
  const OverlapRun run = runOverlapped(30.0, 1);
  ASSERT_EQ(run.publish_times.size(), 10U);  // releases at 0, 100, ..., 900 ms (1000's is due after the end)
  for (std::size_t i = 0; i < run.publish_times.size(); ++i)
    EXPECT_EQ(run.publish_times[i], static_cast<TimeNs>(i) * 100 * kNsPerMillisecond + 30 * kNsPerMillisecond);
  for (const auto& [when_ns, release_ns] : run.seen) {
    // At when, the newest release at least 30 ms old is what the watcher sees (a publication goes before
    // the releases of its instant), none before the first.
    const TimeNs age_ns = when_ns - 30 * kNsPerMillisecond;
    const TimeNs expected =
        age_ns < 0 ? -1 : std::min<TimeNs>(age_ns / (100 * kNsPerMillisecond), 9) * 100 * kNsPerMillisecond;
    ASSERT_EQ(release_ns, expected) << "at " << when_ns;
  }
}

TEST(LockstepExecutor, GivenAnOverlappedTaskWhenItsWorkTakesRandomTimesThenRunsAreIdentical) {
  const OverlapRun a = runOverlapped(30.0, 1);
  const OverlapRun b = runOverlapped(30.0, 2);  // other work durations
  EXPECT_EQ(a.trace, b.trace);
  EXPECT_EQ(a.seen, b.seen);
  EXPECT_EQ(a.results, b.results);
}

TEST(LockstepExecutor, GivenNoLatencyThenAnOverlappedTaskRunsInlineLikeAnyTask) {
  const OverlapRun run = runOverlapped(0.0, 1);
  EXPECT_EQ(run.publish_times.size(), 11U);  // at each release, 1000 ms included
  for (std::size_t i = 0; i < run.publish_times.size(); ++i)
    EXPECT_EQ(run.publish_times[i], static_cast<TimeNs>(i) * 100 * kNsPerMillisecond);
  for (const auto& [when_ns, release_ns] : run.seen)  // the mapper has the higher priority: first
    ASSERT_EQ(release_ns, (when_ns / (100 * kNsPerMillisecond)) * 100 * kNsPerMillisecond) << "at " << when_ns;
}

/// Writes a latest slot at the listed times (its period must divide them), counting from 1.
class ScheduledWriter final : public Task {
 public:
  ScheduledWriter(LatestSlot<int>& slot, std::vector<TimeNs> at_ns) : slot_(slot), at_ns_(std::move(at_ns)) {}
  void step(TimeNs now_ns) override {
    for (const TimeNs t : at_ns_)
      if (t == now_ns) slot_.write(++written_);
  }

 private:
  LatestSlot<int>& slot_;
  std::vector<TimeNs> at_ns_;
  int written_ = 0;
};

TaskSpec triggered(const std::string& name, double fallback_rate_hz, double min_period_ms) {
  TaskSpec s = event(name, "slot");
  s.rate_hz = fallback_rate_hz;
  s.min_period_ms = min_period_ms;
  return s;
}

constexpr TimeNs kMs = kNsPerMillisecond;

/// Lockstep: a 1 kHz writer writes at the given times; the reader is triggered by the slot.
std::vector<TimeNs> runTriggeredReader(const TaskSpec& reader_spec, std::vector<TimeNs> writes_ns, TimeNs end_ns,
                                       std::uint64_t* trace_hash = nullptr) {
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  LatestSlot<int> slot;
  Doorbell bell;
  slot.attachDoorbell(&bell);
  ScheduledWriter writer(slot, std::move(writes_ns));
  RecordingTask reader;
  EXPECT_TRUE(ex.add({periodic("writer", 1000, 10), &writer, nullptr}));
  EXPECT_TRUE(ex.add({reader_spec, &reader, &bell}));
  EXPECT_TRUE(ex.runUntil(end_ns));
  if (trace_hash != nullptr) *trace_hash = ex.traceHash();
  return reader.times;
}

TEST(LockstepExecutor, GivenATriggeredTaskWithAFallbackWhenAWriteComesThenItRunsAtTheWriteAndTheFallbackRestarts) {
  // Fallback 10 Hz, no cap: the timer at 0 and 100 ms, the write at 137 ms, then the timer 100 ms after it.
  const std::vector<TimeNs> times = runTriggeredReader(triggered("r", 10, 0.0), {137 * kMs}, 400 * kMs);
  EXPECT_EQ(times, (std::vector<TimeNs>{0, 100 * kMs, 137 * kMs, 237 * kMs, 337 * kMs}));
}

TEST(LockstepExecutor, GivenNoWritesThenATriggeredTaskRunsAtItsFallbackRate) {
  const std::vector<TimeNs> times = runTriggeredReader(triggered("r", 20, 10.0), {}, 200 * kMs);
  EXPECT_EQ(times, (std::vector<TimeNs>{0, 50 * kMs, 100 * kMs, 150 * kMs, 200 * kMs}));
}

TEST(LockstepExecutor, GivenWritesFasterThanTheRateCapThenRunsAreCapAndARingInsideItIsDeferredNotDropped) {
  // Writes every 10 ms from 5 ms, a 30 ms cap, no fallback: a run at the first write, then each at the
  // end of the cap (the ring inside it waits), reading the newest value.
  std::vector<TimeNs> writes;
  for (TimeNs t = 5 * kMs; t <= 95 * kMs; t += 10 * kMs) writes.push_back(t);
  const std::vector<TimeNs> times = runTriggeredReader(triggered("r", 0, 30.0), writes, 300 * kMs);
  EXPECT_EQ(times, (std::vector<TimeNs>{5 * kMs, 35 * kMs, 65 * kMs, 95 * kMs}));
  // One write inside the cap, after which nothing: still served at the cap's end.
  EXPECT_EQ(runTriggeredReader(triggered("r", 0, 30.0), {5 * kMs, 12 * kMs}, 300 * kMs),
            (std::vector<TimeNs>{5 * kMs, 35 * kMs}));
  // A write after the cap has passed runs at once.
  EXPECT_EQ(runTriggeredReader(triggered("r", 0, 30.0), {5 * kMs, 50 * kMs}, 300 * kMs),
            (std::vector<TimeNs>{5 * kMs, 50 * kMs}));
}

TEST(LockstepExecutor, GivenATriggeredTaskThenTheSameWritesGiveTheSameRunBitForBit) {
  std::vector<TimeNs> writes;
  std::mt19937_64 rng(11);
  for (int i = 0; i < 200; ++i) writes.push_back(static_cast<TimeNs>(rng() % 2000) * kMs);
  std::uint64_t hash_a = 0;
  std::uint64_t hash_b = 0;
  std::uint64_t hash_c = 0;
  const auto a = runTriggeredReader(triggered("r", 20, 25.0), writes, 2 * kNsPerSecond, &hash_a);
  const auto b = runTriggeredReader(triggered("r", 20, 25.0), writes, 2 * kNsPerSecond, &hash_b);
  EXPECT_EQ(a, b);
  EXPECT_EQ(hash_a, hash_b);
  writes.push_back(1999 * kMs + 1);  // not on the writer's grid: no write, same run
  EXPECT_EQ(runTriggeredReader(triggered("r", 20, 25.0), writes, 2 * kNsPerSecond, &hash_c), a);
  EXPECT_EQ(hash_c, hash_a);
  for (std::size_t i = 1; i < a.size(); ++i) {
    EXPECT_GE(a[i] - a[i - 1], 25 * kMs);  // the cap
    EXPECT_LE(a[i] - a[i - 1], 50 * kMs);  // the fallback
  }
}

/// Writes the time (ms) into a slot at each step, without waking anyone.
class ClockWriter final : public Task {
 public:
  explicit ClockWriter(LatestSlot<int>& slot) : slot_(slot) {}
  void step(TimeNs now_ns) override { slot_.write(static_cast<int>(now_ns / kMs), Notify::kNo); }

 private:
  LatestSlot<int>& slot_;
};

/// Records what a slot held at each of its steps.
class SlotReader final : public Task {
 public:
  explicit SlotReader(const LatestSlot<int>& slot) : slot_(slot) {}
  void step(TimeNs now_ns) override { seen.push_back({now_ns, slot_.read().value_or(-1)}); }
  std::vector<std::pair<TimeNs, int>> seen;

 private:
  const LatestSlot<int>& slot_;
};

std::vector<std::pair<TimeNs, int>> runDeferred(bool with_unrelated_task) {
  ManualClock clock(0);
  MonotonicClock wall;
  LockstepExecutor ex(clock, wall);
  LatestSlot<int> trigger;
  LatestSlot<int> fresh;
  Doorbell bell;
  trigger.attachDoorbell(&bell);
  RecordingTask unrelated;
  ClockWriter clock_writer(fresh);
  ScheduledWriter writer(trigger, {10 * kMs, 20 * kMs});
  SlotReader reader(fresh);
  if (with_unrelated_task) {
    EXPECT_TRUE(ex.add({periodic("unrelated", 200, 90), &unrelated, nullptr}));
  }
  EXPECT_TRUE(ex.add({periodic("clock", 100, 50), &clock_writer, nullptr}));
  EXPECT_TRUE(ex.add({periodic("writer", 1000, 10), &writer, nullptr}));
  EXPECT_TRUE(ex.add({triggered("reader", 0, 30.0), &reader, &bell}));
  EXPECT_TRUE(ex.runUntil(100 * kMs));
  return reader.seen;
}

TEST(LockstepExecutor, GivenADeferredReleaseThenItRunsInPriorityOrderWhateverElseRunsAtThatInstant) {
  // The write at 20 ms falls inside the cap: the reader runs at 40 ms, after the higher-priority clock
  // task's step at 40 ms, with or without an unrelated task stepping first at that instant (a replay
  // leaves the simulator's tasks out and must run the same).
  const auto alone = runDeferred(false);
  EXPECT_EQ(alone, (std::vector<std::pair<TimeNs, int>>{{10 * kMs, 10}, {40 * kMs, 40}}));
  EXPECT_EQ(runDeferred(true), alone);
}

TEST(LatestSlotDoorbell, GivenAWriteThatDoesNotNotifyThenTheDoorbellStaysQuiet) {
  LatestSlot<int> slot;
  Doorbell bell;
  slot.attachDoorbell(&bell);
  slot.write(1, Notify::kNo);
  EXPECT_FALSE(bell.pending());
  slot.write(2);
  EXPECT_TRUE(bell.pending());
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

TEST(RealtimeExecutor, GivenASlowObserverThenItsMissedDeadlinesAreItsOwnNotTheFlights) {
  MonotonicClock clock;
  std::atomic<std::uint64_t> misses_seen_by_supervisor{0};
  RealtimeOptions options = unprivileged();
  options.deadline_misses = &misses_seen_by_supervisor;
  RealtimeExecutor ex(clock, options);
  CountingTask slow(std::chrono::microseconds(12'000));  // a recorder starved: 12 ms at 200 Hz
  TaskSpec spec = periodic("recorder", 200);
  spec.budget_ms = 2.0;
  spec.observer = true;
  ASSERT_TRUE(ex.add({spec, &slow, nullptr}));
  ASSERT_TRUE(ex.start());
  std::this_thread::sleep_for(std::chrono::milliseconds(60));
  ex.requestStop();
  ex.join();
  EXPECT_GE(ex.stats()[0].stats->snapshot().missed_deadlines, 2U);  // counted in its own statistics
  EXPECT_EQ(misses_seen_by_supervisor.load(), 0U);                  // the supervisor is not told
}

/// Records the time of every step (the executor's wake-up time), for the real-time executor.
class TimedTask final : public Task {
 public:
  void step(TimeNs now_ns) override {
    if (count_.load(std::memory_order_relaxed) < times_.size()) times_[count_.load(std::memory_order_relaxed)] = now_ns;
    count_.fetch_add(1, std::memory_order_release);
  }
  std::size_t count() const { return count_.load(std::memory_order_acquire); }
  /// After the executor has joined: the time of step i (i below count() and 4096).
  TimeNs at(std::size_t i) const { return times_.at(i); }
  /// After the executor has joined.
  std::vector<TimeNs> times() const {
    return {times_.begin(), times_.begin() + static_cast<std::ptrdiff_t>(std::min(count(), times_.size()))};
  }

 private:
  std::array<TimeNs, 4096> times_{};
  std::atomic<std::size_t> count_{0};
};

/// Waits up to `limit` for pred(); true if it held.
template <typename Pred>
bool waitFor(Pred pred, std::chrono::milliseconds limit) {
  const auto until = std::chrono::steady_clock::now() + limit;
  while (!pred()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return true;
}

TEST(RealtimeExecutor, GivenATriggeredTaskWithASlowFallbackWhenAWriteComesThenItRunsLongBeforeTheFallback) {
  MonotonicClock clock;
  RealtimeExecutor ex(clock, unprivileged());
  LatestSlot<int> slot;
  Doorbell bell;
  slot.attachDoorbell(&bell);
  TimedTask reader;
  ASSERT_TRUE(ex.add({triggered("reader", 0.1, 0.0), &reader, &bell}));  // fallback every 10 s
  ASSERT_TRUE(ex.start());
  ASSERT_TRUE(waitFor([&] { return reader.count() >= 1; }, std::chrono::milliseconds(5000)));  // at the start
  const TimeNs written_ns = clock.now();
  slot.write(1);
  const bool woken = waitFor([&] { return reader.count() >= 2; }, std::chrono::milliseconds(5000));
  ex.requestStop();
  ex.join();
  ASSERT_TRUE(woken);
  const TimeNs woken_ns = reader.at(1);
  EXPECT_GE(woken_ns, written_ns);
  EXPECT_LT(woken_ns - written_ns, 5 * kNsPerSecond);  // loose (a loaded machine); the fallback was 10 s away
}

TEST(RealtimeExecutor, GivenNoWritesThenATriggeredTaskRunsAtItsFallbackRate) {
  MonotonicClock clock;
  RealtimeExecutor ex(clock, unprivileged());
  Doorbell bell;
  TimedTask reader;
  ASSERT_TRUE(ex.add({triggered("reader", 100, 5.0), &reader, &bell}));
  ASSERT_TRUE(ex.start());
  const bool ran = waitFor([&] { return reader.count() >= 5; }, std::chrono::milliseconds(5000));
  ex.requestStop();
  ex.join();
  EXPECT_TRUE(ran);
  const std::vector<TimeNs> times = reader.times();
  for (std::size_t i = 1; i < times.size(); ++i) EXPECT_GE(times[i] - times[i - 1], 5 * kNsPerMillisecond);
}

TEST(RealtimeExecutor, GivenWritesFasterThanTheRateCapThenRunsNeverComeCloserThanTheCap) {
  MonotonicClock clock;
  RealtimeExecutor ex(clock, unprivileged());
  LatestSlot<int> slot;
  Doorbell bell;
  slot.attachDoorbell(&bell);
  TimedTask reader;
  ASSERT_TRUE(ex.add({triggered("reader", 10, 20.0), &reader, &bell}));
  ASSERT_TRUE(ex.start());
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(200);
  for (int i = 0; std::chrono::steady_clock::now() < until; ++i) {
    slot.write(i);
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  ex.requestStop();
  ex.join();
  const std::vector<TimeNs> times = reader.times();
  ASSERT_GE(times.size(), 2U);  // about 10 in 200 ms
  // The cap is a rule on the executor's own wake-up times, so it holds however loaded the machine is.
  for (std::size_t i = 1; i < times.size(); ++i) EXPECT_GE(times[i] - times[i - 1], 20 * kNsPerMillisecond);
}

TEST(RealtimeExecutor, GivenAddAfterStartThenRefused) {
  MonotonicClock clock;
  RealtimeExecutor ex(clock, unprivileged());
  CountingTask t;
  ASSERT_TRUE(ex.add({periodic("a", 10), &t, nullptr}));
  ASSERT_TRUE(ex.start());
  EXPECT_FALSE(ex.add({periodic("b", 10), &t, nullptr}));
  EXPECT_FALSE(ex.start());
  // `t` is declared after the executor and so dies first: stop the thread that steps it now.
  ex.requestStop();
  ex.join();
}

}  // namespace
}  // namespace aerotrack::rt
