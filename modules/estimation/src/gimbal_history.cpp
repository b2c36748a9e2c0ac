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
  if (!std::isfinite(sample.angle_rad) || !ring_.accepts(sample.stamp_ns)) {
    ++rejected_;
    return false;
  }
  ring_.push(sample.stamp_ns, sample.angle_rad);
  return true;
}

GimbalAngleLookup GimbalAngleHistory::lookup(rt::TimeNs t_ns) const {
  // The statuses are the ring's, in the same order.
  static_assert(
      static_cast<int>(HistoryLookupStatus::kOk) == static_cast<int>(rt::BracketStatus::kOk) &&
      static_cast<int>(HistoryLookupStatus::kEmpty) == static_cast<int>(rt::BracketStatus::kEmpty) &&
      static_cast<int>(HistoryLookupStatus::kBeforeOldest) == static_cast<int>(rt::BracketStatus::kBeforeOldest) &&
      static_cast<int>(HistoryLookupStatus::kAfterNewest) == static_cast<int>(rt::BracketStatus::kAfterNewest) &&
      static_cast<int>(HistoryLookupStatus::kGapTooLarge) == static_cast<int>(rt::BracketStatus::kGapTooLarge));
  const rt::Bracket b = ring_.bracket(t_ns, params_.max_gap_ns, params_.future_tolerance_ns);
  GimbalAngleLookup result;
  result.status = static_cast<HistoryLookupStatus>(b.status);
  if (b.status != rt::BracketStatus::kOk) return result;
  const double a = ring_.at(b.lo);
  result.angle_rad = b.alpha == 0.0 ? a : a + b.alpha * (ring_.at(b.hi) - a);
  return result;
}

}  // namespace aerotrack::estimation
