// Where the shipped configuration lives: $AEROTRACK_CONFIG_DIR if set, else next to the binary
// (build/bin/aerotrack -> config/ of the source tree; /usr/local/bin -> /usr/local/share/aerotrack).
#pragma once

#include <string>

namespace aerotrack::app {

std::string configDir();

/// NAME -> <configDir>/scenarios/NAME.yaml; a path (contains '/' or ends in .yaml) is kept as is.
/// Where the converted models live: $AEROTRACK_MODEL_DIR if set, else models/ of the source tree
/// (next to config/), else <prefix>/share/aerotrack/models, else "models".
std::string modelDir();

std::string resolveScenario(const std::string& name_or_file);

}  // namespace aerotrack::app
