// Statistics over trials' summary.json files, shared by `aerotrack bench` (bench.json, the table) and
// `aerotrack bench --suite` (suite.json, report.md): success counts of both verdicts with 95 % Wilson
// score intervals, identity metrics, the person's measured speed, visibility and distance.
#pragma once

#include <vector>

#include <nlohmann/json.hpp>

namespace aerotrack::app {

/// z for a two-sided 95 % interval: the 0.975 quantile of the standard normal distribution.
inline constexpr double kZ95 = 1.959963984540054;

struct ProportionInterval {
  double lo = 0.0;
  double hi = 1.0;
};

/// The Wilson score interval of a proportion of `successes` out of `n` trials (Wilson 1927; Agresti &
/// Coull 1998, "Approximate is better than 'exact'"). Chosen over the normal (Wald) interval because
/// with 10-20 trials and rates near 0 or 1 -- every cell of Table I -- Wald collapses to zero width
/// (10/10 gives [1, 1]) while Wilson gives [0.72, 1]. n == 0: [0, 1] (nothing known).
ProportionInterval wilsonInterval(int successes, int n, double z = kZ95);

/// Aggregates trials' summary.json objects (those of completed trials). Keys: completed, successes,
/// success_rate, success_ci95 [lo, hi], followed_all_the_way, followed_rate, followed_ci95, collisions,
/// visible_ratio_mean, distance_mean_m, min_clearance_m (the smallest; null without obstacles),
/// identity {trials_reported, trials_without_switch, switches_mean, time_on_wrong_person_s_mean}
/// (over the trials that reported identities; means null if none did), person_top_speed_mps_mean,
/// person_top_speed_mps_max, person_mean_speed_mps_mean. Rates and intervals are over completed trials.
nlohmann::json aggregateSummaries(const std::vector<nlohmann::json>& summaries);

/// The q-quantile (0 <= q <= 1) of values, interpolated linearly between order statistics (R's type 7,
/// numpy's default). NaN for no values.
double quantileOf(std::vector<double> values, double q);

}  // namespace aerotrack::app
