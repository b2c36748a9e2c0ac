// Whether a frame of zeros from the depth camera means a dead camera or the sky.
//
// A depth frame with almost no valid pixel is as blind as no frame (issue 23's fault matrix: frames of zeros fed
// a stale map), so the depth task drops it and the supervisor's depth failsafe sees the camera as silent. But a
// working camera returns zeros too where nothing lies within its range: the sky. The depth camera is fixed to the
// body, and a quadrotor braking hard pitches its nose up: at 20-29 degrees nose-up for over a second (crowd seed 2,
// image mode, braking at the world's edge) the D435's 58-degree field held no ground, every frame was dropped as
// dead, and the supervisor held the drone while the person walked on. A frame of zeros is the camera's fault only
// when the camera's view, at the drone's attitude and height, holds ground a working camera would range.
#pragma once

#include <Eigen/Geometry>

#include "aerotrack/hal/types.hpp"

namespace aerotrack::hal {

/// Fewer than 0.5 % of the frame's pixels (every 8th row and column) hold a depth (> 0 and finite), or none sampled.
bool isBlankDepth(const DepthFrame& frame);

/// Whether some pixel's line of sight from the camera at T_WC (optical frame: x right, y down, z forward, in W)
/// meets the ground -- the plane z = 0 of W, below the camera -- nearer than reach_m. The most downward line of
/// sight of a pinhole lies on the image's border or, looking steeply down, inside it: the corners, the edges'
/// midpoints and the principal point are checked. A camera at or below the ground: true.
bool viewHoldsGroundWithin(const Eigen::Isometry3d& T_WC, const CameraIntrinsics& intrinsics, double reach_m);

}  // namespace aerotrack::hal
