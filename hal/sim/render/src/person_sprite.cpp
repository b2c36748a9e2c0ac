// Person sprite: GrabCut segmentation of a photo, part labels, premultiplied-alpha pyramids. See
// person_sprite.hpp.
#include "aerotrack/hal/sim/person_sprite.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "photo_source.hpp"

namespace aerotrack::hal::sim {
namespace {

using K = CocoKeypoint;

constexpr int kMinLevelSidePx = 4;
constexpr int kMarginPx = 24;                 // background around the crop that GrabCut learns from
constexpr double kBoneStrokeFraction = 0.07;  // bone strokes' width, of the torso's length
constexpr double kMinBoneStrokePx = 1.0;

bool finite(const Eigen::Vector2d& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y());
}

Eigen::Vector2d at(const std::array<Eigen::Vector2d, kNumKeypoints>& kp, K k) {
  return kp[index(k)];
}

/// Seeds OpenCV's per-thread RNG for the lifetime of the guard and restores it afterwards.
class SeededOpenCvRng {
 public:
  explicit SeededOpenCvRng(std::uint64_t seed) : saved_(cv::theRNG()) { cv::theRNG() = cv::RNG(seed); }
  ~SeededOpenCvRng() { cv::theRNG() = saved_; }
  SeededOpenCvRng(const SeededOpenCvRng&) = delete;
  SeededOpenCvRng& operator=(const SeededOpenCvRng&) = delete;

 private:
  cv::RNG saved_;
};

cv::Point pixel(const Eigen::Vector2d& p, const Eigen::Vector2d& origin) {
  return {static_cast<int>(std::lround(p.x() - origin.x())), static_cast<int>(std::lround(p.y() - origin.y()))};
}

/// Draws the segments {u0, v0, u1, v1} (photo pixels) into mask, whose origin is at `origin` in the photo.
void drawStrokes(cv::Mat& mask, const std::vector<std::array<double, 4>>& strokes, const Eigen::Vector2d& origin,
                 double width_px, int label) {
  for (const auto& s : strokes) {
    cv::line(mask, pixel({s[0], s[1]}, origin), pixel({s[2], s[3]}, origin), cv::Scalar(label),
             std::max(1, static_cast<int>(std::lround(width_px))), cv::LINE_8);
  }
}

double segmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len_sq = ab.squaredNorm();
  const double t = len_sq > 0.0 ? std::clamp((p - a).dot(ab) / len_sq, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

/// Inside the convex quadrilateral q (either winding)?
bool insideQuad(const Eigen::Vector2d& p, const std::array<Eigen::Vector2d, 4>& q) {
  int sign = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    const Eigen::Vector2d e = q[(i + 1) % 4] - q[i], r = p - q[i];
    const double cross = e.x() * r.y() - e.y() * r.x();
    const int s = cross > 0.0 ? 1 : (cross < 0.0 ? -1 : 0);
    if (s == 0) continue;
    if (sign == 0) sign = s;
    if (s != sign) return false;
  }
  return true;
}

/// Labels every pixel of alpha (level 0) with its body part (person_sprite.hpp).
cv::Mat labelParts(const cv::Mat& alpha, const std::array<Eigen::Vector2d, kNumKeypoints>& kp) {
  const std::array<Eigen::Vector2d, 4> torso = {at(kp, K::kLeftShoulder), at(kp, K::kRightShoulder),
                                                at(kp, K::kRightHip), at(kp, K::kLeftHip)};
  std::array<std::array<Eigen::Vector2d, 2>, kPartCount> bones{};
  for (std::size_t p = 0; p < kPartCount; ++p) bones[p] = bodyPartEnds(static_cast<BodyPart>(p), kp);
  cv::Mat labels(alpha.size(), CV_8UC1, cv::Scalar(kNoPart));
  for (int v = 0; v < alpha.rows; ++v) {
    for (int u = 0; u < alpha.cols; ++u) {
      if (alpha.at<float>(v, u) <= 0.02F) continue;
      const Eigen::Vector2d c(u + 0.5, v + 0.5);
      std::size_t best = 0;
      if (!insideQuad(c, torso)) {
        double best_d = std::numeric_limits<double>::infinity();
        for (std::size_t p = 0; p < kPartCount; ++p) {
          double d = segmentDistance(c, bones[p][0], bones[p][1]);
          if (p == 0) {  // the torso: distance to its outline
            d = std::numeric_limits<double>::infinity();
            for (std::size_t i = 0; i < 4; ++i) d = std::min(d, segmentDistance(c, torso[i], torso[(i + 1) % 4]));
          }
          if (d < best_d) best_d = d, best = p;
        }
      }
      labels.at<std::uint8_t>(v, u) = static_cast<std::uint8_t>(best);
    }
  }
  return labels;
}

}  // namespace

const char* toString(PersonView view) {
  return view == PersonView::kFront ? "front" : "back";
}

rt::Status validate(const PersonSpriteSpec& s) {
  const auto fail = [&](const std::string& key, const std::string& what) {
    return rt::Status(
        rt::Error{"person " + (s.name.empty() ? std::string("(unnamed)") : s.name) + ": " + key + ": " + what});
  };
  if (s.name.empty()) return fail("name", "is empty");
  if (s.image_path.empty()) return fail("image", "is empty");
  if (s.frame < -1) return fail("frame", "must be >= 0 (a video's frame) or absent (a still image)");
  const int x = s.crop_px[0], y = s.crop_px[1], w = s.crop_px[2], h = s.crop_px[3];
  if (x < 0 || y < 0 || w < 8 || h < 8) return fail("crop_px", "must be [x >= 0, y >= 0, width >= 8, height >= 8]");
  for (std::size_t i = 0; i < kNumKeypoints; ++i) {
    const Eigen::Vector2d& p = s.keypoints_px[i];
    if (!finite(p) || p.x() < x || p.x() > x + w || p.y() < y || p.y() > y + h)
      return fail("keypoints_px", "keypoint " + std::to_string(i) + " lies outside crop_px");
  }
  const auto& kp = s.keypoints_px;
  const Eigen::Vector2d neck = 0.5 * (at(kp, K::kLeftShoulder) + at(kp, K::kRightShoulder));
  const Eigen::Vector2d hip = 0.5 * (at(kp, K::kLeftHip) + at(kp, K::kRightHip));
  const Eigen::Vector2d ankle = 0.5 * (at(kp, K::kLeftAnkle) + at(kp, K::kRightAnkle));
  if (!(neck.y() + 4.0 <= hip.y() && hip.y() + 4.0 <= ankle.y()))
    return fail("keypoints_px", "need the neck above the mid-hip above the ankles (v increasing, >= 4 px apart)");
  const bool left_on_right = at(kp, K::kLeftShoulder).x() > at(kp, K::kRightShoulder).x();
  if (left_on_right != (s.view == PersonView::kFront))
    return fail("view", std::string("is ") + toString(s.view) + " but the left shoulder is on the image's " +
                            (left_on_right ? "right (a front view)" : "left (a back view)"));
  if (!(s.background_stroke_width_px >= 1.0 && s.background_stroke_width_px <= 50.0))
    return fail("background_stroke_width_px", "must be in [1, 50] px");
  for (const auto* strokes : {&s.foreground_strokes_px, &s.background_strokes_px}) {
    for (const auto& stroke : *strokes) {
      for (const double c : stroke) {
        if (!std::isfinite(c)) return fail("strokes", "coordinates must be finite");
      }
    }
  }
  if (s.grabcut_iterations < 1 || s.grabcut_iterations > 20) return fail("grabcut_iterations", "must be in [1, 20]");
  return rt::ok();
}

Eigen::Vector2d PersonSprite::neckPx() const {
  return bodyPartEnds(BodyPart::kTorso, keypoints_px_)[0];
}

Eigen::Vector2d PersonSprite::midHipPx() const {
  return bodyPartEnds(BodyPart::kTorso, keypoints_px_)[1];
}

rt::Expected<PersonSprite> PersonSprite::load(const PersonSpriteSpec& spec) {
  if (auto status = validate(spec); !status) return status.error();
  auto photo = readPhoto(spec.image_path, spec.frame);
  if (!photo) return photo.error();
  return fromPhoto(spec, photo.value());
}

rt::Expected<PersonSprite> PersonSprite::fromPhoto(const PersonSpriteSpec& spec, const cv::Mat& photo) {
  if (auto status = validate(spec); !status) return status.error();
  const std::string where = "person " + spec.name + " (" + spec.image_path +
                            (spec.frame >= 0 ? ", frame " + std::to_string(spec.frame) : std::string()) + "): ";
  const cv::Rect crop(spec.crop_px[0], spec.crop_px[1], spec.crop_px[2], spec.crop_px[3]);
  if (photo.type() != CV_8UC3 || (crop & cv::Rect(0, 0, photo.cols, photo.rows)) != crop) {
    return rt::Error{where + "crop_px exceeds the " + std::to_string(photo.cols) + " x " + std::to_string(photo.rows) +
                     " image"};
  }

  // GrabCut on the crop and a margin around it (the margin teaches the background model): outside the
  // crop is background, inside probably foreground, the bones and extra strokes sure.
  const cv::Rect work =
      cv::Rect(crop.x - kMarginPx, crop.y - kMarginPx, crop.width + 2 * kMarginPx, crop.height + 2 * kMarginPx) &
      cv::Rect(0, 0, photo.cols, photo.rows);
  const cv::Rect crop_in_work(crop.x - work.x, crop.y - work.y, crop.width, crop.height);
  cv::Mat mask(work.size(), CV_8UC1, cv::Scalar(cv::GC_BGD));
  mask(crop_in_work).setTo(cv::Scalar(cv::GC_PR_FGD));
  const Eigen::Vector2d shift(work.x, work.y);
  drawStrokes(mask, spec.background_strokes_px, shift, spec.background_stroke_width_px, cv::GC_BGD);
  const auto& kp = spec.keypoints_px;
  const double torso_px = (bodyPartEnds(BodyPart::kTorso, kp)[1] - bodyPartEnds(BodyPart::kTorso, kp)[0]).norm();
  const double bone_width_px = std::max(kMinBoneStrokePx, kBoneStrokeFraction * torso_px);
  std::vector<std::array<double, 4>> bones = spec.foreground_strokes_px;
  for (std::size_t p = 0; p < kPartCount; ++p) {
    const auto ends = bodyPartEnds(static_cast<BodyPart>(p), kp);
    bones.push_back({ends[0].x(), ends[0].y(), ends[1].x(), ends[1].y()});
  }
  bones.push_back({at(kp, K::kLeftShoulder).x(), at(kp, K::kLeftShoulder).y(), at(kp, K::kRightShoulder).x(),
                   at(kp, K::kRightShoulder).y()});
  bones.push_back(
      {at(kp, K::kLeftHip).x(), at(kp, K::kLeftHip).y(), at(kp, K::kRightHip).x(), at(kp, K::kRightHip).y()});
  drawStrokes(mask, bones, shift, bone_width_px, cv::GC_FGD);
  try {
    const SeededOpenCvRng seeded(spec.seed);
    cv::Mat bgd_model, fgd_model;
    cv::grabCut(photo(work).clone(), mask, crop_in_work, bgd_model, fgd_model, spec.grabcut_iterations,
                cv::GC_INIT_WITH_MASK);
  } catch (const cv::Exception& e) {
    return rt::Error{where + "segmentation failed: " + e.what()};
  }
  const cv::Mat foreground_work = (mask == cv::GC_FGD) | (mask == cv::GC_PR_FGD);
  const cv::Mat foreground = foreground_work(crop_in_work).clone();

  // Keep the connected piece that holds the torso (drops specks of background GrabCut let through).
  cv::Mat components;
  cv::connectedComponents(foreground, components, 8, CV_32S);
  const Eigen::Vector2d origin(crop.x, crop.y);
  const cv::Point hip_in_crop = pixel(bodyPartEnds(BodyPart::kTorso, kp)[1], origin);
  const int body_label =
      components.at<int>(std::clamp(hip_in_crop.y, 0, crop.height - 1), std::clamp(hip_in_crop.x, 0, crop.width - 1));
  if (body_label == 0) return rt::Error{where + "segmentation found no person at the mid-hip"};
  cv::Mat alpha;
  cv::Mat(components == body_label).convertTo(alpha, CV_32F, 1.0 / 255.0);
  cv::GaussianBlur(alpha, alpha, cv::Size(3, 3), 0.7, 0.7, cv::BORDER_CONSTANT);  // soft, anti-aliased edges

  PersonSprite sprite;
  sprite.name_ = spec.name;
  sprite.view_ = spec.view;
  for (std::size_t i = 0; i < kNumKeypoints; ++i) sprite.keypoints_px_[i] = spec.keypoints_px[i] - origin;
  cv::Mat bgr;
  photo(crop).convertTo(bgr, CV_32F, 1.0 / 255.0);
  std::vector<cv::Mat> channels;
  cv::split(bgr, channels);
  for (cv::Mat& c : channels) c = c.mul(alpha);
  channels.push_back(alpha);
  cv::Mat level;
  cv::merge(channels, level);
  cv::Mat labels = labelParts(alpha, sprite.keypoints_px_);

  // Per part: bounds, pixel count; the head's luminance and its top third's colour (the hair).
  std::array<cv::Rect, kPartCount> bounds{};
  double head_top = std::numeric_limits<double>::infinity(), head_bottom = -head_top;
  for (int v = 0; v < labels.rows; ++v) {
    for (int u = 0; u < labels.cols; ++u) {
      const std::uint8_t part = labels.at<std::uint8_t>(v, u);
      if (part == kNoPart) continue;
      bounds[part] |= cv::Rect(u, v, 1, 1);
      if (alpha.at<float>(v, u) >= 0.5F) ++sprite.part_pixels_[part];
      if (part == static_cast<std::uint8_t>(BodyPart::kHead)) {
        head_top = std::min(head_top, static_cast<double>(v));
        head_bottom = std::max(head_bottom, static_cast<double>(v));
      }
    }
  }
  for (std::size_t p = 0; p < kPartCount; ++p) {
    const cv::Rect& b = bounds[p];
    sprite.part_bounds_px_[p] = Eigen::Vector4d(b.x, b.y, b.x + b.width, b.y + b.height);
  }
  Eigen::Vector3d hair = Eigen::Vector3d::Zero();
  double hair_weight = 0.0, luminance = 0.0, head_weight = 0.0;
  const double hair_below = head_top + (head_bottom - head_top) / 3.0;
  for (int v = 0; v < labels.rows; ++v) {
    for (int u = 0; u < labels.cols; ++u) {
      if (labels.at<std::uint8_t>(v, u) != static_cast<std::uint8_t>(BodyPart::kHead)) continue;
      const cv::Vec4f c = level.at<cv::Vec4f>(v, u);
      luminance += static_cast<double>(0.114F * c[0] + 0.587F * c[1] + 0.299F * c[2]);
      head_weight += static_cast<double>(c[3]);
      if (v <= hair_below) {
        hair += Eigen::Vector3f(c[0], c[1], c[2]).cast<double>();
        hair_weight += static_cast<double>(c[3]);
      }
    }
  }
  if (hair_weight > 0.0) sprite.hair_bgr_ = (hair / hair_weight).cast<float>();
  if (head_weight > 0.0) sprite.head_luminance_ = static_cast<float>(luminance / head_weight);

  sprite.levels_.push_back(level);
  sprite.labels_.push_back(labels);
  while (std::min(level.cols, level.rows) >= 2 * kMinLevelSidePx) {
    cv::Mat down, down_labels;
    cv::pyrDown(level, down);
    cv::resize(labels, down_labels, down.size(), 0.0, 0.0, cv::INTER_NEAREST);
    sprite.levels_.push_back(down);
    sprite.labels_.push_back(down_labels);
    level = down;
    labels = down_labels;
  }
  sprite.opaque_pixels_ = cv::countNonZero(alpha >= 0.5);
  if (sprite.opaque_pixels_ < 100) return rt::Error{where + "segmentation kept almost nothing of the person"};
  return sprite;
}

}  // namespace aerotrack::hal::sim
