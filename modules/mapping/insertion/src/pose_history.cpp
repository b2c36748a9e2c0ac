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
  if (size_ > 0 && sample.stamp_ns <= newest().stamp_ns) {
    ++rejected_out_of_order_;
    return PushResult::kRejectedOutOfOrder;
  }
  std::size_t slot = 0;
  if (size_ < ring_.size()) {
    slot = (head_ + size_) % ring_.size();
    ++size_;
  } else {  // Full: overwrite the oldest.
    slot = head_;
    head_ = (head_ + 1) % ring_.size();
  }
  ring_[slot] = sample;
  ring_[slot].q_WB.coeffs() /= q_norm;
  ++accepted_;
  return PushResult::kAccepted;
}

PoseLookup PoseHistory::lookup(rt::TimeNs t_ns) const {
  PoseLookup result;
  if (size_ == 0) {
    result.status = PoseLookupStatus::kEmpty;
    return result;
  }
  if (t_ns < oldest().stamp_ns) {
    result.status = PoseLookupStatus::kBeforeOldest;
    return result;
  }
  const hal::OdometrySample& last = newest();
  if (t_ns >= last.stamp_ns) {
    // Equal: the newest sample itself. Later: a hold within the tolerance, else nothing.
    if (t_ns - last.stamp_ns > params_.future_tolerance_ns) {
      result.status = PoseLookupStatus::kAfterNewest;
      return result;
    }
    result.status = PoseLookupStatus::kOk;
    result.T_WB.linear() = last.q_WB.toRotationMatrix();
    result.T_WB.translation() = last.p_WB_m;
    return result;
  }
  // Here oldest <= t < newest and size_ >= 2: find the first sample with stamp > t (index hi in
  // [1, size_ - 1]); the sample before it has stamp <= t.
  std::size_t lo = 0;
  std::size_t hi = size_ - 1;
  while (hi - lo > 1) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (at(mid).stamp_ns <= t_ns) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  const hal::OdometrySample& a = at(lo);
  const hal::OdometrySample& b = at(hi);
  result.status = PoseLookupStatus::kOk;
  if (t_ns == a.stamp_ns) {
    result.T_WB.linear() = a.q_WB.toRotationMatrix();
    result.T_WB.translation() = a.p_WB_m;
    return result;
  }
  const rt::DurationNs gap_ns = b.stamp_ns - a.stamp_ns;
  if (gap_ns > params_.max_gap_ns) {
    result.status = PoseLookupStatus::kGapTooLarge;
    return result;
  }
  const double alpha = static_cast<double>(t_ns - a.stamp_ns) / static_cast<double>(gap_ns);
  result.T_WB.linear() = a.q_WB.slerp(alpha, b.q_WB).toRotationMatrix();
  result.T_WB.translation() = a.p_WB_m + alpha * (b.p_WB_m - a.p_WB_m);
  return result;
}

std::optional<Eigen::Isometry3d> PoseHistory::poseAt(rt::TimeNs t_ns) const {
  const PoseLookup result = lookup(t_ns);
  if (result.status != PoseLookupStatus::kOk) return std::nullopt;
  return result.T_WB;
}

}  // namespace aerotrack::mapping
