// Shared by the target task's tests that range people with the depth camera: a depth image rendered from upright
// bodies, seen from the drone hovering at the origin (target_task_test_util.hpp's pose), and a task rig that ranges
// with it.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/time.hpp"
#include "support/require.hpp"
#include "target_task_test_util.hpp"

namespace aerotrack::estimation::test {

/// A depth camera at the drone's origin looking along W x (160 x 120, 90 degrees): each pixel's range along the
/// optical axis to the nearest of the upright bodies (circles in x-y of radius body_radius_m), else background_m
/// (0: no data, as a stereo camera gives where it sees nothing).
inline std::shared_ptr<hal::DepthFrame> renderBodiesDepth(rt::TimeNs t_ns, const std::vector<Eigen::Vector2d>& bodies_m,
                                                          double body_radius_m, double background_m = 0.0) {
  auto frame = std::make_shared<hal::DepthFrame>();
  frame->stamp_ns = t_ns;
  frame->intrinsics = {160, 120, 80.0, 80.0, 80.0, 60.0, {}};
  // Optical x right, y down, z forward, in the body's x forward, y left, z up.
  frame->T_BC.linear() << 0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, -1.0, 0.0;
  frame->depth_m = cv::Mat(120, 160, CV_32FC1, cv::Scalar(background_m));
  for (int u = 0; u < 160; ++u) {
    // The ray's horizontal part per metre of optical depth: x forward 1, y left -(u - cx) / fx (rows share it).
    const Eigen::Vector2d d(1.0, -(u + 0.5 - 80.0) / 80.0);
    double nearest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector2d& c : bodies_m) {
      // |t d - c|^2 = r^2: the smaller root.
      const double a = d.squaredNorm();
      const double b = -2.0 * d.dot(c);
      const double disc = b * b - 4.0 * a * (c.squaredNorm() - body_radius_m * body_radius_m);
      if (disc >= 0.0) nearest = std::min(nearest, (-b - std::sqrt(disc)) / (2.0 * a));
    }
    if (std::isfinite(nearest)) frame->depth_m.col(u).setTo(cv::Scalar(nearest));
  }
  return frame;
}

/// The pinhole regression, the depth camera's ranges of bodies of body_radius_m, and the rule for someone else along
/// the line of sight (in_front_after_ranged; judged on the gate, or nearer only).
inline TargetTaskParams rangedParams(double body_radius_m, int in_front_after_ranged, bool on_the_gate) {
  TargetTaskParams params;
  params.localization = pinholeLocalization();
  params.in_front_after_ranged = in_front_after_ranged;
  params.in_front_test = on_the_gate ? TargetTaskParams::InFrontTest::kGate : TargetTaskParams::InFrontTest::kNearer;
  params.depth_range.enabled = true;
  params.depth_range.body_offset_m = body_radius_m;
  return params;
}

/// A target task that ranges from the depth frames written to `depth` and publishes whom it follows to `followed`.
struct RangedRig {
  explicit RangedRig(const TargetTaskParams& params) : rig(params) {
    rig.task.publishFollowedTo(followed);
    rig.task.rangeFrom(depth);
  }
  rt::LatestSlot<hal::DetectionFrame> followed;
  rt::SharedSlot<hal::DepthFrame> depth;
  TaskRig rig;
};

/// Someone in a detection frame: where the regression's fit would place them (a torso of the fit's length), and
/// the colour bin of their torso.
struct Drawn {
  double x_m = 0.0;
  double y_m = 0.0;
  int colour_bin = 0;
};

/// Frame i at t_ns, the drone hovering: the depth camera's image of `bodies_m` if it sees them (else no depth frame),
/// a detection frame of `people` (the first the lock-on's), stepped through the task. Its estimate.
inline TargetEstimate stepRanged(RangedRig& ranged, int i, rt::TimeNs t_ns, bool depth_seen,
                                 const std::vector<Eigen::Vector2d>& bodies_m, double body_radius_m,
                                 const std::vector<Drawn>& people) {
  auto& [detections, odometry, gimbal, out, task] = ranged.rig;
  pushHover(odometry, gimbal, t_ns);
  if (depth_seen) ranged.depth.write(renderBodiesDepth(t_ns, bodies_m, body_radius_m));
  hal::DetectionFrame frame = emptyFrame(i, t_ns);
  frame.person_count = static_cast<int>(people.size());
  for (std::size_t k = 0; k < people.size(); ++k)
    drawPersonInColour(frame.persons[k], people[k].x_m, people[k].y_m, people[k].colour_bin);
  frame.target_index = 0;
  detections.try_push(frame);
  task.step(t_ns + 1);
  return aerotrack::test::require(out.read(), "an estimate");
}

}  // namespace aerotrack::estimation::test
