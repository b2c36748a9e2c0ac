// The appearance cue for lock-on and association (issue 5 item 3; issue 22 item 2): the person's
// appearance signature measured from the image (hal/appearance_signature.hpp: colour histograms of
// the torso and the legs, achromatic pixels split by brightness), compared with the Bhattacharyya
// distance. Clothing colour is what tells the followed person from a bystander of similar size at a
// similar place; it is cheap and survives the pose changes and turns that defeat a template.
#pragma once

#include <array>

#include <opencv2/core/mat.hpp>

#include "aerotrack/hal/types.hpp"

namespace aerotrack::perception {

inline constexpr std::size_t kAppearanceBins = hal::kAppearanceSignatureBins;

struct Appearance {
  /// hal's layout: each region sums to 1 when measured, zeros when not.
  hal::AppearanceHistogram histogram{};
  bool valid = false;  ///< At least one region measured.
};

/// The person's signature in an 8-bit BGR image: the torso region from the box of the shoulders and
/// hips, the legs region from the hips down to the knees (only when both knees score at least
/// hal::kLegsMinKeypointScore), each box shrunk to its central part to avoid background and clipped
/// to the image. A region with fewer than min_pixels pixels is not measured; invalid if neither is.
/// Allocation-free; pure.
Appearance personAppearance(const cv::Mat& bgr, const std::array<hal::Keypoint2D, hal::kNumKeypoints>& keypoints,
                            int min_pixels = 20);

/// hal::signatureDistance of two valid appearances (over the regions both measured); 1 if either is
/// invalid.
double appearanceDistance(const Appearance& a, const Appearance& b);

/// a <- (1 - rate) a + rate b region by region, over the regions b measured; a region that a had not
/// measured is taken from b as it is.
void blendAppearance(Appearance& a, const Appearance& b, double rate);

}  // namespace aerotrack::perception
