// The simulator's own parts: the gimbal motor against closed-form responses, the ground-truth
// metrics' verdicts, the baseline follower's trail geometry, and the device factory (sim, null, replay).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "aerotrack/hal/factory.hpp"
#include "aerotrack/hal/replay/stream_codecs.hpp"
#include "aerotrack/hal/sim/baseline_follower.hpp"
#include "aerotrack/hal/sim/gimbal_motor.hpp"
#include "aerotrack/hal/sim/metrics.hpp"

namespace aerotrack::hal::sim {
namespace {

GimbalCommand rateCommand(double rate_radps) {
  GimbalCommand c;
  c.mode = GimbalCommand::Mode::kRate;
  c.rate_radps = rate_radps;
  return c;
}

TEST(GimbalMotor, GivenRateStepThenFirstOrderResponseInClosedForm) {
  GimbalSpec spec;
  spec.time_constant_s = 0.05;
  spec.max_rate_radps = 10.0;
  GimbalMotor motor(spec);
  for (int i = 0; i < 100; ++i) motor.step(rateCommand(2.0), 0.001);  // 0.1 s = 2 tau
  // rate(t) = 2 (1 - e^{-t/tau}); angle(t) = 2 (t - tau (1 - e^{-t/tau}))
  EXPECT_NEAR(motor.rateRadps(), 2.0 * (1.0 - std::exp(-2.0)), 1e-9);
  EXPECT_NEAR(motor.angleRad(), 2.0 * (0.1 - 0.05 * (1.0 - std::exp(-2.0))), 1e-9);
}

TEST(GimbalMotor, GivenRateAboveLimitThenClamped) {
  GimbalSpec spec;
  spec.max_rate_radps = 3.0;
  GimbalMotor motor(spec);
  for (int i = 0; i < 2000; ++i) motor.step(rateCommand(50.0), 0.001);
  EXPECT_NEAR(motor.rateRadps(), 3.0, 1e-9);
}

TEST(GimbalMotor, GivenContinuousRotationThenAngleUnwrapsBeyondTwoPi) {
  GimbalMotor motor(GimbalSpec{});
  for (int i = 0; i < 5000; ++i) motor.step(rateCommand(4.0), 0.001);  // ~20 rad: three turns
  EXPECT_GT(motor.angleRad(), 19.0);
  EXPECT_GT(motor.encoder(0).angle_rad, 19.0);
}

TEST(GimbalMotor, GivenAngleCommandThenConvergesWithoutOvershootBeyondLimit) {
  GimbalSpec spec;
  GimbalMotor motor(spec);
  GimbalCommand c;
  c.mode = GimbalCommand::Mode::kAngle;
  c.angle_rad = 7.0;  // more than a turn: the gimbal goes the long way round as told
  c.max_rate_radps = 2.0;
  double max_rate = 0.0;
  for (int i = 0; i < 8000; ++i) {
    motor.step(c, 0.001);
    max_rate = std::max(max_rate, std::abs(motor.rateRadps()));
  }
  EXPECT_NEAR(motor.angleRad(), 7.0, 1e-3);
  EXPECT_LE(max_rate, 2.0 + 1e-9);
}

TEST(GimbalMotor, EncoderQuantisesToItsResolution) {
  GimbalSpec spec;
  spec.encoder_resolution_rad = 0.01;
  GimbalMotor motor(spec, 0.123456);
  EXPECT_NEAR(motor.encoder(5).angle_rad, 0.12, 1e-12);
  EXPECT_EQ(motor.encoder(5).stamp_ns, 5);
}

ScenarioSpec specWithSuccess(double distance_m) {
  ScenarioSpec s;
  s.drone.radius_m = 0.25;
  s.success.tracking_distance_m = distance_m;
  s.success.final_distance_factor = 2.0;
  return s;
}

MetricsSample sampleOf(double t_s, const Eigen::Vector3d& drone_m, const Eigen::Vector3d& person_m, double clearance_m,
                       Sight sight, bool tracking, double dt_s) {
  MetricsSample s;
  s.t_s = t_s;
  s.dt_s = dt_s;
  s.drone_m = drone_m;
  s.person_m = person_m;
  s.clearance_m = clearance_m;
  s.sight = sight;
  s.tracking = tracking;
  return s;
}

TEST(SimMetrics, GivenCleanRunThenSuccessAndRatios) {
  SimMetrics m(specWithSuccess(2.5));
  const Eigen::Vector3d person(0, 0, 0), drone(2.5, 0, 1.5);
  // Hidden for samples 50-59: out of the image for the first 4, then behind an obstacle.
  for (int i = 0; i < 100; ++i) {
    const Sight sight = i < 50 || i >= 60 ? Sight::kVisible : i < 54 ? Sight::kOutOfImage : Sight::kOccluded;
    m.record(sampleOf(0.02 * i, drone, person, 3.0, sight, i >= 10, 0.02));
  }
  EXPECT_TRUE(m.success()) << m.failureReason();
  EXPECT_EQ(m.collisions(), 0);
  EXPECT_NEAR(m.visibleRatio(), 80.0 / 90.0, 1e-12);  // 10 of 90 tracked samples invisible
  ASSERT_EQ(m.losses().size(), 1U);
  EXPECT_NEAR(m.longestLossS(), 0.2, 1e-12);
  EXPECT_EQ(m.losses()[0].cause, Sight::kOutOfImage);  // the loss is blamed on its first sample
  EXPECT_NEAR(m.outOfImageS(), 4 * 0.02, 1e-12);
  EXPECT_NEAR(m.occludedS(), 6 * 0.02, 1e-12);
  EXPECT_NEAR(m.distanceMeanM(), 2.5, 1e-12);
  EXPECT_NEAR(m.minClearanceM(), 2.75, 1e-12);
}

TEST(SimMetrics, GivenContactThenOneCollisionPerContactAndFailure) {
  SimMetrics m(specWithSuccess(2.5));
  const Eigen::Vector3d p(2.5, 0, 1.5), q(0, 0, 0);
  for (double clearance : {1.0, 0.2, 0.1, 1.0, 0.2, 1.0})
    m.record(sampleOf(0, p, q, clearance, Sight::kVisible, true, 0.02));
  EXPECT_EQ(m.collisions(), 2);
  EXPECT_FALSE(m.success());
  EXPECT_NE(m.failureReason().find("2 collision(s)"), std::string::npos);
}

TEST(SimMetrics, GivenLossNeverRecoveredOrFarAtTheEndThenFailure) {
  SimMetrics lost(specWithSuccess(2.5));
  lost.record(sampleOf(1.0, {2, 0, 1}, {0, 0, 0}, 5, Sight::kVisible, true, 0.02));
  lost.record(sampleOf(1.5, {2, 0, 1}, {0, 0, 0}, 5, Sight::kOccluded, true, 0.02));
  EXPECT_NE(lost.failureReason().find("never re-acquired"), std::string::npos);
  SimMetrics far(specWithSuccess(2.5));
  far.record(sampleOf(1.0, {6, 0, 1}, {0, 0, 0}, 5, Sight::kVisible, true, 0.02));
  EXPECT_NE(far.failureReason().find("final distance 6.0 m exceeds 5.0 m"), std::string::npos);
}

TruthSnapshot truthAt(const Eigen::Vector3d& person, bool walking) {
  TruthSnapshot t;
  t.person_p_W_m = person;
  t.person_walking = walking;
  t.drone_p_W_m = Eigen::Vector3d(-2.5, 0, 1.5);
  t.camera_p_W_m = t.drone_p_W_m;
  return t;
}

TEST(BaselineFollower, GivenPersonNotWalkingThenHoldsTheStartAtAltitude) {
  BaselineFollower f(BaselineFollowerParams{}, Eigen::Vector3d(-2.5, 0, 0), 0.0);
  const FollowCommand c = f.update(truthAt({0, 0, 0}, false), 0);
  EXPECT_NEAR((c.setpoint.p_W_m - Eigen::Vector3d(-2.5, 0, 1.5)).norm(), 0.0, 1e-12);
}

TEST(BaselineFollower, GivenPersonTurnedACornerThenTargetIsOnTheTrailNotTheChord) {
  BaselineFollower f(BaselineFollowerParams{}, Eigen::Vector3d(-2.5, 0, 0), 0.0);
  for (double x = 0.0; x <= 10.0; x += 0.05) f.update(truthAt({x, 0, 0}, true), 0);  // east 10 m
  for (double y = 0.0; y <= 1.0; y += 0.05) f.update(truthAt({10, y, 0}, true), 0);  // then north 1 m
  const FollowCommand c = f.update(truthAt({10, 1.0, 0}, true), 0);
  // 2.5 m of trail back from (10, 1): 1 m south to the corner, then 1.5 m west.
  EXPECT_NEAR(c.setpoint.p_W_m.x(), 8.5, 0.06);
  EXPECT_NEAR(c.setpoint.p_W_m.y(), 0.0, 0.06);
}

TEST(BaselineFollower, GimbalCommandPointsAtThePersonRelativeToTheBody) {
  BaselineFollower f(BaselineFollowerParams{}, Eigen::Vector3d(0, 0, 0), 0.0);
  TruthSnapshot t = truthAt({0, 5, 0}, false);
  t.camera_p_W_m = Eigen::Vector3d(0, 0, 1.5);
  t.drone_yaw_rad = M_PI / 2;       // body faces the person: bearing 0 in the body
  t.gimbal_angle_rad = 4.0 * M_PI;  // two turns wound up: stay near them
  const FollowCommand c = f.update(t, 0);
  EXPECT_EQ(c.gimbal.mode, GimbalCommand::Mode::kAngle);
  EXPECT_NEAR(c.gimbal.angle_rad, 4.0 * M_PI, 1e-9);
}

TEST(DeviceFactory, GivenAllNullThenEverySlotFilledAndNoSimulation) {
  const auto d = makeDevices(HalConfig{}, nullptr, SimulationOptions{}, 0);
  ASSERT_TRUE(d);
  ASSERT_NE(d->gimbal_camera, nullptr);
  ASSERT_NE(d->depth_camera, nullptr);
  ASSERT_NE(d->gimbal, nullptr);
  ASSERT_NE(d->odometry, nullptr);
  ASSERT_NE(d->vehicle_link, nullptr);
  EXPECT_EQ(d->simulation, nullptr);
  EXPECT_EQ(d->odometry->backend(), "null");
  EXPECT_EQ(d->odometry->health(0).state, DeviceHealth::State::kAbsent);
  EXPECT_FALSE(d->odometry->read(0).has_value());
  EXPECT_EQ(d->gimbal_camera->grab(0), nullptr);
  EXPECT_FALSE(d->gimbal_camera->grabDetections(0).has_value());
}

TEST(DeviceFactory, GivenSimBackendWithoutScenarioThenError) {
  HalConfig c;
  c.odometry = "sim";
  const auto d = makeDevices(c, nullptr, SimulationOptions{}, 0);
  ASSERT_FALSE(d);
  EXPECT_EQ(d.error().message, "hal: sim backends need a scenario");
}

TEST(DeviceFactory, GivenUnknownBackendInConfigThenErrorNamesKey) {
  const auto root = rt::ConfigNode::fromString(
      "gimbal_camera: null\ndepth_camera: null\ngimbal: null\nodometry: gps\nvehicle_link: null\n", "hal.yaml");
  ASSERT_TRUE(root);
  const auto parsed = rt::parseConfig<HalConfig>([&] { return parseHalConfig(*root); });
  ASSERT_FALSE(parsed);
  EXPECT_EQ(parsed.error().message, "hal.yaml:4: odometry: 'gps' is not one of: null, sim, replay, real");
}

TEST(DeviceFactory, GivenReplayBackendsThenTheyServeTheRecordingOrSayWhatIsMissing) {
  const std::string base =
      "gimbal_camera: null\ndepth_camera: null\ngimbal: replay\nodometry: replay\n"
      "vehicle_link: replay\n";
  const auto no_map = rt::ConfigNode::fromString(base, "hal.yaml");
  ASSERT_TRUE(no_map);
  const auto refused = rt::parseConfig<HalConfig>([&] { return parseHalConfig(*no_map); });
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("replay: a replay backend needs the replay: map"), std::string::npos);

  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("aerotrack-factory-replay-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  replay::DatasetManifest m;
  m.software_version = "test";
  m.start_ns = 5'000'000'000;
  m.source = "sim";
  m.streams = {{"odometry", "odometry.csv"}};
  ASSERT_TRUE(replay::writeManifest(m, (dir / "manifest.yaml").string()));
  {
    auto w =
        replay::CsvStreamWriter::create((dir / "odometry.csv").string(), replay::DeliveredOdometryCodec::columns());
    ASSERT_TRUE(w);
    OdometrySample o;
    o.stamp_ns = m.start_ns;
    o.p_WB_m = {1, 2, 3};
    ASSERT_TRUE(w->write(o.stamp_ns, replay::DeliveredOdometryCodec::encode({o, 0})));
  }
  const auto root = rt::ConfigNode::fromString(
      base + "replay:\n  dir: " + dir.string() + "\n  offset_s: 0\n  loop: false\n  bad_rows: strict\n", "hal.yaml");
  ASSERT_TRUE(root);
  const auto config = rt::parseConfig<HalConfig>([&] { return parseHalConfig(*root); });
  ASSERT_TRUE(config) << config.error().message;
  // No gimbal stream in the recording: a start-up error, not a silent gimbal.
  const auto missing = makeDevices(*config, nullptr, SimulationOptions{}, 0);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("has no gimbal stream"), std::string::npos) << missing.error().message;
  HalConfig odometry_only = *config;
  odometry_only.gimbal = "null";
  const auto d = makeDevices(odometry_only, nullptr, SimulationOptions{}, 0);
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_EQ(d->odometry->backend(), "replay");
  EXPECT_EQ(d->vehicle_link->backend(), "replay");
  const auto sample = d->odometry->read(0);
  ASSERT_TRUE(sample.has_value());
  EXPECT_EQ(sample->p_WB_m, Eigen::Vector3d(1, 2, 3));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace aerotrack::hal::sim
