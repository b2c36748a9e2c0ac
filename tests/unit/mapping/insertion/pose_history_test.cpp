// Tests of PoseHistory (hal::OdometryHistory, an rt::StampedHistory): interpolation against
// hand-computed poses (linear position, slerp yaw), rejection of out-of-order and non-finite samples,
// and the cases that give no pose (empty, before the oldest, after the newest, a gap). A slow
// linear-scan reference checks lookups after the ring wrapped.
#include "aerotrack/mapping/pose_history.hpp"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace aerotrack::mapping {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr rt::DurationNs kMs = rt::kNsPerMillisecond;

hal::OdometrySample sample(rt::TimeNs stamp_ns, const Eigen::Vector3d& p_WB_m, double yaw_rad) {
  hal::OdometrySample s;
  s.stamp_ns = stamp_ns;
  s.p_WB_m = p_WB_m;
  s.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()));
  return s;
}

PoseHistory makeHistory(PoseHistoryParams params = {}) {
  return PoseHistory::create(params).value();
}

double yawOf(const Eigen::Isometry3d& T) {
  return std::atan2(T.linear()(1, 0), T.linear()(0, 0));
}

TEST(PoseHistory, GivenInvalidParams_WhenCreate_ThenError) {
  PoseHistoryParams params;
  params.capacity = 1;
  EXPECT_FALSE(PoseHistory::create(params).has_value());
  params = {};
  params.max_gap_ns = 0;
  EXPECT_FALSE(PoseHistory::create(params).has_value());
  params = {};
  params.future_tolerance_ns = -1;
  EXPECT_FALSE(PoseHistory::create(params).has_value());
  EXPECT_TRUE(PoseHistory::create({}).has_value());
}

TEST(PoseHistory, GivenYaw0AndYaw90_WhenPoseAtHalfway_ThenYaw45AndMidpoint) {
  PoseHistory history = makeHistory();
  ASSERT_EQ(history.push(sample(0, {0.0, 0.0, 0.0}, 0.0)), PushResult::kAccepted);
  ASSERT_EQ(history.push(sample(20 * kMs, {2.0, 4.0, -2.0}, kPi / 2)), PushResult::kAccepted);

  const std::optional<Eigen::Isometry3d> T_WB = history.valueAt(10 * kMs);
  ASSERT_TRUE(T_WB.has_value());
  EXPECT_NEAR(T_WB->translation().x(), 1.0, 1e-12);
  EXPECT_NEAR(T_WB->translation().y(), 2.0, 1e-12);
  EXPECT_NEAR(T_WB->translation().z(), -1.0, 1e-12);
  EXPECT_NEAR(yawOf(*T_WB), kPi / 4, 1e-12);
  // The rotation stays about z: body z axis is world z.
  EXPECT_NEAR(T_WB->linear()(2, 2), 1.0, 1e-12);

  // A quarter of the way: 22.5 deg and a quarter of the displacement.
  const std::optional<Eigen::Isometry3d> T_quarter = history.valueAt(5 * kMs);
  ASSERT_TRUE(T_quarter.has_value());
  EXPECT_NEAR(yawOf(*T_quarter), kPi / 8, 1e-12);
  EXPECT_TRUE(T_quarter->translation().isApprox(Eigen::Vector3d(0.5, 1.0, -0.5), 1e-12));
}

TEST(PoseHistory, GivenYawAcrossPlusMinusPi_WhenPoseAtHalfway_ThenShortestArcThrough180) {
  PoseHistory history = makeHistory();
  (void)history.push(sample(0, Eigen::Vector3d::Zero(), 170.0 * kPi / 180.0));
  (void)history.push(sample(10 * kMs, Eigen::Vector3d::Zero(), -170.0 * kPi / 180.0));
  const std::optional<Eigen::Isometry3d> T_WB = history.valueAt(5 * kMs);
  ASSERT_TRUE(T_WB.has_value());
  EXPECT_NEAR(std::abs(yawOf(*T_WB)), kPi, 1e-9);  // Not 0 (the long way round).
}

TEST(PoseHistory, GivenSamples_WhenPoseAtTheirStamps_ThenExactlyTheirPoses) {
  PoseHistory history = makeHistory();
  (void)history.push(sample(100, {1.0, 2.0, 3.0}, 0.3));
  (void)history.push(sample(200, {4.0, 5.0, 6.0}, 0.6));
  (void)history.push(sample(300, {7.0, 8.0, 9.0}, 0.9));
  for (int i = 0; i < 3; ++i) {
    const std::optional<Eigen::Isometry3d> T_WB = history.valueAt(100 * (i + 1));
    ASSERT_TRUE(T_WB.has_value());
    EXPECT_TRUE(T_WB->translation().isApprox(Eigen::Vector3d(1.0 + 3 * i, 2.0 + 3 * i, 3.0 + 3 * i), 1e-15));
    EXPECT_NEAR(yawOf(*T_WB), 0.3 * (i + 1), 1e-12);
  }
}

TEST(PoseHistory, GivenOutOfOrderOrDuplicateSample_WhenPush_ThenRejectedAndCounted) {
  PoseHistory history = makeHistory();
  EXPECT_EQ(history.push(sample(10 * kMs, {1.0, 0.0, 0.0}, 0.0)), PushResult::kAccepted);
  EXPECT_EQ(history.push(sample(5 * kMs, {9.0, 0.0, 0.0}, 0.0)), PushResult::kRejectedOutOfOrder);
  EXPECT_EQ(history.push(sample(10 * kMs, {9.0, 0.0, 0.0}, 0.0)), PushResult::kRejectedOutOfOrder);
  EXPECT_EQ(history.rejectedOutOfOrderCount(), 2U);
  EXPECT_EQ(history.acceptedCount(), 1U);
  EXPECT_EQ(history.size(), 1U);
  EXPECT_EQ(history.newest().p_WB_m.x(), 1.0);
}

TEST(PoseHistory, GivenNonFiniteOrZeroQuaternionSample_WhenPush_ThenRejectedAndCounted) {
  PoseHistory history = makeHistory();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  hal::OdometrySample bad_p = sample(1, {nan, 0.0, 0.0}, 0.0);
  hal::OdometrySample bad_q = sample(2, {0.0, 0.0, 0.0}, 0.0);
  bad_q.q_WB.w() = std::numeric_limits<double>::infinity();
  hal::OdometrySample zero_q = sample(3, {0.0, 0.0, 0.0}, 0.0);
  zero_q.q_WB.coeffs().setZero();
  EXPECT_EQ(history.push(bad_p), PushResult::kRejectedInvalid);
  EXPECT_EQ(history.push(bad_q), PushResult::kRejectedInvalid);
  EXPECT_EQ(history.push(zero_q), PushResult::kRejectedInvalid);
  EXPECT_EQ(history.rejectedInvalidCount(), 3U);
  EXPECT_TRUE(history.empty());
}

TEST(PoseHistory, GivenUnnormalisedQuaternion_WhenPush_ThenStoredNormalised) {
  PoseHistory history = makeHistory();
  hal::OdometrySample s = sample(1, {0.0, 0.0, 0.0}, 0.5);
  s.q_WB.coeffs() *= 3.0;
  (void)history.push(s);
  EXPECT_NEAR(history.newest().q_WB.norm(), 1.0, 1e-15);
  const std::optional<Eigen::Isometry3d> T_WB = history.valueAt(1);
  ASSERT_TRUE(T_WB.has_value());
  EXPECT_NEAR(yawOf(*T_WB), 0.5, 1e-12);
}

TEST(PoseHistory, GivenTimesOutsideTheSamples_WhenLookup_ThenNothingAndWhy) {
  PoseHistory history = makeHistory();
  EXPECT_EQ(history.lookup(0).status, PoseLookupStatus::kEmpty);
  EXPECT_FALSE(history.valueAt(0).has_value());
  (void)history.push(sample(100 * kMs, {0.0, 0.0, 0.0}, 0.0));
  (void)history.push(sample(110 * kMs, {1.0, 0.0, 0.0}, 0.0));
  EXPECT_EQ(history.lookup(100 * kMs - 1).status, PoseLookupStatus::kBeforeOldest);
  EXPECT_EQ(history.lookup(110 * kMs + 1).status, PoseLookupStatus::kAfterNewest);
  EXPECT_EQ(history.lookup(130 * kMs).status, PoseLookupStatus::kAfterNewest);  // 20 ms: no extrapolation.
  EXPECT_FALSE(history.valueAt(130 * kMs).has_value());
  EXPECT_TRUE(history.valueAt(110 * kMs).has_value());
}

TEST(PoseHistory, GivenFutureTolerance_WhenLookupJustAfterNewest_ThenNewestPoseHeld) {
  PoseHistoryParams params;
  params.future_tolerance_ns = 2 * kMs;
  PoseHistory history = makeHistory(params);
  (void)history.push(sample(0, {0.0, 0.0, 0.0}, 0.0));
  (void)history.push(sample(10 * kMs, {1.0, 0.0, 0.0}, 0.2));
  const std::optional<Eigen::Isometry3d> held = history.valueAt(12 * kMs);
  ASSERT_TRUE(held.has_value());
  EXPECT_EQ(held->translation().x(), 1.0);  // Held, not extrapolated to 1.2.
  EXPECT_NEAR(yawOf(*held), 0.2, 1e-12);
  EXPECT_EQ(history.lookup(12 * kMs + 1).status, PoseLookupStatus::kAfterNewest);
}

TEST(PoseHistory, GivenGapLongerThanMaxGap_WhenLookupInside_ThenNothingButSamplesStillFound) {
  PoseHistoryParams params;
  params.max_gap_ns = 50 * kMs;
  PoseHistory history = makeHistory(params);
  (void)history.push(sample(0, {0.0, 0.0, 0.0}, 0.0));
  (void)history.push(sample(40 * kMs, {1.0, 0.0, 0.0}, 0.0));   // 40 ms gap: fine.
  (void)history.push(sample(140 * kMs, {2.0, 0.0, 0.0}, 0.0));  // 100 ms gap: stale.
  EXPECT_TRUE(history.valueAt(20 * kMs).has_value());
  EXPECT_EQ(history.lookup(90 * kMs).status, PoseLookupStatus::kGapTooLarge);
  EXPECT_TRUE(history.valueAt(40 * kMs).has_value());
  EXPECT_TRUE(history.valueAt(140 * kMs).has_value());
}

/// Slow reference: linear scan over the samples pushed, kept in a plain vector.
std::optional<Eigen::Isometry3d> referencePose(const std::vector<hal::OdometrySample>& samples, rt::TimeNs t_ns) {
  for (std::size_t i = 0; i + 1 < samples.size(); ++i) {
    const hal::OdometrySample& a = samples[i];
    const hal::OdometrySample& b = samples[i + 1];
    if (a.stamp_ns <= t_ns && t_ns <= b.stamp_ns) {
      const double alpha = static_cast<double>(t_ns - a.stamp_ns) / static_cast<double>(b.stamp_ns - a.stamp_ns);
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.linear() = a.q_WB.slerp(alpha, b.q_WB).toRotationMatrix();
      T.translation() = (1.0 - alpha) * a.p_WB_m + alpha * b.p_WB_m;
      return T;
    }
  }
  return std::nullopt;
}

TEST(PoseHistory, GivenRingWrappedSeveralTimes_WhenLookup_ThenMatchesLinearScanOfKeptSamples) {
  PoseHistoryParams params;
  params.capacity = 7;
  PoseHistory history = makeHistory(params);
  std::vector<hal::OdometrySample> pushed;
  for (int i = 0; i < 30; ++i) {
    const rt::TimeNs stamp_ns = i * 5 * kMs + (i % 3) * 1000;
    pushed.push_back(sample(stamp_ns, {0.1 * i, std::sin(i), 0.01 * i * i}, 0.37 * i));
    ASSERT_EQ(history.push(pushed.back()), PushResult::kAccepted);
  }
  ASSERT_EQ(history.size(), 7U);
  const std::vector<hal::OdometrySample> kept(pushed.end() - 7, pushed.end());
  EXPECT_EQ(history.oldest().stamp_ns, kept.front().stamp_ns);
  EXPECT_EQ(history.lookup(kept.front().stamp_ns - 1).status, PoseLookupStatus::kBeforeOldest);
  for (rt::TimeNs t = kept.front().stamp_ns; t <= kept.back().stamp_ns; t += 333'333) {
    const std::optional<Eigen::Isometry3d> got = history.valueAt(t);
    const std::optional<Eigen::Isometry3d> want = referencePose(kept, t);
    ASSERT_TRUE(got.has_value() && want.has_value()) << t;
    EXPECT_TRUE(got->translation().isApprox(want->translation(), 1e-12)) << t;
    EXPECT_TRUE(got->linear().isApprox(want->linear(), 1e-12)) << t;
  }
}

}  // namespace
}  // namespace aerotrack::mapping
