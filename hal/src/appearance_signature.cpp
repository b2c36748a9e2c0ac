// A person's appearance signature: see appearance_signature.hpp.
#include "aerotrack/hal/appearance_signature.hpp"

#include <algorithm>
#include <cmath>

namespace aerotrack::hal {

namespace {

/// Linear vote of x between the centres (i + 0.5) / n of n bins; clamped at the outer centres.
/// Circular: the last bin's right neighbour is the first (hue).
struct LinearVote {
  int lower = 0, upper = 0;
  double upper_share = 0.0;
};

LinearVote circularVote(double position, int bins) {
  // Bin i is centred on position i (hue bin i on i x 360 / bins degrees).
  const double floor = std::floor(position);
  LinearVote v;
  v.lower = ((static_cast<int>(floor) % bins) + bins) % bins;
  v.upper = (v.lower + 1) % bins;
  v.upper_share = position - floor;
  return v;
}

LinearVote clampedVote(double fraction, int bins) {
  const double position = std::clamp(fraction * bins - 0.5, 0.0, static_cast<double>(bins - 1));
  LinearVote v;
  v.lower = std::min(bins - 2, static_cast<int>(std::floor(position)));
  v.upper = v.lower + 1;
  v.upper_share = position - v.lower;
  return v;
}

}  // namespace

ColourVote colourVote(double hue_deg, double saturation, double value) {
  ColourVote out;
  // The tolerance absorbs rounding only (an 8-bit channel step is 1/255 = 4e-3): chroma = saturation x value
  // computed in float or double must decide alike for a pixel exactly on the threshold.
  constexpr double kRounding = 1e-6;  // also for the saturation bins' edges (85 / 255 is exactly 1/3)
  if (!(value >= kAchromaticMaxValue - kRounding) || !(saturation * value >= kAchromaticMaxChroma - kRounding)) {
    constexpr std::size_t kGreyFirst =
        static_cast<std::size_t>(kSignatureHueBins) * static_cast<std::size_t>(kSignatureSaturationBins);
    const LinearVote v = clampedVote(std::isfinite(value) ? value : 0.0, kSignatureValueBins);
    out.bin = {kGreyFirst + static_cast<std::size_t>(v.lower), kGreyFirst + static_cast<std::size_t>(v.upper)};
    out.share = {1.0 - v.upper_share, v.upper_share};
    return out;
  }
  const int sat_bin =
      std::clamp(static_cast<int>(saturation * kSignatureSaturationBins + kRounding), 0, kSignatureSaturationBins - 1);
  const double turns = hue_deg / 360.0;
  const LinearVote h = circularVote((turns - std::floor(turns)) * kSignatureHueBins, kSignatureHueBins);
  const auto bin = [&](int hue_bin) {
    return static_cast<std::size_t>(hue_bin) * static_cast<std::size_t>(kSignatureSaturationBins) +
           static_cast<std::size_t>(sat_bin);
  };
  out.bin = {bin(h.lower), bin(h.upper)};
  out.share = {1.0 - h.upper_share, h.upper_share};
  return out;
}

void addColour(AppearanceHistogram& signature, SignatureRegion region, double hue_deg, double saturation, double value,
               double weight) {
  const ColourVote v = colourVote(hue_deg, saturation, value);
  const std::size_t offset = regionOffset(region);
  for (std::size_t i = 0; i < 2; ++i) signature[offset + v.bin[i]] += static_cast<float>(weight * v.share[i]);
}

double regionSum(const AppearanceHistogram& signature, SignatureRegion region) {
  const std::size_t offset = regionOffset(region);
  double sum = 0.0;
  for (std::size_t i = 0; i < kSignatureRegionBins; ++i) sum += static_cast<double>(signature[offset + i]);
  return sum;
}

double signatureDistance(const AppearanceHistogram& a, const AppearanceHistogram& b) {
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!(a[i] >= 0.0F) || !(b[i] >= 0.0F) || !std::isfinite(a[i]) || !std::isfinite(b[i])) return 1.0;
  }
  double coefficient_sum = 0.0;
  int regions = 0;
  for (std::size_t r = 0; r < kSignatureRegions; ++r) {
    const auto region = static_cast<SignatureRegion>(r);
    const double sum_a = regionSum(a, region);
    const double sum_b = regionSum(b, region);
    if (!(sum_a > 0.0) || !(sum_b > 0.0)) continue;
    const std::size_t offset = regionOffset(region);
    double bc = 0.0;
    for (std::size_t i = 0; i < kSignatureRegionBins; ++i)
      bc += std::sqrt(static_cast<double>(a[offset + i]) * static_cast<double>(b[offset + i]));
    coefficient_sum += bc / std::sqrt(sum_a * sum_b);
    ++regions;
  }
  if (regions == 0) return 1.0;
  return std::sqrt(std::max(0.0, 1.0 - coefficient_sum / regions));
}

}  // namespace aerotrack::hal
