// The `planning:` section as YAML, for --print-config (parses back to the same parameters:
// planning::parseTrackingPlannerParams).
#pragma once

#include <yaml-cpp/yaml.h>

#include "aerotrack/planning/tracking_planner.hpp"

namespace aerotrack::app {

void emitPlanningYaml(YAML::Emitter& out, const planning::TrackingPlannerParams& p);

}  // namespace aerotrack::app
