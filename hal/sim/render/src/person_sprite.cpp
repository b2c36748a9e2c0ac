// Person sprite: GrabCut segmentation of a photo into a premultiplied-alpha pyramid. See
// person_sprite.hpp.
#include "aerotrack/hal/sim/person_sprite.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace aerotrack::hal::sim {
namespace {

constexpr int kMinLevelSidePx = 4;
constexpr int kMarginPx = 24;  // background around the crop that GrabCut learns from

bool finite(const Eigen::Vector2d& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y());
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

/// Draws the segments {u0, v0, u1, v1} (photo pixels) into mask, whose origin is at `origin` in the photo.
void drawStrokes(cv::Mat& mask, const std::vector<std::array<double, 4>>& strokes, const Eigen::Vector2d& origin,
                 double width_px, int label) {
  const auto point = [&](double u, double v) {
    return cv::Point(static_cast<int>(std::lround(u - origin.x())), static_cast<int>(std::lround(v - origin.y())));
  };
  for (const auto& s : strokes) {
    cv::line(mask, point(s[0], s[1]), point(s[2], s[3]), cv::Scalar(label), static_cast<int>(std::lround(width_px)),
             cv::LINE_8);
  }
}

}  // namespace

rt::Status validate(const PersonSpriteSpec& s) {
  const auto fail = [](const std::string& what) { return rt::Status(rt::Error{"person sprite: " + what}); };
  if (s.image_path.empty()) return fail("image_path is empty");
  const int x = s.crop_px[0], y = s.crop_px[1], w = s.crop_px[2], h = s.crop_px[3];
  if (x < 0 || y < 0 || w < 8 || h < 8) return fail("crop_px must be [x >= 0, y >= 0, width >= 8, height >= 8]");
  const auto inside = [&](const Eigen::Vector2d& p) {
    return finite(p) && p.x() >= x && p.x() <= x + w && p.y() >= y && p.y() <= y + h;
  };
  if (!inside(s.neck_px) || !inside(s.mid_hip_px) || !inside(s.soles_px))
    return fail("neck_px, mid_hip_px and soles_px must lie inside crop_px");
  if (!(s.neck_px.y() + 4.0 <= s.mid_hip_px.y() && s.mid_hip_px.y() + 4.0 <= s.soles_px.y()))
    return fail("need the neck above the mid-hip above the soles (v increasing, at least 4 px apart)");
  for (const double width : {s.foreground_stroke_width_px, s.background_stroke_width_px}) {
    if (!(width >= 1.0 && width <= 50.0)) return fail("stroke widths must be in [1, 50] px");
  }
  for (const auto* strokes : {&s.foreground_strokes_px, &s.background_strokes_px}) {
    for (const auto& stroke : *strokes) {
      for (const double c : stroke) {
        if (!std::isfinite(c)) return fail("stroke coordinates must be finite");
      }
    }
  }
  if (s.grabcut_iterations < 1 || s.grabcut_iterations > 20) return fail("grabcut_iterations must be in [1, 20]");
  return rt::ok();
}

rt::Expected<PersonSprite> PersonSprite::load(const PersonSpriteSpec& spec) {
  if (auto status = validate(spec); !status) return status.error();
  const std::string where = "person sprite " + spec.image_path + ": ";
  if (!std::filesystem::is_regular_file(spec.image_path)) return rt::Error{where + "no such file"};
  cv::Mat photo;
  try {
    photo = cv::imread(spec.image_path, cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    return rt::Error{where + "cannot decode: " + e.what()};
  }
  if (photo.empty()) return rt::Error{where + "cannot read (missing file, or not an image)"};
  const cv::Rect crop(spec.crop_px[0], spec.crop_px[1], spec.crop_px[2], spec.crop_px[3]);
  if ((crop & cv::Rect(0, 0, photo.cols, photo.rows)) != crop) {
    return rt::Error{where + "crop_px exceeds the " + std::to_string(photo.cols) + " x " + std::to_string(photo.rows) +
                     " image"};
  }

  // GrabCut on the crop and a margin around it (the margin teaches the background model): outside the
  // crop is background, inside probably foreground, the strokes sure.
  const cv::Rect work =
      cv::Rect(crop.x - kMarginPx, crop.y - kMarginPx, crop.width + 2 * kMarginPx, crop.height + 2 * kMarginPx) &
      cv::Rect(0, 0, photo.cols, photo.rows);
  const cv::Rect crop_in_work(crop.x - work.x, crop.y - work.y, crop.width, crop.height);
  cv::Mat mask(work.size(), CV_8UC1, cv::Scalar(cv::GC_BGD));
  mask(crop_in_work).setTo(cv::Scalar(cv::GC_PR_FGD));
  const Eigen::Vector2d shift(work.x, work.y);
  drawStrokes(mask, spec.background_strokes_px, shift, spec.background_stroke_width_px, cv::GC_BGD);
  drawStrokes(mask, spec.foreground_strokes_px, shift, spec.foreground_stroke_width_px, cv::GC_FGD);
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
  cv::Mat labels;
  cv::connectedComponents(foreground, labels, 8, CV_32S);
  const cv::Point hip_in_crop(static_cast<int>(spec.mid_hip_px.x()) - crop.x,
                              static_cast<int>(spec.mid_hip_px.y()) - crop.y);
  const int body_label =
      labels.at<int>(std::clamp(hip_in_crop.y, 0, crop.height - 1), std::clamp(hip_in_crop.x, 0, crop.width - 1));
  if (body_label == 0) return rt::Error{where + "segmentation found no person at mid_hip_px"};
  cv::Mat alpha;
  cv::Mat(labels == body_label).convertTo(alpha, CV_32F, 1.0 / 255.0);
  cv::GaussianBlur(alpha, alpha, cv::Size(3, 3), 0.7, 0.7, cv::BORDER_CONSTANT);  // soft, anti-aliased edges

  PersonSprite sprite;
  cv::Mat bgr;
  photo(crop).convertTo(bgr, CV_32F, 1.0 / 255.0);
  std::vector<cv::Mat> channels;
  cv::split(bgr, channels);
  for (cv::Mat& c : channels) c = c.mul(alpha);
  channels.push_back(alpha);
  cv::Mat level;
  cv::merge(channels, level);
  sprite.levels_.push_back(level);
  while (std::min(level.cols, level.rows) >= 2 * kMinLevelSidePx) {
    cv::Mat down;
    cv::pyrDown(level, down);
    sprite.levels_.push_back(down);
    level = down;
  }

  const Eigen::Vector2d origin(crop.x, crop.y);
  sprite.neck_px_ = spec.neck_px - origin;
  sprite.mid_hip_px_ = spec.mid_hip_px - origin;
  sprite.soles_px_ = spec.soles_px - origin;
  sprite.turned_right_ = spec.turned_right;
  const cv::Mat opaque = alpha >= 0.5;
  sprite.opaque_pixels_ = cv::countNonZero(opaque);
  if (sprite.opaque_pixels_ < 100) return rt::Error{where + "segmentation kept almost nothing of the person"};
  const cv::Rect bounds = cv::boundingRect(alpha > 0.02);
  sprite.silhouette_px_ = Eigen::Vector4d(bounds.x, bounds.y, bounds.x + bounds.width, bounds.y + bounds.height);
  return sprite;
}

}  // namespace aerotrack::hal::sim
