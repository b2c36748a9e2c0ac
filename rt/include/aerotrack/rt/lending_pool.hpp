// A pool of large objects (map grids, camera frames) lent out as std::shared_ptr handles: the
// owner fills a free object and publishes it; readers on other threads keep their handle as long as
// they like; the object goes back to the pool when the last handle is dropped, on whichever thread
// that happens. Once warm, lending neither allocates nor copies more than the owner writes.
//
// Why not "reuse a pooled shared_ptr whose use_count() is back to 1": use_count() is a relaxed load,
// so seeing 1 does not order the owner's next writes after the reader's last reads. ThreadSanitizer
// caught exactly that (the mapper rewriting a grid the planner was still reading). Here the return
// is an explicit release store, made after the handle's reference count (an acq_rel atomic) reached
// zero, and the owner checks it with an acquire load: a real happens-before edge, which
// ThreadSanitizer can see because it is all plain atomics.
//
// How the return is observed without allocating: each slot carries room for the handle's control
// block, and the handle is made with an allocator that places the control block there. The
// standard library calls that allocator's deallocate() last of all, after the count reached zero
// and the control block was destroyed, so deallocate() is where the slot is marked free. The
// allocator also co-owns the slot, so a handle outliving the pool keeps its object alive.
//
// One owner thread calls acquire(); handles may be copied and dropped on any thread.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <vector>

namespace aerotrack::rt {

template <class T>
class LendingPool {
 public:
  /// `slots` objects, each a copy of prototype (which is also what the pool grows with).
  LendingPool(std::size_t slots, const T& prototype) : prototype_(prototype) {
    for (std::size_t i = 0; i < slots; ++i) slots_.push_back(std::make_shared<Slot>(prototype_));
  }

  /// Owner thread: a free object, left as its last borrower saw it (the caller overwrites what it
  /// needs), handed out as the only handle. If every object is lent, the pool grows by one.
  std::shared_ptr<T> acquire() {
    for (const std::shared_ptr<Slot>& slot : slots_)
      if (!slot->lent.load(std::memory_order_acquire)) return lend(slot);
    ++growths_;
    slots_.push_back(std::make_shared<Slot>(prototype_));
    return lend(slots_.back());
  }

  std::size_t size() const { return slots_.size(); }
  /// Objects added because every one was lent (a sign the pool is too small for its readers).
  std::uint64_t growths() const { return growths_; }

 private:
  // Comfortably above libstdc++'s control block for a pointer, an empty deleter and this allocator
  // (40 bytes on x86-64 and aarch64); allocate() refuses rather than overrun if that ever changes.
  static constexpr std::size_t kBlockBytes = 128;

  struct Slot {
    explicit Slot(const T& prototype) : object(prototype) {}
    T object;
    alignas(std::max_align_t) unsigned char block[kBlockBytes];
    std::atomic<bool> lent{false};
  };

  template <class U>
  struct BlockAllocator {
    using value_type = U;
    explicit BlockAllocator(std::shared_ptr<Slot> s) : slot(std::move(s)) {}
    template <class V>
    BlockAllocator(const BlockAllocator<V>& other) : slot(other.slot) {}  // NOLINT(google-explicit-constructor)
    U* allocate(std::size_t n) {
      if (n * sizeof(U) > kBlockBytes || alignof(U) > alignof(std::max_align_t)) throw std::bad_alloc();
      return reinterpret_cast<U*>(slot->block);  // NOLINT(cppcoreguidelines-pro-type-reinterpret-cast)
    }
    // Called once, after the last handle is gone and the control block destroyed: the borrower's
    // accesses all happen before this store, and acquire()'s acquire load pairs with it.
    void deallocate(U* /*p*/, std::size_t /*n*/) { slot->lent.store(false, std::memory_order_release); }
    template <class V>
    bool operator==(const BlockAllocator<V>& other) const {
      return slot == other.slot;
    }
    std::shared_ptr<Slot> slot;
  };

  struct KeepObject {
    void operator()(T* /*object*/) const {}  // the slot owns the object
  };

  static std::shared_ptr<T> lend(const std::shared_ptr<Slot>& slot) {
    slot->lent.store(true, std::memory_order_relaxed);  // only this thread sets it; no one reads it lent
    return std::shared_ptr<T>(&slot->object, KeepObject{}, BlockAllocator<T>(slot));
  }

  T prototype_;
  std::vector<std::shared_ptr<Slot>> slots_;
  std::uint64_t growths_ = 0;
};

}  // namespace aerotrack::rt
