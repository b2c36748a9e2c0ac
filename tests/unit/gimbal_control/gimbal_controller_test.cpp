// Gimbal control against a simulated 1-DOF gimbal (an integrator of the commanded rate, rate-limited
// like the motor) on a body that may spin: the error converges, the feed-forward cancels the body's yaw
// rate and follows a walking person, the gimbal spins without limit and never unwinds, the integral
// does not wind up, and a lost person is looked for where predicted, then swept for the right way round.
#include "aerotrack/gimbal_control/gimbal_controller.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Geometry>

namespace aerotrack::gimbal_control {
namespace {

constexpr double kDt = 0.005;  // 200 Hz

struct Rig {
  GimbalControlParams params;
  estimation::GimbalCameraExtrinsics extrinsics;
  GimbalController controller{params, extrinsics};
  hal::GimbalState gimbal;
  hal::OdometrySample odometry;
  estimation::TargetEstimate target;
  double body_yaw_rad = 0.0;
  double body_yaw_rate_radps = 0.0;
  Eigen::Vector3d body_velocity = Eigen::Vector3d::Zero();
  double t_s = 0.0;

  explicit Rig(const GimbalControlParams& p = GimbalControlParams{}) : params(p), controller(p, extrinsics) {
    odometry.p_WB_m = Eigen::Vector3d(0, 0, 1.5);
    target.initialised = true;
    target.lost = false;
  }
  /// One 5 ms step: the controller commands, the gimbal turns at the (limited) command, the body yaws.
  GimbalOutput step(bool search = false) {
    const rt::TimeNs now_ns = rt::secondsToNs(t_s);
    gimbal.stamp_ns = now_ns;
    odometry.stamp_ns = now_ns;
    odometry.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(body_yaw_rad, Eigen::Vector3d::UnitZ()));
    odometry.w_WB_B_radps = Eigen::Vector3d(0, 0, body_yaw_rate_radps);
    odometry.v_WB_mps = body_velocity;
    target.stamp_ns = now_ns;
    if (!target.lost) target.last_accepted_ns = now_ns;  // detections keep coming while not lost
    GimbalInputs in;
    in.now_ns = now_ns;
    in.gimbal = &gimbal;
    in.odometry = &odometry;
    in.target = &target;
    in.search_requested = search;
    const GimbalOutput out = controller.update(in);
    const double rate = std::clamp(out.command.rate_radps, -params.max_rate_radps, params.max_rate_radps);
    gimbal.angle_rad += rate * kDt;
    gimbal.rate_radps = rate;
    body_yaw_rad += body_yaw_rate_radps * kDt;
    odometry.p_WB_m += body_velocity * kDt;
    target.p_WT_m += target.v_WT_mps * kDt;
    t_s += kDt;
    return out;
  }
  double error() const {
    Eigen::Isometry3d T_WB = Eigen::Isometry3d::Identity();
    T_WB.linear() = Eigen::AngleAxisd(body_yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T_WB.translation() = odometry.p_WB_m;
    return horizontalBearingError(estimation::cameraPoseInWorld(T_WB, gimbal.angle_rad, extrinsics), target.p_WT_m);
  }
};

TEST(GimbalController, BearingErrorIsPositiveToTheLeft) {
  const Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  EXPECT_NEAR(horizontalBearingError(T_WC, Eigen::Vector3d(1, 1, 0)), M_PI / 4, 1e-12);
  EXPECT_NEAR(horizontalBearingError(T_WC, Eigen::Vector3d(1, -1, 5)), -M_PI / 4, 1e-12);
  EXPECT_NEAR(std::abs(horizontalBearingError(T_WC, Eigen::Vector3d(-1, 0, 0))), M_PI, 1e-12);
}

TEST(GimbalController, ConvergesOnAStandingPersonTheShortWay) {
  Rig rig;
  rig.target.p_WT_m = Eigen::Vector3d(0.0, -4.0, 1.0);  // 90 degrees to the right
  for (int k = 0; k < 600; ++k) {                       // 3 s
    const GimbalOutput out = rig.step();
    EXPECT_EQ(out.mode, GimbalMode::kTrack);
    EXPECT_LE(rig.gimbal.angle_rad, 1e-9) << "turned the long way at step " << k;
    EXPECT_GE(rig.gimbal.angle_rad, -M_PI / 2 - 0.1) << "overshot at step " << k;  // < 6 degrees
  }
  EXPECT_LT(std::abs(rig.error()), 1e-3);
  EXPECT_NEAR(rig.gimbal.angle_rad, -M_PI / 2, 1e-3);
}

TEST(GimbalController, FeedForwardCancelsTheBodysYawRate) {
  for (const bool ff : {true, false}) {
    GimbalControlParams p;
    p.feed_forward = ff;
    Rig rig(p);
    rig.target.p_WT_m = Eigen::Vector3d(4.0, 0.0, 1.0);
    rig.body_yaw_rate_radps = 1.5;  // the drone turns; the camera must not
    double worst = 0.0;
    for (int k = 0; k < 1000; ++k) {
      rig.step();
      if (k > 400) worst = std::max(worst, std::abs(rig.error()));
    }
    if (ff) {
      EXPECT_LT(worst, 1e-3);
    } else {
      EXPECT_LT(worst, 0.05);  // the integral alone catches up, a little behind at first
    }
  }
}

TEST(GimbalController, FollowsAPersonWalkingAcrossAndSpinsWithoutUnwinding) {
  Rig rig;
  // The person walks a circle of radius 3 m around the drone at 1.5 m/s: three turns in 37.7 s.
  const double radius = 3.0, speed = 1.5;
  double worst = 0.0;
  const int steps = static_cast<int>(3 * 2 * M_PI * radius / speed / kDt);
  for (int k = 0; k < steps; ++k) {
    const double angle = speed * rig.t_s / radius;
    rig.target.p_WT_m = Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), 1.0);
    rig.target.v_WT_mps = Eigen::Vector3d(-speed * std::sin(angle), speed * std::cos(angle), 0.0);
    rig.step();
    if (k > 100) worst = std::max(worst, std::abs(rig.error()));
  }
  EXPECT_LT(worst, 0.01);
  EXPECT_NEAR(rig.gimbal.angle_rad, 6 * M_PI, 0.05);  // three whole turns, unwrapped
}

TEST(GimbalController, IntegralDoesNotWindUpWhileSaturated) {
  GimbalControlParams p;
  p.max_rate_radps = 0.5;  // slow motor: saturated for seconds on a half turn
  p.sweep_rate_radps = 0.5;
  Rig rig(p);
  rig.target.p_WT_m = Eigen::Vector3d(-4.0, 0.1, 1.0);  // almost behind, slightly left
  double overshoot = 0.0;
  for (int k = 0; k < 3000; ++k) {
    rig.step();
    EXPECT_LE(std::abs(rig.controller.integralRadS()), p.integral_limit_rad_s + 1e-12);
    if (rig.gimbal.angle_rad > M_PI) overshoot = std::max(overshoot, rig.gimbal.angle_rad - M_PI + 0.025);
  }
  EXPECT_LT(std::abs(rig.error()), 1e-3);
  EXPECT_LT(overshoot, 0.05);
}

TEST(GimbalController, LostPersonIsLookedForWhereTheyArePredictedThenSwept) {
  Rig rig;
  rig.target.p_WT_m = Eigen::Vector3d(4.0, -1.0, 1.0);  // to the right, walking to the left
  rig.target.v_WT_mps = Eigen::Vector3d(0.0, 1.0, 0.0);
  for (int k = 0; k < 200; ++k) rig.step();
  rig.target.lost = true;
  // First the camera stays on the prediction (the rig moves the estimate on by its velocity).
  const int look_steps = static_cast<int>(rig.params.look_at_prediction_s / kDt) - 1;
  for (int k = 0; k < look_steps; ++k) {
    ASSERT_EQ(rig.step().mode, GimbalMode::kTrack) << k;
    EXPECT_LT(std::abs(rig.error()), 0.05) << k;
  }
  // Then the sweep (its direction: the next test), a whole turn in 2 pi / sweep rate, and on.
  rig.step();
  rig.step();
  const GimbalOutput out = rig.step();
  EXPECT_EQ(out.mode, GimbalMode::kSearch);
  EXPECT_NEAR(std::abs(out.command.rate_radps), rig.params.sweep_rate_radps, 1e-9);
  const double start = rig.gimbal.angle_rad;
  for (int k = 0; k < static_cast<int>(2 * M_PI / rig.params.sweep_rate_radps / kDt); ++k) rig.step();
  EXPECT_NEAR(std::abs(rig.gimbal.angle_rad - start), 2 * M_PI, 0.05);
}

TEST(GimbalController, WithoutLookingAtThePredictionALostPersonIsSweptForAtOnceTowardsWhereTheyWereSeen) {
  GimbalControlParams params;
  params.look_at_prediction_s = 0.0;
  Rig rig(params);
  rig.target.p_WT_m = Eigen::Vector3d(4.0, -1.0, 1.0);  // to the right
  for (int k = 0; k < 20; ++k) rig.step();
  rig.target.lost = true;
  const GimbalOutput out = rig.step();
  EXPECT_EQ(out.mode, GimbalMode::kSearch);
  EXPECT_NEAR(out.command.rate_radps, -rig.params.sweep_rate_radps, 1e-9);  // to the right
}

TEST(GimbalController, BearingSigmaIsTheCovarianceAcrossTheLineOfSightOverTheRange) {
  estimation::TargetEstimate target;
  target.p_WT_m = Eigen::Vector3d(4.0, 0.0, 1.0);  // straight ahead: "across" is y
  target.covariance.setZero();
  target.covariance(0, 0) = 100.0;  // along the line of sight: does not matter
  target.covariance(1, 1) = 1.0;
  EXPECT_NEAR(bearingSigmaRad(Eigen::Isometry3d::Identity(), target), std::atan(0.25), 1e-12);
}

TEST(GimbalController, AnUncertainPredictionIsNotLookedAtButSweptFor) {
  Rig rig;
  rig.target.p_WT_m = Eigen::Vector3d(4.0, -1.0, 1.0);
  for (int k = 0; k < 20; ++k) rig.step();
  rig.target.lost = true;
  rig.target.covariance = 0.25 * Eigen::Matrix<double, 6, 6>::Identity();  // 0.5 m at ~4 m: still sharp
  EXPECT_EQ(rig.step().mode, GimbalMode::kTrack);
  rig.target.covariance = 9.0 * Eigen::Matrix<double, 6, 6>::Identity();  // 3 m at ~4 m: could be anywhere
  EXPECT_EQ(rig.step().mode, GimbalMode::kSearch);
}

TEST(GimbalController, SupervisorsSweepRequestWaitsUntilThePredictionIsOld) {
  Rig rig;
  rig.target.p_WT_m = Eigen::Vector3d(4.0, 1.0, 1.0);
  for (int k = 0; k < 20; ++k) rig.step();
  // Detections still arrive: the request does not turn the camera away from the person.
  EXPECT_EQ(rig.step(true).mode, GimbalMode::kTrack);
  // None for longer than look_at_prediction_s: the sweep starts.
  rig.target.lost = true;
  rig.target.last_accepted_ns = rig.target.stamp_ns - rt::secondsToNs(rig.params.look_at_prediction_s + 0.01);
  EXPECT_EQ(rig.step(true).mode, GimbalMode::kSearch);
}

TEST(GimbalController, MissingInputsCommandNothing) {
  GimbalController controller(GimbalControlParams{}, estimation::GimbalCameraExtrinsics{});
  GimbalInputs in;
  const GimbalOutput out = controller.update(in);
  EXPECT_EQ(out.mode, GimbalMode::kIdle);
  EXPECT_EQ(out.command.rate_radps, 0.0);
}

TEST(GimbalControlParams, EveryKeyIsRequiredAndChecked) {
  const std::string good =
      "g:\n  kp_per_s: 6.0\n  ki_per_s2: 9.0\n  integral_limit_rad_s: 0.2\n  integral_zone_rad: 0.3\n  max_rate_radps: "
      "4.0\n"
      "  sweep_rate_radps: 2.0\n  feed_forward: true\n  max_estimate_age_s: 0.5\n  look_at_prediction_s: 5.0\n  "
      "max_bearing_sigma_rad: 0.38\n";
  auto node = rt::ConfigNode::fromString(good, "g.yaml");
  ASSERT_TRUE(node.has_value());
  const GimbalControlParams p = parseGimbalControlParams(node->child("g"));
  EXPECT_TRUE(validate(p).has_value());
  EXPECT_EQ(p.kp_per_s, 6.0);
  auto fast_sweep = rt::ConfigNode::fromString(
      "g:\n  kp_per_s: 6.0\n  ki_per_s2: 9.0\n  integral_limit_rad_s: 0.2\n  integral_zone_rad: 0.3\n  max_rate_radps: "
      "1.0\n"
      "  sweep_rate_radps: 2.0\n  feed_forward: true\n  max_estimate_age_s: 0.5\n  look_at_prediction_s: 5.0\n  "
      "max_bearing_sigma_rad: 0.38\n",
      "g.yaml");
  ASSERT_TRUE(fast_sweep.has_value());
  EXPECT_THROW(parseGimbalControlParams(fast_sweep->child("g")), rt::ConfigError);
  auto missing = rt::ConfigNode::fromString("g:\n  kp_per_s: 6.0\n", "g.yaml");
  ASSERT_TRUE(missing.has_value());
  EXPECT_THROW(parseGimbalControlParams(missing->child("g")), rt::ConfigError);
}

}  // namespace
}  // namespace aerotrack::gimbal_control
