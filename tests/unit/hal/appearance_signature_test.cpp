// Unit tests of the appearance signature's layout and distance (hal/appearance_signature.hpp): votes
// are continuous across hue and brightness, achromatic colours split by brightness, and the distance
// counts only the regions both signatures measured.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "aerotrack/hal/appearance_signature.hpp"

namespace aerotrack::hal {
namespace {

AppearanceHistogram oneColour(SignatureRegion region, double hue_deg, double saturation, double value) {
  AppearanceHistogram h{};
  addColour(h, region, hue_deg, saturation, value, 1.0);
  return h;
}

TEST(AppearanceSignature, GivenAHueSweep_WhenVoted_ThenTheSignatureChangesContinuouslyAcrossEveryBinEdge) {
  // Pure red sits on the 0/360 degree seam: a step of 0.2 degrees anywhere must move the signature little
  // (a flip between bins would be distance 1; a share eps moved off a bin centre is sqrt(eps / 2) = 0.06).
  for (double hue = -30.0; hue < 390.0; hue += 0.2) {
    const double d = signatureDistance(oneColour(SignatureRegion::kTorso, hue, 0.8, 1.0),
                                       oneColour(SignatureRegion::kTorso, hue + 0.2, 0.8, 1.0));
    EXPECT_LT(d, 0.1) << hue;
  }
  EXPECT_LT(signatureDistance(oneColour(SignatureRegion::kTorso, 359.9, 0.8, 1.0),
                              oneColour(SignatureRegion::kTorso, 0.1, 0.8, 1.0)),
            0.1);
}

TEST(AppearanceSignature, GivenAchromaticColours_WhenVoted_ThenBrightnessSeparatesThemAndVotesBlendBetweenBins) {
  const AppearanceHistogram black = oneColour(SignatureRegion::kTorso, 0.0, 0.0, 0.05);
  const AppearanceHistogram grey = oneColour(SignatureRegion::kTorso, 0.0, 0.0, 0.5);
  const AppearanceHistogram white = oneColour(SignatureRegion::kTorso, 0.0, 0.0, 0.95);
  EXPECT_GT(signatureDistance(black, white), 0.99);
  EXPECT_GT(signatureDistance(black, grey), 0.9);
  for (double v = 0.0; v < 1.0; v += 0.01)
    EXPECT_LT(signatureDistance(oneColour(SignatureRegion::kTorso, 0.0, 0.0, v),
                                oneColour(SignatureRegion::kTorso, 0.0, 0.0, v + 0.01)),
              0.2)
        << v;
  // Too dark for a hue, whatever the saturation says; a weak chroma is grey.
  EXPECT_LT(signatureDistance(oneColour(SignatureRegion::kTorso, 120.0, 1.0, 0.1), black), 0.3);
  EXPECT_LT(signatureDistance(oneColour(SignatureRegion::kTorso, 120.0, 0.05, 0.5), grey), 1e-9);
  const ColourVote v = colourVote(0.0, 0.0, 0.5);
  EXPECT_NEAR(v.share[0] + v.share[1], 1.0, 1e-12);
}

TEST(AppearanceSignature, GivenRegionsMeasuredInOneOnly_WhenCompared_ThenOnlyTheCommonRegionsCount) {
  AppearanceHistogram red_shirt_blue_jeans = oneColour(SignatureRegion::kTorso, 0.0, 0.8, 1.0);
  addColour(red_shirt_blue_jeans, SignatureRegion::kLegs, 220.0, 0.6, 1.0, 1.0);
  AppearanceHistogram red_shirt_khaki = oneColour(SignatureRegion::kTorso, 0.0, 0.8, 1.0);
  addColour(red_shirt_khaki, SignatureRegion::kLegs, 40.0, 0.4, 1.0, 1.0);
  const AppearanceHistogram red_shirt_only = oneColour(SignatureRegion::kTorso, 0.0, 0.8, 1.0);
  EXPECT_NEAR(signatureDistance(red_shirt_blue_jeans, red_shirt_only), 0.0, 1e-6);
  // Torso the same (BC 1), legs disjoint (BC 0): the mean coefficient is 1/2.
  EXPECT_NEAR(signatureDistance(red_shirt_blue_jeans, red_shirt_khaki), std::sqrt(0.5), 1e-6);
  const AppearanceHistogram legs_only = oneColour(SignatureRegion::kLegs, 220.0, 0.6, 1.0);
  EXPECT_DOUBLE_EQ(signatureDistance(red_shirt_only, legs_only), 1.0);  // nothing in common
  EXPECT_DOUBLE_EQ(signatureDistance(AppearanceHistogram{}, AppearanceHistogram{}), 1.0);
}

TEST(AppearanceSignature, GivenAnUnnormalisedOrCorruptSignature_WhenCompared_ThenRegionsAreScaledAndCorruptIsFar) {
  AppearanceHistogram a = oneColour(SignatureRegion::kTorso, 90.0, 0.5, 1.0);
  AppearanceHistogram doubled = a;
  for (float& x : doubled) x *= 2.0F;
  EXPECT_NEAR(signatureDistance(a, doubled), 0.0, 1e-6);
  doubled[3] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_DOUBLE_EQ(signatureDistance(a, doubled), 1.0);
  doubled[3] = -1.0F;
  EXPECT_DOUBLE_EQ(signatureDistance(a, doubled), 1.0);
}

}  // namespace
}  // namespace aerotrack::hal
