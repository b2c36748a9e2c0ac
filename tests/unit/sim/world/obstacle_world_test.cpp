// Tests of ObstacleWorld (hal/sim/world): input validation, raycast / segmentClear / distance
// against analytic values for boxes and cylinders, and against a slow brute-force reference
// (every obstacle, no grid, independent formulas: face planes and caps instead of slabs) on
// random rays and points in a random forest of cylinders and boxes, for several cell sizes.
// Tolerances: 1e-12 m for analytic cases, 1e-9 m against the reference.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "../../../support/require.hpp"
#include "aerotrack/hal/sim/obstacle_world.hpp"

namespace aerotrack::hal::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTol = 1e-12;

ObstacleWorld makeWorld(std::vector<Box> boxes, std::vector<Cylinder> cylinders, double cell_size_m = 1.0) {
  return aerotrack::test::require(ObstacleWorld::create(std::move(boxes), std::move(cylinders), cell_size_m),
                                  "ObstacleWorld::create");
}

Box box(double x0, double y0, double z0, double x1, double y1, double z1) {
  return Box{Eigen::Vector3d(x0, y0, z0), Eigen::Vector3d(x1, y1, z1)};
}

Cylinder cylinder(double x, double y, double r, double z0, double z1) {
  return Cylinder{Eigen::Vector2d(x, y), r, z0, z1};
}

// ---- brute-force reference ------------------------------------------------------------------

bool insideBox(const Box& b, const Eigen::Vector3d& p) {
  return (p.array() >= b.min_W_m.array()).all() && (p.array() <= b.max_W_m.array()).all();
}

bool insideCylinder(const Cylinder& c, const Eigen::Vector3d& p) {
  return (p.head<2>() - c.center_W_m).norm() <= c.radius_m && p.z() >= c.z_min_m && p.z() <= c.z_max_m;
}

/// First hit of the ray on the box surface: each of the six face planes, point-in-face test.
std::optional<double> refHitBox(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  if (insideBox(b, o)) return 0.0;
  std::optional<double> best;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0.0) continue;
    for (const double plane : {b.min_W_m[k], b.max_W_m[k]}) {
      const double t = (plane - o[k]) / d[k];
      if (t < 0.0) continue;
      const Eigen::Vector3d p = o + t * d;
      bool in_face = true;
      for (int m = 0; m < 3; ++m) {
        if (m != k && (p[m] < b.min_W_m[m] || p[m] > b.max_W_m[m])) in_face = false;
      }
      if (in_face && (!best || t < *best)) best = t;
    }
  }
  return best;
}

/// First hit on the cylinder: the side (textbook quadratic, smaller root) and the two caps.
std::optional<double> refHitCylinder(const Cylinder& c, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  if (insideCylinder(c, o)) return 0.0;
  std::optional<double> best;
  const auto consider = [&best](double t) {
    if (t >= 0.0 && (!best || t < *best)) best = t;
  };
  const Eigen::Vector2d oc = o.head<2>() - c.center_W_m;
  const Eigen::Vector2d dxy = d.head<2>();
  const double a = dxy.squaredNorm();
  if (a > 0.0) {
    const double b = 2.0 * oc.dot(dxy);
    const double cc = oc.squaredNorm() - c.radius_m * c.radius_m;
    const double disc = b * b - 4.0 * a * cc;
    if (disc >= 0.0) {
      for (const double t : {(-b - std::sqrt(disc)) / (2.0 * a), (-b + std::sqrt(disc)) / (2.0 * a)}) {
        const double z = o.z() + t * d.z();
        if (z >= c.z_min_m && z <= c.z_max_m) consider(t);
      }
    }
  }
  if (d.z() != 0.0) {
    for (const double plane : {c.z_min_m, c.z_max_m}) {
      const double t = (plane - o.z()) / d.z();
      if ((o.head<2>() + t * dxy - c.center_W_m).norm() <= c.radius_m) consider(t);
    }
  }
  return best;
}

std::optional<double> refRaycast(const ObstacleWorld& world, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                 double max_range_m, bool hit_ground) {
  double best = kInf;
  for (const Box& b : world.boxes()) best = std::min(best, refHitBox(b, o, d).value_or(kInf));
  for (const Cylinder& c : world.cylinders()) best = std::min(best, refHitCylinder(c, o, d).value_or(kInf));
  if (hit_ground) {
    if (o.z() <= 0.0) best = 0.0;
    if (d.z() < 0.0) best = std::min(best, o.z() / -d.z());
  }
  if (best <= max_range_m) return best;
  return std::nullopt;
}

/// Distance to the nearest point of each obstacle, the nearest point found by clamping.
double refDistance(const ObstacleWorld& world, const Eigen::Vector3d& p) {
  double best = kInf;
  for (const Box& b : world.boxes()) {
    best = std::min(best, (p - p.cwiseMax(b.min_W_m).cwiseMin(b.max_W_m)).norm());
  }
  for (const Cylinder& c : world.cylinders()) {
    Eigen::Vector3d nearest;
    const Eigen::Vector2d off = p.head<2>() - c.center_W_m;
    nearest.head<2>() =
        off.norm() <= c.radius_m ? p.head<2>() : Eigen::Vector2d(c.center_W_m + off.normalized() * c.radius_m);
    nearest.z() = std::clamp(p.z(), c.z_min_m, c.z_max_m);
    best = std::min(best, (p - nearest).norm());
  }
  return best;
}

/// ~200 trees (some with raised bottoms) and ~20 boxes (walls, some floating) over 40 x 40 m.
ObstacleWorld randomForest(std::mt19937_64& rng, double cell_size_m) {
  std::uniform_real_distribution<double> xy(-20.0, 20.0);
  std::uniform_real_distribution<double> radius(0.15, 0.4);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Cylinder> trees;
  for (int i = 0; i < 200; ++i) {
    const double z0 = unit(rng) < 0.2 ? 2.0 * unit(rng) : 0.0;
    trees.push_back(cylinder(xy(rng), xy(rng), radius(rng), z0, z0 + 1.0 + 7.0 * unit(rng)));
  }
  std::vector<Box> boxes;
  for (int i = 0; i < 20; ++i) {
    const double x = xy(rng);
    const double y = xy(rng);
    const double z0 = unit(rng) < 0.25 ? 3.0 * unit(rng) : 0.0;
    const double length = 1.0 + 9.0 * unit(rng);
    const double thick = 0.1 + 0.3 * unit(rng);
    const bool along_x = unit(rng) < 0.5;
    boxes.push_back(
        box(x, y, z0, x + (along_x ? length : thick), y + (along_x ? thick : length), z0 + 4.0 * unit(rng)));
  }
  return makeWorld(std::move(boxes), std::move(trees), cell_size_m);
}

Eigen::Vector3d randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Eigen::Vector3d v;
  do v = Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  while (v.norm() < 1e-6);
  return v.normalized();
}

// ---- create ----------------------------------------------------------------------------------

TEST(ObstacleWorldCreate, GivenInvalidObstaclesWhenCreatedThenErrorNamesTheObstacle) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto bad_box = ObstacleWorld::create({box(0, 0, 0, 1, 1, 1), box(0, 0, 0, nan, 1, 1)}, {});
  ASSERT_FALSE(bad_box.has_value());
  EXPECT_NE(bad_box.error().message.find("box 1"), std::string::npos) << bad_box.error().message;
  EXPECT_FALSE(ObstacleWorld::create({box(1, 0, 0, 0, 1, 1)}, {}).has_value());  // min > max
  EXPECT_FALSE(ObstacleWorld::create({box(0, 0, 0, kInf, 1, 1)}, {}).has_value());
  auto bad_radius = ObstacleWorld::create({}, {cylinder(0, 0, 1, 0, 1), cylinder(0, 0, -0.5, 0, 1)});
  ASSERT_FALSE(bad_radius.has_value());
  EXPECT_NE(bad_radius.error().message.find("cylinder 1"), std::string::npos) << bad_radius.error().message;
  EXPECT_FALSE(ObstacleWorld::create({}, {cylinder(0, 0, 0.0, 0, 1)}).has_value());
  EXPECT_FALSE(ObstacleWorld::create({}, {cylinder(0, 0, 1, 2, 1)}).has_value());  // z_min > z_max
  EXPECT_FALSE(ObstacleWorld::create({}, {cylinder(nan, 0, 1, 0, 1)}).has_value());
}

TEST(ObstacleWorldCreate, GivenBadCellSizeOrHugeGridWhenCreatedThenError) {
  for (const double cell : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(), kInf}) {
    EXPECT_FALSE(ObstacleWorld::create({box(0, 0, 0, 1, 1, 1)}, {}, cell).has_value()) << cell;
  }
  EXPECT_FALSE(ObstacleWorld::create({box(0, 0, 0, 1000, 1000, 1)}, {}, 0.01).has_value());
}

TEST(ObstacleWorldCreate, GivenObstaclesWhenCreatedThenBoundsCoverThem) {
  const ObstacleWorld world = makeWorld({box(-1, 2, 0, 3, 4, 5)}, {cylinder(10, -3, 0.5, 1, 7)}, 2.0);
  EXPECT_EQ(world.bounds().min_W_m, Eigen::Vector3d(-1, -3.5, 0));
  EXPECT_EQ(world.bounds().max_W_m, Eigen::Vector3d(10.5, 4, 7));
  EXPECT_EQ(world.gridSize(), Eigen::Vector2i(6, 4));  // 11.5 x 7.5 m (+ padding) in 2 m cells
  EXPECT_EQ(world.boxes().size(), 1U);
  EXPECT_EQ(world.cylinders().size(), 1U);
}

// ---- raycast: box ----------------------------------------------------------------------------

class RaycastBox : public ::testing::Test {
 protected:
  const ObstacleWorld world_ = makeWorld({box(2, -1, 0, 3, 1, 2)}, {});
  std::optional<double> cast(Eigen::Vector3d o, Eigen::Vector3d d, double max_range_m = 100.0) const {
    return world_.raycast(o, d.normalized(), max_range_m, false);
  }
};

TEST_F(RaycastBox, GivenAxisParallelRaysWhenCastThenDistanceToTheFacingFace) {
  EXPECT_NEAR(cast({0, 0, 1}, {1, 0, 0}).value(), 2.0, kTol);
  EXPECT_NEAR(cast({5, 0, 1}, {-1, 0, 0}).value(), 2.0, kTol);
  EXPECT_NEAR(cast({2.5, -4, 1}, {0, 1, 0}).value(), 3.0, kTol);
  EXPECT_NEAR(cast({2.5, 4, 1}, {0, -1, 0}).value(), 3.0, kTol);
  EXPECT_NEAR(cast({2.5, 0, 5}, {0, 0, -1}).value(), 3.0, kTol);
  EXPECT_NEAR(cast({2.5, 0.5, -3}, {0, 0, 1}).value(), 3.0, kTol);
}

TEST_F(RaycastBox, GivenDiagonalRaysWhenCastThenDistanceByTrigonometry) {
  const double theta = 20.0 * std::numbers::pi / 180.0;  // hits x = 2 at y = 2 tan(20 deg) = 0.73 < 1
  EXPECT_NEAR(cast({0, 0, 1}, {std::cos(theta), std::sin(theta), 0}).value(), 2.0 / std::cos(theta), kTol);
  const Eigen::Vector3d d = Eigen::Vector3d(1, 0.2, -0.1).normalized();
  EXPECT_NEAR(cast({0, 0, 1}, d).value(), 2.0 / d.x(), kTol);
  const Eigen::Vector3d down = Eigen::Vector3d(-1, -0.5, -1).normalized();  // onto the top face
  EXPECT_NEAR(cast({3.5, 0.5, 3}, down).value(), 1.0 / -down.z(), kTol);
}

TEST_F(RaycastBox, GivenOriginOutsideTheGridWhenCastThenHitsOrLeaves) {
  EXPECT_NEAR(cast({-50, 0, 1}, {1, 0, 0}).value(), 52.0, kTol);
  EXPECT_NEAR(cast({2.5, 40, 1}, {0, -1, 0}).value(), 39.0, kTol);
  EXPECT_FALSE(cast({0, 0, 1}, {-1, 0, 0}).has_value());    // leaves away from the grid
  EXPECT_FALSE(cast({0, 0, 2.5}, {1, 0, 0}).has_value());   // passes above the box
  EXPECT_FALSE(cast({-50, 5, 1}, {1, 0, 0}).has_value());   // passes beside it
  EXPECT_FALSE(cast({2.5, 0, 5}, {0, 0, 1}).has_value());   // vertical, away
  EXPECT_FALSE(cast({10, 10, 1}, {0, 0, -1}).has_value());  // vertical, outside the grid
}

TEST_F(RaycastBox, GivenMaxRangeWhenHitIsFartherThenNothingAndInclusiveAtTheLimit) {
  EXPECT_FALSE(cast({0, 0, 1}, {1, 0, 0}, 1.9).has_value());
  EXPECT_NEAR(cast({0, 0, 1}, {1, 0, 0}, 2.0).value(), 2.0, kTol);
  EXPECT_FALSE(cast({0, 0, 1}, {1, 0, 0}, -1.0).has_value());
}

TEST_F(RaycastBox, GivenOriginInsideOrOnTheSurfaceWhenCastThenZero) {
  EXPECT_EQ(cast({2.5, 0, 1}, {1, 0, 0}).value(), 0.0);
  EXPECT_EQ(cast({2, 0, 1}, {-1, 0, 0}).value(), 0.0);
  EXPECT_EQ(cast({2.5, 0, 1}, {1, 0, 0}, 0.0).value(), 0.0);
}

TEST_F(RaycastBox, GivenRayGrazingTheTopFaceWhenCastThenTouchingCounts) {
  EXPECT_NEAR(cast({0, 0, 2}, {1, 0, 0}).value(), 2.0, kTol);
}

// ---- raycast: cylinder -----------------------------------------------------------------------

class RaycastCylinder : public ::testing::Test {
 protected:
  const ObstacleWorld world_ = makeWorld({}, {cylinder(5, 0, 0.5, 0, 3), cylinder(-5, 0, 0.5, 1, 3)});
  std::optional<double> cast(Eigen::Vector3d o, Eigen::Vector3d d, bool ground = false) const {
    return world_.raycast(o, d.normalized(), 100.0, ground);
  }
};

TEST_F(RaycastCylinder, GivenHorizontalRaysWhenCastThenDistanceToTheSide) {
  EXPECT_NEAR(cast({0, 0, 1}, {1, 0, 0}).value(), 4.5, kTol);
  EXPECT_NEAR(cast({10, 0, 1}, {-1, 0, 0}).value(), 4.5, kTol);
  EXPECT_NEAR(cast({5, -10, 1}, {0, 1, 0}).value(), 9.5, kTol);
  EXPECT_NEAR(cast({5, 10, 1}, {0, -1, 0}).value(), 9.5, kTol);
  EXPECT_NEAR(cast({0, 0.3, 1}, {1, 0, 0}).value(), 4.6, kTol);  // chord: 5 - sqrt(0.5^2 - 0.3^2)
  const double theta = 3.0 * std::numbers::pi / 180.0;           // t = D cos - sqrt(r^2 - D^2 sin^2)
  const double expected = 5.0 * std::cos(theta) - std::sqrt(0.25 - 25.0 * std::sin(theta) * std::sin(theta));
  EXPECT_NEAR(cast({0, 0, 1}, {std::cos(theta), std::sin(theta), 0}).value(), expected, kTol);
  EXPECT_FALSE(cast({0, 0.51, 1}, {1, 0, 0}).has_value());
}

TEST_F(RaycastCylinder, GivenVerticalRaysWhenCastThenCapsAreHit) {
  EXPECT_NEAR(cast({5.2, 0.1, 10}, {0, 0, -1}).value(), 7.0, kTol);       // top cap
  EXPECT_NEAR(cast({-5.2, 0.1, 0.5}, {0, 0, 1}).value(), 0.5, kTol);      // bottom cap of the raised one
  EXPECT_FALSE(cast({5.6, 0, 10}, {0, 0, -1}).has_value());               // beside it
  EXPECT_NEAR(cast({5.6, 0, 10}, {0, 0, -1}, true).value(), 10.0, kTol);  // ... onto the ground
}

TEST_F(RaycastCylinder, GivenDiagonalRayOverTheRimWhenCastThenTopCapIsHit) {
  // From (3, 0, 5) at 45 deg down: passes x = 4.5 at z = 3.5 (above), meets z = 3 at x = 5.
  EXPECT_NEAR(cast({3, 0, 5}, {1, 0, -1}).value(), 2.0 * std::sqrt(2.0), kTol);
}

TEST_F(RaycastCylinder, GivenRayUnderARaisedCylinderWhenCastThenItPassesBeneath) {
  // The raised cylinder at x = -5 (z in [1, 3]) is above the ray; the next one is hit at x = 4.5.
  EXPECT_NEAR(cast({-10, 0, 0.5}, {1, 0, 0}).value(), 14.5, kTol);
}

// ---- raycast: ground -------------------------------------------------------------------------

TEST(RaycastGround, GivenDownwardRayWhenGroundOnThenGroundHitElseNothing) {
  const ObstacleWorld world = makeWorld({}, {cylinder(5, 0, 0.5, 0, 3)});
  const Eigen::Vector3d d = Eigen::Vector3d(0, 1, -1).normalized();
  EXPECT_NEAR(world.raycast({0, -5, 2}, d, 100.0, true).value(), 2.0 * std::sqrt(2.0), kTol);
  EXPECT_FALSE(world.raycast({0, -5, 2}, d, 100.0, false).has_value());
  EXPECT_FALSE(world.raycast({0, -5, 2}, d, 2.8, true).has_value());  // 2 sqrt 2 = 2.83 > 2.8
  EXPECT_EQ(world.raycast({0, 0, -1}, d, 100.0, true).value(), 0.0);  // below ground: inside it
  // Ground before the obstacle wins; the obstacle before the ground wins.
  const Eigen::Vector3d steep = Eigen::Vector3d(1, 0, -1).normalized();
  EXPECT_NEAR(world.raycast({0, 0, 1}, steep, 100.0, true).value(), std::sqrt(2.0), kTol);
  const Eigen::Vector3d shallow = Eigen::Vector3d(1, 0, -0.1).normalized();
  EXPECT_NEAR(world.raycast({0, 0, 1}, shallow, 100.0, true).value(), 4.5 / shallow.x(), kTol);
}

TEST(RaycastGround, GivenEmptyWorldWhenQueriedThenOnlyTheGroundExists) {
  const ObstacleWorld world = makeWorld({}, {});
  EXPECT_NEAR(world.raycast({0, 0, 3}, {0, 0, -1}, 10.0, true).value(), 3.0, kTol);
  EXPECT_FALSE(world.raycast({0, 0, 3}, {1, 0, 0}, 10.0, true).has_value());
  EXPECT_TRUE(world.segmentClear({0, 0, 1}, {5, 0, -1}));
  EXPECT_EQ(world.distance({1, 2, 3}), kInf);
}

// ---- segmentClear ----------------------------------------------------------------------------

TEST(SegmentClear, GivenWallBetweenTwoPointsThenBlockedAndGapOrDetourIsClear) {
  const ObstacleWorld wall = makeWorld({box(4, -5, 0, 4.2, 5, 3)}, {});
  EXPECT_FALSE(wall.segmentClear({0, 0, 1}, {8, 0, 1}));
  EXPECT_FALSE(wall.segmentClear({8, 0, 1}, {0, 0, 1}));
  EXPECT_TRUE(wall.segmentClear({0, 0, 4}, {8, 0, 4}));       // over the wall
  EXPECT_TRUE(wall.segmentClear({0, 0, 1}, {3.9, 0, 1}));     // stops short
  EXPECT_FALSE(wall.segmentClear({0, 0, 1}, {4.0, 0, 1}));    // ends on the face: touching blocks
  EXPECT_TRUE(wall.segmentClear({0, 0, 1}, {3.0, 0, -1}));    // the ground does not count
  EXPECT_FALSE(wall.segmentClear({4.1, 0, 1}, {4.1, 0, 1}));  // a point inside
  EXPECT_TRUE(wall.segmentClear({1, 0, 1}, {1, 0, 1}));       // a point outside

  const ObstacleWorld gap = makeWorld({box(4, -5, 0, 4.2, -0.5, 3), box(4, 0.5, 0, 4.2, 5, 3)}, {});
  EXPECT_TRUE(gap.segmentClear({0, 0, 1}, {8, 0, 1}));
  EXPECT_TRUE(gap.segmentClear({0, -0.4, 1}, {8, 0.4, 1}));
  EXPECT_FALSE(gap.segmentClear({0, -4, 1}, {8, -1, 1}));  // meets the wall at y = -2.5
}

// ---- distance --------------------------------------------------------------------------------

TEST(Distance, GivenPointsNearABoxThenFaceEdgeAndCornerDistances) {
  const ObstacleWorld world = makeWorld({box(2, -1, 0, 3, 1, 2)}, {});
  EXPECT_NEAR(world.distance({1, 0, 1}), 1.0, kTol);              // face
  EXPECT_NEAR(world.distance({1, -2, 1}), std::sqrt(2.0), kTol);  // edge
  EXPECT_NEAR(world.distance({1, -2, 3}), std::sqrt(3.0), kTol);  // corner
  EXPECT_NEAR(world.distance({4, 3, -2}), 3.0, kTol);             // lower corner (1, 2, 2) away, below ground
  EXPECT_EQ(world.distance({2.5, 0, 1}), 0.0);                    // inside
  EXPECT_EQ(world.distance({2, 0, 1}), 0.0);                      // on the surface
  EXPECT_NEAR(world.distance({-97, 0, 1}), 99.0, kTol);           // far outside the grid
}

TEST(Distance, GivenPointsNearACylinderThenSideCapAndRimDistances) {
  const ObstacleWorld world = makeWorld({}, {cylinder(10, 0, 0.5, 1, 3)});
  EXPECT_NEAR(world.distance({12, 0, 2}), 1.5, kTol);      // side
  EXPECT_NEAR(world.distance({10, 0.2, 4}), 1.0, kTol);    // over the top cap
  EXPECT_NEAR(world.distance({10, 0, 0.25}), 0.75, kTol);  // under the bottom cap
  EXPECT_NEAR(world.distance({10.8, 0, 3.4}), 0.5, kTol);  // beyond the rim: (0.3, 0.4)
  EXPECT_EQ(world.distance({10.1, 0.1, 2}), 0.0);          // inside
  EXPECT_TRUE(std::isnan(world.distance({std::numeric_limits<double>::quiet_NaN(), 0, 0})));
}

// ---- against the brute-force reference -------------------------------------------------------

class AgainstBruteForce : public ::testing::TestWithParam<double> {};

TEST_P(AgainstBruteForce, GivenRandomRaysInARandomForestThenSameHitsAsBruteForce) {
  std::mt19937_64 rng(42);
  const ObstacleWorld world = randomForest(rng, GetParam());
  std::uniform_real_distribution<double> xy(-30.0, 30.0);
  std::uniform_real_distribution<double> z(0.05, 10.0);
  std::uniform_real_distribution<double> range(0.0, 60.0);
  std::uniform_int_distribution<int> pick(0, 19);
  const std::array<Eigen::Vector3d, 6> axes{Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX(),
                                            Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitY(),
                                            Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ()};
  int hits = 0;
  for (int i = 0; i < 10000; ++i) {
    const Eigen::Vector3d o(xy(rng), xy(rng), z(rng));
    const int kind = pick(rng);
    const Eigen::Vector3d d = kind < 6 ? axes[static_cast<std::size_t>(kind)] : randomUnit(rng);  // 30 % axis-parallel
    const double max_range_m = range(rng);
    const bool ground = (i % 2) == 0;
    const auto expected = refRaycast(world, o, d, max_range_m, ground);
    const auto actual = world.raycast(o, d, max_range_m, ground);
    ASSERT_EQ(actual.has_value(), expected.has_value()) << "ray " << i;
    if (expected) {
      ASSERT_NEAR(*actual, *expected, 1e-9) << "ray " << i;
      ++hits;
    }
    const Eigen::Vector3d b = o + max_range_m * d;
    ASSERT_EQ(world.segmentClear(o, b), !refRaycast(world, o, d, max_range_m, false).has_value()) << "segment " << i;
  }
  EXPECT_GT(hits, 2000);  // the test exercises hits, not just misses
  EXPECT_LT(hits, 9000);
}

TEST_P(AgainstBruteForce, GivenRandomPointsInARandomForestThenSameDistanceAsBruteForce) {
  std::mt19937_64 rng(7);
  const ObstacleWorld world = randomForest(rng, GetParam());
  std::uniform_real_distribution<double> xy(-30.0, 30.0);
  std::uniform_real_distribution<double> z(-2.0, 12.0);
  std::uniform_real_distribution<double> far(-500.0, 500.0);
  int zeros = 0;
  for (int i = 0; i < 10000; ++i) {
    Eigen::Vector3d p(xy(rng), xy(rng), z(rng));
    if (i % 10 == 1) p = Eigen::Vector3d(far(rng), far(rng), far(rng));  // far outside the grid
    if (i % 10 == 2) {                                                   // inside a tree
      const Cylinder& c = world.cylinders()[static_cast<std::size_t>(i) % world.cylinders().size()];
      p << c.center_W_m + 0.5 * c.radius_m * Eigen::Vector2d(1, 0), 0.5 * (c.z_min_m + c.z_max_m);
    }
    const double expected = refDistance(world, p);
    ASSERT_NEAR(world.distance(p), expected, 1e-9) << "point " << i;
    zeros += expected == 0.0 ? 1 : 0;
  }
  EXPECT_GE(zeros, 1000);
}

INSTANTIATE_TEST_SUITE_P(CellSizes, AgainstBruteForce, ::testing::Values(0.3, 1.0, 7.0));

}  // namespace
}  // namespace aerotrack::hal::sim
