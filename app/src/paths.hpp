// Where the shipped configuration lives: $AEROTRACK_CONFIG_DIR if set, else next to the binary
// (build/bin/aerotrack -> config/ of the source tree; /usr/local/bin -> /usr/local/share/aerotrack).
#pragma once

#include <string>

namespace aerotrack::app {

std::string configDir();

/// NAME -> <configDir>/scenarios/NAME.yaml; a path (contains '/' or ends in .yaml) is kept as is.
std::string resolveScenario(const std::string& name_or_file);

}  // namespace aerotrack::app
