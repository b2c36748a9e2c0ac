// Unit tests of the calibration view sampler (hal/sim/calibration_views.hpp): the person is where
// the view says, in range and inside the image, and the truth agrees with the camera pose.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "aerotrack/hal/sim/calibration_views.hpp"
#include "aerotrack/hal/sim/keypoint_camera.hpp"

namespace aerotrack::hal::sim {
namespace {

TEST(CalibrationViews, GivenRandomViews_WhenSampled_ThenThePersonIsInRangeInViewAndWhereTheTruthSays) {
  PersonParams person_params;
  auto person = WalkingPerson::create(person_params, {{{0.0, 0.0}, 1.5, 0.0}, {{20.0, 5.0}, 1.5, 0.0}});
  ASSERT_TRUE(person) << person.error().message;
  const KeypointCameraParams camera;
  CalibrationViewParams params;
  params.horizontal_fov_rad = 87.0 * std::numbers::pi / 180.0;
  ASSERT_TRUE(validate(params));
  std::mt19937_64 rng(3);
  for (int i = 0; i < 500; ++i) {
    const CalibrationView v = sampleCalibrationView(*person, person->durationS(), params, rng);
    const double distance_m = std::hypot(v.p_C_flu_m.x(), v.p_C_flu_m.y());
    EXPECT_GE(distance_m, params.min_distance_m - 1e-9);
    EXPECT_LE(distance_m, params.max_distance_m + 1e-9);
    EXPECT_GT(v.p_C_flu_m.x(), 0.0);                                // in front
    EXPECT_NEAR(-v.p_C_flu_m.z(), v.T_WC.translation().z(), 1e-9);  // ground point below the camera
    // The truth in the camera's optical frame is the same point, rotated.
    const Eigen::Vector3d p_optical = v.T_WC.inverse() * v.person.p_W_m;
    EXPECT_NEAR(p_optical.z(), v.p_C_flu_m.x(), 1e-9);
    EXPECT_NEAR(p_optical.x(), -v.p_C_flu_m.y(), 1e-9);
    // The mid-hip projects inside the image's width.
    const Eigen::Vector3d hip_W = 0.5 * (v.person.keypoints_W_m[index(CocoKeypoint::kLeftHip)] +
                                         v.person.keypoints_W_m[index(CocoKeypoint::kRightHip)]);
    const auto px = project(v.T_WC.inverse() * hip_W, camera.intrinsics);
    ASSERT_TRUE(px.has_value());
    EXPECT_GT(px->x(), 0.0);
    EXPECT_LT(px->x(), camera.intrinsics.width_px);
  }
}

TEST(CalibrationViews, GivenBadParams_WhenValidated_ThenRejected) {
  CalibrationViewParams params;
  EXPECT_FALSE(validate(params));  // no field of view
  params.horizontal_fov_rad = 1.0;
  EXPECT_TRUE(validate(params));
  params.max_distance_m = 1.0;
  EXPECT_FALSE(validate(params));
}

}  // namespace
}  // namespace aerotrack::hal::sim
