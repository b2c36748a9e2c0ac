// Bounded single-producer / single-consumer queue for streams (detections, depth frames, records
// for the logger), with a per-channel overflow policy and a drop counter (DESIGN.md rule 4).
//
// Why not moodycamel::ReaderWriterQueue (Debian's libreaderwriterqueue-dev, which the design
// prefers)? Its try_enqueue can only reject the newest item: in an SPSC library only the consumer
// may dequeue, so "drop the oldest, keep the newest" -- what a camera stream wants -- is
// impossible from the producer side. This ring lets the producer take the oldest unread slot with
// one compare-and-swap on the consumer index, race-free with a concurrent pop. tests/bench
// compares it with ReaderWriterQueue: see docs/benchmarks.md "Runtime benchmarks".
//
// Each slot carries a sequence number (as in Vyukov's bounded queue): slot i is free for
// position p when seq == p, holds position p's item when seq == p + 1, and after a pop of
// position p becomes free for p + capacity. Each side learns full/empty from the slot alone, so
// neither reads the other's index on the hot path; only kDropOldest needs a compare-and-swap on
// the consumer index. Positions are 64-bit and never wrap in practice.
//
// Guarantees: try_push and try_pop never block and never allocate (T's move assignment must not
// allocate either; shared_ptr's does not). Exactly one producer thread and one consumer thread.
#pragma once

#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <utility>

#include "aerotrack/rt/doorbell.hpp"

namespace aerotrack::rt {

enum class OverflowPolicy {
  kDropNewest,  ///< Full queue rejects the new item (keeps history contiguous).
  kDropOldest,  ///< Full queue discards its oldest unread item to make room (keeps data fresh).
};

template <class T>
class SpscQueue {
 public:
  /// capacity is rounded up to a power of two (>= 2). Allocates once, here.
  SpscQueue(std::size_t capacity, OverflowPolicy policy)
      : capacity_(std::bit_ceil(capacity < 2 ? std::size_t{2} : capacity)),
        mask_(capacity_ - 1),
        policy_(policy),
        slots_(std::make_unique<Slot[]>(capacity_)) {
    for (std::size_t i = 0; i < capacity_; ++i) slots_[i].seq.store(i, std::memory_order_relaxed);
  }

  SpscQueue(const SpscQueue&) = delete;
  SpscQueue& operator=(const SpscQueue&) = delete;

  void attachDoorbell(Doorbell* doorbell) { doorbell_ = doorbell; }

  /// Producer thread only. Returns true if the item was stored. When full: kDropNewest returns
  /// false; kDropOldest replaces the oldest unread item and returns true -- unless the consumer
  /// is reading exactly that item at this instant, in which case the new item is dropped and it
  /// returns false. Every dropped item (old or new) is counted in dropped().
  bool try_push(T item) {
    const std::uint64_t pos = tail_;
    Slot& slot = slots_[pos & mask_];
    if (slot.seq.load(std::memory_order_acquire) != pos) {  // full: the slot holds position pos - capacity
      dropped_.fetch_add(1, std::memory_order_relaxed);
      if (policy_ == OverflowPolicy::kDropNewest) return false;
      std::uint64_t oldest = pos - capacity_;
      // Claim the oldest unread item; fails if the consumer has already claimed it.
      if (!head_.compare_exchange_strong(oldest, oldest + 1, std::memory_order_acq_rel)) return false;
    }
    slot.value = std::move(item);
    slot.seq.store(pos + 1, std::memory_order_release);
    tail_ = pos + 1;
    published_tail_.store(pos + 1, std::memory_order_relaxed);
    if (doorbell_ != nullptr) doorbell_->ring();
    return true;
  }

  /// Producer thread only. True if try_push would store without dropping: the consumer has freed the
  /// slot (and only this thread fills it, so it stays free until the next push).
  bool canPush() const { return slots_[tail_ & mask_].seq.load(std::memory_order_acquire) == tail_; }

  /// Consumer thread only. Moves the oldest item into out; false if empty.
  bool try_pop(T& out) {
    for (;;) {
      const std::uint64_t pos = head_.load(std::memory_order_acquire);
      Slot& slot = slots_[pos & mask_];
      if (slot.seq.load(std::memory_order_acquire) != pos + 1) {
        // Not filled for pos: empty -- unless the producer just took pos (kDropOldest), which
        // moved head_ on; then look again.
        if (policy_ == OverflowPolicy::kDropNewest || head_.load(std::memory_order_acquire) == pos) return false;
        continue;
      }
      if (policy_ == OverflowPolicy::kDropNewest) {
        head_.store(pos + 1, std::memory_order_relaxed);  // only the consumer moves head_
      } else {
        std::uint64_t expected = pos;
        // Fails only if the producer took this item to make room; then look again.
        if (!head_.compare_exchange_strong(expected, pos + 1, std::memory_order_acq_rel)) continue;
      }
      out = std::move(slot.value);
      slot.seq.store(pos + capacity_, std::memory_order_release);
      return true;
    }
  }

  std::optional<T> try_pop() {
    T out;
    if (!try_pop(out)) return std::nullopt;
    return out;
  }

  /// Approximate number of unread items (exact when neither side is active). Any thread.
  std::size_t size_approx() const {
    const std::uint64_t tail = published_tail_.load(std::memory_order_acquire);
    const std::uint64_t head = head_.load(std::memory_order_acquire);
    return tail >= head ? static_cast<std::size_t>(tail - head) : 0;
  }

  std::size_t capacity() const { return capacity_; }
  OverflowPolicy policy() const { return policy_; }
  /// Items lost to overflow since construction. Any thread.
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  struct Slot {
    std::atomic<std::uint64_t> seq{0};
    T value{};
  };

  const std::size_t capacity_;
  const std::size_t mask_;
  const OverflowPolicy policy_;
  std::unique_ptr<Slot[]> slots_;
  alignas(64) std::atomic<std::uint64_t> head_{0};  // next position to pop (producer CASes it in kDropOldest)
  alignas(64) std::uint64_t tail_ = 0;              // next position to push; producer thread only
  std::atomic<std::uint64_t> published_tail_{0};    // tail_ for size_approx(); never read on the hot path
  std::atomic<std::uint64_t> dropped_{0};
  Doorbell* doorbell_ = nullptr;
};

}  // namespace aerotrack::rt
