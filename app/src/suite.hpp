// Benchmark suites (issue 20 item 6): `aerotrack bench --suite FILE` runs a matrix of cells
// (scenario x speed x mode x camera) over a range of seeds, one `aerotrack sim` process per trial
// writing DIR/<cell>/trial-SEED/summary.json, and writes DIR/suite.json, DIR/report.md and plots.
// This file holds the parts that need no process: parsing the suite file, which trials remain
// (resuming), collecting the summaries, and writing the report and plots.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"
#include "sweep.hpp"

namespace aerotrack::app {

/// The modes a simulated trial flies: `sim --mode`, `bench --mode` and a suite cell's `modes` accept these.
inline std::vector<std::string> simModes() {
  return {"proposed", "baseline", "truth_flight"};
}
/// Empty if `mode` is one of simModes(); else the one-line error "--mode: expected ..., got '<mode>'".
std::string badModeError(const std::string& mode);

/// One cell of the matrix, expanded: every trial of it runs `aerotrack sim` with these options.
struct SuiteCell {
  std::string scenario;             ///< Name in config/scenarios/ or a YAML file.
  std::optional<double> speed_mps;  ///< --speed; empty: the scenario's own speeds.
  std::string mode;                 ///< proposed | baseline.
  std::string camera;               ///< keypoints | image.
  std::string config;               ///< --config; empty: the default (config/sim.yaml).
  SweepPoint sets;                  ///< --set KEY=VALUE of a sweep (sweep.hpp); empty: none.
  std::string id;                   ///< Folder name under the suite's output folder; empty: the folder itself.
};

/// Optional targets; a rate under its target is flagged in report.md.
struct SuiteTargets {
  std::optional<double> followed_rate;  ///< The paper's verdict (followed_all_the_way).
  std::optional<double> success_rate;   ///< Ours (success).
  std::optional<double> visible_ratio;
};

struct SuiteSpec {
  std::string name;
  std::string source;  ///< The suite file.
  std::int64_t first_seed = 1;
  std::int64_t last_seed = 1;
  SuiteTargets targets;
  std::vector<SuiteCell> cells;  ///< In file order: cell, then speed, then mode.
};

/// Parses a suite. Keys (every one checked; unknown keys rejected): name; seeds: N (seeds 1..N) or
/// [first, last]; targets (optional): {followed_rate, success_rate, visible_ratio} in [0, 1]; cells: a
/// non-empty list of {scenario, speeds (optional list in [0.05, 20] m/s), modes (non-empty list of
/// proposed, baseline), camera (optional, keypoints | image, default keypoints), config (optional)}.
rt::Expected<SuiteSpec> parseSuite(const rt::Expected<rt::ConfigNode>& root);
rt::Expected<SuiteSpec> loadSuite(const std::string& path);

/// Every cell once per sweep point (the point's id appended to the cell's), cell by cell.
void applySweep(SuiteSpec& suite, const std::vector<SweepPoint>& points);

/// The `sim` options of one trial of a cell (without the program and "sim").
std::vector<std::string> trialArgs(const SuiteCell& cell, std::int64_t seed, const std::string& dir);

/// suite.json's description of a cell, and back (plan.json keeps the cells this way).
nlohmann::json cellJson(const SuiteCell& cell);
rt::Expected<SuiteCell> cellFromJson(const nlohmann::json& json);

/// DIR/<cell id>/trial-SEED (DIR/trial-SEED for a cell without an id).
std::string trialDir(const std::string& out_dir, const SuiteCell& cell, std::int64_t seed);

/// Whether a trial has finished: its summary.json parses as an object with a verdict and was not
/// written by an interrupted run. A missing, partial or interrupted summary means: run it again.
bool trialComplete(const std::string& trial_dir);

/// The seeds of a cell whose trials are not complete, in order.
std::vector<std::int64_t> remainingSeeds(const std::string& out_dir, const SuiteCell& cell, std::int64_t first_seed,
                                         std::int64_t last_seed);

/// Why a cell cannot run (its scenario or config file does not exist), or empty.
std::string cellError(const SuiteCell& cell);

struct CellResult {
  SuiteCell cell;
  std::string error;                      ///< Set: the cell did not run (report.md shows an error line).
  std::vector<nlohmann::json> summaries;  ///< Of the completed trials, by seed.
  std::vector<std::int64_t> missing_seeds;
};

/// Reads the completed trials' summaries of every cell (error cells keep their error).
std::vector<CellResult> collectResults(const std::string& out_dir, const SuiteSpec& suite,
                                       const std::vector<std::string>& errors);

/// suite.json: the suite, and per cell its options, error, missing seeds, aggregateSummaries() and
/// each trial's verdicts.
nlohmann::json suiteJson(const SuiteSpec& suite, const std::vector<CellResult>& results);

/// The suite's name, source, seeds and targets (suite.json's and plan.json's head).
nlohmann::json suiteHeaderJson(const SuiteSpec& suite);

/// report.md: per scenario a table (speed x mode x camera) and its error lines, and the plots' links.
std::string suiteReport(const SuiteSpec& suite, const std::vector<CellResult>& results,
                        const std::vector<std::string>& plot_files);

/// With a sweep: for every swept key, DIR/sweep-<key>.png -- the paper's success rate (with its 95 %
/// Wilson band) and ours, and the visible ratio per trial (median, 10-90 %), against the key's value,
/// one series per cell of the matrix and values of the other keys. Values that are not all numbers are
/// placed in the order given. Returns the file names written.
rt::Expected<std::vector<std::string>> writeSweepPlots(const std::string& out_dir, const SuiteSpec& suite,
                                                       const std::vector<SweepKey>& keys,
                                                       const std::vector<CellResult>& results);

/// One PNG per scenario, DIR/plot-<scenario>.png: success rate (the paper's verdict, with its 95 %
/// Wilson band, and ours) against person speed per mode; the visible ratio and the mean distance per trial
/// against speed as distributions (median, 10th-90th percentile band over the cell's trials).
/// Returns the file names written (relative to out_dir).
rt::Expected<std::vector<std::string>> writeSuitePlots(const std::string& out_dir, const SuiteSpec& suite,
                                                       const std::vector<CellResult>& results);

}  // namespace aerotrack::app
