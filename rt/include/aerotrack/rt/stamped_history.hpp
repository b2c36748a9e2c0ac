// A bounded, timestamped history with interpolated lookups: the drone's pose at an image's capture
// time, the gimbal's angle at it, ... One template for all of them; what a sample holds and how two
// samples are blended come from a traits class, so this file knows nothing of drones.
//
// Contract (the same for every instance):
// - push: samples must arrive in strictly increasing stamp order. A sample not newer than the newest
//   kept (older or a duplicate) is rejected and counted (kRejectedOutOfOrder), never reordered; one the
//   traits refuse (non-finite, ...) is rejected and counted (kRejectedInvalid). When the ring is full
//   the oldest sample is overwritten. O(1).
// - lookup(t): the two samples around t are found by binary search (rt::StampedRing::bracket) and
//   blended by Traits::interpolate, or a sample's own value when t is its stamp. Never extrapolates:
//   before the oldest sample, after the newest (beyond future_tolerance_ns, within which the newest is
//   held), or between two samples more than max_gap_ns apart, the lookup gives a status and no value.
//   O(log capacity).
//
// A traits class T provides (see the StampedHistoryTraits concept):
//   using Sample = ...;                 // what push() takes; has `TimeNs stamp_ns`
//   using Value = ...;                  // what lookup() gives
//   static constexpr std::string_view kName;                 // "pose history": error messages
//   static bool admit(Sample& s);      // false: refuse it; may normalise s in place (a quaternion)
//   static Value value(const Sample& s);                     // the value at s's own stamp
//   static Value interpolate(const Sample& a, const Sample& b, double alpha);  // alpha in (0, 1)
//   static Value none();               // optional: the value of a failed lookup (default Value{})
//
// Thread safety: none (one owner; const methods may run concurrently with each other).
// Allocation: the ring, once, in create(); push, lookup and valueAt never allocate (provided the
// traits' functions do not).
#pragma once

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/stamped_ring.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::rt {

struct StampedHistoryParams {
  std::size_t capacity = 512;                      ///< Samples kept (2.5 s at 200 Hz); >= 2.
  DurationNs max_gap_ns = 50 * kNsPerMillisecond;  ///< Samples around t farther apart: stale; > 0.
  /// A lookup at most this long after the newest sample gives the newest value unchanged (a hold,
  /// not an extrapolation); later lookups give nothing. >= 0; 0 (default): t > newest, nothing.
  DurationNs future_tolerance_ns = 0;
};

/// Why a lookup did or did not give a value (the ring's bracket outcomes).
using HistoryStatus = BracketStatus;

/// One phrase for a person, e.g. "newer than the newest sample".
constexpr const char* toString(HistoryStatus status) {
  switch (status) {
    case HistoryStatus::kOk:
      return "ok";
    case HistoryStatus::kEmpty:
      return "no sample yet";
    case HistoryStatus::kBeforeOldest:
      return "older than the oldest sample kept";
    case HistoryStatus::kAfterNewest:
      return "newer than the newest sample";
    case HistoryStatus::kGapTooLarge:
      return "the samples around that time are too far apart";
  }
  return "unknown";
}

/// Result of push().
enum class HistoryPush : std::uint8_t {
  kAccepted,
  kRejectedOutOfOrder,  ///< stamp_ns <= the newest stamp kept (older or duplicate).
  kRejectedInvalid,     ///< The traits refused it (non-finite values, a zero quaternion, ...).
};

template <class V>
struct HistoryLookup {
  HistoryStatus status = HistoryStatus::kEmpty;
  V value{};  ///< Valid when status == kOk; the traits' none() otherwise.
};

template <class T>
concept StampedHistoryTraits = requires(typename T::Sample& mutable_sample, const typename T::Sample& sample,
                                        double alpha) {
  { sample.stamp_ns } -> std::convertible_to<TimeNs>;
  { T::kName } -> std::convertible_to<std::string_view>;
  { T::admit(mutable_sample) } -> std::same_as<bool>;
  { T::value(sample) } -> std::convertible_to<typename T::Value>;
  { T::interpolate(sample, sample, alpha) } -> std::convertible_to<typename T::Value>;
};

template <StampedHistoryTraits Traits>
class StampedHistory {
 public:
  using Sample = typename Traits::Sample;
  using Value = typename Traits::Value;
  using Lookup = HistoryLookup<Value>;

  /// Ok if capacity >= 2, max_gap_ns > 0 and future_tolerance_ns >= 0; the error names Traits::kName.
  static Status validate(const StampedHistoryParams& params) {
    const std::string what(Traits::kName);
    if (params.capacity < 2) return Error{what + ": capacity must be >= 2, got " + std::to_string(params.capacity)};
    if (params.max_gap_ns <= 0)
      return Error{what + ": max_gap_ns must be > 0, got " + std::to_string(params.max_gap_ns)};
    if (params.future_tolerance_ns < 0) {
      return Error{what + ": future_tolerance_ns must be >= 0, got " + std::to_string(params.future_tolerance_ns)};
    }
    return ok();
  }

  /// Validates params and allocates the ring.
  static Expected<StampedHistory> create(const StampedHistoryParams& params) {
    if (Status status = validate(params); !status) return status.error();
    return StampedHistory(params);
  }

  /// Appends a sample (see the file comment for the order and validity rules). O(1), no allocation.
  HistoryPush push(const Sample& sample) {
    Sample admitted = sample;
    if (!Traits::admit(admitted)) {
      ++rejected_invalid_;
      return HistoryPush::kRejectedInvalid;
    }
    if (!ring_.accepts(admitted.stamp_ns)) {
      ++rejected_out_of_order_;
      return HistoryPush::kRejectedOutOfOrder;
    }
    ring_.push(admitted.stamp_ns, admitted);
    ++accepted_;
    return HistoryPush::kAccepted;
  }

  /// The value at t_ns: a sample's own value when t is its stamp (or a hold of the newest), else
  /// Traits::interpolate between the two samples around t. O(log size), no allocation.
  Lookup lookup(TimeNs t_ns) const {
    const Bracket b = ring_.bracket(t_ns, params_.max_gap_ns, params_.future_tolerance_ns);
    if (b.status != HistoryStatus::kOk) return Lookup{b.status, none()};
    if (b.alpha == 0.0) return Lookup{b.status, Traits::value(ring_.at(b.lo))};
    return Lookup{b.status, Traits::interpolate(ring_.at(b.lo), ring_.at(b.hi), b.alpha)};
  }
  /// lookup(t_ns) as an optional: nothing unless its status is kOk.
  std::optional<Value> valueAt(TimeNs t_ns) const {
    Lookup result = lookup(t_ns);
    if (result.status != HistoryStatus::kOk) return std::nullopt;
    return std::move(result.value);
  }

  std::size_t size() const { return ring_.size(); }
  std::size_t capacity() const { return params_.capacity; }
  bool empty() const { return ring_.empty(); }
  /// The i-th sample kept, in time order (0: oldest), as admitted (normalised). i < size().
  const Sample& at(std::size_t i) const { return ring_.at(i); }
  /// The oldest / newest sample kept; precondition: !empty().
  const Sample& oldest() const { return ring_.at(0); }
  const Sample& newest() const { return ring_.at(ring_.size() - 1); }

  std::uint64_t acceptedCount() const { return accepted_; }
  std::uint64_t rejectedOutOfOrderCount() const { return rejected_out_of_order_; }
  std::uint64_t rejectedInvalidCount() const { return rejected_invalid_; }
  /// Every rejection, out of order or invalid.
  std::uint64_t rejectedCount() const { return rejected_out_of_order_ + rejected_invalid_; }
  const StampedHistoryParams& params() const { return params_; }

 private:
  explicit StampedHistory(const StampedHistoryParams& params) : params_(params), ring_(params.capacity) {}

  static Value none() {
    if constexpr (requires { Traits::none(); }) {
      return Traits::none();
    } else {
      return Value{};
    }
  }

  StampedHistoryParams params_;
  StampedRing<Sample> ring_;
  std::uint64_t accepted_ = 0;
  std::uint64_t rejected_out_of_order_ = 0;
  std::uint64_t rejected_invalid_ = 0;
};

}  // namespace aerotrack::rt
