// The simulator's disturbances (issue 20, hal/sim/disturbances.hpp) against their analytic
// statistics and physics: the odometry drift's variance against the random walk's (sigma^2 times
// the distance flown plus the time term), jumps at their times and of their sizes, the flight
// controller flying the odometry frame, zero drift leaving the run bit-identical, the wind's force
// and the terminal velocity of its drag law, the gusts' variance and correlation time, and the
// scenario keys' errors.
//
// Statistical tolerances: each estimate is compared with its analytic value within at least 4
// standard deviations of the estimator (worked out next to each check), so a change of seed does
// not make the tests fail; the seeds are fixed, so the tests are deterministic.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "aerotrack/hal/sim/disturbances.hpp"
#include "aerotrack/hal/sim/simulation.hpp"
#include "support/require.hpp"

namespace aerotrack::hal::sim {
namespace {

using rt::kNsPerSecond;

std::mt19937_64 testRng(std::uint64_t seed) {
  std::seed_seq seq{seed, std::uint64_t{0xd15}};
  return std::mt19937_64(seq);
}

double sampleVariance(const std::vector<double>& x) {
  double sum = 0.0, sum2 = 0.0;
  for (double v : x) {
    sum += v;
    sum2 += v * v;
  }
  const double n = static_cast<double>(x.size());
  return (sum2 - sum * sum / n) / (n - 1.0);
}

TEST(OdometryDrift, GivenStraightFlightThenThePositionVarianceGrowsWithDistanceAndTimeAsTheRandomWalk) {
  // 4000 flights of 100 updates, 1 m and 0.1 s each, along x; no yaw walk, so t is the sum of the
  // increments: var(t_x) = a^2 s + b^2 T. The sample variance of 4000 normals has a relative std
  // of sqrt(2 / 3999) = 2.2 %: the 10 % tolerance is 4.5 sigma.
  OdometryDriftSpec spec;
  spec.position_m_per_sqrt_m = 0.1;
  spec.z_m_per_sqrt_m = 0.04;
  spec.position_m_per_sqrt_s = 0.05;
  constexpr int kRuns = 4000;
  std::vector<double> x25, y25, x100, y100, z100;
  for (int run = 0; run < kRuns; ++run) {
    OdometryDrift drift(spec, testRng(2 * run), testRng(2 * run + 1), Eigen::Vector3d::Zero());
    for (int k = 1; k <= 100; ++k) {
      drift.update(0.1 * k, Eigen::Vector3d(k, 0.0, 0.0));
      if (k == 25) {
        x25.push_back(drift.error().t_m.x());
        y25.push_back(drift.error().t_m.y());
      }
    }
    x100.push_back(drift.error().t_m.x());
    y100.push_back(drift.error().t_m.y());
    z100.push_back(drift.error().t_m.z());
    ASSERT_NEAR(drift.distanceFlownM(), 100.0, 1e-9);
  }
  const auto expected = [](double a, double s_m, double b, double t_s) { return a * a * s_m + b * b * t_s; };
  EXPECT_NEAR(sampleVariance(x25) / expected(0.1, 25.0, 0.05, 2.5), 1.0, 0.10);
  EXPECT_NEAR(sampleVariance(y25) / expected(0.1, 25.0, 0.05, 2.5), 1.0, 0.10);
  EXPECT_NEAR(sampleVariance(x100) / expected(0.1, 100.0, 0.05, 10.0), 1.0, 0.10);
  EXPECT_NEAR(sampleVariance(y100) / expected(0.1, 100.0, 0.05, 10.0), 1.0, 0.10);
  EXPECT_NEAR(sampleVariance(z100) / expected(0.04, 100.0, 0.05, 10.0), 1.0, 0.10);
}

TEST(OdometryDrift, GivenAYawWalkThenTheHeadingVarianceGrowsWithDistanceAndTheCrossTrackErrorAsItsIntegral) {
  // Yaw walk only: var(yaw) = c^2 s. Flying on along x with the heading error psi_j on leg j+1, the
  // drone's reported cross-track error is sum_j sin(psi_j) (1 m legs), of variance about
  // c^2 sum_{j,k<N} min(j, k) = c^2 (N - 1) N (2N - 1) / 6 (small angles: psi's std reaches 0.1 rad,
  // sin^2 is then ~1 % below psi^2, inside the 10 % (4.5 sigma) tolerance).
  OdometryDriftSpec spec;
  spec.yaw_rad_per_sqrt_m = 0.01;
  constexpr int kRuns = 4000, kLegs = 100;
  std::vector<double> yaw, cross;
  for (int run = 0; run < kRuns; ++run) {
    OdometryDrift drift(spec, testRng(7 * run + 3), testRng(7 * run + 4), Eigen::Vector3d::Zero());
    for (int k = 1; k <= kLegs; ++k) drift.update(0.1 * k, Eigen::Vector3d(k, 0.0, 0.0));
    yaw.push_back(drift.error().yaw_rad);
    const Eigen::Vector3d p_W(kLegs, 0.0, 0.0);
    cross.push_back((drift.error().toOdometry(p_W) - p_W).y());
  }
  EXPECT_NEAR(sampleVariance(yaw) / (1e-4 * kLegs), 1.0, 0.10);
  const double n = kLegs;
  EXPECT_NEAR(sampleVariance(cross) / (1e-4 * (n - 1.0) * n * (2.0 * n - 1.0) / 6.0), 1.0, 0.10);
}

TEST(OdometryDrift, GivenListedJumpsThenTheyAppearAtTheirTimesWithTheirSizes) {
  OdometryDriftSpec spec;
  spec.jumps = {{1.0, Eigen::Vector3d(1.0, -0.5, 0.2), 0.3}, {2.5, Eigen::Vector3d(0.0, 2.0, 0.0), -0.1}};
  OdometryDrift drift(spec, testRng(1), testRng(2), Eigen::Vector3d(0.0, 0.0, 1.5));
  const Eigen::Vector3d p1_W(3.0, 1.0, 1.5), p2_W(-2.0, 4.0, 2.0);
  for (int k = 0; k < 100; ++k) drift.update(0.01 * k, p1_W);  // up to 0.99 s: no jump yet
  EXPECT_EQ(drift.error().t_m, Eigen::Vector3d::Zero());
  EXPECT_EQ(drift.jumpsApplied(), 0U);
  drift.update(1.0, p1_W);
  // The drone's reported position stepped by dp; the frame turned by dyaw about it.
  EXPECT_TRUE((drift.error().toOdometry(p1_W) - p1_W).isApprox(Eigen::Vector3d(1.0, -0.5, 0.2), 1e-12));
  EXPECT_NEAR(drift.error().yaw_rad, 0.3, 1e-15);
  const Eigen::Vector3d before_O = drift.error().toOdometry(p2_W);
  for (int k = 101; k < 250; ++k) drift.update(0.01 * k, p2_W);
  EXPECT_EQ(drift.jumpsApplied(), 1U);
  drift.update(2.5, p2_W);
  EXPECT_TRUE((drift.error().toOdometry(p2_W) - before_O).isApprox(Eigen::Vector3d(0.0, 2.0, 0.0), 1e-12));
  EXPECT_NEAR(drift.error().yaw_rad, 0.2, 1e-15);
  EXPECT_EQ(drift.jumpsApplied(), 2U);
}

TEST(OdometryDrift, GivenRandomJumpsThenTheirRateAndSizesAreAsConfigured) {
  // 6 per minute over 1000 s: Poisson with mean 100 (std 10); accepted within 4.5 sigma. Each
  // jump moves the stationary drone's reported position by exactly position_m, horizontally, and
  // its heading by +-yaw_rad.
  OdometryDriftSpec spec;
  spec.random_jumps_per_min = 6.0;
  spec.random_jump_position_m = 0.8;
  spec.random_jump_yaw_rad = 0.05;
  OdometryDrift drift(spec, testRng(5), testRng(6), Eigen::Vector3d::Zero());
  const Eigen::Vector3d p_W(1.0, 2.0, 1.0);
  Eigen::Vector3d last_O = p_W;
  double last_yaw = 0.0;
  for (int k = 1; k <= 100000; ++k) {
    const std::size_t before = drift.jumpsApplied();
    drift.update(0.01 * k, p_W);
    const Eigen::Vector3d now_O = drift.error().toOdometry(p_W);
    if (drift.jumpsApplied() == before + 1) {
      EXPECT_NEAR((now_O - last_O).head<2>().norm(), 0.8, 1e-9);
      EXPECT_NEAR(now_O.z(), last_O.z(), 1e-9);
      EXPECT_NEAR(std::abs(std::remainder(drift.error().yaw_rad - last_yaw, 2.0 * M_PI)), 0.05, 1e-9);
    }
    last_O = now_O;
    last_yaw = drift.error().yaw_rad;
  }
  EXPECT_NEAR(static_cast<double>(drift.jumpsApplied()), 100.0, 45.0);
}

TEST(WindField, GustsHaveTheGaussMarkovVarianceAndCorrelationTime) {
  // 10000 s at 100 Hz. The variance estimate of an AR(1) series with N samples and coefficient phi
  // has relative std sqrt(2 (1 + phi^2) / (N (1 - phi^2))): 2.0 % for tau = 0.5 s (10 % = 5 sigma).
  // The lag-tau autocorrelation's estimate has std about sqrt((1 + phi^2)/(N(1 - phi^2))) with
  // phi = exp(-dt/tau) (Bartlett's formula for an AR(1)): 0.014 for tau = 0.5 s; tolerance 0.06.
  WindSpec spec;
  spec.mean_W_mps = {6.0, -1.0, 0.0};
  spec.gust_sigma_mps = {1.5, 1.0, 0.5};
  spec.gust_time_constant_s = {0.5, 0.3, 0.2};
  WindField wind(spec, testRng(11));
  constexpr double kDt = 0.01;
  constexpr int kSteps = 1'000'000;
  std::vector<Eigen::Vector3d> g(kSteps);
  for (int k = 0; k < kSteps; ++k) {
    g[k] = wind.velocityW() - spec.mean_W_mps;
    wind.step(kDt);
  }
  for (int axis = 0; axis < 3; ++axis) {
    double mean = 0.0, var = 0.0;
    for (const auto& v : g) mean += v[axis];
    mean /= kSteps;
    for (const auto& v : g) var += (v[axis] - mean) * (v[axis] - mean);
    var /= kSteps;
    const double sigma = spec.gust_sigma_mps[axis];
    EXPECT_NEAR(var / (sigma * sigma), 1.0, 0.10) << "axis " << axis;
    EXPECT_NEAR(mean / sigma, 0.0, 0.05) << "axis " << axis;
    for (const double lags_in_tau : {1.0, 2.0}) {
      const int lag = static_cast<int>(std::lround(lags_in_tau * spec.gust_time_constant_s[axis] / kDt));
      double c = 0.0;
      for (int k = 0; k + lag < kSteps; ++k) c += (g[k][axis] - mean) * (g[k + lag][axis] - mean);
      c /= (kSteps - lag) * var;
      EXPECT_NEAR(c, std::exp(-lags_in_tau), 0.06) << "axis " << axis << ", lag " << lags_in_tau << " tau";
    }
  }
}

TEST(WindForce, GivenABodyAtRestInASteadyWindThenItAcceleratesAsFOverMAndDriftsToTheDragLawsTerminalVelocity) {
  QuadrotorParams p;
  p.gravity_mps2 = 0.0;  // isolate the horizontal balance
  WindSpec spec;
  spec.body_cd_area_m2 = 0.05;
  const Eigen::Vector3d wind_W(4.0, 0.0, 0.0);
  QuadrotorState s;
  s.p_W_m = {0.0, 0.0, 10.0};
  // At rest, level: F = m d_x w + 0.5 rho CdA w^2 along x.
  const double k = 0.5 * spec.air_density_kgpm3 * spec.body_cd_area_m2;
  const Eigen::Vector3d f_rest = windForceW(p, s, wind_W, spec);
  EXPECT_NEAR(f_rest.x(), p.mass_kg * p.drag_B_per_s.x() * 4.0 + k * 16.0, 1e-12);
  EXPECT_NEAR(f_rest.y(), 0.0, 1e-12);
  EXPECT_NEAR(f_rest.z(), 0.0, 1e-12);
  Quadrotor quad = aerotrack::test::require(Quadrotor::create(p, s), "Quadrotor::create");
  quad.step(QuadrotorCommand{}, 1e-4, windForceW(p, quad.state(), wind_W, spec));
  EXPECT_NEAR(quad.state().v_W_mps.x() / 1e-4, f_rest.x() / p.mass_kg, 1e-3 * f_rest.x() / p.mass_kg);
  // Pushed upwind by 3 N: terminal air-relative speed u solves m d u + k u^2 = 3.
  const Eigen::Vector3d push_W(-3.0, 0.0, 0.0);
  for (int i = 0; i < 100000; ++i)  // 200 s: many time constants
    quad.step(QuadrotorCommand{}, 0.002, windForceW(p, quad.state(), wind_W, spec) + push_W);
  const double d = p.mass_kg * p.drag_B_per_s.x();
  const double u = (-d + std::sqrt(d * d + 4.0 * k * 3.0)) / (2.0 * k);
  EXPECT_NEAR(quad.state().v_W_mps.x(), 4.0 - u, 1e-3);
  EXPECT_NEAR(quad.state().v_W_mps.y(), 0.0, 1e-9);
}

// --- The simulation with disturbances ----------------------------------------------------------

/// A hovering drone at (0, 0, 1.5), the person far away and still, no odometry noise, plus a
/// sensors.odometry.drift block and a wind section when given (flow-style YAML maps).
std::string disturbedYaml(const std::string& odometry_drift, const std::string& wind) {
  std::string yaml = R"(name: disturbed
end_margin_s: 1.0
max_duration_s: 2000.0
world:
  bounds_min_m: [-5.0, -5.0, 0.0]
  bounds_max_m: [12.0, 5.0, 4.0]
person:
  height_m: 1.75
  torso_m: 0.5
  start_delay_s: 500.0
  path:
    - {p_m: [8.0, 0.0], speed_mps: 1.0}
    - {p_m: [8.0, 3.0], speed_mps: 0.0}
drone:
  start_m: [0.0, 0.0, 1.5]
  start_yaw_rad: 0.0
  radius_m: 0.25
  mass_kg: 1.0
  thrust_to_weight: 2.5
success:
  tracking_distance_m: 2.5
  final_distance_factor: 2.0
sensors:
  odometry:
    rate_hz: 100.0
    latency_s: 0.01
    position_noise_m: 0.0
    velocity_noise_mps: 0.0
    yaw_noise_rad: 0.0
)";
  if (!odometry_drift.empty()) yaml += "    drift: " + odometry_drift + "\n";
  if (!wind.empty()) yaml += "wind: " + wind + "\n";
  return yaml;
}

std::unique_ptr<Simulation> makeDisturbedSim(const std::string& yaml) {
  const ScenarioSpec spec = aerotrack::test::require(parseScenarioSpec(yaml, "disturbed.yaml"), "disturbed.yaml");
  const ScenarioInstance trial = aerotrack::test::require(instantiate(spec, 3), "instantiate");
  SimulationOptions options;
  options.render_depth = false;
  return aerotrack::test::require(Simulation::create(trial, options, 0), "Simulation::create");
}

void holdSetpoint(Simulation& sim, double seconds, const Eigen::Vector3d& p_O_m) {
  Setpoint hold;
  hold.p_W_m = p_O_m;  // the setpoint is in the odometry frame
  const rt::TimeNs start = sim.truth().stamp_ns;
  for (rt::TimeNs t = start; t <= start + rt::secondsToNs(seconds); t += 5'000'000) {
    hold.stamp_ns = t;  // streamed (the flight controller holds after 1 s without)
    sim.setpointInbox().write(hold);
    sim.step(t);
  }
}

TEST(SimulationDisturbances, GivenZeroDriftKeysOrAJumpNotYetDueThenTheRunIsBitIdenticalToOneWithout) {
  // Zero keys: no drift model at all. A jump due after the run: the drift model runs (the
  // controller gets the state through the identity T_OW), which must not change a bit either.
  for (const std::string drift :
       {"{position_m_per_sqrt_m: 0.0, yaw_rad_per_sqrt_m: 0.0}", "{jumps: [{t_s: 1000.0, dp_m: [1, 0, 0]}]}"}) {
    SCOPED_TRACE(drift);
    auto plain = makeDisturbedSim(disturbedYaml("", ""));
    auto zero = makeDisturbedSim(disturbedYaml(drift, ""));
    Setpoint go;
    go.p_W_m = {3.0, -1.0, 2.0};
    go.yaw_rad = 0.7;
    for (rt::TimeNs t = 0; t <= 4 * kNsPerSecond; t += 5'000'000) {
      go.stamp_ns = t;  // streamed (the flight controller holds after 1 s without)
      plain->setpointInbox().write(go);
      zero->setpointInbox().write(go);
      plain->step(t);
      zero->step(t);
      ASSERT_EQ(plain->truth().drone.p_W_m, zero->truth().drone.p_W_m);
      ASSERT_EQ(plain->truth().drone.R_WB, zero->truth().drone.R_WB);
      const auto a = plain->odometryOut().read(), b = zero->odometryOut().read();
      ASSERT_EQ(a.has_value(), b.has_value());
      if (a) {
        ASSERT_EQ(a->p_WB_m, b->p_WB_m);
        ASSERT_EQ(a->v_WB_mps, b->v_WB_mps);
        ASSERT_EQ(a->q_WB.coeffs(), b->q_WB.coeffs());
      }
    }
    EXPECT_EQ(zero->odometryFrameError().t_m, Eigen::Vector3d::Zero());
    EXPECT_LT((plain->truth().drone.p_W_m - Eigen::Vector3d(3.0, -1.0, 2.0)).norm(), 0.5);  // it did fly there
  }
}

TEST(SimulationDisturbances, GivenAJumpOfTheOdometryFrameThenTheControllerFliesTheDroneByItInTheWorld) {
  // Hovering at the setpoint s (odometry frame); at 0.5 s the odometry frame jumps by dp and turns
  // by dyaw about the drone. The flight controller flies O, so the drone settles where O says s:
  // p_W = s - R_z(-dyaw) dp, heading -dyaw in the world; the odometry again reads s.
  const Eigen::Vector3d dp(1.0, -0.5, 0.3);
  const double dyaw = 0.4;
  auto sim = makeDisturbedSim(disturbedYaml("{jumps: [{t_s: 0.5, dp_m: [1.0, -0.5, 0.3], dyaw_rad: 0.4}]}", ""));
  const Eigen::Vector3d s(0.0, 0.0, 1.5);
  holdSetpoint(*sim, 0.49, s);
  EXPECT_EQ(sim->odometryFrameError().t_m, Eigen::Vector3d::Zero());
  holdSetpoint(*sim, 0.02, s);
  // The first sample after the jump shows the step (the drone has not moved yet).
  EXPECT_LT((sim->odometryPositionErrorM() - dp).norm(), 0.01);
  holdSetpoint(*sim, 8.0, s);
  const Eigen::Vector3d expected_W = s - Eigen::AngleAxisd(-dyaw, Eigen::Vector3d::UnitZ()) * dp;
  EXPECT_LT((sim->truth().drone.p_W_m - expected_W).norm(), 0.01) << sim->truth().drone.p_W_m.transpose();
  const Eigen::Matrix3d& R = sim->truth().drone.R_WB;
  EXPECT_NEAR(std::atan2(R(1, 0), R(0, 0)), -dyaw, 0.01);
  const auto odometry = sim->odometryOut().read();
  ASSERT_TRUE(odometry);
  EXPECT_LT((odometry->p_WB_m - s).norm(), 0.01);
  // Other threads see T_OW in the truth snapshot; a world setpoint maps into O through it.
  const auto truth = sim->truthOut().read();
  ASSERT_TRUE(truth);
  EXPECT_EQ(truth->odom_t_OW_m, sim->odometryFrameError().t_m);
  EXPECT_EQ(truth->odom_yaw_OW_rad, sim->odometryFrameError().yaw_rad);
  Setpoint at_drone_W;
  at_drone_W.p_W_m = sim->truth().drone.p_W_m;
  at_drone_W.yaw_rad = -dyaw;
  const Setpoint at_drone_O = inOdometryFrame(sim->odometryFrameError(), at_drone_W);
  EXPECT_LT((at_drone_O.p_W_m - s).norm(), 0.01);
  EXPECT_NEAR(at_drone_O.yaw_rad, 0.0, 1e-12);
}

TEST(SimulationDisturbances, GivenASteadyWindThenTheUnawareControllerHoversOffsetByForceOverGain) {
  // No integrator in the position loop: the steady state balances Kp (s - p) + F / m = 0, so the
  // drone settles F / (m Kp) downwind of its setpoint (Kp = 6 horizontally, 8 vertically).
  auto sim = makeDisturbedSim(disturbedYaml("", "{mean_mps: [6.0, -2.0, 0.0]}"));
  const Eigen::Vector3d s(0.0, 0.0, 1.5);
  holdSetpoint(*sim, 10.0, s);
  EXPECT_EQ(sim->windW(), Eigen::Vector3d(6.0, -2.0, 0.0));
  WindSpec spec;
  QuadrotorParams params;
  params.mass_kg = 1.0;
  const Eigen::Vector3d f = windForceW(params, sim->truth().drone, sim->windW(), spec);
  const GeometricControllerParams gains;
  const Eigen::Vector3d offset = sim->truth().drone.p_W_m - s;
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(offset[i], f[i] / (params.mass_kg * gains.position_gain_per_s2[i]), 2e-3) << "axis " << i;
  EXPECT_GT(offset.x(), 0.25);  // 0.3 m for the still vehicle's drag of 0.3 / s
}

TEST(SimulationDisturbances, ScenarioKeysAreChecked) {
  const auto error = [](const std::string& drift, const std::string& wind) {
    const auto spec = parseScenarioSpec(disturbedYaml(drift, wind), "disturbed.yaml");
    return spec ? std::string("no error") : spec.error().message;
  };
  const auto contains = [](const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
  };
  EXPECT_PRED2(contains, error("{position_m_per_sqrt_m: -0.1}", ""),
               "sensors.odometry.drift.position_m_per_sqrt_m: -0.1 is out of range");
  EXPECT_PRED2(contains, error("{yaw_per_m: 0.1}", ""), "sensors.odometry.drift.yaw_per_m: unknown key");
  EXPECT_PRED2(contains, error("{jumps: [{t_s: 2.0, dp_m: [1, 0, 0]}, {t_s: 1.0, dp_m: [0, 1, 0]}]}", ""),
               "jumps must be listed in time order");
  EXPECT_PRED2(contains, error("{jumps: [{t_s: 2.0}]}", ""),
               "sensors.odometry.drift.jumps[0].dp_m: missing required key");
  EXPECT_PRED2(contains, error("{random_jumps: {rate_per_min: 1.0}}", ""),
               "sensors.odometry.drift.random_jumps.position_m: missing required key");
  EXPECT_PRED2(contains, error("", "{gust_sigma_mps: [1, 1, 1]}"), "wind.mean_mps: missing required key");
  EXPECT_PRED2(contains, error("", "{mean_mps: [1, 0, 0], gust_time_constant_s: [1, 0, 1]}"),
               "wind.gust_time_constant_s");
  EXPECT_PRED2(contains, error("", "{mean_mps: [1, 0, 0], gusts: 1}"), "wind.gusts: unknown key");
  EXPECT_PRED2(contains, error("", "{mean_mps: [1, 0]}"), "wind.mean_mps");
  // Accepted, with their values.
  const auto spec = aerotrack::test::require(
      parseScenarioSpec(disturbedYaml("{position_m_per_sqrt_m: 0.14, jumps: [{t_s: 3.0, dp_m: [1, 2, 0]}]}",
                                      "{mean_mps: [6, 0, 0], gust_sigma_mps: [1.5, 1.5, 0.8]}"),
                        "disturbed.yaml"),
      "disturbed.yaml");
  EXPECT_EQ(spec.odometry.drift.position_m_per_sqrt_m, 0.14);
  ASSERT_EQ(spec.odometry.drift.jumps.size(), 1U);
  EXPECT_EQ(spec.odometry.drift.jumps[0].dp_m, Eigen::Vector3d(1, 2, 0));
  ASSERT_TRUE(spec.wind);
  EXPECT_EQ(spec.wind->gust_sigma_mps, Eigen::Vector3d(1.5, 1.5, 0.8));
  EXPECT_EQ(spec.wind->gust_time_constant_s, Eigen::Vector3d(1.0, 1.0, 1.0));
}

}  // namespace
}  // namespace aerotrack::hal::sim
