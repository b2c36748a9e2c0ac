// The geometric controller (hal/sim/geometric_controller.hpp) flying the quadrotor model in closed
// loop at 500 Hz: hover, a 1 m step, a circle with feed-forward, yaw through +-pi, the saturation
// order, the feed-forward body rate against finite differences, and bit-for-bit determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>

#include <Eigen/Geometry>

#include "../../../support/require.hpp"
#include "aerotrack/hal/sim/geometric_controller.hpp"
#include "aerotrack/hal/sim/so3.hpp"

namespace aerotrack::hal::sim {
namespace {

constexpr double kDtS = 0.002;  // physics and controller step, 500 Hz

double tiltRad(const Eigen::Matrix3d& R) {
  return std::acos(std::clamp(R(2, 2), -1.0, 1.0));
}

double yawRad(const Eigen::Matrix3d& R) {
  return std::atan2(R(1, 0), R(0, 0));
}

double wrap(double angle_rad) {
  return std::remainder(angle_rad, 2.0 * M_PI);
}

/// A quadrotor hovering at p with the given yaw, and the controller (default parameters).
struct Loop {
  Quadrotor quad;
  GeometricController controller;

  static Loop hovering(const Eigen::Vector3d& p_W_m, double yaw_rad, const QuadrotorParams& params = {}) {
    QuadrotorState s;
    s.p_W_m = p_W_m;
    s.R_WB = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    s.thrust_n = params.mass_kg * params.gravity_mps2;
    return Loop{aerotrack::test::require(Quadrotor::create(params, s), "Quadrotor::create"),
                aerotrack::test::require(GeometricController::create(GeometricControllerParams{}, params),
                                         "GeometricController::create")};
  }

  /// Flies for n steps; the setpoint is a function of time since the start; `each` sees every step.
  void fly(int n, const std::function<Setpoint(double)>& setpoint_at,
           const std::function<void(double, const QuadrotorCommand&, const QuadrotorState&)>& each = {}) {
    for (int k = 0; k < n; ++k) {
      const QuadrotorCommand command = controller.update(setpoint_at(k * kDtS), quad.state());
      quad.step(command, kDtS);
      if (each) each((k + 1) * kDtS, command, quad.state());
    }
  }
};

Setpoint hold(const Eigen::Vector3d& p_W_m, double yaw_rad) {
  Setpoint sp;
  sp.p_W_m = p_W_m;
  sp.yaw_rad = yaw_rad;
  return sp;
}

TEST(GeometricController, GivenVehicleAtSetpointWhenFlownForTwoSecondsThenHoldsPositionWithHoverThrust) {
  // Position within 1 mm after 2 s, thrust within 0.1 % of m g.
  const Eigen::Vector3d p(1.0, -2.0, 3.0);
  Loop loop = Loop::hovering(p, 0.4);
  QuadrotorCommand last;
  loop.fly(
      1000, [&](double) { return hold(p, 0.4); },
      [&](double, const QuadrotorCommand& c, const QuadrotorState&) { last = c; });
  const double mg = 9.81;
  EXPECT_LT((loop.quad.state().p_W_m - p).norm(), 1e-3);
  EXPECT_NEAR(loop.quad.state().thrust_n, mg, 1e-3 * mg);
  EXPECT_NEAR(last.thrust_n, mg, 1e-3 * mg);
}

TEST(GeometricController, GivenOneMetreStepInXWhenFlownThenSettlesQuicklyWithinTiltAndRateLimits) {
  // Settles within 2 % (2 cm) in under 3 s, overshoot under 20 %, tilt never above max_tilt_rad,
  // commanded rates never beyond the vehicle's limits, altitude kept within 5 cm.
  const QuadrotorParams vehicle;
  Loop loop = Loop::hovering({0.0, 0.0, 2.0}, 0.0);
  double max_x = 0.0, settle_s = 0.0, max_tilt = 0.0, max_z_error = 0.0;
  Eigen::Vector3d max_rate = Eigen::Vector3d::Zero();
  loop.fly(
      2500,
      [](double) {
        return hold({1.0, 0.0, 2.0}, 0.0);
      },
      [&](double t, const QuadrotorCommand& c, const QuadrotorState& s) {
        max_x = std::max(max_x, s.p_W_m.x());
        if (std::abs(s.p_W_m.x() - 1.0) > 0.02) settle_s = t;
        max_tilt = std::max(max_tilt, tiltRad(s.R_WB));
        max_z_error = std::max(max_z_error, std::abs(s.p_W_m.z() - 2.0));
        max_rate = max_rate.cwiseMax(c.w_B_radps.cwiseAbs());
      });
  RecordProperty("overshoot_m", std::to_string(max_x - 1.0));
  RecordProperty("settle_s", std::to_string(settle_s));
  RecordProperty("max_tilt_rad", std::to_string(max_tilt));
  EXPECT_LT(settle_s, 3.0);
  EXPECT_LT(max_x - 1.0, 0.2);
  EXPECT_LE(max_tilt, GeometricControllerParams{}.max_tilt_rad);
  EXPECT_LT(max_z_error, 0.05);
  for (int i = 0; i < 3; ++i) EXPECT_LE(max_rate[i], vehicle.max_body_rate_radps[i]);
  std::printf(
      "step: overshoot %.4f m, settled (2 %%) at %.3f s, max tilt %.3f rad, max |z err| %.4f m, "
      "max rates %.2f %.2f %.2f rad/s\n",
      max_x - 1.0, settle_s, max_tilt, max_z_error, max_rate.x(), max_rate.y(), max_rate.z());
}

TEST(GeometricController, GivenTenMetreStepWhenFlownThenTiltSaturatesAndAltitudeIsHeld) {
  // The desired acceleration (60 m/s^2) is far beyond the tilt limit: the tilt rides the limit
  // (overshooting it by at most 0.01 rad through the rate-loop lag), altitude stays within 10 cm,
  // and the vehicle still arrives (within 20 cm of 10 m after 4 s, no overshoot beyond 2 %).
  Loop loop = Loop::hovering({0.0, 0.0, 2.0}, 0.0);
  double max_x = 0.0, max_tilt = 0.0, max_z_error = 0.0;
  loop.fly(
      2000,
      [](double) {
        return hold({10.0, 0.0, 2.0}, 0.0);
      },
      [&](double, const QuadrotorCommand&, const QuadrotorState& s) {
        max_x = std::max(max_x, s.p_W_m.x());
        max_tilt = std::max(max_tilt, tiltRad(s.R_WB));
        max_z_error = std::max(max_z_error, std::abs(s.p_W_m.z() - 2.0));
      });
  const double max_tilt_rad = GeometricControllerParams{}.max_tilt_rad;
  EXPECT_GT(max_tilt, max_tilt_rad - 0.01);
  EXPECT_LT(max_tilt, max_tilt_rad + 0.01);
  EXPECT_LT(max_z_error, 0.10);
  EXPECT_NEAR(loop.quad.state().p_W_m.x(), 10.0, 0.2);
  EXPECT_LT(max_x, 10.2);
  std::printf("10 m step: max tilt %.4f rad, max |z err| %.4f m\n", max_tilt, max_z_error);
}

TEST(GeometricController, GivenCircleWithFeedForwardWhenFlownThenSteadyStateErrorIsSmall) {
  // Radius 3 m at 2 m/s (0.67 rad/s, 1.33 m/s^2) with v and a feed-forward, starting at rest on the
  // circle: the largest position error during the second lap is under 0.10 m.
  const double radius = 3.0, speed = 2.0, omega = speed / radius, lap_s = 2.0 * M_PI / omega;
  const Eigen::Vector3d centre(1.0, 2.0, 3.0);
  const auto circle = [&](double t) {
    Setpoint sp;
    sp.p_W_m = centre + radius * Eigen::Vector3d(std::cos(omega * t), std::sin(omega * t), 0.0);
    sp.v_W_mps = radius * omega * Eigen::Vector3d(-std::sin(omega * t), std::cos(omega * t), 0.0);
    sp.a_W_mps2 = -radius * omega * omega * Eigen::Vector3d(std::cos(omega * t), std::sin(omega * t), 0.0);
    return sp;
  };
  Loop loop = Loop::hovering(circle(0.0).p_W_m, 0.0);
  double max_error = 0.0;
  loop.fly(static_cast<int>(2.0 * lap_s / kDtS), circle,
           [&](double t, const QuadrotorCommand&, const QuadrotorState& s) {
             if (t >= lap_s) max_error = std::max(max_error, (s.p_W_m - circle(t).p_W_m).norm());
           });
  RecordProperty("circle_max_error_m", std::to_string(max_error));
  std::printf("circle: max error in the second lap %.4f m\n", max_error);
  EXPECT_LT(max_error, 0.10);
}

TEST(GeometricController, GivenYawSetpointAcrossPiWhenFlownThenTurnsTheShortWay) {
  // From yaw 3.0 to -3.0 rad: the short way is +0.283 rad through +pi. The unwrapped yaw never goes
  // below 3.0 - 0.01 (no turn the long way) and ends within 1e-3 rad of the setpoint after 2 s.
  Loop loop = Loop::hovering({0.0, 0.0, 2.0}, 3.0);
  double unwrapped = 3.0, previous = 3.0, min_unwrapped = 3.0;
  loop.fly(
      1000,
      [](double) {
        return hold({0.0, 0.0, 2.0}, -3.0);
      },
      [&](double, const QuadrotorCommand&, const QuadrotorState& s) {
        const double yaw = yawRad(s.R_WB);
        unwrapped += wrap(yaw - previous);
        previous = yaw;
        min_unwrapped = std::min(min_unwrapped, unwrapped);
      });
  EXPECT_GT(min_unwrapped, 3.0 - 0.01);
  EXPECT_NEAR(unwrapped, 3.0 + wrap(-3.0 - 3.0), 1e-3);
  EXPECT_NEAR(wrap(yawRad(loop.quad.state().R_WB) + 3.0), 0.0, 1e-3);
}

TEST(GeometricController, GivenYawRampThroughPiWithRateFeedForwardWhenFlownThenTracksClosely) {
  // yaw(t) = wrap(2.5 + 1.0 t) with yaw_rate 1 rad/s, crossing +-pi at t = 0.64 s: after 0.5 s the
  // wrapped yaw error stays under 5e-3 rad.
  Loop loop = Loop::hovering({0.0, 0.0, 2.0}, 2.5);
  const auto ramp = [](double t) {
    Setpoint sp = hold({0.0, 0.0, 2.0}, wrap(2.5 + t));
    sp.yaw_rate_radps = 1.0;
    return sp;
  };
  double max_error = 0.0;
  loop.fly(1000, ramp, [&](double t, const QuadrotorCommand&, const QuadrotorState& s) {
    if (t >= 0.5) max_error = std::max(max_error, std::abs(wrap(yawRad(s.R_WB) - ramp(t).yaw_rad)));
  });
  std::printf("yaw ramp: max error %.5f rad\n", max_error);
  EXPECT_LT(max_error, 5e-3);
}

TEST(GeometricController, GivenYawRateAndTiltWhenReferenceComputedThenFeedForwardRateMatchesFiniteDifference) {
  // The feed-forward rate w_d of R_d(t) for a tilted reference (constant acceleration setpoint) and a
  // yaw ramp vs log(R_d(t - h)^T R_d(t + h)) / 2h, h = 1e-5 s: tolerance 1e-8 rad/s.
  auto controller = GeometricController::create(GeometricControllerParams{}, QuadrotorParams{});
  ASSERT_TRUE(controller.has_value());
  QuadrotorState estimate;
  estimate.p_W_m = {0.0, 0.0, 5.0};
  const auto setpoint = [&](double t) {
    Setpoint sp = hold(estimate.p_W_m, 0.3 + 0.8 * t);
    sp.yaw_rate_radps = 0.8;
    sp.a_W_mps2 = {3.0, 1.5, -1.0};
    return sp;
  };
  for (const double t : {0.0, 0.7, 2.2, 3.9}) {
    const double h = 1e-5;
    const AttitudeReference ref = controller->reference(setpoint(t), estimate);
    const Eigen::Matrix3d before = controller->reference(setpoint(t - h), estimate).R_WBd;
    const Eigen::Matrix3d after = controller->reference(setpoint(t + h), estimate).R_WBd;
    const Eigen::Vector3d numeric = so3::logMap(before.transpose() * after) / (2.0 * h);
    EXPECT_LT((numeric - ref.w_Bd_radps).norm(), 1e-8) << "t = " << t << ": " << numeric.transpose();
    EXPECT_GT(tiltRad(ref.R_WBd), 0.3);  // genuinely tilted, where yaw_rate (z_W . z_B) would be off
  }
}

TEST(GeometricController, GivenUnreachableAccelerationWhenReferenceComputedThenAltitudeComesFirst) {
  // Tolerances 1e-12: exact limits.
  const QuadrotorParams vehicle;
  const GeometricControllerParams params;
  auto controller = GeometricController::create(params, vehicle);
  ASSERT_TRUE(controller.has_value());
  const QuadrotorState hover;
  // Far too much horizontal: vertical kept at g, tilt at its limit, horizontal direction kept.
  Setpoint sideways;
  sideways.a_W_mps2 = {40.0, 30.0, 0.0};
  AttitudeReference ref = controller->reference(sideways, hover);
  EXPECT_NEAR(ref.thrust_accel_W_mps2.z(), vehicle.gravity_mps2, 1e-12);
  EXPECT_NEAR(tiltRad(ref.R_WBd), params.max_tilt_rad, 1e-12);
  EXPECT_NEAR(ref.thrust_accel_W_mps2.y() / ref.thrust_accel_W_mps2.x(), 0.75, 1e-12);
  // Climbing hard and sideways: vertical kept, horizontal shortened to fit the thrust limit.
  Setpoint climb;
  climb.a_W_mps2 = {30.0, 0.0, 12.0};
  ref = controller->reference(climb, hover);
  const double a_max = vehicle.max_thrust_n / vehicle.mass_kg;
  EXPECT_NEAR(ref.thrust_accel_W_mps2.z(), 12.0 + vehicle.gravity_mps2, 1e-12);
  EXPECT_NEAR(ref.thrust_accel_W_mps2.norm(), a_max, 1e-12);
  EXPECT_LE(tiltRad(ref.R_WBd), params.max_tilt_rad);
  // More than the thrust can give straight up: straight up at full thrust.
  Setpoint rocket;
  rocket.a_W_mps2 = {5.0, 0.0, 100.0};
  ref = controller->reference(rocket, hover);
  EXPECT_LT((ref.thrust_accel_W_mps2 - Eigen::Vector3d(0.0, 0.0, a_max)).norm(), 1e-12);
  EXPECT_NEAR(controller->update(rocket, hover).thrust_n, vehicle.max_thrust_n, 1e-12);
  // Falling faster than gravity: the minimum vertical specific thrust, level, thrust at its floor.
  Setpoint dive;
  dive.a_W_mps2 = {0.0, 0.0, -20.0};
  ref = controller->reference(dive, hover);
  EXPECT_NEAR(ref.thrust_accel_W_mps2.z(), GeometricController::kMinVerticalAccelMps2, 1e-12);
}

TEST(GeometricController, GivenLargeAttitudeErrorsWhenUpdatedThenCommandsStayWithinLimits) {
  // Upside down, on its side, yawed by pi: every output within the vehicle's limits (exact).
  const QuadrotorParams vehicle;
  auto controller = GeometricController::create(GeometricControllerParams{}, vehicle);
  ASSERT_TRUE(controller.has_value());
  for (const Eigen::Matrix3d& R : {Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix(),
                                   Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix(),
                                   Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
                                   Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, 1, 1).normalized()).toRotationMatrix()}) {
    QuadrotorState s;
    s.R_WB = R;
    s.p_W_m = {0.0, 0.0, 3.0};
    Setpoint sp = hold({5.0, -5.0, 1.0}, 1.0);
    sp.yaw_rate_radps = 10.0;
    const QuadrotorCommand c = controller->update(sp, s);
    EXPECT_TRUE(c.w_B_radps.allFinite() && std::isfinite(c.thrust_n));
    for (int i = 0; i < 3; ++i) EXPECT_LE(std::abs(c.w_B_radps[i]), vehicle.max_body_rate_radps[i]);
    EXPECT_GE(c.thrust_n, vehicle.min_thrust_n);
    EXPECT_LE(c.thrust_n, vehicle.max_thrust_n);
  }
}

TEST(GeometricController, GivenSameInputsWhenFlownTwiceThenStatesAreBitForBitEqual) {
  // 5 s of a moving, yawing setpoint, twice: every double of the final state identical.
  const auto moving = [](double t) {
    Setpoint sp = hold({std::sin(t), 2.0 * std::cos(0.5 * t), 2.0 + 0.3 * t}, wrap(3.0 + 1.5 * t));
    sp.v_W_mps = {std::cos(t), -std::sin(0.5 * t), 0.3};
    sp.yaw_rate_radps = 1.5;
    return sp;
  };
  Loop first = Loop::hovering({0.0, 2.0, 2.0}, 3.0);
  Loop second = Loop::hovering({0.0, 2.0, 2.0}, 3.0);
  first.fly(2500, moving);
  second.fly(2500, moving);
  const QuadrotorState& a = first.quad.state();
  const QuadrotorState& b = second.quad.state();
  const auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(bits(a.p_W_m[i]), bits(b.p_W_m[i]));
    EXPECT_EQ(bits(a.v_W_mps[i]), bits(b.v_W_mps[i]));
    EXPECT_EQ(bits(a.w_B_radps[i]), bits(b.w_B_radps[i]));
    EXPECT_EQ(bits(a.a_W_mps2[i]), bits(b.a_W_mps2[i]));
  }
  for (int i = 0; i < 9; ++i) EXPECT_EQ(bits(a.R_WB.data()[i]), bits(b.R_WB.data()[i]));
  EXPECT_EQ(bits(a.thrust_n), bits(b.thrust_n));
  EXPECT_EQ(a.on_ground, b.on_ground);
}

TEST(GeometricController, GivenInvalidParametersWhenCreatedThenReturnsError) {
  GeometricControllerParams tilt;
  tilt.max_tilt_rad = 1.6;
  EXPECT_FALSE(GeometricController::create(tilt, QuadrotorParams{}).has_value());
  GeometricControllerParams gain;
  gain.attitude_gain_per_s.z() = 0.0;
  EXPECT_FALSE(GeometricController::create(gain, QuadrotorParams{}).has_value());
  GeometricControllerParams kp;
  kp.position_gain_per_s2.x() = -1.0;
  EXPECT_FALSE(GeometricController::create(kp, QuadrotorParams{}).has_value());
  QuadrotorParams vehicle;
  vehicle.mass_kg = -1.0;
  EXPECT_FALSE(GeometricController::create(GeometricControllerParams{}, vehicle).has_value());
}

}  // namespace
}  // namespace aerotrack::hal::sim
