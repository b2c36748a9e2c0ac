// Latest-value channel for large immutable data (images, map snapshots, trajectories), passed as
// shared handles (DESIGN.md rule 4): the writer publishes a std::shared_ptr<const T>; readers get
// their own reference and may keep it as long as they like, so the writer never waits for a
// reader's work and a reader never sees a half-written object.
//
// The handle itself is guarded by a priority-inheritance mutex held only for a pointer swap or a
// reference-count increment (tens of nanoseconds, never across user code); the previous object
// is released after the lock is dropped. We do not use std::atomic<std::shared_ptr>: libstdc++ 12
// implements it with a lock bit that ThreadSanitizer cannot see, so the concurrency tests could
// not check it, and it has no priority inheritance either. The object is allocated by the
// producer, outside the channel; the last holder of a handle frees it.
#pragma once

#include <pthread.h>

#include <atomic>
#include <cstdint>
#include <memory>

#include "aerotrack/rt/doorbell.hpp"

namespace aerotrack::rt {

template <class T>
class SharedSlot {
 public:
  using Handle = std::shared_ptr<const T>;

  SharedSlot() {
    pthread_mutexattr_t attr;
    pthread_mutexattr_init(&attr);
    pthread_mutexattr_setprotocol(&attr, PTHREAD_PRIO_INHERIT);
    pthread_mutex_init(&mutex_, &attr);
    pthread_mutexattr_destroy(&attr);
  }
  ~SharedSlot() { pthread_mutex_destroy(&mutex_); }
  SharedSlot(const SharedSlot&) = delete;
  SharedSlot& operator=(const SharedSlot&) = delete;

  void attachDoorbell(Doorbell* doorbell) { doorbell_ = doorbell; }

  /// Any writer thread (normally one). Publishes a new handle; no allocation.
  void write(Handle handle) {
    pthread_mutex_lock(&mutex_);
    value_.swap(handle);
    version_.fetch_add(1, std::memory_order_release);
    pthread_mutex_unlock(&mutex_);
    handle.reset();  // the previous object, if this was its last holder, is freed here
    if (doorbell_ != nullptr) doorbell_->ring();
  }

  /// Any reader thread: the newest handle, or an empty one if nothing was written.
  Handle read() const {
    pthread_mutex_lock(&mutex_);
    Handle out = value_;
    pthread_mutex_unlock(&mutex_);
    return out;
  }

  /// Number of writes so far.
  std::uint64_t version() const { return version_.load(std::memory_order_acquire); }

 private:
  mutable pthread_mutex_t mutex_;
  Handle value_;
  std::atomic<std::uint64_t> version_{0};
  Doorbell* doorbell_ = nullptr;
};

}  // namespace aerotrack::rt
