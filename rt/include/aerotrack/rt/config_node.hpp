// Strict reading of YAML configuration into typed structs. Every error names the file, the line
// and the full key path ("config/sim.yaml:14: tasks[2].rate_hz: expected a number, got 'fast'"):
// a missing key, a key nobody reads (unknown or misspelt), a wrong type, an out-of-range value.
// Nothing is silently defaulted: optional keys take their default in code, next to the reader
// call, and `aerotrack run --print-config` shows the effective values.
//
// Use: parse functions take a ConfigNode, read every key they know, then call finish(), which
// rejects the keys left over. Inside parsing, errors are thrown as ConfigError to keep the
// parsers linear; parseConfig() converts them to an Error value at the boundary (rule 6).
#pragma once

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <limits>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::rt {

/// An interval of numbers with open or closed ends ("[0, 1)"), for range checks that parsing and
/// validation share (field_table.hpp). Only finite numbers are ever inside: an infinite end means "no
/// bound on this side" and is written open ("(0, inf)"), so finite() admits every finite number.
struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = true;
  bool hi_open = true;

  static constexpr Range closed(double low, double high) { return {low, high, false, false}; }     ///< [low, high]
  static constexpr Range closedOpen(double low, double high) { return {low, high, false, true}; }  ///< [low, high)
  static constexpr Range openClosed(double low, double high) { return {low, high, true, false}; }  ///< (low, high]
  static constexpr Range open(double low, double high) { return {low, high, true, true}; }         ///< (low, high)
  static constexpr Range atLeast(double low) { return {low, std::numeric_limits<double>::infinity(), false, true}; }
  static constexpr Range greaterThan(double low) { return {low, std::numeric_limits<double>::infinity(), true, true}; }
  static constexpr Range finite() { return {}; }  ///< (-inf, inf)

  /// Whether `value` is finite and inside. Pure.
  bool contains(double value) const;
  /// "[0, 1)", "(0, inf)", "(-inf, inf)" (numbers as formatConfigNumber writes them).
  std::string toString() const;
};

/// A number for messages and printed configs: the %g form when it reads back as the same double
/// ("0.05", "1e+06", "100000"), else the shortest form that does ("0.9999999999999999"); "nan", "inf".
std::string formatConfigNumber(double value);

/// Thrown by ConfigNode while parsing; caught by parseConfig(). Do not let it escape a library.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One `--set KEY=VALUE` of the command line: KEY a key path as messages write it
/// ("planning.search.time_step_s", "tasks[2].rate_hz"), VALUE YAML text ("0.05", "true", "[1, 2]").
/// The value replaces the file's (or adds the key to a map that exists), and is then read and checked
/// by the same parser as the file: a misspelt key is an unknown key, a bad value is out of range.
struct ConfigOverride {
  std::string key;
  std::string value;
};

/// Splits "KEY=VALUE" at the first '='. Error ("--set: ...") if there is none or KEY is empty or
/// not a key path (words of letters, digits, '_' and '-', joined by '.', each with optional [i]).
Expected<ConfigOverride> parseConfigOverride(const std::string& assignment);

class ConfigNode {
 public:
  /// Reads and parses a YAML file, then applies `overrides` in order. Error if it is missing,
  /// unreadable or not valid YAML, or an override's path does not lead into the file (a missing
  /// parent map, a list index out of range) or its value is not valid YAML. Messages about a key an
  /// override set say "--set KEY" instead of the file and line.
  static Expected<ConfigNode> loadFile(const std::string& path, const std::vector<ConfigOverride>& overrides = {});
  /// Parses YAML text; source_name stands for the file name in messages.
  static Expected<ConfigNode> fromString(const std::string& text, const std::string& source_name,
                                         const std::vector<ConfigOverride>& overrides = {});

  bool has(const std::string& key) const;
  /// Whether the key is present and a list (for keys that take a scalar or a list).
  bool isList(const std::string& key) const;

  // Required scalars. Throw ConfigError if missing, of the wrong type or outside [min, max].
  double getDouble(const std::string& key, double min, double max) const;
  /// As above, in `range` ("key: 1 is out of range [0, 1)").
  double getDouble(const std::string& key, const Range& range) const;
  int getInt(const std::string& key, int min, int max) const;
  std::uint64_t getUint64(const std::string& key) const;
  bool getBool(const std::string& key) const;
  std::string getString(const std::string& key) const;
  /// A string that must be one of `allowed`. If "null" is allowed, a YAML null means "null".
  std::string getEnum(const std::string& key, std::initializer_list<const char*> allowed) const;
  std::string getEnum(const std::string& key, const std::vector<std::string>& allowed) const;
  /// A non-empty list of strings, each one of `allowed`, no repeats ("modes: [proposed, baseline]").
  std::vector<std::string> getEnumList(const std::string& key, const std::vector<std::string>& allowed) const;
  /// A list of exactly `size` numbers (any size if size == 0), each in [min, max].
  std::vector<double> getDoubleList(const std::string& key, std::size_t size, double min, double max) const;
  /// As above, each in `range`.
  std::vector<double> getDoubleList(const std::string& key, std::size_t size, const Range& range) const;
  /// A list of rows, each a list of exactly `columns` numbers in [min, max] ("[[0, 0, 1], [5, 0, 1]]").
  std::vector<std::vector<double>> getDoubleRows(const std::string& key, std::size_t columns, double min,
                                                 double max) const;

  // Optional scalars: the default applies only when the key is absent; a present key is checked.
  double getDoubleOr(const std::string& key, double fallback, double min, double max) const;
  int getIntOr(const std::string& key, int fallback, int min, int max) const;
  bool getBoolOr(const std::string& key, bool fallback) const;
  std::string getStringOr(const std::string& key, const std::string& fallback) const;

  /// A required nested map.
  ConfigNode child(const std::string& key) const;
  /// A required list of maps ("tasks: [ {...}, {...} ]"). May be empty.
  std::vector<ConfigNode> childList(const std::string& key) const;

  /// Rejects keys of this map that no getter asked for. Call after reading a map.
  void finish() const;

  /// Throws a ConfigError about `key` of this node (for checks across several keys).
  [[noreturn]] void fail(const std::string& key, const std::string& message) const;

  /// "file:line: path" of this node, for messages.
  std::string where() const;
  const std::string& sourceName() const { return *source_; }

 private:
  ConfigNode(const YAML::Node& node, std::shared_ptr<const std::string> source, std::string path,
             std::shared_ptr<const std::set<std::string>> overridden);
  YAML::Node require(const std::string& key) const;
  std::string keyPath(const std::string& key) const;
  std::string locate(const YAML::Node& node, const std::string& key) const;
  std::string locateAt(const YAML::Node& node, const std::string& full_path) const;
  template <class T>
  T scalarAs(const std::string& key, const YAML::Node& value, const char* what) const;

  YAML::Node node_;
  std::shared_ptr<const std::string> source_;
  std::string path_;
  std::shared_ptr<std::set<std::string>> used_;              // shared so copies of a node agree
  std::shared_ptr<const std::set<std::string>> overridden_;  // key paths set by --set (and everything under them)
};

/// Runs a parse function and turns a thrown ConfigError into an Error value. A YAML exception that a
/// reader let through (a conversion on an unexpected node) becomes one too, rather than terminate.
template <class T>
Expected<T> parseConfig(const std::function<T()>& parse) {
  try {
    return parse();
  } catch (const ConfigError& error) {
    return Error{error.what()};
  } catch (const YAML::Exception& error) {
    return Error{"YAML: " + error.msg};
  }
}

}  // namespace aerotrack::rt
