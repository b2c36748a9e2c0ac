// A simulated stereo depth camera like the Intel RealSense D435 (the paper's depth sensor):
// one ray per pixel centre through an ideal pinhole into the ObstacleWorld and the ground;
// each pixel holds the z coordinate of the first hit in the camera frame (what a D435 reports,
// not the ray length), with the active-stereo error model of a D400 camera: Gaussian depth noise
// whose standard deviation grows with the square of the depth, sigma = k z^2, from Intel's
// "Best-Known-Methods for Tuning Intel RealSense D400 Depth Cameras" (Grunnet-Jepsen et al.,
// 2018): RMS error = z^2 * subpixel / (focal_px * baseline); with the D435's 50 mm baseline,
// focal ~ 640 px at 1280 x 720 and subpixel ~ 0.05, k ~ 0.0015 per metre (about 6 mm at 2 m,
// consistent with Intel's "< 2 % at 2 m" specification). Invalid pixels (no hit, out of range,
// random dropout) are 0, as on the real sensor. Depths are whole millimetres, the D435's Z16 unit
// (hal/depth_units.hpp).
#pragma once

#include <random>
#include <span>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include "aerotrack/hal/sim/obstacle_world.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

struct DepthCameraParams {
  int width_px = 160;                 ///< Kept low for speed (the D435 gives up to 1280); 1 .. 8192.
  int height_px = 120;                ///< 1 .. 8192.
  double hfov_deg = 87.0;             ///< Horizontal field of view (D435 depth: 87 deg); in (0, 180).
  double vfov_deg = 58.0;             ///< Vertical field of view (D435 depth: 58 deg); in (0, 180).
  double min_range_m = 0.3;           ///< Nearer depths read 0 (D435 minimum depth ~0.28 m at 848 x 480).
  double max_range_m = 10.0;          ///< Farther depths read 0 (Intel: up to ~10 m, scene-dependent).
  double noise_coeff_per_m = 0.0015;  ///< k in sigma = k z^2 (see the file comment); >= 0.
  double dropout_probability = 0.01;  ///< Chance that a valid pixel reads 0 anyway; in [0, 1].

  /// Ok if every field is in its documented range (finite, 0 <= min_range_m < max_range_m).
  static rt::Status validate(const DepthCameraParams& params);
};

/// Pinhole intrinsics of the simulated camera, no distortion. Pixel (u, v) covers
/// [u, u + 1) x [v, v + 1) with the origin at the top-left pixel's corner, so its centre is at
/// (u + 0.5, v + 0.5) and the principal point is the image centre (width/2, height/2).
/// fx and fy follow from the two fields of view separately: pixels are square only when the
/// aspect ratio matches them (the D435's 87 x 58 deg fits 848 x 480; 160 x 120 does not).
/// Precondition: validate(params) is ok. Allocation-free.
hal::CameraIntrinsics depthIntrinsics(const DepthCameraParams& params);

/// Inclusive pixel ranges [u0, u1] x [v0, v1].
struct PixelRect {
  int u0 = 0, u1 = -1, v0 = 0, v1 = -1;
};

/// The pixels of a pinhole camera (pose: R_CW rotates world vectors into C, camera at p_WC_m; C has
/// x right, y down, z forward) whose centres can see the part of the box with camera z >= near_m:
/// the bounds of that convex part's projected vertices (corners in front, edges cut at z = near_m),
/// one pixel of margin for rounding. False if no pixel can. Used by the depth camera and the
/// image renderer to visit only the pixels an obstacle may cover. Pure, allocation-free.
bool projectBoxToPixels(const Box& box, const Eigen::Matrix3d& R_CW, const Eigen::Vector3d& p_WC_m,
                        const hal::CameraIntrinsics& k, double near_m, PixelRect& rect);

/// Renders one depth image from camera pose T_WC (camera C in world W; C is the OpenCV camera
/// frame: x right, y down, z forward). depth_m becomes CV_32FC1, height_px x width_px, and is
/// (re)allocated only if its size or type differs (cv::Mat::create; a depth_m sharing its buffer
/// with other Mats is written in place). Pixel value: the camera-frame z in metres of the first
/// obstacle or ground hit through the pixel centre, plus N(0, (k z^2)^2) noise; 0 when nothing is
/// hit, when the true z is outside [min_range_m, max_range_m], or on dropout. The range test uses
/// the true z, so a noisy value may stray slightly past the limits; a value the noise would
/// push to <= 0 reads 0. Values are rounded to whole millimetres (depthToZ16, depthFromZ16). Randomness only from rng,
/// in row-major pixel order: dropout takes one geometric draw per dropped pixel (the run of valid pixels kept before
/// it; one more at the start when 0 < dropout_probability < 1), noise one normal draw per kept valid pixel (when
/// noise_coeff_per_m > 0). Same seed, same image (for one standard library).
/// The result equals ObstacleWorld::raycast through each pixel centre (ground on), but it is
/// rendered without the grid, using the shared origin of the rays: the ground analytically per
/// pixel, then each obstacle within range against only the pixels its bounding box projects onto,
/// keeping the nearest depth (a z-buffer in depth_m). Cost: O(obstacles in the world + pixels
/// covered by obstacles within range). No allocation besides depth_m's.
/// Precondition: validate(params) is ok. Not thread-safe on one rng/depth_m; otherwise reentrant.
/// extra_cylinders: moving obstacles of this instant (the simulator's bystanders), rendered like the
/// world's cylinders; none leaves the image exactly as before.
void renderDepth(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC, const DepthCameraParams& params,
                 std::mt19937_64& rng, cv::Mat& depth_m, std::span<const Cylinder> extra_cylinders = {});

}  // namespace aerotrack::hal::sim
