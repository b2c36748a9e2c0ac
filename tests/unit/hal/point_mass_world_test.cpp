// The foundation's point-mass world against closed-form cases, and the device factory.
#include <gtest/gtest.h>

#include <cmath>

#include "aerotrack/hal/factory.hpp"
#include "aerotrack/hal/sim/point_mass_world.hpp"

namespace aerotrack::hal::sim {
namespace {

using rt::kNsPerSecond;

TEST(PointMassWorld, GivenNoSetpointThenHoldsItsStartPose) {
  PointMassParams p;
  p.start_p_W_m = {1, 2, 3};
  p.start_yaw_rad = 0.5;
  PointMassWorld world(p, 0);
  world.step(5 * kNsPerSecond);
  const PointMassTruth t = world.truth();
  EXPECT_EQ(t.stamp_ns, 5 * kNsPerSecond);
  EXPECT_NEAR((t.p_W_m - p.start_p_W_m).norm(), 0.0, 1e-12);
  EXPECT_NEAR(t.yaw_rad, 0.5, 1e-12);
}

TEST(PointMassWorld, GivenFeedForwardOnlyThenMotionIsExactConstantAcceleration) {
  PointMassParams p;
  p.position_gain_per_s2 = 0.0;
  p.velocity_gain_per_s = 0.0;
  PointMassWorld world(p, 0);
  Setpoint sp;
  sp.a_W_mps2 = {1.0, -2.0, 0.5};
  world.setSetpoint(sp);
  world.step(2 * kNsPerSecond);
  const PointMassTruth t = world.truth();
  // p = a t^2 / 2, v = a t, with t = 2 s
  EXPECT_NEAR((t.p_W_m - Eigen::Vector3d(2.0, -4.0, 1.0)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((t.v_W_mps - Eigen::Vector3d(2.0, -4.0, 1.0)).norm(), 0.0, 1e-9);
}

TEST(PointMassWorld, GivenLargeStepThenAccelerationSaturatesAndPositionConverges) {
  PointMassParams p;
  p.max_accel_mps2 = 3.0;
  PointMassWorld world(p, 0);
  Setpoint sp;
  sp.p_W_m = {10, 0, 0};
  world.setSetpoint(sp);
  double max_a = 0;
  for (int i = 1; i <= 1000; ++i) {  // 10 s in 10 ms steps
    world.step(i * 10'000'000LL);
    max_a = std::max(max_a, world.truth().a_W_mps2.norm());
  }
  EXPECT_LE(max_a, 3.0 + 1e-9);
  EXPECT_GT(max_a, 2.99);
  EXPECT_LT((world.truth().p_W_m - sp.p_W_m).norm(), 0.01);
  EXPECT_LT(world.truth().v_W_mps.norm(), 0.01);
}

TEST(PointMassWorld, GivenYawSetpointThenTurnsShortWayAtBoundedRate) {
  PointMassParams p;
  p.start_yaw_rad = 3.0;
  p.max_yaw_rate_radps = 1.0;
  PointMassWorld world(p, 0);
  Setpoint sp;
  sp.yaw_rad = -3.0;  // 0.283 rad away through +pi, not 6 rad the long way
  world.setSetpoint(sp);
  world.step(100'000'000);  // 0.1 s: at most 0.1 rad
  EXPECT_NEAR(world.truth().yaw_rad, 3.1, 1e-9);
  world.step(kNsPerSecond);
  EXPECT_NEAR(world.truth().yaw_rad, -3.0, 1e-9);
}

TEST(PointMassWorld, GivenStepBackwardsThenIgnored) {
  PointMassWorld world(PointMassParams{}, 1000);
  world.step(500);
  EXPECT_EQ(world.truth().stamp_ns, 1000);
}

TEST(DeviceFactory, GivenAllNullThenEverySlotFilledAndNoWorld) {
  const auto d = makeDevices(HalConfig{}, PointMassParams{}, 0);
  ASSERT_TRUE(d);
  ASSERT_NE(d->gimbal_camera, nullptr);
  ASSERT_NE(d->depth_camera, nullptr);
  ASSERT_NE(d->gimbal, nullptr);
  ASSERT_NE(d->odometry, nullptr);
  ASSERT_NE(d->vehicle_link, nullptr);
  EXPECT_EQ(d->world, nullptr);
  EXPECT_EQ(d->odometry->backend(), "null");
  EXPECT_EQ(d->odometry->health(0).state, DeviceHealth::State::kAbsent);
  EXPECT_FALSE(d->odometry->read(0).has_value());
  EXPECT_EQ(d->gimbal_camera->grab(0), nullptr);
}

TEST(DeviceFactory, GivenSimOdometryAndLinkThenTheyShareOneWorld) {
  HalConfig c;
  c.odometry = "sim";
  c.vehicle_link = "sim";
  PointMassParams p;
  p.start_p_W_m = {0, 0, 1};
  auto d = makeDevices(c, p, 0);
  ASSERT_TRUE(d);
  ASSERT_NE(d->world, nullptr);
  Setpoint sp;
  sp.p_W_m = {1, 0, 1};
  d->vehicle_link->send(sp);
  d->world->step(10 * kNsPerSecond);
  const auto odom = d->odometry->read(0);
  ASSERT_TRUE(odom.has_value());
  EXPECT_NEAR(odom->p_WB_m.x(), 1.0, 1e-3);
  EXPECT_EQ(odom->stamp_ns, 10 * kNsPerSecond);
  EXPECT_EQ(d->vehicle_link->status(0).mode, FlightMode::kOffboard);
}

TEST(DeviceFactory, GivenUnknownBackendInConfigThenErrorNamesKey) {
  const auto root = rt::ConfigNode::fromString(
      "gimbal_camera: null\ndepth_camera: null\ngimbal: null\nodometry: gps\nvehicle_link: null\n", "hal.yaml");
  ASSERT_TRUE(root);
  const auto parsed = rt::parseConfig<HalConfig>([&] { return parseHalConfig(*root); });
  ASSERT_FALSE(parsed);
  EXPECT_EQ(parsed.error().message, "hal.yaml:4: odometry: 'gps' is not one of: null, sim");
}

}  // namespace
}  // namespace aerotrack::hal::sim
