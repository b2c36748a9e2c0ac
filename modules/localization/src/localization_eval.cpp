// Held-out evaluation of a localization model (see localization_eval.hpp).
#include "aerotrack/localization/localization_eval.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace aerotrack::localization {
namespace {

/// Quantile q in [0, 1] of sorted values, linear between order statistics.
double quantile(const std::vector<double>& sorted, double q) {
  const double position = q * static_cast<double>(sorted.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(position));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  const double t = position - static_cast<double>(lo);
  return sorted[lo] + t * (sorted[hi] - sorted[lo]);
}

double mean(const std::vector<double>& values) {
  double sum = 0.0;
  for (const double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

}  // namespace

rt::Expected<LocalizationEvaluation> evaluate(const LocalizationParams& params,
                                              std::span<const LocalizationSample> samples) {
  if (samples.empty()) return rt::Error{"evaluation: no samples"};
  std::vector<double> errors;
  errors.reserve(samples.size());
  std::map<long, std::vector<double>> bins;  // floor(distance) -> errors
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const LocalizationSample& s = samples[i];
    if (!std::isfinite(s.torso_px) || !std::isfinite(s.u_px) || !std::isfinite(s.x_m) || !std::isfinite(s.y_m) ||
        !(s.torso_px > 0.0)) {
      return rt::Error{"evaluation: sample " + std::to_string(i) + " is not finite or has torso_px <= 0"};
    }
    const Eigen::Vector3d p_C = predict(params, s.torso_px, s.u_px);
    const double error_m = std::hypot(p_C.x() - s.x_m, p_C.y() - s.y_m);
    errors.push_back(error_m);
    bins[std::lround(std::floor(std::hypot(s.x_m, s.y_m)))].push_back(error_m);
  }
  LocalizationEvaluation result;
  result.model = std::string(toString(params.model));
  result.samples = samples.size();
  result.mean_error_m = mean(errors);
  std::sort(errors.begin(), errors.end());
  result.median_error_m = quantile(errors, 0.5);
  result.p95_error_m = quantile(errors, 0.95);
  result.max_error_m = errors.back();
  for (auto& [floor_m, bin_errors] : bins) {
    std::sort(bin_errors.begin(), bin_errors.end());
    DistanceBin bin;
    bin.from_m = static_cast<double>(floor_m);
    bin.to_m = bin.from_m + 1.0;
    bin.samples = bin_errors.size();
    bin.mean_error_m = mean(bin_errors);
    bin.p95_error_m = quantile(bin_errors, 0.95);
    bin.max_error_m = bin_errors.back();
    result.by_distance.push_back(bin);
  }
  return result;
}

}  // namespace aerotrack::localization
