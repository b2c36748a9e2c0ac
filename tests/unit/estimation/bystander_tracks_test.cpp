// The tracks of the other people in view (bystander_tracks.hpp): started, gated on their own prediction,
// forgotten after lost_after_s, their slots reused oldest first, and marked when seen beside the followed
// person.
#include <gtest/gtest.h>

#include "aerotrack/estimation/bystander_tracks.hpp"
#include "support/require.hpp"

namespace aerotrack::estimation {
namespace {

TargetMeasurement at(double t_s, double x_m, double y_m) {
  TargetMeasurement m;
  m.stamp_ns = rt::secondsToNs(t_s);
  m.p_WT_m = Eigen::Vector3d(x_m, y_m, 1.2);
  m.std_xy_m = 0.1;
  return m;
}

TEST(BystanderTracks, GivenAWalkerTracked_ThenTheirNextPositionFitsTheirTrackAndAJumpDoesNot) {
  TargetEstimatorParams params;
  BystanderTracks tracks = aerotrack::test::require(BystanderTracks::create(params, 3), "tracks");
  EXPECT_EQ(tracks.liveCount(0), 0U);
  const std::size_t i = tracks.start(at(0.0, 5.0, 0.0), {}, false);
  for (int k = 1; k <= 30; ++k)
    EXPECT_EQ(tracks.update(i, at(k / 30.0, 5.0 + k / 30.0, 0.0), {}, 0.1, k > 20), MeasurementVerdict::kAccepted);
  EXPECT_TRUE(tracks.live(i, rt::secondsToNs(1.0)));
  EXPECT_TRUE(tracks.seenWithFollowed(i));
  // Walking on at 1 m/s: 6.1 m at 1.1 s fits; 1.5 m aside does not.
  EXPECT_LT(*tracks.mahalanobisSq(i, at(1.1, 6.1, 0.0)), 1.0);
  EXPECT_GT(*tracks.mahalanobisSq(i, at(1.1, 6.1, 1.5)), params.gate_chi2);
  // Unmeasured for longer than lost_after_s: no longer live, no distance to it, its slot free.
  EXPECT_FALSE(tracks.live(i, rt::secondsToNs(1.0 + params.lost_after_s + 0.1)));
  EXPECT_FALSE(tracks.mahalanobisSq(i, at(2.2, 6.2, 0.0)).has_value());
  EXPECT_EQ(tracks.start(at(2.2, 0.0, 3.0), {}, false), i);
  EXPECT_FALSE(tracks.seenWithFollowed(i));
}

TEST(BystanderTracks, GivenEverySlotLive_WhenAnotherStarts_ThenTheOneMeasuredLongestAgoIsReused) {
  BystanderTracks tracks = aerotrack::test::require(BystanderTracks::create(TargetEstimatorParams{}, 2), "tracks");
  const std::size_t a = tracks.start(at(0.0, 1.0, 0.0), {}, false);
  const std::size_t b = tracks.start(at(0.1, 2.0, 0.0), {}, false);
  ASSERT_NE(a, b);
  tracks.update(a, at(0.2, 1.0, 0.0), {}, 0.1, false);
  EXPECT_EQ(tracks.start(at(0.3, 3.0, 0.0), {}, true), b);
  EXPECT_TRUE(tracks.seenWithFollowed(b));
  tracks.drop(a);
  EXPECT_FALSE(tracks.live(a, rt::secondsToNs(0.3)));
  EXPECT_EQ(tracks.liveCount(rt::secondsToNs(0.3)), 1U);
}

TEST(BystanderTracks, GivenOneWalkerLiveAndOneLost_ThenTheEstimateCarriesTheLiveOneAtItsPredictedPlace) {
  // The planner keeps away from the other people along their constant-velocity paths (issue 21 item 5): the
  // estimate carries each live track's state at its stamp, and none of a track unmeasured for lost_after_s.
  TargetEstimatorParams params;
  BystanderTracks tracks = aerotrack::test::require(BystanderTracks::create(params, 3), "tracks");
  const std::size_t walker = tracks.start(at(0.0, 5.0, 0.0), {}, false);
  for (int k = 1; k <= 30; ++k) tracks.update(walker, at(k / 10.0, 5.0, -k / 10.0), {}, 0.1, false);  // 1 m/s -y
  tracks.start(at(0.5, 9.0, 9.0), {}, false);  // seen once, at 0.5 s
  TargetEstimate estimate;
  tracks.fillOthers(rt::secondsToNs(3.0 + 0.6), estimate);
  ASSERT_EQ(estimate.other_count, 1U);
  EXPECT_NEAR(estimate.others[0].p_W_m.x(), 5.0, 0.05);
  EXPECT_NEAR(estimate.others[0].p_W_m.y(), -3.6, 0.1);
  EXPECT_NEAR(estimate.others[0].v_W_mps.y(), -1.0, 0.1);
  tracks.fillOthers(rt::secondsToNs(3.0 + params.lost_after_s + 0.1), estimate);
  EXPECT_EQ(estimate.other_count, 0U);
}

perception::Appearance inBin(std::size_t bin) {
  perception::Appearance a;
  a.histogram[bin] = 1.0F;  // the first region's bins: one colour
  a.valid = true;
  return a;
}

TEST(BystanderTracks, GivenAYoungTrack_ThenItsColourIsTheMeanOfItsFramesAndThenABlendAtTheRate) {
  // A young track's colour is not its first crop's (in a crowd, parts of others): the mean of its frames while
  // there are fewer than 1/rate, then a running blend, checked against both written out by hand.
  constexpr double kRate = 0.1;
  BystanderTracks tracks = aerotrack::test::require(BystanderTracks::create(TargetEstimatorParams{}, 1), "tracks");
  const std::size_t i = tracks.start(at(0.0, 5.0, 0.0), inBin(0), false);
  EXPECT_EQ(tracks.lookSamples(i), 1);
  // Frames 2 and 3 in bin 1, and one with no colour (not counted).
  tracks.update(i, at(0.1, 5.0, 0.0), inBin(1), kRate, false);
  tracks.update(i, at(0.2, 5.0, 0.0), perception::Appearance{}, kRate, false);
  tracks.update(i, at(0.3, 5.0, 0.0), inBin(1), kRate, false);
  EXPECT_EQ(tracks.lookSamples(i), 3);
  EXPECT_NEAR(tracks.look(i).histogram[0], 1.0 / 3.0, 1e-6);
  EXPECT_NEAR(tracks.look(i).histogram[1], 2.0 / 3.0, 1e-6);
  // Seven more in bin 2: the mean of ten; then two in bin 0, blended at the rate.
  for (int k = 0; k < 7; ++k) tracks.update(i, at(0.4 + 0.1 * k, 5.0, 0.0), inBin(2), kRate, false);
  EXPECT_NEAR(tracks.look(i).histogram[2], 0.7, 1e-6);
  for (int k = 0; k < 2; ++k) tracks.update(i, at(1.1 + 0.1 * k, 5.0, 0.0), inBin(0), kRate, false);
  EXPECT_EQ(tracks.lookSamples(i), 12);
  const double kept = (1.0 - kRate) * (1.0 - kRate);
  EXPECT_NEAR(tracks.look(i).histogram[0], kept * 0.1 + (1.0 - kept), 1e-6);
  EXPECT_NEAR(tracks.look(i).histogram[1], kept * 0.2, 1e-6);
  EXPECT_NEAR(tracks.look(i).histogram[2], kept * 0.7, 1e-6);
  tracks.drop(i);
  EXPECT_EQ(tracks.lookSamples(i), 0);
}

}  // namespace
}  // namespace aerotrack::estimation
