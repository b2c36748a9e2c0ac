// Latest-value channel for large immutable data (images, map snapshots, trajectories), passed as
// shared handles (DESIGN.md rule 4): the writer publishes a std::shared_ptr<const T>; readers get
// their own reference and may keep it as long as they like, so the writer never waits for them
// and a reader never sees a half-written object.
//
// Built on std::atomic<std::shared_ptr> (C++20). libstdc++ implements it with a lock bit held for
// a pointer swap and a reference-count increment (tens of nanoseconds), not across user code.
// The object itself is allocated by the producer, outside the channel; the last reader to drop a
// handle frees it.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>

#include "aerotrack/rt/doorbell.hpp"

namespace aerotrack::rt {

template <class T>
class SharedSlot {
 public:
  using Handle = std::shared_ptr<const T>;

  void attachDoorbell(Doorbell* doorbell) { doorbell_ = doorbell; }

  /// Any writer thread (normally one). Publishes a new handle; no allocation.
  void write(Handle handle) {
    value_.store(std::move(handle), std::memory_order_release);
    version_.fetch_add(1, std::memory_order_acq_rel);
    if (doorbell_ != nullptr) doorbell_->ring();
  }

  /// Any reader thread: the newest handle, or an empty one if nothing was written.
  Handle read() const { return value_.load(std::memory_order_acquire); }

  /// Number of writes so far.
  std::uint64_t version() const { return version_.load(std::memory_order_acquire); }

 private:
  std::atomic<Handle> value_;
  std::atomic<std::uint64_t> version_{0};
  Doorbell* doorbell_ = nullptr;
};

}  // namespace aerotrack::rt
