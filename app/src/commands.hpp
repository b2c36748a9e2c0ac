// The subcommands that have landed. Each returns the process exit status and prints its own
// one-line errors (the app is where printing happens, DESIGN.md rule 6).
#pragma once

#include <string>

#include <vector>

#include "aerotrack/rt/config_node.hpp"
#include "cli.hpp"

namespace aerotrack::app {

int runCommand(const ParsedArgs& args);
int simCommand(const ParsedArgs& args);
int replayCommand(const ParsedArgs& args);
int importVideoCommand(const ParsedArgs& args);
int exportMcapCommand(const ParsedArgs& args);
int benchCommand(const ParsedArgs& args);
int benchMergeCommand(const ParsedArgs& args);
/// The --set KEY=VALUE options of run, sim and replay, parsed (rt::ConfigOverride).
rt::Expected<std::vector<rt::ConfigOverride>> configOverrides(const ParsedArgs& args);
int detectCommand(const ParsedArgs& args);
int datasetCommand(const ParsedArgs& args);
int calibrateCommand(const ParsedArgs& args);
int evalLocalizationCommand(const ParsedArgs& args);

/// Prints "aerotrack <command>: <message>" on stderr and returns the failing exit status, 1.
int failCommand(const char* command, const std::string& message);

}  // namespace aerotrack::app
