// Unit tests of MoveNet's singlepose decoding on hand-made head tensors: the answer of each case is
// worked out by hand from how the heads are built, and a slow, obvious reference (the graph's
// operations written literally over std::vector) checks random heads.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "aerotrack/perception/movenet_decode.hpp"

namespace aerotrack::perception {
namespace {

constexpr int kGrid = 48;
constexpr int kJoints = 17;

/// Owns head tensors of one singlepose output and hands out views.
struct Heads {
  std::vector<float> heatmap = std::vector<float>(kJoints * kGrid * kGrid, 0.0F);
  std::vector<float> center = std::vector<float>(kGrid * kGrid, 0.0F);
  std::vector<float> regress = std::vector<float>(2 * kJoints * kGrid * kGrid, 0.0F);
  std::vector<float> offset = std::vector<float>(2 * kJoints * kGrid * kGrid, 0.0F);

  static std::size_t at(int c, int y, int x) { return (static_cast<std::size_t>(c) * kGrid + y) * kGrid + x; }
  SinglePoseHeads view() const {
    return {{heatmap.data(), kJoints, kGrid, kGrid},
            {center.data(), 1, kGrid, kGrid},
            {regress.data(), 2 * kJoints, kGrid, kGrid},
            {offset.data(), 2 * kJoints, kGrid, kGrid}};
  }
};

DecodeConstants constants() {
  DecodeConstants c;
  c.coord_scale_y = 1.0F / kGrid;
  c.coord_scale_x = 1.0F / kGrid;
  c.distance_bias = 1.8F;
  return c;
}

TEST(DecodeSinglePose, GivenHeadsBuiltAroundOnePerson_WhenDecoded_ThenJointsAreAtTheirCellsPlusOffsets) {
  Heads h;
  h.center[Heads::at(0, 20, 30)] = 0.9F;
  for (int k = 0; k < kJoints; ++k) {
    // Joint k sits at cell (10 + k, 25) and the regression from the centre points there.
    const int y = 10 + k, x = 25;
    h.regress[Heads::at(2 * k, 20, 30)] = static_cast<float>(y - 20);
    h.regress[Heads::at(2 * k + 1, 20, 30)] = static_cast<float>(x - 30);
    h.heatmap[Heads::at(k, y, x)] = 0.5F + 0.01F * static_cast<float>(k);
    h.offset[Heads::at(2 * k, y, x)] = 0.25F;
    h.offset[Heads::at(2 * k + 1, y, x)] = -0.5F;
  }
  const NormalisedPose pose = decodeSinglePose(h.view(), constants());
  for (int k = 0; k < kJoints; ++k) {
    const NormalisedKeypoint& p = pose[static_cast<std::size_t>(k)];
    EXPECT_FLOAT_EQ(p.y, (10.0F + static_cast<float>(k) + 0.25F) / kGrid) << k;
    EXPECT_FLOAT_EQ(p.x, (25.0F - 0.5F) / kGrid) << k;
    EXPECT_FLOAT_EQ(p.score, 0.5F + 0.01F * static_cast<float>(k)) << k;
  }
}

TEST(DecodeSinglePose, GivenAStrongerPeakFarFromTheRegressedJoint_WhenDecoded_ThenTheNearPeakWins) {
  // The distance weighting is what ties a joint to its own person: a bystander's brighter wrist
  // 20 cells away loses to the person's own weaker wrist next to where the regression points.
  Heads h;
  h.center[Heads::at(0, 24, 24)] = 1.0F;
  const int wrist = 9;
  h.regress[Heads::at(2 * wrist, 24, 24)] = 5.0F;  // regressed to (29, 24)
  h.heatmap[Heads::at(wrist, 30, 24)] = 0.4F;      // distance 1:  0.4 / 2.8 = 0.143
  h.heatmap[Heads::at(wrist, 5, 5)] = 0.95F;       // distance 31: 0.95 / 32.8 = 0.029
  const NormalisedPose pose = decodeSinglePose(h.view(), constants());
  EXPECT_FLOAT_EQ(pose[wrist].y, 30.0F / kGrid);
  EXPECT_FLOAT_EQ(pose[wrist].x, 24.0F / kGrid);
  EXPECT_FLOAT_EQ(pose[wrist].score, 0.4F);
}

TEST(DecodeSinglePose, GivenTiedCentreCells_WhenDecoded_ThenTheFirstInRowMajorOrderIsTheCentre) {
  Heads h;
  h.center[Heads::at(0, 7, 40)] = 0.5F;
  h.center[Heads::at(0, 30, 3)] = 0.5F;
  h.regress[Heads::at(0, 7, 40)] = 1.0F;  // from the first centre, joint 0 lies one cell below
  h.heatmap[Heads::at(0, 8, 40)] = 0.7F;
  h.heatmap[Heads::at(0, 31, 3)] = 0.7F;
  const NormalisedPose pose = decodeSinglePose(h.view(), constants());
  EXPECT_FLOAT_EQ(pose[0].y, 8.0F / kGrid);
  EXPECT_FLOAT_EQ(pose[0].x, 40.0F / kGrid);
}

/// The graph's operations, written out literally.
NormalisedPose referenceDecode(const Heads& h, const DecodeConstants& c) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < h.center.size(); ++i)
    if (h.center[i] > h.center[best]) best = i;
  const int cy = static_cast<int>(best) / kGrid, cx = static_cast<int>(best) % kGrid;
  NormalisedPose pose{};
  for (int k = 0; k < kJoints; ++k) {
    const float ry = static_cast<float>(cy) + h.regress[Heads::at(2 * k, cy, cx)];
    const float rx = static_cast<float>(cx) + h.regress[Heads::at(2 * k + 1, cy, cx)];
    std::vector<float> weighted(kGrid * kGrid);
    for (int y = 0; y < kGrid; ++y)
      for (int x = 0; x < kGrid; ++x) {
        const float sy = (static_cast<float>(y) - ry) * (static_cast<float>(y) - ry);
        const float sx = (static_cast<float>(x) - rx) * (static_cast<float>(x) - rx);
        weighted[static_cast<std::size_t>(y * kGrid + x)] =
            h.heatmap[Heads::at(k, y, x)] / (std::sqrt(sy + sx) + c.distance_bias);
      }
    std::size_t arg = 0;
    for (std::size_t i = 1; i < weighted.size(); ++i)
      if (weighted[i] > weighted[arg]) arg = i;
    const int y = static_cast<int>(arg) / kGrid, x = static_cast<int>(arg) % kGrid;
    pose[static_cast<std::size_t>(k)] = {
        (static_cast<float>(y) + h.offset[Heads::at(2 * k, y, x)]) * c.coord_scale_y,
        (static_cast<float>(x) + h.offset[Heads::at(2 * k + 1, y, x)]) * c.coord_scale_x,
        h.heatmap[Heads::at(k, y, x)]};
  }
  return pose;
}

TEST(DecodeSinglePose, GivenRandomHeads_WhenDecoded_ThenItMatchesTheLiteralReference) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0F, 1.0F), signed_cells(-10.0F, 10.0F), sub(-1.0F, 1.0F);
  for (int trial = 0; trial < 20; ++trial) {
    Heads h;
    for (float& v : h.heatmap) v = unit(rng);
    for (float& v : h.center) v = unit(rng);
    for (float& v : h.regress) v = signed_cells(rng);
    for (float& v : h.offset) v = sub(rng);
    const NormalisedPose got = decodeSinglePose(h.view(), constants());
    const NormalisedPose want = referenceDecode(h, constants());
    for (std::size_t k = 0; k < got.size(); ++k) {
      EXPECT_EQ(got[k].y, want[k].y);
      EXPECT_EQ(got[k].x, want[k].x);
      EXPECT_EQ(got[k].score, want[k].score);
    }
  }
}

TEST(DecodeSinglePose, GivenHeadsOfTheWrongShape_WhenChecked_ThenTheyAreRejected) {
  Heads h;
  SinglePoseHeads v = h.view();
  EXPECT_TRUE(shapesValid(v));
  v.regress.channels = 17;
  EXPECT_FALSE(shapesValid(v));
  v = h.view();
  v.center.width = 47;
  EXPECT_FALSE(shapesValid(v));
  v = h.view();
  v.offset.data = nullptr;
  EXPECT_FALSE(shapesValid(v));
}

}  // namespace
}  // namespace aerotrack::perception
