// Tests of camera to world (issue 6, item 4): hand-computed poses with the gimbal at 0, 90, 180,
// 270 degrees and beyond a turn, a yawed and translated drone, the simulator's camera convention,
// and lookups interpolated from the timestamped histories at the capture time.
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "aerotrack/estimation/camera_to_world.hpp"

namespace aerotrack::estimation {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

GimbalCameraExtrinsics simLikeExtrinsics() {
  GimbalCameraExtrinsics e;
  e.p_BG_m = Eigen::Vector3d(0.1, 0.0, -0.05);
  return e;
}

void expectNear(const Eigen::Vector3d& actual, const Eigen::Vector3d& expected, double tolerance = 1e-12) {
  EXPECT_NEAR((actual - expected).norm(), 0.0, tolerance)
      << "actual " << actual.transpose() << ", expected " << expected.transpose();
}

TEST(CameraToWorld, GivenALevelDroneAtTheOriginThenTheGimbalAngleTurnsThePointAboutBodyZ) {
  // Given the drone at the origin, level, facing world x; a person 3 m ahead of the camera, 0.5 m
  // to its left and 1 m below it.
  const Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d p_C(3.0, 0.5, -1.0);
  const Eigen::Vector3d mount(0.1, 0.0, -0.05);
  // When the gimbal is at 0, 90, 180, 270 degrees and beyond a full turn, then (by hand):
  expectNear(cameraToWorld(p_C, T_WB, 0.0, simLikeExtrinsics()), mount + Eigen::Vector3d(3.0, 0.5, -1.0));
  expectNear(cameraToWorld(p_C, T_WB, 90 * kDeg, simLikeExtrinsics()), mount + Eigen::Vector3d(-0.5, 3.0, -1.0));
  expectNear(cameraToWorld(p_C, T_WB, 180 * kDeg, simLikeExtrinsics()), mount + Eigen::Vector3d(-3.0, -0.5, -1.0));
  expectNear(cameraToWorld(p_C, T_WB, 270 * kDeg, simLikeExtrinsics()), mount + Eigen::Vector3d(0.5, -3.0, -1.0));
  expectNear(cameraToWorld(p_C, T_WB, 450 * kDeg, simLikeExtrinsics()), mount + Eigen::Vector3d(-0.5, 3.0, -1.0));
  expectNear(cameraToWorld(p_C, T_WB, 720 * kDeg, simLikeExtrinsics()), mount + Eigen::Vector3d(3.0, 0.5, -1.0));
  expectNear(cameraToWorld(p_C, T_WB, -90 * kDeg, simLikeExtrinsics()), mount + Eigen::Vector3d(0.5, -3.0, -1.0));
}

TEST(CameraToWorld, GivenAYawedTranslatedDroneThenTheBodyPoseAppliesAfterTheGimbal) {
  // Given the drone at (10, 5, 2) yawed 90 degrees (facing world +y) and the gimbal at 90 degrees
  // (camera along body +y, i.e. world -x).
  Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
  T_WB.linear() = Eigen::AngleAxisd(90 * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T_WB.translation() = Eigen::Vector3d(10.0, 5.0, 2.0);
  // When the person is 3 m ahead of the camera and 1 m below.
  const Eigen::Vector3d p_W = cameraToWorld(Eigen::Vector3d(3.0, 0.0, -1.0), T_WB, 90 * kDeg, simLikeExtrinsics());
  // Then: body point = mount + (0, 3, -1) = (0.1, 3, -1.05); world = Rz(90) body + t = (-3, 0.1, -1.05) + t.
  expectNear(p_W, Eigen::Vector3d(7.0, 5.1, 0.95));
  // And at 450 degrees the same.
  expectNear(cameraToWorld(Eigen::Vector3d(3.0, 0.0, -1.0), T_WB, 450 * kDeg, simLikeExtrinsics()), p_W, 1e-12);
}

TEST(CameraToWorld, GivenTheSimulatorsConventionThenTheOpticalPoseMatchesItExactly) {
  // Given the simulator's formula (hal/sim Simulation::cameraPose): R_WC_optical = R_WB Rz(psi)
  // R_FLU_optical, camera centre p_WB + R_WB mount_B.
  Eigen::Matrix3d R_flu_optical;
  R_flu_optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
  T_WB.linear() =
      (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(-0.03, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  T_WB.translation() = Eigen::Vector3d(-3.0, 4.0, 2.5);
  for (const double psi : {0.0, 1.0, -2.5, 7.5}) {
    const Eigen::Matrix3d R_sim =
        T_WB.linear() * Eigen::AngleAxisd(psi, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R_flu_optical;
    const Eigen::Vector3d p_sim = T_WB.translation() + T_WB.linear() * simLikeExtrinsics().p_BG_m;
    // When our camera pose is turned into the optical frame.
    const Eigen::Isometry3d T_WC = cameraPoseInWorld(T_WB, psi, simLikeExtrinsics());
    // Then it is the simulator's.
    EXPECT_NEAR((T_WC.linear() * opticalAxesInCamera() - R_sim).norm(), 0.0, 1e-12);
    expectNear(T_WC.translation(), p_sim);
  }
  // And a point right of the image centre (optical x > 0) has y < 0 in C (y left).
  const Eigen::Vector3d p_optical(0.5, 0.0, 4.0);
  const Eigen::Vector3d p_C = opticalAxesInCamera() * p_optical;
  expectNear(p_C, Eigen::Vector3d(4.0, -0.5, 0.0));
}

TEST(CameraToWorld, GivenWorldPoints_ThenWorldToPixelIsTheSimulatorsPinholeAndRefusesPointsBehind) {
  // By hand: a level camera at the origin looking along W x; a point 5 m ahead, 1 m left, 0.5 m up.
  const hal::CameraIntrinsics k{640, 480, 337.2, 331.0, 322.0, 236.0, {}};
  const Eigen::Isometry3d level = cameraPoseInWorld(Eigen::Isometry3d::Identity(), 0.0, GimbalCameraExtrinsics{});
  const auto ahead = worldToPixel(Eigen::Vector3d(5.0, 1.0, 0.5), level, k);
  ASSERT_TRUE(ahead.has_value());
  EXPECT_NEAR(ahead->u_px, 322.0 - 337.2 * 1.0 / 5.0, 1e-9);
  EXPECT_NEAR(ahead->v_px, 236.0 - 331.0 * 0.5 / 5.0, 1e-9);
  EXPECT_NEAR(ahead->depth_m, 5.0, 1e-12);
  // Behind the camera, beside it, or not finite: nothing.
  EXPECT_FALSE(worldToPixel(Eigen::Vector3d(-5.0, 1.0, 0.5), level, k).has_value());
  EXPECT_FALSE(worldToPixel(Eigen::Vector3d(0.0, 3.0, 0.0), level, k).has_value());
  EXPECT_FALSE(worldToPixel(Eigen::Vector3d(5.0, std::nan(""), 0.5), level, k).has_value());
  // A tilted, yawed drone with the gimbal turned: the simulator's optical pose (hal/sim Simulation::cameraPose,
  // rebuilt here as the test above does) projects the same points to the same pixels.
  Eigen::Matrix3d R_flu_optical;
  R_flu_optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
  T_WB.linear() = (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  T_WB.translation() = Eigen::Vector3d(-3.0, 4.0, 1.5);
  const double psi = 2.1;
  const Eigen::Matrix3d R_sim =
      T_WB.linear() * Eigen::AngleAxisd(psi, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R_flu_optical;
  const Eigen::Vector3d p_sim = T_WB.translation() + T_WB.linear() * simLikeExtrinsics().p_BG_m;
  const Eigen::Isometry3d T_WC = cameraPoseInWorld(T_WB, psi, simLikeExtrinsics());
  int seen = 0;
  for (const double x : {-8.0, -2.0, 3.0})
    for (const double y : {-1.0, 4.0, 9.0})
      for (const double z : {0.0, 1.1, 2.0}) {
        const Eigen::Vector3d p_W(x, y, z);
        const Eigen::Vector3d q = R_sim.transpose() * (p_W - p_sim);
        const auto pixel = worldToPixel(p_W, T_WC, k);
        ASSERT_EQ(pixel.has_value(), q.z() > 0.01) << p_W.transpose();
        if (!pixel) continue;
        ++seen;
        EXPECT_NEAR(pixel->u_px, k.fx_px * q.x() / q.z() + k.cx_px, 1e-9);
        EXPECT_NEAR(pixel->v_px, k.fy_px * q.y() / q.z() + k.cy_px, 1e-9);
        EXPECT_NEAR(pixel->depth_m, q.z(), 1e-12);
      }
  EXPECT_GT(seen, 3);
  EXPECT_LT(seen, 27);
}

TEST(CameraToWorld, GivenAPitchedDroneThenTheLevelFrameIgnoresThePitchAndKeepsTheHeading) {
  // The drone pitches 10 degrees nose down while yawed 90 degrees; the gimbal adds 90 more, so the
  // camera heads along -x. A regression fitted on a level camera says: 2.5 m ahead, 0.3 m left,
  // 1.7 m below. In the level frame that is exactly where the person is, whatever the pitch.
  GimbalCameraExtrinsics e;
  e.p_BG_m = Eigen::Vector3d(0.1, 0.0, 0.0);
  Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
  T_WB.linear() = (Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(10.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()))
                      .toRotationMatrix();
  T_WB.translation() = Eigen::Vector3d(5.0, 1.0, 1.7);
  const Eigen::Vector3d p_C(2.5, 0.3, -1.7);
  const Eigen::Vector3d camera_W = cameraPoseInWorld(T_WB, M_PI / 2, e).translation();
  const Eigen::Vector3d level = cameraToWorld(p_C, T_WB, M_PI / 2, e, CameraFrame::kLevel);
  // The camera's heading: body x (world +y) turned 90 degrees left: world -x.
  EXPECT_NEAR(level.x(), camera_W.x() - 2.5, 1e-9);
  EXPECT_NEAR(level.y(), camera_W.y() - 0.3, 1e-9);
  EXPECT_NEAR(level.z(), camera_W.z() - 1.7, 1e-9);
  // Read in the tilted camera frame, the same numbers land 0.3 m nearer: the error the level
  // frame removes.
  const Eigen::Vector3d tilted = cameraToWorld(p_C, T_WB, M_PI / 2, e, CameraFrame::kCamera);
  EXPECT_GT((tilted - level).head<2>().norm(), 0.25);
}

TEST(CameraToWorld, GivenARolledPitchedCamera_ThenTheLevelHomographyMovesEachPixelToTheLevelCamerasPixel) {
  // The drone rolled 25 and pitched -15 degrees (braking hard sideways), yawed 0.7 rad, the gimbal at 0.4.
  Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
  T_WB.linear() =
      (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-15.0 * kDeg, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(25.0 * kDeg, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  T_WB.translation() = Eigen::Vector3d(2.0, -1.0, 1.6);
  const Eigen::Isometry3d T_WC = cameraPoseInWorld(T_WB, 0.4, simLikeExtrinsics());
  const hal::CameraIntrinsics k{640, 480, 337.2, 331.0, 322.0, 236.0, {}};
  // The level camera built independently: the same centre, its optical axis the camera's forward axis laid
  // flat on the ground.
  const Eigen::Vector3d forward_W = T_WC.linear().col(0);
  const Eigen::Vector3d flat_W = Eigen::Vector3d(forward_W.x(), forward_W.y(), 0.0).normalized();
  Eigen::Matrix3d R_W_level_optical;  // columns: right, down, forward
  R_W_level_optical.col(2) = flat_W;
  R_W_level_optical.col(1) = -Eigen::Vector3d::UnitZ();
  R_W_level_optical.col(0) = R_W_level_optical.col(1).cross(flat_W);
  const auto pixel = [&](const Eigen::Matrix3d& R_W_optical, const Eigen::Vector3d& p_W) {
    const Eigen::Vector3d q = R_W_optical.transpose() * (p_W - T_WC.translation());
    return Eigen::Vector2d(k.fx_px * q.x() / q.z() + k.cx_px, k.fy_px * q.y() / q.z() + k.cy_px);
  };
  const Eigen::Matrix3d H = levelHomography(T_WC, k);
  // People's joints 2-8 m ahead, 2 m either side, from the ground to 2 m up.
  for (const double ahead : {2.0, 4.5, 8.0})
    for (const double side : {-2.0, 0.3, 2.0})
      for (const double up : {0.0, 1.2, 2.0}) {
        const Eigen::Vector3d p_W = T_WC.translation() + ahead * flat_W +
                                    side * Eigen::Vector3d::UnitZ().cross(flat_W) +
                                    Eigen::Vector3d(0.0, 0.0, up - T_WC.translation().z());
        const Eigen::Vector2d tilted = pixel(T_WC.linear() * opticalAxesInCamera(), p_W);
        const Eigen::Vector3d h = H * tilted.homogeneous();
        ASSERT_GT(h.z(), 0.0);
        const Eigen::Vector2d level = pixel(R_W_level_optical, p_W);
        EXPECT_NEAR((h.hnormalized() - level).norm(), 0.0, 1e-9) << ahead << " " << side << " " << up;
      }
  // And a level camera's homography is the identity.
  Eigen::Isometry3d level_WB = Eigen::Isometry3d::Identity();
  level_WB.linear() = Eigen::AngleAxisd(-1.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_NEAR(
      (levelHomography(cameraPoseInWorld(level_WB, 2.0, simLikeExtrinsics()), k) - Eigen::Matrix3d::Identity()).norm(),
      0.0, 1e-12);
}

TEST(CameraToWorld, GivenHistoriesThenTheCaptureTimeIsInterpolatedNotTheLatest) {
  // Given odometry at 0 and 100 ms (moving 1 m along x, yaw 0 -> 90 degrees) and gimbal samples
  // at 0 and 100 ms (0 -> 90 degrees).
  auto poses = hal::OdometryHistory::create({});
  auto gimbal = GimbalAngleHistory::create({.capacity = 8, .max_gap_ns = 200 * rt::kNsPerMillisecond});
  ASSERT_TRUE(poses && gimbal);
  hal::OdometryHistory& pose_history = *poses;
  hal::OdometrySample odo;
  odo.stamp_ns = 0;
  ASSERT_EQ(pose_history.push(odo), rt::HistoryPush::kAccepted);
  odo.stamp_ns = 40 * rt::kNsPerMillisecond;
  odo.p_WB_m = Eigen::Vector3d(0.4, 0.0, 0.0);
  odo.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(36 * kDeg, Eigen::Vector3d::UnitZ()));
  ASSERT_EQ(pose_history.push(odo), rt::HistoryPush::kAccepted);
  odo.stamp_ns = 80 * rt::kNsPerMillisecond;
  odo.p_WB_m = Eigen::Vector3d(0.8, 0.0, 0.0);
  odo.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(72 * kDeg, Eigen::Vector3d::UnitZ()));
  ASSERT_EQ(pose_history.push(odo), rt::HistoryPush::kAccepted);
  ASSERT_EQ(gimbal->push({0, 0.0, 0.0}), rt::HistoryPush::kAccepted);
  ASSERT_EQ(gimbal->push({100 * rt::kNsPerMillisecond, 90 * kDeg, 0.0}), rt::HistoryPush::kAccepted);
  const GimbalCameraExtrinsics extrinsics;  // camera at the body origin
  // When the image was captured at 20 ms.
  const auto p_W =
      cameraToWorldAt(20 * rt::kNsPerMillisecond, Eigen::Vector3d(2.0, 0.0, 0.0), *poses, *gimbal, extrinsics);
  // Then the body is at x = 0.2 m, yawed 18 degrees, the gimbal at 18 degrees: 36 degrees total.
  ASSERT_TRUE(p_W) << p_W.error().message;
  expectNear(*p_W, Eigen::Vector3d(0.2 + 2.0 * std::cos(36 * kDeg), 2.0 * std::sin(36 * kDeg), 0.0), 1e-9);
  // And a time outside a history is an error naming it.
  const auto late =
      cameraToWorldAt(90 * rt::kNsPerMillisecond, Eigen::Vector3d(2.0, 0.0, 0.0), *poses, *gimbal, extrinsics);
  ASSERT_FALSE(late);
  EXPECT_NE(late.error().message.find("no body pose"), std::string::npos) << late.error().message;
  const auto early = cameraToWorldAt(-1, Eigen::Vector3d(2.0, 0.0, 0.0), *poses, *gimbal, extrinsics);
  ASSERT_FALSE(early);
}

TEST(GimbalAngleHistory, GivenMultiTurnAnglesThenInterpolationIsLinearInTheUnwrappedAngle) {
  auto history = GimbalAngleHistory::create({.capacity = 4, .max_gap_ns = 100});
  ASSERT_TRUE(history);
  // Given 350 and 370 degrees (unwrapped) 10 ns apart.
  ASSERT_EQ(history->push({10, 350 * kDeg, 0.0}), rt::HistoryPush::kAccepted);
  ASSERT_EQ(history->push({20, 370 * kDeg, 0.0}), rt::HistoryPush::kAccepted);
  // Then the midpoint is 360 degrees, not 180.
  const GimbalAngleLookup mid = history->lookup(15);
  ASSERT_EQ(mid.status, HistoryLookupStatus::kOk);
  EXPECT_NEAR(mid.value, 360 * kDeg, 1e-12);
  // And out-of-order, duplicate and non-finite samples are refused.
  EXPECT_EQ(history->push({20, 0.0, 0.0}), rt::HistoryPush::kRejectedOutOfOrder);
  EXPECT_EQ(history->push({30, std::nan(""), 0.0}), rt::HistoryPush::kRejectedInvalid);
  EXPECT_EQ(history->rejectedCount(), 2u);
  EXPECT_EQ(history->lookup(5).status, HistoryLookupStatus::kBeforeOldest);
  EXPECT_EQ(history->lookup(21).status, HistoryLookupStatus::kAfterNewest);
  ASSERT_EQ(history->push({300, 0.0, 0.0}), rt::HistoryPush::kAccepted);
  EXPECT_EQ(history->lookup(100).status, HistoryLookupStatus::kGapTooLarge);
  EXPECT_EQ(history->lookup(20).status, HistoryLookupStatus::kOk);  // exactly a sample
  // The ring keeps the newest 4.
  ASSERT_EQ(history->push({310, 0.0, 0.0}), rt::HistoryPush::kAccepted);
  ASSERT_EQ(history->push({320, 0.0, 0.0}), rt::HistoryPush::kAccepted);
  EXPECT_EQ(history->lookup(15).status, HistoryLookupStatus::kBeforeOldest);
  EXPECT_FALSE(GimbalAngleHistory::create({.capacity = 1}));
}

TEST(GimbalCameraExtrinsics, GivenAConfigSectionThenParsedStrictly) {
  const auto root = rt::ConfigNode::fromString(
      "camera:\n  mount_m: [0.1, 0, -0.05]\n  camera_in_gimbal_m: [0.02, 0, 0]\n"
      "  camera_in_gimbal_rpy_rad: [0, 0, 0.5]\n",
      "x.yaml");
  ASSERT_TRUE(root);
  const auto e =
      rt::parseConfig<GimbalCameraExtrinsics>([&root] { return parseGimbalCameraExtrinsics(root->child("camera")); });
  ASSERT_TRUE(e) << e.error().message;
  expectNear(e->p_BG_m, Eigen::Vector3d(0.1, 0.0, -0.05));
  expectNear(e->T_GC * Eigen::Vector3d(1.0, 0.0, 0.0), Eigen::Vector3d(0.02 + std::cos(0.5), std::sin(0.5), 0.0));
  const auto bad = rt::ConfigNode::fromString(
      "camera:\n  mount_m: [0.1, 0, -0.05]\n  camera_in_gimbal_m: [0, 0, 0]\n"
      "  camera_in_gimbal_rpy_rad: [0, 0, 0]\n  pitch_rad: 0\n",
      "x.yaml");
  ASSERT_TRUE(bad);
  const auto error =
      rt::parseConfig<GimbalCameraExtrinsics>([&bad] { return parseGimbalCameraExtrinsics(bad->child("camera")); });
  ASSERT_FALSE(error);
  EXPECT_NE(error.error().message.find("camera.pitch_rad: unknown key"), std::string::npos) << error.error().message;
}

}  // namespace
}  // namespace aerotrack::estimation
