// Command-line parsing for `aerotrack <command> [options]` (DESIGN.md, "The command line").
// Strict: an unknown option, a missing value, a missing required option or a bad number is a
// one-line error. No globals: the command table is data passed in.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::app {

struct OptionSpec {
  std::string name;        ///< Without the leading "--".
  std::string value_name;  ///< Empty: a flag without value.
  bool required = false;
  std::string help;
  bool repeatable = false;  ///< May be given more than once (ParsedArgs::lists keeps every value in order).
};

struct CommandSpec {
  std::string name;  ///< One word, or two for a sub-command ("bench merge").
  std::string summary;
  std::string positional;  ///< Name of the one positional argument ("IMAGE|VIDEO"), empty if none.
  std::vector<OptionSpec> options;
  std::string landed_in;  ///< Non-empty: the capability has not landed; names the issue that brings it.
};

struct ParsedArgs {
  std::string command;
  std::optional<std::string> positional;
  std::map<std::string, std::string> values;
  std::map<std::string, std::vector<std::string>> lists;  ///< Repeatable options, every value in order.
  std::set<std::string> flags;
  bool help = false;

  bool has(const std::string& name) const {
    return values.count(name) != 0 || flags.count(name) != 0 || lists.count(name) != 0;
  }
  std::string valueOr(const std::string& name, const std::string& fallback) const;
  /// A repeatable option's values (empty if not given).
  std::vector<std::string> listOf(const std::string& name) const;
};

/// The commands of DESIGN.md.
std::vector<CommandSpec> commandTable();

/// Parses argv[1..]. `--help` anywhere sets help (the command may be empty for the top level).
rt::Expected<ParsedArgs> parseArgs(const std::vector<std::string>& args, const std::vector<CommandSpec>& table);

std::string usage(const std::vector<CommandSpec>& table);
std::string usage(const CommandSpec& command);

/// Parses a number option; error names the option ("--seed: expected an integer ...").
rt::Expected<double> parseDouble(const std::string& option, const std::string& text, double min, double max);
rt::Expected<std::int64_t> parseInt(const std::string& option, const std::string& text, std::int64_t min,
                                    std::int64_t max);

}  // namespace aerotrack::app
