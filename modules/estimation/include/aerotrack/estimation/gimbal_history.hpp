// GimbalAngleHistory: the gimbal's recent encoder angles, to look up the angle at the capture
// time of an image (issue 6, item 4; the paper's Sect. IV-B moves p_C to the world frame with the
// camera pose of that image). An instance of rt::StampedHistory, the contract the drone's pose
// history (hal::OdometryHistory) shares: a fixed-capacity ring in strictly increasing stamp order,
// allocated once; no extrapolation (before the oldest, after the newest beyond an optional hold
// tolerance, or across a gap longer than max_gap_ns: a status and no angle). The angle is unwrapped
// and multi-turn (hal::GimbalState), so linear interpolation between the two samples around t is
// exact for a constant rate and never takes the short way round a wrap.
#pragma once

#include <cmath>
#include <string_view>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/stamped_history.hpp"

namespace aerotrack::estimation {

/// rt::StampedHistory traits of the gimbal encoder: angle_rad (unwrapped, about body z from body x).
struct GimbalAngleTraits {
  using Sample = hal::GimbalState;
  using Value = double;
  static constexpr std::string_view kName = "gimbal history";

  /// Refuses a non-finite angle.
  static bool admit(const hal::GimbalState& s) { return std::isfinite(s.angle_rad); }
  static double value(const hal::GimbalState& s) { return s.angle_rad; }
  /// a + alpha (b - a) in the unwrapped angle.
  static double interpolate(const hal::GimbalState& a, const hal::GimbalState& b, double alpha) {
    return a.angle_rad + alpha * (b.angle_rad - a.angle_rad);
  }
};

/// Thread safety: none (one owner). Allocation: once, in create(); push and lookups never allocate.
using GimbalAngleHistory = rt::StampedHistory<GimbalAngleTraits>;
/// capacity (>= 2, default 512), max_gap_ns (> 0, default 50 ms), future_tolerance_ns (>= 0, default 0).
using GimbalHistoryParams = rt::StampedHistoryParams;
using HistoryLookupStatus = rt::HistoryStatus;
using GimbalAngleLookup = rt::HistoryLookup<double>;  ///< value: angle_rad when status is kOk.

}  // namespace aerotrack::estimation
