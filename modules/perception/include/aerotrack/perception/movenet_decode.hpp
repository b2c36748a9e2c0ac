// MoveNet's decoding, in C++ because OpenCV 4.6's DNN has no ArgMax/GatherND/TopK (issue 5): the
// converted ONNX graph stops at the heads and these functions do what the rest of the original
// TensorFlow.js graph did, operation for operation in float32, so that the keypoints agree with the
// original model to 1e-4 (tools/fidelity). The head layouts and every constant are documented in
// scripts/models/README.md, which is the contract between the converter and this decoder; the
// constants come from the model's sidecar (ModelInfo, movenet_model.hpp), never from this file.
//
// All functions are pure and allocation-free: heads are read through raw views, results go into
// fixed-size arrays. Coordinates are normalised to the network input: y, x in [0, 1].
#pragma once

#include <array>
#include <cstddef>

#include "aerotrack/hal/types.hpp"

namespace aerotrack::perception {

/// One head tensor [1, C, H, W] (NCHW, float32, contiguous).
struct HeadView {
  const float* data = nullptr;
  int channels = 0;
  int height = 0;
  int width = 0;

  float at(int c, int y, int x) const {
    return data[(static_cast<std::size_t>(c) * static_cast<std::size_t>(height) + static_cast<std::size_t>(y)) *
                    static_cast<std::size_t>(width) +
                static_cast<std::size_t>(x)];
  }
  /// Both views hold data on the same non-empty grid (the heads of one model output do).
  bool sameGridAs(const HeadView& other) const {
    return data != nullptr && other.data != nullptr && height == other.height && width == other.width && height > 0 &&
           width > 0;
  }
};

/// The constants of the decoding, read from the model's sidecar.
struct DecodeConstants {
  /// Singlepose and multipose: keypoint y, x = (cell + offset) * coord_scale (about 1 / H).
  float coord_scale_y = 0.0F;
  float coord_scale_x = 0.0F;
  /// Singlepose: heatmap / (distance to the regressed joint + distance_bias) picks the joint's cell.
  float distance_bias = 0.0F;
  /// Multipose (scripts/models/README.md, "multipose decode"; sidecar names in brackets):
  int nms_kernel = 0;          ///< [nms_kernel] A centre cell is a peak if it equals the max of this k x k window...
  float nms_tolerance = 0.0F;  ///< [nms_tolerance] ...to within this.
  float sigma_scale = 0.0F;    ///< [sigma_scale] Joint weight exp(-d^2 / (min(H, W) x this)), d in cells.
  float box_scale_min = 0.0F;  ///< [box_scale_min] Box size is max(box_scale head, this)...
  float box_half = 0.0F;       ///< [box_half] ...and the box reaches size x this on each side of its centre.
  float keypoint_threshold = 0.0F;  ///< [keypoint_threshold] Joints above it count for the instance score.
};

/// Singlepose heads: heatmap [1,17,H,W] (sigmoid), center [1,1,H,W] (sigmoid x the model's centre
/// weight map), regress and offset [1,34,H,W] (channel 2k: y, 2k+1: x of joint k, in cells).
struct SinglePoseHeads {
  HeadView heatmap, center, regress, offset;
};

/// One decoded pose: y, x normalised to the network input, and the joint's heatmap score.
struct NormalisedKeypoint {
  float y = 0.0F;
  float x = 0.0F;
  float score = 0.0F;
};
using NormalisedPose = std::array<NormalisedKeypoint, hal::kNumKeypoints>;

/// Checks shapes: 17 heatmap channels, 1 centre channel, 34 regress/offset channels, equal H and W
/// across heads. Returns false on a mismatch.
bool shapesValid(const SinglePoseHeads& heads);

/// The singlepose decoding of MoveNet: the centre cell of the person (first argmax of the weighted
/// centre map), each joint regressed from it, then the heatmap cell nearest to the regressed joint
/// (heatmap / (distance + bias), first argmax), refined by its offset. Expects shapesValid(heads).
NormalisedPose decodeSinglePose(const SinglePoseHeads& heads, const DecodeConstants& constants);

/// Multipose heads: heatmap, center (sigmoid), regress, offset as above, box_scale and box_offset
/// [1,2,H,W] (y, x; in cells).
struct MultiPoseHeads {
  HeadView heatmap, center, regress, offset, box_scale, box_offset;
};
inline constexpr std::size_t kMaxMultiPoseInstances = 6;

struct MultiPoseInstance {
  NormalisedPose keypoints{};
  float box_ymin = 0.0F, box_xmin = 0.0F, box_ymax = 0.0F, box_xmax = 0.0F;  ///< Normalised.
  float score = 0.0F;
};
struct MultiPoseResult {
  std::array<MultiPoseInstance, kMaxMultiPoseInstances> instances{};  ///< In the model's order.
};

bool shapesValid(const MultiPoseHeads& heads);

/// The multipose decoding of MoveNet (scripts/models/README.md, "multipose decode"): the six
/// strongest local maxima of the centre map, each with its regressed joints snapped to the
/// distance-weighted heatmap maximum inside its box, offsets, box and instance score. Expects
/// shapesValid(heads). Always returns six instances, as the model does; the caller thresholds the
/// scores.
MultiPoseResult decodeMultiPose(const MultiPoseHeads& heads, const DecodeConstants& constants);

}  // namespace aerotrack::perception
