// Clocks, time conversions and timing statistics against hand-computed values.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "aerotrack/rt/clock.hpp"
#include "aerotrack/rt/timing_stats.hpp"

namespace aerotrack::rt {
namespace {

TEST(Time, ConversionsRoundToNearestNanosecond) {
  EXPECT_EQ(secondsToNs(1.5), 1'500'000'000);
  EXPECT_EQ(millisecondsToNs(0.0000004), 0);
  EXPECT_EQ(millisecondsToNs(0.0000006), 1);
  EXPECT_EQ(periodFromRateHz(200.0), 5'000'000);
  EXPECT_EQ(periodFromRateHz(3.0), 333'333'333);
  EXPECT_DOUBLE_EQ(nsToSeconds(2'500'000'000), 2.5);
}

TEST(ManualClock, GivenSetForwardThenMovesAndBackwardIsRefused) {
  ManualClock clock(100);
  EXPECT_EQ(clock.now(), 100);
  EXPECT_TRUE(clock.set(250));
  EXPECT_EQ(clock.now(), 250);
  EXPECT_FALSE(clock.set(249));
  EXPECT_EQ(clock.now(), 250);
  EXPECT_TRUE(clock.advance(50));
  EXPECT_EQ(clock.now(), 300);
  EXPECT_FALSE(clock.advance(-1));
}

TEST(MonotonicClock, NeverGoesBackwards) {
  MonotonicClock clock;
  TimeNs last = clock.now();
  for (int i = 0; i < 10000; ++i) {
    const TimeNs t = clock.now();
    ASSERT_GE(t, last);
    last = t;
  }
}

TEST(LatencyHistogram, GivenEmptyThenZero) {
  LatencyHistogram h;
  EXPECT_EQ(h.count(), 0U);
  EXPECT_EQ(h.quantileNs(0.5), 0.0);
  EXPECT_EQ(h.meanNs(), 0.0);
}

TEST(LatencyHistogram, GivenRandomSamplesThenQuantilesWithinOnePercentOfExactOrderStatistics) {
  std::mt19937 rng(42);
  std::lognormal_distribution<double> dist(std::log(50'000.0), 1.0);  // around 50 us
  std::vector<DurationNs> samples;
  LatencyHistogram h;
  for (int i = 0; i < 20000; ++i) {
    const auto s = static_cast<DurationNs>(dist(rng));
    samples.push_back(s);
    h.record(s);
  }
  std::sort(samples.begin(), samples.end());
  for (double q : {0.5, 0.9, 0.99}) {
    const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(samples.size()))) - 1;
    const double exact = static_cast<double>(samples[rank]);
    EXPECT_GE(h.quantileNs(q), exact) << "q=" << q;  // upper bucket edge
    EXPECT_LE(h.quantileNs(q), exact * 1.0101) << "q=" << q;
  }
  EXPECT_EQ(h.maxNs(), static_cast<double>(samples.back()));
  EXPECT_EQ(h.quantileNs(1.0), static_cast<double>(samples.back()));
}

TEST(TimingStats, GivenRunsOverBudgetThenCountedAsOverruns) {
  TimingStats stats(1'000'000);  // 1 ms budget
  stats.recordRun(500'000);
  stats.recordRun(1'000'000);  // exactly on budget: not an overrun
  stats.recordRun(1'000'001);
  stats.addMissedDeadlines(3);
  const TimingSnapshot s = stats.snapshot();
  EXPECT_EQ(s.runs, 3U);
  EXPECT_EQ(s.overruns, 1U);
  EXPECT_EQ(s.missed_deadlines, 3U);
  EXPECT_NEAR(s.max_ms, 1.000001, 1e-9);
  EXPECT_NEAR(s.mean_ms, (0.5 + 1.0 + 1.000001) / 3.0, 1e-9);
  EXPECT_NEAR(s.p50_ms, 1.0, 0.0101);
}

}  // namespace
}  // namespace aerotrack::rt
