// Unit tests of the lock-on for detection-delivering cameras (keypoint_lock_on.hpp): the followed
// person is kept whatever order the device lists people in, the appearance signature is what tells a
// bystander from the target after a loss, a designated target is learnt and then followed, and a
// malformed signature is no appearance at all.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "aerotrack/perception/keypoint_lock_on.hpp"

namespace aerotrack::perception {
namespace {

using hal::CocoKeypoint;
using hal::index;

constexpr rt::TimeNs kLockOnFrameNs = rt::kNsPerSecond / 30;

/// An upright person seen from the front: torso centred at u_px, torso_px long, all joints scored.
hal::PersonDetection uprightDetection(double u_px, double torso_px, int shirt_bin, double score = 0.8) {
  hal::PersonDetection d;
  const double neck_v = 240.0 - 0.5 * torso_px, hip_v = 240.0 + 0.5 * torso_px, half_width = 0.3 * torso_px;
  for (auto& k : d.keypoints) k = {u_px, 240.0, score};
  d.keypoints[index(CocoKeypoint::kLeftShoulder)] = {u_px + half_width, neck_v, score};
  d.keypoints[index(CocoKeypoint::kRightShoulder)] = {u_px - half_width, neck_v, score};
  d.keypoints[index(CocoKeypoint::kLeftHip)] = {u_px + 0.7 * half_width, hip_v, score};
  d.keypoints[index(CocoKeypoint::kRightHip)] = {u_px - 0.7 * half_width, hip_v, score};
  d.score = score;
  if (shirt_bin >= 0) {
    d.appearance[static_cast<std::size_t>(shirt_bin)] = 1.0F;
    d.has_appearance = true;
  }
  return d;
}

hal::DetectionFrame frameOf(rt::TimeNs stamp_ns, std::initializer_list<hal::PersonDetection> persons) {
  hal::DetectionFrame f;
  f.stamp_ns = stamp_ns;
  f.intrinsics.width_px = 640;
  f.intrinsics.height_px = 480;
  for (const auto& p : persons) f.persons[f.person_count++] = p;
  f.target_index = -1;
  return f;
}

TEST(KeypointLockOn, GivenPeopleListedInAShuffledOrder_WhenTheTargetIsLocked_ThenItIsFollowedInEveryFrame) {
  KeypointLockOn lock_on(TrackerParams{}, TorsoFeatureParams{});
  for (int i = 0; i < 60; ++i) {
    const double target_u = 300.0 + 1.0 * i, bystander_u = 450.0 - 2.0 * i;
    const auto target = uprightDetection(target_u, 90.0, 3), bystander = uprightDetection(bystander_u, 80.0, 20, 0.7);
    // The device's order changes every frame; at the first frame the target is the larger and more
    // confident one (first lock: tracker_test.cpp), and then it must be kept as the bystander crosses.
    hal::DetectionFrame f = (i % 2 == 0) ? frameOf(i * kLockOnFrameNs, {target, bystander})
                                         : frameOf(i * kLockOnFrameNs, {bystander, target});
    lock_on.apply(f);
    ASSERT_GE(f.target_index, 0) << i;
    EXPECT_NEAR(f.persons[static_cast<std::size_t>(f.target_index)].keypoints[0].u_px, target_u, 1e-9) << i;
  }
}

TEST(KeypointLockOn, GivenALostTarget_WhenOnlyABystanderIsSeen_ThenNobodyIsFollowedUntilTheTargetReturns) {
  KeypointLockOn lock_on(TrackerParams{}, TorsoFeatureParams{});
  rt::TimeNs t = 0;
  for (int i = 0; i < 10; ++i, t += kLockOnFrameNs) {
    auto f = frameOf(t, {uprightDetection(320.0, 90.0, 3)});
    lock_on.apply(f);
    ASSERT_EQ(f.target_index, 0);
  }
  // Two seconds of a different shirt where the target was (longer than lost_after_s).
  for (int i = 0; i < 60; ++i, t += kLockOnFrameNs) {
    auto f = frameOf(t, {uprightDetection(320.0, 90.0, 20)});
    lock_on.apply(f);
    EXPECT_EQ(f.target_index, -1) << i;
  }
  auto back = frameOf(t, {uprightDetection(100.0, 60.0, 20), uprightDetection(500.0, 70.0, 3)});
  lock_on.apply(back);
  EXPECT_EQ(back.target_index, 1);
}

TEST(KeypointLockOn, GivenADesignatedTarget_WhenLaterFramesLeaveTheChoiceOpen_ThenTheDesignatedPersonIsFollowed) {
  KeypointLockOn lock_on(TrackerParams{}, TorsoFeatureParams{});
  // The designated person is the smaller, less salient one: acquisition alone would pick the other.
  auto f = frameOf(0, {uprightDetection(100.0, 90.0, 3, 0.9), uprightDetection(400.0, 60.0, 20, 0.6)});
  f.target_index = 1;
  lock_on.apply(f);
  EXPECT_EQ(f.target_index, 1);
  EXPECT_TRUE(lock_on.tracker().locked(0));
  auto open = frameOf(kLockOnFrameNs, {uprightDetection(402.0, 60.0, 20, 0.6), uprightDetection(98.0, 90.0, 3, 0.9)});
  lock_on.apply(open);
  EXPECT_EQ(open.target_index, 0);
  // A target index past the listed persons names nobody: the choice is open.
  auto bad = frameOf(2 * kLockOnFrameNs, {uprightDetection(404.0, 60.0, 20, 0.6)});
  bad.target_index = 3;
  lock_on.apply(bad);
  EXPECT_EQ(bad.target_index, 0);
}

TEST(KeypointLockOn, GivenMalformedSignatures_WhenConverted_ThenTheyAreNoAppearance) {
  auto d = uprightDetection(100.0, 90.0, 3);
  EXPECT_TRUE(toAppearance(d).valid);
  d.appearance[5] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(toAppearance(d).valid);
  d.appearance.fill(0.0F);
  EXPECT_FALSE(toAppearance(d).valid);
  d.appearance[1] = -0.5F;
  d.appearance[2] = 1.5F;
  EXPECT_FALSE(toAppearance(d).valid);
  // Unnormalised but valid: scaled to sum to 1.
  d.appearance.fill(0.0F);
  d.appearance[1] = 2.0F;
  d.appearance[2] = 6.0F;
  const Appearance a = toAppearance(d);
  ASSERT_TRUE(a.valid);
  EXPECT_FLOAT_EQ(a.histogram[1], 0.25F);
  EXPECT_FLOAT_EQ(a.histogram[2], 0.75F);
}

}  // namespace
}  // namespace aerotrack::perception
