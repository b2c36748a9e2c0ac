// GimbalAngleHistory: a ring of encoder angles and interpolated lookups (see gimbal_history.hpp).
#include "aerotrack/estimation/gimbal_history.hpp"

#include <cmath>
#include <string>

namespace aerotrack::estimation {

rt::Status validate(const GimbalHistoryParams& params) {
  if (params.capacity < 2) {
    return rt::Error{"gimbal history: capacity must be >= 2, got " + std::to_string(params.capacity)};
  }
  if (params.max_gap_ns <= 0) {
    return rt::Error{"gimbal history: max_gap_ns must be > 0, got " + std::to_string(params.max_gap_ns)};
  }
  if (params.future_tolerance_ns < 0) {
    return rt::Error{"gimbal history: future_tolerance_ns must be >= 0, got " +
                     std::to_string(params.future_tolerance_ns)};
  }
  return rt::ok();
}

const char* toString(HistoryLookupStatus status) {
  switch (status) {
    case HistoryLookupStatus::kOk:
      return "ok";
    case HistoryLookupStatus::kEmpty:
      return "no gimbal sample yet";
    case HistoryLookupStatus::kBeforeOldest:
      return "older than the oldest gimbal sample kept";
    case HistoryLookupStatus::kAfterNewest:
      return "newer than the newest gimbal sample";
    case HistoryLookupStatus::kGapTooLarge:
      return "gimbal sample gap around that time is too long";
  }
  return "unknown";
}

rt::Expected<GimbalAngleHistory> GimbalAngleHistory::create(const GimbalHistoryParams& params) {
  if (rt::Status status = validate(params); !status) return status.error();
  return GimbalAngleHistory(params);
}

GimbalAngleHistory::GimbalAngleHistory(const GimbalHistoryParams& params) : params_(params), ring_(params.capacity) {}

bool GimbalAngleHistory::push(const hal::GimbalState& sample) {
  if (!std::isfinite(sample.angle_rad) || (size_ > 0 && sample.stamp_ns <= at(size_ - 1).stamp_ns)) {
    ++rejected_;
    return false;
  }
  std::size_t slot = 0;
  if (size_ < ring_.size()) {
    slot = (head_ + size_) % ring_.size();
    ++size_;
  } else {
    slot = head_;
    head_ = (head_ + 1) % ring_.size();
  }
  ring_[slot] = {sample.stamp_ns, sample.angle_rad};
  return true;
}

GimbalAngleLookup GimbalAngleHistory::lookup(rt::TimeNs t_ns) const {
  GimbalAngleLookup result;
  if (size_ == 0) return result;
  if (t_ns < at(0).stamp_ns) {
    result.status = HistoryLookupStatus::kBeforeOldest;
    return result;
  }
  const Sample& last = at(size_ - 1);
  if (t_ns >= last.stamp_ns) {
    if (t_ns - last.stamp_ns > params_.future_tolerance_ns) {
      result.status = HistoryLookupStatus::kAfterNewest;
      return result;
    }
    result.status = HistoryLookupStatus::kOk;
    result.angle_rad = last.angle_rad;
    return result;
  }
  std::size_t lo = 0;  // at(lo).stamp <= t < at(hi).stamp
  std::size_t hi = size_ - 1;
  while (hi - lo > 1) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (at(mid).stamp_ns <= t_ns) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  const Sample& a = at(lo);
  const Sample& b = at(hi);
  if (t_ns == a.stamp_ns) {
    result.status = HistoryLookupStatus::kOk;
    result.angle_rad = a.angle_rad;
    return result;
  }
  if (b.stamp_ns - a.stamp_ns > params_.max_gap_ns) {
    result.status = HistoryLookupStatus::kGapTooLarge;
    return result;
  }
  const double alpha = static_cast<double>(t_ns - a.stamp_ns) / static_cast<double>(b.stamp_ns - a.stamp_ns);
  result.status = HistoryLookupStatus::kOk;
  result.angle_rad = a.angle_rad + alpha * (b.angle_rad - a.angle_rad);
  return result;
}

}  // namespace aerotrack::estimation
