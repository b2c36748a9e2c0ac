// Parameter sweeps: see sweep.hpp.
#include "sweep.hpp"

#include <set>

namespace aerotrack::app {

rt::Expected<SweepKey> parseSweepOption(const std::string& text) {
  const auto parsed = rt::parseConfigOverride(text);
  if (!parsed) return parsed.error();
  SweepKey sweep{parsed->key, {}};
  // Split at the commas outside brackets and quotes: a value may itself be a YAML list.
  int depth = 0;
  char quote = 0;
  std::string current;
  const auto finish_value = [&]() -> rt::Status {
    if (current.find_first_not_of(" \t") == std::string::npos)
      return rt::Error{"--set " + sweep.key + ": an empty value in '" + parsed->value + "'"};
    for (const std::string& v : sweep.values)
      if (v == current) return rt::Error{"--set " + sweep.key + ": value '" + current + "' given twice"};
    sweep.values.push_back(current);
    current.clear();
    return rt::ok();
  };
  for (const char c : parsed->value) {
    if (quote != 0) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    } else if (c == ',' && depth == 0) {
      if (auto s = finish_value(); !s) return s.error();
      continue;
    }
    current += c;
  }
  if (auto s = finish_value(); !s) return s.error();
  return sweep;
}

rt::Expected<std::vector<SweepPoint>> sweepPoints(const std::vector<SweepKey>& keys, std::size_t max_points) {
  std::set<std::string> seen;
  std::size_t count = 1;
  for (const SweepKey& k : keys) {
    if (!seen.insert(k.key).second) return rt::Error{"--set " + k.key + ": the key is swept twice"};
    count *= k.values.size();
    if (count > max_points)
      return rt::Error{"--set: more than " + std::to_string(max_points) + " combinations of values"};
  }
  std::vector<SweepPoint> points{SweepPoint{}};
  for (const SweepKey& k : keys) {
    std::vector<SweepPoint> next;
    next.reserve(points.size() * k.values.size());
    for (const SweepPoint& p : points)
      for (const std::string& v : k.values) {
        SweepPoint q = p;
        q.push_back({k.key, v});
        next.push_back(std::move(q));
      }
    points = std::move(next);
  }
  return points;
}

std::string sweepPointId(const SweepPoint& point) {
  std::string id;
  for (const rt::ConfigOverride& o : point) {
    if (!id.empty()) id += '+';
    for (const char c : o.key + "=" + o.value) {
      const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                        c == '_' || c == '=' || c == '-';
      id += keep ? c : '_';
    }
  }
  return id;
}

std::string sweepPointLabel(const SweepPoint& point) {
  std::string label;
  for (const rt::ConfigOverride& o : point) {
    if (!label.empty()) label += ", ";
    label += o.key + "=" + o.value;
  }
  return label;
}

std::vector<std::string> sweepArgs(const SweepPoint& point) {
  std::vector<std::string> args;
  for (const rt::ConfigOverride& o : point) {
    args.emplace_back("--set");
    args.push_back(o.key + "=" + o.value);
  }
  return args;
}

}  // namespace aerotrack::app
