// A frame of zeros from the depth camera: dead, or the sky (depth_view.hpp). The view of a D435-like camera on a
// hovering drone holds ground in reach; pitched nose-up past half its vertical field, high above the ground, it
// does not; looking straight down, the principal point's line of sight finds it. Blank frames by their sampled
// valid pixels.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "aerotrack/hal/depth_view.hpp"

namespace aerotrack::hal {
namespace {

/// 848 x 480 with 58 degrees of vertical field (the D435's depth stream).
CameraIntrinsics d435() {
  CameraIntrinsics k;
  k.width_px = 848;
  k.height_px = 480;
  k.fy_px = 240.0 / std::tan(29.0 * std::numbers::pi / 180.0);
  k.fx_px = k.fy_px;
  k.cx_px = 424.0;
  k.cy_px = 240.0;
  return k;
}

/// The optical frame (x right, y down, z forward) of a camera at height_m looking along +x of W, its nose pitched
/// up by pitch_up_deg (negative: down).
Eigen::Isometry3d camera(double height_m, double pitch_up_deg) {
  Eigen::Matrix3d optical_in_flu;  // columns: the optical x, y, z axes in forward-left-up
  optical_in_flu << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Eigen::Matrix3d pitch =
      Eigen::AngleAxisd(-pitch_up_deg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  T_WC.linear() = pitch * optical_in_flu;
  T_WC.translation() = Eigen::Vector3d(0.0, 0.0, height_m);
  return T_WC;
}

TEST(DepthView, AHoveringCameraSeesTheGroundAndOnePitchedUpPastHalfItsFieldSeesTheSky) {
  // Level at 1.5 m: the lowest lines of sight, 29 degrees down, meet the ground at 1.5 / sin 29 = 3.1 m.
  EXPECT_TRUE(viewHoldsGroundWithin(camera(1.5, 0.0), d435(), 6.0));
  EXPECT_FALSE(viewHoldsGroundWithin(camera(1.5, 0.0), d435(), 3.0)) << "3.1 m is beyond a 3 m reach";
  // Crowd seed 2, image mode: braking at 1.57 m with the optical axis 20-29 degrees above the horizon.
  // 10 degrees up: the lowest lines of sight 19 degrees down, at 1.57 / sin 19 = 4.8 m; 20 up: 9 down, 10 m.
  EXPECT_TRUE(viewHoldsGroundWithin(camera(1.57, 10.0), d435(), 6.0));
  EXPECT_FALSE(viewHoldsGroundWithin(camera(1.57, 20.0), d435(), 6.0));
  EXPECT_FALSE(viewHoldsGroundWithin(camera(1.57, 29.0), d435(), 6.0));
  EXPECT_FALSE(viewHoldsGroundWithin(camera(1.57, 35.0), d435(), 6.0));
  // Pitched down, the ground fills the view.
  EXPECT_TRUE(viewHoldsGroundWithin(camera(1.5, -20.0), d435(), 6.0));
  // High up, level: nothing within reach.
  EXPECT_FALSE(viewHoldsGroundWithin(camera(20.0, 0.0), d435(), 6.0));
  // Looking straight down from 5 m: the corners are farther (5 / cos of their angle), the centre is not.
  EXPECT_TRUE(viewHoldsGroundWithin(camera(5.0, -90.0), d435(), 5.1));
  // On or below the ground: everything is near.
  EXPECT_TRUE(viewHoldsGroundWithin(camera(0.0, 45.0), d435(), 1.0));
}

TEST(DepthView, AFrameIsBlankUnderHalfAPercentOfValidSamples) {
  DepthFrame frame;
  frame.depth_m = cv::Mat::zeros(480, 848, CV_32FC1);
  EXPECT_TRUE(isBlankDepth(frame));
  // 60 x 106 = 6360 samples: 32 valid (0.50 %) is not blank, 31 is.
  int set = 0;
  for (int v = 0; v < 480 && set < 31; v += 8)
    for (int u = 0; u < 848 && set < 31; u += 8, ++set) frame.depth_m.at<float>(v, u) = 2.0F;
  EXPECT_TRUE(isBlankDepth(frame));
  frame.depth_m.at<float>(472, 840) = 2.0F;
  EXPECT_FALSE(isBlankDepth(frame));
  frame.depth_m.at<float>(472, 840) = std::nanf("");
  EXPECT_TRUE(isBlankDepth(frame)) << "NaN is no data";
  DepthFrame empty;
  EXPECT_TRUE(isBlankDepth(empty));
}

}  // namespace
}  // namespace aerotrack::hal
