// A time-ordered ring of stamped samples and the bracket search that interpolating histories need
// (the drone's pose at an image's capture time, the gimbal's angle, ...): samples arrive in strictly
// increasing stamp order, the oldest is overwritten when the ring is full, and for a time t the
// search finds the samples around it. It knows nothing of what a sample holds: the owner
// interpolates. Thread safety: none (one owner; const methods may run concurrently with each other).
// Allocation: once, in the constructor.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "aerotrack/rt/time.hpp"

namespace aerotrack::rt {

enum class BracketStatus : std::uint8_t {
  kOk,            ///< lo/hi/alpha are valid.
  kEmpty,         ///< No sample yet.
  kBeforeOldest,  ///< t is older than the oldest sample kept.
  kAfterNewest,   ///< t is newer than the newest sample by more than the tolerance.
  kGapTooLarge,   ///< The samples around t are farther apart than the allowed gap.
};

/// Where t falls: the value at t is at(lo) when alpha == 0 (t is a sample's stamp, or a hold of the
/// newest within the tolerance), else at(lo) + alpha (at(hi) - at(lo)) with alpha in (0, 1).
struct Bracket {
  BracketStatus status = BracketStatus::kEmpty;
  std::size_t lo = 0;
  std::size_t hi = 0;
  double alpha = 0.0;
};

template <class T>
class StampedRing {
 public:
  /// capacity >= 2 (the caller validates).
  explicit StampedRing(std::size_t capacity) : ring_(capacity) {}

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  /// True if a sample stamped stamp_ns may be pushed: newer than the newest kept.
  bool accepts(TimeNs stamp_ns) const { return size_ == 0 || stamp_ns > stampAt(size_ - 1); }
  /// Appends a sample the ring accepts(); when full, overwrites the oldest. O(1), no allocation.
  void push(TimeNs stamp_ns, const T& value) {
    std::size_t slot = 0;
    if (size_ < ring_.size()) {
      slot = (head_ + size_) % ring_.size();
      ++size_;
    } else {
      slot = head_;
      head_ = (head_ + 1) % ring_.size();
    }
    ring_[slot] = {stamp_ns, value};
  }
  /// The i-th sample in time order (0: oldest) and its stamp. i < size().
  const T& at(std::size_t i) const { return ring_[(head_ + i) % ring_.size()].value; }
  TimeNs stampAt(std::size_t i) const { return ring_[(head_ + i) % ring_.size()].stamp_ns; }

  /// The samples around t_ns by binary search, O(log size). A t after the newest sample by at most
  /// future_tolerance_ns holds the newest (no extrapolation).
  Bracket bracket(TimeNs t_ns, DurationNs max_gap_ns, DurationNs future_tolerance_ns) const {
    Bracket b;
    if (size_ == 0) return b;
    if (t_ns < stampAt(0)) {
      b.status = BracketStatus::kBeforeOldest;
      return b;
    }
    if (t_ns >= stampAt(size_ - 1)) {
      b.status = t_ns - stampAt(size_ - 1) > future_tolerance_ns ? BracketStatus::kAfterNewest : BracketStatus::kOk;
      b.lo = b.hi = size_ - 1;
      return b;
    }
    // Here oldest <= t < newest and size >= 2: stampAt(lo) <= t < stampAt(hi).
    std::size_t lo = 0;
    std::size_t hi = size_ - 1;
    while (hi - lo > 1) {
      const std::size_t mid = lo + (hi - lo) / 2;
      if (stampAt(mid) <= t_ns)
        lo = mid;
      else
        hi = mid;
    }
    b.lo = lo;
    b.hi = hi;
    b.status = BracketStatus::kOk;
    if (t_ns == stampAt(lo)) return b;
    const DurationNs gap_ns = stampAt(hi) - stampAt(lo);
    if (gap_ns > max_gap_ns) {
      b.status = BracketStatus::kGapTooLarge;
      return b;
    }
    b.alpha = static_cast<double>(t_ns - stampAt(lo)) / static_cast<double>(gap_ns);
    return b;
  }

 private:
  struct Entry {
    TimeNs stamp_ns = 0;
    T value{};
  };
  std::vector<Entry> ring_;
  std::size_t head_ = 0;  ///< Index in ring_ of the oldest sample.
  std::size_t size_ = 0;
};

}  // namespace aerotrack::rt
