// The task registry (app/src/system.cpp): the names the task table may use are exactly the tasks the
// system can build. Given / when / then: every name of every shipped task table is known, every known
// name builds on the simulator, and a simulator-only task is refused without one.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "app_config.hpp"
#include "sim_report.hpp"
#include "system.hpp"

namespace aerotrack::app {
namespace {

const std::string kShippedConfigs = AEROTRACK_SOURCE_DIR "/config";

bool known(const std::string& name) {
  const std::vector<std::string> names = System::knownTasks();
  return std::find(names.begin(), names.end(), name) != names.end();
}

TEST(TaskRegistry, GivenTheShippedTaskTablesThenEveryNameIsKnown) {
  for (const char* file : {"sim.yaml", "null.yaml", "drone.yaml"}) {
    const auto config = loadAppConfig(kShippedConfigs + "/" + file);
    ASSERT_TRUE(config) << config.error().message;
    for (const rt::TaskSpec& spec : config->tasks) EXPECT_TRUE(known(spec.name)) << file << ": " << spec.name;
  }
}

TEST(TaskRegistry, GivenTheKnownNamesThenEachIsListedOnce) {
  std::vector<std::string> names = System::knownTasks();
  ASSERT_FALSE(names.empty());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(std::adjacent_find(names.begin(), names.end()), names.end());
}

TEST(TaskRegistry, GivenEachKnownNameThenItBuildsOnTheSimulator) {
  const auto config = loadAppConfig(kShippedConfigs + "/sim.yaml");
  ASSERT_TRUE(config) << config.error().message;
  auto trial = loadTrial(AEROTRACK_SOURCE_DIR "/config/scenarios/open.yaml", 1, std::nullopt);
  ASSERT_TRUE(trial) << trial.error().message;
  const rt::TaskSpec world = config->tasks.front();
  ASSERT_EQ(world.name, "sim_world");
  for (const std::string& name : System::knownTasks()) {
    AppConfig one = *config;
    one.tasks = {world};
    if (name != world.name) {
      rt::TaskSpec spec = world;
      spec.name = name;
      one.tasks.push_back(spec);
    }
    const auto system = System::build(one, &trial.value(), 0);
    ASSERT_TRUE(system) << name << ": " << system.error().message;
    EXPECT_EQ((*system)->bindings().back().spec.name, name);
  }
}

TEST(TaskRegistry, GivenASimulatorOnlyTaskWithoutTheSimulatorThenItIsRefused) {
  auto config = loadAppConfig(kShippedConfigs + "/null.yaml");
  ASSERT_TRUE(config) << config.error().message;
  rt::TaskSpec spec = config->tasks.front();
  spec.name = "camera_strip";
  config->tasks.push_back(spec);
  const auto system = System::build(*config, nullptr, 0);
  ASSERT_FALSE(system);
  EXPECT_NE(system.error().message.find("task 'camera_strip' needs a sim backend in hal"), std::string::npos)
      << system.error().message;
}

}  // namespace
}  // namespace aerotrack::app
