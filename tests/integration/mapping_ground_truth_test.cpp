// The mapper against the simulator's ground truth (issue 4): fly the forest with the simulated
// D435 (noise sigma = k z^2, dropout), map it, then compare with the true obstacles. Measured
// (seed 1, 25 s), OctoMap's prob_miss 0.4: precision 0.9999 over 36,764 occupied voxels; recall 0.986
// on the trees and 0.886 on the ground. The configured 0.45: precision 0.9999 over 44,820; recall
// 0.990 on the trees and 0.969 on the ground. Along sharp_turn's building (32 s): obstacle recall
// 0.9936 with 0.4, 0.9972 with 0.45.
//   precision: occupied map voxels whose centre lies within one voxel diagonal of a true surface;
//   recall:    surface voxels that a noise-free camera at the same poses saw within range, found
//              occupied in the map (or a face neighbour of them: the noise at 6 m is 5 cm).
#include <gtest/gtest.h>

#include "aerotrack/hal/sim/bystanders.hpp"

#include <algorithm>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "aerotrack/hal/sim/baseline_follower.hpp"
#include "aerotrack/hal/sim/simulation.hpp"
#include "aerotrack/mapping/mapper.hpp"

namespace aerotrack {
namespace {

using KeySet = std::set<std::array<int, 3>>;

std::array<int, 3> keyOf(const octomap::OcTreeKey& k) {
  return {k[0], k[1], k[2]};
}

struct MapScore {
  std::size_t occupied = 0, seen = 0;
  double precision = 0.0, recall = 0.0, obstacle_recall = 0.0, ground_recall = 0.0;
  std::uint64_t frames = 0;
};

/// Flies `scenario` (seed 1) for duration_s with the truth-fed follower, maps it with prob_miss, and
/// scores the map against the true obstacles (see the top of the file).
/// The followed person's body at t_ns as the simulator renders it in depth (a cylinder of the scenario's height).
hal::sim::Cylinder personBody(const hal::sim::Simulation& sim, rt::TimeNs t_ns) {
  return {sim.personAt(t_ns).p_W_m.head<2>(), hal::sim::kPersonBodyRadiusM, 0.0, sim.scenario().spec.person.height_m};
}

/// Their column as the mapper leaves it out (a voxel's margin around the body; the ground row kept).
mapping::ExcludedBody excluded(const hal::sim::Cylinder& body) {
  return {body.center_W_m, body.radius_m + 0.1, 0.1, body.z_max_m + 0.1};
}

MapScore mapAndScore(const std::string& scenario, double duration_s, double prob_miss) {
  MapScore score;
  auto spec = hal::sim::loadScenarioSpec(AEROTRACK_SOURCE_DIR "/config/scenarios/" + scenario + ".yaml");
  EXPECT_TRUE(spec);
  if (!spec) return score;
  auto trial = hal::sim::instantiate(*spec, 1);
  EXPECT_TRUE(trial);
  if (!trial) return score;
  auto sim = hal::sim::Simulation::create(*trial, hal::sim::SimulationOptions{}, 0);
  EXPECT_TRUE(sim);
  if (!sim) return score;
  mapping::MapperParams params;
  params.octomap.prob_miss = prob_miss;
  auto mapper = mapping::Mapper::create(params);
  EXPECT_TRUE(mapper) << mapper.error().message;
  if (!mapper) return score;
  hal::sim::BaselineFollower follower({}, trial->spec.drone.start_m, trial->spec.drone.start_yaw_rad);
  hal::sim::DepthCameraParams exact = trial->spec.depth_camera.camera;
  exact.noise_coeff_per_m = 0.0;
  exact.dropout_probability = 0.0;
  std::mt19937_64 rng(1);
  const octomap::OcTree& tree = mapper->octomap().tree();
  KeySet truth_seen;
  octomap::Pointcloud hits, misses;
  std::uint64_t depth_version = 0;
  std::vector<std::shared_ptr<const hal::DepthFrame>> pending_frames;

  const rt::TimeNs end_ns = rt::secondsToNs(duration_s);
  for (rt::TimeNs t = 0; t <= end_ns; t += 2'000'000) {  // the physics step: captures fall on step ends
    (*sim)->step(t);
    const auto truth = (*sim)->truthOut().read();
    const auto command = follower.update(*truth, t);
    (*sim)->setpointInbox().write(command.setpoint);
    (*sim)->gimbalInbox().write(command.gimbal);
    if (const auto odom = (*sim)->odometryOut().read()) mapper->addOdometry(*odom);
    // The true depth-camera pose now (a frame captured in this step has stamp t).
    const hal::sim::QuadrotorState& drone = (*sim)->truth().drone;
    Eigen::Matrix3d optical;
    optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;
    Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
    T_WC.linear() = drone.R_WB * optical;
    T_WC.translation() = drone.p_W_m + drone.R_WB * trial->spec.depth_camera.mount_B_m;
    if ((*sim)->depthOut().version() != depth_version) {
      depth_version = (*sim)->depthOut().version();
      const auto frame = (*sim)->depthOut().read();
      pending_frames.push_back(frame);
      if (frame->stamp_ns == t) {
        // The truth: what the camera sees of the world, the person in front of it hiding what is behind them
        // but not a surface to map themselves.
        cv::Mat exact_depth;
        const hal::sim::Cylinder person = personBody(**sim, t);
        hal::sim::renderDepth((*sim)->obstacles(), T_WC, exact, rng, exact_depth,
                              std::span<const hal::sim::Cylinder>(&person, 1));
        hal::DepthFrame exact_frame = *frame;
        exact_frame.depth_m = exact_depth;
        const mapping::ExcludedBody body = excluded(person);
        EXPECT_TRUE(mapping::depthToPoints(exact_frame, T_WC, params.points, hits, misses,
                                           std::span<const mapping::ExcludedBody>(&body, 1)));
        for (const auto& p : hits) truth_seen.insert(keyOf(tree.coordToKey(p)));
      }
    }
    // Insert frames once odometry (10 ms late) covers them.
    while (!pending_frames.empty() && mapper->poses().size() > 0 &&
           mapper->poses().newest().stamp_ns >= pending_frames.front()->stamp_ns) {
      // The person is in the depth images (issue 22); the map of the world leaves them out, as the app does
      // from its estimate -- here from the truth, so that this test scores the mapping of the world alone.
      const mapping::ExcludedBody body = excluded(personBody(**sim, pending_frames.front()->stamp_ns));
      EXPECT_TRUE(mapper->insert(*pending_frames.front(), std::span<const mapping::ExcludedBody>(&body, 1)));
      pending_frames.erase(pending_frames.begin());
    }
  }
  score.frames = mapper->stats().frames_inserted;

  // Precision: every occupied leaf, by its distance to the nearest true surface.
  const double tolerance_m = tree.getResolution() * std::sqrt(3.0);
  std::size_t occupied = 0, near_surface = 0;
  KeySet occupied_keys;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it) || it.getDepth() != tree.getTreeDepth()) continue;
    ++occupied;
    const octomap::point3d c = it.getCoordinate();
    // True surfaces: the obstacles and the ground plane z = 0, which the camera sees too.
    const double to_surface_m =
        std::min((*sim)->obstacles().distance(Eigen::Vector3f(c.x(), c.y(), c.z()).cast<double>()),
                 std::abs(static_cast<double>(c.z())));
    if (to_surface_m <= tolerance_m) ++near_surface;
    occupied_keys.insert(keyOf(it.getKey()));
  }
  // Recall: seen surface voxels found occupied (or a face neighbour occupied), for the trees and
  // for the ground separately (the ground row of voxels has keys of z = 0 .. 0.1 m).
  const int ground_key_z = tree.coordToKey(octomap::point3d(0.0F, 0.0F, 0.05F))[2];
  std::size_t found = 0, ground_seen = 0, ground_found = 0;
  for (const auto& k : truth_seen) {
    bool hit = occupied_keys.count(k) != 0;
    for (int axis = 0; axis < 3 && !hit; ++axis)
      for (int d : {-1, 1}) {
        auto n = k;
        n[static_cast<std::size_t>(axis)] += d;
        hit = hit || occupied_keys.count(n) != 0;
      }
    found += hit ? 1 : 0;
    if (k[2] == ground_key_z) {
      ++ground_seen;
      ground_found += hit ? 1 : 0;
    }
  }
  score.occupied = occupied;
  score.seen = truth_seen.size();
  score.precision = static_cast<double>(near_surface) / static_cast<double>(std::max<std::size_t>(occupied, 1));
  score.recall = static_cast<double>(found) / static_cast<double>(std::max<std::size_t>(truth_seen.size(), 1));
  score.obstacle_recall = static_cast<double>(found - ground_found) /
                          static_cast<double>(std::max<std::size_t>(truth_seen.size() - ground_seen, 1));
  score.ground_recall = static_cast<double>(ground_found) / static_cast<double>(std::max<std::size_t>(ground_seen, 1));
  std::printf(
      "%s, prob_miss %.2f: %zu occupied voxels, precision %.4f; %zu seen surface voxels, recall %.4f "
      "(obstacles %.4f, ground %.4f)\n",
      scenario.c_str(), prob_miss, occupied, score.precision, score.seen, score.recall, score.obstacle_recall,
      score.ground_recall);
  return score;
}

TEST(MappingGroundTruth, GivenAForestSweepThenTreeVoxelsHavePrecisionAndRecallAbove95Percent) {
  // OctoMap's own sensor model (prob_miss 0.4) and the configured one (config/sim.yaml: 0.45).
  for (const double prob_miss : {0.4, 0.45}) {
    const MapScore s = mapAndScore("forest", 25.0, prob_miss);
    ASSERT_GT(s.frames, 300U);
    ASSERT_GT(s.seen, 1000U);
    RecordProperty("precision_" + std::to_string(prob_miss), std::to_string(s.precision));
    RecordProperty("recall_" + std::to_string(prob_miss), std::to_string(s.recall));
    EXPECT_GE(s.precision, 0.95);
    // The obstacles -- the trees -- are what the planner must not miss.
    EXPECT_GE(s.obstacle_recall, 0.95);
    // The ground is mapped less completely: rays that graze it far away clear floor voxels that
    // steeper rays marked (a known OctoMap effect). Kept as a floor, not a goal.
    EXPECT_GE(s.ground_recall, 0.85);
    EXPECT_GE(s.recall, 0.93);
  }
}

// A wall flown along at close range is seen at grazing angles: rays to points beyond it pass through
// its surface voxels and clear them (each pass a "miss"). With OctoMap's prob_miss 0.4 a wall voxel at
// the upper clamp is cleared by 9 such frames (0.6 s at 15 Hz); the planner then cut the sharp turn's
// corner into the building (issue 9). With 0.45 it takes 17. Flown along the building of sharp_turn (the
// person walks 0.9 m from it) and round its corner, the building must stay mapped.
TEST(MappingGroundTruth, GivenAWallFlownAlongAtCloseRangeThenItStaysMapped) {
  const MapScore octomap_default = mapAndScore("sharp_turn", 32.0, 0.4);
  const MapScore configured = mapAndScore("sharp_turn", 32.0, 0.45);
  ASSERT_GT(configured.seen, 1000U);
  EXPECT_GE(configured.precision, 0.95);
  EXPECT_GE(configured.obstacle_recall, 0.95);
  EXPECT_GT(configured.obstacle_recall, octomap_default.obstacle_recall);
}

}  // namespace
}  // namespace aerotrack
