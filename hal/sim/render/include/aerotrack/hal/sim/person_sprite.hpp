// One simulated person's appearance in image mode: a real person cut out of a photo or a video frame
// and cut again into body parts, so that the renderer (scene_renderer.hpp) can warp each part onto
// the simulated person's keypoints every frame -- arms and legs move with the gait, the body turns,
// and the real keypoint network (MoveNet, issue 5) sees real human imagery in closed-loop runs.
//
// Loading, once:
//   - Segmentation: GrabCut (Rother, Kolmogorov & Blake, SIGGRAPH 2004) inside a crop rectangle,
//     with sure-foreground strokes along the skeleton's bones (drawn from the COCO-17 keypoints
//     measured in the photo; their width a fraction of the torso's length) and any extra strokes
//     the spec gives (e.g. sure background between the legs).
//   - Parts: every opaque pixel is labelled with one of ten body parts (kPartCount): inside the
//     torso's quadrilateral (shoulders and hips) it is the torso's, elsewhere the nearest bone's
//     (head: neck to head centre; upper arm, forearm, thigh, shin on each side). The renderer samples
//     a part only from pixels of its own label, so a warped forearm never drags torso pixels along.
//   - The photo's view: front (the person faces the photo's camera: their left shoulder on the
//     image's right) or back. It must agree with the keypoints' shoulder order, a check against
//     data-entry errors. A person seen from the other side is drawn mirrored by the renderer, a
//     front photo's head then painted in its hair colour (the back of a head shows no face).
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

#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

/// Which side of the person the photo shows.
enum class PersonView : std::uint8_t { kFront, kBack };

/// "front" or "back".
const char* toString(PersonView view);

/// Body parts a sprite is cut into. The bones (keypoint pairs) are in bodyPartBone().
enum class BodyPart : std::uint8_t {
  kTorso,
  kHead,
  kLeftUpperArm,
  kLeftForearm,
  kRightUpperArm,
  kRightForearm,
  kLeftThigh,
  kLeftShin,
  kRightThigh,
  kRightShin,
};
inline constexpr std::size_t kPartCount = 10;
/// The label of transparent pixels in PersonSprite::labels().
inline constexpr std::uint8_t kNoPart = 255;

/// Where the person is in the photo and how to cut them out. Pixel coordinates of the photo (u right,
/// v down, origin at the top-left pixel's corner). The default is the standing man on the left of
/// OpenCV's sample basketball1.png (Debian package opencv-doc); default_cast.hpp lists the others.
struct PersonSpriteSpec {
  std::string name = "basketball1_standing";
  std::string image_path = "/usr/share/doc/opencv-doc/examples/data/basketball1.png";
  /// A video's frame (0-based) when image_path is a video; -1 for a still image.
  int frame = -1;
  PersonView view = PersonView::kFront;
  std::array<int, 4> crop_px = {22, 80, 160, 399};  ///< x, y, width, height: the person lies inside.
  /// COCO-17 keypoints in the photo, the person's left and right (hal::CocoKeypoint order): MoveNet
  /// thunder's on the crop (`aerotrack detect --model thunder`), checked by eye. The network's own
  /// joints, not joints measured by hand: the renderer pins these photo points to the simulated
  /// joints, so the network finds the simulated torso in the rendered person (hips measured by hand
  /// at the crotch's level less 15 px, 18 px below thunder's, made the network's torso 13 % short).
  std::array<Eigen::Vector2d, kNumKeypoints> keypoints_px = {{{95, 115},
                                                              {98, 107},
                                                              {85, 108},
                                                              {94, 111},
                                                              {66, 114},
                                                              {114, 158},
                                                              {45, 156},
                                                              {142, 215},
                                                              {89, 206},
                                                              {145, 173},
                                                              {127, 166},
                                                              {111, 274},
                                                              {69, 277},
                                                              {119, 373},
                                                              {66, 374},
                                                              {115, 440},
                                                              {59, 455}}};
  /// Extra segments {u0, v0, u1, v1} drawn as sure foreground and sure background; the bones are
  /// always sure foreground.
  std::vector<std::array<double, 4>> foreground_strokes_px = {{88, 94, 85, 135}, {78, 95, 98, 95}};
  std::vector<std::array<double, 4>> background_strokes_px = {{84, 328, 86, 450}, {108, 80, 108, 128}};
  double background_stroke_width_px = 4.0;
  int grabcut_iterations = 5;  ///< [1, 20].
  std::uint64_t seed = 1;      ///< For GrabCut's k-means++ initialisation.
};

/// Checks what can be checked without the photo: a name, crop size >= 8, keypoints finite and inside
/// the crop, the neck above the hips above the ankles, the view agreeing with the shoulders' order,
/// stroke width in [1, 50] px, iterations in [1, 20], frame >= -1. Errors name the spec's key.
rt::Status validate(const PersonSpriteSpec& spec);

/// The two points a body part hangs between: a bone's keypoints; the torso neck (mid-shoulders) to
/// mid-hip; the head neck to head centre (the mean of nose, eyes and ears). For image or 3D points.
template <typename Point>
std::array<Point, 2> bodyPartEnds(BodyPart part, const std::array<Point, kNumKeypoints>& kp) {
  using Joint = CocoKeypoint;
  const auto at = [&](Joint k) -> const Point& { return kp[index(k)]; };
  const Point neck = 0.5 * (at(Joint::kLeftShoulder) + at(Joint::kRightShoulder));
  switch (part) {
    case BodyPart::kTorso:
      return {neck, Point(0.5 * (at(Joint::kLeftHip) + at(Joint::kRightHip)))};
    case BodyPart::kHead:
      return {neck, Point((kp[0] + kp[1] + kp[2] + kp[3] + kp[4]) / 5.0)};
    case BodyPart::kLeftUpperArm:
      return {at(Joint::kLeftShoulder), at(Joint::kLeftElbow)};
    case BodyPart::kLeftForearm:
      return {at(Joint::kLeftElbow), at(Joint::kLeftWrist)};
    case BodyPart::kRightUpperArm:
      return {at(Joint::kRightShoulder), at(Joint::kRightElbow)};
    case BodyPart::kRightForearm:
      return {at(Joint::kRightElbow), at(Joint::kRightWrist)};
    case BodyPart::kLeftThigh:
      return {at(Joint::kLeftHip), at(Joint::kLeftKnee)};
    case BodyPart::kLeftShin:
      return {at(Joint::kLeftKnee), at(Joint::kLeftAnkle)};
    case BodyPart::kRightThigh:
      return {at(Joint::kRightHip), at(Joint::kRightKnee)};
    case BodyPart::kRightShin:
      return {at(Joint::kRightKnee), at(Joint::kRightAnkle)};
  }
  return {neck, neck};
}

/// The cut-out person: premultiplied BGRA (CV_32FC4, channels in [0, 1]) and part labels (CV_8UC1,
/// kNoPart where transparent) in pyramids whose level k has 2^-k of the crop's size, for alias-free
/// sampling at any scale. Immutable after load(); const methods are thread-safe.
class PersonSprite {
 public:
  /// Reads the photo (or the video up to its frame), checks the spec against its size, segments it,
  /// labels the parts and builds the pyramids. Errors (missing, unreadable or corrupt file, a frame
  /// past the video's end, crop outside the photo, nothing segmented) name the file. Allocates; about
  /// 0.2-1 s (GrabCut; 2-core development machine).
  static rt::Expected<PersonSprite> load(const PersonSpriteSpec& spec);
  /// As load(), with the decoded photo given (for a cast that reads one video once).
  static rt::Expected<PersonSprite> fromPhoto(const PersonSpriteSpec& spec, const cv::Mat& photo_bgr);

  const std::string& name() const { return name_; }
  PersonView view() const { return view_; }
  const std::vector<cv::Mat>& levels() const { return levels_; }
  const std::vector<cv::Mat>& labels() const { return labels_; }
  /// Keypoints in level-0 sprite pixels (crop coordinates).
  const std::array<Eigen::Vector2d, kNumKeypoints>& keypointsPx() const { return keypoints_px_; }
  Eigen::Vector2d neckPx() const;
  Eigen::Vector2d midHipPx() const;
  /// Bounds of each part's pixels in level-0 sprite pixels: {u_min, v_min, u_max, v_max} (corners);
  /// all zero for a part with no pixels.
  const std::array<Eigen::Vector4d, kPartCount>& partBoundsPx() const { return part_bounds_px_; }
  /// Pixels (alpha >= 0.5) of each part at level 0.
  const std::array<int, kPartCount>& partPixels() const { return part_pixels_; }
  /// Mean colour (B, G, R in [0, 1]) of the top third of the head: the hair, painted over a front
  /// photo's face when the person is seen from behind.
  const Eigen::Vector3f& hairBgr() const { return hair_bgr_; }
  /// Mean luminance of the head's pixels, [0, 1].
  float headLuminance() const { return head_luminance_; }
  /// Number of level-0 pixels with alpha >= 0.5.
  int opaquePixels() const { return opaque_pixels_; }

 private:
  PersonSprite() = default;

  std::string name_;
  PersonView view_ = PersonView::kFront;
  std::vector<cv::Mat> levels_;
  std::vector<cv::Mat> labels_;
  std::array<Eigen::Vector2d, kNumKeypoints> keypoints_px_{};
  std::array<Eigen::Vector4d, kPartCount> part_bounds_px_{};
  std::array<int, kPartCount> part_pixels_{};
  Eigen::Vector3f hair_bgr_ = Eigen::Vector3f::Zero();
  float head_luminance_ = 0.5F;
  int opaque_pixels_ = 0;
};

}  // namespace aerotrack::hal::sim
