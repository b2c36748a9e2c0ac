// Parameter sweeps (issue 25 item 1): `aerotrack bench --set KEY=V1,V2,...` (repeatable) runs every
// combination of the values (the cartesian product, first key slowest) as its own cell, each trial a
// `sim --set KEY=V ...`; the keys are any config key, checked by the config's own parser before a
// trial starts (rt::ConfigOverride).
#pragma once

#include <string>
#include <vector>

#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::app {

struct SweepKey {
  std::string key;
  std::vector<std::string> values;  ///< YAML texts, in the order given.
};

/// One combination: a value for every swept key, in the keys' order.
using SweepPoint = std::vector<rt::ConfigOverride>;

/// Parses "KEY=V1,V2,...": commas inside [], {} or quotes do not split ("k=[1, 2],[3, 4]" is two
/// values). Error (one line, naming the option) for no '=', a bad key path, an empty value, a value
/// given twice.
rt::Expected<SweepKey> parseSweepOption(const std::string& text);

/// The cartesian product of the keys' values, first key slowest; one empty point for no keys. Error if
/// a key is swept twice or the product has more than `max_points` points.
rt::Expected<std::vector<SweepPoint>> sweepPoints(const std::vector<SweepKey>& keys, std::size_t max_points);

/// A folder-safe name of a point: "planning.w=0.5+vehicle.max_speed_mps=3" with characters other than
/// letters, digits and ._=+- replaced by '_'. Empty for the empty point.
std::string sweepPointId(const SweepPoint& point);

/// "planning.w=0.5, vehicle.max_speed_mps=3" (for tables and legends).
std::string sweepPointLabel(const SweepPoint& point);

/// The `sim` options that apply a point: --set KEY=VALUE for each.
std::vector<std::string> sweepArgs(const SweepPoint& point);

}  // namespace aerotrack::app
