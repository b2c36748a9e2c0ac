// Shared by the target task's tests: a level 640 x 480 gimbal camera of 87 deg horizontal field of view at
// the world's origin, looking along W x, and the pinhole localization of a 0.5 m torso seen by it.
#pragma once

#include "aerotrack/estimation/target_task.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/localization/localization_model.hpp"
#include "aerotrack/rt/spsc_queue.hpp"
#include "support/require.hpp"

namespace aerotrack::estimation::test {

inline constexpr double kFocalPx = 337.2;
inline constexpr double kTorsoM = 0.5;
inline constexpr int kWidthPx = 640;
inline constexpr int kHeightPx = 480;
inline constexpr double kFrameRateHz = 30.0;

inline localization::LocalizationParams pinholeLocalization() {
  localization::LocalizationParams p;
  p.model = localization::LocalizationModel::kPinhole;
  p.pinhole.fx_px = kFocalPx;
  p.pinhole.fy_px = kFocalPx;
  p.pinhole.cx_px = 0.5 * kWidthPx;
  p.pinhole.torso_m = kTorsoM;
  p.z_m = -0.4;
  return p;
}

/// An upright torso of a person at (x forward, y left) of the camera, the neck `neck_above_centre` torso
/// lengths above the image's centre row; `cut`: the hips guessed on the bottom rows with a middling score,
/// as MoveNet does for hips outside the frame (no distance from such a torso).
inline void drawTorso(hal::PersonDetection& person, double x_m, double y_m, double neck_above_centre, bool cut) {
  using hal::CocoKeypoint;
  using hal::index;
  const double u_px = 0.5 * kWidthPx - kFocalPx * y_m / x_m;
  const double torso_px = kFocalPx * kTorsoM / x_m;
  const double neck_v_px = 0.5 * kHeightPx - neck_above_centre * torso_px;
  auto& k = person.keypoints;
  k[index(CocoKeypoint::kLeftShoulder)] = {u_px + 0.2 * torso_px, neck_v_px, 0.8};
  k[index(CocoKeypoint::kRightShoulder)] = {u_px - 0.2 * torso_px, neck_v_px, 0.8};
  const double hip_v_px = cut ? kHeightPx - 6.0 : neck_v_px + torso_px;
  const double hip_score = cut ? 0.4 : 0.8;
  k[index(CocoKeypoint::kLeftHip)] = {u_px + 0.15 * torso_px, hip_v_px, hip_score};
  k[index(CocoKeypoint::kRightHip)] = {u_px - 0.15 * torso_px, hip_v_px, hip_score};
  person.score = 0.6;
}

/// A whole upright torso (drawTorso, the neck 0.3 torso lengths above the centre row) in one colour: a one-bin
/// appearance signature; `cut` as drawTorso's.
inline void drawPersonInColour(hal::PersonDetection& person, double x_m, double y_m, int colour_bin, bool cut = false) {
  drawTorso(person, x_m, y_m, 0.3, cut);
  person.appearance.fill(0.0F);
  person.appearance[static_cast<std::size_t>(colour_bin)] = 1.0F;
  person.has_appearance = true;
}

/// Frame i of the camera, stamped t_ns, with nobody in it yet and nobody designated.
inline hal::DetectionFrame emptyFrame(int i, rt::TimeNs t_ns) {
  hal::DetectionFrame frame;
  frame.stamp_ns = t_ns;
  frame.result_ns = t_ns;
  frame.sequence = static_cast<std::uint64_t>(i) + 1;
  frame.intrinsics = {kWidthPx, kHeightPx, kFocalPx, kFocalPx, 0.5 * kWidthPx, 0.5 * kHeightPx, {}};
  return frame;
}

/// The drone hovering at the origin, the gimbal at 0: one odometry sample and one encoder reading at t_ns.
inline void pushHover(rt::SpscQueue<hal::OdometrySample>& odometry, rt::SpscQueue<hal::GimbalState>& gimbal,
                      rt::TimeNs t_ns) {
  hal::OdometrySample pose;
  pose.stamp_ns = t_ns;
  odometry.try_push(pose);
  gimbal.try_push({t_ns, 0.0, 0.0});
}

/// A target task on its own input queues and estimate slot (not movable: the task refers to them).
struct TaskRig {
  explicit TaskRig(const TargetTaskParams& params)
      : task(aerotrack::test::require(TargetTask::create(params, detections, odometry, gimbal, out), "task")) {}
  TaskRig(const TaskRig&) = delete;
  TaskRig& operator=(const TaskRig&) = delete;
  rt::SpscQueue<hal::DetectionFrame> detections{64, rt::OverflowPolicy::kDropOldest};
  rt::SpscQueue<hal::OdometrySample> odometry{256, rt::OverflowPolicy::kDropOldest};
  rt::SpscQueue<hal::GimbalState> gimbal{256, rt::OverflowPolicy::kDropOldest};
  rt::LatestSlot<TargetEstimate> out;
  TargetTask task;
};

/// A target task that publishes whom it follows to `followed`.
struct FollowedRig {
  explicit FollowedRig(const TargetTaskParams& params) : rig(params) { rig.task.publishFollowedTo(followed); }
  rt::LatestSlot<hal::DetectionFrame> followed;
  TaskRig rig;
};

}  // namespace aerotrack::estimation::test
