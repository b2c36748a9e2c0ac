// MoveNet multipose decoding: see movenet_decode.hpp and scripts/models/README.md ("multipose
// decode"). Mirrors the tail of the TensorFlow.js graph: MaxPool peak suppression on the centre
// map, TopK(6), box from box_scale/box_offset clipped to the grid, joints regressed from each
// centre and snapped to the maximum of heatmap x exp(-d^2 / (min(H, W) sigma)) inside the box,
// offsets, and the instance score. Every intermediate is rounded to float32 as TensorFlow.js
// stores it; transcendental functions are evaluated in double and rounded, as its CPU backend
// does with Math.exp. Cells outside an instance's box weigh exactly zero in the graph, so only
// the box is scanned, in the same row-major order (ties resolve as in tf.argMax).
#include <algorithm>
#include <cmath>

#include "aerotrack/perception/movenet_decode.hpp"

namespace aerotrack::perception {

namespace {

constexpr int kJoints = static_cast<int>(hal::kNumKeypoints);

/// Where joint k's y and x sit in a per-instance array of 2 x 17 values.
std::size_t yIndex(int k) {
  return 2 * static_cast<std::size_t>(k);
}
std::size_t xIndex(int k) {
  return 2 * static_cast<std::size_t>(k) + 1;
}

struct Box {
  float ymin, xmin, ymax, xmax;  ///< Grid cells, clipped to [0, H] and [0, W].
  bool contains(int y, int x) const {
    const auto fy = static_cast<float>(y), fx = static_cast<float>(x);
    return fy >= ymin && fy < ymax && fx >= xmin && fx < xmax;
  }
};

float clip(float v, float hi) {
  return std::max(std::min(v, hi), 0.0F);
}

/// The graph's joint weight for one cell, instance and joint (zero outside the box).
float weighted(const MultiPoseHeads& heads, const Box& box, float joint_y, float joint_x, float sigma_cells2, int k,
               int y, int x) {
  if (!box.contains(y, x)) return 0.0F;
  const float dy = static_cast<float>(y) - joint_y;
  const float dx = static_cast<float>(x) - joint_x;
  const float d2 = dy * dy + dx * dx;
  const float exponent = (-1.0F * d2) / sigma_cells2;
  const auto weight = static_cast<float>(std::exp(static_cast<double>(exponent)));
  return heads.heatmap.at(k, y, x) * weight;
}

}  // namespace

bool shapesValid(const MultiPoseHeads& heads) {
  const auto& h = heads;
  return h.heatmap.channels == kJoints && h.center.channels == 1 && h.regress.channels == 2 * kJoints &&
         h.offset.channels == 2 * kJoints && h.box_scale.channels == 2 && h.box_offset.channels == 2 &&
         h.heatmap.sameGridAs(h.center) && h.heatmap.sameGridAs(h.regress) && h.heatmap.sameGridAs(h.offset) &&
         h.heatmap.sameGridAs(h.box_scale) && h.heatmap.sameGridAs(h.box_offset);
}

MultiPoseResult decodeMultiPose(const MultiPoseHeads& heads, const DecodeConstants& c) {
  const int h = heads.center.height;
  const int w = heads.center.width;
  const int r = c.nms_kernel / 2;

  // 1. Centre peaks: a cell equal (within tolerance) to the maximum of its window; others count 0.
  // 2. The six largest, larger first, ties to the lower flat index (TopK).
  struct Peak {
    float value;
    int index;
  };
  std::array<Peak, kMaxMultiPoseInstances> top{};
  for (Peak& p : top) p = {-1.0F, -1};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float v = heads.center.at(0, y, x);
      float window_max = v;
      for (int yy = std::max(0, y - r); yy <= std::min(h - 1, y + r); ++yy)
        for (int xx = std::max(0, x - r); xx <= std::min(w - 1, x + r); ++xx)
          window_max = std::max(window_max, heads.center.at(0, yy, xx));
      const float masked = std::abs(v - window_max) < c.nms_tolerance ? v : 0.0F;
      const Peak candidate{masked, y * w + x};
      // Insert keeping the order (value descending, index ascending); later equal values go after.
      for (std::size_t i = 0; i < top.size(); ++i)
        if (top[i].index < 0 || candidate.value > top[i].value) {
          for (std::size_t j = top.size() - 1; j > i; --j) top[j] = top[j - 1];
          top[i] = candidate;
          break;
        }
    }

  // 3. Boxes and regressed joints of each instance.
  std::array<Box, kMaxMultiPoseInstances> boxes{};
  std::array<std::array<float, 2 * hal::kNumKeypoints>, kMaxMultiPoseInstances> regressed{};
  const auto fh = static_cast<float>(h), fw = static_cast<float>(w);
  for (std::size_t n = 0; n < top.size(); ++n) {
    const int cy = top[n].index / w;
    const int cx = top[n].index - cy * w;
    const float size_y = std::max(heads.box_scale.at(0, cy, cx), c.box_scale_min);
    const float size_x = std::max(heads.box_scale.at(1, cy, cx), c.box_scale_min);
    const float centre_y = static_cast<float>(cy) + heads.box_offset.at(0, cy, cx);
    const float centre_x = static_cast<float>(cx) + heads.box_offset.at(1, cy, cx);
    boxes[n] = {clip(centre_y - size_y * c.box_half, fh), clip(centre_x - size_x * c.box_half, fw),
                clip(centre_y + size_y * c.box_half, fh), clip(centre_x + size_x * c.box_half, fw)};
    for (int k = 0; k < kJoints; ++k) {
      regressed[n][yIndex(k)] = static_cast<float>(cy) + heads.regress.at(2 * k, cy, cx);
      regressed[n][xIndex(k)] = static_cast<float>(cx) + heads.regress.at(2 * k + 1, cy, cx);
    }
  }

  // 4-6. Each joint at the maximum of its weighted heatmap inside its box; its score is the
  // largest weighted value any instance gives that cell (the graph's Max over instances).
  const float sigma_cells2 = static_cast<float>(std::min(h, w)) * c.sigma_scale;
  MultiPoseResult result;
  for (std::size_t n = 0; n < top.size(); ++n) {
    MultiPoseInstance& out = result.instances[n];
    const Box& box = boxes[n];
    // The box in whole cells: outside it every weight is zero.
    const int y0 = std::clamp(static_cast<int>(std::ceil(box.ymin)), 0, h);
    const int y1 = std::clamp(static_cast<int>(std::ceil(box.ymax)), 0, h);
    const int x0 = std::clamp(static_cast<int>(std::ceil(box.xmin)), 0, w);
    const int x1 = std::clamp(static_cast<int>(std::ceil(box.xmax)), 0, w);
    float score_sum = 0.0F;
    float count = 0.0F;
    for (int k = 0; k < kJoints; ++k) {
      const float jy = regressed[n][yIndex(k)];
      const float jx = regressed[n][xIndex(k)];
      // Weights are >= 0 and zero outside the box, so starting from cell 0 with value 0 and taking
      // only larger values gives tf.argMax's first maximum, also when every value is zero.
      int best_y = 0, best_x = 0;
      float best = 0.0F;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
          if (const float v = weighted(heads, box, jy, jx, sigma_cells2, k, y, x); v > best) {
            best = v;
            best_y = y;
            best_x = x;
          }
      float score = 0.0F;
      for (std::size_t m = 0; m < top.size(); ++m)
        score = std::max(score, weighted(heads, boxes[m], regressed[m][yIndex(k)], regressed[m][xIndex(k)],
                                         sigma_cells2, k, best_y, best_x));
      NormalisedKeypoint& kp = out.keypoints[static_cast<std::size_t>(k)];
      kp.y = (static_cast<float>(best_y) + heads.offset.at(2 * k, best_y, best_x)) * c.coord_scale_y;
      kp.x = (static_cast<float>(best_x) + heads.offset.at(2 * k + 1, best_y, best_x)) * c.coord_scale_x;
      kp.score = score;
      if (score > c.keypoint_threshold) {
        score_sum += top[n].value * score;
        count += 1.0F;
      }
    }
    out.box_ymin = std::min(std::max(box.ymin * c.coord_scale_y, 0.0F), 1.0F);
    out.box_xmin = std::min(std::max(box.xmin * c.coord_scale_x, 0.0F), 1.0F);
    out.box_ymax = std::min(std::max(box.ymax * c.coord_scale_y, 0.0F), 1.0F);
    out.box_xmax = std::min(std::max(box.xmax * c.coord_scale_x, 0.0F), 1.0F);
    out.score = (1.0F / std::max(count, 1.0F)) * score_sum;  // the graph's Maximum_1: at least one
  }
  return result;
}

}  // namespace aerotrack::perception
