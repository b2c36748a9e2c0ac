// Unit tests of MoveNet's multipose decoding: hand-made heads with a worked-out answer, and random
// heads against a literal transcription of the graph's tail (every instance x joint x cell, as the
// graph computes it, without the decoder's box-only scan).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "aerotrack/perception/movenet_decode.hpp"

namespace aerotrack::perception {
namespace {

constexpr int kGrid = 64;
constexpr int kJoints = 17;

struct Heads {
  std::vector<float> heatmap = std::vector<float>(kJoints * kGrid * kGrid, 0.0F);
  std::vector<float> center = std::vector<float>(kGrid * kGrid, 0.0F);
  std::vector<float> regress = std::vector<float>(2 * kJoints * kGrid * kGrid, 0.0F);
  std::vector<float> offset = std::vector<float>(2 * kJoints * kGrid * kGrid, 0.0F);
  std::vector<float> box_scale = std::vector<float>(2 * kGrid * kGrid, 0.0F);
  std::vector<float> box_offset = std::vector<float>(2 * kGrid * kGrid, 0.0F);

  static std::size_t at(int c, int y, int x) { return (static_cast<std::size_t>(c) * kGrid + y) * kGrid + x; }
  MultiPoseHeads view() const {
    return {{heatmap.data(), kJoints, kGrid, kGrid},     {center.data(), 1, kGrid, kGrid},
            {regress.data(), 2 * kJoints, kGrid, kGrid}, {offset.data(), 2 * kJoints, kGrid, kGrid},
            {box_scale.data(), 2, kGrid, kGrid},         {box_offset.data(), 2, kGrid, kGrid}};
  }
};

DecodeConstants constants() {
  DecodeConstants c;
  c.coord_scale_y = c.coord_scale_x = 1.0F / kGrid;
  c.nms_kernel = 5;
  c.nms_tolerance = 1e-6F;
  c.sigma_scale = 0.3F;
  c.box_scale_min = 0.0F;
  c.box_half = 0.5F;
  c.keypoint_threshold = 0.127F;
  return c;
}

/// A person centred at cell (cy, cx), box h x w cells, every joint at (cy + dy_k, cx) with heat 0.8.
void addPerson(Heads& h, int cy, int cx, float centre, float box_h, float box_w) {
  h.center[Heads::at(0, cy, cx)] = centre;
  h.box_scale[Heads::at(0, cy, cx)] = box_h;
  h.box_scale[Heads::at(1, cy, cx)] = box_w;
  for (int k = 0; k < kJoints; ++k) {
    const int dy = k - 8;
    h.regress[Heads::at(2 * k, cy, cx)] = static_cast<float>(dy);
    h.heatmap[Heads::at(k, cy + dy, cx)] = 0.8F;
    h.offset[Heads::at(2 * k + 1, cy + dy, cx)] = 0.5F;
  }
}

TEST(DecodeMultiPose, GivenTwoPeople_WhenDecoded_ThenEachHasItsBoxJointsAndScore) {
  Heads h;
  addPerson(h, 20, 15, 0.9F, 20.0F, 8.0F);
  addPerson(h, 40, 50, 0.6F, 20.0F, 8.0F);
  h.center[Heads::at(0, 21, 16)] = 0.85F;  // a neighbour inside the 5 x 5 window: suppressed
  const MultiPoseResult r = decodeMultiPose(h.view(), constants());

  const MultiPoseInstance& a = r.instances[0];
  EXPECT_FLOAT_EQ(a.box_ymin, 10.0F / kGrid);
  EXPECT_FLOAT_EQ(a.box_ymax, 30.0F / kGrid);
  EXPECT_FLOAT_EQ(a.box_xmin, 11.0F / kGrid);
  EXPECT_FLOAT_EQ(a.box_xmax, 19.0F / kGrid);
  for (int k = 0; k < kJoints; ++k) {
    EXPECT_FLOAT_EQ(a.keypoints[static_cast<std::size_t>(k)].y, static_cast<float>(20 + k - 8) / kGrid) << k;
    EXPECT_FLOAT_EQ(a.keypoints[static_cast<std::size_t>(k)].x, 15.5F / kGrid) << k;
    EXPECT_FLOAT_EQ(a.keypoints[static_cast<std::size_t>(k)].score, 0.8F) << k;  // on the joint: weight exp(0)
  }
  EXPECT_FLOAT_EQ(a.score, 0.9F * 0.8F);  // centre score x mean joint score

  const MultiPoseInstance& b = r.instances[1];
  EXPECT_FLOAT_EQ(b.keypoints[0].y, 32.0F / kGrid);
  EXPECT_FLOAT_EQ(b.keypoints[0].x, 50.5F / kGrid);
  EXPECT_FLOAT_EQ(b.score, 0.6F * 0.8F);
  // The suppressed neighbour is not an instance: the rest are empty cells with score 0.
  for (std::size_t n = 2; n < r.instances.size(); ++n) EXPECT_FLOAT_EQ(r.instances[n].score, 0.0F) << n;
}

TEST(DecodeMultiPose, GivenABoxReachingPastTheGrid_WhenDecoded_ThenItIsClippedToTheImage) {
  Heads h;
  addPerson(h, 10, 3, 0.9F, 30.0F, 10.0F);
  const MultiPoseResult r = decodeMultiPose(h.view(), constants());
  EXPECT_FLOAT_EQ(r.instances[0].box_ymin, 0.0F);
  EXPECT_FLOAT_EQ(r.instances[0].box_xmin, 0.0F);
  EXPECT_FLOAT_EQ(r.instances[0].box_ymax, 25.0F / kGrid);
  EXPECT_FLOAT_EQ(r.instances[0].box_xmax, 8.0F / kGrid);
}

/// The graph, literally: the full [H, W, 6, 17] tensor of weighted heatmaps.
MultiPoseResult referenceDecode(const Heads& h, const DecodeConstants& c) {
  std::vector<float> masked(kGrid * kGrid);
  for (int y = 0; y < kGrid; ++y)
    for (int x = 0; x < kGrid; ++x) {
      float m = -INFINITY;
      for (int yy = y - 2; yy <= y + 2; ++yy)
        for (int xx = x - 2; xx <= x + 2; ++xx)
          if (yy >= 0 && yy < kGrid && xx >= 0 && xx < kGrid) m = std::max(m, h.center[Heads::at(0, yy, xx)]);
      const float v = h.center[Heads::at(0, y, x)];
      masked[static_cast<std::size_t>(y * kGrid + x)] = v * (std::abs(v - m) < c.nms_tolerance ? 1.0F : 0.0F);
    }
  std::vector<int> order(masked.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return masked[static_cast<std::size_t>(a)] > masked[static_cast<std::size_t>(b)];
  });
  const int n_inst = 6;
  std::vector<float> w9(static_cast<std::size_t>(kGrid * kGrid * n_inst * kJoints));
  std::array<std::array<float, 4>, 6> boxes{};
  for (int n = 0; n < n_inst; ++n) {
    const int cy = order[static_cast<std::size_t>(n)] / kGrid, cx = order[static_cast<std::size_t>(n)] % kGrid;
    const float sy = std::max(h.box_scale[Heads::at(0, cy, cx)], 0.0F) * 0.5F;
    const float sx = std::max(h.box_scale[Heads::at(1, cy, cx)], 0.0F) * 0.5F;
    const float oy = static_cast<float>(cy) + h.box_offset[Heads::at(0, cy, cx)];
    const float ox = static_cast<float>(cx) + h.box_offset[Heads::at(1, cy, cx)];
    const auto clip = [](float v) { return std::max(std::min(v, static_cast<float>(kGrid)), 0.0F); };
    boxes[static_cast<std::size_t>(n)] = {clip(oy - sy), clip(ox - sx), clip(oy + sy), clip(ox + sx)};
    for (int k = 0; k < kJoints; ++k) {
      const float ky = static_cast<float>(cy) + h.regress[Heads::at(2 * k, cy, cx)];
      const float kx = static_cast<float>(cx) + h.regress[Heads::at(2 * k + 1, cy, cx)];
      for (int y = 0; y < kGrid; ++y)
        for (int x = 0; x < kGrid; ++x) {
          const float d2 = (static_cast<float>(y) - ky) * (static_cast<float>(y) - ky) +
                           (static_cast<float>(x) - kx) * (static_cast<float>(x) - kx);
          const auto e = static_cast<float>(std::exp(static_cast<double>((-1.0F * d2) / (kGrid * c.sigma_scale))));
          const auto& bx = boxes[static_cast<std::size_t>(n)];
          const float inside = (static_cast<float>(y) >= bx[0] && static_cast<float>(y) < bx[2] &&
                                static_cast<float>(x) >= bx[1] && static_cast<float>(x) < bx[3])
                                   ? 1.0F
                                   : 0.0F;
          w9[static_cast<std::size_t>(((y * kGrid + x) * n_inst + n) * kJoints + k)] =
              h.heatmap[Heads::at(k, y, x)] * e * inside;
        }
    }
  }
  MultiPoseResult r;
  for (int n = 0; n < n_inst; ++n) {
    float sum = 0.0F, count = 0.0F;
    for (int k = 0; k < kJoints; ++k) {
      int arg = 0;
      for (int i = 1; i < kGrid * kGrid; ++i)
        if (w9[static_cast<std::size_t>((i * n_inst + n) * kJoints + k)] >
            w9[static_cast<std::size_t>((arg * n_inst + n) * kJoints + k)])
          arg = i;
      float score = 0.0F;
      for (int m = 0; m < n_inst; ++m)
        score = std::max(score, w9[static_cast<std::size_t>((arg * n_inst + m) * kJoints + k)]);
      const int y = arg / kGrid, x = arg % kGrid;
      r.instances[static_cast<std::size_t>(n)].keypoints[static_cast<std::size_t>(k)] = {
          (static_cast<float>(y) + h.offset[Heads::at(2 * k, y, x)]) * c.coord_scale_y,
          (static_cast<float>(x) + h.offset[Heads::at(2 * k + 1, y, x)]) * c.coord_scale_x, score};
      if (score > c.keypoint_threshold) {
        sum += masked[static_cast<std::size_t>(order[static_cast<std::size_t>(n)])] * score;
        count += 1.0F;
      }
    }
    r.instances[static_cast<std::size_t>(n)].score = (1.0F / std::max(count, 1.0F)) * sum;
  }
  return r;
}

TEST(DecodeMultiPose, GivenRandomHeads_WhenDecoded_ThenItMatchesTheLiteralGraph) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0F, 1.0F), cells(-6.0F, 6.0F), sub(-1.0F, 1.0F), size(2.0F, 30.0F);
  for (int trial = 0; trial < 3; ++trial) {
    Heads h;
    for (float& v : h.heatmap) v = unit(rng) * unit(rng);
    for (float& v : h.center) v = unit(rng);
    for (float& v : h.regress) v = cells(rng);
    for (float& v : h.offset) v = sub(rng);
    for (float& v : h.box_scale) v = size(rng);
    for (float& v : h.box_offset) v = sub(rng);
    const MultiPoseResult got = decodeMultiPose(h.view(), constants());
    const MultiPoseResult want = referenceDecode(h, constants());
    for (std::size_t n = 0; n < got.instances.size(); ++n) {
      EXPECT_EQ(got.instances[n].score, want.instances[n].score) << n;
      for (std::size_t k = 0; k < hal::kNumKeypoints; ++k) {
        EXPECT_EQ(got.instances[n].keypoints[k].y, want.instances[n].keypoints[k].y) << n << " " << k;
        EXPECT_EQ(got.instances[n].keypoints[k].x, want.instances[n].keypoints[k].x) << n << " " << k;
        EXPECT_EQ(got.instances[n].keypoints[k].score, want.instances[n].keypoints[k].score) << n << " " << k;
      }
    }
  }
}

}  // namespace
}  // namespace aerotrack::perception
