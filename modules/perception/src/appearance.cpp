// Torso colour histogram: see appearance.hpp.
#include "aerotrack/perception/appearance.hpp"

#include <algorithm>
#include <cmath>

namespace aerotrack::perception {

using hal::CocoKeypoint;
using hal::index;

namespace {

/// Adds one BGR pixel to the histogram (HSV as OpenCV defines it, computed inline to avoid a
/// colour conversion buffer). Hue votes into its two nearest bins in proportion to closeness, so
/// that a colour on a bin boundary (pure red sits at 0/360 degrees) does not flip between bins with
/// pixel noise.
void vote(const cv::Vec3b& px, std::array<double, kAppearanceBins>& counts) {
  const int b = px[0], g = px[1], r = px[2];
  const int max = std::max({r, g, b});
  const int min = std::min({r, g, b});
  const int chroma = max - min;
  constexpr int kMinValue = 40;   // darker: hue is noise
  constexpr int kMinChroma = 25;  // greyer: hue is noise
  if (max < kMinValue || chroma < kMinChroma) {
    counts[kAppearanceBins - 1] += 1.0;
    return;
  }
  double hue_deg = 0.0;
  if (max == r)
    hue_deg = 60.0 * (g - b) / chroma;
  else if (max == g)
    hue_deg = 120.0 + 60.0 * (b - r) / chroma;
  else
    hue_deg = 240.0 + 60.0 * (r - g) / chroma;
  if (hue_deg < 0.0) hue_deg += 360.0;
  const double saturation = static_cast<double>(chroma) / max;
  const int sat_bin = std::min(kSaturationBins - 1, static_cast<int>(saturation * kSaturationBins));
  // Bin i is centred on hue i x 360 / kHueBins.
  const double position = hue_deg / 360.0 * kHueBins;
  const int lower = static_cast<int>(std::floor(position)) % kHueBins;
  const int upper = (lower + 1) % kHueBins;
  const double upper_share = position - std::floor(position);
  const auto bin = [&](int hue_bin) {
    return static_cast<std::size_t>(hue_bin) * static_cast<std::size_t>(kSaturationBins) +
           static_cast<std::size_t>(sat_bin);
  };
  counts[bin(lower)] += 1.0 - upper_share;
  counts[bin(upper)] += upper_share;
}

}  // namespace

Appearance torsoAppearance(const cv::Mat& bgr, const std::array<hal::Keypoint2D, hal::kNumKeypoints>& keypoints,
                           int min_pixels) {
  Appearance out;
  if (bgr.empty() || bgr.type() != CV_8UC3) return out;
  double u_min = 1e300, u_max = -1e300, v_min = 1e300, v_max = -1e300;
  for (CocoKeypoint k :
       {CocoKeypoint::kLeftShoulder, CocoKeypoint::kRightShoulder, CocoKeypoint::kLeftHip, CocoKeypoint::kRightHip}) {
    const hal::Keypoint2D& p = keypoints[index(k)];
    u_min = std::min(u_min, p.u_px);
    u_max = std::max(u_max, p.u_px);
    v_min = std::min(v_min, p.v_px);
    v_max = std::max(v_max, p.v_px);
  }
  // The central part of the torso box: joints sit on the body's outline, so its edges hold background.
  const double du = 0.2 * (u_max - u_min);
  const double dv = 0.15 * (v_max - v_min);
  const int u0 = std::max(0, static_cast<int>(std::floor(u_min + du)));
  const int u1 = std::min(bgr.cols, static_cast<int>(std::ceil(u_max - du)));
  const int v0 = std::max(0, static_cast<int>(std::floor(v_min + dv)));
  const int v1 = std::min(bgr.rows, static_cast<int>(std::ceil(v_max - dv)));
  if (u1 <= u0 || v1 <= v0 || (u1 - u0) * (v1 - v0) < min_pixels) return out;

  std::array<double, kAppearanceBins> counts{};
  for (int v = v0; v < v1; ++v) {
    const auto* row = bgr.ptr<cv::Vec3b>(v);
    for (int u = u0; u < u1; ++u) vote(row[u], counts);
  }
  const double total = static_cast<double>((u1 - u0) * (v1 - v0));
  for (std::size_t i = 0; i < counts.size(); ++i) out.histogram[i] = static_cast<float>(counts[i] / total);
  out.valid = true;
  return out;
}

double appearanceDistance(const Appearance& a, const Appearance& b) {
  if (!a.valid || !b.valid) return 1.0;
  double coefficient = 0.0;
  for (std::size_t i = 0; i < a.histogram.size(); ++i)
    coefficient += std::sqrt(static_cast<double>(a.histogram[i]) * static_cast<double>(b.histogram[i]));
  return std::sqrt(std::max(0.0, 1.0 - coefficient));
}

void blendAppearance(Appearance& a, const Appearance& b, double rate) {
  if (!b.valid) return;
  if (!a.valid) {
    a = b;
    return;
  }
  for (std::size_t i = 0; i < a.histogram.size(); ++i)
    a.histogram[i] = static_cast<float>((1.0 - rate) * static_cast<double>(a.histogram[i]) +
                                        rate * static_cast<double>(b.histogram[i]));
}

}  // namespace aerotrack::perception
