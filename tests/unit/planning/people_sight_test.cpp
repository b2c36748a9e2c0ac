// The other people hide the person (issue 22 item 2; peopleBlockSight, SightBlockers,
// TrackingPlannerParams::bystander_sight_radius_m): the test against a slow reference that walks the line of
// sight in small steps, the visible goal turned round the person past someone standing in front of them, the
// search's occlusion penalty for someone on the line of sight, and the planner's goal with and without the rule.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "aerotrack/planning/kinodynamic_search.hpp"
#include "aerotrack/planning/tracking_planner.hpp"
#include "planner_test_util.hpp"
#include "search_test_util.hpp"
#include "support/require.hpp"

namespace aerotrack::planning {
namespace {

// The slow, obvious reading: walk from `from` towards `to` in 1 mm steps (the ends left out); someone blocks when
// a step passes within radius_m of them and they stand nearer `from` than `to` does, not on the person.
bool blocksByWalking(const Eigen::Vector2d& from, const Eigen::Vector2d& to, const Eigen::Vector2d& q,
                     double radius_m) {
  if ((q - to).norm() < radius_m) return false;
  const double length_m = (to - from).norm();
  const int steps = static_cast<int>(std::ceil(length_m / 1e-3));
  double nearest_m = std::numeric_limits<double>::infinity();
  int nearest_step = -1;
  for (int k = 1; k < steps; ++k) {
    const double d = (from + (to - from) * (static_cast<double>(k) / steps) - q).norm();
    if (d < nearest_m) {
      nearest_m = d;
      nearest_step = k;
    }
  }
  // The nearest step at an end of the walk: the foot of the perpendicular is outside the segment.
  return nearest_step > 1 && nearest_step < steps - 1 && nearest_m < radius_m;
}

TEST(PeopleBlockSight, AgreesWithWalkingTheLineOfSightOnRandomScenes) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(-6.0, 6.0);
  int blocked = 0, checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Eigen::Vector2d from(coord(rng), coord(rng));
    const Eigen::Vector2d to(coord(rng), coord(rng));
    const Eigen::Vector2d q = from + std::uniform_real_distribution<double>(-0.2, 1.2)(rng) * (to - from) +
                              Eigen::Vector2d(coord(rng), coord(rng)) * 0.15;
    constexpr double kRadiusM = 0.5;
    // Within a step of the rule's edges both readings may differ by the walk's resolution: not judged.
    const Eigen::Vector2d u = (to - from).normalized();
    const double along_m = (q - from).dot(u);
    const double across_m = std::abs(u.x() * (q - from).y() - u.y() * (q - from).x());
    if (std::abs(across_m - kRadiusM) < 5e-3 || std::abs(along_m) < 5e-3 ||
        std::abs(along_m - (to - from).norm()) < 5e-3 || std::abs((q - to).norm() - kRadiusM) < 5e-3)
      continue;
    const std::array<Eigen::Vector2d, 1> people{q};
    const bool fast = peopleBlockSight(from, to, people, kRadiusM);
    EXPECT_EQ(fast, blocksByWalking(from, to, q, kRadiusM))
        << from.transpose() << " -> " << to.transpose() << " past " << q.transpose();
    blocked += fast ? 1 : 0;
    ++checked;
  }
  EXPECT_GT(checked, 300);
  EXPECT_GT(blocked, 30) << "the scenes put people on the line of sight";
  EXPECT_LT(blocked, checked - 30) << "... and off it";
  // Nobody, no radius, or looking at oneself: nothing blocks.
  const std::array<Eigen::Vector2d, 1> middle{Eigen::Vector2d(1.0, 0.0)};
  EXPECT_FALSE(peopleBlockSight({0, 0}, {2, 0}, {}, 0.5));
  EXPECT_FALSE(peopleBlockSight({0, 0}, {2, 0}, middle, 0.0));
  EXPECT_FALSE(peopleBlockSight({0, 0}, {0, 0}, middle, 0.5));
  EXPECT_TRUE(peopleBlockSight({0, 0}, {2, 0}, middle, 0.5));
}

// Open ground; the followed person stands at the origin, the drone 3 m west of them: the plain goal is 2.5 m west.
struct OpenGround {
  mapping::LocalGrid grid =
      test::makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(0, 0, 1.5), {{{-10, -10, -0.2}, {10, 10, 0.0}}});
  KinematicState person;
  Eigen::Vector3d drone{-3.0, 0.0, 1.5};
  OpenGround() { person.p_W_m = Eigen::Vector3d(0.0, 0.0, 1.0); }
};

double turnRad(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return std::abs(std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b)));
}

TEST(TrackingGoal, GivenSomeoneStandingInFrontOfThePersonThenTheVisibleGoalTurnsPastThem) {
  const OpenGround g;
  const TrackingGoalParams params;
  const KinematicState plain = makeTrackingGoal(g.person, g.person, g.drone, params);
  ASSERT_TRUE(plain.p_W_m.head<2>().isApprox(Eigen::Vector2d(-2.5, 0.0)));
  const std::array<Eigen::Vector2d, 1> in_front{Eigen::Vector2d(-1.2, 0.1)};
  SightBlockers others{in_front, {}, 0.5};
  const KinematicState visible = makeVisibleTrackingGoal(g.grid, g.person, g.person, g.drone, params, nullptr, others);
  EXPECT_FALSE(peopleBlockSight(visible.p_W_m.head<2>(), g.person.p_W_m.head<2>(), in_front, others.radius_m));
  EXPECT_NEAR((visible.p_W_m - g.person.p_W_m).head<2>().norm(), params.tracking_distance_m, 1e-9);
  // The nearest such point round the circle: every smaller turn has them on the line of sight.
  const Eigen::Vector2d plain_offset = plain.p_W_m.head<2>();
  const double turn = turnRad(plain_offset, visible.p_W_m.head<2>());
  EXPECT_GT(turn, 0.0);
  for (double smaller = 0.0; smaller < turn - 1e-6; smaller += params.visible_step_rad) {
    for (const double sign : {1.0, -1.0}) {
      const Eigen::Vector2d p = Eigen::Rotation2Dd(sign * smaller) * plain_offset;
      EXPECT_TRUE(peopleBlockSight(p, Eigen::Vector2d::Zero(), in_front, others.radius_m)) << smaller;
    }
  }
  // Off (no radius), beside the person's own place (their second track), or behind them: the plain goal.
  others.radius_m = 0.0;
  EXPECT_TRUE(makeVisibleTrackingGoal(g.grid, g.person, g.person, g.drone, params, nullptr, others)
                  .p_W_m.isApprox(plain.p_W_m));
  others.radius_m = 0.5;
  for (const Eigen::Vector2d& q : {Eigen::Vector2d(-0.3, 0.1), Eigen::Vector2d(1.5, 0.0)}) {
    const std::array<Eigen::Vector2d, 1> harmless{q};
    others.now_W_m = harmless;
    EXPECT_TRUE(makeVisibleTrackingGoal(g.grid, g.person, g.person, g.drone, params, nullptr, others)
                    .p_W_m.isApprox(plain.p_W_m))
        << q.transpose();
  }
}

TEST(TrackingGoal, GivenSomeoneWalkingInFrontOfWhereThePersonWillBeThenTheGoalSeesBothWhereItCan) {
  // The person will be 3 m north; someone will stand on the line from the plain goal to there, not now.
  const OpenGround g;
  const TrackingGoalParams params;
  const Eigen::Vector3d ahead(0.0, 3.0, 1.0);
  const KinematicState plain = makeTrackingGoal(g.person, g.person, g.drone, params);
  const Eigen::Vector2d mid = 0.5 * (plain.p_W_m.head<2>() + ahead.head<2>());
  const std::array<Eigen::Vector2d, 1> later{mid};
  const SightBlockers others{{}, later, 0.5};
  ASSERT_TRUE(peopleBlockSight(plain.p_W_m.head<2>(), ahead.head<2>(), later, 0.5));
  const KinematicState seeing = makeVisibleTrackingGoal(g.grid, g.person, g.person, g.drone, params, &ahead, others);
  EXPECT_FALSE(seeing.p_W_m.isApprox(plain.p_W_m));
  EXPECT_FALSE(peopleBlockSight(seeing.p_W_m.head<2>(), ahead.head<2>(), later, 0.5));
  // Nobody in the way of the point ahead: the plain goal (it sees the person now and there).
  EXPECT_TRUE(makeVisibleTrackingGoal(g.grid, g.person, g.person, g.drone, params, &ahead, SightBlockers{})
                  .p_W_m.isApprox(plain.p_W_m));
}

// Samples (every 10 ms) of the path from which someone on the line of sight hides the person.
int hiddenSamples(const SearchPath& path, const Eigen::Vector2d& person, const MovingPerson& other, double radius_m) {
  int hidden = 0;
  for (double t = 0.0; t <= path.duration_s; t += 0.01) {
    const std::array<Eigen::Vector2d, 1> at{other.at(t)};
    hidden += peopleBlockSight(path.stateAt(t).p_W_m.head<2>(), person, at, radius_m) ? 1 : 0;
  }
  return hidden;
}

TEST(KinodynamicSearch, GivenSomeoneToPassThenTheOcclusionAwareSearchPassesOnTheSideThatSeesThePerson) {
  // The paper's occlusion figure with someone standing on the way instead of the obstacle: the goal 6 m ahead, the
  // followed person 4 m to the left of it, someone standing 3 m ahead, 0.3 m to the left of the straight way, kept
  // 0.8 m clear of. Passing them on the right is shorter, and there they hide the person.
  const mapping::LocalGrid grid =
      test::makeBoxGrid(Eigen::Vector3d(12.0, 12.0, 3.2), Eigen::Vector3d(3.0, 0.0, 1.6), {});
  const Eigen::Vector2d p_person(4.5, 4.0);
  const PersonPositionFn person = [&](double /*t_s*/) { return Eigen::Vector3d(p_person.x(), p_person.y(), 1.5); };
  KinodynamicSearchParams params;
  params.max_expansions = 5000;
  params.max_nodes = 400000;
  KinodynamicSearch search = aerotrack::test::require(KinodynamicSearch::create(params), "create");
  const std::array<MovingPerson, 1> other = {MovingPerson{{3.0, 0.3}, {0.0, 0.0}, 0.0}};
  constexpr double kClearanceM = 0.8;
  constexpr double kRadiusM = 0.5;
  const KinematicState start{Eigen::Vector3d(0.0, 0.0, 1.5), Eigen::Vector3d::Zero()};
  const KinematicState goal{Eigen::Vector3d(6.0, 0.0, 1.5), Eigen::Vector3d::Zero()};
  const auto pass = [&](double sight_radius_m, bool aware) {
    search.setOcclusionAware(aware);
    search.setPeople(other, kClearanceM, sight_radius_m);
    SearchPath path;
    EXPECT_EQ(search.search(grid, start, goal, 0.0, person, path), SearchStatus::kReachedGoal);
    double y_at_them = 0.0, closest_m = 1e9;  // the path's side where it passes them
    for (double t = 0.0; t <= path.duration_s; t += 0.01) {
      const Eigen::Vector2d p = path.stateAt(t).p_W_m.head<2>();
      if ((p - other[0].p_W_m).norm() < closest_m) {
        closest_m = (p - other[0].p_W_m).norm();
        y_at_them = p.y();
      }
    }
    return std::pair<double, int>(y_at_them, hiddenSamples(path, p_person, other[0], kRadiusM));
  };
  const auto [y_off, hidden_off] = pass(0.0, true);
  EXPECT_LT(y_off, other[0].p_W_m.y()) << "without the rule: the shorter way, on their right";
  EXPECT_GT(hidden_off, 0);
  const auto [y_on, hidden_on] = pass(kRadiusM, true);
  EXPECT_GT(y_on, other[0].p_W_m.y()) << "with it: on their left, between them and the person";
  EXPECT_LT(hidden_on, hidden_off);
  // The baseline (no occlusion terms) ignores the rule.
  EXPECT_EQ(pass(kRadiusM, false), pass(0.0, false));
}

TEST(TrackingPlanner, GivenSomeoneStandingBetweenTheGoalAndThePersonThenThePlanEndsWhereItSeesPastThem) {
  // The person stands 6 m ahead of the hovering drone; someone stands 1.3 m in front of them, on the line.
  test::PlanCase c{
      test::makeBoxGrid(Eigen::Vector3d(20, 20, 5), Eigen::Vector3d(0, 0, 1.5), {{{-10, -10, -0.2}, {10, 10, 0.0}}}),
      {},
      {}};
  c.odometry.p_WB_m = Eigen::Vector3d(0, 0, 1.5);
  c.person.initialised = true;
  c.person.lost = false;
  c.person.p_WT_m = Eigen::Vector3d(6.0, 0.0, 1.0);
  c.person.others[c.person.other_count++] =
      estimation::OtherPerson{Eigen::Vector3d(4.7, 0.0, 1.0), Eigen::Vector3d::Zero()};
  const Eigen::Vector2d p_person(6.0, 0.0);
  const std::array<Eigen::Vector2d, 1> other{Eigen::Vector2d(4.7, 0.0)};
  const auto end_hidden = [&](double sight_radius_m) {
    TrackingPlannerParams params = test::defaultParams();
    params.bystander_sight_radius_m = sight_radius_m;
    TrackingPlanner planner = test::makePlanner(params);
    PolynomialTrajectory out;
    const PlanReport report = planner.plan(c.inputs(), out);
    EXPECT_EQ(report.status, PlanStatus::kPlanned) << toString(report.status);
    return peopleBlockSight(out.sample(out.durationS()).p_W_m.head<2>(), p_person, other, 0.5);
  };
  EXPECT_TRUE(end_hidden(0.0)) << "off: the plain goal, behind them";
  EXPECT_FALSE(end_hidden(0.5));
}

}  // namespace
}  // namespace aerotrack::planning
