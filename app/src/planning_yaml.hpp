// The `planning:` section as YAML, for --print-config: the planner's field table prints it
// (planning::trackingPlannerFields(), the same table that parses it back to the same parameters).
#pragma once

#include <yaml-cpp/yaml.h>

#include "aerotrack/planning/tracking_planner.hpp"

namespace aerotrack::app {

/// Writes `p` as a YAML map (every key, table order, numbers exact) at the emitter's current position.
void emitPlanningYaml(YAML::Emitter& out, const planning::TrackingPlannerParams& p);

}  // namespace aerotrack::app
