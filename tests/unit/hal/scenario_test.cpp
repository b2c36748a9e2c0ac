// Scenario files and their per-seed instances: the built-in scenarios load and instantiate, the
// generators keep their promises (density, clearance from the person's path, a passable
// corridor), seeds are deterministic, and a malformed file names the bad field.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iostream>
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
                         ::testing::Values("sharp_turn", "forest", "corridor", "open", "runner", "drift", "windy",
                                           "crowd", "crossing"));

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

// Issue 20: the person's speed-profile keys, scripted behaviours per path point, and the random
// walk's behaviours block.

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// The top speed of the person in a trial, sampled every 10 ms; mean_mps: path length / walk time.
double topSpeedMps(const ScenarioInstance& trial, double* mean_mps = nullptr) {
  const WalkingPerson w = aerotrack::test::require(WalkingPerson::create(trial.spec.person, trial.spec.path), "person");
  double top = 0.0;
  for (double t = 0.0; t <= w.durationS(); t += 0.01) top = std::max(top, w.state(t).speed_mps);
  if (mean_mps) *mean_mps = w.lengthM() / w.durationS();
  return top;
}

TEST(ScenarioFile, GivenPersonMotionAndPathPointKeysThenTheyReachTheWalkingPerson) {
  const std::string text = replaced(readFile(kScenarios + "sharp_turn.yaml"), "  start_delay_s: 4.0\n",
                                    "  start_delay_s: 4.0\n  max_accel_mps2: 3.5\n  corner_radius_m: 0.8\n"
                                    "  max_lateral_accel_mps2: 5.0\n  max_yaw_rate_radps: 4.0\n  wide_corners: true\n"
                                    "  max_corner_cut_m: 0.7\n  max_backward_speed_mps: 1.5\n");
  const std::string scripted =
      replaced(text, "- {p_m: [21.4, 0.9], speed_mps: 1.5}",
               "- {p_m: [21.4, 0.9], speed_mps: 1.2, pause_s: 2.5, backwards: true, accel_mps2: 4.0}");
  const ScenarioSpec spec = aerotrack::test::require(parseScenarioSpec(scripted, "s.yaml"), "spec");
  EXPECT_EQ(spec.person.max_accel_mps2, 3.5);
  EXPECT_EQ(spec.person.corner_radius_m, 0.8);
  EXPECT_EQ(spec.person.max_lateral_accel_mps2, 5.0);
  EXPECT_EQ(spec.person.max_yaw_rate_radps, 4.0);
  EXPECT_TRUE(spec.person.wide_corners);
  EXPECT_EQ(spec.person.max_corner_cut_m, 0.7);
  EXPECT_EQ(spec.person.max_backward_speed_mps, 1.5);
  ASSERT_EQ(spec.path.size(), 3U);
  EXPECT_EQ(spec.path[1].pause_s, 2.5);
  EXPECT_TRUE(spec.path[1].backwards);
  EXPECT_EQ(spec.path[1].accel_mps2, 4.0);
  EXPECT_FALSE(spec.path[0].backwards);
  EXPECT_EQ(spec.path[0].pause_s, 0.0);
  EXPECT_EQ(spec.path[0].accel_mps2, 0.0);
  // Defaults: unchanged from PersonParams.
  const ScenarioSpec plain = load("sharp_turn");
  EXPECT_EQ(plain.person.max_accel_mps2, PersonParams{}.max_accel_mps2);
  EXPECT_EQ(plain.person.corner_radius_m, PersonParams{}.corner_radius_m);
  EXPECT_FALSE(plain.person.wide_corners);
}

TEST(ScenarioFile, GivenBadPersonMotionOrBehaviourValuesThenErrorsNameTheKey) {
  const std::string text = readFile(kScenarios + "sharp_turn.yaml");
  const auto expectError = [](const std::string& yaml, const std::string& message) {
    const auto spec = parseScenarioSpec(yaml, "s.yaml");
    ASSERT_FALSE(spec) << message;
    EXPECT_NE(spec.error().message.find(message), std::string::npos) << spec.error().message;
  };
  const auto withPerson = [&](const std::string& keys) {
    return replaced(text, "  start_delay_s: 4.0\n", "  start_delay_s: 4.0\n" + keys);
  };
  expectError(withPerson("  max_accel_mps2: -1\n"), "person.max_accel_mps2: -1 is out of range");
  expectError(withPerson("  corner_radius_m: 11\n"), "person.corner_radius_m: 11 is out of range");
  expectError(withPerson("  max_lateral_accel_mps2: 0\n"), "person.max_lateral_accel_mps2: 0 is out of range");
  expectError(withPerson("  max_yaw_rate_radps: 30\n"), "person.max_yaw_rate_radps: 30 is out of range");
  expectError(withPerson("  max_backward_speed_mps: 4\n"), "person.max_backward_speed_mps: 4 is out of range");
  expectError(withPerson("  wide_corners: maybe\n"), "person.wide_corners");
  const auto withPoint = [&](const std::string& keys) {
    return replaced(text, "- {p_m: [0.0, 0.9], speed_mps: 1.5}", "- {p_m: [0.0, 0.9], " + keys + "}");
  };
  expectError(withPoint("speed_mps: 1.5, pause_s: -1"), "person.path[0].pause_s: -1 is out of range");
  expectError(withPoint("speed_mps: 1.5, accel_mps2: 0"), "person.path[0].accel_mps2: 0 is out of range");
  expectError(withPoint("speed_mps: 2.5, backwards: true"), "person.path[0].speed_mps: a backward leg's speed");
  const std::string forest = readFile(kScenarios + "forest.yaml");
  const auto withBehaviours = [&](const std::string& keys) {
    return replaced(forest, "    speed_mps: [2.0, 3.0]\n", "    speed_mps: [2.0, 3.0]\n    behaviours:\n" + keys);
  };
  expectError(withBehaviours("      sprint_probability: 1.5\n"),
              "person.random_path.behaviours.sprint_probability: 1.5 is out of range");
  expectError(withBehaviours("      sprint_speed_mps: [4.0, 7.0]\n"), "behaviours.sprint_speed_mps");
  expectError(withBehaviours("      pause_s: [3.0, 1.0]\n"), "behaviours.pause_s: a range is [min, max]");
  expectError(withBehaviours("      backwards_speed_mps: [1.0, 3.5]\n"), "behaviours.backwards_speed_mps");
  expectError(withBehaviours("      jump_probability: 0.1\n"), "behaviours.jump_probability: unknown key");
}

// --speed reaches the asked speed where the legs are long enough: forest's runner profile
// (max_accel_mps2 3, wide corners) on its 6-12 m legs.
TEST(Forest, SpeedOverrideOfFiveAndSixGivesDifferentTopSpeeds) {
  const ScenarioSpec spec = load("forest");
  const auto five = instantiate(spec, 1, 5.0);
  const auto six = instantiate(spec, 1, 6.0);
  ASSERT_TRUE(five && six);
  double mean5 = 0.0, mean6 = 0.0;
  const double top5 = topSpeedMps(*five, &mean5), top6 = topSpeedMps(*six, &mean6);
  std::cout << "forest seed 1: top/mean speed " << top5 << "/" << mean5 << " m/s at --speed 5, " << top6 << "/" << mean6
            << " m/s at --speed 6\n";
  EXPECT_GT(mean6, mean5);
  EXPECT_NEAR(top5, 5.0, 1e-9);
  EXPECT_GT(top6, 5.5);
  EXPECT_LE(top6, 6.0 + 1e-9);
}

std::string forestWithBehaviours(const std::string& keys) {
  return replaced(readFile(kScenarios + "forest.yaml"), "    speed_mps: [2.0, 3.0]\n",
                  "    speed_mps: [2.0, 3.0]\n    behaviours:\n" + keys);
}

TEST(RandomPathBehaviours, GivenZeroProbabilitiesThenTheWalkIsUnchanged) {
  const ScenarioSpec plain = load("forest");
  const ScenarioSpec with_block = aerotrack::test::require(
      parseScenarioSpec(forestWithBehaviours("      sprint_probability: 0.0\n"), "f.yaml"), "spec");
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const auto a = instantiate(plain, seed);
    const auto b = instantiate(with_block, seed);
    ASSERT_TRUE(a && b);
    ASSERT_EQ(a->spec.path.size(), b->spec.path.size());
    for (std::size_t i = 0; i < a->spec.path.size(); ++i) {
      EXPECT_EQ(a->spec.path[i].p_W_m, b->spec.path[i].p_W_m);
      EXPECT_EQ(a->spec.path[i].speed_mps, b->spec.path[i].speed_mps);
      EXPECT_EQ(a->spec.path[i].pause_s, b->spec.path[i].pause_s);
    }
    EXPECT_EQ(a->spec.cylinders.size(), b->spec.cylinders.size());
    EXPECT_EQ(a->duration_s, b->duration_s);
  }
}

TEST(RandomPathBehaviours, GivenCertainBehavioursThenEveryLegGetsThemDeterministicallyOnTheSamePolyline) {
  const ScenarioSpec plain = load("forest");
  const ScenarioSpec spec = aerotrack::test::require(
      parseScenarioSpec(forestWithBehaviours("      sprint_probability: 1.0\n      sprint_speed_mps: [5.0, 6.0]\n"
                                             "      sprint_accel_mps2: 4.0\n      speed_change_probability: 1.0\n"
                                             "      speed_change_mps: [1.0, 2.0]\n      pause_probability: 1.0\n"
                                             "      pause_s: [1.0, 2.0]\n      reversal_probability: 1.0\n"
                                             "      reversal_m: [2.0, 4.0]\n      backwards_probability: 0.5\n"
                                             "      backwards_speed_mps: [0.6, 1.0]\n"),
                        "f.yaml"),
      "spec");
  int backward_legs = 0, turned_reversals = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const auto base = instantiate(plain, seed);
    const auto a = instantiate(spec, seed);
    const auto again = instantiate(spec, seed);
    ASSERT_TRUE(base && a && again);
    const auto& path = a->spec.path;
    const auto& legs = base->spec.path;
    // Same seed, same walk.
    ASSERT_EQ(path.size(), again->spec.path.size());
    for (std::size_t i = 0; i < path.size(); ++i) {
      EXPECT_EQ(path[i].p_W_m, again->spec.path[i].p_W_m);
      EXPECT_EQ(path[i].speed_mps, again->spec.path[i].speed_mps);
      EXPECT_EQ(path[i].backwards, again->spec.path[i].backwards);
    }
    // Each inner leg: start (sprint), mid (speed change), end (pause, reversal), turn point.
    const std::size_t n_legs = legs.size() - 1;
    ASSERT_EQ(path.size(), 4 * (n_legs - 1) + 2 + 1) << seed;
    EXPECT_EQ(path.front().p_W_m, legs.front().p_W_m);
    EXPECT_EQ(path.back().p_W_m, legs.back().p_W_m);
    for (std::size_t leg = 0; leg < n_legs; ++leg) {
      const PathPoint& start = path[4 * leg];
      const PathPoint& mid = path[4 * leg + 1];
      EXPECT_EQ(start.p_W_m, legs[leg].p_W_m);
      EXPECT_GE(start.speed_mps, 5.0);
      EXPECT_LE(start.speed_mps, 6.0);
      EXPECT_EQ(start.accel_mps2, 4.0);
      EXPECT_GE(mid.speed_mps, 1.0);
      EXPECT_LE(mid.speed_mps, 2.0);
      // Points stay on the base polyline (so the trees' clearance holds).
      EXPECT_LT(distanceToPath(mid.p_W_m, legs), 1e-9);
      if (leg + 1 == n_legs) break;
      const PathPoint& end = path[4 * leg + 2];
      const PathPoint& turn = path[4 * leg + 3];
      EXPECT_EQ(end.p_W_m, legs[leg + 1].p_W_m);
      EXPECT_GE(end.pause_s, 1.0);
      EXPECT_LE(end.pause_s, 2.0);
      const double back_m = (turn.p_W_m - end.p_W_m).norm();
      EXPECT_GE(back_m, std::min(2.0, 0.8 * (legs[leg + 1].p_W_m - legs[leg].p_W_m).norm()) - 1e-9);
      EXPECT_LE(back_m, 4.0 + 1e-9);
      EXPECT_LT(distanceToPath(turn.p_W_m, legs), 1e-9);
      if (end.backwards) {
        ++backward_legs;
        EXPECT_LE(end.speed_mps, 1.0);
      } else {
        ++turned_reversals;
      }
    }
    EXPECT_GT(a->duration_s, base->duration_s);
    // --speed replaces the forward legs' speeds only; backward legs keep theirs.
    const auto fast = instantiate(spec, seed, 6.0);
    ASSERT_TRUE(fast);
    for (std::size_t i = 0; i + 1 < fast->spec.path.size(); ++i)
      EXPECT_EQ(fast->spec.path[i].speed_mps, fast->spec.path[i].backwards ? path[i].speed_mps : 6.0);
  }
  EXPECT_GT(backward_legs, 0);
  EXPECT_GT(turned_reversals, 0);
}

}  // namespace
}  // namespace aerotrack::hal::sim
