// PoseHistory: the vehicle's recent odometry, to look up the body pose T_WB at the capture time of
// a depth frame (issue 4). A fixed-capacity ring of hal::OdometrySample in strictly increasing
// stamp order, allocated once. A lookup binary-searches the two samples around t and interpolates
// between them: position linearly, orientation by spherical linear interpolation (slerp, shortest
// arc). It never extrapolates: before the oldest sample, after the newest (beyond an optional
// hold tolerance) or across a gap longer than max_gap_ns it returns nothing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/stamped_ring.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::mapping {

struct PoseHistoryParams {
  std::size_t capacity = 512;                              ///< Samples kept (2.5 s at 200 Hz); >= 2.
  rt::DurationNs max_gap_ns = 50 * rt::kNsPerMillisecond;  ///< Bracketing samples farther apart: stale; > 0.
  /// A lookup at most this long after the newest sample returns the newest pose unchanged (a
  /// hold, not an extrapolation); later lookups return nothing. 0 (default): t > newest, nothing.
  rt::DurationNs future_tolerance_ns = 0;
};

/// Ok if capacity >= 2, max_gap_ns > 0 and future_tolerance_ns >= 0.
rt::Status validate(const PoseHistoryParams& params);

/// Why a lookup did or did not give a pose.
enum class PoseLookupStatus : std::uint8_t {
  kOk,
  kEmpty,         ///< No sample yet.
  kBeforeOldest,  ///< t is older than the oldest sample kept.
  kAfterNewest,   ///< t is newer than the newest sample (+ future_tolerance_ns): odometry lags.
  kGapTooLarge,   ///< The samples around t are more than max_gap_ns apart.
};
const char* toString(PoseLookupStatus status);

struct PoseLookup {
  PoseLookupStatus status = PoseLookupStatus::kEmpty;
  Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();  ///< Valid when status == kOk.
};

/// Result of push().
enum class PushResult : std::uint8_t {
  kAccepted,
  kRejectedOutOfOrder,  ///< stamp_ns <= the newest stamp (older or duplicate).
  kRejectedNonFinite,   ///< Non-finite position or orientation, or a zero quaternion.
};

/// Thread safety: none (one owner; const lookups may run concurrently with each other only).
/// Allocation: the ring, once, in create(); push and lookups never allocate.
class PoseHistory {
 public:
  /// Validates params and allocates the ring.
  static rt::Expected<PoseHistory> create(const PoseHistoryParams& params);

  /// Appends a sample (W world ENU, B body FLU). Rejected and counted if its stamp is not newer
  /// than the newest one kept or if p_WB_m / q_WB are not finite (or q_WB has zero norm). q_WB is
  /// stored normalised. When full, the oldest sample is overwritten. O(1).
  PushResult push(const hal::OdometrySample& sample);

  /// T_WB (body in world) at t_ns, interpolated (linear position, slerp rotation) between the
  /// two samples around t, or exactly a sample when t equals its stamp. O(log capacity).
  PoseLookup lookup(rt::TimeNs t_ns) const;
  /// lookup(t_ns) as an optional: nothing unless status is kOk.
  std::optional<Eigen::Isometry3d> poseAt(rt::TimeNs t_ns) const;

  std::size_t size() const { return ring_.size(); }
  std::size_t capacity() const { return params_.capacity; }
  bool empty() const { return ring_.empty(); }
  /// The oldest / newest sample kept; precondition: !empty().
  const hal::OdometrySample& oldest() const { return at(0); }
  const hal::OdometrySample& newest() const { return at(ring_.size() - 1); }

  std::uint64_t acceptedCount() const { return accepted_; }
  std::uint64_t rejectedOutOfOrderCount() const { return rejected_out_of_order_; }
  std::uint64_t rejectedNonFiniteCount() const { return rejected_non_finite_; }
  const PoseHistoryParams& params() const { return params_; }

 private:
  explicit PoseHistory(const PoseHistoryParams& params);
  /// i-th sample in time order (0: oldest).
  const hal::OdometrySample& at(std::size_t i) const { return ring_.at(i); }

  PoseHistoryParams params_;
  rt::StampedRing<hal::OdometrySample> ring_;
  std::uint64_t accepted_ = 0;
  std::uint64_t rejected_out_of_order_ = 0;
  std::uint64_t rejected_non_finite_ = 0;
};

}  // namespace aerotrack::mapping
