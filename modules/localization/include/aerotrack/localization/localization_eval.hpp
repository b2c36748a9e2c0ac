// Held-out evaluation of a fitted localization model (issue 6, `aerotrack eval-localization`):
// the horizontal error |(x, y) predicted - (x, y) true| in the camera frame, summarised (mean,
// median, 95th percentile, max; the paper reports a mean of about 0.20 m, Sect. IV-B) and
// tabulated against the true horizontal distance in 1 m bins.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "aerotrack/localization/localization_model.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::localization {

/// Errors of the samples whose true horizontal distance hypot(x_m, y_m) is in [from_m, to_m).
struct DistanceBin {
  double from_m = 0.0;
  double to_m = 0.0;
  std::size_t samples = 0;
  double mean_error_m = 0.0;
  double p95_error_m = 0.0;
  double max_error_m = 0.0;
};

struct LocalizationEvaluation {
  std::string model;  ///< "paper" or "pinhole".
  std::size_t samples = 0;
  double mean_error_m = 0.0;
  double median_error_m = 0.0;
  double p95_error_m = 0.0;  ///< Linear interpolation between order statistics.
  double max_error_m = 0.0;
  std::vector<DistanceBin> by_distance;  ///< 1 m bins, ascending, only the bins holding samples.
};

/// Evaluates params on samples. Error if samples is empty or a sample has a non-finite value or
/// torso_px <= 0. Thread safety: reentrant. Allocates O(samples).
rt::Expected<LocalizationEvaluation> evaluate(const LocalizationParams& params,
                                              std::span<const LocalizationSample> samples);

}  // namespace aerotrack::localization
