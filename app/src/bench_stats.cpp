// Statistics over trials: see bench_stats.hpp.
#include "bench_stats.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace aerotrack::app {

ProportionInterval wilsonInterval(int successes, int n, double z) {
  if (n <= 0) return {0.0, 1.0};
  const double nn = static_cast<double>(n);
  const double p = static_cast<double>(successes) / nn;
  const double z2 = z * z;
  const double denominator = 1.0 + z2 / nn;
  const double centre = (p + z2 / (2.0 * nn)) / denominator;
  const double half = z / denominator * std::sqrt(p * (1.0 - p) / nn + z2 / (4.0 * nn * nn));
  // Clamp only the rounding at k = 0 and k = n, where the exact bounds are 0 and 1.
  return {std::clamp(centre - half, 0.0, 1.0), std::clamp(centre + half, 0.0, 1.0)};
}

namespace {

double statsNumberOr(const nlohmann::json& object, const char* key, double fallback) {
  const auto it = object.find(key);
  return it != object.end() && it->is_number() ? it->get<double>() : fallback;
}

nlohmann::json statsInterval(int k, int n) {
  const ProportionInterval ci = wilsonInterval(k, n);
  return nlohmann::json::array({ci.lo, ci.hi});
}

nlohmann::json statsMeanOrNull(double sum, int n) {
  return n > 0 ? nlohmann::json(sum / n) : nlohmann::json(nullptr);
}

}  // namespace

nlohmann::json aggregateSummaries(const std::vector<nlohmann::json>& summaries) {
  const int n = static_cast<int>(summaries.size());
  int successes = 0, followed = 0, collisions = 0, identity_trials = 0, no_switch = 0, speed_trials = 0;
  int nearest_trials = 0, no_switch_nearest = 0;  // by the nearest match alone (identity_switches_nearest)
  double visible_sum = 0.0, distance_sum = 0.0, switches_sum = 0.0, wrong_sum_s = 0.0;
  double top_speed_sum = 0.0, top_speed_max = 0.0, mean_speed_sum = 0.0;
  double min_clearance = std::numeric_limits<double>::infinity();
  for (const nlohmann::json& s : summaries) {
    successes += s.value("success", false) ? 1 : 0;
    followed += s.value("followed_all_the_way", false) ? 1 : 0;
    collisions += static_cast<int>(statsNumberOr(s, "collisions", 0.0));
    visible_sum += statsNumberOr(s, "visible_ratio", 0.0);
    distance_sum += statsNumberOr(s, "distance_mean_m", 0.0);
    min_clearance = std::min(min_clearance, statsNumberOr(s, "min_clearance_m", min_clearance));
    if (s.contains("identity_switches") && s["identity_switches"].is_number()) {
      ++identity_trials;
      const double switches = s["identity_switches"].get<double>();
      switches_sum += switches;
      no_switch += switches == 0.0 ? 1 : 0;
      wrong_sum_s += statsNumberOr(s, "time_on_wrong_person_s", 0.0);
    }
    if (s.contains("identity_switches_nearest") && s["identity_switches_nearest"].is_number()) {
      ++nearest_trials;
      no_switch_nearest += s["identity_switches_nearest"].get<double>() == 0.0 ? 1 : 0;
    }
    if (s.contains("person_top_speed_mps") && s["person_top_speed_mps"].is_number()) {
      ++speed_trials;
      top_speed_sum += s["person_top_speed_mps"].get<double>();
      top_speed_max = std::max(top_speed_max, s["person_top_speed_mps"].get<double>());
      mean_speed_sum += statsNumberOr(s, "person_mean_speed_mps", 0.0);
    }
  }
  return {
      {"completed", n},
      {"successes", successes},
      {"success_rate", n > 0 ? successes / static_cast<double>(n) : 0.0},
      {"success_ci95", statsInterval(successes, n)},
      {"followed_all_the_way", followed},
      {"followed_rate", n > 0 ? followed / static_cast<double>(n) : 0.0},
      {"followed_ci95", statsInterval(followed, n)},
      {"collisions", collisions},
      {"visible_ratio_mean", statsMeanOrNull(visible_sum, n)},
      {"distance_mean_m", statsMeanOrNull(distance_sum, n)},
      {"min_clearance_m", std::isfinite(min_clearance) ? nlohmann::json(min_clearance) : nlohmann::json(nullptr)},
      {"identity",
       {{"trials_reported", identity_trials},
        {"trials_without_switch", no_switch},
        {"trials_without_switch_nearest",
         nearest_trials > 0 ? nlohmann::json(no_switch_nearest) : nlohmann::json(nullptr)},
        {"switches_mean", statsMeanOrNull(switches_sum, identity_trials)},
        {"time_on_wrong_person_s_mean", statsMeanOrNull(wrong_sum_s, identity_trials)}}},
      {"person_top_speed_mps_mean", statsMeanOrNull(top_speed_sum, speed_trials)},
      {"person_top_speed_mps_max", speed_trials > 0 ? nlohmann::json(top_speed_max) : nlohmann::json(nullptr)},
      {"person_mean_speed_mps_mean", statsMeanOrNull(mean_speed_sum, speed_trials)},
  };
}

double quantileOf(std::vector<double> values, double q) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const double at = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(at));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  return values[below] + (at - static_cast<double>(below)) * (values[above] - values[below]);
}

}  // namespace aerotrack::app
