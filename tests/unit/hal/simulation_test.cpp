// The integrated simulation against hand-built situations: sensor rates and latencies, the
// depth camera seeing a wall at a known distance, occlusion hiding the person, odometry noise,
// gimbal commands, collisions counted, a forced occlusion hiding the person from the depth camera too.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "aerotrack/hal/sim/simulation.hpp"
#include "support/require.hpp"

namespace aerotrack::hal::sim {
namespace {

using rt::kNsPerSecond;

/// A person standing 4 m in front of a hovering drone (their walk starts only after 500 s),
/// optionally behind a wall, and a wall 6 m behind the person.
std::string worldYaml(bool wall_between) {
  std::string boxes = "    - {min_m: [10.0, -5.0, 0.0], max_m: [10.5, 5.0, 3.0]}\n";
  if (wall_between) boxes += "    - {min_m: [1.5, -2.0, 0.0], max_m: [2.0, 2.0, 3.0]}\n";
  return R"(name: test
end_margin_s: 1.0
max_duration_s: 2000.0
world:
  bounds_min_m: [-5.0, -5.0, 0.0]
  bounds_max_m: [12.0, 5.0, 4.0]
  boxes:
)" + boxes +
         R"(person:
  height_m: 1.75
  torso_m: 0.5
  start_delay_s: 500.0
  path:
    - {p_m: [4.0, 0.0], speed_mps: 1.0}
    - {p_m: [4.0, 3.0], speed_mps: 0.0}
drone:
  start_m: [0.0, 0.0, 1.5]
  start_yaw_rad: 0.0
  radius_m: 0.25
  mass_kg: 1.0
  thrust_to_weight: 2.5
success:
  tracking_distance_m: 2.5
  final_distance_factor: 2.0
)";
}

std::unique_ptr<Simulation> makeSim(bool wall_between, bool depth = true, const SimFaults& faults = {}) {
  const ScenarioSpec spec =
      aerotrack::test::require(parseScenarioSpec(worldYaml(wall_between), "test.yaml"), "test.yaml");
  const ScenarioInstance trial = aerotrack::test::require(instantiate(spec, 1), "instantiate");
  SimulationOptions options;
  options.render_depth = depth;
  options.faults = faults;
  return aerotrack::test::require(Simulation::create(trial, options, 0), "Simulation::create");
}

void hover(Simulation& sim, double seconds, std::vector<DetectionFrame>* detections = nullptr) {
  const rt::TimeNs start = sim.truth().stamp_ns;
  Setpoint hold;
  hold.p_W_m = Eigen::Vector3d(0, 0, 1.5);
  for (rt::TimeNs t = start; t <= start + rt::secondsToNs(seconds); t += 5'000'000) {
    hold.stamp_ns = t;  // streamed, as a companion computer does (the flight controller holds after 1 s without)
    sim.setpointInbox().write(hold);
    sim.step(t);
    while (auto f = sim.detectionsOut().try_pop())
      if (detections != nullptr) detections->push_back(*f);
  }
}

TEST(Simulation, GivenPersonInViewThenDetectionsAt30HzArriveAfterTheDetectorLatency) {
  auto sim = makeSim(false, false);
  std::vector<DetectionFrame> frames;
  hover(*sim, 2.0, &frames);
  EXPECT_NEAR(static_cast<double>(frames.size()), 2.0 * 30.0, 2.0);
  for (const DetectionFrame& f : frames) EXPECT_EQ(f.result_ns - f.stamp_ns, 40 * rt::kNsPerMillisecond);
  int with_person = 0;
  for (const DetectionFrame& f : frames) with_person += f.person_count == 1 ? 1 : 0;
  EXPECT_GT(with_person, 55);
  // The person stands 4 m ahead on the optical axis: the torso's centre near the image centre.
  const PersonDetection& p = frames.back().persons[0];
  double u_sum = 0.0;
  int detected = 0;
  for (CocoKeypoint k :
       {CocoKeypoint::kLeftShoulder, CocoKeypoint::kRightShoulder, CocoKeypoint::kLeftHip, CocoKeypoint::kRightHip})
    if (p.keypoints[index(k)].score > 0.0) {  // a missed keypoint has score 0 and no position
      u_sum += p.keypoints[index(k)].u_px;
      ++detected;
    }
  ASSERT_GT(detected, 0);
  EXPECT_NEAR(u_sum / detected, 320.0, 15.0);
  EXPECT_EQ(sim->personSight(sim->truth().T_WC, sim->truth().person), Sight::kVisible);
  // Turned away (the camera yawed half a turn about the world's z), the torso leaves the image.
  Eigen::Isometry3d T_WC_away = sim->truth().T_WC;
  T_WC_away.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix() * T_WC_away.linear();
  EXPECT_EQ(sim->personSight(T_WC_away, sim->truth().person), Sight::kOutOfImage);
}

TEST(Simulation, GivenWallBetweenThenPersonIsHiddenAndNotDetected) {
  auto sim = makeSim(true, false);
  std::vector<DetectionFrame> frames;
  hover(*sim, 1.0, &frames);
  ASSERT_FALSE(frames.empty());
  for (const DetectionFrame& f : frames) EXPECT_EQ(f.person_count, 0U);
  EXPECT_EQ(sim->personSight(sim->truth().T_WC, sim->truth().person), Sight::kOccluded);
}

TEST(Simulation, GivenWallAheadThenDepthFramesAt15HzSeeItAtItsDistance) {
  auto sim = makeSim(false, true);
  std::uint64_t version = 0, frames = 0;
  DepthFrameHandle last;
  Setpoint hold;
  hold.p_W_m = Eigen::Vector3d(0, 0, 1.5);
  sim->setpointInbox().write(hold);
  for (rt::TimeNs t = 0; t <= 2 * kNsPerSecond; t += 5'000'000) {
    sim->step(t);
    if (sim->depthOut().version() != version) {
      version = sim->depthOut().version();
      last = sim->depthOut().read();
      ++frames;
    }
  }
  EXPECT_NEAR(static_cast<double>(frames), 30.0, 1.0);
  ASSERT_TRUE(last);
  // The top rows look over the person's head (1.75 m tall, 4 m away) at the wall at x = 10 m,
  // 10 - 0.12 m (the camera's mount) in front of the camera.
  const int u = last->depth_m.cols / 2 + 10;
  float seen = 0.0F;
  for (int v = 0; v < last->depth_m.rows / 2 && seen == 0.0F; ++v) seen = last->depth_m.at<float>(v, u);
  EXPECT_NEAR(seen, 10.0 - 0.12, 3.0 * 0.0015 * 100.0);  // 3 sigma of the depth noise at ~10 m
}

TEST(Simulation, GivenAForcedOcclusionThenTheDepthCameraDoesNotSeeThePersonEither) {
  // The person stands 4 m ahead (their near side 3.75 m, 3.63 m from the camera's mount); from 0.5 s to 1.5 s a
  // forced occlusion hides them from every camera on the drone: the depth camera's centre pixel then sees the
  // wall 10 m away behind them.
  SimFaults faults;
  faults.person_occluded = {0.5, 1.5};
  auto sim = makeSim(false, true, faults);
  Setpoint hold;
  hold.p_W_m = Eigen::Vector3d(0, 0, 1.5);
  sim->setpointInbox().write(hold);
  std::uint64_t version = 0;
  std::array<int, 3> frames{}, seen{};  // before, in and after the window
  for (rt::TimeNs t = 0; t <= 2 * kNsPerSecond; t += 5'000'000) {
    hold.stamp_ns = t;
    sim->setpointInbox().write(hold);
    sim->step(t);
    if (sim->depthOut().version() == version) continue;
    version = sim->depthOut().version();
    const DepthFrameHandle frame = sim->depthOut().read();
    const float centre = frame->depth_m.at<float>(frame->depth_m.rows / 2, frame->depth_m.cols / 2);
    const double t_s = sim->secondsSinceStart(frame->stamp_ns);
    const std::size_t window = t_s < 0.5 ? 0 : (t_s < 1.5 ? 1 : 2);
    ++frames[window];
    seen[window] += std::abs(static_cast<double>(centre) - 3.63) < 0.2 ? 1 : 0;
  }
  EXPECT_GE(frames[0], 6);  // 15 Hz
  EXPECT_GE(frames[1], 14);
  EXPECT_GE(seen[0], frames[0] - 1);  // a pixel may drop out
  EXPECT_EQ(seen[1], 0);
  EXPECT_GE(seen[2], frames[2] - 1);
  EXPECT_GE(frames[2], 6);
}

TEST(Simulation, OdometryIsDelayedByItsLatencyAndNoisyAsConfigured) {
  auto sim = makeSim(false, false);
  Setpoint hold;
  hold.p_W_m = Eigen::Vector3d(0, 0, 1.5);
  sim->setpointInbox().write(hold);
  double sum2 = 0.0;
  int n = 0;
  for (rt::TimeNs t = 0; t <= 20 * kNsPerSecond; t += 10'000'000) {
    sim->step(t);
    const auto o = sim->odometryOut().read();
    if (t < 10 * rt::kNsPerMillisecond) continue;  // the first sample is due after the latency
    ASSERT_TRUE(o);
    if (t > 0) {
      EXPECT_EQ(t - o->stamp_ns, 10 * rt::kNsPerMillisecond);
    }
    if (t > 3 * kNsPerSecond) {  // hovering still: the error is the noise
      sum2 += (o->p_WB_m.x() - sim->truth().drone.p_W_m.x()) * (o->p_WB_m.x() - sim->truth().drone.p_W_m.x());
      ++n;
    }
  }
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.02, 0.003);
}

TEST(Simulation, GimbalFollowsAngleCommandsAndReportsEncoderReadings) {
  auto sim = makeSim(false, false);
  GimbalCommand c;
  c.mode = GimbalCommand::Mode::kAngle;
  c.angle_rad = 2.0 * M_PI + 1.0;  // more than a turn: the slip ring allows it
  sim->gimbalInbox().write(c);
  hover(*sim, 4.0);
  const auto encoder = sim->gimbalOut().read();
  ASSERT_TRUE(encoder);
  EXPECT_NEAR(encoder->angle_rad, 2.0 * M_PI + 1.0, 1e-3);
}

TEST(Simulation, GivenSetpointInsideAWallThenTheCollisionIsCounted) {
  auto sim = makeSim(false, false);
  Setpoint into_wall;
  into_wall.p_W_m = Eigen::Vector3d(10.2, 0, 1.5);
  into_wall.yaw_rad = 0.0;
  for (rt::TimeNs t = 0; t <= 10 * kNsPerSecond; t += 5'000'000) {
    into_wall.stamp_ns = t;  // streamed (the flight controller holds after 1 s without)
    sim->setpointInbox().write(into_wall);
    sim->step(t);
  }
  EXPECT_GE(sim->metrics().collisions(), 1);
  EXPECT_LT(sim->metrics().minClearanceM(), 0.0);
}

TEST(Simulation, GivenSetpointsThatStopThenTheFlightControllerHoldsWhereItIsAfterOneSecond) {
  // PX4's offboard-loss failsafe (COM_OF_LOSS_T): the vehicle_link_lost fault of issue 23 relies on it.
  auto sim = makeSim(false, false);
  Setpoint go;
  go.p_W_m = Eigen::Vector3d(0, 0, 1.5);
  for (rt::TimeNs t = 0; t <= 3 * kNsPerSecond; t += 5'000'000) {  // climb to 1.5 m, streamed
    go.stamp_ns = t;
    sim->setpointInbox().write(go);
    sim->step(t);
  }
  go.p_W_m = Eigen::Vector3d(6, 0, 1.5);  // one last setpoint, 6 m away, then silence
  go.stamp_ns = 3 * kNsPerSecond + 5'000'000;
  sim->setpointInbox().write(go);
  for (rt::TimeNs t = go.stamp_ns; t <= 9 * kNsPerSecond; t += 5'000'000) sim->step(t);
  EXPECT_EQ(sim->offboardLosses(), 1U);
  EXPECT_LT(sim->truth().drone.v_W_mps.norm(), 0.2);  // at rest
  EXPECT_LT(sim->truth().drone.p_W_m.x(), 5.0);       // held short of the stale setpoint
  EXPECT_GT(sim->truth().drone.p_W_m.x(), 0.5);       // it had flown towards it for a second
}

TEST(Simulation, GivenSameSeedThenBitIdenticalTruth) {
  auto a = makeSim(false, true), b = makeSim(false, true);
  hover(*a, 3.0);
  hover(*b, 3.0);
  EXPECT_EQ(a->truth().drone.p_W_m, b->truth().drone.p_W_m);
  EXPECT_EQ(a->odometryOut().read()->p_WB_m, b->odometryOut().read()->p_WB_m);
}

}  // namespace
}  // namespace aerotrack::hal::sim
