// Someone the look gate refuses for the live followed track, fitting it better than any bystander track, stays off
// the bystander tracks (look_refused_off_tracks, issue 22 item 2). Against ground truth: the person stands 5 m ahead
// of a hovering drone beside a look-alike 0.6 m to their left, both seen for a second (the look-alike on a
// bystander track); then the look-alike is hidden and the person turns (a look inside the colour gate, outside
// their own spread) for a few frames. As traced in the image-mode crowd in closed loop (seed 66): the turned person
// was given the look-alike's track, which left the look-alike to a new track never seen beside the person.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "aerotrack/estimation/target_task.hpp"
#include "support/require.hpp"
#include "target_task_test_util.hpp"

namespace aerotrack::estimation {
namespace look_off_tracks_test {
namespace {

constexpr double kRateHz = test::kFrameRateHz;
constexpr double kPersonXM = 5.0;
constexpr double kLookAlikeYM = 0.6;
constexpr int kBesideFrames = static_cast<int>(kRateHz);
constexpr int kTurnedFrames = 8;  ///< fewer than look_gate_confirm_s (0.5 s) confirms the turned look in
constexpr int kColourBin = 3;

struct Scene {
  double track_y_m = std::numeric_limits<double>::quiet_NaN();  ///< the bystander track nearest the look-alike
  int person_given = 0;                                         ///< turned frames given to the followed track
  TargetTaskStats stats;
};

Scene run(bool look_refused_off_tracks) {
  TargetTaskParams params;
  params.localization = test::pinholeLocalization();
  params.look_refused_off_tracks = look_refused_off_tracks;
  test::FollowedRig rig(params);
  auto& [detections, odometry, gimbal, out, task] = rig.rig;
  Scene scene;
  for (int i = 0; i < kBesideFrames + kTurnedFrames; ++i) {
    const rt::TimeNs t_ns = rt::secondsToNs(i / kRateHz);
    test::pushHover(odometry, gimbal, t_ns);
    hal::DetectionFrame frame = test::emptyFrame(i, t_ns);
    hal::PersonDetection& p = frame.persons[frame.person_count++];
    test::drawPersonInColour(p, kPersonXM, 0.0, kColourBin);
    const bool turned = i >= kBesideFrames;
    if (!turned) {
      const float noise = 0.02F * static_cast<float>(i % 3);  // the person's own frames differ a little
      p.appearance[kColourBin] = 1.0F - noise;
      p.appearance[kColourBin + 1] = noise;
      test::drawPersonInColour(frame.persons[frame.person_count++], kPersonXM, kLookAlikeYM, kColourBin);
    } else {
      p.appearance[kColourBin] = 0.7F;  // turned: 0.41 from the learnt colour, inside the colour gate
      p.appearance[kColourBin + 2] = 0.3F;
    }
    frame.target_index = i == 0 ? 0 : -1;  // designated in the first frame only
    detections.try_push(frame);
    task.step(t_ns + 1);
    const auto f = rig.followed.read();
    if (turned && f && f->sequence == frame.sequence && f->target_index == 0) ++scene.person_given;
  }
  const TargetEstimate e = aerotrack::test::require(out.read(), "an estimate");
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < e.other_count; ++k) {
    const double y_m = e.others[k].p_W_m.y();
    if (std::abs(y_m - kLookAlikeYM) < std::abs(nearest - kLookAlikeYM)) nearest = y_m;
  }
  scene.track_y_m = nearest;
  scene.stats = task.stats();
  return scene;
}

TEST(TargetTaskLookOffTracks, GivenThePersonTurnedBesideAHiddenLookAlikesTrack_ThenTheTrackStaysTheLookAlikes) {
  const Scene off = run(false);
  const Scene on = run(true);
  // Refused by the look gate either way: the followed track coasts on the person's place.
  EXPECT_EQ(off.person_given, 0);
  EXPECT_EQ(on.person_given, 0);
  // Without the rule the look-alike's track takes the turned person and is pulled onto them.
  EXPECT_LT(off.track_y_m, 0.5 * kLookAlikeYM);
  EXPECT_EQ(off.stats.look_refused_kept_off, 0U);
  // With it, the track coasts where the look-alike stands.
  EXPECT_NEAR(on.track_y_m, kLookAlikeYM, 0.1);
  EXPECT_EQ(on.stats.look_refused_kept_off, static_cast<std::uint64_t>(kTurnedFrames));
}

}  // namespace
}  // namespace look_off_tracks_test
}  // namespace aerotrack::estimation
