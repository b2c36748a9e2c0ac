// A bearing goes to whichever track it is likelier on (bearing_by_likelihood, issue 22 item 2). Against ground
// truth: the person stands 5 m ahead of a hovering drone; a bystander in the same clothes walks across 3 m ahead at
// 1 m/s, both seen whole for a second, the bystander on a track of their own, every detection scattered as the
// network's. Then the network misses the person, who is about to be hidden: for 0.6 s it finds only the bystander,
// whole (their track fed, the followed track starving), then for 0.4 s with their hips cut off (a bearing) as they
// pass in front of the person. A bearing is placed at the followed track's predicted range, so where the bystander's
// line of sight crosses the person's place it fits the starved followed track's wide gate as closely as the
// bystander's own (traced: image-mode crowd seed 19, taken at d2 0.00, the bystander's track 0.02 m from that line).
// Over seeded draws, without the rule some of these bearings are given to the followed track, with it none; and with
// the bystander walking 3 m to the side, the person's own bearings are taken as without it.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include "aerotrack/estimation/target_task.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "support/require.hpp"
#include "target_task_test_util.hpp"

namespace aerotrack::estimation {
namespace bearing_ambiguity_test {
namespace {

constexpr double kRateHz = test::kFrameRateHz;
constexpr double kPersonXM = 5.0;
constexpr double kOtherXM = 3.0;            ///< the bystander's walk across, in front of the person...
constexpr double kOtherStartYM = 1.9;       ///< ... from here...
constexpr double kOtherSpeedMps = -1.0;     ///< ... at this speed: in front of the person at 1.9 s
constexpr double kOtherAsideYM = 3.0;       ///< or, beside: their walk 3 m to the side
constexpr int kColour = 3;                  ///< both dressed alike: colour tells nobody apart
constexpr double kRangeScatter = 0.05;      ///< the network's scatter: a fraction of the range...
constexpr double kAcrossScatterRad = 0.01;  ///< ... and across the line of sight (about 3 px)
constexpr double kLockS = 1.0;              ///< both seen whole
constexpr double kMissS = 0.6;              ///< the person missed, the bystander seen whole
constexpr double kCutS = 0.4;               ///< the person missed, one cut-off torso in the frame
constexpr int kDraws = 20;

struct Scene {
  int given = 0;  ///< frames with a cut-off torso whose bearing went to the followed track
  TargetTaskStats stats;
};

/// One draw. The cut-off torso is the bystander's crossing in front of the person, or (own_bearing) the person's,
/// the bystander walking 3 m to the side.
Scene run(bool by_likelihood, bool own_bearing, std::uint64_t seed) {
  TargetTaskParams params;
  params.localization = test::pinholeLocalization();
  params.bearing_by_likelihood = by_likelihood;
  rt::LatestSlot<hal::DetectionFrame> followed;
  test::TaskRig rig(params);
  auto& [detections, odometry, gimbal, out, task] = rig;
  task.publishFollowedTo(followed);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  // Where the network puts someone at (x, y): their range and their angle scattered.
  const auto scattered = [&](double x_m, double y_m) {
    const double range = x_m * (1.0 + kRangeScatter * normal(rng));
    const double angle = y_m / x_m + kAcrossScatterRad * normal(rng);
    return Eigen::Vector2d(range, range * angle);
  };
  Scene scene;
  const int frames = static_cast<int>((kLockS + kMissS + kCutS) * kRateHz);
  for (int i = 0; i < frames; ++i) {
    const double t_s = i / kRateHz;
    const rt::TimeNs t_ns = rt::secondsToNs(t_s);
    test::pushHover(odometry, gimbal, t_ns);
    const Eigen::Vector2d other_m = own_bearing ? Eigen::Vector2d(kOtherXM, kOtherAsideYM + kOtherSpeedMps * t_s)
                                                : Eigen::Vector2d(kOtherXM, kOtherStartYM + kOtherSpeedMps * t_s);
    const bool cut = t_s >= kLockS + kMissS;
    hal::DetectionFrame frame = test::emptyFrame(i, t_ns);
    if (t_s < kLockS) {
      frame.person_count = 2;
      const Eigen::Vector2d person = scattered(kPersonXM, 0.0);
      const Eigen::Vector2d other = scattered(other_m.x(), other_m.y());
      test::drawPersonInColour(frame.persons[0], person.x(), person.y(), kColour);
      test::drawPersonInColour(frame.persons[1], other.x(), other.y(), kColour);
      frame.target_index = 0;
    } else if (!cut) {
      frame.person_count = 1;
      const Eigen::Vector2d other = scattered(other_m.x(), other_m.y());
      test::drawPersonInColour(frame.persons[0], other.x(), other.y(), kColour);
    } else {
      frame.person_count = 1;
      // A cut-off torso: its line of sight only (drawn at the person's range on it).
      const Eigen::Vector2d seen = own_bearing ? scattered(kPersonXM, 0.0) : scattered(other_m.x(), other_m.y());
      test::drawPersonInColour(frame.persons[0], kPersonXM, seen.y() * kPersonXM / seen.x(), kColour, true);
    }
    detections.try_push(frame);
    task.step(t_ns + 1);
    const auto f = followed.read();
    if (cut && f && f->sequence == frame.sequence && f->target_index >= 0) ++scene.given;
  }
  scene.stats = task.stats();
  return scene;
}

TEST(TargetTaskBearingAmbiguity, GivenABystandersBearingCrossingThePersonsPlace_WhenByLikelihood_ThenItIsNeverTaken) {
  int given_by_distance = 0;
  int given_by_likelihood = 0;
  for (int d = 0; d < kDraws; ++d) {
    given_by_distance += run(false, false, static_cast<std::uint64_t>(d)).given;
    given_by_likelihood += run(true, false, static_cast<std::uint64_t>(d)).given;
  }
  // By the distances alone the starved followed track takes some of them.
  EXPECT_GT(given_by_distance, 0);
  EXPECT_EQ(given_by_likelihood, 0);
}

TEST(TargetTaskBearingAmbiguity,
     GivenThePersonsOwnBearingWithTheBystanderAside_WhenByLikelihood_ThenItIsTakenAsBefore) {
  for (int d = 0; d < kDraws; ++d) {
    const Scene by_distance = run(false, true, static_cast<std::uint64_t>(d));
    const Scene by_likelihood = run(true, true, static_cast<std::uint64_t>(d));
    EXPECT_GT(by_distance.given, 0) << "draw " << d;
    EXPECT_EQ(by_likelihood.given, by_distance.given) << "draw " << d;
    EXPECT_EQ(by_likelihood.stats.bearings, by_distance.stats.bearings) << "draw " << d;
  }
}

}  // namespace
}  // namespace bearing_ambiguity_test
}  // namespace aerotrack::estimation
