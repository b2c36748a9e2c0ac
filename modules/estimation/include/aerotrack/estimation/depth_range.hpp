// The person's distance from the depth camera (issue 22, item 3). The localization regression reads the distance
// from the torso's length in the image, and a person whose torso is longer or shorter than the fit's average is
// placed too far or too near by the same factor, every frame (the basketball player of image mode: 0.3-0.7 m
// long at 3-6 m); no filter averages that away. The drone's depth camera measures the distance directly wherever
// it sees the person: the gimbal camera's line of sight through the torso's centre is marched in steps, each
// point projected into the depth image, until a point lies on the surface the depth camera sees there (within a
// tolerance): the person's front. Their centre lies a body's half depth farther.
//
// The cameras differ in place and time, so the march checks what it finds: a surface the depth camera sees in
// front of the line (something between it and the person) ends it with nothing, as does a range that disagrees
// with the regression's by more than a factor (the line missed the person and met the wall behind them). The
// newest depth image taken at or before the photo is used, at most max_offset_s before it; how far a person
// walks in the difference is added to the noise (not carried along the estimate's velocity, which a wrong
// velocity would then confirm). The noise grows as a stereo camera's does (k z^2, Intel's D400 tuning guide),
// from a floor that is the person's own depth.
#pragma once

#include <cstdint>
#include <optional>

#include <Eigen/Geometry>

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::estimation {

struct DepthRangeParams {
  bool enabled = false;         ///< Off unless configured (a drone without a depth camera, or one facing elsewhere).
  double body_offset_m = 0.15;  ///< From the body's front, which the depth camera sees, to its centre.
  double step_m = 0.05;         ///< The march's step along the line of sight.
  double surface_tolerance_m = 0.2;  ///< A point within this (depth-camera z) of the depth image's value is on it.
  double min_range_m = 0.5;          ///< The march's span along the line of sight.
  double max_range_m = 8.0;
  double max_ratio = 1.5;            ///< The range within [1/r, r] of the regression's, else not the person.
  double max_offset_s = 0.05;        ///< The depth image at most this far in time from the photo.
  double range_std_m = 0.05;         ///< The noise's floor along the line of sight (the body's depth varies)...
  double range_std_per_m2 = 0.0015;  ///< ... and the stereo noise k z^2 added to it (in quadrature).
  double cross_std_per_m = 0.01;     ///< Across the line of sight: the keypoints' scatter, per metre of range.
  double person_speed_mps = 1.5;     ///< How fast they may have moved between depth image and photo (noise).
  /// > 0: the followed person's own scale, learnt from the depth camera. Each of the live followed track's frames
  /// that the depth camera ranged (the range or, too sharp for the gate, the regression's taken) gives the ratio of
  /// that range to the regression's; their running mean in log (the first samples averaged, then this rate per
  /// frame) scales every regression distance after, where the depth camera does not see the person -- as the
  /// followed person's: the bystander tracks keep the fit's own scale. The regression places a person whose torso
  /// is longer or shorter than its fit's average too near or too far by a factor that no filter averages away;
  /// unscaled, 0.5 s out of the depth camera's view fed the track distances 0.3-0.5 m short at 3.4-4.7 m, its
  /// speed fell from 1.0 to 0.3 m/s, and the person's own depth ranges, now beyond the gate, were refused as
  /// someone in front (traced: image-mode crowd seed 1 at 21.8-23.2 s, docs/benchmarks.md). Within
  /// [1/max_ratio, max_ratio]. 0: off.
  double scale_rate = 0.0;
};

/// Ok if every field is finite and in range (0 < step <= tolerance, 0 <= min < max, ratio >= 1, stds >= 0).
rt::Status validate(const DepthRangeParams& params);

/// Reads the `depth_range:` section of `estimation:` (every key required but scale_rate, absent: 0). Throws
/// rt::ConfigError naming the key.
DepthRangeParams parseDepthRangeParams(const rt::ConfigNode& node);

enum class DepthRangeStatus : std::uint8_t {
  kFound,      ///< The line of sight meets a surface the depth camera sees.
  kOutOfView,  ///< No point of the line lies in the depth image with data.
  kOccluded,   ///< The depth camera sees something in front of the line before it meets a surface.
  kNoSurface,  ///< The line runs through free space the whole span.
};
const char* toString(DepthRangeStatus status);

struct DepthSurface {
  DepthRangeStatus status = DepthRangeStatus::kOutOfView;
  double range_m = 0.0;  ///< Along the line of sight to the surface (kFound).
};

/// Marches the line origin_W + s dir_W (dir_W a unit vector; s from min_range_m to max_range_m by step_m) through
/// the depth image `depth` taken from T_WD (the depth camera's optical frame: x right, y down, z forward, in W),
/// and returns the first surface met. The step where the point first lies within surface_tolerance_m of the
/// depth there is refined to where the line crosses that depth (linear in s). Pixels without data are skipped.
/// Pure, allocation-free; the image must be CV_32FC1 of the intrinsics' size (else kOutOfView).
DepthSurface surfaceAlongLine(const hal::DepthFrame& depth, const Eigen::Isometry3d& T_WD,
                              const Eigen::Vector3d& origin_W, const Eigen::Vector3d& dir_W,
                              const DepthRangeParams& params);

/// The horizontal position of a person whose front `surface` is at range_m along dir_W from origin_W: the
/// surface point moved body_offset_m farther along the line's horizontal direction. Pure.
Eigen::Vector2d bodyCentreBehind(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& dir_W, double range_m,
                                 const DepthRangeParams& params);

/// The noise along the line of sight of a range of range_m: sqrt(range_std_m^2 + (range_std_per_m2 r^2)^2). Pure.
double depthRangeStdM(double range_m, const DepthRangeParams& params);

}  // namespace aerotrack::estimation
