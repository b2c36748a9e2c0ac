// The simulated person's appearance in image mode: a cut-out of a real person from a photo, so that
// the real keypoint network (MoveNet, issue 5) sees real human imagery inside closed-loop runs. The
// photo is segmented once, at load, by GrabCut (Rother, Kolmogorov & Blake, "GrabCut", SIGGRAPH 2004)
// inside a crop rectangle, helped by a few sure-foreground strokes along the body's bones and
// sure-background strokes (e.g. between the legs), all measured by hand in the photo and kept as data
// in PersonSpriteSpec next to the photo's own torso: the neck (mid-shoulders) and mid-hip pixel
// positions a COCO keypoint detector would report, and the point between the soles. The renderer
// (scene_renderer.hpp) places the sprite so that this torso lands on the projected torso of the
// simulated person's keypoints.
//
// The default is the standing man on the left of OpenCV's sample `basketball1.png` (Debian package
// opencv-doc): upright, whole body in view, facing the camera and turned a little towards the
// image's right. Measured on a 3x enlargement with a 10 px grid: shoulders at (45, 158) and
// (113, 152), neck (79, 153); hip joints (62, 292) and (104, 292) at the crotch's level less 15 px,
// mid-hip (83, 292); soles at row 472. The photo's camera looks down on him from nearby, so his legs
// are short for his torso; the renderer stretches the part below the hips to reach the ground.
//
// Determinism: GrabCut initialises its colour models with k-means++ from OpenCV's per-thread RNG;
// load() seeds that RNG with spec.seed for the call and restores its previous state, so the sprite is
// the same on every call and thread.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

/// Where the person is in the photo and how to cut them out. Pixel coordinates of the photo
/// (u right, v down, origin at the top-left pixel's corner).
struct PersonSpriteSpec {
  std::string image_path = "/usr/share/doc/opencv-doc/examples/data/basketball1.png";
  std::array<int, 4> crop_px = {22, 80, 160, 399};  ///< x, y, width, height: the person lies inside.
  Eigen::Vector2d neck_px{79.0, 153.0};             ///< Mid-shoulders.
  Eigen::Vector2d mid_hip_px{83.0, 292.0};          ///< Midpoint of the hip joints.
  Eigen::Vector2d soles_px{90.0, 472.0};            ///< Between the soles: where the person meets the ground.
  /// True if the person faces the camera turned towards the image's right (their left); the renderer
  /// mirrors the sprite when the simulated person clearly walks the other way across the image.
  bool turned_right = true;
  /// Segments {u0, v0, u1, v1} drawn as sure foreground (along the bones) and sure background.
  std::vector<std::array<double, 4>> foreground_strokes_px = {
      {88, 94, 85, 135},   {85, 135, 79, 153},   {79, 153, 83, 292},   {45, 158, 113, 155}, {45, 158, 66, 200},
      {66, 200, 145, 150}, {113, 155, 122, 200}, {122, 200, 148, 152}, {83, 292, 62, 300},  {83, 292, 104, 300},
      {62, 300, 58, 455},  {104, 300, 125, 460}, {78, 95, 98, 95}};
  std::vector<std::array<double, 4>> background_strokes_px = {{84, 328, 86, 450}, {108, 80, 108, 128}};
  double foreground_stroke_width_px = 7.0;
  double background_stroke_width_px = 4.0;
  int grabcut_iterations = 5;  ///< [1, 20].
  std::uint64_t seed = 1;      ///< For GrabCut's k-means++ initialisation.
};

/// Checks what can be checked without the photo: crop size > 0, points inside the crop, the neck
/// above the hips above the soles, stroke widths in [1, 50] px, iterations in [1, 20].
rt::Status validate(const PersonSpriteSpec& spec);

/// The cut-out person: premultiplied BGRA (CV_32FC4, channels in [0, 1]) in a pyramid whose level k
/// has 2^-k of the crop's size, for alias-free sampling at any scale. Immutable after load();
/// const methods are thread-safe.
class PersonSprite {
 public:
  /// Reads the photo, checks the spec against its size, segments it and builds the pyramid.
  /// Errors (missing, unreadable or corrupt file, crop outside the photo, nothing segmented) name
  /// the file. Allocates; takes about 1 s for the default photo (GrabCut; 2-core development machine).
  static rt::Expected<PersonSprite> load(const PersonSpriteSpec& spec);

  const std::vector<cv::Mat>& levels() const { return levels_; }
  /// Torso and soles in level-0 sprite pixels (crop coordinates).
  const Eigen::Vector2d& neckPx() const { return neck_px_; }
  const Eigen::Vector2d& midHipPx() const { return mid_hip_px_; }
  const Eigen::Vector2d& solesPx() const { return soles_px_; }
  /// Bounds of the opaque pixels in level-0 sprite pixels: {u_min, v_min, u_max, v_max} (corners).
  const Eigen::Vector4d& silhouetteBoundsPx() const { return silhouette_px_; }
  bool turnedRight() const { return turned_right_; }
  /// Number of level-0 pixels with alpha >= 0.5.
  int opaquePixels() const { return opaque_pixels_; }

 private:
  PersonSprite() = default;

  std::vector<cv::Mat> levels_;
  Eigen::Vector2d neck_px_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d mid_hip_px_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d soles_px_ = Eigen::Vector2d::Zero();
  Eigen::Vector4d silhouette_px_ = Eigen::Vector4d::Zero();
  bool turned_right_ = true;
  int opaque_pixels_ = 0;
};

}  // namespace aerotrack::hal::sim
