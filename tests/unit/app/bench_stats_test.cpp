// Wilson score intervals against published values, and the aggregation of trials' summaries.
#include <gtest/gtest.h>

#include "bench_stats.hpp"

#include <cmath>

namespace aerotrack::app {
namespace {

TEST(WilsonInterval, GivenPublishedCasesThenMatches) {
  // Newcombe (1998), "Two-sided confidence intervals for the single proportion", Stat. Med. 17,
  // its worked examples, method 3 (score, no continuity correction): 81/263 -> 0.2553-0.3662; 0/20 -> 0-0.1611;
  // 1/29 -> 0.0061-0.1718.
  ProportionInterval ci = wilsonInterval(81, 263);
  EXPECT_NEAR(ci.lo, 0.2553, 5e-5);
  EXPECT_NEAR(ci.hi, 0.3662, 5e-5);
  ci = wilsonInterval(0, 20);
  EXPECT_DOUBLE_EQ(ci.lo, 0.0);
  EXPECT_NEAR(ci.hi, 0.1611, 5e-5);
  ci = wilsonInterval(1, 29);
  EXPECT_NEAR(ci.lo, 0.0061, 5e-5);
  EXPECT_NEAR(ci.hi, 0.1718, 5e-5);
}

TEST(WilsonInterval, GivenTableOneCountsThenHandComputedValues) {
  // By hand, z = 1.96: 8/10: centre (0.8 + 0.19208) / 1.38415 = 0.71682, half 1.41601 * sqrt(0.016 + 0.0096040)
  // = 0.22651 -> [0.4903, 0.9433]. 10/10: [10 / (10 + z^2), 1] = [0.7225, 1].
  ProportionInterval ci = wilsonInterval(8, 10);
  EXPECT_NEAR(ci.lo, 0.4902, 2e-4);
  EXPECT_NEAR(ci.hi, 0.9433, 2e-4);
  ci = wilsonInterval(10, 10);
  EXPECT_NEAR(ci.lo, 10.0 / (10.0 + kZ95 * kZ95), 1e-12);
  EXPECT_DOUBLE_EQ(ci.hi, 1.0);
  // Symmetric: k of n and n - k of n mirror each other.
  const ProportionInterval a = wilsonInterval(3, 10), b = wilsonInterval(7, 10);
  EXPECT_NEAR(a.lo, 1.0 - b.hi, 1e-12);
  EXPECT_NEAR(a.hi, 1.0 - b.lo, 1e-12);
}

TEST(WilsonInterval, GivenNoTrialsThenEverything) {
  const ProportionInterval ci = wilsonInterval(0, 0);
  EXPECT_EQ(ci.lo, 0.0);
  EXPECT_EQ(ci.hi, 1.0);
}

TEST(AggregateSummaries, GivenTrialsThenCountsMeansAndIdentity) {
  const std::vector<nlohmann::json> s = {
      {{"success", true},
       {"followed_all_the_way", true},
       {"visible_ratio", 0.9},
       {"distance_mean_m", 3.0},
       {"min_clearance_m", 0.5},
       {"identity_switches", 0},
       {"identity_switches_nearest", 3},
       {"time_on_wrong_person_s", 0.0},
       {"person_top_speed_mps", 1.5},
       {"person_mean_speed_mps", 1.2}},
      {{"success", true},
       {"followed_all_the_way", false},
       {"visible_ratio", 0.7},
       {"distance_mean_m", 4.0},
       {"min_clearance_m", 0.3},
       {"identity_switches", 2},
       {"time_on_wrong_person_s", 3.0},
       {"person_top_speed_mps", 1.7},
       {"person_mean_speed_mps", 1.0}},
      {{"success", false},
       {"followed_all_the_way", false},
       {"visible_ratio", 0.5},
       {"distance_mean_m", 5.0},
       {"min_clearance_m", nullptr},
       {"identity_switches", nullptr},
       {"time_on_wrong_person_s", nullptr},
       {"person_top_speed_mps", 1.6},
       {"person_mean_speed_mps", 1.1}},
  };
  const nlohmann::json a = aggregateSummaries(s);
  EXPECT_EQ(a["completed"], 3);
  EXPECT_EQ(a["successes"], 2);
  EXPECT_EQ(a["followed_all_the_way"], 1);
  EXPECT_NEAR(a["followed_rate"].get<double>(), 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(a["followed_ci95"][0].get<double>(), wilsonInterval(1, 3).lo, 1e-12);
  EXPECT_NEAR(a["visible_ratio_mean"].get<double>(), 0.7, 1e-12);
  EXPECT_NEAR(a["distance_mean_m"].get<double>(), 4.0, 1e-12);
  EXPECT_NEAR(a["min_clearance_m"].get<double>(), 0.3, 1e-12);
  EXPECT_EQ(a["identity"]["trials_reported"], 2);  // the third reported no identities
  EXPECT_EQ(a["identity"]["trials_without_switch"], 1);
  // By the nearest match (CLEAR MOT's kept correspondences aside): reported by one trial, with switches.
  EXPECT_EQ(a["identity"]["trials_without_switch_nearest"], 0);
  EXPECT_NEAR(a["identity"]["time_on_wrong_person_s_mean"].get<double>(), 1.5, 1e-12);
  EXPECT_NEAR(a["person_top_speed_mps_mean"].get<double>(), 1.6, 1e-12);
  EXPECT_NEAR(a["person_top_speed_mps_max"].get<double>(), 1.7, 1e-12);
  EXPECT_NEAR(a["person_mean_speed_mps_mean"].get<double>(), 1.1, 1e-12);
}

TEST(AggregateSummaries, GivenNoTrialsThenNullMeansAndFullInterval) {
  const nlohmann::json a = aggregateSummaries({});
  EXPECT_EQ(a["completed"], 0);
  EXPECT_TRUE(a["visible_ratio_mean"].is_null());
  EXPECT_TRUE(a["identity"]["time_on_wrong_person_s_mean"].is_null());
  EXPECT_TRUE(a["identity"]["trials_without_switch_nearest"].is_null());
  EXPECT_EQ(a["success_ci95"], nlohmann::json::array({0.0, 1.0}));
}

TEST(QuantileOf, GivenValuesThenLinearInterpolationAsNumpysDefault) {
  // numpy.quantile([3, 1, 4, 1, 5], q): 0.1 -> 1.0, 0.5 -> 3.0, 0.9 -> 4.6, 0.75 -> 4.0
  const std::vector<double> v = {3.0, 1.0, 4.0, 1.0, 5.0};
  EXPECT_DOUBLE_EQ(quantileOf(v, 0.1), 1.0);
  EXPECT_DOUBLE_EQ(quantileOf(v, 0.5), 3.0);
  EXPECT_DOUBLE_EQ(quantileOf(v, 0.9), 4.6);
  EXPECT_DOUBLE_EQ(quantileOf(v, 0.75), 4.0);
  EXPECT_DOUBLE_EQ(quantileOf(v, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(quantileOf(v, 1.0), 5.0);
  EXPECT_DOUBLE_EQ(quantileOf({2.5}, 0.3), 2.5);
  EXPECT_TRUE(std::isnan(quantileOf({}, 0.5)));
}

}  // namespace
}  // namespace aerotrack::app
