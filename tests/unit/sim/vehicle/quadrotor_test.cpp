// The quadrotor model (hal/sim/quadrotor.hpp) against closed-form solutions: free fall, level climb,
// rotation at a constant rate, first-order lags, drag decay, the ground plane, command limits, and
// the reported acceleration against a finite difference of the velocity.
#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Geometry>

#include "../../../support/require.hpp"
#include "aerotrack/hal/sim/quadrotor.hpp"

namespace aerotrack::hal::sim {
namespace {

constexpr double kG = 9.81;

QuadrotorParams noDrag() {
  QuadrotorParams p;
  p.drag_B_per_s.setZero();
  return p;
}

Quadrotor make(const QuadrotorParams& params, const QuadrotorState& initial) {
  return aerotrack::test::require(Quadrotor::create(params, initial), "Quadrotor::create");
}

Eigen::Matrix3d rotation(double angle_rad, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
}

double orthonormalityError(const Eigen::Matrix3d& R) {
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
}

TEST(Quadrotor, GivenZeroThrustWhenSteppedThenFallsFreely) {
  // z(t) = z0 - g t^2 / 2 to 1e-6 m, v(t) = -g t to 1e-9 m/s; the attitude turning does not matter.
  QuadrotorState s;
  s.p_W_m = {1.0, 2.0, 100.0};
  s.R_WB = rotation(0.4, {1, 1, 0});
  s.w_B_radps = {0.5, -0.2, 1.0};
  Quadrotor quad = make(noDrag(), s);
  QuadrotorCommand command;
  command.w_B_radps = s.w_B_radps;
  const double dt_s = 0.002;
  for (int k = 1; k <= 2000; ++k) {
    quad.step(command, dt_s);
    const double t = k * dt_s;
    if (k % 250 != 0) continue;
    EXPECT_NEAR(quad.state().p_W_m.z(), 100.0 - 0.5 * kG * t * t, 1e-6) << "t = " << t;
    EXPECT_NEAR(quad.state().p_W_m.x(), 1.0, 1e-9);
    EXPECT_NEAR(quad.state().v_W_mps.z(), -kG * t, 1e-9);
    EXPECT_NEAR(quad.state().a_W_mps2.z(), -kG, 1e-12);
  }
  EXPECT_FALSE(quad.state().on_ground);
}

TEST(Quadrotor, GivenLevelThrustAboveWeightWhenSteppedFromTheGroundThenClimbsWithConstantAcceleration) {
  // z(t) = (T/m - g) t^2 / 2 to 1e-9 m, starting on the ground (lift-off in the first step).
  const double thrust_n = 1.5 * kG;
  QuadrotorState s;
  s.on_ground = true;
  s.thrust_n = thrust_n;
  Quadrotor quad = make(noDrag(), s);
  QuadrotorCommand command{thrust_n, Eigen::Vector3d::Zero()};
  const double dt_s = 0.001;
  for (int k = 1; k <= 3000; ++k) {
    quad.step(command, dt_s);
    ASSERT_FALSE(quad.state().on_ground);
    const double t = k * dt_s;
    ASSERT_NEAR(quad.state().p_W_m.z(), 0.5 * (thrust_n - kG) * t * t, 1e-9) << "t = " << t;
  }
  EXPECT_NEAR(quad.state().a_W_mps2.z(), thrust_n - kG, 1e-12);
  EXPECT_NEAR(quad.state().p_W_m.head<2>().norm(), 0.0, 1e-12);
}

TEST(Quadrotor, GivenConstantBodyRateWhenSteppedThenAttitudeIsTheExactExponential) {
  // R(t) = R0 exp(t [w]x) to 1e-9, and R stays orthonormal to 1e-13, over 2 s in 1000 steps.
  QuadrotorState s;
  s.p_W_m = {0.0, 0.0, 1000.0};
  s.R_WB = rotation(0.9, {0.2, -1.0, 0.4});
  s.w_B_radps = {1.3, -0.7, 2.1};
  s.thrust_n = kG;
  Quadrotor quad = make(QuadrotorParams{}, s);
  const QuadrotorCommand command{kG, s.w_B_radps};
  const double dt_s = 0.002;
  for (int k = 1; k <= 1000; ++k) {
    quad.step(command, dt_s);
    const double t = k * dt_s;
    const Eigen::Matrix3d expected = s.R_WB * rotation(t * s.w_B_radps.norm(), s.w_B_radps);
    ASSERT_LT((quad.state().R_WB - expected).cwiseAbs().maxCoeff(), 1e-9) << "t = " << t;
    ASSERT_LT(orthonormalityError(quad.state().R_WB), 1e-13);
  }
  EXPECT_LT((quad.state().w_B_radps - s.w_B_radps).norm(), 1e-15);
}

TEST(Quadrotor, GivenStepCommandsWhenSteppedThenThrustAndRateFollowFirstOrderLags) {
  // T(t) = Tc + (T0 - Tc) exp(-t/tau_T) to 1e-12 N, w(t) likewise, and for a rate of fixed direction
  // the turned angle is the exact integral wc t + (w0 - wc) tau (1 - exp(-t/tau)) to 1e-12 rad.
  const QuadrotorParams p;
  QuadrotorState s;
  s.p_W_m = {0.0, 0.0, 1000.0};
  s.thrust_n = 5.0;
  s.w_B_radps = {0.0, 0.0, 0.5};
  Quadrotor quad = make(p, s);
  const QuadrotorCommand command{15.0, Eigen::Vector3d(0.0, 0.0, 2.5)};
  const double dt_s = 0.001;
  for (int k = 1; k <= 200; ++k) {
    quad.step(command, dt_s);
    const double t = k * dt_s;
    const double thrust_decay = std::exp(-t / p.thrust_time_constant_s);
    const double rate_decay = std::exp(-t / p.body_rate_time_constant_s);
    ASSERT_NEAR(quad.state().thrust_n, 15.0 + (5.0 - 15.0) * thrust_decay, 1e-12);
    ASSERT_NEAR(quad.state().w_B_radps.z(), 2.5 + (0.5 - 2.5) * rate_decay, 1e-12);
    const double angle = 2.5 * t + (0.5 - 2.5) * p.body_rate_time_constant_s * (1.0 - rate_decay);
    const Eigen::Matrix3d& R = quad.state().R_WB;
    ASSERT_NEAR(std::remainder(std::atan2(R(1, 0), R(0, 0)) - angle, 2.0 * M_PI), 0.0, 1e-12) << "t = " << t;
  }
}

TEST(Quadrotor, GivenHoverThrustAndInitialVelocityWhenSteppedThenDragDecaysExponentially) {
  // Level (yawed) hover, v0 = (2, -1, 0.5): each body axis decays as v0 exp(-d t), the position
  // moves by v0 (1 - exp(-d t)) / d; tolerance 1e-12 m/s and 1e-12 m over 3 s.
  const QuadrotorParams p;
  QuadrotorState s;
  s.p_W_m = {0.0, 0.0, 50.0};
  s.v_W_mps = {2.0, -1.0, 0.5};
  s.R_WB = rotation(0.7, Eigen::Vector3d::UnitZ());
  s.thrust_n = p.mass_kg * p.gravity_mps2;
  Quadrotor quad = make(p, s);
  const QuadrotorCommand command{s.thrust_n, Eigen::Vector3d::Zero()};
  const double dt_s = 0.002;
  for (int k = 1; k <= 1500; ++k) quad.step(command, dt_s);
  const double t = 3.0;
  const double dxy = p.drag_B_per_s.x();  // x and y drag are equal, so yaw does not matter
  const double dz = p.drag_B_per_s.z();
  const Eigen::Vector3d v_expected(2.0 * std::exp(-dxy * t), -1.0 * std::exp(-dxy * t), 0.5 * std::exp(-dz * t));
  const Eigen::Vector3d dp_expected(2.0 * -std::expm1(-dxy * t) / dxy, -1.0 * -std::expm1(-dxy * t) / dxy,
                                    0.5 * -std::expm1(-dz * t) / dz);
  EXPECT_LT((quad.state().v_W_mps - v_expected).norm(), 1e-12);
  EXPECT_LT((quad.state().p_W_m - s.p_W_m - dp_expected).norm(), 1e-12);
  EXPECT_LT(
      (quad.state().a_W_mps2 - Eigen::Vector3d(-dxy * v_expected.x(), -dxy * v_expected.y(), -dz * v_expected.z()))
          .norm(),
      1e-12);
}

TEST(Quadrotor, GivenRestingOnGroundWhenThrustBelowWeightThenStaysPut) {
  // Thrust 0.5 m g with a rate command for 5 s: exactly where it was, v = 0, attitude unchanged.
  QuadrotorState s;
  s.p_W_m = {3.0, -4.0, 0.0};
  s.R_WB = rotation(1.2, Eigen::Vector3d::UnitZ());
  s.on_ground = true;
  Quadrotor quad = make(QuadrotorParams{}, s);
  const QuadrotorCommand command{0.5 * kG, Eigen::Vector3d(2.0, -1.0, 1.0)};
  for (int k = 0; k < 2500; ++k) quad.step(command, 0.002);
  EXPECT_TRUE(quad.state().on_ground);
  EXPECT_EQ(quad.state().p_W_m, s.p_W_m);
  EXPECT_EQ(quad.state().v_W_mps, Eigen::Vector3d::Zero());
  EXPECT_EQ(quad.state().a_W_mps2, Eigen::Vector3d::Zero());
  EXPECT_EQ(quad.state().R_WB, s.R_WB);
  EXPECT_NEAR(quad.state().thrust_n, 0.5 * kG, 1e-12);  // the motors still spin up
}

TEST(Quadrotor, GivenRestingOnGroundWhenThrustExceedsWeightThenLiftsOff) {
  // Thrust command 1.2 m g from 0 N: lifts off once the lagged thrust passes m g, at
  // t = -tau ln(1 - 1/1.2) = 35.8 ms (to within a step), then climbs (no drag).
  const QuadrotorParams p = noDrag();
  QuadrotorState s;
  s.on_ground = true;
  Quadrotor quad = make(p, s);
  const QuadrotorCommand command{1.2 * kG, Eigen::Vector3d::Zero()};
  const double lift_off_s = -p.thrust_time_constant_s * std::log(1.0 - 1.0 / 1.2);
  const double dt_s = 0.001;
  double first_airborne_s = -1.0;
  for (int k = 1; k <= 1000; ++k) {
    quad.step(command, dt_s);
    if (!quad.state().on_ground && first_airborne_s < 0.0) first_airborne_s = k * dt_s;
  }
  EXPECT_NEAR(first_airborne_s, lift_off_s, 1.5 * dt_s);
  EXPECT_FALSE(quad.state().on_ground);
  // Afterwards a(t) = A (1 - exp(-t/tau)) - g with A = 1.2 g; integrated twice from rest at t0, the
  // height after 1 s, to 1e-4 m (lift-off happens at a step boundary).
  const double A = 1.2 * kG, tau = p.thrust_time_constant_s, t0 = lift_off_s, t = 1.0;
  const double e0 = std::exp(-t0 / tau), e1 = std::exp(-t / tau);
  const double z_expected = 0.5 * (A - kG) * (t - t0) * (t - t0) - A * tau * (tau * (e1 - e0) + e0 * (t - t0));
  EXPECT_NEAR(quad.state().p_W_m.z(), z_expected, 1e-4);
  EXPECT_NEAR(quad.state().v_W_mps.z(), (A - kG) * (t - t0) + A * tau * (e1 - e0), 1e-4);
}

TEST(Quadrotor, GivenFallingTiltedVehicleWhenItReachesTheGroundThenItLandsLevelAndStops) {
  // From z = 1 m with no thrust: on the ground within 0.46 s, then z = 0 and v = 0 exactly, the
  // attitude levelled with its heading kept (to 1e-12 rad).
  QuadrotorState s;
  s.p_W_m = {0.0, 0.0, 1.0};
  s.v_W_mps = {1.0, 0.0, 0.0};
  s.R_WB = rotation(0.5, Eigen::Vector3d::UnitZ()) * rotation(0.2, Eigen::Vector3d::UnitX());
  Quadrotor quad = make(noDrag(), s);
  const QuadrotorCommand command{0.0, Eigen::Vector3d::Zero()};
  for (int k = 0; k < 500; ++k) quad.step(command, 0.002);
  const QuadrotorState& end = quad.state();
  EXPECT_TRUE(end.on_ground);
  EXPECT_EQ(end.p_W_m.z(), 0.0);
  EXPECT_NEAR(end.p_W_m.x(), std::sqrt(2.0 / kG), 0.003);  // slid 1 m/s for the fall time, to a step
  EXPECT_EQ(end.v_W_mps, Eigen::Vector3d::Zero());
  EXPECT_NEAR(end.R_WB(2, 2), 1.0, 1e-15);
  EXPECT_NEAR(std::atan2(end.R_WB(1, 0), end.R_WB(0, 0)), 0.5, 1e-12);
}

TEST(Quadrotor, GivenCommandsBeyondLimitsWhenSteppedThenTheyAreClamped) {
  // After 1 s (33 rate time constants) thrust and rates sit at the limits to 1e-9.
  const QuadrotorParams p;
  QuadrotorState s;
  s.p_W_m = {0.0, 0.0, 1000.0};
  s.thrust_n = kG;
  Quadrotor quad = make(p, s);
  const QuadrotorCommand command{1000.0, Eigen::Vector3d(100.0, -100.0, 100.0)};
  for (int k = 0; k < 500; ++k) quad.step(command, 0.002);
  EXPECT_NEAR(quad.state().thrust_n, p.max_thrust_n, 1e-9);
  EXPECT_LT((quad.state().w_B_radps - Eigen::Vector3d(6.0, -6.0, 3.0)).norm(), 1e-9);
  Quadrotor low = make(p, s);
  for (int k = 0; k < 500; ++k) low.step(QuadrotorCommand{-5.0, Eigen::Vector3d::Zero()}, 0.002);
  EXPECT_NEAR(low.state().thrust_n, p.min_thrust_n, 1e-9);
}

TEST(Quadrotor, GivenManoeuvreWhenSteppedThenReportedAccelerationMatchesFiniteDifferenceOfVelocity) {
  // a(t) reported at the end of a step vs (v(t + h) - v(t - h)) / 2h with h = 1e-4 s while thrust,
  // rates and drag all change: error O(h^2 * jerk), tolerance 1e-5 m/s^2.
  const QuadrotorParams p;
  QuadrotorState s;
  s.p_W_m = {0.0, 0.0, 100.0};
  s.v_W_mps = {3.0, -2.0, 1.0};
  s.R_WB = rotation(0.3, {1, 2, 0});
  s.thrust_n = 8.0;
  Quadrotor quad = make(p, s);
  const QuadrotorCommand command{14.0, Eigen::Vector3d(1.0, -2.0, 0.5)};
  const double h = 1e-4;
  for (int k = 0; k < 300; ++k) quad.step(command, h);
  const Eigen::Vector3d v_before = quad.state().v_W_mps;
  quad.step(command, h);
  const Eigen::Vector3d a = quad.state().a_W_mps2;
  quad.step(command, h);
  const Eigen::Vector3d numeric = (quad.state().v_W_mps - v_before) / (2.0 * h);
  EXPECT_LT((numeric - a).norm(), 1e-5) << "numeric " << numeric.transpose() << " reported " << a.transpose();
}

TEST(Quadrotor, GivenExternalForceOnABodyAtRestThenItAcceleratesAsFOverMAndReachesTheDragTerminalVelocity) {
  // No gravity, no thrust, level: u' = F/m - d u per body axis, so u(t) = F/(m d) (1 - exp(-d t))
  // (exact, the discretisation is exact for a constant attitude), a(0+) = F/m and the terminal
  // velocity is F / (m d) (issue 20: the wind's force enters here).
  QuadrotorParams p;
  p.gravity_mps2 = 0.0;
  p.mass_kg = 2.0;
  p.max_thrust_n = 50.0;
  p.drag_B_per_s = {0.3, 0.5, 0.1};
  QuadrotorState s;
  s.p_W_m = {0.0, 0.0, 10.0};
  Quadrotor quad = make(p, s);
  const Eigen::Vector3d f_W_n(1.2, -0.8, 0.4);
  const double dt_s = 0.002;
  quad.step(QuadrotorCommand{}, dt_s, f_W_n);
  for (int i = 0; i < 3; ++i) {
    const double d = p.drag_B_per_s[i];
    EXPECT_NEAR(quad.state().v_W_mps[i], f_W_n[i] / (p.mass_kg * d) * -std::expm1(-d * dt_s), 1e-12);
    EXPECT_NEAR(quad.state().a_W_mps2[i], f_W_n[i] / p.mass_kg - d * quad.state().v_W_mps[i], 1e-12);
  }
  for (int k = 1; k < 50000; ++k) quad.step(QuadrotorCommand{}, dt_s, f_W_n);  // 100 s: > 10 time constants
  for (int i = 0; i < 3; ++i) {
    const double terminal = f_W_n[i] / (p.mass_kg * p.drag_B_per_s[i]);
    EXPECT_NEAR(quad.state().v_W_mps[i], terminal, 1e-3 * std::abs(terminal)) << "axis " << i;
  }
}

TEST(Quadrotor, GivenZeroExternalForceThenTheStepIsBitIdenticalToAStepWithout) {
  QuadrotorState s;
  s.p_W_m = {1.0, 2.0, 3.0};
  s.v_W_mps = {0.5, -0.3, 0.2};
  s.R_WB = rotation(0.3, {1, 2, 3});
  s.thrust_n = 9.0;
  Quadrotor a = make(QuadrotorParams{}, s);
  Quadrotor b = make(QuadrotorParams{}, s);
  QuadrotorCommand command;
  command.thrust_n = 11.0;
  command.w_B_radps = {0.2, -0.1, 0.4};
  for (int k = 0; k < 500; ++k) {
    a.step(command, 0.002);
    b.step(command, 0.002, Eigen::Vector3d::Zero());
  }
  EXPECT_EQ(a.state().p_W_m, b.state().p_W_m);
  EXPECT_EQ(a.state().v_W_mps, b.state().v_W_mps);
  EXPECT_EQ(a.state().R_WB, b.state().R_WB);
  EXPECT_EQ(a.state().a_W_mps2, b.state().a_W_mps2);
}

TEST(Quadrotor, GivenInvalidParametersOrStateWhenCreatedThenReturnsError) {
  QuadrotorParams bad_mass;
  bad_mass.mass_kg = 0.0;
  EXPECT_FALSE(Quadrotor::create(bad_mass, QuadrotorState{}).has_value());
  QuadrotorParams bad_thrust;
  bad_thrust.max_thrust_n = -1.0;
  EXPECT_FALSE(Quadrotor::create(bad_thrust, QuadrotorState{}).has_value());
  QuadrotorParams bad_tau;
  bad_tau.thrust_time_constant_s = -0.1;
  EXPECT_FALSE(Quadrotor::create(bad_tau, QuadrotorState{}).has_value());
  QuadrotorState below_ground;
  below_ground.p_W_m.z() = -0.1;
  EXPECT_FALSE(Quadrotor::create(QuadrotorParams{}, below_ground).has_value());
  QuadrotorState sheared;
  sheared.R_WB(0, 1) = 0.1;
  const auto result = Quadrotor::create(QuadrotorParams{}, sheared);
  ASSERT_FALSE(result.has_value());
  EXPECT_EQ(result.error().message, "quadrotor: initial R_WB is not a rotation matrix");
}

TEST(Quadrotor, GivenNonPositiveTimeStepWhenSteppedThenNothingChanges) {
  QuadrotorState s;
  s.p_W_m = {0.0, 0.0, 10.0};
  Quadrotor quad = make(QuadrotorParams{}, s);
  quad.step(QuadrotorCommand{}, 0.0);
  quad.step(QuadrotorCommand{}, -1.0);
  quad.step(QuadrotorCommand{}, std::nan(""));
  EXPECT_EQ(quad.state().p_W_m, s.p_W_m);
  EXPECT_EQ(quad.state().v_W_mps, s.v_W_mps);
}

}  // namespace
}  // namespace aerotrack::hal::sim
