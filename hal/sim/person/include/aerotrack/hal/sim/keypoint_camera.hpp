// The simulator's keypoint-mode camera: what a single-person keypoint detector (MoveNet) reports when
// the gimbal camera looks at the simulated person. The 17 COCO keypoints are projected with an ideal
// pinhole (no distortion); a keypoint behind the camera, outside the image, hidden from the camera
// centre (a line-of-sight query supplied by the obstacle world) or randomly missed gets score 0;
// visible ones get isotropic Gaussian pixel noise whose standard deviation is a fixed fraction of the
// projected torso (neck-to-mid-hip) length -- 0.028, measured for MoveNet on real video -- and a
// uniform random score. A keypoint just outside the image is not dropped but guessed, as MoveNet
// guesses a body the frame cuts off: a little inside the nearest edge with a middling score
// (messi5.jpg cut at the waist: hips 2-19 px inside the edge at a 116 px torso, scores 0.31-0.47;
// issue 22), so the torso-reliability rule meets the network's failure, not an empty joint.
// Randomness comes only from the caller's generator: each call draws exactly
// four 53-bit uniforms per keypoint from the raw engine output (Box-Muller for the noise), so the
// result is identical for the same seed on every platform and standard library.
#pragma once

#include <array>
#include <functional>
#include <numbers>
#include <optional>
#include <random>

#include <Eigen/Geometry>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

/// Ideal pinhole intrinsics (no distortion) with the principal point at the image centre and square
/// pixels: fx = fy = (width_px / 2) / tan(horizontal_fov_rad / 2). Pure, allocation-free.
CameraIntrinsics pinholeIntrinsics(int width_px, int height_px, double horizontal_fov_rad);

struct KeypointCameraParams {
  /// 640 x 480, 87 deg horizontal field of view (fx = fy = 320 / tan(43.5 deg) = 337.2 px).
  CameraIntrinsics intrinsics = pinholeIntrinsics(640, 480, 87.0 * std::numbers::pi / 180.0);
  /// Per-axis standard deviation of the pixel noise of each visible keypoint, as a fraction of the
  /// projected torso length (mid-shoulders to mid-hips, in pixels).
  double pixel_noise_torso_fraction = 0.028;
  double keypoint_miss_probability = 0.03;  ///< Chance that a visible keypoint is not reported.
  int min_visible_keypoints = 5;            ///< Fewer reported keypoints: no detection at all.
  double min_score = 0.5;                   ///< Scores of reported keypoints: uniform in
  double max_score = 0.95;                  ///< [min_score, max_score].
  /// The box around the reported keypoints grows by this fraction of its larger side on every side
  /// (the head top and feet extend beyond the nose and ankles), then is clipped to the image.
  double bbox_margin_fraction = 0.08;
  /// A keypoint outside the image by at most this many torso lengths is guessed inside it (0: dropped,
  /// as before issue 22) ...
  double cut_guess_reach_torso = 1.0;
  double cut_guess_min_inset_torso = 0.02;  ///< ... this far inside the nearest edge (uniform between the
  double cut_guess_max_inset_torso = 0.16;  ///< two, in torso lengths) ...
  double cut_guess_min_score = 0.30;        ///< ... with a score uniform in
  double cut_guess_max_score = 0.47;        ///< [cut_guess_min_score, cut_guess_max_score].
};

/// Checks the parameters: positive image size and focal lengths, zero distortion, noise >= 0,
/// probabilities in [0, 1], 1 <= min_visible_keypoints <= 17, 0 < min_score <= max_score <= 1.
rt::Status validate(const KeypointCameraParams& params);

/// The camera's optical axes (OpenCV: x right, y down, z forward) expressed in a forward-left-up
/// frame (the gimbal's, the body's): R_FLU_optical. Pure.
Eigen::Matrix3d opticalAxesInFlu();

/// A camera at eye_W looking at target_W with no roll (x right and level, y down, z forward; world z
/// up): T_WC for renderings and tests. target_W must not be straight above or below eye_W. Pure.
Eigen::Isometry3d cameraLookingAt(const Eigen::Vector3d& eye_W, const Eigen::Vector3d& target_W);

/// True if the straight segment between the two world points (metres) is unobstructed. Supplied by
/// the obstacle world; an empty function means nothing is ever obstructed.
using LineOfSight = std::function<bool(const Eigen::Vector3d& from_W_m, const Eigen::Vector3d& to_W_m)>;

/// Pixel coordinates (u right, v down) of a point given in the camera frame (OpenCV: x right, y down,
/// z forward), by the ideal pinhole; nothing if z <= 1 mm. Distortion coefficients are ignored. The
/// result may lie outside the image. Pure, allocation-free.
std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_C_m, const CameraIntrinsics& intrinsics);

/// How well a detection fits one person whose true COCO keypoints (camera frame, metres) are
/// keypoints_C_m: the mean pixel distance between the reported keypoints (score > 0) and the same
/// keypoints projected, as a fraction of the projected neck-to-hip length. The smaller of two
/// readings: the labels as given, and with left and right exchanged -- a real network often reads a
/// back view as a front (measured on the rendered cast: shoulders one shoulder-width apart), and
/// that is the same person. Nothing when the person cannot be what the detector saw: the neck or
/// hip is nearer than 0.1 m, both project outside the image, or a reported keypoint of theirs is
/// behind the camera (a person beside the camera plane projects to huge, meaningless pixels).
std::optional<double> keypointMatchError(const PersonDetection& detection,
                                         const std::array<Eigen::Vector3d, kNumKeypoints>& keypoints_C_m,
                                         const CameraIntrinsics& intrinsics);

/// What the detector reports for one person whose COCO keypoints (world frame, metres) are
/// keypoints_W_m, seen by a camera at pose T_WC (camera frame C in the world W). Unreported keypoints
/// have score 0 and coordinates 0; reported ones are noisy, clamped to the image. The box bounds the
/// reported keypoints with a margin, clipped to the image; the person score is the mean reported
/// score. Nothing if fewer than min_visible_keypoints are reported. Expects validated params. Calls
/// line_of_sight(camera centre, keypoint) only for keypoints that project into the image and are not
/// randomly missed. Draws 68 numbers from rng whatever happens. Allocation-free; thread-safe if
/// line_of_sight is and rng is not shared.
std::optional<PersonDetection> observe(const std::array<Eigen::Vector3d, kNumKeypoints>& keypoints_W_m,
                                       const Eigen::Isometry3d& T_WC, const KeypointCameraParams& params,
                                       const LineOfSight& line_of_sight, std::mt19937_64& rng);

}  // namespace aerotrack::hal::sim
