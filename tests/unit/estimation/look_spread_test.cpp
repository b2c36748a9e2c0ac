// The look gate's robust spread (look_spread.hpp): median and MAD of the window against a sort of the same
// values; a few seconds of blends with a passer-by barely move the gate, where the running mean and standard
// deviation it replaced opened it; a real change of the person's look moves it once it fills half the window.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <random>
#include <vector>

#include "aerotrack/estimation/look_spread.hpp"

namespace aerotrack::estimation {
namespace {

double sortedMedian(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

TEST(LookSpread, MedianAndMadEqualASortOfTheLastWindowOfValues) {
  std::mt19937_64 rng(7);
  std::gamma_distribution<double> distance(2.0, 0.03);  // skewed, positive, like colour distances
  LookSpread spread;
  std::deque<double> last;
  for (int i = 0; i < 300; ++i) {
    const double d = distance(rng);
    spread.push(d);
    last.push_back(d);
    if (last.size() > LookSpread::kWindow) last.pop_front();
    const std::vector<double> window(last.begin(), last.end());
    const double median = sortedMedian(window);
    std::vector<double> deviations;
    for (const double x : window) deviations.push_back(std::abs(x - median));
    ASSERT_EQ(spread.count(), window.size());
    ASSERT_DOUBLE_EQ(spread.median(), median) << i;
    ASSERT_DOUBLE_EQ(spread.mad(), sortedMedian(deviations)) << i;
    ASSERT_DOUBLE_EQ(spread.threshold(3.0), median + 3.0 * LookSpread::kMadToSigma * spread.mad());
  }
}

TEST(LookSpread, ForNormalDistancesTheThresholdIsTheMeanPlusSigmas) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> distance(0.5, 0.1);
  LookSpread spread;
  double sum = 0.0;
  int n = 0;
  for (int i = 0; i < 6400; ++i) {
    spread.push(distance(rng));
    if (i % LookSpread::kWindow == LookSpread::kWindow - 1) {
      sum += spread.threshold(3.0);
      ++n;
    }
  }
  EXPECT_NEAR(sum / n, 0.5 + 3.0 * 0.1, 0.03) << "1.4826 MAD estimates the standard deviation";
}

TEST(LookSpread, GivenTwoSecondsOfBlendsWithAPasserBy_ThenTheGateBarelyMovesWhereTheRunningMeanOpened) {
  // The person's own distances 0.06 +- 0.02 (image mode, crowd seed 17 before the group), then 26 frames (2 s at
  // 13 Hz) of blends at 0.15-0.32, the passer-by then at 0.30 (seed 17 at 23 s).
  std::mt19937_64 rng(17);
  std::normal_distribution<double> own(0.06, 0.02);
  std::uniform_real_distribution<double> blend(0.15, 0.32);
  LookSpread spread;
  double mean = 0.0, mean_sq = 0.0;  // the gate it replaced: rate max(0.1, 1 / n)
  int n = 0;
  const auto push = [&](double d) {
    spread.push(d);
    ++n;
    const double rate = std::max(0.1, 1.0 / n);
    mean += rate * (d - mean);
    mean_sq += rate * (d * d - mean_sq);
  };
  for (int i = 0; i < 100; ++i) push(std::max(0.0, own(rng)));
  const double before = spread.threshold(3.0);
  EXPECT_NEAR(before, 0.06 + 3 * 0.02, 0.03);
  for (int i = 0; i < 26; ++i) push(i % 3 == 2 ? std::max(0.0, own(rng)) : blend(rng));
  const double running = mean + 3.0 * std::sqrt(std::max(0.0, mean_sq - mean * mean));
  EXPECT_GT(running, 0.30) << "the running gate took the passer-by";
  EXPECT_LT(spread.threshold(3.0), 0.25) << "the robust one does not";
  EXPECT_LT(spread.threshold(3.0) - before, 0.1);
}

TEST(LookSpread, GivenARealChangeOfLook_ThenTheGateFollowsOnceItFillsHalfTheWindow) {
  LookSpread spread;
  for (int i = 0; i < 64; ++i) spread.push(0.05 + 0.001 * (i % 5));
  for (int i = 0; i < 40; ++i) spread.push(0.25 + 0.001 * (i % 5));
  EXPECT_GT(spread.median(), 0.2);
  EXPECT_GT(spread.threshold(3.0), 0.25);
}

TEST(LookSpread, NonFiniteDistancesAreIgnoredAndAnEmptyWindowGatesAtZero) {
  LookSpread spread;
  EXPECT_EQ(spread.count(), 0u);
  EXPECT_EQ(spread.threshold(3.0), 0.0);
  spread.push(std::numeric_limits<double>::quiet_NaN());
  spread.push(std::numeric_limits<double>::infinity());
  EXPECT_EQ(spread.count(), 0u);
  spread.push(0.1);
  EXPECT_EQ(spread.count(), 1u);
  EXPECT_DOUBLE_EQ(spread.median(), 0.1);
  EXPECT_DOUBLE_EQ(spread.mad(), 0.0);
  spread.clear();
  EXPECT_EQ(spread.count(), 0u);
}

}  // namespace
}  // namespace aerotrack::estimation
