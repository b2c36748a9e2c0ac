// PoseHistory: a ring of odometry samples and interpolated pose lookups (see pose_history.hpp).
#include "aerotrack/mapping/pose_history.hpp"

#include <string>

namespace aerotrack::mapping {

rt::Status validate(const PoseHistoryParams& params) {
  if (params.capacity < 2) {
    return rt::Error{"pose history: capacity must be >= 2, got " + std::to_string(params.capacity)};
  }
  if (params.max_gap_ns <= 0) {
    return rt::Error{"pose history: max_gap_ns must be > 0, got " + std::to_string(params.max_gap_ns)};
  }
  if (params.future_tolerance_ns < 0) {
    return rt::Error{"pose history: future_tolerance_ns must be >= 0, got " +
                     std::to_string(params.future_tolerance_ns)};
  }
  return rt::ok();
}

const char* toString(PoseLookupStatus status) {
  switch (status) {
    case PoseLookupStatus::kOk:
      return "ok";
    case PoseLookupStatus::kEmpty:
      return "no odometry yet";
    case PoseLookupStatus::kBeforeOldest:
      return "older than the oldest odometry kept";
    case PoseLookupStatus::kAfterNewest:
      return "newer than the newest odometry";
    case PoseLookupStatus::kGapTooLarge:
      return "odometry gap around that time is too long";
  }
  return "unknown";
}

rt::Expected<PoseHistory> PoseHistory::create(const PoseHistoryParams& params) {
  if (rt::Status status = validate(params); !status) return status.error();
  return PoseHistory(params);
}

PoseHistory::PoseHistory(const PoseHistoryParams& params) : params_(params), ring_(params.capacity) {}

PushResult PoseHistory::push(const hal::OdometrySample& sample) {
  const double q_norm = sample.q_WB.norm();
  if (!sample.p_WB_m.allFinite() || !sample.q_WB.coeffs().allFinite() || !(q_norm > 1e-9)) {
    ++rejected_non_finite_;
    return PushResult::kRejectedNonFinite;
  }
  if (!ring_.accepts(sample.stamp_ns)) {
    ++rejected_out_of_order_;
    return PushResult::kRejectedOutOfOrder;
  }
  hal::OdometrySample normalised = sample;
  normalised.q_WB.coeffs() /= q_norm;
  ring_.push(sample.stamp_ns, normalised);
  ++accepted_;
  return PushResult::kAccepted;
}

PoseLookup PoseHistory::lookup(rt::TimeNs t_ns) const {
  // The statuses are the ring's, in the same order.
  static_assert(static_cast<int>(PoseLookupStatus::kOk) == static_cast<int>(rt::BracketStatus::kOk) &&
                static_cast<int>(PoseLookupStatus::kEmpty) == static_cast<int>(rt::BracketStatus::kEmpty) &&
                static_cast<int>(PoseLookupStatus::kBeforeOldest) ==
                    static_cast<int>(rt::BracketStatus::kBeforeOldest) &&
                static_cast<int>(PoseLookupStatus::kAfterNewest) == static_cast<int>(rt::BracketStatus::kAfterNewest) &&
                static_cast<int>(PoseLookupStatus::kGapTooLarge) == static_cast<int>(rt::BracketStatus::kGapTooLarge));
  const rt::Bracket b = ring_.bracket(t_ns, params_.max_gap_ns, params_.future_tolerance_ns);
  PoseLookup result;
  result.status = static_cast<PoseLookupStatus>(b.status);
  if (b.status != rt::BracketStatus::kOk) return result;
  const hal::OdometrySample& a = at(b.lo);
  if (b.alpha == 0.0) {  // a sample's own time, or a hold of the newest
    result.T_WB.linear() = a.q_WB.toRotationMatrix();
    result.T_WB.translation() = a.p_WB_m;
    return result;
  }
  const hal::OdometrySample& c = at(b.hi);
  result.T_WB.linear() = a.q_WB.slerp(b.alpha, c.q_WB).toRotationMatrix();
  result.T_WB.translation() = a.p_WB_m + b.alpha * (c.p_WB_m - a.p_WB_m);
  return result;
}

std::optional<Eigen::Isometry3d> PoseHistory::poseAt(rt::TimeNs t_ns) const {
  const PoseLookup result = lookup(t_ns);
  if (result.status != PoseLookupStatus::kOk) return std::nullopt;
  return result.T_WB;
}

}  // namespace aerotrack::mapping
