// GimbalAngleHistory: the gimbal's recent encoder angles, to look up the angle at the capture
// time of an image (issue 6, item 4; the paper's Sect. IV-B moves p_C to the world frame with the
// camera pose of that image). The angle is unwrapped and multi-turn (hal::GimbalState), so
// linear interpolation between the two samples around t is exact for a constant rate and never
// takes the short way round a wrap. The same contract as mapping::PoseHistory: a fixed-capacity
// ring in strictly increasing stamp order, allocated once; no extrapolation (before the oldest,
// after the newest beyond an optional hold tolerance, or across a gap longer than max_gap_ns:
// nothing).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/stamped_ring.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::estimation {

struct GimbalHistoryParams {
  std::size_t capacity = 512;                              ///< Samples kept (2.5 s at 200 Hz); >= 2.
  rt::DurationNs max_gap_ns = 50 * rt::kNsPerMillisecond;  ///< Bracketing samples farther apart: stale; > 0.
  /// A lookup at most this long after the newest sample returns the newest angle (a hold); >= 0.
  rt::DurationNs future_tolerance_ns = 0;
};

/// Ok if capacity >= 2, max_gap_ns > 0 and future_tolerance_ns >= 0.
rt::Status validate(const GimbalHistoryParams& params);

enum class HistoryLookupStatus : std::uint8_t { kOk, kEmpty, kBeforeOldest, kAfterNewest, kGapTooLarge };
/// One line for a person, e.g. "newer than the newest gimbal sample".
const char* toString(HistoryLookupStatus status);

struct GimbalAngleLookup {
  HistoryLookupStatus status = HistoryLookupStatus::kEmpty;
  double angle_rad = 0.0;  ///< Unwrapped, about body z from body x; valid when status == kOk.
};

/// Thread safety: none (one owner; const lookups may run concurrently with each other only).
/// Allocation: the ring, once, in create(); push and lookups never allocate.
class GimbalAngleHistory {
 public:
  static rt::Expected<GimbalAngleHistory> create(const GimbalHistoryParams& params);

  /// Appends a sample. False (and counted) if its stamp is not newer than the newest kept or its
  /// angle is not finite. When full, the oldest is overwritten. O(1).
  bool push(const hal::GimbalState& sample);

  /// The angle at t_ns, linearly interpolated between the samples around it. O(log capacity).
  GimbalAngleLookup lookup(rt::TimeNs t_ns) const;

  std::size_t size() const { return ring_.size(); }
  bool empty() const { return ring_.empty(); }
  std::uint64_t rejectedCount() const { return rejected_; }

 private:
  explicit GimbalAngleHistory(const GimbalHistoryParams& params);

  GimbalHistoryParams params_;
  rt::StampedRing<double> ring_;  ///< Unwrapped angles, radians.
  std::uint64_t rejected_ = 0;
};

}  // namespace aerotrack::estimation
