// The merge step of `aerotrack bench` (issue 25): reads whatever trials of a plan have finished, by
// whatever engine ran them, and writes the reports -- per cell of a bench DIR/<cell>/bench.json and
// bench.png and the table on stdout; for a suite DIR/suite.json, report.md and the plots; with a sweep
// the plots against each swept key. It only reads trial folders and rewrites reports, so running it
// again gives the same files. Trials without a result are listed, one line each with the reason, and
// in DIR/missing.txt ("INDEX CELL SEED DIR: reason").
#pragma once

#include <cstddef>
#include <vector>

#include "trial_plan.hpp"

namespace aerotrack::app {

struct MergeOutcome {
  std::vector<std::size_t> missing;  ///< Trial indices without a complete result.
  int error_cells = 0;
};

/// Merges and reports; error only when a report cannot be written.
rt::Expected<MergeOutcome> mergeTrials(const TrialPlan& plan);

}  // namespace aerotrack::app
