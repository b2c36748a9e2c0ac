// Trajectory server and the minimum-jerk tour: closed-form values, limits, derivatives against
// finite differences, yaw along the velocity.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "aerotrack/trajectory_server/min_jerk_tour.hpp"
#include "aerotrack/trajectory_server/trajectory_server.hpp"
#include "aerotrack/trajectory_server/trajectory_server_task.hpp"
#include "support/require.hpp"

namespace aerotrack::trajectory_server {
namespace {

MinJerkTour makeTour(double vmax = 2.0, double amax = 2.0) {
  return aerotrack::test::require(MinJerkTour::create({{0, 0, 0}, {4, 0, 0}, {4, 3, 0}}, vmax, amax),
                                  "MinJerkTour::create");
}

TEST(MinJerkTour, GivenBadInputThenError) {
  EXPECT_FALSE(MinJerkTour::create({{0, 0, 0}}, 1, 1));
  EXPECT_FALSE(MinJerkTour::create({{0, 0, 0}, {1, 0, 0}}, 0, 1));
  EXPECT_FALSE(MinJerkTour::create({{0, 0, 0}, {std::numeric_limits<double>::quiet_NaN(), 0, 0}}, 1, 1));
}

TEST(MinJerkTour, LegDurationIsTheSmallestThatRespectsBothLimits) {
  const MinJerkTour tour = makeTour(2.0, 2.0);
  // 4 m: speed needs 1.875*4/2 = 3.75 s, accel needs sqrt(5.7735*4/2) = 3.398 s
  EXPECT_NEAR(tour.legDurationsS()[0], 3.75, 1e-9);
  // 3 m: speed 2.8125 s, accel sqrt(5.7735*3/2) = 2.9428 s
  EXPECT_NEAR(tour.legDurationsS()[1], std::sqrt(10.0 / std::sqrt(3.0) * 3.0 / 2.0), 1e-9);
  EXPECT_NEAR(tour.durationS(), tour.legDurationsS()[0] + tour.legDurationsS()[1], 1e-12);
}

TEST(MinJerkTour, PassesThroughWaypointsAtRestAndHoldsAfterTheEnd) {
  const MinJerkTour tour = makeTour();
  const double t1 = tour.legDurationsS()[0];
  for (double t : {0.0, t1, tour.durationS(), tour.durationS() + 5.0, -1.0}) {
    const TrajectorySample s = tour.sample(t);
    EXPECT_LT(s.v_W_mps.norm(), 1e-9) << t;
    EXPECT_LT(s.a_W_mps2.norm(), 1e-9) << t;
  }
  EXPECT_LT((tour.sample(t1).p_W_m - Eigen::Vector3d(4, 0, 0)).norm(), 1e-12);
  EXPECT_LT((tour.sample(99).p_W_m - Eigen::Vector3d(4, 3, 0)).norm(), 1e-12);
  EXPECT_LT((tour.sample(t1 / 2).p_W_m - Eigen::Vector3d(2, 0, 0)).norm(), 1e-12);  // symmetric
}

TEST(MinJerkTour, RespectsSpeedAndAccelerationLimitsEverywhere) {
  const MinJerkTour tour = makeTour(1.5, 1.0);
  double vmax = 0, amax = 0;
  for (double t = 0; t <= tour.durationS(); t += 0.001) {
    vmax = std::max(vmax, tour.sample(t).v_W_mps.norm());
    amax = std::max(amax, tour.sample(t).a_W_mps2.norm());
  }
  EXPECT_LE(vmax, 1.5 + 1e-9);
  EXPECT_LE(amax, 1.0 + 1e-9);
  EXPECT_GT(std::max(vmax / 1.5, amax / 1.0), 0.999);  // and one of them is reached
}

TEST(MinJerkTour, VelocityAndAccelerationMatchFiniteDifferences) {
  const MinJerkTour tour = makeTour();
  const double h = 1e-5;
  for (double t = 0.1; t < tour.durationS() - 0.1; t += 0.37) {
    const Eigen::Vector3d v_fd = (tour.sample(t + h).p_W_m - tour.sample(t - h).p_W_m) / (2 * h);
    const Eigen::Vector3d a_fd = (tour.sample(t + h).v_W_mps - tour.sample(t - h).v_W_mps) / (2 * h);
    EXPECT_LT((v_fd - tour.sample(t).v_W_mps).norm(), 1e-6) << t;
    EXPECT_LT((a_fd - tour.sample(t).a_W_mps2).norm(), 1e-6) << t;
  }
}

TEST(TrajectoryServer, GivenNoTrajectoryThenNoSetpoint) {
  TrajectoryServer server(TrajectoryServerParams{});
  EXPECT_FALSE(server.sample(0).has_value());
}

TEST(TrajectoryServer, GivenMovingTrajectoryThenYawFollowsVelocityAndYawRateMatchesItsDerivative) {
  const auto tour = std::make_shared<const MinJerkTour>(makeTour());
  TrajectoryServerParams params;
  params.initial_yaw_rad = 1.0;
  TrajectoryServer server(params);
  const rt::TimeNs start = 1'000'000'000;
  server.setTrajectory({tour, start});

  const auto before = server.sample(0);  // before the start: first state, initial yaw held
  ASSERT_TRUE(before);
  EXPECT_EQ(before->yaw_rad, 1.0);
  EXPECT_LT(before->p_W_m.norm(), 1e-12);

  const double t1 = tour->legDurationsS()[0];
  const auto on_leg1 = server.sample(start + rt::secondsToNs(t1 / 2));
  EXPECT_NEAR(on_leg1->yaw_rad, 0.0, 1e-9);  // flying +x
  const auto on_leg2 = server.sample(start + rt::secondsToNs(t1 + tour->legDurationsS()[1] / 2));
  EXPECT_NEAR(on_leg2->yaw_rad, M_PI / 2, 1e-9);  // flying +y
  EXPECT_EQ(on_leg2->stamp_ns, start + rt::secondsToNs(t1 + tour->legDurationsS()[1] / 2));

  const auto after = server.sample(start + rt::secondsToNs(100));
  EXPECT_NEAR(after->yaw_rad, M_PI / 2, 1e-9);  // held after stopping
  EXPECT_LT((after->p_W_m - Eigen::Vector3d(4, 3, 0)).norm(), 1e-12);
}

/// A circle at constant speed: yaw rate is speed / radius.
class Circle final : public Trajectory {
 public:
  double durationS() const override { return 100; }
  TrajectorySample sample(double t) const override {
    const double w = 0.5, r = 2.0;
    TrajectorySample s;
    s.p_W_m = {r * std::cos(w * t), r * std::sin(w * t), 1};
    s.v_W_mps = {-r * w * std::sin(w * t), r * w * std::cos(w * t), 0};
    s.a_W_mps2 = {-r * w * w * std::cos(w * t), -r * w * w * std::sin(w * t), 0};
    return s;
  }
};

TEST(TrajectoryServer, GivenCircleThenYawRateIsSpeedOverRadius) {
  TrajectoryServer server(TrajectoryServerParams{});
  server.setTrajectory({std::make_shared<const Circle>(), 0});
  const auto sp = server.sample(rt::secondsToNs(3.0));
  EXPECT_NEAR(sp->yaw_rate_radps, 0.5, 1e-9);
  EXPECT_NEAR(std::remainder(sp->yaw_rad - (0.5 * 3.0 + M_PI / 2), 2 * M_PI), 0.0, 1e-9);
}

// A straight line at constant velocity from p0, to tell trajectories apart.
class Line final : public Trajectory {
 public:
  Line(Eigen::Vector3d p0, Eigen::Vector3d v, double duration_s)
      : p0_(std::move(p0)), v_(std::move(v)), d_(duration_s) {}
  double durationS() const override { return d_; }
  TrajectorySample sample(double t_s) const override {
    TrajectorySample s;
    s.p_W_m = p0_ + v_ * std::clamp(t_s, 0.0, d_);
    s.v_W_mps = v_;
    return s;
  }

 private:
  Eigen::Vector3d p0_, v_;
  double d_;
};

TEST(TrajectoryServer, GivenNewTrajectoryThenCurrentIsFlownUntilItsStartTime) {
  TrajectoryServer server(TrajectoryServerParams{});
  const auto first = std::make_shared<const Line>(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 0, 0), 10.0);
  server.setTrajectory({first, 0});
  // The replacement starts at 1.05 s from where the first will be then (1.05 m), going along y.
  const auto second = std::make_shared<const Line>(Eigen::Vector3d(1.05, 0, 0), Eigen::Vector3d(0, 1, 0), 10.0);
  server.setTrajectory({second, rt::secondsToNs(1.05)});
  const auto before = server.sample(rt::secondsToNs(1.0));
  ASSERT_TRUE(before);
  EXPECT_NEAR(before->p_W_m.x(), 1.0, 1e-12);
  EXPECT_NEAR(before->v_W_mps.x(), 1.0, 1e-12);
  const auto at = server.sample(rt::secondsToNs(1.05));
  ASSERT_TRUE(at);
  EXPECT_NEAR((at->p_W_m - Eigen::Vector3d(1.05, 0, 0)).norm(), 0.0, 1e-12);  // continuous position
  EXPECT_NEAR(at->v_W_mps.y(), 1.0, 1e-12);                                   // the new one is flown
  EXPECT_EQ(server.current().trajectory, second);
}

TEST(TrajectoryServer, GivenTrajectoryWhoseStartHasJustPassedThenItTakesOverAtOnce) {
  TrajectoryServer server(TrajectoryServerParams{});  // max_late_takeover_s 0.1
  server.setTrajectory({std::make_shared<const Line>(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 0, 0), 10.0), 0});
  const auto late = std::make_shared<const Line>(Eigen::Vector3d(0, 5, 0), Eigen::Vector3d::Zero(), 10.0);
  server.setTrajectory({late, rt::secondsToNs(0.5)});
  const auto s = server.sample(rt::secondsToNs(0.59));
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->p_W_m.y(), 5.0, 1e-12);
  EXPECT_EQ(server.lateRefusals(), 0U);
}

TEST(TrajectoryServer, GivenTrajectoryTakingOverLongAfterItsStartThenItIsRefusedAndTheCurrentOneFlown) {
  // A planner held up 1.5 s past its budget (issue 23's task overrun) hands over a plan that began where
  // the vehicle was 1.5 s ago: taking it over would jump the setpoint from x = 2 m to (0, 5) m.
  TrajectoryServer server(TrajectoryServerParams{});
  const auto first = std::make_shared<const Line>(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 0, 0), 10.0);
  server.setTrajectory({first, 0});
  server.setTrajectory(
      {std::make_shared<const Line>(Eigen::Vector3d(0, 5, 0), Eigen::Vector3d::Zero(), 10.0), rt::secondsToNs(0.5)});
  const auto s = server.sample(rt::secondsToNs(2.0));
  ASSERT_TRUE(s);
  EXPECT_NEAR((s->p_W_m - Eigen::Vector3d(2.0, 0, 0)).norm(), 0.0, 1e-12);  // no jump: the first one goes on
  EXPECT_EQ(server.current().trajectory, first);
  EXPECT_EQ(server.lateRefusals(), 1U);
  // The next plan, on time, takes over as usual.
  const auto next = std::make_shared<const Line>(Eigen::Vector3d(2.05, 0, 0), Eigen::Vector3d(0, 1, 0), 10.0);
  server.setTrajectory({next, rt::secondsToNs(2.05)});
  ASSERT_TRUE(server.sample(rt::secondsToNs(2.05)));
  EXPECT_EQ(server.current().trajectory, next);
  EXPECT_EQ(server.lateRefusals(), 1U);
}

TEST(TrajectoryServer, MeasuresCaptureToFirstSetpointLatencyOncePerTrajectory) {
  TrajectoryServer server(TrajectoryServerParams{});
  const auto line = std::make_shared<const Line>(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 0, 0), 10.0);
  server.setTrajectory({line, 0, -1});  // no image behind it (a take-off): not measured
  (void)server.sample(rt::secondsToNs(0.01));
  EXPECT_EQ(server.captureToSetpoint().count(), 0U);
  // Planned from an image captured at 0.90 s, taking over at 1.05 s, first sampled at 1.06 s.
  server.setTrajectory({line, rt::secondsToNs(1.05), rt::secondsToNs(0.90)});
  (void)server.sample(rt::secondsToNs(1.00));  // still the old one
  EXPECT_EQ(server.captureToSetpoint().count(), 0U);
  (void)server.sample(rt::secondsToNs(1.06));
  (void)server.sample(rt::secondsToNs(1.07));
  ASSERT_EQ(server.captureToSetpoint().count(), 1U);
  EXPECT_NEAR(server.captureToSetpoint().maxNs(), 0.16e9, 1.0);
}

TEST(TrajectoryServer, GivenFinishedTrajectoryThenEndIsHeldAtRest) {
  TrajectoryServer server(TrajectoryServerParams{});
  server.setTrajectory({std::make_shared<const Line>(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 0, 0), 2.0), 0});
  const auto s = server.sample(rt::secondsToNs(3.0));
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->p_W_m.x(), 2.0, 1e-12);
  EXPECT_EQ(s->v_W_mps.norm(), 0.0);
  EXPECT_EQ(s->a_W_mps2.norm(), 0.0);
}

/// A vehicle link whose state the test sets; it counts the setpoints sent.
class ScriptedLink final : public hal::VehicleLink {
 public:
  std::string_view backend() const override { return "test"; }
  hal::DeviceHealth health(rt::TimeNs /*now_ns*/) const override { return {}; }
  void send(const hal::Setpoint& /*setpoint*/) override { ++sent; }
  hal::VehicleStatus status(rt::TimeNs now_ns) override { return {now_ns, link_ok, true, hal::FlightMode::kOffboard}; }
  bool link_ok = false;
  int sent = 0;
};

TEST(TrajectoryServerTask, ReportsTheLinkLostOnlyAfterItWasUp) {
  const rt::SharedSlot<TimedTrajectory> trajectories;
  rt::LatestSlot<hal::Setpoint> setpoints;
  ScriptedLink link;
  TrajectoryServerTask task(TrajectoryServerParams{}, trajectories, link, setpoints);
  std::atomic<bool> lost{true};
  task.reportLinkLossTo(lost);
  task.step(0);
  EXPECT_FALSE(lost.load()) << "a link never up (no vehicle, or not yet connected) is not lost";
  EXPECT_EQ(link.sent, 0) << "no trajectory yet: nothing is sent";
  link.link_ok = true;
  task.step(10'000'000);
  EXPECT_FALSE(lost.load());
  link.link_ok = false;
  task.step(20'000'000);
  EXPECT_TRUE(lost.load());
  link.link_ok = true;
  task.step(30'000'000);
  EXPECT_FALSE(lost.load()) << "the report follows the link; the supervisor latches the hold";
}

}  // namespace
}  // namespace aerotrack::trajectory_server
