// Checks that a parameter struct's field table (rt/field_table.hpp) really keeps its reader, its
// validate() and its writer in agreement, walking the table's leaves (no field is listed by hand):
//   roundTrip   written, read back: every field equal (the defaults, then each field moved on its own);
//   rangeEnds   at each end of each field's range, a value just inside and one just outside: the reader
//               and validate() accept or reject the same values, and a rejection names the key;
//   keys        the writer prints exactly the keys the reader reads (each one required, no other one).
// The reader and the writer are the module's public ones (given as functions), so the checks hold for
// what the program uses, whatever implements it.
#pragma once

#include <gtest/gtest.h>
#include <algorithm>

#include <cfloat>
#include <cmath>
#include <functional>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/field_table.hpp"

namespace aerotrack::field_checks {

template <class S>
struct FieldTableUnderTest {
  const rt::FieldTable<S>& table;
  std::function<std::string(const S&)> write;                    ///< The module's writer.
  std::function<rt::Expected<S>(const std::string& yaml)> read;  ///< The module's reader (errors as values).
  std::function<rt::Status(const S&)> validate;                  ///< The module's validate().
};

/// A value just inside or just outside one end of a range.
struct RangeProbe {
  double value = 0.0;
  bool inside = false;
  std::string end;  ///< "lo" or "hi"
};

/// Moves `value` one step towards `direction`: the next double (integers: the next integer), never a
/// subnormal (the YAML reader refuses those as numbers, which would test the wrong thing).
inline double stepTowards(double value, double direction, bool integer) {
  if (integer) return direction > value ? value + 1.0 : value - 1.0;
  const double next = std::nextafter(value, direction);
  if (next != 0.0 && std::abs(next) < DBL_MIN) return std::copysign(DBL_MIN, next);
  return next;
}

/// Just inside and just outside each end: a closed end itself and the next value out; an open end the
/// next value in and the end itself; an infinite end the largest finite value and the infinity.
inline std::vector<RangeProbe> rangeProbes(const rt::Range& range, bool integer) {
  std::vector<RangeProbe> probes;
  const double inf = std::numeric_limits<double>::infinity();
  const auto add = [&](double bound, bool open, double outward, const char* end) {
    if (!std::isfinite(bound)) {
      probes.push_back({std::copysign(std::numeric_limits<double>::max(), outward), true, end});
      probes.push_back({std::copysign(inf, outward), false, end});
    } else if (open) {
      probes.push_back({stepTowards(bound, -outward, integer), true, end});
      probes.push_back({bound, false, end});
    } else {
      probes.push_back({bound, true, end});
      probes.push_back({stepTowards(bound, outward, integer), false, end});
    }
  };
  add(range.lo, range.lo_open, -inf, "lo");
  add(range.hi, range.hi_open, inf, "hi");
  return probes;
}

inline bool isNumeric(rt::FieldKind kind) {
  return kind == rt::FieldKind::kNumber || kind == rt::FieldKind::kInteger || kind == rt::FieldKind::kNumberList;
}

/// A value strictly inside `range` that differs from `current` (and prints with all its digits).
inline double interiorValue(const rt::Range& range, bool integer, double current) {
  double value = 0.0;
  if (std::isfinite(range.lo) && std::isfinite(range.hi)) {
    value = range.lo + (range.hi - range.lo) * 0.3141592653589793;
  } else if (std::isfinite(range.lo)) {
    value = range.lo + 1.2345678901234567;
  } else if (std::isfinite(range.hi)) {
    value = range.hi - 1.2345678901234567;
  } else {
    value = -1234.5678901234567;
  }
  if (integer) value = std::round(value);
  if (value == current) value = integer ? value + 1.0 : std::nextafter(value, range.hi);
  return value;
}

/// Every active field of `expected` and `actual` prints the same (exact numbers: the same value).
template <class S>
void expectSameFields(const rt::FieldTable<S>& table, const S& expected, const S& actual, const std::string& what) {
  for (const rt::FieldLeaf<S>& leaf : table.leaves()) {
    if (!leaf.active(expected)) continue;
    EXPECT_TRUE(leaf.active(actual)) << what << ": " << leaf.path;
    EXPECT_EQ(leaf.text(actual), leaf.text(expected)) << what << ": " << leaf.path;
  }
}

/// Written and read back, `base` comes back field by field; so does `base` with each field moved on its
/// own to another value (flags flipped, choices cycled, numbers inside their range), where that is valid.
/// Returns how many variants were checked.
template <class S>
int roundTrip(const FieldTableUnderTest<S>& t, const S& base) {
  const auto check = [&t](const S& params, const std::string& what) {
    const rt::Expected<S> back = t.read(t.write(params));
    if (!back) {
      ADD_FAILURE() << what << ": the written YAML does not read back: " << back.error().message;
      return;
    }
    expectSameFields(t.table, params, *back, what);
  };
  if (const rt::Status valid = t.validate(base); !valid) {
    ADD_FAILURE() << "the base parameters are invalid: " << valid.error().message;
    return 0;
  }
  check(base, "base");
  int variants = 1;
  for (const rt::FieldLeaf<S>& leaf : t.table.leaves()) {
    if (!leaf.active(base)) continue;
    for (std::size_t item = 0; item < leaf.items; ++item) {
      S moved = base;
      const double now = leaf.get(base, item);
      switch (leaf.kind) {
        case rt::FieldKind::kFlag:
          leaf.set(moved, item, now != 0.0 ? 0.0 : 1.0);
          break;
        case rt::FieldKind::kChoice:
          leaf.set(moved, item, std::fmod(now + 1.0, static_cast<double>(leaf.choices.size())));
          break;
        case rt::FieldKind::kCount:
          leaf.set(moved, item, now + 1.0);
          break;
        default:
          leaf.set(moved, item, interiorValue(leaf.range, leaf.kind == rt::FieldKind::kInteger, now));
          break;
      }
      EXPECT_NE(leaf.text(moved), leaf.text(base)) << leaf.path << " did not move";
      if (!t.validate(moved)) continue;  // a rule across fields refuses the move (both sides agree: rangeEnds)
      check(moved, leaf.path + " moved to " + leaf.text(moved));
      ++variants;
    }
  }
  return variants;
}

/// At both ends of every numeric field's range: a value just inside and one just outside. Outside: the
/// reader and validate() both refuse it, naming the key path. Inside: both accept it (the reader giving
/// exactly that value back), or both refuse it, which only a rule across fields may do; those cases are
/// returned as "path@lo" / "path@hi" for the caller to compare with the rules it knows.
template <class S>
std::set<std::string> rangeEnds(const FieldTableUnderTest<S>& t, const S& base, int* probes_checked = nullptr) {
  std::set<std::string> refused_inside;
  int checked = 0;
  for (const rt::FieldLeaf<S>& leaf : t.table.leaves()) {
    if (!leaf.active(base) || !isNumeric(leaf.kind)) continue;
    for (std::size_t item = 0; item < leaf.items; ++item) {
      for (const RangeProbe& probe : rangeProbes(leaf.range, leaf.kind == rt::FieldKind::kInteger)) {
        S params = base;
        leaf.set(params, item, probe.value);
        const std::string what = leaf.path + (leaf.items > 1 ? "[" + std::to_string(item) + "]" : "") + " = " +
                                 rt::formatConfigNumber(probe.value) + " (" + (probe.inside ? "inside " : "outside ") +
                                 leaf.range.toString() + ")";
        const rt::Status valid = t.validate(params);
        const rt::Expected<S> read = t.read(t.write(params));
        ++checked;
        if (!probe.inside) {
          EXPECT_FALSE(valid) << what << ": validate() accepts it";
          EXPECT_FALSE(read) << what << ": the reader accepts it";
          if (!valid) {
            EXPECT_NE(valid.error().message.find(leaf.path), std::string::npos) << valid.error().message;
          }
          if (!read) {
            EXPECT_NE(read.error().message.find(leaf.path), std::string::npos) << read.error().message;
          }
          continue;
        }
        EXPECT_EQ(valid.has_value(), read.has_value())
            << what << ": validate() " << (valid ? "accepts" : "refuses (" + valid.error().message + ")")
            << " but the reader " << (read ? "accepts" : "refuses (" + read.error().message + ")");
        if (valid && read) {
          EXPECT_EQ(leaf.get(*read, item), probe.value) << what;
        } else if (!valid && !read) {
          refused_inside.insert(leaf.path + "@" + probe.end);
        }
      }
    }
  }
  if (probes_checked != nullptr) *probes_checked = checked;
  return refused_inside;
}

/// Key paths of a YAML document's maps ("goal", "goal.predicted_weight"), in document order.
inline void collectKeys(const YAML::Node& map, const std::string& prefix, std::vector<std::string>& out) {
  for (const auto& item : map) {
    const std::string path = prefix + item.first.as<std::string>();
    out.push_back(path);
    if (item.second.IsMap()) collectKeys(item.second, path + ".", out);
  }
}

/// The written keys are the table's keys for `params`; the reader needs every one of them but `optional`
/// (removing any other one is "missing required key" naming it; removing an optional one still reads) and
/// reads no other one (an extra key in any map is "unknown key"). Returns the written key paths.
template <class S>
std::vector<std::string> keys(const FieldTableUnderTest<S>& t, const S& params,
                              const std::vector<std::string>& optional = {}) {
  const std::string text = t.write(params);
  const YAML::Node document = YAML::Load(text);
  std::vector<std::string> written;
  collectKeys(document, "", written);
  EXPECT_EQ(written, t.table.keyPaths(params));
  EXPECT_TRUE(t.read(text)) << "the written YAML does not read back";
  for (const std::string& path : written) {
    // Remove `path` from a fresh copy of the document.
    YAML::Node copy = YAML::Load(text);
    YAML::Node parent = copy;
    std::string rest = path;
    for (std::size_t dot = rest.find('.'); dot != std::string::npos; dot = rest.find('.')) {
      parent.reset(parent[rest.substr(0, dot)]);
      rest = rest.substr(dot + 1);
    }
    parent.remove(rest);
    const rt::Expected<S> without = t.read(YAML::Dump(copy));
    const bool is_optional = std::find(optional.begin(), optional.end(), path) != optional.end();
    if (is_optional) {
      EXPECT_TRUE(without) << "does not read without the optional " << path;
    } else {
      EXPECT_FALSE(without) << "reads without " << path;
    }
    if (!without && !is_optional) {
      EXPECT_NE(without.error().message.find(path + ": missing required key"), std::string::npos)
          << without.error().message;
    }
    // An extra key beside `path`.
    YAML::Node extra = YAML::Load(text);
    YAML::Node map = extra;
    rest = path;
    for (std::size_t dot = rest.find('.'); dot != std::string::npos; dot = rest.find('.')) {
      map.reset(map[rest.substr(0, dot)]);
      rest = rest.substr(dot + 1);
    }
    map["not_a_key"] = 1;
    const rt::Expected<S> with = t.read(YAML::Dump(extra));
    EXPECT_FALSE(with) << "reads with an extra key beside " << path;
    if (!with) {
      EXPECT_NE(with.error().message.find("not_a_key: unknown key"), std::string::npos) << with.error().message;
    }
  }
  return written;
}

}  // namespace aerotrack::field_checks
