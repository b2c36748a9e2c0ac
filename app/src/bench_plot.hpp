// bench.png (issue 24 item 4): what a bench's trials were like, not only how many succeeded -- the
// distributions over the trials of the time the person was in sight and of the mean distance kept, as
// histograms, under a line with both verdicts. Suites plot the same against speed (suite.hpp).
#pragma once

#include <string>
#include <vector>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::app {

struct BenchPlotData {
  std::string title;                    ///< e.g. "sharp_turn, 20 trials, 1.5 m/s"
  std::string verdict;                  ///< the verdicts line
  std::vector<double> visible_ratio;    ///< per trial, in [0, 1]
  std::vector<double> distance_mean_m;  ///< per trial
};

/// Writes the picture; error naming the file if it cannot be written.
rt::Status writeBenchPlot(const std::string& png_path, const BenchPlotData& data);

}  // namespace aerotrack::app
