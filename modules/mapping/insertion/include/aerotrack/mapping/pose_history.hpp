// PoseHistory: the vehicle's recent odometry, to look up the body pose T_WB at the capture time of
// a depth frame (issue 4). It is hal::OdometryHistory (hal/odometry_history.hpp), the one
// rt::StampedHistory of odometry that the target estimator shares: a fixed-capacity ring in strictly
// increasing stamp order, allocated once; lookups interpolate position linearly and orientation by
// slerp and never extrapolate (before the oldest, after the newest beyond future_tolerance_ns, or
// across a gap longer than max_gap_ns: a status and no pose). These names are the mapping's for it.
#pragma once

#include <Eigen/Geometry>

#include "aerotrack/hal/odometry_history.hpp"
#include "aerotrack/rt/stamped_history.hpp"

namespace aerotrack::mapping {

using PoseHistory = hal::OdometryHistory;
/// capacity (>= 2, default 512), max_gap_ns (> 0, default 50 ms), future_tolerance_ns (>= 0, default 0).
using PoseHistoryParams = rt::StampedHistoryParams;
using PoseLookupStatus = rt::HistoryStatus;
using PoseLookup = rt::HistoryLookup<Eigen::Isometry3d>;  ///< value: T_WB when status is kOk.
using PushResult = rt::HistoryPush;

}  // namespace aerotrack::mapping
