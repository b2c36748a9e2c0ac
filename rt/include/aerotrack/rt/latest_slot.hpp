// Latest-value channel for small state (odometry, gimbal angle, setpoints): newest wins, one
// writer, any number of readers, readers never block the writer (DESIGN.md rule 4).
//
// Two buffers, each a sequence lock whose payload is stored in atomic 64-bit words with
// release/acquire ordering (the formulation of Boehm, "Can seqlocks get along with programming
// language memory models?", MSPC 2012, free of data races in the C++ memory model, so
// ThreadSanitizer checks it without suppressions). Write n goes into buffer n % 2, and only then is
// n published as the newest; a reader copies the newest published buffer, which the writer does not
// touch until it has published the next write. So write() is wait-free, and a reader retries only
// when the writer has finished a whole write during the read: it never waits for a write in
// progress. That is what SCHED_FIFO needs. A single seqlock (one buffer, readers spinning while the
// sequence is odd) livelocks when a higher-priority reader preempts the writer mid-copy on its CPU:
// the reader spins and the writer never runs again: the likely cause of a realtime sim that froze in
// CI (docs/testing.md, "A reader that waited for a preempted writer"). No allocation after construction.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <optional>
#include <type_traits>

#include "aerotrack/rt/bitwise_copyable.hpp"
#include "aerotrack/rt/doorbell.hpp"

namespace aerotrack::rt {

template <class T>
class LatestSlot {
  static_assert(kIsBitwiseCopyable<T>,
                "LatestSlot copies T word by word (see bitwise_copyable.hpp); "
                "pass large data as a SharedSlot handle");
  static_assert(std::is_default_constructible_v<T>);
  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;

 public:
  /// Optional doorbell rung after each write (for an event-triggered reader). Set before start.
  void attachDoorbell(Doorbell* doorbell) { doorbell_ = doorbell; }

  /// Single writer. Wait-free, no allocation. notify: whether to ring the attached doorbell.
  void write(const T& value, Notify notify = Notify::kYes) {
    publish(stage(value));
    if (doorbell_ != nullptr && notify == Notify::kYes) doorbell_->ring();
  }

  /// Any reader thread. Returns the newest value, or nothing if none was ever written.
  std::optional<T> read() const {
    T out;
    if (readVersioned(out) == 0) return std::nullopt;
    return out;
  }

  /// Reads the newest value into out if its version is newer than last_version, and updates
  /// last_version. Returns true if out was written. Lets a periodic reader skip stale data.
  bool readIfNewer(std::uint64_t& last_version, T& out) const {
    T candidate;
    const std::uint64_t version = readVersioned(candidate);
    if (version == 0 || version == last_version) return false;
    out = candidate;
    last_version = version;
    return true;
  }

  /// Number of writes so far (0: never written). Any thread.
  std::uint64_t version() const { return newest_.load(std::memory_order_acquire); }

 private:
  friend struct LatestSlotTestAccess;  // a read between stage() and publish(), deterministically

  struct Buffer {
    /// 2n: holds write n, complete; odd: a write is being copied in.
    alignas(64) std::atomic<std::uint64_t> seq{0};
    std::array<std::atomic<std::uint64_t>, kWords> words{};
  };

  // Copies value into the buffer the newest write does not occupy; returns the write's number.
  std::uint64_t stage(const T& value) {
    std::array<std::uint64_t, kWords> buffer{};
    std::memcpy(static_cast<void*>(buffer.data()), static_cast<const void*>(&value), sizeof(T));
    const std::uint64_t n = newest_.load(std::memory_order_relaxed) + 1;  // only this thread stores it
    Buffer& b = buffers_[n % 2];
    b.seq.store(2 * n - 1, std::memory_order_relaxed);  // odd: a reader of write n - 2 sees the change
    // Release: a reader that loads any new word also sees the odd sequence (Boehm's formulation).
    for (std::size_t i = 0; i < kWords; ++i) b.words[i].store(buffer[i], std::memory_order_release);
    b.seq.store(2 * n, std::memory_order_release);
    return n;
  }

  void publish(std::uint64_t n) { newest_.store(n, std::memory_order_release); }

  // Returns the number of the write copied into out (0 if never written).
  std::uint64_t readVersioned(T& out) const {
    std::array<std::uint64_t, kWords> buffer{};
    for (;;) {
      const std::uint64_t n = newest_.load(std::memory_order_acquire);
      if (n == 0) return 0;
      const Buffer& b = buffers_[n % 2];
      const std::uint64_t before = b.seq.load(std::memory_order_acquire);
      if (before == 2 * n) {
        // Acquire loads of the words: if any observes a newer write, the seq load below sees it.
        for (std::size_t i = 0; i < kWords; ++i) buffer[i] = b.words[i].load(std::memory_order_acquire);
        if (b.seq.load(std::memory_order_relaxed) == before) {
          std::memcpy(static_cast<void*>(&out), static_cast<const void*>(buffer.data()), sizeof(T));
          return n;
        }
      }
      // The writer reused this buffer for write n + 2, so it has published n + 1 since our load of
      // newest_: it made progress, and the next pass reads the newer write.
    }
  }

  alignas(64) std::atomic<std::uint64_t> newest_{0};  // the newest published write (0: none)
  std::array<Buffer, 2> buffers_{};
  Doorbell* doorbell_ = nullptr;
};

}  // namespace aerotrack::rt
