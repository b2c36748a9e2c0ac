// A person's appearance signature (issue 22 item 2): what tells the followed person from a bystander
// of the same size at the same place. Two regions, each a colour histogram that sums to 1 when
// measured and is all zeros when not:
//   - the torso: the box spanned by the shoulders and hips (the shirt or jacket), seen from the
//     front and the back alike, so it survives a turn;
//   - the legs: the box from the hips to the knees (trousers, a skirt), measured only when both
//     knees are seen.
// Each region: 12 hue x 3 saturation bins for coloured pixels and 4 brightness bins for the
// achromatic ones (black, dark grey, light grey, white). Measured on the simulator's six real
// people (tests/tools/cast_appearance.cpp), the first version's one grey bin held five of them at
// distance 0.00 -- dark and grey clothes are most clothes -- so achromatic pixels are split by
// brightness, and the legs add a second garment.
//
// The layout is shared by the image pipeline (perception/appearance.hpp measures it from pixels),
// the simulator's keypoint camera (which reports each person's true signature with noise) and the
// recorded detections.csv; this header is its one definition. Pure.
#pragma once

#include <array>
#include <cstddef>

namespace aerotrack::hal {

inline constexpr int kSignatureHueBins = 12;
inline constexpr int kSignatureSaturationBins = 3;
inline constexpr int kSignatureValueBins = 4;  ///< Achromatic pixels by brightness.
inline constexpr std::size_t kSignatureRegionBins =
    static_cast<std::size_t>(kSignatureHueBins) * static_cast<std::size_t>(kSignatureSaturationBins) +
    static_cast<std::size_t>(kSignatureValueBins);

enum class SignatureRegion : std::size_t { kTorso = 0, kLegs = 1 };
inline constexpr std::size_t kSignatureRegions = 2;
inline constexpr std::size_t kAppearanceSignatureBins = kSignatureRegions * kSignatureRegionBins;

using AppearanceHistogram = std::array<float, kAppearanceSignatureBins>;

/// A pixel or cloth colour is achromatic (its hue is noise) below this brightness (the largest channel
/// in [0, 1]) or this chroma (largest minus smallest channel).
inline constexpr double kAchromaticMaxValue = 40.0 / 255.0;
inline constexpr double kAchromaticMaxChroma = 25.0 / 255.0;
/// A knee must score at least this for the legs region to be measured.
inline constexpr double kLegsMinKeypointScore = 0.3;

/// Where one colour votes inside a region: its two nearest bins and their shares (summing to 1).
/// Hue votes between its two nearest hue bins and brightness between its two nearest brightness
/// bins, in proportion to closeness, so that a colour on a bin boundary (pure red at 0/360 degrees)
/// does not flip between bins with pixel noise.
struct ColourVote {
  std::array<std::size_t, 2> bin{};  ///< Indices within a region, [0, kSignatureRegionBins).
  std::array<double, 2> share{};
};

/// The vote of a colour given as HSV (hexcone: value = the largest channel, saturation = chroma /
/// value; all in [0, 1], hue in degrees, any turn).
ColourVote colourVote(double hue_deg, double saturation, double value);

/// The first bin of a region in a signature.
constexpr std::size_t regionOffset(SignatureRegion region) {
  return static_cast<std::size_t>(region) * kSignatureRegionBins;
}

/// Adds weight x the colour's vote to a region of a signature.
void addColour(AppearanceHistogram& signature, SignatureRegion region, double hue_deg, double saturation, double value,
               double weight);

/// The sum of a region's bins (1 when measured and normalised, 0 when not measured).
double regionSum(const AppearanceHistogram& signature, SignatureRegion region);

/// Bhattacharyya distance sqrt(1 - BC) in [0, 1], where BC is the Bhattacharyya coefficient averaged
/// over the regions measured in both (each region normalised by its own sum). 1 when no region is
/// measured in both, or a bin is negative or not finite.
double signatureDistance(const AppearanceHistogram& a, const AppearanceHistogram& b);

}  // namespace aerotrack::hal
