// The mapper against the simulator's ground truth (issue 4): fly the forest with the simulated
// D435 (noise sigma = k z^2, dropout), map it, then compare with the true obstacles. Measured
// (seed 1, 25 s): precision 0.9999 over 36,764 occupied voxels; recall 0.986 on the trees and 0.886
// on the ground (see below).
//   precision: occupied map voxels whose centre lies within one voxel diagonal of a true surface;
//   recall:    surface voxels that a noise-free camera at the same poses saw within range, found
//              occupied in the map (or a face neighbour of them: the noise at 6 m is 5 cm).
#include <gtest/gtest.h>

#include <random>
#include <set>
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

TEST(MappingGroundTruth, GivenAForestSweepThenTreeVoxelsHavePrecisionAndRecallAbove95Percent) {
  auto spec = hal::sim::loadScenarioSpec(AEROTRACK_SOURCE_DIR "/config/scenarios/forest.yaml");
  ASSERT_TRUE(spec);
  auto trial = hal::sim::instantiate(*spec, 1);
  ASSERT_TRUE(trial);
  auto sim = hal::sim::Simulation::create(*trial, hal::sim::SimulationOptions{}, 0);
  ASSERT_TRUE(sim);
  mapping::MapperParams params;
  auto mapper = mapping::Mapper::create(params);
  ASSERT_TRUE(mapper) << mapper.error().message;
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

  const rt::TimeNs end_ns = rt::secondsToNs(25.0);
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
        cv::Mat exact_depth;
        hal::sim::renderDepth((*sim)->obstacles(), T_WC, exact, rng, exact_depth);
        hal::DepthFrame exact_frame = *frame;
        exact_frame.depth_m = exact_depth;
        ASSERT_TRUE(mapping::depthToPoints(exact_frame, T_WC, params.points, hits, misses));
        for (const auto& p : hits) truth_seen.insert(keyOf(tree.coordToKey(p)));
      }
    }
    // Insert frames once odometry (10 ms late) covers them.
    while (!pending_frames.empty() && mapper->poses().size() > 0 &&
           mapper->poses().newest().stamp_ns >= pending_frames.front()->stamp_ns) {
      EXPECT_TRUE(mapper->insert(*pending_frames.front()));
      pending_frames.erase(pending_frames.begin());
    }
  }
  ASSERT_GT(mapper->stats().frames_inserted, 300U);
  ASSERT_GT(truth_seen.size(), 1000U);

  // Precision: every occupied leaf, by its distance to the nearest true surface.
  const double tolerance_m = tree.getResolution() * std::sqrt(3.0);
  std::size_t occupied = 0, near_surface = 0;
  KeySet occupied_keys;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it) || it.getDepth() != tree.getTreeDepth()) continue;
    ++occupied;
    const octomap::point3d c = it.getCoordinate();
    // True surfaces: the obstacles and the ground plane z = 0, which the camera sees too.
    const double to_surface_m = std::min((*sim)->obstacles().distance(Eigen::Vector3d(c.x(), c.y(), c.z())),
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
  const double precision = static_cast<double>(near_surface) / static_cast<double>(occupied);
  const double recall = static_cast<double>(found) / static_cast<double>(truth_seen.size());
  const double tree_recall =
      static_cast<double>(found - ground_found) / static_cast<double>(truth_seen.size() - ground_seen);
  const double ground_recall = static_cast<double>(ground_found) / static_cast<double>(ground_seen);
  std::printf("recall on trees %.4f (%zu voxels), on the ground %.4f (%zu voxels)\n", tree_recall,
              truth_seen.size() - ground_seen, ground_recall, ground_seen);
  RecordProperty("precision", std::to_string(precision));
  RecordProperty("recall", std::to_string(recall));
  std::printf("mapping vs ground truth: %zu occupied voxels, precision %.4f; %zu seen surface voxels, recall %.4f\n",
              occupied, precision, truth_seen.size(), recall);
  EXPECT_GE(precision, 0.95);
  // The obstacles -- the trees -- are what the planner must not miss.
  EXPECT_GE(tree_recall, 0.95);
  // The ground is mapped less completely: rays that graze it far away clear floor voxels that
  // steeper rays marked (a known OctoMap effect). Measured 0.886; kept as a floor, not a goal.
  EXPECT_GE(ground_recall, 0.85);
  EXPECT_GE(recall, 0.93);
}

}  // namespace
}  // namespace aerotrack
