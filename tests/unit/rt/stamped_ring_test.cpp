// Unit tests of rt::StampedRing: order, overwrite when full, and every bracket outcome, against
// hand-worked stamps.
#include <gtest/gtest.h>

#include "aerotrack/rt/stamped_ring.hpp"

namespace aerotrack::rt {
namespace {

TEST(StampedRing, GivenSamplesWhenFullThenTheOldestIsOverwrittenAndOrderKept) {
  StampedRing<int> ring(3);
  EXPECT_TRUE(ring.empty());
  for (int i = 1; i <= 5; ++i) {
    ASSERT_TRUE(ring.accepts(i * 10));
    ring.push(i * 10, i);
  }
  EXPECT_FALSE(ring.accepts(50));  // not newer than the newest
  ASSERT_EQ(ring.size(), 3U);
  EXPECT_EQ(ring.at(0), 3);
  EXPECT_EQ(ring.stampAt(0), 30);
  EXPECT_EQ(ring.at(2), 5);
}

TEST(StampedRing, GivenTimesAroundTheSamplesWhenBracketedThenEachOutcomeIsReported) {
  StampedRing<double> ring(8);
  EXPECT_EQ(ring.bracket(0, 100, 0).status, BracketStatus::kEmpty);
  for (TimeNs t : {100, 200, 300, 700}) ring.push(t, static_cast<double>(t));
  EXPECT_EQ(ring.bracket(99, 150, 0).status, BracketStatus::kBeforeOldest);
  const Bracket between = ring.bracket(250, 150, 0);
  EXPECT_EQ(between.status, BracketStatus::kOk);
  EXPECT_EQ(between.lo, 1U);
  EXPECT_EQ(between.hi, 2U);
  EXPECT_DOUBLE_EQ(between.alpha, 0.5);
  const Bracket exact = ring.bracket(200, 150, 0);
  EXPECT_EQ(exact.status, BracketStatus::kOk);
  EXPECT_EQ(exact.lo, 1U);
  EXPECT_EQ(exact.alpha, 0.0);
  EXPECT_EQ(ring.bracket(400, 150, 0).status, BracketStatus::kGapTooLarge);  // 300..700 is 400 apart
  EXPECT_EQ(ring.bracket(700, 150, 0).lo, 3U);
  EXPECT_EQ(ring.bracket(720, 150, 0).status, BracketStatus::kAfterNewest);
  const Bracket hold = ring.bracket(720, 150, 50);
  EXPECT_EQ(hold.status, BracketStatus::kOk);
  EXPECT_EQ(hold.lo, 3U);
  EXPECT_EQ(hold.alpha, 0.0);
}

}  // namespace
}  // namespace aerotrack::rt
