// Two-thread stress tests of the channels, meant to run under ThreadSanitizer as well as plain.
// Each checks the invariant a reader relies on: SPSC order with no item duplicated or invented,
// drop counts that add up, latest-value reads that are never torn and never go back in time.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <array>
#include <atomic>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "aerotrack/rt/doorbell.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/lending_pool.hpp"
#include "aerotrack/rt/realtime_executor.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/spsc_queue.hpp"
#include "support/sanitizers.hpp"

namespace aerotrack::rt {
namespace {

#if defined(AEROTRACK_TEST_TSAN)
constexpr std::uint64_t kItems = 200'000;  // TSan slows atomics ~10x
#else
constexpr std::uint64_t kItems = 2'000'000;
#endif

void stressQueue(OverflowPolicy policy, std::size_t capacity) {
  SpscQueue<std::uint64_t> q(capacity, policy);
  std::atomic<bool> done{false};
  std::uint64_t accepted = 0;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kItems; ++i)
      if (q.try_push(i)) ++accepted;
    done.store(true, std::memory_order_release);
  });
  std::uint64_t popped = 0;
  std::uint64_t last = 0;
  bool first = true;
  bool ordered = true;
  for (;;) {
    std::uint64_t v = 0;
    if (q.try_pop(v)) {
      if (!first && v <= last) ordered = false;
      last = v;
      first = false;
      ++popped;
    } else if (done.load(std::memory_order_acquire) && q.size_approx() == 0) {
      break;
    }
  }
  producer.join();
  EXPECT_TRUE(ordered);
  EXPECT_LT(last, kItems);
  if (policy == OverflowPolicy::kDropNewest) {
    EXPECT_EQ(popped, accepted);
    EXPECT_EQ(popped + q.dropped(), kItems);
  } else {
    // Every item was either delivered or counted as dropped (an accepted push may later be
    // dropped as the oldest; a rejected one is counted once).
    EXPECT_EQ(popped + q.dropped(), kItems);
  }
}

TEST(SpscQueueStress, DropNewestSmallQueueKeepsOrderAndCounts) {
  stressQueue(OverflowPolicy::kDropNewest, 8);
}
TEST(SpscQueueStress, DropOldestSmallQueueKeepsOrderAndCounts) {
  stressQueue(OverflowPolicy::kDropOldest, 8);
}
TEST(SpscQueueStress, DropOldestTinyQueueKeepsOrderAndCounts) {
  stressQueue(OverflowPolicy::kDropOldest, 2);
}
TEST(SpscQueueStress, LargeQueueLosesNothingWhenConsumerKeepsUp) {
  stressQueue(OverflowPolicy::kDropNewest, 1 << 16);
}

TEST(SpscQueueStress, SharedHandlesAreNeitherLeakedNorFreedTwice) {
  SpscQueue<std::shared_ptr<const std::vector<int>>> q(4, OverflowPolicy::kDropOldest);
  auto witness = std::make_shared<const std::vector<int>>(16, 1);
  std::weak_ptr<const std::vector<int>> watch = witness;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kItems / 10; ++i) q.try_push(witness);
    done.store(true);
  });
  std::shared_ptr<const std::vector<int>> item;
  while (!done.load() || q.size_approx() > 0)
    if (q.try_pop(item)) {
      ASSERT_EQ(item->size(), 16U);
    }
  producer.join();
  item.reset();
  while (q.try_pop(item)) item.reset();
  witness.reset();
  // The queue's slots may still hold moved-from (empty) or dropped-over handles; none of ours.
  EXPECT_TRUE(watch.expired() || watch.use_count() <= static_cast<long>(q.capacity()));
}

struct Wide {
  std::array<std::uint64_t, 9> words;  // 72 bytes: a torn read would mix two writes
};

TEST(LatestSlotStress, ReadersNeverSeeTornOrOlderValues) {
  LatestSlot<Wide> slot;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (std::uint64_t i = 1; i <= kItems; ++i) {
      Wide w;
      w.words.fill(i);
      slot.write(w);
    }
    done.store(true);
  });
  std::vector<std::thread> readers;
  std::atomic<int> torn{0}, backwards{0};
  for (int r = 0; r < 2; ++r) {
    readers.emplace_back([&] {
      std::uint64_t last = 0;
      while (!done.load()) {
        const auto w = slot.read();
        if (!w) continue;
        for (std::uint64_t v : w->words)
          if (v != w->words[0]) torn.fetch_add(1);
        if (w->words[0] < last) backwards.fetch_add(1);
        last = w->words[0];
      }
    });
  }
  writer.join();
  for (auto& t : readers) t.join();
  EXPECT_EQ(torn.load(), 0);
  EXPECT_EQ(backwards.load(), 0);
  EXPECT_EQ(slot.read()->words[0], kItems);
}

/// Puts the calling thread on one CPU at a SCHED_FIFO priority; false where that is not permitted.
bool runFifoOn(int cpu, int priority) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  if (pthread_setaffinity_np(pthread_self(), sizeof(set), &set) != 0) return false;
  sched_param param{};
  param.sched_priority = priority;
  return pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
}

TEST(LatestSlotStress, AHigherPriorityReaderOnTheWritersCpuNeverWaitsForIt) {
  // The real-time executor's situation: a reader at a higher SCHED_FIFO priority wakes on the CPU
  // where the writer is copying a write in, so the writer cannot run until the reader sleeps again.
  // A reader that waited for the write to finish would spin forever (the single-buffer seqlock did:
  // 0 of 500 reads in 10 s; the likely cause of a realtime sim that froze in CI). The writer writes
  // without pause, so wake-ups land mid-write. Where SCHED_FIFO is refused (not root, no CAP_SYS_NICE)
  // there is nothing to test.
  cpu_set_t allowed;
  ASSERT_EQ(sched_getaffinity(0, sizeof(allowed), &allowed), 0);
  int cpu = 0;
  while (cpu < CPU_SETSIZE && !CPU_ISSET(cpu, &allowed)) ++cpu;
  LatestSlot<Wide> slot;
  std::atomic<bool> done{false};
  std::atomic<int> refused{0};
  std::atomic<int> reads{0};
  std::atomic<int> torn{0};
  std::thread writer([&] {
    if (!runFifoOn(cpu, 10)) refused.fetch_add(1);
    Wide w{};
    for (std::uint64_t i = 1; !done.load(std::memory_order_relaxed); ++i) {
      w.words.fill(i);
      slot.write(w);
    }
  });
  constexpr int kReads = 500;
  std::thread reader([&] {
    if (!runFifoOn(cpu, 20)) refused.fetch_add(1);
    for (int k = 0; k < kReads; ++k) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      const auto w = slot.read();
      if (w && w->words.front() != w->words.back()) torn.fetch_add(1);
      reads.fetch_add(1);
    }
  });
  // This thread is on the other CPUs at normal priority: it watches, and if the reader is stuck it
  // stops the writer and takes the reader's priority away, so that the writer can finish its write
  // and leave, and the test end.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (reads.load() < kReads && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  const int finished = reads.load();
  done.store(true);
  if (finished < kReads) {
    const sched_param normal{};
    pthread_setschedparam(reader.native_handle(), SCHED_OTHER, &normal);
  }
  writer.join();
  reader.join();
  if (refused.load() > 0) GTEST_SKIP() << "SCHED_FIFO or CPU affinity not permitted here";
  EXPECT_EQ(finished, kReads) << "the reader waited for a writer it had preempted";
  EXPECT_EQ(torn.load(), 0);
}

TEST(SharedSlotStress, ReadersAlwaysGetACompleteObject) {
  SharedSlot<std::vector<std::uint64_t>> slot;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (std::uint64_t i = 1; i <= kItems / 20; ++i)
      slot.write(std::make_shared<const std::vector<std::uint64_t>>(32, i));
    done.store(true);
  });
  int bad = 0;
  while (!done.load()) {
    const auto v = slot.read();
    if (!v) continue;
    for (std::uint64_t x : *v)
      if (x != v->front()) ++bad;
  }
  writer.join();
  EXPECT_EQ(bad, 0);
}

TEST(LendingPoolStress, ObjectsAreRewrittenOnlyAfterEveryReaderLetThemGo) {
  // The mapper's grid snapshots and the camera's frames: the owner rewrites pooled objects in place
  // and publishes them through a SharedSlot; two readers keep a few recent handles each for a while.
  // A rewrite of an object a reader still holds shows as a mixed object (and, under TSan, a race).
  LendingPool<std::vector<std::uint64_t>> pool(3, std::vector<std::uint64_t>(64, 0));
  SharedSlot<std::vector<std::uint64_t>> slot;
  std::atomic<bool> done{false};
  std::atomic<int> mixed{0};
  std::vector<std::thread> readers;
  for (int r = 0; r < 2; ++r) {
    readers.emplace_back([&, r] {
      std::array<std::shared_ptr<const std::vector<std::uint64_t>>, 4> kept;
      std::size_t next = 0;
      while (!done.load()) {
        auto v = slot.read();
        if (!v) continue;
        for (const auto& held : kept)
          if (held)
            for (std::uint64_t x : *held)
              if (x != held->front()) mixed.fetch_add(1);
        kept[next] = std::move(v);
        next = (next + 1 + static_cast<std::size_t>(r)) % kept.size();
      }
    });
  }
  for (std::uint64_t i = 1; i <= kItems / 20; ++i) {
    std::shared_ptr<std::vector<std::uint64_t>> object = pool.acquire();
    for (std::uint64_t& x : *object) x = i;
    slot.write(std::move(object));
  }
  done.store(true);
  for (auto& t : readers) t.join();
  EXPECT_EQ(mixed.load(), 0);
  EXPECT_GE(pool.size(), 3U);  // grows while readers hold many; never below its start
}

TEST(DoorbellStress, NoRingIsLost) {
  // The waiter sleeps up to 10 s per wait; a single lost wake-up would stall it that long, so
  // finishing well within the limit shows every ring woke it (or found it awake).
  Doorbell bell;
  std::atomic<std::uint64_t> produced{0};
  std::atomic<bool> done{false};
  const auto start = std::chrono::steady_clock::now();
  std::thread consumer([&] {
    std::uint64_t seen = 0;
    while (!done.load() || seen < produced.load()) {
      if (bell.waitFor(10 * kNsPerSecond)) {
        bell.consume();
        seen = produced.load();  // everything produced before consume() is visible
      }
    }
  });
  for (int i = 0; i < 20000; ++i) {
    produced.fetch_add(1);
    bell.ring();
    if (i % 1000 == 0) std::this_thread::sleep_for(std::chrono::microseconds(200));  // let the waiter sleep
  }
  done.store(true);
  bell.ring();
  consumer.join();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
}

/// Reads the slot on every run; checks that values never go back and that runs respect the cap.
class CappedReader final : public Task {
 public:
  CappedReader(const LatestSlot<std::uint64_t>& slot, DurationNs cap_ns) : slot_(slot), cap_ns_(cap_ns) {}
  void step(TimeNs now_ns) override {
    if (last_run_ns_ >= 0 && now_ns - last_run_ns_ < cap_ns_) cap_broken_.store(true, std::memory_order_relaxed);
    last_run_ns_ = now_ns;
    const std::uint64_t v = slot_.read().value_or(0);
    if (v < seen_.load(std::memory_order_relaxed)) went_back_.store(true, std::memory_order_relaxed);
    seen_.store(v, std::memory_order_release);
    runs_.fetch_add(1, std::memory_order_relaxed);
  }
  std::uint64_t seen() const { return seen_.load(std::memory_order_acquire); }
  bool capBroken() const { return cap_broken_.load(std::memory_order_relaxed); }
  bool wentBack() const { return went_back_.load(std::memory_order_relaxed); }
  std::uint64_t runs() const { return runs_.load(std::memory_order_relaxed); }

 private:
  const LatestSlot<std::uint64_t>& slot_;
  DurationNs cap_ns_;
  TimeNs last_run_ns_ = -1;
  std::atomic<std::uint64_t> seen_{0};
  std::atomic<std::uint64_t> runs_{0};
  std::atomic<bool> cap_broken_{false};
  std::atomic<bool> went_back_{false};
};

TEST(TriggeredTaskStress, AWriterNeverBlocksAndTheLastWriteIsAlwaysServedWithinTheCap) {
  // A writer hammers a slot whose doorbell triggers a task on the real-time executor (a 1 ms cap, a
  // 10 s fallback). After every burst the reader must see the burst's last value: a lost wake-up
  // would leave it waiting for the 10 s fallback. The writer is wait-free (no lock to contend).
  LatestSlot<std::uint64_t> slot;
  Doorbell bell;
  slot.attachDoorbell(&bell);
  CappedReader reader(slot, kNsPerMillisecond);
  MonotonicClock clock;
  RealtimeOptions options;
  options.use_realtime_priority = false;
  options.lock_memory = false;
  RealtimeExecutor ex(clock, options);
  TaskSpec spec;
  spec.name = "reader";
  spec.trigger = "slot";
  spec.rate_hz = 0.1;
  spec.min_period_ms = 1.0;
  spec.budget_ms = 1.0;
  ASSERT_TRUE(ex.add({spec, &reader, &bell}));
  ASSERT_TRUE(ex.start());
  constexpr int kBursts = 50;
  const std::uint64_t per_burst = kItems / 200;
  std::uint64_t value = 0;
  bool all_served = true;
  for (int burst = 0; burst < kBursts && all_served; ++burst) {
    for (std::uint64_t i = 0; i < per_burst; ++i) slot.write(++value);
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (reader.seen() != value && std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    all_served = reader.seen() == value;
  }
  ex.requestStop();
  ex.join();
  EXPECT_TRUE(all_served) << "a burst's last write was not served: a lost wake-up";
  EXPECT_FALSE(reader.capBroken());
  EXPECT_FALSE(reader.wentBack());
  EXPECT_GE(reader.runs(), static_cast<std::uint64_t>(kBursts));
}

}  // namespace
}  // namespace aerotrack::rt
