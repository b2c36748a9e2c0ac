// Our types as Foxglove messages (app/src/foxglove_messages.hpp): each filler against the module it
// draws from -- the transform chain against estimation's camera pose, the calibration against the
// pinhole model, the depth points against the depth image, the uncertainty ellipsoid against the
// covariance -- and the schema data a reader rebuilds the types from.
#include "foxglove_messages.hpp"

#include <google/protobuf/descriptor.pb.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <vector>

namespace aerotrack::app::foxglove_log {
namespace {

Eigen::Isometry3d toIsometry(const foxglove::FrameTransform& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(t.translation().x(), t.translation().y(), t.translation().z());
  T.linear() =
      Eigen::Quaterniond(t.rotation().w(), t.rotation().x(), t.rotation().y(), t.rotation().z()).toRotationMatrix();
  return T;
}

TEST(FoxgloveMessages, SchemaDataIsAFileDescriptorSetWithEveryImportBeforeItsUser) {
  google::protobuf::FileDescriptorSet set;
  ASSERT_TRUE(set.ParseFromString(fileDescriptorSet(*foxglove::SceneUpdate::descriptor())));
  std::vector<std::string> names;
  for (const auto& file : set.file()) {
    for (const std::string& dependency : file.dependency()) {
      EXPECT_NE(std::find(names.begin(), names.end(), dependency), names.end())
          << file.name() << " before " << dependency;
    }
    names.push_back(file.name());
  }
  EXPECT_EQ(names.back(), "foxglove/SceneUpdate.proto");
  EXPECT_NE(std::find(names.begin(), names.end(), "google/protobuf/timestamp.proto"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "foxglove/CubePrimitive.proto"), names.end());
}

TEST(FoxgloveMessages, TimestampsSplitNanosecondsIncludingNegativeOnes) {
  google::protobuf::Timestamp t;
  setTime(t, 12'345'678'901);
  EXPECT_EQ(t.seconds(), 12);
  EXPECT_EQ(t.nanos(), 345'678'901);
  setTime(t, -1);
  EXPECT_EQ(t.seconds(), -1);
  EXPECT_EQ(t.nanos(), 999'999'999);
}

TEST(FoxgloveMessages, TheTransformChainIsEstimationsCameraPose) {
  hal::OdometrySample odometry;
  odometry.stamp_ns = 5'000'000'000;
  odometry.p_WB_m = {1.0, -2.0, 1.5};
  odometry.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 0.1, 1.0).normalized()));
  estimation::GimbalCameraExtrinsics extrinsics;
  extrinsics.p_BG_m = {0.08, 0.0, -0.06};
  extrinsics.T_GC.translation() = Eigen::Vector3d(0.02, 0.0, 0.01);
  extrinsics.T_GC.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()).toRotationMatrix();
  Eigen::Isometry3d T_BD = Eigen::Isometry3d::Identity();
  T_BD.translation() = Eigen::Vector3d(0.1, 0.0, 0.0);
  foxglove::FrameTransforms m;
  fillTransforms(m, odometry, 2.0, &extrinsics, &T_BD);
  ASSERT_EQ(m.transforms_size(), 5);
  Eigen::Isometry3d T_W_optical = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 4; ++i) T_W_optical = T_W_optical * toIsometry(m.transforms(i));
  EXPECT_EQ(m.transforms(3).child_frame_id(), "camera_optical");
  Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
  T_WB.linear() = odometry.q_WB.toRotationMatrix();
  T_WB.translation() = odometry.p_WB_m;
  const Eigen::Isometry3d T_WC = estimation::cameraPoseInWorld(T_WB, 2.0, extrinsics);
  EXPECT_TRUE(T_W_optical.translation().isApprox(T_WC.translation(), 1e-12));
  EXPECT_TRUE(T_W_optical.linear().isApprox(T_WC.linear() * estimation::opticalAxesInCamera(), 1e-12));
  EXPECT_EQ(m.transforms(4).child_frame_id(), "depth_optical");
  EXPECT_EQ(m.transforms(0).timestamp().seconds(), 5);
  // Without the gimbal's mounting only the body is placed.
  fillTransforms(m, odometry, 2.0, nullptr, nullptr);
  EXPECT_EQ(m.transforms_size(), 1);
}

TEST(FoxgloveMessages, TheCalibrationIsThePinholeModelOfTheFrame) {
  hal::CameraIntrinsics k;
  k.width_px = 640;
  k.height_px = 480;
  k.fx_px = 500.0;
  k.fy_px = 501.0;
  k.cx_px = 320.5;
  k.cy_px = 239.5;
  k.distortion = {0.1, -0.01, 0.0, 0.0, 0.001};
  foxglove::CameraCalibration m;
  fillCalibration(m, 7, k);
  EXPECT_EQ(m.width(), 640U);
  EXPECT_EQ(m.frame_id(), "camera_optical");
  ASSERT_EQ(m.k_size(), 9);
  ASSERT_EQ(m.p_size(), 12);
  ASSERT_EQ(m.d_size(), 5);
  const Eigen::Vector3d p_C(0.4, -0.3, 4.0);  // a point in front of the camera, optical axes
  const double u = (m.k(0) * p_C.x() + m.k(2) * p_C.z()) / p_C.z();
  const double v = (m.k(4) * p_C.y() + m.k(5) * p_C.z()) / p_C.z();
  EXPECT_DOUBLE_EQ(u, k.fx_px * 0.1 + k.cx_px);
  EXPECT_DOUBLE_EQ(v, k.fy_px * -0.075 + k.cy_px);
  EXPECT_DOUBLE_EQ(m.p(0), m.k(0));
  EXPECT_DOUBLE_EQ(m.p(10), 1.0);
}

TEST(FoxgloveMessages, SkeletonsDrawOnlyLimbsWhoseEndsWereFound) {
  hal::DetectionFrame frame;
  frame.stamp_ns = 3;
  frame.person_count = 2;
  frame.target_index = 1;
  for (std::size_t p = 0; p < 2; ++p) {
    for (std::size_t i = 0; i < hal::kNumKeypoints; ++i) {
      frame.persons[p].keypoints[i] = {10.0 * static_cast<double>(i), 5.0 * static_cast<double>(p), 0.9};
    }
  }
  frame.persons[0].keypoints[0].score = 0.05;  // the nose of person 0 not found: its 4 limbs are left out
  foxglove::ImageAnnotations m;
  fillAnnotations(m, frame, 0.2);
  ASSERT_EQ(m.points_size(), 4);  // limbs and joints of each person
  EXPECT_EQ(m.points(0).points_size(), 2 * (18 - 4));
  EXPECT_EQ(m.points(1).points_size(), 16);
  EXPECT_EQ(m.points(2).points_size(), 2 * 18);
  ASSERT_EQ(m.texts_size(), 2);
  EXPECT_EQ(m.texts(1).text().rfind("target", 0), 0U);
  EXPECT_EQ(m.texts(0).text().rfind("person", 0), 0U);
  EXPECT_GT(m.points(2).outline_color().g(), m.points(0).outline_color().g());  // the followed one in green
}

TEST(FoxgloveMessages, TheUncertaintyEllipsoidSpansTwoSigmaAlongTheCovariancesAxes) {
  estimation::TargetEstimate e;
  e.stamp_ns = 1;
  e.initialised = true;
  e.lost = false;
  e.p_WT_m = {2.0, 1.0, 0.9};
  e.v_WT_mps = {1.0, 0.0, 0.0};
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  e.covariance.setIdentity();
  e.covariance.topLeftCorner<3, 3>() = R * Eigen::Vector3d(0.04, 0.01, 0.0025).asDiagonal() * R.transpose();
  foxglove::SceneUpdate m;
  fillEstimate(m, e);
  ASSERT_EQ(m.entities_size(), 1);
  const foxglove::SceneEntity& entity = m.entities(0);
  ASSERT_EQ(entity.spheres_size(), 2);
  ASSERT_EQ(entity.arrows_size(), 1);
  const foxglove::SpherePrimitive& ellipsoid = entity.spheres(1);
  const Eigen::Quaterniond q(ellipsoid.pose().orientation().w(), ellipsoid.pose().orientation().x(),
                             ellipsoid.pose().orientation().y(), ellipsoid.pose().orientation().z());
  const Eigen::Vector3d size(ellipsoid.size().x(), ellipsoid.size().y(), ellipsoid.size().z());
  // The ellipsoid's axes scaled to half its size give back the covariance: (size/4)^2 = sigma^2.
  const Eigen::Matrix3d S =
      q.toRotationMatrix() * (size / 4.0).cwiseAbs2().asDiagonal() * q.toRotationMatrix().transpose();
  EXPECT_TRUE(S.isApprox(e.covariance.topLeftCorner<3, 3>(), 1e-9)) << S;
  EXPECT_NEAR(entity.arrows(0).shaft_length(), 1.0, 1e-12);
  e.initialised = false;
  fillEstimate(m, e);
  EXPECT_EQ(m.entities(0).spheres_size(), 0);  // nothing to draw, the entity still replaces the old one
}

TEST(FoxgloveMessages, DepthPointsAreTheDepthImageBackProjected) {
  hal::DepthFrame frame;
  frame.stamp_ns = 9;
  frame.intrinsics.fx_px = 100.0;
  frame.intrinsics.fy_px = 100.0;
  frame.intrinsics.cx_px = 8.0;
  frame.intrinsics.cy_px = 6.0;
  frame.depth_m = cv::Mat(12, 16, CV_32FC1, cv::Scalar(2.0));
  frame.depth_m.at<float>(0, 0) = 0.0F;                                     // no return
  frame.depth_m.at<float>(0, 4) = std::numeric_limits<float>::quiet_NaN();  // no return
  foxglove::PointCloud m;
  fillDepthPoints(m, frame, 4);
  ASSERT_EQ(m.point_stride(), 12U);
  ASSERT_EQ(m.data().size() % 12, 0U);
  EXPECT_EQ(m.data().size() / 12, 4U * 3U - 2U);
  float xyz[3];
  std::memcpy(xyz, m.data().data(), sizeof(xyz));  // the first point: pixel (8, 0)
  EXPECT_FLOAT_EQ(xyz[0], 0.0F);
  EXPECT_FLOAT_EQ(xyz[1], -0.12F);
  EXPECT_FLOAT_EQ(xyz[2], 2.0F);
}

TEST(FoxgloveMessages, APlanShowsItsBoxesSearchAndPrediction) {
  planning::PlanSnapshot plan;
  plan.stamp_ns = 4;
  plan.box_count = 3;
  for (std::size_t i = 0; i < 3; ++i) {
    plan.box_lo_W_m[i] = Eigen::Vector3d::Constant(static_cast<double>(i));
    plan.box_hi_W_m[i] = Eigen::Vector3d::Constant(static_cast<double>(i) + 1.5);
  }
  plan.search_count = 10;
  plan.prediction_count = 0;
  foxglove::SceneUpdate m;
  fillPlan(m, plan);
  ASSERT_EQ(m.entities_size(), 3);
  EXPECT_EQ(m.entities(0).cubes_size(), 3);
  EXPECT_DOUBLE_EQ(m.entities(0).cubes(1).size().x(), 1.5);
  EXPECT_DOUBLE_EQ(m.entities(0).cubes(1).pose().position().x(), 1.75);
  EXPECT_EQ(m.entities(1).lines(0).points_size(), 10);
  EXPECT_EQ(m.entities(2).lines_size(), 0);  // no prediction this cycle: the old one is replaced by nothing
}

}  // namespace
}  // namespace aerotrack::app::foxglove_log

namespace aerotrack::app::foxglove_log {
namespace {

TEST(FoxgloveMessages, TheFlownPathIsWrittenInStretchesThatJoinAndCarryTheirOdometrysTime) {
  FlownPath path(1.0);
  foxglove::SceneUpdate scene;
  std::vector<foxglove::SceneUpdate> written;
  for (int i = 0; i <= 250; ++i) {  // 2.5 s of odometry at 100 Hz
    const rt::TimeNs stamp_ns = rt::secondsToNs(0.01 * i);
    if (path.add(stamp_ns, Eigen::Vector3d(0.01 * i, 0, 1), scene)) written.push_back(scene);
  }
  ASSERT_EQ(written.size(), 2U);   // at 1 s and 2 s
  ASSERT_TRUE(path.flush(scene));  // 2 s .. 2.5 s
  written.push_back(scene);
  EXPECT_FALSE(path.flush(scene));  // nothing left but the joint
  for (std::size_t k = 0; k < written.size(); ++k) {
    const foxglove::SceneEntity& e = written[k].entities(0);
    EXPECT_EQ(e.id(), "path/" + std::to_string(k));
    const auto& points = e.lines(0).points();
    EXPECT_EQ(e.timestamp().seconds() * 1000000000LL + e.timestamp().nanos(),
              rt::secondsToNs(0.01 * std::round(100.0 * points[points.size() - 1].x())));
    if (k > 0) {  // each stretch starts where the last ended
      const auto& before = written[k - 1].entities(0).lines(0).points();
      EXPECT_EQ(points[0].x(), before[before.size() - 1].x());
    }
  }
  EXPECT_EQ(path.lastStampNs(), rt::secondsToNs(2.5));
}

TEST(FoxgloveMessages, ARecordedTrajectoryLooksLikeTheLiveOne) {
  foxglove::SceneUpdate recorded, live;
  const std::vector<Eigen::Vector3d> points{{0, 0, 1}, {1, 0, 1}};
  fillTrajectoryPoints(recorded, 5, points);
  fillTrajectory(live, 5, trajectory_server::TimedTrajectory{}, 4);  // no trajectory: the entity alone
  EXPECT_EQ(recorded.entities(0).id(), live.entities(0).id());
  ASSERT_EQ(recorded.entities(0).lines_size(), 1);
  EXPECT_EQ(recorded.entities(0).lines(0).points_size(), 2);
  EXPECT_FLOAT_EQ(static_cast<float>(recorded.entities(0).lines(0).color().b()), 0.9F);  // cyan, not the path's green
}

}  // namespace
}  // namespace aerotrack::app::foxglove_log
