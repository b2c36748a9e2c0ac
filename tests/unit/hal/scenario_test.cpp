// Scenario files and their per-seed instances: the built-in scenarios load and instantiate, the
// generators keep their promises (density, clearance from the person's path, a passable
// corridor), seeds are deterministic, and a malformed file names the bad field.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "aerotrack/hal/sim/scenario.hpp"
#include "support/require.hpp"

namespace aerotrack::hal::sim {
namespace {

const std::string kScenarios = AEROTRACK_SOURCE_DIR "/config/scenarios/";

ScenarioSpec load(const std::string& name) {
  return aerotrack::test::require(loadScenarioSpec(kScenarios + name + ".yaml"), name);
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

double distanceToPath(const Eigen::Vector2d& p, const std::vector<PathPoint>& path) {
  double best = 1e9;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Eigen::Vector2d a = path[i].p_W_m, ab = path[i + 1].p_W_m - a;
    const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * ab - p).norm());
  }
  return best;
}

class BuiltInScenario : public ::testing::TestWithParam<std::string> {};

TEST_P(BuiltInScenario, LoadsAndInstantiatesForSeveralSeeds) {
  const ScenarioSpec spec = load(GetParam());
  EXPECT_EQ(spec.name, GetParam());
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const auto trial = instantiate(spec, seed);
    ASSERT_TRUE(trial) << trial.error().message;
    EXPECT_GE(trial->spec.path.size(), 2U);
    EXPECT_GT(trial->duration_s, trial->spec.person_start_delay_s);
    EXPECT_LE(trial->duration_s, spec.max_duration_s);
    EXPECT_TRUE(ObstacleWorld::create(trial->spec.boxes, trial->spec.cylinders)) << "seed " << seed;
  }
}

TEST_P(BuiltInScenario, SameSeedGivesTheSameTrial) {
  const ScenarioSpec spec = load(GetParam());
  const auto a = instantiate(spec, 7), b = instantiate(spec, 7);
  ASSERT_TRUE(a && b);
  ASSERT_EQ(a->spec.path.size(), b->spec.path.size());
  for (std::size_t i = 0; i < a->spec.path.size(); ++i) {
    EXPECT_EQ(a->spec.path[i].p_W_m, b->spec.path[i].p_W_m);
    EXPECT_EQ(a->spec.path[i].speed_mps, b->spec.path[i].speed_mps);
  }
  ASSERT_EQ(a->spec.cylinders.size(), b->spec.cylinders.size());
  for (std::size_t i = 0; i < a->spec.cylinders.size(); ++i)
    EXPECT_EQ(a->spec.cylinders[i].center_W_m, b->spec.cylinders[i].center_W_m);
  ASSERT_EQ(a->spec.boxes.size(), b->spec.boxes.size());
  EXPECT_EQ(a->duration_s, b->duration_s);
}

TEST_P(BuiltInScenario, ThePersonsPathAndTheDronesStartAreClearOfObstacles) {
  const ScenarioSpec spec = load(GetParam());
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const auto trial = instantiate(spec, seed);
    ASSERT_TRUE(trial);
    const auto world = ObstacleWorld::create(trial->spec.boxes, trial->spec.cylinders);
    ASSERT_TRUE(world);
    const auto& path = trial->spec.path;
    for (std::size_t i = 0; i + 1 < path.size(); ++i)
      for (double t = 0.0; t <= 1.0; t += 0.02) {
        const Eigen::Vector2d p = path[i].p_W_m + t * (path[i + 1].p_W_m - path[i].p_W_m);
        EXPECT_GT(world->distance(Eigen::Vector3d(p.x(), p.y(), 1.0)), 0.6)
            << "seed " << seed << " at " << p.transpose();
      }
    EXPECT_GT(world->distance(trial->spec.drone.start_m + Eigen::Vector3d(0, 0, 1.0)), 0.6) << "seed " << seed;
  }
}

INSTANTIATE_TEST_SUITE_P(Scenarios, BuiltInScenario,
                         ::testing::Values("sharp_turn", "forest", "corridor", "open", "crowd", "crossing"));

TEST(SharpTurn, SeedsPickBothTurnSidesAndMirrorTheWholeWorld) {
  const ScenarioSpec spec = load("sharp_turn");
  int mirrored = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const auto trial = instantiate(spec, seed);
    ASSERT_TRUE(trial);
    const double building_y = trial->spec.boxes[0].min_W_m.y() + trial->spec.boxes[0].max_W_m.y();
    const double turn_y = trial->spec.path.back().p_W_m.y();
    EXPECT_GT(building_y * turn_y, 0.0) << "the building is on the side the person turns to";
    mirrored += trial->mirrored ? 1 : 0;
  }
  EXPECT_GT(mirrored, 3);
  EXPECT_LT(mirrored, 17);
}

TEST(SharpTurn, SpeedOverrideIsJitteredByTenPercentAtMost) {
  const ScenarioSpec spec = load("sharp_turn");
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const auto trial = instantiate(spec, seed, 0.85);
    ASSERT_TRUE(trial);
    EXPECT_GE(trial->spec.path[0].speed_mps, 0.85 * 0.9 - 1e-12);
    EXPECT_LE(trial->spec.path[0].speed_mps, 0.85 * 1.1 + 1e-12);
    EXPECT_EQ(trial->spec.path[0].speed_mps, trial->spec.path[1].speed_mps);
  }
}

TEST(Forest, TreesReachTheRequestedDensityWithoutOverlapAndClearOfThePath) {
  const ScenarioSpec spec = load("forest");
  const auto trial = instantiate(spec, 3);
  ASSERT_TRUE(trial);
  const auto& trees = trial->spec.cylinders;
  const double target = spec.forest->density_per_m2 * 40.0 * 40.0;  // 192
  EXPECT_GT(static_cast<double>(trees.size()), 0.85 * target);
  EXPECT_LE(static_cast<double>(trees.size()), target + 1.0);
  for (std::size_t i = 0; i < trees.size(); ++i) {
    EXPECT_GE(trees[i].radius_m, 0.15);
    EXPECT_LE(trees[i].radius_m, 0.4);
    EXPECT_GE(distanceToPath(trees[i].center_W_m, trial->spec.path), trees[i].radius_m + 1.0 - 1e-9);
    for (std::size_t j = 0; j < i; ++j)
      EXPECT_GE((trees[i].center_W_m - trees[j].center_W_m).norm(), trees[i].radius_m + trees[j].radius_m + 0.9 - 1e-9);
  }
  double max_speed = 0.0;
  for (const auto& p : trial->spec.path) max_speed = std::max(max_speed, p.speed_mps);
  EXPECT_LE(max_speed, 3.0);
}

TEST(Corridor, WallsLeaveTheCentrelinePassableAndClutterStaysAgainstTheWalls) {
  const ScenarioSpec spec = load("corridor");
  const auto trial = instantiate(spec, 2);
  ASSERT_TRUE(trial);
  const auto world = ObstacleWorld::create(trial->spec.boxes, trial->spec.cylinders);
  ASSERT_TRUE(world);
  const auto& line = spec.corridor->centreline_m;
  double narrowest = 1e9;
  for (std::size_t i = 0; i + 1 < line.size(); ++i)
    for (double t = 0.0; t <= 1.0; t += 0.01)
      narrowest =
          std::min(narrowest, world->distance(Eigen::Vector3d(0, 0, 1.0) +
                                              Eigen::Vector3d((line[i] + t * (line[i + 1] - line[i])).x(),
                                                              (line[i] + t * (line[i + 1] - line[i])).y(), 0.0)));
  // Half the width, less the deepest clutter, less the 0.1 m wall raster.
  EXPECT_GE(narrowest, 1.25 - 0.5 - 0.1);
  // A point a little outside the corridor is inside a wall.
  EXPECT_EQ(world->distance(Eigen::Vector3d(7.0, 1.25 + 0.1, 1.0)), 0.0);
}

TEST(ScenarioFile, GivenMalformedFieldsThenErrorsNameThem) {
  const std::string text = readFile(kScenarios + "sharp_turn.yaml");
  const auto withReplaced = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    t.replace(t.find(from), from.size(), to);
    return parseScenarioSpec(t, "s.yaml");
  };
  const auto bad_radius = withReplaced("radius_m: 0.3, height_m: 3.0}", "radius_m: -1, height_m: 3.0}");
  ASSERT_FALSE(bad_radius);
  EXPECT_NE(bad_radius.error().message.find("world.cylinders[0].radius_m: -1 is out of range"), std::string::npos)
      << bad_radius.error().message;
  const auto unknown = withReplaced("  height_m: 1.75", "  height_m: 1.75\n  weight_kg: 70");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("person.weight_kg: unknown key"), std::string::npos)
      << unknown.error().message;
  const auto misspelt = withReplaced("  height_m: 1.75", "  hight_m: 1.75");
  ASSERT_FALSE(misspelt);
  EXPECT_NE(misspelt.error().message.find("person.height_m: missing required key"), std::string::npos);
  const auto no_speed = withReplaced("- {p_m: [0.0, 0.9], speed_mps: 1.5}", "- {p_m: [0.0, 0.9]}");
  ASSERT_FALSE(no_speed);
  EXPECT_NE(no_speed.error().message.find("person.path[0].speed_mps: missing required key"), std::string::npos)
      << no_speed.error().message;
  const auto inverted_box = withReplaced("max_m: [20.5, 14.0, 4.0]", "max_m: [2.5, 14.0, 4.0]");
  ASSERT_FALSE(inverted_box);
  EXPECT_NE(inverted_box.error().message.find("world.boxes[0].max_m: must be greater than min_m"), std::string::npos);
}

}  // namespace
}  // namespace aerotrack::hal::sim
