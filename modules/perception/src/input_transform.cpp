// Letterbox, tracking crop and network input filling: see input_transform.hpp.
#include "aerotrack/perception/input_transform.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace aerotrack::perception {

using hal::CocoKeypoint;
using hal::index;

InputTransform letterbox(int width_px, int height_px, int input_size_px) {
  const double side_px = std::max(width_px, height_px);
  return squareRegion(0.5 * width_px, 0.5 * height_px, side_px, input_size_px);
}

InputTransform squareRegion(double centre_u_px, double centre_v_px, double side_px, int input_size_px) {
  InputTransform t;
  t.region_u0_px = centre_u_px - 0.5 * side_px;
  t.region_v0_px = centre_v_px - 0.5 * side_px;
  t.region_side_px = side_px;
  t.input_size_px = input_size_px;
  return t;
}

bool cropAroundPerson(const std::array<hal::Keypoint2D, hal::kNumKeypoints>& keypoints, int width_px, int height_px,
                      int input_size_px, const CropParams& params, InputTransform& out) {
  const auto confident = [&](CocoKeypoint k) { return keypoints[index(k)].score >= params.min_score; };
  const bool hips = confident(CocoKeypoint::kLeftHip) || confident(CocoKeypoint::kRightHip);
  const bool shoulders = confident(CocoKeypoint::kLeftShoulder) || confident(CocoKeypoint::kRightShoulder);
  if (!hips || !shoulders) return false;

  // Centre on the mid-hip as MoveNet's reference cropping does (both hip estimates, confident or not:
  // the hip pair is always predicted and the midpoint is stable).
  const hal::Keypoint2D& lh = keypoints[index(CocoKeypoint::kLeftHip)];
  const hal::Keypoint2D& rh = keypoints[index(CocoKeypoint::kRightHip)];
  const double centre_u_px = 0.5 * (lh.u_px + rh.u_px);
  const double centre_v_px = 0.5 * (lh.v_px + rh.v_px);

  double torso_range_px = 0.0;
  double body_range_px = 0.0;
  for (std::size_t i = 0; i < hal::kNumKeypoints; ++i) {
    if (keypoints[i].score < params.min_score) continue;
    const double range_px =
        std::max(std::abs(keypoints[i].u_px - centre_u_px), std::abs(keypoints[i].v_px - centre_v_px));
    body_range_px = std::max(body_range_px, range_px);
    const auto k = static_cast<CocoKeypoint>(i);
    if (k == CocoKeypoint::kLeftShoulder || k == CocoKeypoint::kRightShoulder || k == CocoKeypoint::kLeftHip ||
        k == CocoKeypoint::kRightHip)
      torso_range_px = std::max(torso_range_px, range_px);
  }
  const double larger_side_px = std::max(width_px, height_px);
  double half_px = std::max(params.torso_factor * torso_range_px, params.body_factor * body_range_px);
  half_px = std::max(half_px, 0.5 * params.min_side_fraction * larger_side_px);
  // A crop that would be larger than the letterbox gains nothing: use the whole frame.
  if (half_px >= 0.5 * larger_side_px) {
    out = letterbox(width_px, height_px, input_size_px);
    return true;
  }
  out = squareRegion(centre_u_px, centre_v_px, 2.0 * half_px, input_size_px);
  return true;
}

cv::Mat makeInputBlob(int input_size_px) {
  const int shape[] = {1, 3, input_size_px, input_size_px};
  return cv::Mat(4, shape, CV_32F, cv::Scalar(0.0));
}

void fillInputBlob(const cv::Mat& bgr, const InputTransform& transform, TransformScratch& scratch, cv::Mat& blob) {
  const int s = transform.input_size_px;
  const double scale = transform.scale();
  // warpAffine maps destination pixel indices to source pixel indices; with pixel i covering
  // [i, i + 1), the centre i + 0.5 of a network pixel lands on image u = (i + 0.5) / scale + u0,
  // i.e. source index (i + 0.5) / scale + u0 - 0.5.
  const double shift_u = 0.5 / scale + transform.region_u0_px - 0.5;
  const double shift_v = 0.5 / scale + transform.region_v0_px - 0.5;
  const cv::Matx23d net_to_image(1.0 / scale, 0.0, shift_u, 0.0, 1.0 / scale, shift_v);
  const bool identity = std::abs(scale - 1.0) < 1e-12 && std::abs(shift_u) < 1e-12 && std::abs(shift_v) < 1e-12 &&
                        bgr.cols == s && bgr.rows == s;
  if (identity) {
    bgr.copyTo(scratch.warped_bgr);
  } else {
    cv::warpAffine(bgr, scratch.warped_bgr, net_to_image, cv::Size(s, s), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                   cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0));
  }
  // Planes of the NCHW blob in RGB order, written in place (no allocation).
  float* base = blob.ptr<float>();
  const std::size_t plane = static_cast<std::size_t>(s) * static_cast<std::size_t>(s);
  for (int v = 0; v < s; ++v) {
    const auto* row = scratch.warped_bgr.ptr<cv::Vec3b>(v);
    float* r = base + static_cast<std::size_t>(v) * static_cast<std::size_t>(s);
    float* g = r + plane;
    float* b = g + plane;
    for (int u = 0; u < s; ++u) {
      b[u] = row[u][0];
      g[u] = row[u][1];
      r[u] = row[u][2];
    }
  }
}

}  // namespace aerotrack::perception
