// The network sees a square S x S image; the camera delivers W x H. An InputTransform maps a square
// region of the camera image onto the network input by a scale and a shift, which covers both cases
// MoveNet needs (issue 5, item 3):
//   - the letterbox: the whole frame, centred in a square of side max(W, H), padded with black;
//   - the tracking crop: a square around the person's last keypoints (MoveNet's own "crop region"),
//     which may extend past the image border (padded with black too).
// Coordinates are continuous pixels with the origin at the top-left pixel's corner (hal::Keypoint2D),
// so that pixel i covers [i, i + 1): image u = net_u / scale + region_u0. A frame that already is
// S x S maps with scale 1 and no shift, and its pixels reach the network unchanged (the fidelity
// check relies on this).
#pragma once

#include <array>

#include <opencv2/core/mat.hpp>

#include "aerotrack/hal/types.hpp"

namespace aerotrack::perception {

/// A square region of the camera image (may extend past its borders) mapped onto the S x S network
/// input. Pure value type.
struct InputTransform {
  double region_u0_px = 0.0;  ///< Top-left corner of the square region in the image.
  double region_v0_px = 0.0;
  double region_side_px = 1.0;  ///< Side of the square region in image pixels (> 0).
  int input_size_px = 1;        ///< S: side of the network input.

  double scale() const { return input_size_px / region_side_px; }
  /// Network input pixel -> image pixel.
  double toImageU(double net_u_px) const { return region_u0_px + net_u_px / scale(); }
  double toImageV(double net_v_px) const { return region_v0_px + net_v_px / scale(); }
};

/// The whole W x H frame, centred in a square of side max(W, H). Requires W, H, S > 0.
InputTransform letterbox(int width_px, int height_px, int input_size_px);

/// A square region of side side_px centred on (centre_u_px, centre_v_px). Requires side_px > 0.
InputTransform squareRegion(double centre_u_px, double centre_v_px, double side_px, int input_size_px);

/// MoveNet's crop for tracking (the TF Hub model card's "determine crop region"): a square centred
/// on the mid-hip whose half side covers the torso joints with margin torso_factor and every
/// confident joint with margin body_factor, never smaller than min_side_fraction of the frame's
/// larger side. Joints with score < min_score are ignored; nothing if the hips or shoulders are
/// not confident. Pure.
struct CropParams {
  double min_score = 0.3;
  double torso_factor = 1.9;        ///< Half side >= torso_factor x the largest torso-joint distance.
  double body_factor = 1.2;         ///< Half side >= body_factor x the largest joint distance.
  double min_side_fraction = 0.25;  ///< Side >= this x max(W, H), so a far person keeps context.
};
bool cropAroundPerson(const std::array<hal::Keypoint2D, hal::kNumKeypoints>& keypoints, int width_px, int height_px,
                      int input_size_px, const CropParams& params, InputTransform& out);

/// Fills blob (float32, shape [1, 3, S, S], allocated by the caller once) with the transformed
/// region of bgr (8-bit BGR, any size) as RGB values 0..255, bilinear, black outside the image.
/// Allocation-free after the first call with a given size (scratch is reused). Not thread-safe for
/// one scratch.
struct TransformScratch {
  cv::Mat warped_bgr;  ///< S x S, CV_8UC3.
};
void fillInputBlob(const cv::Mat& bgr, const InputTransform& transform, TransformScratch& scratch, cv::Mat& blob);

/// A blob of shape [1, 3, S, S], float32. Allocates.
cv::Mat makeInputBlob(int input_size_px);

}  // namespace aerotrack::perception
