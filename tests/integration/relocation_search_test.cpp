// The relocation's search in the closed loop (issue 21 item 3), on the sim HAL in lockstep: the person is hidden
// (a forced occlusion) just before a building's corner, turns round it and stops behind it. The relocation's
// predicted path is cut short (relocate_timeout_s 1 s), so the drone is left before the corner: hovering there (no
// search: the scenario file's override of supervisor.search_timeout_s) it never sees the person again; searching, it
// flies to where they can be and finds them.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <optional>
#include <sstream>

#include "aerotrack/rt/lockstep_executor.hpp"
#include "app_config.hpp"
#include "sim_report.hpp"
#include "support/require.hpp"
#include "system.hpp"

namespace aerotrack::app {
namespace {

const std::string kSearchConfigDir = AEROTRACK_SOURCE_DIR "/config";

// config/sim.yaml with the localization path made absolute, the relocation cut to 1 s, the search's time-out set
// and the person hidden from the camera from 6 s to 8 s (they reach the corner at about 7.4 s).
std::string searchYaml(double search_timeout_s) {
  std::ifstream in(kSearchConfigDir + "/sim.yaml");
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  const auto replace = [&text](const std::string& from, const std::string& to) {
    const auto pos = text.find(from);
    EXPECT_NE(pos, std::string::npos) << from;
    if (pos != std::string::npos) text.replace(pos, from.size(), to);
  };
  replace("localization_params: localization.yaml", "localization_params: " + kSearchConfigDir + "/localization.yaml");
  replace("localization_params_image: localization_image.yaml",
          "localization_params_image: " + kSearchConfigDir + "/localization_image.yaml");
  replace("  relocate_timeout_s: 5.0", "  relocate_timeout_s: 1.0");
  replace("  search_timeout_s: 20.0", "  search_timeout_s: " + std::to_string(search_timeout_s));
  replace("  render_depth: true\n", "  render_depth: true\n  faults:\n    person_occluded_s: [6.0, 8.0]\n");
  return text;
}

struct SearchFlight {
  nlohmann::json summary;
  std::string mode;
};

// The config searches for 15 s; `scenario_search_timeout_s` (if given) overrides that in the scenario's file (its
// `supervisor:` section), as a scenario may.
SearchFlight flyCornerHide(std::optional<double> scenario_search_timeout_s) {
  auto config = parseAppConfig(searchYaml(15.0), "relocation_search.yaml");
  EXPECT_TRUE(config) << (config ? "" : config.error().message);
  std::string scenario = AEROTRACK_SOURCE_DIR "/tests/data/corner_hide.yaml";
  if (scenario_search_timeout_s) {
    std::ifstream in(scenario);
    std::stringstream text;
    text << in.rdbuf() << "supervisor:\n  search_timeout_s: " << *scenario_search_timeout_s << "\n";
    scenario = ::testing::TempDir() + "/corner_hide_override.yaml";
    std::ofstream(scenario) << text.str();
  }
  auto trial = loadTrial(scenario, 1, std::nullopt);
  EXPECT_TRUE(trial) << (trial ? "" : trial.error().message);
  if (!config || !trial) return {};
  auto system = System::build(*config, &trial.value(), 0);
  EXPECT_TRUE(system) << (system ? "" : system.error().message);
  if (!system) return {};
  rt::ManualClock clock(0);
  rt::MonotonicClock wall;
  rt::LockstepExecutor executor(clock, wall);
  for (const auto& b : (*system)->bindings()) EXPECT_TRUE(executor.add(b));
  // 16 s: the person stops behind the building at about 11.7 s; the search finds them by then.
  EXPECT_TRUE(executor.runUntil(rt::secondsToNs(std::min(16.0, trial->duration_s))));
  const hal::sim::Simulation& sim = aerotrack::test::require((*system)->devices().simulation.get(), "the simulation");
  RunInfo info;
  info.sim_time_s = rt::nsToSeconds(clock.now());
  info.supervisor = supervisorSummary((*system)->supervisorTask(), 0, 0.02);  // the supervisor runs at 50 Hz
  SearchFlight f;
  f.summary = simSummary(sim, info);
  const supervisor::SupervisorTask& sup = aerotrack::test::require((*system)->supervisorTask(), "the supervisor task");
  f.mode = supervisor::toString(sup.state().mode);
  return f;
}

TEST(ClosedLoopSearch, TheSearchFindsAPersonHiddenRoundACornerWhereTheHoverDoesNot) {
  const SearchFlight hover = flyCornerHide(0.0);  // the scenario says: no search, hold "person not found" at once
  // The forced occlusion's relocation ends in a hold, "not found", and no relocation searches. (Where the drone
  // ends depends on how well it kept up: since issue 21's goal lead it holds close enough to see the person
  // come out of the forced occlusion, and tracks again; the relocation itself found nobody. A later loss at the
  // corner may be found again on the relocation path itself -- since the depth camera ranges the person, issue
  // 22 -- but never by a search.)
  const nlohmann::json& hovered = hover.summary["supervisor"]["relocations"];
  ASSERT_FALSE(hovered.empty()) << hover.summary["supervisor"].dump(2);
  EXPECT_EQ(hovered[0]["outcome"], "not found") << hover.summary["supervisor"].dump(2);
  for (const nlohmann::json& r : hovered) {
    EXPECT_NE(r["outcome"], "found while searching") << hover.summary["supervisor"].dump(2);
    EXPECT_TRUE(r["search_s"].is_null());
  }
  EXPECT_GT(hover.summary["supervisor"]["seconds_in"]["hold"].get<double>(), 0.0);

  const SearchFlight search = flyCornerHide(std::nullopt);
  const nlohmann::json& relocations = search.summary["supervisor"]["relocations"];
  ASSERT_FALSE(relocations.empty()) << search.summary["supervisor"].dump(2);
  const nlohmann::json& r = relocations[0];
  EXPECT_EQ(r["outcome"], "found while searching") << search.summary["supervisor"].dump(2);
  EXPECT_TRUE(r["search_s"].is_number());
  EXPECT_LT(r["duration_s"].get<double>(), 1.5 + 15.0);
  EXPECT_EQ(search.mode, "track");
  EXPECT_EQ(search.summary["collisions"], 0);
}

}  // namespace
}  // namespace aerotrack::app
