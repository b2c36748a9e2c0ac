// Channel semantics on one thread: latest-value slots, shared slots, the SPSC queue's overflow
// policies and drop counter, and doorbells. Concurrency is in tests/concurrency.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "aerotrack/rt/doorbell.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/spsc_queue.hpp"

namespace aerotrack::rt {

// Stops a write half-way, between copying it in and publishing it: where the writer is when a
// higher-priority reader preempts it on its CPU.
struct LatestSlotTestAccess {
  template <class T>
  static std::uint64_t stage(LatestSlot<T>& slot, const T& value) {
    return slot.stage(value);
  }
  template <class T>
  static void publish(LatestSlot<T>& slot, std::uint64_t n) {
    slot.publish(n);
  }
};

namespace {

struct Pose {
  double x, y, z;
  long stamp;
};

TEST(LatestSlot, GivenNoWriteWhenReadThenNothing) {
  LatestSlot<Pose> slot;
  EXPECT_FALSE(slot.read().has_value());
  EXPECT_EQ(slot.version(), 0U);
}

TEST(LatestSlot, GivenTwoWritesWhenReadThenNewestWins) {
  LatestSlot<Pose> slot;
  slot.write({1, 2, 3, 10});
  slot.write({4, 5, 6, 20});
  const auto p = slot.read();
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->x, 4);
  EXPECT_EQ(p->stamp, 20);
  EXPECT_EQ(slot.version(), 2U);
}

TEST(LatestSlot, GivenReaderUpToDateWhenReadIfNewerThenFalseUntilNextWrite) {
  LatestSlot<int> slot;
  std::uint64_t seen = 0;
  int value = -1;
  EXPECT_FALSE(slot.readIfNewer(seen, value));
  slot.write(7);
  EXPECT_TRUE(slot.readIfNewer(seen, value));
  EXPECT_EQ(value, 7);
  EXPECT_FALSE(slot.readIfNewer(seen, value));
  slot.write(8);
  EXPECT_TRUE(slot.readIfNewer(seen, value));
  EXPECT_EQ(value, 8);
}

// A reader must never wait for the writer (under SCHED_FIFO the writer it waits for may be the thread
// it preempted): with a write half-done, a read returns at once with the newest complete write. A
// single-buffer sequence lock spins here forever (the test's timeout catches it).
TEST(LatestSlot, GivenAWriteStoppedHalfWayWhenReadThenTheNewestCompleteWriteAtOnce) {
  LatestSlot<Pose> slot;
  const std::uint64_t first = LatestSlotTestAccess::stage(slot, Pose{9, 9, 9, 1});
  EXPECT_FALSE(slot.read().has_value()) << "nothing published yet";
  LatestSlotTestAccess::publish(slot, first);
  for (long stamp = 2; stamp <= 5; ++stamp) {  // both buffers, in turn, half-written
    const std::uint64_t n = LatestSlotTestAccess::stage(slot, Pose{0, 0, 0, stamp});
    const auto p = slot.read();
    ASSERT_TRUE(p.has_value());
    EXPECT_EQ(p->stamp, stamp - 1);
    EXPECT_EQ(slot.version(), static_cast<std::uint64_t>(stamp - 1));
    LatestSlotTestAccess::publish(slot, n);
    EXPECT_EQ(slot.read()->stamp, stamp);
  }
}

TEST(LatestSlot, GivenAttachedDoorbellWhenWrittenThenDoorbellPending) {
  LatestSlot<int> slot;
  Doorbell bell;
  slot.attachDoorbell(&bell);
  EXPECT_FALSE(bell.pending());
  slot.write(1);
  EXPECT_TRUE(bell.pending());
  bell.consume();
  EXPECT_FALSE(bell.pending());
}

TEST(SharedSlot, GivenHandleWrittenWhenReadThenSameObjectAndReaderKeepsItAlive) {
  SharedSlot<std::string> slot;
  EXPECT_EQ(slot.read(), nullptr);
  auto first = std::make_shared<const std::string>("first");
  std::weak_ptr<const std::string> watch = first;
  slot.write(first);
  first.reset();
  auto held = slot.read();
  slot.write(std::make_shared<const std::string>("second"));
  EXPECT_EQ(*held, "first");  // the reader's handle outlives the slot's
  EXPECT_FALSE(watch.expired());
  held.reset();
  EXPECT_TRUE(watch.expired());
  EXPECT_EQ(*slot.read(), "second");
  EXPECT_EQ(slot.version(), 2U);
}

TEST(SpscQueue, GivenCapacityNotPowerOfTwoThenRoundedUp) {
  SpscQueue<int> q(5, OverflowPolicy::kDropNewest);
  EXPECT_EQ(q.capacity(), 8U);
  SpscQueue<int> tiny(0, OverflowPolicy::kDropNewest);
  EXPECT_EQ(tiny.capacity(), 2U);
}

TEST(SpscQueue, GivenItemsPushedWhenPoppedThenFifoOrder) {
  SpscQueue<int> q(4, OverflowPolicy::kDropNewest);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(q.try_push(i));
  EXPECT_EQ(q.size_approx(), 3U);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(q.try_pop(), i);
  EXPECT_FALSE(q.try_pop().has_value());
  EXPECT_EQ(q.dropped(), 0U);
}

TEST(SpscQueue, GivenFullDropNewestQueueWhenPushThenNewItemRejectedAndCounted) {
  SpscQueue<int> q(4, OverflowPolicy::kDropNewest);
  for (int i = 0; i < 4; ++i) {
    EXPECT_TRUE(q.canPush());
    EXPECT_TRUE(q.try_push(i));
  }
  EXPECT_FALSE(q.canPush());
  EXPECT_FALSE(q.try_push(99));
  EXPECT_FALSE(q.try_push(100));
  EXPECT_EQ(q.dropped(), 2U);
  EXPECT_EQ(q.try_pop(), 0);
  EXPECT_TRUE(q.canPush());                               // one slot freed
  for (int i = 1; i < 4; ++i) EXPECT_EQ(q.try_pop(), i);  // the old items survive, in order
  EXPECT_FALSE(q.try_pop().has_value());
}

TEST(SpscQueue, GivenFullDropOldestQueueWhenPushThenOldestReplacedAndCounted) {
  SpscQueue<int> q(4, OverflowPolicy::kDropOldest);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(q.try_push(i));
  EXPECT_TRUE(q.try_push(4));
  EXPECT_TRUE(q.try_push(5));
  EXPECT_EQ(q.dropped(), 2U);
  EXPECT_EQ(q.size_approx(), 4U);
  for (int i = 2; i < 6; ++i) EXPECT_EQ(q.try_pop(), i);  // 0 and 1 were dropped
  EXPECT_FALSE(q.try_pop().has_value());
}

TEST(SpscQueue, GivenWrapAroundManyTimesThenOrderKept) {
  SpscQueue<int> q(4, OverflowPolicy::kDropOldest);
  int next_expected = 0;
  for (int i = 0; i < 1000; ++i) {
    ASSERT_TRUE(q.try_push(i));
    if (i % 3 == 2) {  // consumer slower than producer: some items dropped, order preserved
      int v = -1;
      ASSERT_TRUE(q.try_pop(v));
      EXPECT_GE(v, next_expected);
      next_expected = v + 1;
    }
  }
  EXPECT_EQ(q.dropped() + q.size_approx() + static_cast<std::uint64_t>(1000 / 3), 1000U);
}

TEST(SpscQueue, GivenMoveOnlyHandlesThenOwnershipTransfersAndDroppedOnesAreFreed) {
  SpscQueue<std::unique_ptr<int>> q(2, OverflowPolicy::kDropOldest);
  EXPECT_TRUE(q.try_push(std::make_unique<int>(1)));
  EXPECT_TRUE(q.try_push(std::make_unique<int>(2)));
  EXPECT_TRUE(q.try_push(std::make_unique<int>(3)));  // frees 1
  auto a = q.try_pop();
  ASSERT_TRUE(a.has_value());
  EXPECT_EQ(**a, 2);
  EXPECT_EQ(*q.try_pop().value(), 3);
}

TEST(SpscQueue, GivenAttachedDoorbellWhenPushAcceptedThenRings) {
  SpscQueue<int> q(2, OverflowPolicy::kDropNewest);
  Doorbell bell;
  q.attachDoorbell(&bell);
  EXPECT_TRUE(q.try_push(1));
  EXPECT_TRUE(bell.pending());
  bell.consume();
  EXPECT_TRUE(q.try_push(2));
  bell.consume();
  EXPECT_FALSE(q.try_push(3));  // rejected: no new data, no ring
  EXPECT_FALSE(bell.pending());
}

TEST(Doorbell, GivenNoRingWhenWaitThenTimesOutFalse) {
  Doorbell bell;
  EXPECT_FALSE(bell.waitFor(1'000'000));  // 1 ms
}

TEST(Doorbell, GivenRingBeforeWaitThenWaitReturnsAtOnce) {
  Doorbell bell;
  bell.ring();
  EXPECT_TRUE(bell.waitFor(10 * kNsPerSecond));
}

}  // namespace
}  // namespace aerotrack::rt
