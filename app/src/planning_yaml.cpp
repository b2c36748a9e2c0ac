// The planning section as YAML: see planning_yaml.hpp.
#include "planning_yaml.hpp"

namespace aerotrack::app {

void emitPlanningYaml(YAML::Emitter& out, const planning::TrackingPlannerParams& p) {
  planning::trackingPlannerFields().emit(out, p);
}

}  // namespace aerotrack::app
