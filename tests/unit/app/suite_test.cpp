// Benchmark suites without running a simulation: parsing and its errors, which trials remain when a
// suite is resumed (fake summary files), and the report and plots from synthetic summaries.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "bench_stats.hpp"
#include "suite.hpp"
#include "support/temp_dir.hpp"

namespace aerotrack::app {
namespace {

rt::Expected<SuiteSpec> suiteFrom(const std::string& yaml) {
  return parseSuite(rt::ConfigNode::fromString(yaml, "suite.yaml"));
}

void writeFile(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path) << text;
}

TEST(SuiteParse, GivenMatrixThenCellsExpandInFileOrder) {
  const auto s = suiteFrom(R"(name: t1
seeds: 20
targets: {followed_rate: 0.8}
cells:
  - {scenario: sharp_turn, speeds: [0.85, 1.5], modes: [proposed, baseline]}
  - {scenario: forest, modes: [baseline], camera: image, config: config/sim.yaml}
)");
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->name, "t1");
  EXPECT_EQ(s->first_seed, 1);
  EXPECT_EQ(s->last_seed, 20);
  ASSERT_TRUE(s->targets.followed_rate);
  EXPECT_DOUBLE_EQ(*s->targets.followed_rate, 0.8);
  EXPECT_FALSE(s->targets.success_rate);
  ASSERT_EQ(s->cells.size(), 5U);
  EXPECT_EQ(s->cells[0].id, "sharp_turn-0.85mps-proposed-keypoints");
  EXPECT_EQ(s->cells[1].id, "sharp_turn-0.85mps-baseline-keypoints");
  EXPECT_EQ(s->cells[3].id, "sharp_turn-1.5mps-baseline-keypoints");
  EXPECT_DOUBLE_EQ(*s->cells[3].speed_mps, 1.5);
  EXPECT_EQ(s->cells[4].id, "forest-own-baseline-image-sim");
  EXPECT_FALSE(s->cells[4].speed_mps);
  EXPECT_EQ(s->cells[4].config, "config/sim.yaml");
}

TEST(SuiteParse, GivenSeedRangeThenFirstAndLast) {
  const auto s = suiteFrom("name: r\nseeds: [5, 9]\ncells: [{scenario: open, modes: [proposed]}]\n");
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->first_seed, 5);
  EXPECT_EQ(s->last_seed, 9);
}

TEST(SuiteParse, GivenBadInputThenOneLineNamingFileLineAndKey) {
  const std::string cell = "cells: [{scenario: open, modes: [proposed]}]\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"name: x\nseeds: 0\n" + cell, "seeds"},
      {"name: x\nseeds: [9, 5]\n" + cell, "seeds"},
      {"name: x\nseeds: [1.5, 5]\n" + cell, "seeds"},
      {"name: x\nseeds: 3\ncells: []\n", "cells"},
      {"name: x\nseeds: 3\n", "cells"},
      {"name: x\nseeds: 3\ncolor: red\n" + cell, "color"},
      {"name: x\nseeds: 3\ncells: [{scenario: open, modes: [proposed, fast]}]\n", "modes"},
      {"name: x\nseeds: 3\ncells: [{scenario: open, modes: [proposed, proposed]}]\n", "modes"},
      {"name: x\nseeds: 3\ncells: [{scenario: open, modes: []}]\n", "modes"},
      {"name: x\nseeds: 3\ncells: [{scenario: open}]\n", "modes"},
      {"name: x\nseeds: 3\ncells: [{scenario: open, modes: [proposed], speeds: [0.0]}]\n", "speeds"},
      {"name: x\nseeds: 3\ncells: [{scenario: open, modes: [proposed], speeds: [25]}]\n", "speeds"},
      {"name: x\nseeds: 3\ncells: [{scenario: open, modes: [proposed], camera: lidar}]\n", "camera"},
      {"name: x\nseeds: 3\ncells: [{scenario: open, modes: [proposed], seeds: 4}]\n", "seeds"},
      {"name: x\nseeds: 3\ntargets: {followed_rate: 1.2}\n" + cell, "followed_rate"},
      {"name: x\nseeds: 3\ncells: [{scenario: open, modes: [proposed]}, {scenario: open, modes: [proposed]}]\n",
       "appears twice"},
  };
  for (const auto& [yaml, key] : cases) {
    const auto s = suiteFrom(yaml);
    ASSERT_FALSE(s) << yaml;
    const std::string& message = s.error().message;
    EXPECT_NE(message.find("suite.yaml:"), std::string::npos) << message;
    EXPECT_NE(message.find(key), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

const char* kCompleteSummary = R"({"seed": 1, "success": true, "followed_all_the_way": false})";

TEST(SuiteResume, GivenSomeTrialsCompleteThenOnlyTheOthersRemain) {
  test::TempDir dir;
  SuiteCell cell;
  cell.id = "sharp_turn-0.85mps-proposed-keypoints";
  writeFile(trialDir(dir.path(), cell, 1) + "/summary.json", kCompleteSummary);
  writeFile(trialDir(dir.path(), cell, 2) + "/summary.json", R"({"seed": 2, "succ)");  // cut off mid-write
  writeFile(trialDir(dir.path(), cell, 3) + "/summary.json",
            R"({"seed": 3, "success": false, "interrupted": true})");  // stopped by SIGTERM
  writeFile(trialDir(dir.path(), cell, 4) + "/log.txt", "started, no summary");
  writeFile(trialDir(dir.path(), cell, 5) + "/summary.json", kCompleteSummary);
  writeFile(trialDir(dir.path(), cell, 6) + "/summary.json", "[1, 2]");  // not an object
  EXPECT_TRUE(trialComplete(trialDir(dir.path(), cell, 1)));
  EXPECT_FALSE(trialComplete(trialDir(dir.path(), cell, 2)));
  EXPECT_EQ(remainingSeeds(dir.path(), cell, 1, 7), (std::vector<std::int64_t>{2, 3, 4, 6, 7}));
  EXPECT_EQ(remainingSeeds(dir.path(), cell, 5, 5), (std::vector<std::int64_t>{}));
  SuiteCell other = cell;
  other.id = "sharp_turn-0.85mps-baseline-keypoints";  // another cell's folder: nothing done there
  EXPECT_EQ(remainingSeeds(dir.path(), other, 1, 2), (std::vector<std::int64_t>{1, 2}));
}

TEST(SuiteResume, GivenMissingScenarioFileThenCellError) {
  SuiteCell cell;
  cell.scenario = "/nonexistent/no_such_scenario.yaml";
  EXPECT_NE(cellError(cell).find("/nonexistent/no_such_scenario.yaml does not exist"), std::string::npos);
}

std::string syntheticSummary(int seed, bool success, bool followed, double visible, double distance_m) {
  return nlohmann::json({{"seed", seed},
                         {"success", success},
                         {"followed_all_the_way", followed},
                         {"follow_failure_reason", followed ? nlohmann::json(nullptr) : nlohmann::json("lost")},
                         {"visible_ratio", visible},
                         {"distance_mean_m", distance_m},
                         {"min_clearance_m", 0.4},
                         {"identity_switches", seed % 2},
                         {"time_on_wrong_person_s", 0.6 * (seed % 2)},
                         {"person_top_speed_mps", 1.5},
                         {"person_mean_speed_mps", 1.25}})
      .dump();
}

TEST(SuiteReport, GivenSyntheticSummariesThenTablesIntervalsErrorsAndPlots) {
  test::TempDir dir;
  const auto suite = suiteFrom(R"(name: synth
seeds: 4
targets: {followed_rate: 0.9}
cells:
  - {scenario: sharp_turn, speeds: [0.85, 1.5], modes: [proposed, baseline]}
  - {scenario: crowd, modes: [proposed]}
)");
  ASSERT_TRUE(suite) << suite.error().message;
  std::vector<std::string> errors(suite->cells.size());
  for (std::size_t c = 0; c < 4; ++c) {  // the sharp_turn cells: proposed all followed, baseline 2 of 4
    const bool baseline = suite->cells[c].mode == "baseline";
    for (int seed = 1; seed <= 4; ++seed) {
      if (c == 3 && seed == 4) continue;  // one trial without a result
      writeFile(trialDir(dir.path(), suite->cells[c], seed) + "/summary.json",
                syntheticSummary(seed, true, !baseline || seed <= 2, baseline ? 0.6 : 0.9, baseline ? 4.0 : 3.0));
    }
  }
  errors[4] = "scenario file config/scenarios/crowd.yaml does not exist";
  const std::vector<CellResult> results = collectResults(dir.path(), *suite, errors);
  ASSERT_EQ(results.size(), 5U);
  EXPECT_EQ(results[0].summaries.size(), 4U);
  EXPECT_EQ(results[3].missing_seeds, (std::vector<std::int64_t>{4}));

  const nlohmann::json json = suiteJson(*suite, results);
  EXPECT_EQ(json["cells"][1]["stats"]["followed_all_the_way"], 2);
  EXPECT_EQ(json["cells"][1]["stats"]["successes"], 4);
  EXPECT_EQ(json["cells"][4]["error"], errors[4]);
  EXPECT_EQ(json["cells"][0]["trials"].size(), 4U);

  const auto plots = writeSuitePlots(dir.path(), *suite, results);
  ASSERT_TRUE(plots) << plots.error().message;
  EXPECT_EQ(*plots, (std::vector<std::string>{"plot-sharp_turn.png"}));  // crowd has no results
  EXPECT_TRUE(std::filesystem::file_size(dir.path() + "/plot-sharp_turn.png") > 1000);

  const std::string md = suiteReport(*suite, results, *plots);
  const ProportionInterval half = wilsonInterval(2, 4), all = wilsonInterval(4, 4);
  char expected[128];
  std::snprintf(expected, sizeof(expected), "🔴 2/4 = 0.50 [%.2f, %.2f]", half.lo, half.hi);
  EXPECT_NE(md.find(expected), std::string::npos) << md;  // baseline at 0.85 m/s, under the 0.9 target
  std::snprintf(expected, sizeof(expected), "| 0.85 m/s | proposed | keypoints | 4/4 = 1.00 [%.2f, 1.00]", all.lo);
  EXPECT_NE(md.find(expected), std::string::npos) << md;
  EXPECT_NE(md.find("## crowd"), std::string::npos);
  EXPECT_NE(md.find("**error** crowd-own-proposed-keypoints: scenario file config/scenarios/crowd.yaml does not exist"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("sharp_turn-1.5mps-baseline-keypoints: 1 trial(s) without a result"), std::string::npos) << md;
  EXPECT_NE(md.find("| 2/4 | 0.3 s | 1.50 / 1.25 m/s |"), std::string::npos) << md;  // seeds 1, 3 switch once
  EXPECT_NE(md.find("![sharp_turn](plot-sharp_turn.png)"), std::string::npos);
}

}  // namespace
}  // namespace aerotrack::app
