// A simple appearance cue for lock-on (issue 5, item 3): the hue-saturation histogram of the
// person's torso (the box spanned by the shoulders and hips), compared with the Bhattacharyya
// distance. Clothing colour is what tells the followed person from a bystander of similar size at
// a similar place; it is cheap and survives the pose changes that defeat a template. Dark and
// unsaturated pixels have no reliable hue and go into one shared "grey" bin.
#pragma once

#include <array>

#include <opencv2/core/mat.hpp>

#include "aerotrack/hal/types.hpp"

namespace aerotrack::perception {

inline constexpr int kHueBins = 12;
inline constexpr int kSaturationBins = 3;
inline constexpr int kAppearanceBins = kHueBins * kSaturationBins + 1;  ///< + the grey bin.

struct Appearance {
  std::array<float, kAppearanceBins> histogram{};  ///< Sums to 1 when valid.
  bool valid = false;
};

/// The torso histogram of a person in an 8-bit BGR image; invalid if the torso joints' box
/// (shrunk to its central part to avoid background) has fewer than min_pixels pixels inside the
/// image. Allocation-free; pure.
Appearance torsoAppearance(const cv::Mat& bgr, const std::array<hal::Keypoint2D, hal::kNumKeypoints>& keypoints,
                           int min_pixels = 20);

/// Bhattacharyya distance sqrt(1 - sum sqrt(a_i b_i)) in [0, 1]; 1 if either is invalid.
double appearanceDistance(const Appearance& a, const Appearance& b);

/// a <- (1 - rate) a + rate b (both valid); b if a is invalid.
void blendAppearance(Appearance& a, const Appearance& b, double rate);

}  // namespace aerotrack::perception
