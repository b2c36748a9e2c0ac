// The image-mode gimbal camera's picture of the simulated scene: an ideal pinhole (no distortion, no
// noise) looking from a camera pose T_WC (OpenCV axes: x right, y down, z forward) at
//   - the sky, a vertical gradient, and the ground plane z = 0 with a world-fixed grass texture (2 m
//     tiles and 0.25 m / 0.05 m cells of hashed brightness, finer octaves fading out as a pixel's
//     footprint grows, so motion is visible without aliasing), hazed with distance;
//   - the obstacles of the ObstacleWorld, ray cast per pixel against each obstacle within range over
//     the pixels its bounding box projects onto (as the depth camera does), kept by a z-buffer,
//     Lambert-shaded under a fixed sun and textured (bark on cylinders, panels on boxes);
//   - the person as a photo cut-out (person_sprite.hpp) on a fronto-parallel billboard at the depth of
//     the projected mid-hip, drawn only where it is nearer than the obstacles' z-buffer (per-pixel
//     occlusion; the ground never hides it). Its placement (placeSprite) maps the sprite's neck and
//     mid-hip exactly onto the projected neck (mid-shoulders) and mid-hip of the simulated person's
//     keypoints, by a similarity above the hips; below the hips the sprite is stretched along the torso
//     axis so that the soles land on the projected ground point under the pelvis (the photo's legs are
//     foreshortened). It is mirrored when the person clearly walks towards the image's other side.
// Pixel (u, v) samples its centre (u + 0.5, v + 0.5). Everything is a pure function of (world, pose,
// person, parameters, sprite): no randomness, no clocks; the same input gives the same image, bit for
// bit, on one platform.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include "aerotrack/hal/sim/keypoint_camera.hpp"
#include "aerotrack/hal/sim/obstacle_world.hpp"
#include "aerotrack/hal/sim/person_sprite.hpp"
#include "aerotrack/hal/sim/walking_person.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

struct SceneRenderParams {
  /// Default: the keypoint camera's 640 x 480, 87 deg pinhole. Distortion must be zero.
  CameraIntrinsics intrinsics = KeypointCameraParams{}.intrinsics;
  double max_range_m = 80.0;       ///< Obstacles farther (camera-frame z) are not drawn; (1, 1e4].
  double haze_distance_m = 120.0;  ///< Colours blend 63 % towards the horizon's at this distance; > 0.
  Eigen::Vector3d sun_dir_W = Eigen::Vector3d(0.35, 0.25, 0.9).normalized();  ///< Towards the sun, unit.
};

/// Ok if the intrinsics are a valid distortion-free pinhole (sizes 1..8192) and the distances are in
/// range.
rt::Status validate(const SceneRenderParams& params);

/// Where the person's sprite lands in the image (pixel coordinates, u right, v down).
struct SpritePlacement {
  bool visible = false;  ///< Neck, mid-hip and ground point at least 0.1 m in front of the camera.
  Eigen::Vector2d neck_px = Eigen::Vector2d::Zero();     ///< Projected mid-shoulders.
  Eigen::Vector2d mid_hip_px = Eigen::Vector2d::Zero();  ///< Projected mid-hips: the anchor.
  Eigen::Vector2d soles_px = Eigen::Vector2d::Zero();    ///< Where the sprite's soles land.
  Eigen::Vector2d down = Eigen::Vector2d::UnitY();       ///< Unit image direction neck -> mid-hip.
  double scale = 0.0;                                    ///< Image px per sprite px at and above the hips.
  double leg_scale = 0.0;  ///< Image px per sprite px along `down` below the hips, in [0.5, 2.5] x scale.
  bool mirrored = false;
  double depth_m = 0.0;                                 ///< Camera-frame z of the billboard (mid-hip).
  Eigen::Vector4d bounds_px = Eigen::Vector4d::Zero();  ///< {u_min, v_min, u_max, v_max} of the silhouette.
};

/// Per-pixel buffers render() reuses between calls (allocated on first use or a size change).
struct RenderScratch {
  cv::Mat depth_m;      ///< CV_32FC1: camera-frame z of the nearest obstacle, +inf where none.
  cv::Mat obstacle_id;  ///< CV_32SC1: that obstacle (boxes first, then cylinders), -1 where none.
};

/// One person to draw (several: the bystanders of issue 20). recolour: the sprite's clothes (below
/// the neck) take clothing_bgr (each channel in [0, 1]), keeping their brightness, so that
/// bystanders dress differently from the target (whose photo keeps its colours, as do look-alikes').
struct RenderedPerson {
  const PersonState* state = nullptr;
  bool recolour = false;
  Eigen::Vector3f clothing_bgr = Eigen::Vector3f::Ones();
};

/// Draws scenes; holds the sprite (shared, immutable). Copies are cheap; const methods are thread-safe.
class SceneRenderer {
 public:
  /// Validates the parameters and loads the sprite (PersonSprite::load): a missing or corrupt photo is
  /// an error naming it. Allocates.
  static rt::Expected<SceneRenderer> create(const SceneRenderParams& params, const PersonSpriteSpec& sprite);

  /// Renders the scene seen from T_WC into bgr (CV_8UC3, intrinsics' height x width; (re)allocated
  /// only if its size or type differs). person null: no person. Two passes: every obstacle within
  /// range writes its depth over the pixels its bounds project onto (a z-buffer in scratch), then each
  /// pixel is shaded once (obstacle, ground or sky), then the sprite is drawn where it is nearer than
  /// the obstacles. Cost: O(pixels + pixels under the obstacles' projected bounds + the sprite's
  /// pixels); no allocation besides bgr's and scratch's. Thread-safe for distinct bgr / scratch.
  void render(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC, const PersonState* person, cv::Mat& bgr,
              RenderScratch& scratch) const;
  /// As above with several persons (at most 32 drawn), each over the obstacles' z-buffer and drawn
  /// farthest first, so nearer persons hide farther ones (painter's order by billboard depth).
  void render(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC, std::span<const RenderedPerson> persons,
              cv::Mat& bgr, RenderScratch& scratch) const;

  /// Where render() puts the person's sprite. Pure, allocation-free.
  SpritePlacement placeSprite(const PersonState& person, const Eigen::Isometry3d& T_WC) const;

  const SceneRenderParams& params() const { return params_; }
  const PersonSprite& sprite() const { return *sprite_; }

 private:
  /// The ground's texture: brightness factors on a 25.6 m square period, level k with 0.05 * 2^k m
  /// texels (a mip pyramid, 512 x 512 down to 1 x 1).
  struct GroundTexture {
    std::vector<std::vector<float>> levels;
  };

  SceneRenderer(const SceneRenderParams& params, std::shared_ptr<const PersonSprite> sprite,
                std::shared_ptr<const GroundTexture> ground)
      : params_(params), sprite_(std::move(sprite)), ground_(std::move(ground)) {}

  void rasterObstacles(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC, RenderScratch& scratch) const;
  void shade(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC, const RenderScratch& scratch,
             cv::Mat& bgr) const;
  void drawPerson(const SpritePlacement& placement, cv::Mat& bgr, const cv::Mat& depth_m,
                  const RenderedPerson& look) const;

  SceneRenderParams params_;
  std::shared_ptr<const PersonSprite> sprite_;
  std::shared_ptr<const GroundTexture> ground_;
};

}  // namespace aerotrack::hal::sim
