// Strict YAML reading: see config_node.hpp.
#include "aerotrack/rt/config_node.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <locale>
#include <map>
#include <sstream>
#include <string_view>

#include "aerotrack/rt/input_file.hpp"
#include "aerotrack/rt/input_limits.hpp"

namespace aerotrack::rt {
namespace {

/// yaml-cpp keeps both entries of a key given twice and returns the first: a second value, often
/// the one meant, would be silently ignored. Walks every map of the document.
Status checkUniqueKeys(const YAML::Node& node, const std::string& source, const std::string& path) {
  if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      if (auto status = checkUniqueKeys(node[i], source, path + "[" + std::to_string(i) + "]"); !status) return status;
    }
  }
  if (!node.IsMap()) return ok();
  std::map<std::string, int> first_line;
  for (const auto& entry : node) {
    const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : std::string("<complex key>");
    std::string key_path = path;
    if (!key_path.empty()) key_path += '.';
    key_path += key;
    const int line = entry.first.Mark().is_null() ? 0 : entry.first.Mark().line + 1;
    if (const auto [it, inserted] = first_line.emplace(key, line); !inserted) {
      std::string message = source;
      message.append(":").append(std::to_string(line)).append(": ").append(key_path);
      message.append(": given twice (first on line ").append(std::to_string(it->second)).append(")");
      return Error{message};
    }
    if (auto status = checkUniqueKeys(entry.second, source, key_path); !status) return status;
  }
  return ok();
}

/// One step of an override's key path: a map key, or a list index (key empty).
struct PathStep {
  std::string key;
  std::size_t index = 0;
};

/// "tasks[2].rate_hz" -> tasks, [2], rate_hz. Empty if the text is not a key path.
std::vector<PathStep> splitKeyPath(const std::string& path) {
  std::vector<PathStep> steps;
  std::size_t i = 0;
  const auto word_char = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  };
  while (i < path.size()) {
    const std::size_t start = i;
    while (i < path.size() && word_char(path[i])) ++i;
    if (i == start) return {};
    steps.push_back({path.substr(start, i - start), 0});
    while (i < path.size() && path[i] == '[') {
      const std::size_t close = path.find(']', i);
      if (close == std::string::npos || close == i + 1 || close - i > 7) return {};
      std::size_t index = 0;
      for (std::size_t k = i + 1; k < close; ++k) {
        if (path[k] < '0' || path[k] > '9') return {};
        index = index * 10 + static_cast<std::size_t>(path[k] - '0');
      }
      steps.push_back({"", index});
      i = close + 1;
    }
    if (i == path.size()) break;
    if (path[i] != '.' || i + 1 == path.size()) return {};
    ++i;
  }
  return steps;
}

/// Puts `value` at `key_path` of `root`: every step but the last must exist; the last may add a key
/// to a map (the parser then accepts or rejects it like any key of the file).
Status applyOverride(YAML::Node& root, const ConfigOverride& o, const std::string& source) {
  const std::string what = "--set " + o.key;
  const std::vector<PathStep> steps = splitKeyPath(o.key);
  if (steps.empty()) return Error{what + ": not a key path (expected words joined by '.', e.g. planning.rate_hz)"};
  YAML::Node value;
  try {
    value = YAML::Load(o.value);
  } catch (const YAML::Exception& e) {
    return Error{what + ": invalid YAML value '" + o.value + "': " + e.msg};
  }
  // yaml-cpp: `node = other` would overwrite the referenced node's content; reset() rebinds.
  YAML::Node at;
  at.reset(root);
  std::string reached;  // the path walked so far, as messages write it
  const auto failure = [&](std::initializer_list<std::string_view> parts) {
    std::string message = what;
    message += ": ";
    for (const std::string_view part : parts) message += part;
    return Error{message};
  };
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const PathStep& step = steps[i];
    const bool last = i + 1 == steps.size();
    if (!step.key.empty()) {
      if (!at.IsMap()) return failure({reached.empty() ? source : reached, " is not a map of keys in ", source});
      if (last) {
        at[step.key] = value;
        return ok();
      }
      if (!at[step.key].IsDefined())
        return failure({source, " has no key ", reached, reached.empty() ? "" : ".", step.key});
      at.reset(at[step.key]);
      if (!reached.empty()) reached += '.';
      reached += step.key;
    } else {
      const std::string index = std::to_string(step.index);
      if (!at.IsSequence() || step.index >= at.size())
        return failure({reached, " has no item [", index, "] in ", source});
      if (last) {
        at[step.index] = value;
        return ok();
      }
      at.reset(at[step.index]);
      reached += '[';
      reached += index;
      reached += ']';
    }
  }
  return ok();
}

std::string shortValue(const YAML::Node& value) {
  if (value.IsScalar()) return "'" + value.Scalar() + "'";
  if (value.IsMap()) return "a map";
  if (value.IsSequence()) return "a list";
  return "nothing";
}

}  // namespace

std::string formatConfigNumber(double value) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << value;
  std::string text = out.str();
  if (!std::isfinite(value) || std::strtod(text.c_str(), nullptr) == value) return text;
  std::array<char, 32> buffer{};
  const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return ec == std::errc() ? std::string(buffer.data(), end) : text;
}

bool Range::contains(double value) const {
  return std::isfinite(value) && (lo_open ? value > lo : value >= lo) && (hi_open ? value < hi : value <= hi);
}

std::string Range::toString() const {
  const bool lo_excluded = lo_open || !std::isfinite(lo);
  const bool hi_excluded = hi_open || !std::isfinite(hi);
  return (lo_excluded ? "(" : "[") + formatConfigNumber(lo) + ", " + formatConfigNumber(hi) + (hi_excluded ? ")" : "]");
}

Expected<ConfigOverride> parseConfigOverride(const std::string& assignment) {
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos) return Error{"--set: expected KEY=VALUE, got '" + assignment + "'"};
  ConfigOverride o{assignment.substr(0, eq), assignment.substr(eq + 1)};
  if (splitKeyPath(o.key).empty())
    return Error{"--set: '" + o.key + "' is not a key path (expected words joined by '.', e.g. planning.rate_hz)"};
  return o;
}

ConfigNode::ConfigNode(const YAML::Node& node, std::shared_ptr<const std::string> source, std::string path,
                       std::shared_ptr<const std::set<std::string>> overridden)
    : node_(node),
      source_(std::move(source)),
      path_(std::move(path)),
      used_(std::make_shared<std::set<std::string>>()),
      overridden_(std::move(overridden)) {}

Expected<ConfigNode> ConfigNode::fromString(const std::string& text, const std::string& source_name,
                                            const std::vector<ConfigOverride>& overrides) {
  auto source = std::make_shared<const std::string>(source_name);
  auto overridden = std::make_shared<std::set<std::string>>();
  try {
    YAML::Node root = YAML::Load(text);
    if (!root.IsMap()) return Error{source_name + ": the top level must be a map of keys"};
    if (auto status = checkUniqueKeys(root, source_name, ""); !status) return status.error();
    for (const ConfigOverride& o : overrides) {
      if (auto status = applyOverride(root, o, source_name); !status) return status.error();
      overridden->insert(o.key);
    }
    return ConfigNode(root, source, "", overridden);
  } catch (const YAML::Exception& e) {
    return Error{source_name + ":" + std::to_string(e.mark.line + 1) + ": invalid YAML: " + e.msg};
  }
}

Expected<ConfigNode> ConfigNode::loadFile(const std::string& path, const std::vector<ConfigOverride>& overrides) {
  Expected<std::string> text = readBoundedFile(path, limits::kMaxYamlBytes);
  if (!text) return text.error();
  return fromString(text.value(), path, overrides);
}

std::string ConfigNode::keyPath(const std::string& key) const {
  if (key.empty()) return path_;
  return path_.empty() ? key : path_ + "." + key;
}

std::string ConfigNode::locateAt(const YAML::Node& node, const std::string& full_path) const {
  // A value from the command line has no line in the file: name the --set that gave it.
  for (const std::string& set : *overridden_) {
    if (full_path.compare(0, set.size(), set) == 0 &&
        (full_path.size() == set.size() || full_path[set.size()] == '.' || full_path[set.size()] == '['))
      return "--set " + full_path;
  }
  const YAML::Mark mark = node.Mark();
  std::string out = *source_;
  if (!mark.is_null()) out += ":" + std::to_string(mark.line + 1);
  return full_path.empty() ? out : out + ": " + full_path;
}

std::string ConfigNode::locate(const YAML::Node& node, const std::string& key) const {
  return locateAt(node, keyPath(key));
}

std::string ConfigNode::where() const {
  return locate(node_, "");
}

void ConfigNode::fail(const std::string& key, const std::string& message) const {
  const YAML::Node value = node_.IsMap() ? node_[key] : YAML::Node();
  throw ConfigError(locate(value.IsDefined() ? value : node_, key) + ": " + message);
}

bool ConfigNode::has(const std::string& key) const {
  return node_.IsMap() && node_[key].IsDefined();
}

YAML::Node ConfigNode::require(const std::string& key) const {
  used_->insert(key);
  const YAML::Node value = node_[key];
  if (!value.IsDefined()) throw ConfigError(locate(node_, key) + ": missing required key");
  if (value.IsNull()) fail(key, "has no value");
  return value;
}

template <class T>
T ConfigNode::scalarAs(const std::string& key, const YAML::Node& value, const char* what) const {
  if (!value.IsScalar()) fail(key, std::string("expected ") + what + ", got " + shortValue(value));
  try {
    return value.as<T>();
  } catch (const YAML::Exception&) {
    fail(key, std::string("expected ") + what + ", got " + shortValue(value));
  }
}

double ConfigNode::getDouble(const std::string& key, double min, double max) const {
  return getDouble(key, Range::closed(min, max));
}

double ConfigNode::getDouble(const std::string& key, const Range& range) const {
  const double v = scalarAs<double>(key, require(key), "a number");
  if (!range.contains(v)) fail(key, formatConfigNumber(v) + " is out of range " + range.toString());
  return v;
}

int ConfigNode::getInt(const std::string& key, int min, int max) const {
  const int v = scalarAs<int>(key, require(key), "an integer");
  if (v < min || v > max)
    fail(key, std::to_string(v) + " is out of range [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  return v;
}

std::uint64_t ConfigNode::getUint64(const std::string& key) const {
  const YAML::Node value = require(key);
  if (value.IsScalar() && !value.Scalar().empty() && value.Scalar()[0] == '-')
    fail(key, "expected a non-negative integer, got " + shortValue(value));
  return scalarAs<std::uint64_t>(key, value, "a non-negative integer");
}

bool ConfigNode::getBool(const std::string& key) const {
  return scalarAs<bool>(key, require(key), "true or false");
}

std::string ConfigNode::getString(const std::string& key) const {
  return scalarAs<std::string>(key, require(key), "a string");
}

std::string ConfigNode::getEnum(const std::string& key, std::initializer_list<const char*> allowed) const {
  return getEnum(key, std::vector<std::string>(allowed.begin(), allowed.end()));
}

std::string ConfigNode::getEnum(const std::string& key, const std::vector<std::string>& allowed) const {
  // YAML reads a bare `null` as "no value"; where "null" is an allowed name (null backends), it
  // means that name.
  const YAML::Node raw = node_.IsMap() ? node_[key] : YAML::Node();
  const bool null_allowed = std::find(allowed.begin(), allowed.end(), "null") != allowed.end();
  if (null_allowed && raw.IsDefined() && raw.IsNull()) {
    used_->insert(key);
    return "null";
  }
  std::string v = getString(key);
  std::string list;
  for (const std::string& a : allowed) {
    if (v == a) return v;
    list += list.empty() ? a : ", " + a;
  }
  fail(key, "'" + v + "' is not one of: " + list);
}

bool ConfigNode::isList(const std::string& key) const {
  return node_.IsMap() && node_[key].IsDefined() && node_[key].IsSequence();
}

std::vector<std::string> ConfigNode::getEnumList(const std::string& key,
                                                 const std::vector<std::string>& allowed) const {
  const YAML::Node value = require(key);
  if (!value.IsSequence() || value.size() == 0)
    fail(key, "expected a non-empty list of names, got " + shortValue(value));
  std::string names;
  for (const std::string& a : allowed) {
    if (!names.empty()) names += ", ";
    names += a;
  }
  const std::string not_allowed = "' is not one of: " + names;
  const auto item = [](std::size_t i, const std::string& v, const std::string& what) {
    std::string message = "item ";
    message += std::to_string(i);
    message += ": '";
    message += v;
    message += what;
    return message;
  };
  std::vector<std::string> out;
  for (std::size_t i = 0; i < value.size(); ++i) {
    std::string index_key = key;
    index_key += '[';
    index_key += std::to_string(i);
    index_key += ']';
    const std::string v = scalarAs<std::string>(index_key, value[i], "a name");
    if (std::find(allowed.begin(), allowed.end(), v) == allowed.end()) fail(key, item(i, v, not_allowed));
    if (std::find(out.begin(), out.end(), v) != out.end()) fail(key, item(i, v, "' is repeated"));
    out.push_back(v);
  }
  return out;
}

std::vector<double> ConfigNode::getDoubleList(const std::string& key, std::size_t size, double min, double max) const {
  return getDoubleList(key, size, Range::closed(min, max));
}

std::vector<double> ConfigNode::getDoubleList(const std::string& key, std::size_t size, const Range& range) const {
  const YAML::Node value = require(key);
  if (!value.IsSequence()) fail(key, "expected a list of numbers, got " + shortValue(value));
  if (size != 0 && value.size() != size)
    fail(key, "expected " + std::to_string(size) + " numbers, got " + std::to_string(value.size()));
  std::vector<double> out;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string item_key = key + "[" + std::to_string(i) + "]";
    const double v = scalarAs<double>(item_key, value[i], "a number");
    if (!range.contains(v))
      fail(key, "item " + std::to_string(i) + ": " + formatConfigNumber(v) + " is out of range " + range.toString());
    out.push_back(v);
  }
  return out;
}

std::vector<std::vector<double>> ConfigNode::getDoubleRows(const std::string& key, std::size_t columns, double min,
                                                           double max) const {
  const YAML::Node value = require(key);
  if (!value.IsSequence()) fail(key, "expected a list of rows, got " + shortValue(value));
  std::vector<std::vector<double>> rows;
  for (std::size_t r = 0; r < value.size(); ++r) {
    const YAML::Node row = value[r];
    const std::string row_name = "row " + std::to_string(r);
    if (!row.IsSequence() || row.size() != columns)
      fail(key, row_name + ": expected a list of " + std::to_string(columns) + " numbers, got " + shortValue(row));
    std::vector<double> out;
    for (std::size_t c = 0; c < columns; ++c) {
      if (!row[c].IsScalar()) fail(key, row_name + ": expected a number, got " + shortValue(row[c]));
      double v = 0.0;
      try {
        v = row[c].as<double>();
      } catch (const YAML::Exception&) {
        fail(key, row_name + ": expected a number, got " + shortValue(row[c]));
      }
      if (const Range range = Range::closed(min, max); !range.contains(v))
        fail(key, row_name + ": " + formatConfigNumber(v) + " is out of range " + range.toString());
      out.push_back(v);
    }
    rows.push_back(std::move(out));
  }
  return rows;
}

double ConfigNode::getDoubleOr(const std::string& key, double fallback, double min, double max) const {
  if (!has(key)) {
    used_->insert(key);
    return fallback;
  }
  return getDouble(key, min, max);
}

int ConfigNode::getIntOr(const std::string& key, int fallback, int min, int max) const {
  if (!has(key)) {
    used_->insert(key);
    return fallback;
  }
  return getInt(key, min, max);
}

bool ConfigNode::getBoolOr(const std::string& key, bool fallback) const {
  if (!has(key)) {
    used_->insert(key);
    return fallback;
  }
  return getBool(key);
}

std::string ConfigNode::getStringOr(const std::string& key, const std::string& fallback) const {
  if (!has(key)) {
    used_->insert(key);
    return fallback;
  }
  return getString(key);
}

ConfigNode ConfigNode::child(const std::string& key) const {
  const YAML::Node value = require(key);
  if (!value.IsMap()) fail(key, "expected a map of keys, got " + shortValue(value));
  return ConfigNode(value, source_, keyPath(key), overridden_);
}

std::vector<ConfigNode> ConfigNode::childList(const std::string& key) const {
  const YAML::Node value = require(key);
  if (!value.IsSequence()) fail(key, "expected a list, got " + shortValue(value));
  std::vector<ConfigNode> out;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string item_path = keyPath(key) + "[" + std::to_string(i) + "]";
    if (!value[i].IsMap())
      throw ConfigError(locateAt(value[i], item_path) + ": expected a map of keys, got " + shortValue(value[i]));
    out.push_back(ConfigNode(value[i], source_, item_path, overridden_));
  }
  return out;
}

void ConfigNode::finish() const {
  if (!node_.IsMap()) return;
  for (const auto& item : node_) {
    // A key that is a list or a map ("[a, b]: 1") is never one we read (as<string> would throw a
    // YAML exception past the caller: found by fuzz_scenario).
    if (!item.first.IsScalar())
      throw ConfigError(locate(item.first, "") + ": a key must be a plain word, got a list or map");
    const std::string key = item.first.Scalar();
    if (used_->count(key) == 0) throw ConfigError(locate(item.first, key) + ": unknown key");
  }
}

}  // namespace aerotrack::rt
