// Tests of the walking person (hal/sim/person/walking_person.hpp) against closed-form values: body
// proportions when standing, the trapezoidal speed profile on a straight line, the corner arc of a
// 90-degree turn, stops, pauses and reversals, and the gait (alternating feet, opposite arm swing,
// cadence f = 1.8 (v / 1.4)^0.58 steps/s).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "../../../support/require.hpp"
#include "aerotrack/hal/sim/walking_person.hpp"

namespace aerotrack::hal::sim {
namespace {

using K = CocoKeypoint;
constexpr double kPi = std::numbers::pi;

const Eigen::Vector3d& kp(const PersonState& s, K k) {
  return s.keypoints_W_m[index(k)];
}

WalkingPerson make(const std::vector<PathPoint>& path, const PersonParams& params = {}) {
  return aerotrack::test::require(WalkingPerson::create(params, path), "WalkingPerson::create");
}

// Forward component of a keypoint relative to the pelvis ground point, along the heading.
double forwardOf(const PersonState& s, K k) {
  const Eigen::Vector3d d = kp(s, k) - s.p_W_m;
  return d.x() * std::cos(s.heading_rad) + d.y() * std::sin(s.heading_rad);
}

double distanceToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - p).norm();
}

TEST(WalkingPerson, GivenInvalidInputsWhenCreatingThenReturnsAnError) {
  EXPECT_FALSE(WalkingPerson::create({}, {}).has_value());
  EXPECT_FALSE(WalkingPerson::create({}, {{{0, 0}, 0.0}, {{1, 0}, 1.0}}).has_value());  // zero speed
  EXPECT_FALSE(WalkingPerson::create({}, {{{0, 0}, 7.0}, {{1, 0}, 1.0}}).has_value());  // too fast
  EXPECT_FALSE(WalkingPerson::create({}, {{{0, 0}, 1.0}, {{0, 0}, 1.0}}).has_value());  // repeated point
  EXPECT_FALSE(WalkingPerson::create({}, {{{0, NAN}, 1.0}}).has_value());
  EXPECT_FALSE(WalkingPerson::create({}, {{{0, 0}, 1.0, -1.0}, {{1, 0}, 1.0}}).has_value());
  PersonParams p;
  p.torso_m = 0.2;  // below 0.2 H
  EXPECT_FALSE(WalkingPerson::create(p, {{{0, 0}, 1.0}}).has_value());
  p = {};
  p.max_accel_mps2 = 0.0;
  const auto bad = WalkingPerson::create(p, {{{0, 0}, 1.0}});
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("max_accel_mps2"), std::string::npos);
  // The last point's speed is ignored.
  EXPECT_TRUE(WalkingPerson::create({}, {{{0, 0}, 1.0}, {{1, 0}, 0.0}}).has_value());
}

TEST(WalkingPerson, GivenOnePointPathWhenStandingThenBodyFollowsAnthropometricProportions) {
  const PersonParams params;  // H = 1.75 m, torso 0.50 m
  const double h = params.height_m;
  const WalkingPerson w = make({{{2.0, 3.0}, 1.0}});
  EXPECT_EQ(w.durationS(), 0.0);
  const PersonState s = w.state(7.0);
  EXPECT_NEAR((s.p_W_m - Eigen::Vector3d(2, 3, 0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(s.speed_mps, 0.0);
  EXPECT_EQ(s.heading_rad, 0.0);
  // Ankles near the ground: at the ankle height 0.039 H = 6.8 cm.
  EXPECT_NEAR(kp(s, K::kLeftAnkle).z(), 0.039 * h, 1e-9);
  EXPECT_NEAR(kp(s, K::kRightAnkle).z(), 0.039 * h, 1e-9);
  // Upper body (neck to mid-hips) = torso_m within 1 cm.
  const Eigen::Vector3d neck = 0.5 * (kp(s, K::kLeftShoulder) + kp(s, K::kRightShoulder));
  const Eigen::Vector3d mid_hip = 0.5 * (kp(s, K::kLeftHip) + kp(s, K::kRightHip));
  EXPECT_NEAR((neck - mid_hip).norm(), params.torso_m, 0.01);
  EXPECT_NEAR(mid_hip.z(), 0.530 * h, 1e-9);
  // Nose at about 0.93 H (within 0.02 H = 3.5 cm), eyes at 0.936 H within 1 cm.
  EXPECT_NEAR(kp(s, K::kNose).z() / h, 0.93, 0.02);
  EXPECT_NEAR(kp(s, K::kLeftEye).z(), 0.936 * h, 0.01);
  // Legs straight (hip-ankle distance = thigh + shank), arms hanging straight down.
  const double leg = (0.530 - 0.039) * h;
  EXPECT_NEAR((kp(s, K::kLeftHip) - kp(s, K::kLeftAnkle)).norm(), leg, 1e-9);
  const double arm = (0.186 + 0.146) * h;
  EXPECT_NEAR((kp(s, K::kRightShoulder) - kp(s, K::kRightWrist)).z(), arm, 1e-9);
  EXPECT_NEAR((kp(s, K::kRightShoulder) - kp(s, K::kRightWrist)).head<2>().norm(), 0.0, 1e-9);
  // Widths: shoulders 0.259 H, hips 0.191 H.
  EXPECT_NEAR((kp(s, K::kLeftShoulder) - kp(s, K::kRightShoulder)).norm(), 0.259 * h, 1e-9);
  EXPECT_NEAR((kp(s, K::kLeftHip) - kp(s, K::kRightHip)).norm(), 0.191 * h, 1e-9);
}

TEST(WalkingPerson, GivenNonDefaultTorsoWhenStandingThenNeckToHipEqualsTorso) {
  PersonParams p;
  p.height_m = 1.60;
  p.torso_m = 0.55;
  const PersonState s = make({{{0, 0}, 1.0}}, p).state(0.0);
  const Eigen::Vector3d neck = 0.5 * (kp(s, K::kLeftShoulder) + kp(s, K::kRightShoulder));
  const Eigen::Vector3d mid_hip = 0.5 * (kp(s, K::kLeftHip) + kp(s, K::kRightHip));
  EXPECT_NEAR((neck - mid_hip).norm(), 0.55, 1e-9);
}

TEST(WalkingPerson, GivenHeadingNorthWhenStandingThenLeftKeypointsAreOnThePersonsLeft) {
  const WalkingPerson w = make({{{0, 0}, 1.0}, {{0, 10}, 1.0}});
  const PersonState s = w.state(-1.0);  // before the start: standing, facing the first leg
  EXPECT_NEAR(s.heading_rad, kPi / 2, 1e-12);
  const Eigen::Vector3d left_W(-1, 0, 0);  // heading +y: the person's left is -x
  const std::pair<K, K> pairs[] = {{K::kLeftEye, K::kRightEye},           {K::kLeftEar, K::kRightEar},
                                   {K::kLeftShoulder, K::kRightShoulder}, {K::kLeftElbow, K::kRightElbow},
                                   {K::kLeftWrist, K::kRightWrist},       {K::kLeftHip, K::kRightHip},
                                   {K::kLeftKnee, K::kRightKnee},         {K::kLeftAnkle, K::kRightAnkle}};
  for (const auto& [l, r] : pairs) {
    EXPECT_GT((kp(s, l) - kp(s, r)).dot(left_W), 0.05) << index(l);
  }
  // The nose is in front (+y) of the ears.
  EXPECT_GT(kp(s, K::kNose).y() - kp(s, K::kLeftEar).y(), 0.05);
}

TEST(WalkingPerson, GivenStraightLegWhenWalkingThenSpeedProfileIsTrapezoidal) {
  const PersonParams params;  // a = 1.5 m/s^2
  const double v = 1.4, a = params.max_accel_mps2, len = 20.0;
  const WalkingPerson w = make({{{0, 0}, v}, {{len, 0}, v}});
  // Closed form: len / v + v / a (accelerate v / a, cruise, decelerate v / a).
  EXPECT_NEAR(w.durationS(), len / v + v / a, 1e-9);
  // Acceleration phase: x = a t^2 / 2.
  EXPECT_NEAR(w.state(0.5).p_W_m.x(), 0.5 * a * 0.25, 1e-9);
  EXPECT_NEAR(w.state(0.5).speed_mps, 0.75, 1e-9);
  // After the acceleration phase the position advances at the commanded speed.
  for (double t = v / a + 0.01; t + 1.0 < w.durationS() - v / a; t += 0.37) {
    EXPECT_NEAR(w.state(t + 1.0).p_W_m.x() - w.state(t).p_W_m.x(), v, 1e-9) << t;
    EXPECT_NEAR(w.state(t).speed_mps, v, 1e-9);
  }
  // Speed never above the leg speed; |dv/dt| and |d2p/dt2| (finite differences) within a.
  const double dt = 0.01;
  for (double t = -1.0; t < w.durationS() + 1.0; t += dt) {
    const PersonState s0 = w.state(t - dt), s1 = w.state(t), s2 = w.state(t + dt);
    EXPECT_LE(s1.speed_mps, v + 1e-12);
    EXPECT_LE(std::abs(s2.speed_mps - s1.speed_mps) / dt, a + 1e-6) << t;
    EXPECT_LE((s2.p_W_m - 2.0 * s1.p_W_m + s0.p_W_m).norm() / (dt * dt), a + 1e-6) << t;
    EXPECT_NEAR(s1.p_W_m.y(), 0.0, 1e-12);
    EXPECT_EQ(s1.p_W_m.z(), 0.0);
  }
}

TEST(WalkingPerson, GivenFasterSecondLegWhenWalkingThenEachLegsSpeedIsRespected) {
  const PersonParams params;
  const WalkingPerson w = make({{{0, 0}, 1.0}, {{10, 0}, 2.0}, {{20, 0}, 1.0}});
  double max_speed = 0.0;
  const double dt = 0.01;
  for (double t = 0.0; t < w.durationS(); t += dt) {
    const PersonState s = w.state(t);
    EXPECT_LE(s.speed_mps, (s.p_W_m.x() < 10.0 ? 1.0 : 2.0) + 1e-9) << t;
    EXPECT_LE(std::abs(w.state(t + dt).speed_mps - s.speed_mps) / dt, params.max_accel_mps2 + 1e-6);
    max_speed = std::max(max_speed, s.speed_mps);
  }
  EXPECT_NEAR(max_speed, 2.0, 1e-9);  // 1 m to speed up, 4/3 m to stop: 2 m/s is reached
  // Closed form: 0 -> 1 m/s over 1/3 m (2/3 s), 9.667 m cruise; 1 -> 2 m/s over 1 m (2/3 s),
  // 7.667 m cruise; 2 -> 0 over 4/3 m (4/3 s).
  EXPECT_NEAR(w.durationS(), (2.0 / 3.0 + (10.0 - 1.0 / 3.0)) + 2.0 / 3.0 + (10.0 - 1.0 - 4.0 / 3.0) / 2.0 + 4.0 / 3.0,
              1e-9);
}

TEST(WalkingPerson, GivenRightAngleCornerWhenWalkingThenFollowsArcAndSlowsDown) {
  const PersonParams params;  // r = 0.5 m, lateral 2 m/s^2: corner speed sqrt(2 * 0.5) = 1 m/s
  const double r = params.corner_radius_m;
  const WalkingPerson w = make({{{0, 0}, 1.4}, {{10, 0}, 1.4}, {{10, 10}, 1.4}});
  // Path length: two legs shortened by r each, plus the quarter arc.
  EXPECT_NEAR(w.lengthM(), 20.0 - 2.0 * r + 0.5 * kPi * r, 1e-9);
  const Eigen::Vector2d a(0, 0), corner(10, 0), b(10, 10);
  const double dt = 0.005;
  double prev_heading = 0.0, closest = 1e9, max_dev = 0.0, max_corner_speed = 0.0, max_speed = 0.0;
  for (double t = 0.0; t <= w.durationS() + dt; t += dt) {
    const PersonState s = w.state(t);
    const Eigen::Vector2d p = s.p_W_m.head<2>();
    const double dev = std::min(distanceToSegment(p, a, corner), distanceToSegment(p, corner, b));
    max_dev = std::max(max_dev, dev);
    closest = std::min(closest, (p - corner).norm());
    // Heading continuous and monotone: rate v / r <= 1 / 0.5 = 2 rad/s.
    EXPECT_GE(s.heading_rad, prev_heading - 1e-12);
    EXPECT_LE(s.heading_rad - prev_heading, 2.0 * dt + 1e-9) << t;
    prev_heading = s.heading_rad;
    if ((p - corner).norm() < r)
      max_corner_speed  // on the arc
          = std::max(max_corner_speed, s.speed_mps);
    max_speed = std::max(max_speed, s.speed_mps);
  }
  EXPECT_NEAR(prev_heading, kPi / 2, 1e-12);
  // Arc midpoint is r (sqrt 2 - 1) = 0.207 m from the corner: the farthest the path strays.
  EXPECT_LE(max_dev, r * (std::sqrt(2.0) - 1.0) + 1e-9);
  EXPECT_NEAR(closest, r * (std::sqrt(2.0) - 1.0), 1e-4);
  EXPECT_LE(closest, r);
  EXPECT_NEAR(max_corner_speed, 1.0, 1e-6);  // slowed from 1.4 to sqrt(a_lat r)
  EXPECT_NEAR(max_speed, 1.4, 1e-9);
}

TEST(WalkingPerson, GivenPathEndWhenTimePassesThenStandsStillAtTheEnd) {
  const WalkingPerson w = make({{{0, 0}, 1.4}, {{10, 0}, 1.4}, {{10, 10}, 1.4}});
  const PersonState end = w.state(w.durationS());
  const PersonState later = w.state(w.durationS() + 100.0);
  for (const PersonState& s : {end, later}) {
    EXPECT_EQ(s.speed_mps, 0.0);
    EXPECT_EQ(s.v_W_mps.norm(), 0.0);
    EXPECT_NEAR((s.p_W_m - Eigen::Vector3d(10, 10, 0)).norm(), 0.0, 1e-9);
    EXPECT_NEAR(s.heading_rad, kPi / 2, 1e-12);
  }
  for (std::size_t k = 0; k < kNumKeypoints; ++k) EXPECT_EQ(end.keypoints_W_m[k], later.keypoints_W_m[k]);
  // Standing pose: both ankles on the ground directly under the hips.
  EXPECT_NEAR(kp(end, K::kLeftAnkle).z(), 0.039 * 1.75, 1e-9);
  EXPECT_NEAR((kp(end, K::kLeftAnkle) - kp(end, K::kLeftHip)).head<2>().norm(), 0.0, 1e-9);
}

TEST(WalkingPerson, GivenPauseAtCornerWhenWalkingThenStopsTurnsOnTheSpotAndWaits) {
  PersonParams params;
  const WalkingPerson w = make({{{0, 0}, 1.4}, {{5, 0}, 1.4, 2.0}, {{5, 5}, 1.4}}, params);
  // Two runs of 5 m from rest to rest, plus the turn (pi/2 at pi rad/s: 0.5 s) and the 2 s pause.
  const double run = 5.0 / 1.4 + 1.4 / 1.5;
  EXPECT_NEAR(w.durationS(), 2.0 * run + 0.5 + 2.0, 1e-9);
  EXPECT_NEAR(w.lengthM(), 10.0, 1e-12);  // no arc: the corner point itself is visited
  const PersonState arrive = w.state(run);
  EXPECT_NEAR((arrive.p_W_m - Eigen::Vector3d(5, 0, 0)).norm(), 0.0, 1e-9);
  EXPECT_EQ(arrive.speed_mps, 0.0);
  EXPECT_NEAR(arrive.heading_rad, 0.0, 1e-12);
  EXPECT_NEAR(w.state(run + 0.25).heading_rad, kPi / 4, 1e-12);  // smoothstep midpoint
  const PersonState waiting = w.state(run + 0.5 + 1.9);
  EXPECT_NEAR((waiting.p_W_m - Eigen::Vector3d(5, 0, 0)).norm(), 0.0, 1e-9);
  EXPECT_NEAR(waiting.heading_rad, kPi / 2, 1e-12);
  EXPECT_GT(w.state(run + 2.6).p_W_m.y(), 0.0);  // walking again
}

TEST(WalkingPerson, GivenStartPauseWhenWaitingThenStandsAtStartFacingTheFirstLeg) {
  const WalkingPerson w = make({{{1, 1}, 1.0, 3.0}, {{1, -4}, 1.0}});
  EXPECT_NEAR(w.durationS(), 3.0 + 5.0 / 1.0 + 1.0 / 1.5, 1e-9);
  const PersonState s = w.state(2.9);
  EXPECT_NEAR((s.p_W_m - Eigen::Vector3d(1, 1, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(s.heading_rad, -kPi / 2, 1e-12);
}

TEST(WalkingPerson, GivenReversalWhenWalkingThenStopsAtTheTurnPointAndTurnsAround) {
  const WalkingPerson w = make({{{0, 0}, 1.4}, {{4, 0}, 1.4}, {{0, 0}, 1.4}});
  double max_x = -1.0;
  for (double t = 0.0; t <= w.durationS(); t += 0.01) {
    const PersonState s = w.state(t);
    max_x = std::max(max_x, s.p_W_m.x());
    EXPECT_NEAR(s.p_W_m.y(), 0.0, 1e-12);
    if (s.p_W_m.x() > 4.0 - 1e-9) {
      EXPECT_EQ(s.speed_mps, 0.0);
    }
  }
  EXPECT_NEAR(max_x, 4.0, 1e-9);
  EXPECT_NEAR(std::abs(w.state(w.durationS()).heading_rad), kPi, 1e-9);
  EXPECT_NEAR(w.durationS(), 2.0 * (4.0 / 1.4 + 1.4 / 1.5) + 1.0, 1e-9);  // turning pi at pi rad/s
}

// Keypoints move continuously (< 1 cm per ms, i.e. below 10 m/s) through every phase transition.
TEST(WalkingPerson, GivenCornersStopsAndPausesWhenSampledFinelyThenKeypointsAreContinuous) {
  const WalkingPerson w = make({{{0, 0}, 1.0, 0.5},
                                {{3, 0}, 2.0},
                                {{3, 3}, 0.7, 1.0},
                                {{0, 3}, 1.8},
                                {{1, 0.5}, 1.4},
                                {{-2, 0.4}, 1.4},
                                {{4, 0.4}, 1.4}});
  const double dt = 0.001;
  PersonState prev = w.state(-dt);
  double worst = 0.0;
  for (double t = 0.0; t <= w.durationS() + 0.1; t += dt) {
    const PersonState s = w.state(t);
    for (std::size_t k = 0; k < kNumKeypoints; ++k) {
      worst = std::max(worst, (s.keypoints_W_m[k] - prev.keypoints_W_m[k]).norm());
    }
    EXPECT_LE((s.p_W_m - prev.p_W_m).norm(), 2.0 * dt + 1e-9);
    prev = s;
  }
  EXPECT_LT(worst, 0.01);
}

struct GaitSample {
  double left_ankle, right_ankle, left_wrist, right_wrist, leg_rad, lower_ankle_z;
};

GaitSample gaitAt(const PersonState& s) {
  // Leg angle: the hip-to-ankle line against the vertical, positive forward.
  const Eigen::Vector3d leg = kp(s, K::kLeftAnkle) - kp(s, K::kLeftHip);
  const double leg_fwd = leg.x() * std::cos(s.heading_rad) + leg.y() * std::sin(s.heading_rad);
  return {forwardOf(s, K::kLeftAnkle),   forwardOf(s, K::kRightAnkle),
          forwardOf(s, K::kLeftWrist),   forwardOf(s, K::kRightWrist),
          std::atan2(leg_fwd, -leg.z()), std::min(kp(s, K::kLeftAnkle).z(), kp(s, K::kRightAnkle).z())};
}

double correlation(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) mx += x[i] / n, my += y[i] / n;
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  return sxy / std::sqrt(sxx * syy);
}

TEST(WalkingPerson, GivenSteadyWalkWhenOneStrideElapsesThenFeetAlternateAndArmsSwingOpposite) {
  const double v = 1.4;
  const WalkingPerson w = make({{{0, 0}, v}, {{100, 0}, v}});
  const double f = 1.8;             // steps/s at 1.4 m/s
  const double step_m = v / f;      // 0.778 m
  const double stride_s = 2.0 / f;  // one stride = two steps
  std::vector<double> la, ra, lw, rw;
  double max_leg = 0.0, max_lower_ankle = 0.0;
  for (double t = 10.0; t < 10.0 + stride_s; t += 0.002) {
    const GaitSample g = gaitAt(w.state(t));
    la.push_back(g.left_ankle);
    ra.push_back(g.right_ankle);
    lw.push_back(g.left_wrist);
    rw.push_back(g.right_wrist);
    max_leg = std::max(max_leg, std::abs(g.leg_rad));
    max_lower_ankle = std::max(max_lower_ankle, g.lower_ankle_z);
  }
  // Ankles reach +-step/2 in front of and behind the pelvis, in antiphase.
  EXPECT_NEAR(*std::max_element(la.begin(), la.end()), 0.5 * step_m, 0.01);
  EXPECT_NEAR(*std::min_element(la.begin(), la.end()), -0.5 * step_m, 0.01);
  EXPECT_NEAR(*std::max_element(ra.begin(), ra.end()), 0.5 * step_m, 0.01);
  EXPECT_LT(correlation(la, ra), -0.9);
  // Each wrist swings opposite to the ankle on its side.
  EXPECT_LT(correlation(lw, la), -0.8);
  EXPECT_LT(correlation(rw, ra), -0.8);
  // Legs swing about +-25 deg at 1.4 m/s (within 3 deg).
  EXPECT_NEAR(max_leg * 180.0 / kPi, 25.0, 3.0);
  // The lower foot stays near the ground: at most 7 cm of heel rise above the standing ankle height.
  EXPECT_LE(max_lower_ankle, 0.039 * 1.75 + 0.07);
}

TEST(WalkingPerson, GivenFasterWalkWhenCountingStepsThenCadenceRisesAsPowerLaw) {
  double cadence[2] = {0.0, 0.0};
  const double speeds[2] = {1.0, 2.0};
  for (int i = 0; i < 2; ++i) {
    const double v = speeds[i];
    const WalkingPerson w = make({{{0, 0}, v}, {{100, 0}, v}});
    // A step = the feet passing each other = a sign change of (left - right ankle) forward offset.
    const double t0 = 5.0, t1 = 35.0;
    int crossings = 0;
    double prev = gaitAt(w.state(t0)).left_ankle - gaitAt(w.state(t0)).right_ankle;
    for (double t = t0; t < t1; t += 0.002) {
      const GaitSample g = gaitAt(w.state(t));
      const double d = g.left_ankle - g.right_ankle;
      if ((d > 0) != (prev > 0)) ++crossings;
      prev = d;
    }
    cadence[i] = crossings / (t1 - t0);
    const double expected = 1.8 * std::pow(v / 1.4, 0.58);  // 1.48 and 2.21 steps/s
    EXPECT_NEAR(cadence[i], expected, 0.05 * expected) << v;
    EXPECT_NEAR(w.cadenceHz(v), expected, 1e-12);
  }
  EXPECT_GT(cadence[1], cadence[0] * 1.3);
}

// Issue 20: a runner's speed profile and scripted behaviours.

// A long straight leg reaches its speed: accelerate v / a, cruise, brake v / a (closed form).
TEST(WalkingPerson, GivenLongStraightLegAtRunningSpeedWhenRunningThenReachesTheLegSpeed) {
  for (const double v : {5.0, 6.0}) {
    const PersonParams params;  // a = 1.5 m/s^2: 8.3 m (5 m/s) or 12 m (6 m/s) to speed up
    const double len = 60.0, a = params.max_accel_mps2;
    const WalkingPerson w = make({{{0, 0}, v}, {{len, 0}, v}});
    double top = 0.0;
    for (double t = 0.0; t <= w.durationS(); t += 0.01) top = std::max(top, w.state(t).speed_mps);
    EXPECT_NEAR(top, v, 1e-9) << v;
    EXPECT_NEAR(w.durationS(), len / v + v / a, 1e-9) << v;
    EXPECT_NEAR(w.state(0.5 * w.durationS()).v_W_mps.x(), v, 1e-9);
  }
}

// A leg's own acceleration bound (a sprint start) replaces the person's.
TEST(WalkingPerson, GivenLegAccelerationWhenStartingThenSpeedsUpAtThatRate) {
  PathPoint start{{0, 0}, 6.0};
  start.accel_mps2 = 4.0;
  const WalkingPerson w = make({start, {{40, 0}, 6.0}});
  EXPECT_NEAR(w.state(1.0).speed_mps, 4.0, 1e-9);
  EXPECT_NEAR(w.state(1.0).p_W_m.x(), 2.0, 1e-9);  // a t^2 / 2
  EXPECT_NEAR(w.durationS(), 40.0 / 6.0 + 6.0 / 4.0, 1e-9);
  start.accel_mps2 = 11.0;
  EXPECT_FALSE(WalkingPerson::create({}, {start, {{40, 0}, 6.0}}).has_value());
}

// A collinear point changes the speed mid-leg without stopping there.
TEST(WalkingPerson, GivenSpeedChangeMidLegWhenRunningThenSpeedsUpWithoutStopping) {
  const WalkingPerson w = make({{{0, 0}, 2.0}, {{20, 0}, 5.0}, {{50, 0}, 5.0}});
  double speed_at_change = -1.0, top_first = 0.0, top = 0.0;
  for (double t = 0.0; t <= w.durationS(); t += 0.005) {
    const PersonState s = w.state(t);
    if (s.p_W_m.x() < 20.0) top_first = std::max(top_first, s.speed_mps);
    if (speed_at_change < 0.0 && s.p_W_m.x() >= 20.0) speed_at_change = s.speed_mps;
    top = std::max(top, s.speed_mps);
  }
  EXPECT_NEAR(top_first, 2.0, 1e-9);
  EXPECT_NEAR(speed_at_change, 2.0, 0.02);  // it speeds up only after the point
  EXPECT_NEAR(top, 5.0, 1e-9);
}

// Runner's corners: the radius is v^2 / a_lat, so the corner is run at the leg speed.
TEST(WalkingPerson, GivenWideCornersWhenRunningARightAngleThenKeepsTheLegSpeedOnTheArc) {
  PersonParams params;
  params.wide_corners = true;
  params.max_lateral_accel_mps2 = 4.0;
  params.max_corner_cut_m = 3.0;
  params.max_accel_mps2 = 3.0;
  const double v = 4.0, r = v * v / params.max_lateral_accel_mps2;  // 4 m
  const WalkingPerson w = make({{{0, 0}, v}, {{20, 0}, v}, {{20, 20}, v}}, params);
  const double t_reach = v / params.max_accel_mps2;
  double closest_to_corner = 1e9;
  for (double t = t_reach + 0.01; t < w.durationS() - t_reach - 0.01; t += 0.01) {
    const PersonState s = w.state(t);
    EXPECT_NEAR(s.speed_mps, v, 1e-9) << t;
    closest_to_corner = std::min(closest_to_corner, (s.p_W_m.head<2>() - Eigen::Vector2d(20, 0)).norm());
    // On the arc: centre (16, 4), radius 4.
    if (s.p_W_m.x() > 16.0 + 1e-9 && s.p_W_m.y() < 4.0 - 1e-9) {
      EXPECT_NEAR((s.p_W_m.head<2>() - Eigen::Vector2d(20.0 - r, r)).norm(), r, 1e-9) << t;
    }
  }
  EXPECT_NEAR(closest_to_corner, r * (std::sqrt(2.0) - 1.0), 0.01);  // the arc's midpoint
  // The walker's model (the default) slows to sqrt(a_lat * 0.5 m) on a 0.5 m arc instead.
  params.wide_corners = false;
  const WalkingPerson walker = make({{{0, 0}, v}, {{20, 0}, v}, {{20, 20}, v}}, params);
  double slowest = 1e9;
  for (double t = 3.0; t < walker.durationS() - 3.0; t += 0.01) slowest = std::min(slowest, walker.state(t).speed_mps);
  EXPECT_NEAR(slowest, std::sqrt(4.0 * 0.5), 0.01);
}

// max_corner_cut_m keeps a widened corner near the corner point.
TEST(WalkingPerson, GivenCornerCutLimitWhenRunningARightAngleThenTheArcStaysThatCloseToTheCorner) {
  PersonParams params;
  params.wide_corners = true;
  params.max_lateral_accel_mps2 = 4.0;
  params.max_corner_cut_m = 0.8;
  const WalkingPerson w = make({{{0, 0}, 5.0}, {{20, 0}, 5.0}, {{20, 20}, 5.0}}, params);
  const double r = 0.8 / (std::sqrt(2.0) - 1.0);  // 1.93 m, below v^2 / a_lat = 6.25 m
  double closest = 1e9, slowest = 1e9;
  for (double t = 3.0; t < w.durationS() - 3.0; t += 0.005) {
    const PersonState s = w.state(t);
    closest = std::min(closest, (s.p_W_m.head<2>() - Eigen::Vector2d(20, 0)).norm());
    slowest = std::min(slowest, s.speed_mps);
  }
  EXPECT_NEAR(closest, 0.8, 0.01);
  EXPECT_NEAR(slowest, std::sqrt(4.0 * r), 0.01);
}

// Walking backwards: facing against the motion, the gait reversed (the stance foot still does not
// slip), and the speed limited.
TEST(WalkingPerson, GivenBackwardLegWhenWalkingThenFacesAgainstTheMotionAndTheStanceFootStays) {
  PathPoint start{{0, 0}, 1.0};
  start.backwards = true;
  const WalkingPerson w = make({start, {{0, 10}, 1.0}});  // moving +y, facing -y
  EXPECT_NEAR(w.state(-1.0).heading_rad, -0.5 * kPi, 1e-12);
  const double dt = 1e-3;
  for (double t = 1.5; t < 8.0; t += 0.05) {
    const PersonState s = w.state(t);
    EXPECT_NEAR(s.speed_mps, 1.0, 1e-9);
    EXPECT_NEAR(s.v_W_mps.y(), 1.0, 1e-9);
    EXPECT_NEAR(s.heading_rad, -0.5 * kPi, 1e-12);
    EXPECT_NEAR(w.state(t + dt).p_W_m.y() - s.p_W_m.y(), dt, 1e-9);
    EXPECT_LT(kp(s, K::kNose).y(), s.p_W_m.y());  // the face looks back along the path
    // The lower ankle (the stance foot) does not slip along the path while the body moves at 1 m/s.
    const PersonState s1 = w.state(t + dt);
    const K stance = kp(s, K::kLeftAnkle).z() < kp(s, K::kRightAnkle).z() ? K::kLeftAnkle : K::kRightAnkle;
    EXPECT_LT(std::abs(kp(s1, stance).y() - kp(s, stance).y()) / dt, 0.05) << t;  // the gait runs in reverse
  }
  start.speed_mps = 2.5;  // above max_backward_speed_mps (2 m/s)
  const auto too_fast = WalkingPerson::create({}, {start, {{0, 10}, 1.0}});
  ASSERT_FALSE(too_fast.has_value());
  EXPECT_NE(too_fast.error().message.find("backward"), std::string::npos);
  PersonParams params;
  params.max_backward_speed_mps = 2.5;
  EXPECT_TRUE(WalkingPerson::create(params, {start, {{0, 10}, 1.0}}).has_value());
}

// Run out, turn back on the spot, run back past the start, stop and back up towards +x still facing
// -x, then turn round and walk on: the facing turns at the reversal and where backing up ends.
TEST(WalkingPerson, GivenReversalThenBackwardLegWhenWalkingThenFacingFollowsTheScript) {
  PathPoint back_up{{-5, 0}, 1.0};
  back_up.backwards = true;
  back_up.pause_s = 1.0;
  const WalkingPerson w = make({{{0, 0}, 3.0}, {{10, 0}, 3.0}, back_up, {{0, 0}, 1.4}, {{4, 0}, 1.4}});
  enum Part { kOut, kBack, kBackingUp, kOn };
  Part part = kOut;
  int samples[4] = {0, 0, 0, 0};
  double paused_s = 0.0;
  const double dt = 0.01;
  for (double t = 0.0; t <= w.durationS(); t += dt) {
    const PersonState s = w.state(t);
    EXPECT_NEAR(s.p_W_m.y(), 0.0, 1e-12);
    if (std::abs(s.p_W_m.x() + 5.0) < 1e-9) paused_s += dt;
    const double vx = s.v_W_mps.x();
    if (vx == 0.0) continue;
    if (part == kOut && vx < 0.0) part = kBack;
    if (part == kBack && vx > 0.0) part = kBackingUp;
    if (part == kBackingUp && s.p_W_m.x() > -1e-9) part = kOn;
    ++samples[part];
    EXPECT_NEAR(std::abs(vx), s.speed_mps, 1e-12);
    const double facing_x = part == kOut || part == kOn ? 1.0 : -1.0;
    EXPECT_NEAR(std::cos(s.heading_rad), facing_x, 1e-9) << t << " part " << part;
    if (part == kBackingUp) {
      EXPECT_LE(s.speed_mps, 1.0 + 1e-9);
      EXPECT_LT(s.p_W_m.x(), 0.0);
    }
  }
  for (const int n : samples) EXPECT_GT(n, 50);
  // At x = -5 only the pause: the facing does not turn (backing up keeps facing -x).
  EXPECT_NEAR(paused_s, 1.0, 0.03);
  EXPECT_NEAR(w.state(w.durationS()).heading_rad, 0.0, 1e-12);
  // Timeline: 10 m at 3 m/s (a = 1.5), turn pi at pi rad/s, 15 m at 3 m/s, pause, 5 m backing up at
  // 1 m/s, turn pi, 4 m at 1.4 m/s.
  const double a = PersonParams{}.max_accel_mps2;
  const auto leg = [a](double len, double v) { return len / v + v / a; };
  EXPECT_NEAR(w.durationS(), leg(10, 3) + 1.0 + leg(15, 3) + 1.0 + leg(5, 1) + 1.0 + leg(4, 1.4), 1e-9);
}

// Keypoints stay continuous (< 1 cm per ms) where backward walking begins and ends, through a
// reversal, a mid-leg speed change and wide runner's corners.
TEST(WalkingPerson, GivenBackwardLegsAndWideCornersWhenSampledFinelyThenKeypointsAreContinuous) {
  PersonParams params;
  params.wide_corners = true;
  params.max_lateral_accel_mps2 = 4.0;
  params.max_corner_cut_m = 0.6;
  params.max_accel_mps2 = 2.5;
  PathPoint back_up{{4, 2}, 1.0};
  back_up.backwards = true;
  PathPoint back_corner{{8, 2}, 1.0};
  back_corner.backwards = true;
  const WalkingPerson w = make({{{0, 0}, 2.0},
                                {{4, 0}, 3.0},  // speed change mid-line
                                {{10, 0}, 3.0},
                                {{10, 6}, 2.0},  // reversal
                                {{10, 2}, 2.0},
                                back_up,        // reversal into a backward leg: no turn
                                back_corner,    // backward legs joined by an arc
                                {{8, 5}, 1.4},  // backward -> forward: stop and turn
                                {{4, 5}, 1.4}},
                               params);
  const double dt = 0.001;
  PersonState prev = w.state(-dt);
  double worst = 0.0;
  for (double t = 0.0; t <= w.durationS() + 0.1; t += dt) {
    const PersonState s = w.state(t);
    for (std::size_t k = 0; k < kNumKeypoints; ++k) {
      worst = std::max(worst, (s.keypoints_W_m[k] - prev.keypoints_W_m[k]).norm());
    }
    EXPECT_LE((s.p_W_m - prev.p_W_m).norm(), 3.0 * dt + 1e-9);
    prev = s;
  }
  EXPECT_LT(worst, 0.01);
}

}  // namespace
}  // namespace aerotrack::hal::sim
