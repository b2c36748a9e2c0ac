// Appearance from the image: see appearance.hpp.
#include "aerotrack/perception/appearance.hpp"

#include <algorithm>
#include <cmath>

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

/// Histograms the box into one region of the signature, normalised to sum to 1.
void measureRegion(const cv::Mat& bgr, const PixelBox& box, SignatureRegion region, hal::AppearanceHistogram& out) {
  // Counted in double (thousands of unit votes), then normalised into the float signature.
  std::array<double, hal::kSignatureRegionBins> counts{};
  for (int v = box.v0; v < box.v1; ++v) {
    const auto* row = bgr.ptr<cv::Vec3b>(v);
    for (int u = box.u0; u < box.u1; ++u) {
      const int b = row[u][0], g = row[u][1], r = row[u][2];
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
      const hal::ColourVote vote = hal::colourVote(hue_deg, saturation, max / 255.0);
      counts[vote.bin[0]] += vote.share[0];
      counts[vote.bin[1]] += vote.share[1];
    }
  }
  const double total = static_cast<double>(box.pixels());
  const std::size_t offset = hal::regionOffset(region);
  for (std::size_t i = 0; i < counts.size(); ++i) out[offset + i] = static_cast<float>(counts[i] / total);
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
    measureRegion(bgr, torso, SignatureRegion::kTorso, out.histogram);
    out.valid = true;
  }

  // Legs: the thighs, between the hips and the knees. Their box's lower half holds the gap between
  // the legs, so only its upper 60 % and the central 80 % of the hips' width are taken.
  const hal::Keypoint2D& lk = keypoints[index(CocoKeypoint::kLeftKnee)];
  const hal::Keypoint2D& rk = keypoints[index(CocoKeypoint::kRightKnee)];
  const bool knees_seen = lk.score >= hal::kLegsMinKeypointScore && rk.score >= hal::kLegsMinKeypointScore &&
                          std::isfinite(lk.v_px) && std::isfinite(rk.v_px);
  const double hip_v = 0.5 * (lh.v_px + rh.v_px);
  const double thigh_px = 0.5 * (lk.v_px + rk.v_px) - hip_v;
  if (knees_seen && thigh_px > 2.0) {
    const double hip_u_min = std::min(lh.u_px, rh.u_px);
    const double hip_u_max = std::max(lh.u_px, rh.u_px);
    const double margin = 0.1 * (hip_u_max - hip_u_min);
    const PixelBox legs =
        clipped(hip_u_min + margin, hip_u_max - margin, hip_v + 0.05 * thigh_px, hip_v + 0.6 * thigh_px, bgr);
    if (legs.pixels() >= min_pixels) {
      measureRegion(bgr, legs, SignatureRegion::kLegs, out.histogram);
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
