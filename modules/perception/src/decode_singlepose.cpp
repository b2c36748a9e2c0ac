// MoveNet singlepose decoding: see movenet_decode.hpp. Mirrors the tail of the TensorFlow.js graph
// (ArgMax over the weighted centre, GatherNd of the regression, SquaredDifference/Sqrt distance,
// RealDiv, ArgMax, GatherNd of the offsets) in float32 and in the same order of operations.
#include <cmath>

#include "aerotrack/perception/movenet_decode.hpp"

namespace aerotrack::perception {

bool shapesValid(const SinglePoseHeads& heads) {
  return heads.heatmap.channels == static_cast<int>(hal::kNumKeypoints) && heads.center.channels == 1 &&
         heads.regress.channels == 2 * static_cast<int>(hal::kNumKeypoints) &&
         heads.offset.channels == 2 * static_cast<int>(hal::kNumKeypoints) && heads.heatmap.sameGridAs(heads.center) &&
         heads.heatmap.sameGridAs(heads.regress) && heads.heatmap.sameGridAs(heads.offset);
}

NormalisedPose decodeSinglePose(const SinglePoseHeads& heads, const DecodeConstants& constants) {
  const int h = heads.heatmap.height;
  const int w = heads.heatmap.width;

  // The person's centre: the first maximum in row-major order (tf.argMax keeps the first).
  int centre_y = 0;
  int centre_x = 0;
  float best = heads.center.at(0, 0, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (const float c = heads.center.at(0, y, x); c > best) {
        best = c;
        centre_y = y;
        centre_x = x;
      }

  NormalisedPose pose{};
  for (int k = 0; k < static_cast<int>(hal::kNumKeypoints); ++k) {
    const float regressed_y = static_cast<float>(centre_y) + heads.regress.at(2 * k, centre_y, centre_x);
    const float regressed_x = static_cast<float>(centre_x) + heads.regress.at(2 * k + 1, centre_y, centre_x);
    int joint_y = 0;
    int joint_x = 0;
    float best_weighted = -1.0F;
    for (int y = 0; y < h; ++y) {
      const float dy = static_cast<float>(y) - regressed_y;
      for (int x = 0; x < w; ++x) {
        const float dx = static_cast<float>(x) - regressed_x;
        const float distance = std::sqrt(dy * dy + dx * dx);
        const float weighted = heads.heatmap.at(k, y, x) / (distance + constants.distance_bias);
        if (weighted > best_weighted) {
          best_weighted = weighted;
          joint_y = y;
          joint_x = x;
        }
      }
    }
    NormalisedKeypoint& out = pose[static_cast<std::size_t>(k)];
    out.y = (static_cast<float>(joint_y) + heads.offset.at(2 * k, joint_y, joint_x)) * constants.coord_scale_y;
    out.x = (static_cast<float>(joint_x) + heads.offset.at(2 * k + 1, joint_y, joint_x)) * constants.coord_scale_x;
    out.score = heads.heatmap.at(k, joint_y, joint_x);
  }
  return pose;
}

}  // namespace aerotrack::perception
