// The image-mode gimbal camera's picture of the simulated scene: an ideal pinhole (no distortion, no
// noise) looking from a camera pose T_WC (OpenCV axes: x right, y down, z forward) at
//   - the sky, a vertical gradient, and the ground plane z = 0 with a world-fixed grass texture (2 m
//     tiles and 0.25 m / 0.05 m cells of hashed brightness, finer octaves fading out as a pixel's
//     footprint grows, so motion is visible without aliasing), hazed with distance;
//   - the obstacles of the ObstacleWorld, ray cast per pixel against each obstacle within range over
//     the pixels its bounding box projects onto (as the depth camera does), kept by a z-buffer,
//     Lambert-shaded under a fixed sun and textured (bark on cylinders, panels on boxes);
//   - people (person_cast.hpp), each a real person cut into ten body parts (person_sprite.hpp), each
//     part warped onto the projected keypoints of the simulated person every frame: the torso by the
//     homography of its four joints (widened to at least half the photo's width where the person is
//     seen from the side), the head and the eight limb bones by affine maps that take the photo's
//     bone onto the projected one (along) and keep the body's width at the person's depth (across).
//     A part samples only its own pixels of the photo; the parts are drawn farthest first, each where
//     it is nearer than the obstacles' z-buffer (per-pixel occlusion; the ground never hides them).
//     A person seen from the side the photo does not show is drawn mirrored (a front photo's head in
//     its hair colour).
// Pixel (u, v) samples its centre (u + 0.5, v + 0.5). Everything is a pure function of (world, pose,
// person, parameters, sprite): no randomness, no clocks; the same input gives the same image, bit for
// bit, on one platform.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include "aerotrack/hal/sim/background_shader.hpp"
#include "aerotrack/hal/sim/depth_camera.hpp"
#include "aerotrack/hal/sim/keypoint_camera.hpp"
#include "aerotrack/hal/sim/obstacle_world.hpp"
#include "aerotrack/hal/sim/person_cast.hpp"
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

/// Where one body part lands: the map from image pixels to the photo's level-0 sprite pixels.
struct PartPlacement {
  Eigen::Matrix3d H_sprite_image = Eigen::Matrix3d::Identity();  ///< Homogeneous (u, v, 1) -> sprite px.
  Eigen::Vector4d bounds_px = Eigen::Vector4d::Zero();           ///< {u_min, v_min, u_max, v_max}.
  double depth_m = 0.0;                                          ///< Camera-frame z, for drawing order.
  bool drawn = false;
};

/// Where a person is drawn (pixel coordinates, u right, v down).
struct SpritePlacement {
  bool visible = false;  ///< Every keypoint and the ground point at least 0.1 m in front of the camera.
  Eigen::Vector2d neck_px = Eigen::Vector2d::Zero();     ///< Projected mid-shoulders.
  Eigen::Vector2d mid_hip_px = Eigen::Vector2d::Zero();  ///< Projected mid-hips.
  double scale = 0.0;           ///< Image px per sprite px across the body (the person's width at their depth).
  bool mirrored = false;        ///< Seen from the side the photo does not show.
  bool hair_over_face = false;  ///< A front photo seen from behind: the head is painted in its hair colour.
  double depth_m = 0.0;         ///< Camera-frame z of the mid-hip (people are drawn farthest first).
  Eigen::Vector4d bounds_px = Eigen::Vector4d::Zero();  ///< {u_min, v_min, u_max, v_max} of all parts.
  std::array<PartPlacement, kPartCount> parts{};
  std::array<std::uint8_t, kPartCount> order{};  ///< Parts, farthest first.
};

/// Per-pixel buffers render() reuses between calls (allocated on first use or a size change).
struct RenderScratch {
  cv::Mat depth_m;      ///< CV_32FC1: camera-frame z of the nearest obstacle, +inf where none.
  cv::Mat obstacle_id;  ///< CV_32SC1: that obstacle (boxes first, then cylinders), -1 where none.
};

/// One person to draw (several: the bystanders of issue 20), wearing the cast's person `person`.
/// recolour: the clothes (every part but the head) take clothing_bgr (each channel in [0, 1]),
/// keeping their brightness (for a cast of one, so that bystanders still dress differently).
struct RenderedPerson {
  const PersonState* state = nullptr;
  std::size_t person = 0;
  bool recolour = false;
  Eigen::Vector3f clothing_bgr = Eigen::Vector3f::Ones();
};

/// Draws scenes; holds the cast's sprites (shared, immutable). Copies are cheap; const methods are thread-safe.
class SceneRenderer {
 public:
  /// Validates the parameters and loads the cast (loadCast): a missing or corrupt photo is an error
  /// naming it. Allocates.
  static rt::Expected<SceneRenderer> create(const SceneRenderParams& params, const PersonCastSpec& cast);

  /// Renders the scene seen from T_WC into bgr (CV_8UC3, intrinsics' height x width; (re)allocated
  /// only if its size or type differs). person null: no person; else the cast's person cast_index. Two passes: every
  /// obstacle within range writes its depth over the pixels its bounds project onto (a z-buffer in scratch), then each
  /// pixel is shaded once (obstacle, ground or sky), then the sprite is drawn where it is nearer than
  /// the obstacles. Cost: O(pixels + pixels under the obstacles' projected bounds + the sprite's
  /// pixels); no allocation besides bgr's and scratch's. Thread-safe for distinct bgr / scratch.
  void render(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC, const PersonState* person, cv::Mat& bgr,
              RenderScratch& scratch, std::size_t cast_index = 0) const;
  /// As above with several persons (at most 32 drawn), each over the obstacles' z-buffer and drawn
  /// farthest first, so nearer persons hide farther ones (painter's order by billboard depth).
  void render(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC, std::span<const RenderedPerson> persons,
              cv::Mat& bgr, RenderScratch& scratch) const;

  /// Where render() puts the cast's person `cast_index` (< castSize()) dressed as `person`. Pure,
  /// allocation-free.
  SpritePlacement placeSprite(const PersonState& person, const Eigen::Isometry3d& T_WC,
                              std::size_t cast_index = 0) const;

  const SceneRenderParams& params() const { return params_; }
  std::size_t castSize() const { return sprites_.size(); }
  const PersonSprite& sprite(std::size_t cast_index = 0) const { return *sprites_.at(cast_index); }

 private:
  SceneRenderer(const SceneRenderParams& params, PersonSprites sprites, std::shared_ptr<const GroundTexture> ground)
      : params_(params), sprites_(std::move(sprites)), ground_(std::move(ground)) {}

  void rasterObstacles(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC, RenderScratch& scratch) const;
  /// A trunk seen from outside its footprint, over its projected bounds: the side in single precision,
  /// vectorised (a forest frame's most pixels); a cap, rarely seen, the general way.
  void rasterCylinderFromOutside(const Cylinder& cyl, int label, const Eigen::Isometry3d& T_WC, const PixelRect& rect,
                                 RenderScratch& scratch) const;
  void shade(const ObstacleWorld& world, const Eigen::Isometry3d& T_WC, const RenderScratch& scratch,
             cv::Mat& bgr) const;
  void drawPerson(const SpritePlacement& placement, cv::Mat& bgr, const cv::Mat& depth_m,
                  const RenderedPerson& look) const;

  SceneRenderParams params_;
  PersonSprites sprites_;
  std::shared_ptr<const GroundTexture> ground_;
};

}  // namespace aerotrack::hal::sim
