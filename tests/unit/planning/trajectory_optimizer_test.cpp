// TrajectoryOptimizer: every cost term's gradient (with respect to q and, through the softplus, T)
// against central differences; the optimised trajectory on random corridors stays inside its boxes
// and within the limits; bad problems are refused with a reason.
#include "aerotrack/planning/trajectory_optimizer.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "aerotrack/planning/camera_view.hpp"
#include "random_corridor.hpp"

namespace aerotrack::planning {
namespace {

using test::randomCorridor;
using test::RandomCorridor;

// Central differences of evaluate(terms) at x, against its analytic gradient: every component within
// 1e-6 relative (of the larger of the component and 1e-3 of the gradient's largest entry, so that
// entries that are zero up to rounding are compared on the gradient's scale).
void expectGradientMatches(TrajectoryOptimizer& opt, const Eigen::VectorXd& x, std::uint32_t terms, const char* name) {
  Eigen::VectorXd grad;
  const double f = opt.evaluate(x, grad, terms);
  ASSERT_TRUE(std::isfinite(f)) << name;
  const double scale = std::max(1e-9, grad.cwiseAbs().maxCoeff());
  Eigen::VectorXd scratch;
  int active = 0;
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    const double h = 1e-6 * std::max(1.0, std::abs(x(k)));
    Eigen::VectorXd plus = x;
    Eigen::VectorXd minus = x;
    plus(k) += h;
    minus(k) -= h;
    const double fd = (opt.evaluate(plus, scratch, terms) - opt.evaluate(minus, scratch, terms)) / (2.0 * h);
    EXPECT_NEAR(grad(k), fd, 1e-6 * std::max(std::abs(fd), 1e-3 * scale)) << name << " variable " << k;
    if (std::abs(grad(k)) > 0.0) ++active;
  }
  EXPECT_GT(active, 0) << name << ": the term must be active at the test point";
}

TEST(TrajectoryOptimizer, EveryTermsGradientMatchesCentralDifferences) {
  std::mt19937 rng(21);
  const RandomCorridor c = randomCorridor(5, rng, 4.0);  // fast: the velocity and acceleration terms bite
  TrajectoryOptimizerParams params;
  params.max_velocity_mps = 2.0;
  params.max_acceleration_mps2 = 2.0;
  params.max_jerk_mps3 = 3.0;
  params.corridor_margin_m = 0.5;  // samples near the walls count as outside
  auto opt = TrajectoryOptimizer::create(params);
  ASSERT_TRUE(opt.has_value());
  ASSERT_TRUE(opt->setProblem(c.problem()).has_value());
  Eigen::VectorXd x = opt->initialVariables();
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  for (Eigen::Index k = 0; k < x.size(); ++k) x(k) += jitter(rng);  // away from the initial guess's symmetries
  const std::pair<std::uint32_t, const char*> terms[] = {
      {kJerkEnergy, "J_S"},
      {kBarrier, "J_F"},
      {kTime, "rho_t"},
      {kWaypointVelocity, "rho_v"},
      {kWaypointAcceleration, "rho_a"},
      {kCorridorSamples, "rho_c"},
      {kVelocitySamples, "rho_vs"},
      {kAccelerationSamples, "rho_as"},
      {kJerkSamples, "rho_js"},
      {kAllTerms, "all"},
  };
  for (const auto& [mask, name] : terms) expectGradientMatches(*opt, x, mask, name);

  // The speed-dependent margin (issue 21 item 5): the corridor term then depends on v too.
  params.corridor_margin_per_speed_s = 0.1;
  auto speed_opt = TrajectoryOptimizer::create(params);
  ASSERT_TRUE(speed_opt.has_value());
  ASSERT_TRUE(speed_opt->setProblem(c.problem()).has_value());
  expectGradientMatches(*speed_opt, x, kCorridorSamples, "rho_c with a margin per speed");
  expectGradientMatches(*speed_opt, x, kAllTerms, "all with a margin per speed");
  Eigen::VectorXd grad;
  EXPECT_GT(speed_opt->evaluate(x, grad, kCorridorSamples), opt->evaluate(x, grad, kCorridorSamples));
}

// The camera-view term (issue 21): its gradient, with the person moving, so that the sample times' dependence on
// every earlier duration counts too.
TEST(TrajectoryOptimizer, TheCameraViewTermsGradientMatchesCentralDifferences) {
  std::mt19937 rng(21);
  const RandomCorridor c = randomCorridor(5, rng, 4.0);
  TrajectoryOptimizerParams params;
  params.camera_view_weight = 1e3;
  params.camera_half_vfov_rad = 0.3;  // narrow: active along much of the path
  params.camera_view_margin_rad = 0.0;
  auto opt = TrajectoryOptimizer::create(params);
  ASSERT_TRUE(opt.has_value());
  std::vector<Eigen::Vector3d> person;
  for (int k = 0; k < 60; ++k) person.push_back(c.start.col(0) + Eigen::Vector3d(1.0 + 1.3 * 0.1 * k, 0.8, -0.5));
  TrajectoryProblem problem = c.problem();
  problem.person_torso_W_m = person;
  problem.person_sample_dt_s = 0.1;
  problem.person_torso_half_m = 0.25;
  ASSERT_TRUE(opt->setProblem(problem).has_value());
  Eigen::VectorXd x = opt->initialVariables();
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  for (Eigen::Index k = 0; k < x.size(); ++k) x(k) += jitter(rng);
  expectGradientMatches(*opt, x, kCameraViewSamples, "rho_cv");
  expectGradientMatches(*opt, x, kAllTerms, "all with rho_cv");
  // No person samples: no term.
  ASSERT_TRUE(opt->setProblem(c.problem()).has_value());
  Eigen::VectorXd grad;
  EXPECT_EQ(opt->evaluate(x, grad, kCameraViewSamples), 0.0);
}

// Braking to a stop 1.2 m short of a person: without the term the nose-up pitch of the brake takes the hips out
// of the bottom of the image; with it the optimiser brakes earlier and gentler, and keeps them in view.
TEST(TrajectoryOptimizer, TheCameraViewTermKeepsAClosePersonInViewWhileBraking) {
  TrajectoryOptimizerParams params;
  params.max_velocity_mps = 6.0;
  params.max_acceleration_mps2 = 6.0;
  params.max_jerk_mps3 = 60.0;
  params.time_weight = 200.0;  // a runner's: brakes hard
  CorridorBox box;
  box.lo_W_m = Eigen::Vector3d(-1.0, -2.0, 0.5);
  box.hi_W_m = Eigen::Vector3d(6.0, 2.0, 3.0);
  const std::vector<CorridorBox> boxes = {box, box};
  const std::vector<Eigen::Vector3d> waypoints = {{2.0, 0.0, 1.5}};
  const std::vector<double> durations = {0.8, 0.8};
  StatePva start = StatePva::Zero();
  start.col(0) = Eigen::Vector3d(0.0, 0.0, 1.5);
  start.col(1) = Eigen::Vector3d(4.0, 0.0, 0.0);
  StatePva end = StatePva::Zero();
  end.col(0) = Eigen::Vector3d(4.3, 0.0, 1.5);
  const std::vector<Eigen::Vector3d> person(40, Eigen::Vector3d(5.5, 0.0, 1.1));  // standing, torso centre
  TrajectoryProblem problem{start, end, boxes, waypoints, durations};
  problem.person_torso_W_m = person;
  problem.person_sample_dt_s = 0.1;
  problem.person_torso_half_m = 0.25;
  const double limit_rad = params.camera_half_vfov_rad;
  // The largest angle of the hips below the optical axis along the trajectory.
  const auto worst_hips_rad = [&](const PolynomialTrajectory& traj) {
    double worst = -1e9;
    for (double t = 0.0; t <= traj.durationS(); t += 0.01) {
      const auto s = traj.sample(t);
      const Eigen::Vector3d b3 = (s.a_W_mps2 + Eigen::Vector3d(0.0, 0.0, kGravityMps2)).normalized();
      const Eigen::Vector3d d = (Eigen::Vector3d(5.5, 0.0, 0.85) - s.p_W_m).normalized();
      worst = std::max(worst, -std::asin(b3.dot(d)));
    }
    return worst;
  };
  PolynomialTrajectory plain(8);
  PolynomialTrajectory viewed(8);
  auto off = TrajectoryOptimizer::create(params);
  ASSERT_TRUE(off.has_value());
  ASSERT_TRUE(off->optimize(problem, plain).has_value());
  params.camera_view_weight = 1e5;  // the weight measured in the envelope (docs/benchmarks.md; ships at 0)
  auto on = TrajectoryOptimizer::create(params);
  ASSERT_TRUE(on.has_value());
  ASSERT_TRUE(on->optimize(problem, viewed).has_value());
  EXPECT_GT(worst_hips_rad(plain), limit_rad) << "the test must start outside the view";
  // A soft penalty: the hips may enter the margin (0.05 rad) but stay in the image (0.80 rad without the term).
  EXPECT_LT(worst_hips_rad(viewed), limit_rad);
  EXPECT_GT(viewed.durationS(), plain.durationS()) << "by braking earlier";
}

TEST(TrajectoryOptimizer, SoftplusRoundTrips) {
  for (const double t : {1e-3, 0.1, 0.7, 1.0, 5.0, 40.0}) {
    EXPECT_NEAR(TrajectoryOptimizer::durationFromTau(TrajectoryOptimizer::tauFromDuration(t)), t,
                1e-12 * std::max(1.0, t));
  }
  EXPECT_GT(TrajectoryOptimizer::durationFromTau(-50.0), 0.0);
}

struct TrajectoryStats {
  double max_outside_m = 0.0;  // largest distance of a sample outside its piece's box
  double max_speed_mps = 0.0;
  double max_acceleration_mps2 = 0.0;
};

TrajectoryStats inspect(const PolynomialTrajectory& traj, const std::vector<CorridorBox>& boxes) {
  TrajectoryStats s;
  double t0 = 0.0;
  for (int i = 0; i < traj.pieces(); ++i) {
    const double d = traj.pieceDurationS(i);
    for (int k = 0; k <= 200; ++k) {
      const double t = t0 + d * k / 200.0;
      const trajectory_server::TrajectorySample x = traj.sample(t);
      const CorridorBox& box = boxes[static_cast<std::size_t>(i)];
      const Eigen::Vector3d outside =
          (box.lo_W_m - x.p_W_m).cwiseMax(x.p_W_m - box.hi_W_m).cwiseMax(Eigen::Vector3d::Zero());
      s.max_outside_m = std::max(s.max_outside_m, outside.maxCoeff());
      s.max_speed_mps = std::max(s.max_speed_mps, x.v_W_mps.norm());
      s.max_acceleration_mps2 = std::max(s.max_acceleration_mps2, x.a_W_mps2.norm());
    }
    t0 += d;
  }
  return s;
}

TEST(TrajectoryOptimizer, StaysInsideRandomCorridorsWithinLimits) {
  std::mt19937 rng(1234);
  TrajectoryOptimizerParams params;
  params.corridor_margin_m = 0.05;
  auto opt = TrajectoryOptimizer::create(params);
  ASSERT_TRUE(opt.has_value());
  for (int trial = 0; trial < 40; ++trial) {
    const RandomCorridor c = randomCorridor(2 + trial % 10, rng, 1.5);
    PolynomialTrajectory traj;
    const auto result = opt->optimize(c.problem(), traj);
    ASSERT_TRUE(result.has_value()) << result.error().message;
    EXPECT_LT(result->cost, result->initial_cost) << "trial " << trial;
    const TrajectoryStats s = inspect(traj, c.boxes);
    EXPECT_LE(s.max_outside_m, 0.0) << "trial " << trial;
    EXPECT_LE(s.max_speed_mps, params.max_velocity_mps * 1.02) << "trial " << trial;
    EXPECT_LE(s.max_acceleration_mps2, params.max_acceleration_mps2 * 1.02) << "trial " << trial;
    // The boundary states are exactly the problem's.
    EXPECT_LT((traj.sample(0.0).p_W_m - c.start.col(0)).norm(), 1e-9);
    EXPECT_LT((traj.sample(0.0).v_W_mps - c.start.col(1)).norm(), 1e-9);
    EXPECT_LT((traj.sample(traj.durationS()).p_W_m - c.end.col(0)).norm(), 1e-9);
  }
}

TEST(TrajectoryOptimizer, AProblemsTimeWeightScaleIsRhoTTimesItAndShortensTheTrajectory) {
  std::mt19937 rng(77);
  const RandomCorridor c = randomCorridor(4, rng, 1.5);
  TrajectoryOptimizerParams params;
  params.max_velocity_mps = 6.0;  // limits far off: the time is set by rho_t against the jerk
  params.max_acceleration_mps2 = 6.0;
  params.max_jerk_mps3 = 60.0;
  auto opt = TrajectoryOptimizer::create(params);
  ASSERT_TRUE(opt.has_value());
  ASSERT_TRUE(opt->setProblem(c.problem()).has_value());
  const Eigen::VectorXd x = opt->initialVariables();
  Eigen::VectorXd grad;
  const double time_cost = opt->evaluate(x, grad, kTime);

  TrajectoryProblem scaled = c.problem();
  scaled.time_weight_scale = 10.0;
  ASSERT_TRUE(opt->setProblem(scaled).has_value());
  EXPECT_NEAR(opt->evaluate(x, grad, kTime), 10.0 * time_cost, 1e-9 * time_cost);
  expectGradientMatches(*opt, x, kTime, "rho_t scaled");

  PolynomialTrajectory plain;
  PolynomialTrajectory fast;
  ASSERT_TRUE(opt->optimize(c.problem(), plain).has_value());
  ASSERT_TRUE(opt->optimize(scaled, fast).has_value());
  // The min-jerk piece's duration goes as rho_t^(-1/6): 10 x rho_t, about 0.68 x the time.
  EXPECT_LT(fast.durationS(), 0.8 * plain.durationS());
  EXPECT_GT(fast.durationS(), 0.5 * plain.durationS());

  PolynomialTrajectory traj;
  for (const double bad : {0.0, -1.0, std::nan("")}) {
    TrajectoryProblem refused = c.problem();
    refused.time_weight_scale = bad;
    EXPECT_FALSE(opt->optimize(refused, traj).has_value()) << bad;
  }
}

TEST(TrajectoryOptimizer, RefusesBadProblems) {
  std::mt19937 rng(5);
  RandomCorridor c = randomCorridor(3, rng);
  auto opt = TrajectoryOptimizer::create(TrajectoryOptimizerParams{});
  ASSERT_TRUE(opt.has_value());
  PolynomialTrajectory traj;
  {
    RandomCorridor bad = c;
    bad.waypoints[0] = bad.boxes[0].hi_W_m + Eigen::Vector3d::Ones();
    const auto r = opt->optimize(bad.problem(), traj);
    ASSERT_FALSE(r.has_value());
    EXPECT_NE(r.error().message.find("waypoint 0"), std::string::npos);
  }
  {
    RandomCorridor bad = c;
    bad.durations[1] = -1.0;
    EXPECT_FALSE(opt->optimize(bad.problem(), traj).has_value());
  }
  {
    RandomCorridor bad = c;
    bad.waypoints.pop_back();
    EXPECT_FALSE(opt->optimize(bad.problem(), traj).has_value());
  }
  {
    RandomCorridor bad = c;
    bad.start(0, 0) = std::nan("");
    EXPECT_FALSE(opt->optimize(bad.problem(), traj).has_value());
  }
  TrajectoryOptimizerParams params;
  params.samples_per_piece = 0;
  EXPECT_FALSE(TrajectoryOptimizer::create(params).has_value());
}

}  // namespace
}  // namespace aerotrack::planning
