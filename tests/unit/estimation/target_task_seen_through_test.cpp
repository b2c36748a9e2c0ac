// A bearing the depth camera sees through is not the followed person (depth_vets_bearings, issue 22 item 2).
// Against ground truth: the person stands 5 m ahead of a hovering drone, measured for a second; then, for half a
// second, the network misses them and returns someone else on nearly the same line of sight, their torso cut off
// (a bearing, bearing_fallback): either a look-alike 2.5 m in front of the person, hiding them (traced: image-mode
// crowd seed 9 flown from the truth, depth 1.3 m against 2.4 m predicted), or a walker 7 m behind them whose line
// of sight passes beside the person's body (seed 100 in closed loop: no surface within 8 m). The depth camera,
// rendered from the bodies and a wall 20 m away, sees the one in front, or past the person's place. The
// measurements scatter as the network's do (the followed track's gate as wide as in image mode).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "aerotrack/estimation/target_task.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "support/require.hpp"
#include "target_task_depth_util.hpp"
#include "target_task_test_util.hpp"

namespace aerotrack::estimation {
namespace seen_through_test {
namespace {

constexpr double kRateHz = test::kFrameRateHz;
constexpr double kBodyRadiusM = 0.25;
constexpr double kPersonXM = 5.0;
constexpr double kWallXM = 20.0;
constexpr double kInFrontXM = 2.5;          ///< the look-alike in front, on the person's line of sight
constexpr double kBehindXM = 12.0;          ///< the walker behind...
constexpr double kBehindAsideM = 0.4;       ///< ... whose line of sight passes this far from the person's centre
constexpr int kMissedFrames = 15;           ///< the network misses the person this long
constexpr double kNetworkNoiseStdM = 0.01;  // config/localization_image.yaml: 0.27 m at 5 m
constexpr double kNetworkNoiseStdPerM = 0.05;

struct Scene {
  int other_given = 0;         ///< missed frames whose followed person was the other one
  int person_given_after = 0;  ///< frames after the miss whose followed person was the person
  int frames_after = 0;
  TargetEstimate estimate;
  TargetTaskStats stats;
};

Scene run(bool depth_vets_bearings, bool in_front) {
  TargetTaskParams params;
  params.localization = test::pinholeLocalization();
  params.localization.noise_std_m = kNetworkNoiseStdM;
  params.localization.noise_std_per_m = kNetworkNoiseStdPerM;
  params.depth_range.enabled = true;
  params.depth_range.body_offset_m = kBodyRadiusM;
  params.depth_vets_bearings = depth_vets_bearings;
  rt::LatestSlot<hal::DetectionFrame> followed;
  rt::SharedSlot<hal::DepthFrame> depth;
  test::TaskRig rig(params);
  auto& [detections, odometry, gimbal, out, task] = rig;
  task.publishFollowedTo(followed);
  task.rangeFrom(depth);
  // The other one: in front on the person's line of sight, or behind on a line passing beside them.
  const Eigen::Vector2d other_m =
      in_front ? Eigen::Vector2d(kInFrontXM, 0.0) : Eigen::Vector2d(kBehindXM, kBehindAsideM * kBehindXM / kPersonXM);
  const Eigen::Vector2d person_m(kPersonXM, 0.0);
  Scene scene;
  const int lock_frames = static_cast<int>(kRateHz);
  const int after_frames = 15;
  for (int i = 0; i <= lock_frames + kMissedFrames + after_frames; ++i) {
    const rt::TimeNs t_ns = rt::secondsToNs(i / kRateHz);
    test::pushHover(odometry, gimbal, t_ns);
    const bool missed = i > lock_frames && i <= lock_frames + kMissedFrames;
    const bool after = i > lock_frames + kMissedFrames;
    std::vector<Eigen::Vector2d> bodies{person_m};
    if (missed || !in_front) bodies.push_back(other_m);
    depth.write(test::renderBodiesDepth(t_ns, bodies, kBodyRadiusM, kWallXM));
    hal::DetectionFrame frame = test::emptyFrame(i, t_ns);
    frame.person_count = 1;
    if (missed) {  // the other one, cut off at the waist: a bearing (drawn at the person's distance, on their line)
      const double y_m = other_m.y() * kPersonXM / other_m.x();
      test::drawPersonInColour(frame.persons[0], kPersonXM, y_m, 3, true);
    } else {
      test::drawPersonInColour(frame.persons[0], kPersonXM, 0.0, 3);
    }
    frame.target_index = 0;
    detections.try_push(frame);
    task.step(t_ns + 1);
    scene.frames_after += after ? 1 : 0;
    const auto f = followed.read();
    if (!f || f->sequence != frame.sequence || f->target_index < 0) continue;
    if (missed) ++scene.other_given;
    if (after) ++scene.person_given_after;
  }
  scene.estimate = aerotrack::test::require(out.read(), "an estimate");
  scene.stats = task.stats();
  return scene;
}

void expectKeptOnThePerson(bool in_front) {
  const Scene taken = run(false, in_front);
  const Scene kept = run(true, in_front);
  // Without the rule the bearing is given: it fits the prediction at any range.
  EXPECT_GT(taken.other_given, 0);
  EXPECT_GT(taken.stats.bearings, 0U);
  EXPECT_EQ(taken.stats.seen_through, 0U);
  // With it, never: each such frame is counted, the person is taken in every frame after, the estimate on them.
  EXPECT_EQ(kept.other_given, 0);
  EXPECT_EQ(kept.stats.bearings, 0U);
  EXPECT_EQ(kept.stats.seen_through, static_cast<std::uint64_t>(taken.other_given));
  EXPECT_EQ(kept.person_given_after, kept.frames_after);
  ASSERT_TRUE(kept.estimate.initialised && !kept.estimate.lost);
  EXPECT_NEAR(kept.estimate.p_WT_m.x(), kPersonXM, 0.1);
  EXPECT_NEAR(kept.estimate.p_WT_m.y(), 0.0, 0.1);
}

TEST(TargetTaskSeenThrough, GivenABearingOfSomeoneInFrontHidingThePerson_ThenItIsNotTheirs) {
  expectKeptOnThePerson(true);
}

TEST(TargetTaskSeenThrough, GivenABearingOfSomeoneFarBehindBesideThePerson_ThenItIsNotTheirs) {
  expectKeptOnThePerson(false);
}

}  // namespace
}  // namespace seen_through_test
}  // namespace aerotrack::estimation
