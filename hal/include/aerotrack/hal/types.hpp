// Messages that cross the HAL. Every message carries the time its data was sampled (stamp_ns,
// on the executor's clock). Frames follow monogram notation (DESIGN.md rule 7): W world (ENU,
// z up), B body (FLU: x forward, y left, z up), C camera. p_WB_m is the position of B in W in
// metres; q_WB rotates B-frame vectors into W.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include "aerotrack/hal/appearance_signature.hpp"
#include "aerotrack/rt/bitwise_copyable.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::hal {

using rt::TimeNs;

/// Pinhole intrinsics with Brown-Conrady distortion (k1, k2, p1, p2, k3), OpenCV convention.
struct CameraIntrinsics {
  int width_px = 0;
  int height_px = 0;
  double fx_px = 0.0;
  double fy_px = 0.0;
  double cx_px = 0.0;
  double cy_px = 0.0;
  std::array<double, 5> distortion{};
};

/// One gimbal-camera image. Immutable once published; shared by handle.
struct ImageFrame {
  TimeNs stamp_ns = 0;         ///< Exposure time.
  std::uint64_t sequence = 0;  ///< Frame counter from the device; gaps mean dropped frames.
  cv::Mat bgr;                 ///< 8-bit BGR.
  CameraIntrinsics intrinsics;
};
using ImageFrameHandle = std::shared_ptr<const ImageFrame>;

/// One depth image, camera fixed to the body.
struct DepthFrame {
  TimeNs stamp_ns = 0;
  std::uint64_t sequence = 0;
  cv::Mat depth_m;  ///< CV_32FC1 range along the optical axis, metres; 0 or NaN: no data.
  CameraIntrinsics intrinsics;
  Eigen::Isometry3d T_BC = Eigen::Isometry3d::Identity();  ///< Depth camera C (z forward) in body B.
};
using DepthFrameHandle = std::shared_ptr<const DepthFrame>;

/// Gimbal encoder feedback. The gimbal spins without limit (slip ring): angle_rad is unwrapped,
/// multi-turn, measured from the body's x axis about the body's z axis.
struct GimbalState {
  TimeNs stamp_ns = 0;
  double angle_rad = 0.0;
  double rate_radps = 0.0;
};

struct GimbalCommand {
  enum class Mode : std::uint8_t { kRate, kAngle };
  TimeNs stamp_ns = 0;
  Mode mode = Mode::kRate;
  double rate_radps = 0.0;      ///< kRate: commanded rate.
  double angle_rad = 0.0;       ///< kAngle: target unwrapped angle.
  double max_rate_radps = 0.0;  ///< kAngle: speed limit (0: the device's default).
};

/// COCO body keypoints in the order MoveNet and COCO use (index = enum value).
enum class CocoKeypoint : std::uint8_t {
  kNose,
  kLeftEye,
  kRightEye,
  kLeftEar,
  kRightEar,
  kLeftShoulder,
  kRightShoulder,
  kLeftElbow,
  kRightElbow,
  kLeftWrist,
  kRightWrist,
  kLeftHip,
  kRightHip,
  kLeftKnee,
  kRightKnee,
  kLeftAnkle,
  kRightAnkle,
};
inline constexpr std::size_t kNumKeypoints = 17;
inline constexpr std::size_t index(CocoKeypoint k) {
  return static_cast<std::size_t>(k);
}

/// One keypoint in image pixels (u right, v down, origin at the top-left pixel's corner).
struct Keypoint2D {
  double u_px = 0.0;
  double v_px = 0.0;
  double score = 0.0;  ///< Confidence in [0, 1]; 0: not detected.
};

/// One person found in an image: what the keypoint detector (issue 5) outputs, and what the
/// simulator's keypoint-mode camera produces so that everything downstream is exercised.
/// COCO skeleton edges (the pairs MoveNet's demos draw).
inline constexpr std::array<std::pair<int, int>, 18> kCocoSkeleton = {{{0, 1},
                                                                       {0, 2},
                                                                       {1, 3},
                                                                       {2, 4},
                                                                       {5, 6},
                                                                       {5, 7},
                                                                       {7, 9},
                                                                       {6, 8},
                                                                       {8, 10},
                                                                       {5, 11},
                                                                       {6, 12},
                                                                       {11, 12},
                                                                       {11, 13},
                                                                       {13, 15},
                                                                       {12, 14},
                                                                       {14, 16},
                                                                       {0, 5},
                                                                       {0, 6}}};

struct PersonDetection {
  std::array<Keypoint2D, kNumKeypoints> keypoints{};
  double score = 0.0;                                                         ///< Person confidence in [0, 1].
  double bbox_u_px = 0.0, bbox_v_px = 0.0, bbox_w_px = 0.0, bbox_h_px = 0.0;  ///< Top-left corner, size.
  /// The person's appearance signature (appearance_signature.hpp: torso and legs colour histograms, each
  /// summing to 1 when measured, zeros when not) when the source measured one: the simulator's keypoint
  /// camera reports it, the image pipeline measures it from the image. Recorded in detections.csv, so the
  /// lock-on and the association rerun on it in replay.
  AppearanceHistogram appearance{};
  bool has_appearance = false;
};

inline constexpr std::size_t kMaxPersons = 6;  ///< MoveNet multipose returns at most six.

/// The persons detected in one gimbal-camera frame. Fixed size (no allocation): travels through
/// latest-value slots and queues.
struct DetectionFrame {
  TimeNs stamp_ns = 0;          ///< Exposure time of the image.
  TimeNs result_ns = 0;         ///< When the detection was available (stamp_ns + detector latency).
  std::uint64_t sequence = 0;   ///< Frame counter.
  CameraIntrinsics intrinsics;  ///< Of the image the pixels refer to.
  std::size_t person_count = 0;
  std::array<PersonDetection, kMaxPersons> persons{};
  /// Which of persons[] is the followed person (the detector's lock-on), -1 if none of them is:
  /// bystanders alone, or the target was not found.
  int target_index = -1;
  /// On the frames the target task hands back as its verdicts (whom it took): its second hypothesis of the followed
  /// person is open and the followed track holds someone that hypothesis does not explain, so the detector should
  /// show it everyone in the next frame, not the crop around whom it holds (issue 22, item 2; swap_check.hpp).
  bool whole_frame_wanted = false;
  /// On the verdicts that took nobody (target_index -1) while the followed track is live: where the track predicts
  /// the person's torso in this image -- its centre and its neck-to-hip length, pixels; torso_px 0: no prediction
  /// (issue 22, item 2). The detector's next crop looks there, not around whom its own lock-on holds.
  struct PredictedTorso {
    double u_px = 0.0;
    double v_px = 0.0;
    double torso_px = 0.0;
  } predicted_torso;
};

/// Vehicle state estimate from the flight controller or the simulator.
struct OdometrySample {
  TimeNs stamp_ns = 0;
  Eigen::Vector3d p_WB_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();
  Eigen::Vector3d v_WB_mps = Eigen::Vector3d::Zero();      ///< Velocity of B in W, expressed in W.
  Eigen::Vector3d w_WB_B_radps = Eigen::Vector3d::Zero();  ///< Angular velocity, expressed in B.
};

/// Full-state setpoint for the flight controller (PX4 offboard / ArduPilot guided style).
struct Setpoint {
  TimeNs stamp_ns = 0;
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_W_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_W_mps2 = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;
  double yaw_rate_radps = 0.0;
};

enum class FlightMode : std::uint8_t { kUnknown, kManual, kHold, kOffboard, kLand };

struct VehicleStatus {
  TimeNs stamp_ns = 0;
  bool link_ok = false;
  bool armed = false;
  FlightMode mode = FlightMode::kUnknown;
};

/// Health of one device, for the supervisor and the exit report.
struct DeviceHealth {
  enum class State : std::uint8_t {
    kOk,        ///< Producing data as expected.
    kDegraded,  ///< Producing data with errors (dropped frames, retries).
    kFailed,    ///< Not producing data (unplugged, timed out, bus-off).
    kAbsent,    ///< Null backend: there is no such device on this vehicle.
  };
  State state = State::kAbsent;
  std::string detail;         ///< One line for a person.
  TimeNs last_sample_ns = 0;  ///< Stamp of the newest sample delivered (0: none yet).
  std::uint64_t error_count = 0;
};

const char* toString(DeviceHealth::State state);
const char* toString(FlightMode mode);

}  // namespace aerotrack::hal

// The small state messages travel through rt::LatestSlot: Eigen members are fixed-size arrays of
// doubles (see rt/bitwise_copyable.hpp).
#define AEROTRACK_HAL_BITWISE(Type)                               \
  static_assert(std::is_standard_layout_v<aerotrack::hal::Type>); \
  template <>                                                     \
  struct aerotrack::rt::IsBitwiseCopyable<aerotrack::hal::Type> : std::true_type {};
AEROTRACK_HAL_BITWISE(OdometrySample)
AEROTRACK_HAL_BITWISE(Setpoint)
#undef AEROTRACK_HAL_BITWISE
static_assert(std::is_trivially_copyable_v<aerotrack::hal::GimbalState>);
static_assert(std::is_trivially_copyable_v<aerotrack::hal::GimbalCommand>);
static_assert(std::is_trivially_copyable_v<aerotrack::hal::VehicleStatus>);
static_assert(std::is_trivially_copyable_v<aerotrack::hal::DetectionFrame>);
