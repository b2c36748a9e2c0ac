// Appearance from the image: see appearance.hpp.
#include "aerotrack/perception/appearance.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace aerotrack::perception {

using hal::CocoKeypoint;
using hal::index;
using hal::SignatureRegion;

namespace {

struct PixelBox {
  int u0 = 0, u1 = 0, v0 = 0, v1 = 0;  ///< [u0, u1) x [v0, v1)
  int pixels() const { return (u1 - u0) * (v1 - v0); }
};

PixelBox clipped(double u_min, double u_max, double v_min, double v_max, const cv::Mat& image) {
  PixelBox b;
  b.u0 = std::max(0, static_cast<int>(std::floor(u_min)));
  b.u1 = std::min(image.cols, static_cast<int>(std::ceil(u_max)));
  b.v0 = std::max(0, static_cast<int>(std::floor(v_min)));
  b.v1 = std::min(image.rows, static_cast<int>(std::ceil(v_max)));
  if (b.u1 < b.u0) b.u1 = b.u0;
  if (b.v1 < b.v0) b.v1 = b.v0;
  return b;
}

/// Adds one BGR pixel's vote (HSV as OpenCV defines it, computed inline to avoid a conversion buffer).
void vote(const cv::Vec3b& px, std::array<double, hal::kSignatureRegionBins>& counts) {
  const int b = px[0], g = px[1], r = px[2];
  const int max = std::max({r, g, b});
  const int chroma = max - std::min({r, g, b});
  double hue_deg = 0.0;
  if (chroma > 0) {
    if (max == r)
      hue_deg = 60.0 * (g - b) / chroma;
    else if (max == g)
      hue_deg = 120.0 + 60.0 * (b - r) / chroma;
    else
      hue_deg = 240.0 + 60.0 * (r - g) / chroma;
  }
  const double saturation = max > 0 ? static_cast<double>(chroma) / max : 0.0;
  const hal::ColourVote v = hal::colourVote(hue_deg, saturation, max / 255.0);
  counts[v.bin[0]] += v.share[0];
  counts[v.bin[1]] += v.share[1];
}

/// Writes the counts, normalised to sum to 1, into one region of the signature.
void store(const std::array<double, hal::kSignatureRegionBins>& counts, double total, SignatureRegion region,
           hal::AppearanceHistogram& out) {
  const std::size_t offset = hal::regionOffset(region);
  for (std::size_t i = 0; i < counts.size(); ++i) out[offset + i] = static_cast<float>(counts[i] / total);
}

/// Votes the pixels of a band along the bone a -> b: from `from` to `to` of its length, half_width px to
/// either side of it (nearest pixel; those outside the image skipped). Returns the pixels voted.
int voteAlongBone(const cv::Mat& bgr, const hal::Keypoint2D& a, const hal::Keypoint2D& b, double from, double to,
                  double half_width_px, std::array<double, hal::kSignatureRegionBins>& counts) {
  const double du = b.u_px - a.u_px, dv = b.v_px - a.v_px;
  const double length_px = std::hypot(du, dv);
  if (!(length_px > 1.0)) return 0;
  const double nu = -dv / length_px, nv = du / length_px;  // unit normal
  int voted = 0;
  const int along = static_cast<int>(std::ceil((to - from) * length_px));
  const int across = static_cast<int>(std::floor(half_width_px));
  for (int i = 0; i <= along; ++i) {
    const double t = from + (to - from) * i / std::max(along, 1);
    for (int j = -across; j <= across; ++j) {
      const int u = static_cast<int>(std::lround(a.u_px + t * du + j * nu));
      const int v = static_cast<int>(std::lround(a.v_px + t * dv + j * nv));
      if (u < 0 || v < 0 || u >= bgr.cols || v >= bgr.rows) continue;
      vote(bgr.at<cv::Vec3b>(v, u), counts);
      ++voted;
    }
  }
  return voted;
}

}  // namespace

Appearance personAppearance(const cv::Mat& bgr, const std::array<hal::Keypoint2D, hal::kNumKeypoints>& keypoints,
                            int min_pixels) {
  Appearance out;
  if (bgr.empty() || bgr.type() != CV_8UC3) return out;
  const hal::Keypoint2D& ls = keypoints[index(CocoKeypoint::kLeftShoulder)];
  const hal::Keypoint2D& rs = keypoints[index(CocoKeypoint::kRightShoulder)];
  const hal::Keypoint2D& lh = keypoints[index(CocoKeypoint::kLeftHip)];
  const hal::Keypoint2D& rh = keypoints[index(CocoKeypoint::kRightHip)];
  for (const hal::Keypoint2D* p : {&ls, &rs, &lh, &rh})
    if (!std::isfinite(p->u_px) || !std::isfinite(p->v_px)) return out;

  // Torso: the central part of the joints' box (joints sit on the body's outline, so its edges hold
  // background).
  const double u_min = std::min({ls.u_px, rs.u_px, lh.u_px, rh.u_px});
  const double u_max = std::max({ls.u_px, rs.u_px, lh.u_px, rh.u_px});
  const double v_min = std::min({ls.v_px, rs.v_px, lh.v_px, rh.v_px});
  const double v_max = std::max({ls.v_px, rs.v_px, lh.v_px, rh.v_px});
  const double du = 0.2 * (u_max - u_min);
  const double dv = 0.15 * (v_max - v_min);
  const PixelBox torso = clipped(u_min + du, u_max - du, v_min + dv, v_max - dv, bgr);
  if (torso.pixels() >= min_pixels) {
    std::array<double, hal::kSignatureRegionBins> counts{};
    for (int v = torso.v0; v < torso.v1; ++v) {
      const auto* row = bgr.ptr<cv::Vec3b>(v);
      for (int u = torso.u0; u < torso.u1; ++u) vote(row[u], counts);
    }
    store(counts, static_cast<double>(torso.pixels()), SignatureRegion::kTorso, out.histogram);
    out.valid = true;
  }

  // Legs: a band along each thigh, hip to knee. A box between the hips and the knees would hold the
  // background between the legs of a walker in stride (measured in image mode: the same person's legs at
  // distance 0.3-0.6 from their own reference, where the torso's stayed under 0.03).
  const hal::Keypoint2D& lk = keypoints[index(CocoKeypoint::kLeftKnee)];
  const hal::Keypoint2D& rk = keypoints[index(CocoKeypoint::kRightKnee)];
  const bool knees_seen = lk.score >= hal::kLegsMinKeypointScore && rk.score >= hal::kLegsMinKeypointScore &&
                          std::isfinite(lk.u_px) && std::isfinite(lk.v_px) && std::isfinite(rk.u_px) &&
                          std::isfinite(rk.v_px);
  if (knees_seen) {
    // The thigh is about a third as wide as it is long; its central half, away from the outline.
    constexpr double kHalfWidthOfLength = 0.08;
    std::array<double, hal::kSignatureRegionBins> counts{};
    int voted = 0;
    for (const auto& [hip, knee] : {std::pair{&lh, &lk}, std::pair{&rh, &rk}}) {
      const double length_px = std::hypot(knee->u_px - hip->u_px, knee->v_px - hip->v_px);
      voted += voteAlongBone(bgr, *hip, *knee, 0.15, 0.75, kHalfWidthOfLength * length_px, counts);
    }
    if (voted >= min_pixels) {
      store(counts, static_cast<double>(voted), SignatureRegion::kLegs, out.histogram);
      out.valid = true;
    }
  }
  return out;
}

double appearanceDistance(const Appearance& a, const Appearance& b) {
  if (!a.valid || !b.valid) return 1.0;
  return hal::signatureDistance(a.histogram, b.histogram);
}

void blendAppearance(Appearance& a, const Appearance& b, double rate) {
  if (!b.valid) return;
  if (!a.valid) a.histogram.fill(0.0F);
  for (std::size_t r = 0; r < hal::kSignatureRegions; ++r) {
    const auto region = static_cast<SignatureRegion>(r);
    if (!(hal::regionSum(b.histogram, region) > 0.0)) continue;
    const bool a_has = a.valid && hal::regionSum(a.histogram, region) > 0.0;
    const std::size_t offset = hal::regionOffset(region);
    for (std::size_t i = offset; i < offset + hal::kSignatureRegionBins; ++i) {
      a.histogram[i] = a_has ? static_cast<float>((1.0 - rate) * static_cast<double>(a.histogram[i]) +
                                                  rate * static_cast<double>(b.histogram[i]))
                             : b.histogram[i];
    }
  }
  a.valid = true;
}

}  // namespace aerotrack::perception
