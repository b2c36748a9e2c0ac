// Which detected person the target task gives the estimator (issue 22 item 2): with `association:
// estimate` the person nearest the live track's prediction, whoever the lock-on chose, and nobody when
// nobody is near it. Against ground
// truth: the followed person walks across in front of a hovering drone while a look-alike stands 1.5 m
// beside their path; for one second the lock-on (judging in the image) swaps to the look-alike. Taking
// the lock-on's choice, the estimator refuses the jump, then restarts on the look-alike; choosing by the
// estimate, it stays on the person. And a passer-by in another colour inside the position gate does not
// take a half-hidden person's place.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "aerotrack/estimation/target_task.hpp"
#include "support/require.hpp"
#include "target_task_test_util.hpp"

namespace aerotrack::estimation {
namespace association_test {
namespace {

constexpr double kFx = test::kFocalPx;
constexpr int kW = test::kWidthPx;
constexpr int kH = test::kHeightPx;
constexpr double kRateHz = test::kFrameRateHz;

// A person at (x forward, y left) of a level camera at the origin along W x, in one colour; `cut`: the hips
// guessed on the bottom rows (no distance).
using test::drawPersonInColour;

using test::emptyFrame;

struct Scene {
  TargetEstimate estimate;
  TargetTaskStats stats;
  int followed_last = -2;   ///< target_index of the last frame published as followed
  int followed_person = 0;  ///< frames published with the person (index 0) as followed
  /// Frames handed back with nobody taken and a prediction of the person's torso (predicted_torso), the largest
  /// distance of its centre from the person's true column, and the sizes it gave; frames that took someone
  /// and still carried a prediction.
  int predicted = 0;
  double worst_predicted_u_px = 0.0;
  double min_predicted_torso_px = 1e9, max_predicted_torso_px = 0.0;
  int predicted_with_someone = 0;
};

constexpr double kLookAlikeY = 1.5;
constexpr int kPersonColour = 3;
constexpr int kOtherColour = 20;

/// What happens from 1.5 to 2.5 s.
enum class Event {
  kSwap,     ///< the lock-on takes the look-alike (same colour, 1.5 m beside the path); the person in view
  kHide,     ///< the person is out of view; the lock-on takes the look-alike
  kPasserBy  ///< the person half hidden (no distance), a passer-by in another colour 0.3 m in front; the
             ///< lock-on keeps the person
};
double personY(double t_s) {
  return -1.0 + 0.5 * t_s;
}  // walks left at 0.5 m/s, 5 m ahead

/// end_s at 30 Hz. Person 0 is the followed one, person 1 the look-alike at (5, 1.5) (or the passer-by).
Scene run(bool choose_by_estimate, Event event, double end_s = 4.0) {
  TargetTaskParams params;
  params.localization = test::pinholeLocalization();
  params.choose_by_estimate = choose_by_estimate;
  rt::LatestSlot<hal::DetectionFrame> followed;
  test::TaskRig rig(params);
  auto& [detections, odometry, gimbal, out, task] = rig;
  task.publishFollowedTo(followed);
  Scene scene;
  const int frames = static_cast<int>(end_s * kRateHz);
  for (int i = 0; i <= frames; ++i) {
    const double t_s = i / kRateHz;
    const rt::TimeNs t_ns = rt::secondsToNs(t_s);
    test::pushHover(odometry, gimbal, t_ns);
    const bool during = t_s >= 1.5 && t_s < 2.5;
    const bool swapped = during && event != Event::kPasserBy;
    const bool hide_person = event == Event::kHide;
    hal::DetectionFrame frame = emptyFrame(i, t_ns);
    if (swapped && hide_person) {
      frame.person_count = 1;
      drawPersonInColour(frame.persons[0], 5.0, kLookAlikeY, kPersonColour);  // only the look-alike, listed first
      frame.target_index = 0;
    } else if (during && event == Event::kPasserBy) {
      frame.person_count = 2;
      drawPersonInColour(frame.persons[0], 5.0, personY(t_s), kPersonColour, true);
      drawPersonInColour(frame.persons[1], 4.7, personY(t_s), kOtherColour);
      frame.target_index = 0;
    } else {
      frame.person_count = 2;
      drawPersonInColour(frame.persons[0], 5.0, personY(t_s), kPersonColour);
      drawPersonInColour(frame.persons[1], 5.0, kLookAlikeY, kPersonColour);
      frame.target_index = swapped ? 1 : 0;
    }
    detections.try_push(frame);
    task.step(t_ns + 1);
    if (const auto f = followed.read(); f && f->sequence == frame.sequence) {
      scene.followed_last = f->target_index;
      const bool is_person = !(swapped && hide_person) && f->target_index == 0;
      if (is_person) ++scene.followed_person;
      const hal::DetectionFrame::PredictedTorso& p = f->predicted_torso;
      if (p.torso_px > 0.0 && f->target_index >= 0) ++scene.predicted_with_someone;
      if (p.torso_px > 0.0 && f->target_index < 0) {
        ++scene.predicted;
        const double true_u_px = 0.5 * kW - kFx * personY(t_s) / 5.0;
        scene.worst_predicted_u_px = std::max(scene.worst_predicted_u_px, std::abs(p.u_px - true_u_px));
        scene.min_predicted_torso_px = std::min(scene.min_predicted_torso_px, p.torso_px);
        scene.max_predicted_torso_px = std::max(scene.max_predicted_torso_px, p.torso_px);
        // The torso centre 1.1 m above the ground (the default), seen from a camera on the ground 5 m away.
        EXPECT_NEAR(p.v_px, 0.5 * kH - kFx * 1.1 / 5.0, 3.0);
      }
    }
  }
  scene.estimate = aerotrack::test::require(out.read(), "an estimate");
  scene.stats = task.stats();
  return scene;
}

TEST(TargetTaskAssociation, GivenTheLockOnSwapsToALookAlike_WhenChoosingByTheEstimate_ThenTheTrackStaysOnThePerson) {
  const Scene by_estimate = run(true, Event::kSwap);
  const Scene by_lock_on = run(false, Event::kSwap);
  ASSERT_TRUE(by_estimate.estimate.initialised && !by_estimate.estimate.lost);
  // Truth at 4 s: (5, 1.0), 0.5 m from the look-alike.
  EXPECT_NEAR(by_estimate.estimate.p_WT_m.y(), personY(4.0), 0.15);
  EXPECT_EQ(by_estimate.stats.reassigned, 30U) << "every swapped frame given back to the person";
  EXPECT_EQ(by_estimate.stats.rejected, 0U);
  EXPECT_EQ(by_estimate.followed_person, 121) << "the followed slot names the person in every frame";
  // The lock-on's choice: 8 refusals, then the filter restarts on the look-alike and follows it until the
  // lock-on comes back, and the jump back is refused in turn.
  EXPECT_EQ(by_lock_on.stats.reassigned, 0U);
  EXPECT_GE(by_lock_on.stats.rejected, 8U);
  EXPECT_EQ(by_lock_on.followed_person, 91);
}

TEST(TargetTaskAssociation,
     GivenOnlyALookAlikeInView_WhenTheTrackTakesNobody_ThenEachVerdictSaysWhereThePersonShouldBeInTheImage) {
  // The detector's crop looks where the live track predicts the person (issue 22, item 2): the verdicts that
  // took nobody carry the prediction's torso in the frame's image; those that took the person carry none.
  const Scene hidden = run(true, Event::kHide);
  EXPECT_EQ(hidden.predicted, 30) << "every frame of the hiding (1.5 to 2.5 s at 30 Hz)";
  EXPECT_EQ(hidden.predicted_with_someone, 0);
  // The coasting track's own error (0.15 m at 5 m) is 10 px; the torso 0.5 m at 5 m is 33.7 px.
  EXPECT_LT(hidden.worst_predicted_u_px, 12.0);
  EXPECT_NEAR(hidden.min_predicted_torso_px, kFx * 0.5 / 5.0, 1.0);
  EXPECT_NEAR(hidden.max_predicted_torso_px, kFx * 0.5 / 5.0, 1.0);
  const Scene swapped = run(true, Event::kSwap);
  EXPECT_EQ(swapped.predicted + swapped.predicted_with_someone, 0) << "the person taken in every frame";
}

TEST(TargetTaskAssociation,
     GivenOnlyALookAlikeInView_WhenChoosingByTheEstimate_ThenTheTrackCoastsAndTakesThePersonBack) {
  // Nobody within the gate while the person is hidden: nobody is given to the estimator and the track coasts
  // on the person's walk. The lock-on's choice, given as before (`association: lock_on`), is refused 7 times
  // and the 8th restarts the filter on the look-alike (the restart rule), 0.27 s into the hiding.
  const Scene coasting = run(true, Event::kHide, 2.1);
  EXPECT_EQ(coasting.stats.rejected, 0U);
  EXPECT_EQ(coasting.followed_last, -1) << "nobody given while hidden";
  EXPECT_NEAR(coasting.estimate.p_WT_m.y(), personY(2.1), 0.15);
  const Scene by_lock_on = run(false, Event::kHide, 2.1);
  EXPECT_EQ(by_lock_on.stats.rejected, 7U);
  EXPECT_NEAR(by_lock_on.estimate.p_WT_m.y(), kLookAlikeY, 0.2);
  // The coasting track's gate grows with its covariance (where a walker can have gone): 0.7 s into the hiding
  // it holds the look-alike standing 1.25 m beside the predicted path. The look-alike's own track (tracked
  // beside the person since the start) explains them better, and the person's track coasts on.
  const Scene late = run(true, Event::kHide, 2.45);
  EXPECT_EQ(late.followed_last, -1);
  EXPECT_NEAR(late.estimate.p_WT_m.y(), personY(2.45), 0.15);
  // Reappearing, the person is taken back.
  const Scene after = run(true, Event::kHide);
  ASSERT_TRUE(after.estimate.initialised && !after.estimate.lost);
  EXPECT_EQ(after.followed_last, 0);
  EXPECT_NEAR(after.estimate.p_WT_m.y(), personY(4.0), 0.15);
}

TEST(TargetTaskAssociation,
     GivenAPasserByInAnotherColourInTheGate_WhenThePersonIsHalfHidden_ThenTheLockOnsChoiceStands) {
  // The crossing scenario's case: the passer-by has a distance and is inside the position gate, the person
  // (half hidden) has none; the colour the task has learnt refuses the passer-by, so the person's bearing
  // goes on to the estimator.
  const Scene by_estimate = run(true, Event::kPasserBy);
  EXPECT_EQ(by_estimate.stats.reassigned, 0U);
  EXPECT_EQ(by_estimate.stats.unreliable, 30U);
  EXPECT_EQ(by_estimate.followed_person, 121);
  EXPECT_NEAR(by_estimate.estimate.p_WT_m.y(), personY(4.0), 0.15);
}

/// The person walks as in run(). From 1.5 s either (kNewcomer) they are hidden and a newcomer dressed almost
/// like them (a colour within the colour gate) appears 0.3 m beside where they would be, with a distance, and
/// walks towards the drone at 1.2 m/s, seen only while the person is hidden (so no track of their own); or
/// (kNewLook) the person stays in view and their look changes as much (a turn, the light). The person's own
/// signatures carry a little noise. Returns the frames from 1.5 s given to the estimator, and the estimate.
enum class LookEvent { kNewcomer, kNewLook };
struct LookScene {
  int given_after = 0;
  TargetEstimate estimate;
};
LookScene runLook(LookEvent event, double look_gate_sigmas, double end_s = 2.5) {
  TargetTaskParams params;
  params.localization = test::pinholeLocalization();
  params.look_gate_sigmas = look_gate_sigmas;
  rt::LatestSlot<hal::DetectionFrame> followed;
  test::TaskRig rig(params);
  auto& [detections, odometry, gimbal, out, task] = rig;
  task.publishFollowedTo(followed);
  LookScene scene;
  const int frames = static_cast<int>(end_s * kRateHz);
  for (int i = 0; i < frames; ++i) {
    const double t_s = i / kRateHz;
    const rt::TimeNs t_ns = rt::secondsToNs(t_s);
    test::pushHover(odometry, gimbal, t_ns);
    const bool after = t_s >= 1.5;
    hal::DetectionFrame frame = emptyFrame(i, t_ns);
    frame.person_count = 1;
    frame.target_index = i == 0 ? 0 : -1;  // designated in the first frame only
    hal::PersonDetection& p = frame.persons[0];
    if (!after) {
      drawPersonInColour(p, 5.0, personY(t_s), kPersonColour);
      const float noise = 0.02F * static_cast<float>(i % 3);  // the person's own frames differ a little
      p.appearance[kPersonColour] = 1.0F - noise;
      p.appearance[kPersonColour + 1] = noise;
    } else {
      if (event == LookEvent::kNewcomer)
        drawPersonInColour(p, 5.0 - 1.2 * (t_s - 1.5), personY(t_s) + 0.3, kPersonColour);
      else
        drawPersonInColour(p, 5.0, personY(t_s), kPersonColour);
      p.appearance[kPersonColour] = 0.7F;  // distance 0.41 to the person's colour: inside the colour gate (0.45)
      p.appearance[kPersonColour + 2] = 0.3F;
    }
    detections.try_push(frame);
    task.step(t_ns + 1);
    if (const auto f = followed.read(); after && f && f->sequence == frame.sequence && f->target_index == 0)
      ++scene.given_after;
  }
  scene.estimate = aerotrack::test::require(out.read(), "an estimate");
  return scene;
}

TEST(TargetTaskAssociation,
     GivenANewcomerAlmostLikeTheHiddenPersonInTheGate_WhenTheirColourIsFartherThanThePersonsOwn_ThenTheyAreRefused) {
  // Crowd seed 2 (keypoint mode): a newcomer in similar clothes beside the hidden person, inside the motion and
  // colour gates, took the track for good. The person's own colour distances (0.00-0.05) tell the newcomer's
  // 0.41 apart, and by the time the look gate's confirmation (0.5 s) would give in, the newcomer has walked out
  // of the track's motion gate: the track coasts on the person's walk.
  const LookScene gated = runLook(LookEvent::kNewcomer, 3.0);
  EXPECT_EQ(gated.given_after, 0);
  EXPECT_NEAR(gated.estimate.p_WT_m.y(), personY(2.5), 0.15);
  EXPECT_NEAR(gated.estimate.p_WT_m.x(), 5.0, 0.15);
  // Without the look gate the newcomer is taken and pulls the track towards the drone.
  const LookScene colour_gate_only = runLook(LookEvent::kNewcomer, 0.0);
  EXPECT_GE(colour_gate_only.given_after, 5);
  EXPECT_LT(colour_gate_only.estimate.p_WT_m.x(), 4.8);
}

TEST(TargetTaskAssociation,
     GivenThePersonsLookChanges_WhenTheyStayInTheGate_ThenTheyAreTakenAgainAfterTheConfirmation) {
  // The look gate learns only from the frames it lets through; without the confirmation, a person whose look
  // changed for good (image mode: a turn, the light) would be shut out (measured: sharp_turn in image mode lost
  // 85 % of its measurements). Refused in every frame for look_gate_confirm_s (0.5 s, 15 frames), then taken.
  const LookScene changed = runLook(LookEvent::kNewLook, 3.0, 3.0);
  EXPECT_GE(changed.given_after, 45 - 16);
  EXPECT_LE(changed.given_after, 45 - 14);
  EXPECT_FALSE(changed.estimate.lost);
  EXPECT_NEAR(changed.estimate.p_WT_m.y(), personY(3.0), 0.15);
}

}  // namespace
}  // namespace association_test
}  // namespace aerotrack::estimation
