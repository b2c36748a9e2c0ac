// Someone in front of the followed person (in_front_after_ranged, issue 22 item 2). Against ground truth: the
// person stands 5 m ahead of a hovering drone; a crosser walks across 1.5 m in front of them. While the crosser
// hides the person, the crop shows the crosser alone, and the regression, fooled by a partly hidden torso, puts
// them at the person's distance (traced in the image-mode crowd, seeds 44 and 53: 3.17 m against the person's
// 3.17 m, the crosser at 2.25 m). The gate takes that distance. The depth camera, rendered here from the two
// bodies, ranges the crosser 1.5 m nearer: far outside the gate, and without the rule the regression's distance
// is given instead (the fallback for a track restarted with a wrong velocity). in_front_test: gate: a walker passes
// 0.6 m behind the person, and where they step out beside the person's body the crop shows them, torso read at the
// person's distance (traced, crowd seed 3: a look-alike ranged 0.32 m farther, given at the regression's distance).
#include <gtest/gtest.h>

#include <cmath>

#include "aerotrack/estimation/target_task.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "support/require.hpp"
#include "target_task_depth_util.hpp"
#include "target_task_test_util.hpp"

namespace aerotrack::estimation {
namespace in_front_test {
namespace {

constexpr double kRateHz = test::kFrameRateHz;
constexpr double kBodyRadiusM = 0.25;
constexpr double kPersonXM = 5.0;
constexpr double kCrosserXM = 3.5;
constexpr double kCrosserSpeedMps = 1.5;
constexpr double kDurationS = 5.0;

/// The crosser's y at t_s: walking right, crossing the line of sight at crossing_s. Briskly: the person stays
/// hidden for 0.47 s, in which the coasting track's reach along the line of sight (4 standard deviations, about
/// 1 m after half a second) stays short of the 1.5 m between them; a person hidden for longer may have walked
/// that far towards the drone, and the gate lets them.
double crosserY(double t_s, double crossing_s) {
  return -kCrosserSpeedMps * (t_s - crossing_s);
}

struct Scene {
  int crosser_given = 0;       ///< frames whose followed person was the crosser
  int person_given_after = 0;  ///< frames after the crossing whose followed person was the person
  /// While the person was hidden: the frames whose estimate tracked someone else within 0.3 m of the crosser.
  int crosser_tracked = 0;
  TargetEstimate estimate;
  TargetTaskStats stats;
};

/// The depth camera sees nothing in [gap_from_s, gap_to_s) (the person outside its narrower view).
struct DepthGap {
  double from_s = 0.0;
  double to_s = 0.0;
};

Scene run(int in_front_after_ranged, double crossing_s, DepthGap gap = {}, bool spans_unseen = false,
          int unseen_limit = 0) {
  TargetTaskParams params = test::rangedParams(kBodyRadiusM, in_front_after_ranged, false);
  params.in_front_streak_spans_unseen = spans_unseen;
  params.in_front_unseen_limit = unseen_limit;
  test::RangedRig ranged(params);
  auto& [detections, odometry, gimbal, out, task] = ranged.rig;
  auto& followed = ranged.followed;
  auto& depth = ranged.depth;
  Scene scene;
  const int frames = static_cast<int>(kDurationS * kRateHz);
  for (int i = 0; i <= frames; ++i) {
    const double t_s = i / kRateHz;
    const rt::TimeNs t_ns = rt::secondsToNs(t_s);
    test::pushHover(odometry, gimbal, t_ns);
    const double crosser_y_m = crosserY(t_s, crossing_s);
    if (t_s < gap.from_s || t_s >= gap.to_s)
      depth.write(test::renderBodiesDepth(
          t_ns, {Eigen::Vector2d(kPersonXM, 0.0), Eigen::Vector2d(kCrosserXM, crosser_y_m)}, kBodyRadiusM));
    // The crosser hides the person where their bodies overlap in the image (at the person's distance).
    const bool hidden = std::abs(crosser_y_m * kPersonXM / kCrosserXM) < 2.0 * kBodyRadiusM;
    hal::DetectionFrame frame = test::emptyFrame(i, t_ns);
    frame.person_count = 1;
    // Hidden: the crosser, in their column, with the torso of someone at the person's distance.
    test::drawPersonInColour(frame.persons[0], kPersonXM, hidden ? crosser_y_m * kPersonXM / kCrosserXM : 0.0, 3);
    frame.target_index = 0;
    detections.try_push(frame);
    task.step(t_ns + 1);
    if (const auto e = out.read(); hidden && e) {
      for (std::size_t k = 0; k < e->other_count; ++k)
        if ((e->others[k].p_W_m.head<2>() - Eigen::Vector2d(kCrosserXM, crosser_y_m)).norm() < 0.3) {
          ++scene.crosser_tracked;
          break;
        }
    }
    const auto f = followed.read();
    if (!f || f->sequence != frame.sequence || f->target_index < 0) continue;
    if (hidden) ++scene.crosser_given;
    if (!hidden && t_s > crossing_s + 0.5) ++scene.person_given_after;
  }
  scene.estimate = aerotrack::test::require(out.read(), "an estimate");
  scene.stats = task.stats();
  return scene;
}

TEST(TargetTaskInFront, GivenACrosserRangedInFrontOfTheStandingPerson_ThenTheFollowedTrackDoesNotTakeThem) {
  const Scene kept = run(5, 2.5);
  const Scene taken = run(0, 2.5);
  // Without the rule the regression's distance of the crosser is given (their depth range failed the gate).
  EXPECT_GT(taken.crosser_given, 0);
  EXPECT_EQ(taken.stats.in_front, 0U);
  // With it, never: each such frame is counted, and the person is taken again in every frame after.
  EXPECT_EQ(kept.crosser_given, 0);
  EXPECT_GE(kept.stats.in_front, 5U);
  EXPECT_EQ(kept.person_given_after, static_cast<int>(std::round((kDurationS - 3.0) * kRateHz)));
  ASSERT_TRUE(kept.estimate.initialised && !kept.estimate.lost);
  EXPECT_NEAR(kept.estimate.p_WT_m.x(), kPersonXM, 0.1);
  EXPECT_NEAR(kept.estimate.p_WT_m.y(), 0.0, 0.1);
  // Someone ranged in front of the person is someone else: from the second such frame on they are on a track of
  // their own (at their depth-ranged place), competing for the frames after.
  EXPECT_EQ(taken.crosser_tracked, 0);
  EXPECT_GE(kept.crosser_tracked, static_cast<int>(kept.stats.in_front) - 1);
  // Most of the person's own frames were ranged by the depth camera.
  EXPECT_GT(kept.stats.depth_ranged, kept.stats.detections / 2);
}

struct BehindScene {
  int walker_shown = 0;   ///< frames whose detection was the walker behind
  int walker_given = 0;   ///< ... given to the followed track
  int person_given = 0;   ///< frames whose detection was the person, given
  int person_frames = 0;  ///< frames whose detection was the person
  TargetEstimate estimate;
  TargetTaskStats stats;
};

/// The person stands 5 m ahead of the hovering drone; a walker crosses at 0.6 m/s 0.6 m behind them. Where the
/// walker's torso is beside the person's body in the image (0.3-0.45 m aside at the person's distance: the depth
/// camera's ray through it passes the person and ends on the walker) the crop shows the walker, torso read at the
/// person's distance; elsewhere the person.
BehindScene runBehind(const TargetTaskParams& params) {
  constexpr double kWalkerXM = kPersonXM + 0.6;
  constexpr double kWalkerSpeedMps = 0.6;
  constexpr double kCrossingS = 2.5;
  test::RangedRig ranged(params);
  auto& [detections, odometry, gimbal, out, task] = ranged.rig;
  auto& followed = ranged.followed;
  auto& depth = ranged.depth;
  BehindScene scene;
  const int frames = static_cast<int>(kDurationS * kRateHz);
  for (int i = 0; i <= frames; ++i) {
    const double t_s = i / kRateHz;
    const rt::TimeNs t_ns = rt::secondsToNs(t_s);
    test::pushHover(odometry, gimbal, t_ns);
    const double walker_y_m = kWalkerSpeedMps * (t_s - kCrossingS);
    depth.write(test::renderBodiesDepth(t_ns, {Eigen::Vector2d(kPersonXM, 0.0), Eigen::Vector2d(kWalkerXM, walker_y_m)},
                                        kBodyRadiusM));
    const double aside_m = std::abs(walker_y_m * kPersonXM / kWalkerXM);  // their column, at the person's distance
    const bool walker = aside_m >= 0.3 && aside_m <= 0.45;
    hal::DetectionFrame frame = test::emptyFrame(i, t_ns);
    frame.person_count = 1;
    test::drawPersonInColour(frame.persons[0], kPersonXM, walker ? walker_y_m * kPersonXM / kWalkerXM : 0.0, 3);
    frame.target_index = 0;
    detections.try_push(frame);
    task.step(t_ns + 1);
    (walker ? scene.walker_shown : scene.person_frames) += 1;
    const auto f = followed.read();
    if (!f || f->sequence != frame.sequence || f->target_index < 0) continue;
    (walker ? scene.walker_given : scene.person_given) += 1;
  }
  scene.estimate = aerotrack::test::require(out.read(), "an estimate");
  scene.stats = task.stats();
  return scene;
}

/// Without the rule (taken) the walker is given in every frame they are shown, and no frame is refused; with it
/// (kept) never: each such frame is counted, and the person is taken in every one of their frames.
void expectTakenThenKept(const BehindScene& taken, const BehindScene& kept) {
  ASSERT_GT(kept.walker_shown, 5);  // on both sides of the person, a few frames each
  EXPECT_EQ(taken.walker_given, taken.walker_shown);
  EXPECT_EQ(taken.stats.in_front, 0U);
  EXPECT_EQ(kept.walker_given, 0);
  EXPECT_EQ(kept.stats.in_front, static_cast<std::size_t>(kept.walker_shown));
  EXPECT_EQ(kept.person_given, kept.person_frames);
  ASSERT_TRUE(kept.estimate.initialised && !kept.estimate.lost);
  EXPECT_NEAR(kept.estimate.p_WT_m.x(), kPersonXM, 0.1);
  EXPECT_NEAR(kept.estimate.p_WT_m.y(), 0.0, 0.1);
}

TEST(TargetTaskInFront, GivenAWalkerRangedBehindThePersonBesideThem_WhenJudgedOnTheGate_ThenTheTrackDoesNotTakeThem) {
  const BehindScene taken = runBehind(test::rangedParams(kBodyRadiusM, 5, false));
  const BehindScene kept = runBehind(test::rangedParams(kBodyRadiusM, 5, true));
  // Nearer only: the walker's depth range fails the gate, and the regression's distance of them is given, every time.
  // On the gate: never.
  expectTakenThenKept(taken, kept);
}

TEST(TargetTaskInFront, GivenAWalkerBehindInsideTheGate_WhenTheBoundIsTheOwnRangesSpread_ThenTheTrackDoesNotTakeThem) {
  // A looser depth camera's noise model (0.2 m along the line of sight, 0.4 m across at 5 m): the walker 0.6 m
  // behind is ranged inside the gate's 16.3, and is given. The bound in_front_gate_chi2 = 5 (above the person's own
  // ranged d2 here, which the test checks: every one of their frames is still given) refuses them.
  TargetTaskParams loose = test::rangedParams(kBodyRadiusM, 5, true);
  loose.depth_range.range_std_m = 0.2;
  loose.depth_range.cross_std_per_m = 0.08;
  TargetTaskParams bound = loose;
  bound.in_front_gate_chi2 = 5.0;
  const BehindScene taken = runBehind(loose);
  const BehindScene kept = runBehind(bound);
  expectTakenThenKept(taken, kept);
}

TEST(TargetTaskInFront, GivenTheDepthCameraBlindBeforeACrossing_WhenTheStreakSpansIt_ThenTheRuleStaysArmed) {
  // Ranged for 1.5 s, then the depth camera sees nothing until just before the crosser hides the person (the person
  // outside its view): the regression's measurements are taken meanwhile. Ending the streak, they leave the rule
  // unarmed when the crosser comes, and the crosser is given; spanning them (the depth camera said nothing against
  // the track), it holds, and the crosser is not.
  constexpr double kCrossingS = 3.0;
  const DepthGap gap{1.5, kCrossingS - 0.3};
  const Scene ended = run(5, kCrossingS, gap, false);
  const Scene spanned = run(5, kCrossingS, gap, true);
  EXPECT_GT(ended.crosser_given, 0);
  EXPECT_EQ(spanned.crosser_given, 0);
  EXPECT_GE(spanned.stats.in_front, 5U);
  EXPECT_EQ(spanned.person_given_after, static_cast<int>(std::round((kDurationS - kCrossingS - 0.5) * kRateHz)));
  ASSERT_TRUE(spanned.estimate.initialised && !spanned.estimate.lost);
  EXPECT_NEAR(spanned.estimate.p_WT_m.x(), kPersonXM, 0.1);
  // in_front_unseen_limit: the 1.2 s unseen end the streak after all -- the track's distance is the regression's by
  // then -- and the two ranged frames before the crosser hides the person do not arm it again: the crosser is given
  // (the limit's price: someone else ranged first after a long gap is judged as the regression's, as a drifted
  // person must be)...
  const Scene limited = run(5, kCrossingS, gap, true, 2);
  EXPECT_GT(limited.crosser_given, 0);
  EXPECT_EQ(limited.stats.in_front, 0U);
  // ... while five agreeing ranges before the crossing arm it again, and the crosser is not.
  const Scene rearmed = run(5, kCrossingS, DepthGap{1.5, kCrossingS - 0.5}, true, 2);
  EXPECT_EQ(rearmed.crosser_given, 0);
  EXPECT_GE(rearmed.stats.in_front, 5U);
}

TEST(TargetTaskInFront, GivenTooFewRangesYet_ThenTheRegressionsDistanceIsStillGiven) {
  // The crosser hides the person from the fourth frame: the track has not yet been ranged five times in a row,
  // its distance is not known to agree with the depth camera's (a restart may have given it a wrong velocity),
  // and the regression's distance is given as before.
  const Scene early = run(5, 0.3);
  EXPECT_GT(early.crosser_given, 0);
}

struct WeaveScene {
  int person_given = 0;      ///< frames whose detection (always the person) the followed track took
  int tracked_as_other = 0;  ///< frames with a bystander track within 0.3 m of the person: a track on themselves
  TargetTaskStats stats;
};

/// The person alone, 5 m ahead of the hovering drone, weaving across the line of sight (0.5 m either way, a 2.5 s
/// period: up to 3.2 m/s^2 sideways), so the track's constant-velocity prediction errs, and their own ranged d2
/// spreads; the bound in_front_gate_chi2 = 0.8 refuses the tail of that spread, inside the estimator's gate (at 1 it
/// refused none of these frames).
WeaveScene runWeave(bool doubtful_starts_track) {
  TargetTaskParams params = test::rangedParams(kBodyRadiusM, 5, true);
  params.in_front_gate_chi2 = 0.8;
  params.in_front_doubtful_starts_track = doubtful_starts_track;
  test::RangedRig ranged(params);
  auto& [detections, odometry, gimbal, out, task] = ranged.rig;
  auto& followed = ranged.followed;
  auto& depth = ranged.depth;
  WeaveScene scene;
  const int frames = static_cast<int>(kDurationS * kRateHz);
  for (int i = 0; i <= frames; ++i) {
    const double t_s = i / kRateHz;
    const rt::TimeNs t_ns = rt::secondsToNs(t_s);
    test::pushHover(odometry, gimbal, t_ns);
    const double y_m = 0.5 * std::sin(2.0 * M_PI * t_s / 2.5);
    depth.write(test::renderBodiesDepth(t_ns, {Eigen::Vector2d(kPersonXM, y_m)}, kBodyRadiusM));
    hal::DetectionFrame frame = test::emptyFrame(i, t_ns);
    frame.person_count = 1;
    test::drawPersonInColour(frame.persons[0], kPersonXM, y_m, 3);
    frame.target_index = 0;
    detections.try_push(frame);
    task.step(t_ns + 1);
    const TargetEstimate e = aerotrack::test::require(out.read(), "an estimate");
    for (std::size_t k = 0; k < e.other_count; ++k)
      if ((e.others[k].p_W_m.head<2>() - Eigen::Vector2d(kPersonXM, y_m)).norm() < 0.3) {
        ++scene.tracked_as_other;
        break;
      }
    const auto f = followed.read();
    if (f && f->sequence == frame.sequence && f->target_index >= 0) ++scene.person_given;
  }
  scene.stats = task.stats();
  return scene;
}

TEST(TargetTaskInFront, GivenThePersonsOwnFramesRefusedByTheBound_WhenDoubtStartsNoTrack_ThenNoneIsStartedOnThem) {
  const WeaveScene started = runWeave(true);
  const WeaveScene not_started = runWeave(false);
  // The bound refuses the person's own frames either way (and the track, starved, drifts: the cost of a bound
  // below the person's own spread, which the option does not remove). Started, a bystander track then holds the
  // person in most frames; not started, never, and the followed track is given as many of their frames.
  ASSERT_GT(started.stats.in_front, 10U);
  EXPECT_EQ(not_started.stats.in_front, started.stats.in_front);
  EXPECT_GT(started.tracked_as_other, 10);
  EXPECT_EQ(not_started.tracked_as_other, 0);
  EXPECT_GE(not_started.person_given, started.person_given);
}

}  // namespace
}  // namespace in_front_test
}  // namespace aerotrack::estimation
