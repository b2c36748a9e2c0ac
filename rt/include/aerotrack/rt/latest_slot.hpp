// Latest-value channel for small state (odometry, gimbal angle, setpoints): newest wins, one
// writer, any number of readers, readers never block the writer (DESIGN.md rule 4).
//
// It is a sequence lock whose payload is stored in atomic 64-bit words with release/acquire
// ordering, the formulation of Boehm ("Can seqlocks get along with programming language memory
// models?", MSPC 2012) that is free of data races in the C++ memory model, so ThreadSanitizer
// checks it without suppressions. write() is wait-free; read() retries only while a write is in
// progress, which lasts a few word copies. No allocation after construction.
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
    std::array<std::uint64_t, kWords> buffer{};
    std::memcpy(static_cast<void*>(buffer.data()), static_cast<const void*>(&value), sizeof(T));
    const std::uint64_t seq = seq_.load(std::memory_order_relaxed);
    seq_.store(seq + 1, std::memory_order_relaxed);  // odd: write in progress
    for (std::size_t i = 0; i < kWords; ++i) words_[i].store(buffer[i], std::memory_order_release);
    seq_.store(seq + 2, std::memory_order_release);
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
  std::uint64_t version() const { return seq_.load(std::memory_order_acquire) / 2; }

 private:
  // Returns the version of the value copied into out (0 if never written).
  std::uint64_t readVersioned(T& out) const {
    std::array<std::uint64_t, kWords> buffer{};
    for (;;) {
      const std::uint64_t before = seq_.load(std::memory_order_acquire);
      if (before == 0) return 0;
      if ((before & 1U) != 0) continue;  // writer mid-copy; it finishes within a few stores
      // Acquire loads of the words: if any observes a newer write, the seq load below sees it.
      for (std::size_t i = 0; i < kWords; ++i) buffer[i] = words_[i].load(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) == before) {
        std::memcpy(static_cast<void*>(&out), static_cast<const void*>(buffer.data()), sizeof(T));
        return before / 2;
      }
    }
  }

  alignas(64) std::atomic<std::uint64_t> seq_{0};
  std::array<std::atomic<std::uint64_t>, kWords> words_{};
  Doorbell* doorbell_ = nullptr;
};

}  // namespace aerotrack::rt
