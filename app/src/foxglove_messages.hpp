// Our types as Foxglove's well-known messages (issue 24 item 1; the schemas: @foxglove/schemas,
// compiled by hal/replay/foxglove). Pure functions: each fills a message it is given (cleared first)
// from a value, so the flight log can reuse its messages. Frames (Foxglove's frame ids):
//   world            the world, ENU (odometry's frame)
//   base_link        the body, FLU
//   gimbal           base_link turned by the gimbal's encoder angle about z, at its rotation centre
//   camera           the gimbal camera, FLU (estimation's frame C)
//   camera_optical   the gimbal camera, OpenCV axes (x right, y down, z forward): images and calibration
//   depth_optical    the depth camera, OpenCV axes
#pragma once

#include <foxglove/CameraCalibration.pb.h>
#include <foxglove/CompressedImage.pb.h>
#include <foxglove/FrameTransforms.pb.h>
#include <foxglove/ImageAnnotations.pb.h>
#include <foxglove/PointCloud.pb.h>
#include <foxglove/SceneUpdate.pb.h>

#include <span>
#include <string>
#include <vector>

#include "aerotrack/estimation/camera_to_world.hpp"
#include "aerotrack/estimation/target_estimator.hpp"
#include "aerotrack/hal/sim/obstacle_world.hpp"
#include "aerotrack/hal/sim/simulation.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/mapping/local_grid.hpp"
#include "aerotrack/planning/plan_snapshot.hpp"
#include "aerotrack/rt/time.hpp"
#include "aerotrack/supervisor/supervisor.hpp"
#include "aerotrack/trajectory_server/trajectory.hpp"
#include "json_line.hpp"

namespace aerotrack::app::foxglove_log {

/// The serialized FileDescriptorSet of a message type and every file it imports: an MCAP protobuf
/// schema's data.
std::string fileDescriptorSet(const google::protobuf::Descriptor& descriptor);

void setTime(google::protobuf::Timestamp& t, rt::TimeNs ns);

/// world -> base_link from the odometry; base_link -> gimbal -> camera -> camera_optical when the
/// extrinsics are known (the gimbal angle is the newest encoder reading); base_link -> depth_optical
/// when T_BD is given.
void fillTransforms(foxglove::FrameTransforms& m, const hal::OdometrySample& odometry, double gimbal_angle_rad,
                    const estimation::GimbalCameraExtrinsics* extrinsics, const Eigen::Isometry3d* T_BD);

/// The pinhole model of a frame's intrinsics (plumb_bob distortion), in camera_optical.
void fillCalibration(foxglove::CameraCalibration& m, rt::TimeNs stamp_ns, const hal::CameraIntrinsics& intrinsics);

/// Every person's skeleton (COCO limbs whose both ends scored >= min_score) and keypoints; the followed
/// person (target_index) in green with a label, bystanders in orange.
void fillAnnotations(foxglove::ImageAnnotations& m, const hal::DetectionFrame& frame, double min_score);

/// The person's estimate: a sphere at p_WT, an ellipsoid of its 2-sigma position uncertainty, its
/// velocity as an arrow (green while tracked, grey when lost), and the other people tracked (blue).
void fillEstimate(foxglove::SceneUpdate& m, const estimation::TargetEstimate& estimate);

/// The trajectory being flown from its start: a line through `samples` points.
void fillTrajectory(foxglove::SceneUpdate& m, rt::TimeNs stamp_ns, const trajectory_server::TimedTrajectory& t,
                    int samples);

/// A planning cycle: its corridor's boxes (entity "planning/corridor"), the kinodynamic search's path
/// ("planning/search") and the person's Bezier prediction ("person/prediction").
void fillPlan(foxglove::SceneUpdate& m, const planning::PlanSnapshot& plan);

/// A recorded trajectory as the points it was recorded with (export-mcap): the same entity and look
/// as fillTrajectory.
void fillTrajectoryPoints(foxglove::SceneUpdate& m, rt::TimeNs stamp_ns, std::span<const Eigen::Vector3d> points_W_m);

/// A stretch of the flown path (entity "path/<index>", kept for the whole log).
void fillPathSegment(foxglove::SceneUpdate& m, rt::TimeNs stamp_ns, int index,
                     std::span<const Eigen::Vector3d> points_W_m);

/// The flown path cut into stretches of `stretch_s` seconds of odometry, each starting where the last
/// ended, written as path/0, path/1, ... (so a viewer draws the whole flight without one ever-growing
/// message). Shared by the live log and export-mcap. Allocation-free once its buffer has grown.
class FlownPath {
 public:
  explicit FlownPath(double stretch_s) : stretch_s_(stretch_s) { points_W_m_.reserve(256); }
  /// Adds an odometry position; true when a stretch is complete and in `scene` (stamped `stamp_ns`).
  bool add(rt::TimeNs stamp_ns, const Eigen::Vector3d& p_WB_m, foxglove::SceneUpdate& scene);
  /// The unfinished stretch, if it has a segment (at the end of a log); its stamp is the last position's.
  bool flush(foxglove::SceneUpdate& scene);
  rt::TimeNs lastStampNs() const { return last_ns_; }

 private:
  double stretch_s_;
  std::vector<Eigen::Vector3d> points_W_m_;
  int stretches_ = 0;
  rt::TimeNs start_ns_ = -1;
  rt::TimeNs last_ns_ = -1;
};

/// A depth image as points in depth_optical (x, y, z float32), one pixel in `step` along each axis;
/// pixels without a return are left out. Reuses m's storage (no Clear(): its data keeps its capacity, so a
/// message kept from frame to frame allocates nothing once it has held the largest cloud).
void fillDepthPoints(foxglove::PointCloud& m, const hal::DepthFrame& frame, int step);

/// The occupied cells of the local grid's window, as cubes.
void fillOccupied(foxglove::SceneUpdate& m, rt::TimeNs stamp_ns, const mapping::LocalGrid& grid);

/// The simulator's obstacles (ground truth), kept for the whole log.
void fillObstacles(foxglove::SceneUpdate& m, rt::TimeNs stamp_ns, const hal::sim::ObstacleWorld& world);

/// The simulator's truth: the person (a yellow cylinder of a person's size) and the drone's true position.
void fillTruth(foxglove::SceneUpdate& m, const hal::sim::TruthSnapshot& truth);

/// JSON values for plots, written into `out` without allocating: an estimate (p, v, sigma, lost, age of its
/// newest measurement, people tracked), a setpoint (p, v, a, yaw), a gimbal command, a planning cycle, the
/// supervisor's state, the simulator's truth (with the estimate's error when one is live).
std::string_view estimateJson(const estimation::TargetEstimate& estimate, JsonLine& out);
std::string_view setpointJson(const hal::Setpoint& setpoint, JsonLine& out);
std::string_view gimbalCommandJson(const hal::GimbalCommand& command, JsonLine& out);
std::string_view planCycleJson(const planning::PlanSnapshot& plan, JsonLine& out);
std::string_view supervisorJson(const supervisor::SupervisorState& state, JsonLine& out);
std::string_view truthJson(const hal::sim::TruthSnapshot& truth, const estimation::TargetEstimate* live_estimate,
                           JsonLine& out);

}  // namespace aerotrack::app::foxglove_log
