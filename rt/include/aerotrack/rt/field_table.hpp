// Field tables: the one list of a parameter struct's config keys (issue 19 item 4). Each entry names a
// key, the member it fills and the values it may take; parsing, validation and printing all walk the
// same list, so a range cannot be written twice and disagree (planning_budget_s was [0, 0.999] in the
// parser and [0, 1) in validate, and the YAML writer was a third copy of the key list).
//
//   parse(node)     reads every key in table order through ConfigNode (so every error keeps the form
//                   "file:line: key.path: message": "planning_budget_s: 1 is out of range [0, 1)"), then
//                   finish() (a key nobody reads is an error), then the table's rules. Throws ConfigError.
//   validate(s)     the same ranges and rules on a struct built in code; the first failure as an Error
//                   naming the key path: "goal.predicted_weight must be in [0, 1], got 2".
//   emit(out, s)    the struct as a YAML map in table order, numbers exact: parse(emit(s)) gives s back.
//
// Policy: every key of a table is required. The defaults in the struct definitions serve code that builds
// parameters (tests, tools); a config file states every value (nothing is silently defaulted).
// Rules are the checks across fields ("flight_altitude_m must be > takeoff_below_m"): parse and validate
// both run them after every field's own range, so the two can only accept the same structs.
// A nested struct is a section() with its own table; its messages carry the section's key ("goal.").
// An entry may be active only for some values of the entries before it (when()): the localization's
// `paper:` / `pinhole:` section, chosen by `model`. An inactive entry is not read (so its key is an unknown
// key), not checked and not printed.
//
// Tables are constants: build each once, in the module that owns the struct (a function-local static
// next to the struct's validate(), declared in its header). Building, parsing, validating and printing
// allocate (strings, std::function): start-up and tools only, never a hot path. Thread-safe once built
// (everything is const).
#pragma once

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::rt {

enum class FieldKind : std::uint8_t {
  kNumber,      ///< double, in a Range
  kInteger,     ///< int, in a closed range
  kCount,       ///< unsigned integer (any size_t / uint64 value)
  kFlag,        ///< bool
  kNumberList,  ///< a fixed number of doubles, each in a Range ("[3.0, 3.0, 2.0]")
  kChoice,      ///< an enum, written by name
  kSection,     ///< a nested struct with its own table
};

/// The value as emit() prints it: formatConfigNumber, with YAML's spellings .nan, .inf, -.inf.
std::string formatYamlNumber(double value);

/// One value-holding key of a table, sections flattened (for tests and tools that walk every field).
template <class S>
struct FieldLeaf {
  std::string path;  ///< Key path from the table's root: "goal.predicted_weight".
  FieldKind kind = FieldKind::kNumber;
  Range range;                           ///< kNumber, kNumberList (each item); kInteger: closed, whole ends.
  std::size_t items = 1;                 ///< kNumberList: the list's length; else 1.
  std::vector<std::string> choices;      ///< kChoice: the names, index i for the i-th value given to choice().
  std::function<bool(const S&)> active;  ///< Whether the key is read, checked and printed for s.
  std::function<double(const S&, std::size_t)> get;  ///< Item i (0 unless kNumberList); choices: the index.
  std::function<void(S&, std::size_t, double)> set;  ///< Inverse of get (flags: != 0; integers: truncated).
  std::function<std::string(const S&)> text;         ///< The value as emit() prints it.
};

/// A check across fields, run after every field's own range. `key` is the key blamed in messages.
template <class S>
struct FieldRule {
  std::string key;
  std::string requirement;  ///< Completes "<key> ...": "must be > takeoff_below_m".
  std::function<bool(const S&)> holds;
};

/// One entry of a FieldTable<S>; build with number(), integer(), count(), flag(), numberList(), choice()
/// or section() below.
template <class S>
class Field {
 public:
  /// What an entry does, filled in by the builder functions.
  struct Ops {
    std::function<void(const ConfigNode&, S&)> read;                ///< Reads the key from its map.
    std::function<std::optional<std::string>(const S&)> check;      ///< The failure, naming the key path.
    std::function<void(YAML::Emitter&, const S&)> write;            ///< The value (after the key).
    std::function<std::vector<FieldLeaf<S>>()> leaves;              ///< Paths relative to the entry's table.
    std::function<std::vector<std::string>(const S&)> nested_keys;  ///< Sections: their key paths, relative.
  };

  Field(std::string key, FieldKind kind, Ops ops) : key_(std::move(key)), kind_(kind), ops_(std::move(ops)) {}

  /// The same entry, active only for structs where `predicate` holds. Parsing evaluates it on the struct
  /// as read so far: it may look only at entries listed before this one.
  Field when(std::function<bool(const S&)> predicate) const {
    Field out = *this;
    out.active_ = std::move(predicate);
    return out;
  }
  /// The same entry with `text` printed above its key as YAML comment lines (one per '\n'-separated
  /// line). Use on top-level tables, not on the first key (yaml-cpp indents nested comments badly).
  Field withComment(const std::string& text) const {
    Field out = *this;
    out.comment_ = text;
    return out;
  }

  const std::string& key() const { return key_; }
  FieldKind kind() const { return kind_; }
  bool activeFor(const S& s) const { return !active_ || active_(s); }
  const std::function<bool(const S&)>& activePredicate() const { return active_; }
  const std::string& comment() const { return comment_; }
  const Ops& ops() const { return ops_; }

 private:
  std::string key_;
  FieldKind kind_;
  Ops ops_;
  std::function<bool(const S&)> active_;
  std::string comment_;
};

template <class S>
class FieldTable {
 public:
  explicit FieldTable(std::vector<Field<S>> fields, std::vector<FieldRule<S>> rules = {})
      : fields_(std::move(fields)), rules_(std::move(rules)) {}

  /// Reads `node` (a map): every active key in table order, range-checked, then finish(), then the
  /// rules. Starts from S{} (members outside the table keep their defaults). Throws ConfigError.
  S parse(const ConfigNode& node) const {
    S s{};
    parseInto(node, s);
    return s;
  }

  /// parse() into an existing struct (sections use it).
  void parseInto(const ConfigNode& node, S& s) const {
    for (const Field<S>& field : fields_) {
      if (field.activeFor(s)) field.ops().read(node, s);
    }
    node.finish();
    for (const FieldRule<S>& rule : rules_) {
      if (!rule.holds(s)) node.fail(rule.key, rule.requirement);
    }
  }

  /// Every active field in its range (sections recursively, with their rules), then the rules. The
  /// error names the key path relative to this table: "goal.predicted_weight must be in [0, 1], got 2".
  Status validate(const S& s) const {
    if (std::optional<std::string> failure = firstFailure(s)) return Error{*std::move(failure)};
    return ok();
  }

  /// `s` as a YAML map (block style; number lists in flow style), active keys in table order.
  void emit(YAML::Emitter& out, const S& s) const {
    out << YAML::BeginMap;
    for (const Field<S>& field : fields_) {
      if (!field.activeFor(s)) continue;
      emitComment(out, field.comment());
      out << YAML::Key << field.key() << YAML::Value;
      field.ops().write(out, s);
    }
    out << YAML::EndMap;
  }

  /// emit() into a string (no trailing newline).
  std::string toYaml(const S& s) const {
    YAML::Emitter out;
    emit(out, s);
    return out.c_str();
  }

  const std::vector<Field<S>>& fields() const { return fields_; }
  const std::vector<FieldRule<S>>& rules() const { return rules_; }

  /// Every value-holding key, sections flattened, in table order (active or not).
  std::vector<FieldLeaf<S>> leaves() const {
    std::vector<FieldLeaf<S>> out;
    for (const Field<S>& field : fields_) {
      for (FieldLeaf<S>& leaf : field.ops().leaves()) {
        leaf.active = bothActive(field.activePredicate(), std::move(leaf.active));
        if (!leaf.active) leaf.active = [](const S&) { return true; };
        out.push_back(std::move(leaf));
      }
    }
    return out;
  }

  /// The key paths that parse reads and emit writes for `s` (sections and their keys), in table order.
  std::vector<std::string> keyPaths(const S& s) const {
    std::vector<std::string> out;
    for (const Field<S>& field : fields_) {
      if (!field.activeFor(s)) continue;
      out.push_back(field.key());
      if (field.ops().nested_keys) {
        for (const std::string& key : field.ops().nested_keys(s)) out.push_back(field.key() + "." + key);
      }
    }
    return out;
  }

  /// The first failure of validate() as text (nullopt: valid). Sections use it.
  std::optional<std::string> firstFailure(const S& s) const {
    for (const Field<S>& field : fields_) {
      if (!field.activeFor(s)) continue;
      if (std::optional<std::string> failure = field.ops().check(s)) return failure;
    }
    for (const FieldRule<S>& rule : rules_) {
      if (!rule.holds(s)) return rule.key + " " + rule.requirement;
    }
    return std::nullopt;
  }

 private:
  static void emitComment(YAML::Emitter& out, const std::string& text) {
    if (text.empty()) return;
    std::size_t start = 0;
    while (start <= text.size()) {
      const std::size_t end = text.find('\n', start);
      const std::size_t stop = end == std::string::npos ? text.size() : end;
      out << YAML::Newline << YAML::Comment(text.substr(start, stop - start));
      start = stop + 1;
    }
  }

  static std::function<bool(const S&)> bothActive(std::function<bool(const S&)> a, std::function<bool(const S&)> b) {
    if (!a) return b;
    if (!b) return a;
    return [a = std::move(a), b = std::move(b)](const S& s) { return a(s) && b(s); };
  }

  std::vector<Field<S>> fields_;
  std::vector<FieldRule<S>> rules_;
};

namespace field_detail {

/// "<key> must be in <range>, got <value>".
std::string outOfRange(const std::string& key, const Range& range, double value);

template <class S>
FieldLeaf<S> leafOf(const std::string& key, FieldKind kind, const Range& range,
                    std::function<double(const S&, std::size_t)> get, std::function<void(S&, std::size_t, double)> set,
                    std::function<std::string(const S&)> text) {
  FieldLeaf<S> leaf;
  leaf.path = key;
  leaf.kind = kind;
  leaf.range = range;
  leaf.get = std::move(get);
  leaf.set = std::move(set);
  leaf.text = std::move(text);
  return leaf;
}

}  // namespace field_detail

/// A required number (double) in `range`.
template <class S>
Field<S> number(std::string key, double S::*member, Range range) {
  typename Field<S>::Ops ops;
  ops.read = [key, member, range](const ConfigNode& node, S& s) { s.*member = node.getDouble(key, range); };
  ops.check = [key, member, range](const S& s) -> std::optional<std::string> {
    if (range.contains(s.*member)) return std::nullopt;
    return field_detail::outOfRange(key, range, s.*member);
  };
  ops.write = [member](YAML::Emitter& out, const S& s) { out << formatYamlNumber(s.*member); };
  ops.leaves = [key, member, range] {
    return std::vector<FieldLeaf<S>>{field_detail::leafOf<S>(
        key, FieldKind::kNumber, range, [member](const S& s, std::size_t) { return s.*member; },
        [member](S& s, std::size_t, double v) { s.*member = v; },
        [member](const S& s) { return formatYamlNumber(s.*member); })};
  };
  return Field<S>(std::move(key), FieldKind::kNumber, std::move(ops));
}

/// A number (double) in `range` that a file may leave out: absent, it reads as `fallback` (a key added to a
/// file format after files of it were written). Written, checked and walked like number().
template <class S>
Field<S> optionalNumber(std::string key, double S::*member, Range range, double fallback) {
  Field<S> field = number(key, member, range);
  typename Field<S>::Ops ops = field.ops();
  ops.read = [key, member, range, fallback](const ConfigNode& node, S& s) {
    s.*member = node.has(key) ? node.getDouble(key, range) : fallback;
  };
  return Field<S>(std::move(key), FieldKind::kNumber, std::move(ops));
}

/// A required integer in [min, max].
template <class S>
Field<S> integer(std::string key, int S::*member, int min, int max) {
  const Range range = Range::closed(min, max);
  typename Field<S>::Ops ops;
  ops.read = [key, member, min, max](const ConfigNode& node, S& s) { s.*member = node.getInt(key, min, max); };
  ops.check = [key, member, range](const S& s) -> std::optional<std::string> {
    if (range.contains(s.*member)) return std::nullopt;
    return field_detail::outOfRange(key, range, s.*member);
  };
  ops.write = [member](YAML::Emitter& out, const S& s) { out << s.*member; };
  ops.leaves = [key, member, range] {
    return std::vector<FieldLeaf<S>>{field_detail::leafOf<S>(
        key, FieldKind::kInteger, range, [member](const S& s, std::size_t) { return s.*member; },
        [member](S& s, std::size_t, double v) { s.*member = static_cast<int>(v); },
        [member](const S& s) { return std::to_string(s.*member); })};
  };
  return Field<S>(std::move(key), FieldKind::kInteger, std::move(ops));
}

/// A required non-negative integer (a count), any value of T.
template <class S, std::unsigned_integral T>
Field<S> count(std::string key, T S::*member) {
  typename Field<S>::Ops ops;
  ops.read = [key, member](const ConfigNode& node, S& s) { s.*member = static_cast<T>(node.getUint64(key)); };
  ops.check = [](const S&) -> std::optional<std::string> { return std::nullopt; };
  ops.write = [member](YAML::Emitter& out, const S& s) { out << static_cast<std::uint64_t>(s.*member); };
  ops.leaves = [key, member] {
    return std::vector<FieldLeaf<S>>{field_detail::leafOf<S>(
        key, FieldKind::kCount, Range::atLeast(0.0),
        [member](const S& s, std::size_t) { return static_cast<double>(s.*member); },
        [member](S& s, std::size_t, double v) { s.*member = static_cast<T>(v); },
        [member](const S& s) { return std::to_string(s.*member); })};
  };
  return Field<S>(std::move(key), FieldKind::kCount, std::move(ops));
}

/// A required true / false.
template <class S>
Field<S> flag(std::string key, bool S::*member) {
  typename Field<S>::Ops ops;
  ops.read = [key, member](const ConfigNode& node, S& s) { s.*member = node.getBool(key); };
  ops.check = [](const S&) -> std::optional<std::string> { return std::nullopt; };
  ops.write = [member](YAML::Emitter& out, const S& s) { out << s.*member; };
  ops.leaves = [key, member] {
    return std::vector<FieldLeaf<S>>{field_detail::leafOf<S>(
        key, FieldKind::kFlag, Range::closed(0.0, 1.0),
        [member](const S& s, std::size_t) { return s.*member ? 1.0 : 0.0; },
        [member](S& s, std::size_t, double v) { s.*member = v != 0.0; },
        [member](const S& s) { return std::string(s.*member ? "true" : "false"); })};
  };
  return Field<S>(std::move(key), FieldKind::kFlag, std::move(ops));
}

/// A required list of exactly `items` numbers, each in `range`, into a member with data() (std::array,
/// Eigen::Vector3d, ...) holding at least `items` doubles. Printed in flow style: "[3, 3, 2]".
template <class S, class V>
Field<S> numberList(std::string key, V S::*member, std::size_t items, Range range) {
  typename Field<S>::Ops ops;
  ops.read = [key, member, items, range](const ConfigNode& node, S& s) {
    const std::vector<double> values = node.getDoubleList(key, items, range);
    for (std::size_t i = 0; i < items; ++i) (s.*member).data()[i] = values[i];
  };
  ops.check = [key, member, items, range](const S& s) -> std::optional<std::string> {
    for (std::size_t i = 0; i < items; ++i) {
      const double v = (s.*member).data()[i];
      if (!range.contains(v)) return field_detail::outOfRange(key + "[" + std::to_string(i) + "]", range, v);
    }
    return std::nullopt;
  };
  ops.write = [member, items](YAML::Emitter& out, const S& s) {
    out << YAML::Flow << YAML::BeginSeq;
    for (std::size_t i = 0; i < items; ++i) out << formatYamlNumber((s.*member).data()[i]);
    out << YAML::EndSeq;
  };
  ops.leaves = [key, member, items, range] {
    FieldLeaf<S> leaf = field_detail::leafOf<S>(
        key, FieldKind::kNumberList, range, [member](const S& s, std::size_t i) { return (s.*member).data()[i]; },
        [member](S& s, std::size_t i, double v) { (s.*member).data()[i] = v; },
        [member, items](const S& s) {
          std::string text = "[";
          for (std::size_t i = 0; i < items; ++i)
            text += (i == 0 ? "" : ", ") + formatYamlNumber((s.*member).data()[i]);
          return text + "]";
        });
    leaf.items = items;
    return std::vector<FieldLeaf<S>>{std::move(leaf)};
  };
  return Field<S>(std::move(key), FieldKind::kNumberList, std::move(ops));
}

/// A required name, one of `names` (each with the enum value it stands for).
template <class S, class E>
Field<S> choice(std::string key, E S::*member, std::vector<std::pair<std::string, E>> names) {
  std::vector<std::string> allowed;
  allowed.reserve(names.size());
  for (const auto& [name, value] : names) allowed.push_back(name);
  const auto index_of = [names](E value) -> std::optional<std::size_t> {
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (names[i].second == value) return i;
    }
    return std::nullopt;
  };
  const auto name_of = [names, index_of](E value) {
    const std::optional<std::size_t> i = index_of(value);
    return i ? names[*i].first : std::string("?");
  };
  typename Field<S>::Ops ops;
  ops.read = [key, member, names, allowed](const ConfigNode& node, S& s) {
    const std::string name = node.getEnum(key, allowed);
    for (const auto& [candidate, value] : names) {
      if (candidate == name) s.*member = value;
    }
  };
  ops.check = [key, member, index_of, allowed](const S& s) -> std::optional<std::string> {
    if (index_of(s.*member)) return std::nullopt;
    std::string list;
    for (const std::string& name : allowed) list += (list.empty() ? "" : ", ") + name;
    return key + " must be one of: " + list;
  };
  ops.write = [member, name_of](YAML::Emitter& out, const S& s) { out << name_of(s.*member); };
  ops.leaves = [key, member, names, allowed, index_of, name_of] {
    FieldLeaf<S> leaf = field_detail::leafOf<S>(
        key, FieldKind::kChoice, Range::closed(0.0, static_cast<double>(names.size()) - 1.0),
        [member, index_of](const S& s, std::size_t) {
          const std::optional<std::size_t> i = index_of(s.*member);
          return i ? static_cast<double>(*i) : -1.0;
        },
        [member, names](S& s, std::size_t, double v) { s.*member = names.at(static_cast<std::size_t>(v)).second; },
        [member, name_of](const S& s) { return name_of(s.*member); });
    leaf.choices = allowed;
    return std::vector<FieldLeaf<S>>{std::move(leaf)};
  };
  return Field<S>(std::move(key), FieldKind::kChoice, std::move(ops));
}

/// A required map holding the nested struct `member`, read, checked and printed by `table` (a copy is
/// kept). Its messages carry the section's key: "goal.predicted_weight must be in [0, 1], got 2".
template <class S, class T>
Field<S> section(std::string key, T S::*member, FieldTable<T> table) {
  const auto nested = std::make_shared<const FieldTable<T>>(std::move(table));
  typename Field<S>::Ops ops;
  ops.read = [key, member, nested](const ConfigNode& node, S& s) { nested->parseInto(node.child(key), s.*member); };
  ops.check = [key, member, nested](const S& s) -> std::optional<std::string> {
    if (std::optional<std::string> failure = nested->firstFailure(s.*member)) return key + "." + *failure;
    return std::nullopt;
  };
  ops.write = [member, nested](YAML::Emitter& out, const S& s) { nested->emit(out, s.*member); };
  ops.leaves = [key, member, nested] {
    std::vector<FieldLeaf<S>> out;
    for (FieldLeaf<T>& inner : nested->leaves()) {
      FieldLeaf<S> leaf;
      leaf.path = key + "." + inner.path;
      leaf.kind = inner.kind;
      leaf.range = inner.range;
      leaf.items = inner.items;
      leaf.choices = std::move(inner.choices);
      leaf.active = [member, a = std::move(inner.active)](const S& s) { return a(s.*member); };
      leaf.get = [member, g = std::move(inner.get)](const S& s, std::size_t i) { return g(s.*member, i); };
      leaf.set = [member, f = std::move(inner.set)](S& s, std::size_t i, double v) { f(s.*member, i, v); };
      leaf.text = [member, t = std::move(inner.text)](const S& s) { return t(s.*member); };
      out.push_back(std::move(leaf));
    }
    return out;
  };
  ops.nested_keys = [member, nested](const S& s) { return nested->keyPaths(s.*member); };
  return Field<S>(std::move(key), FieldKind::kSection, std::move(ops));
}

}  // namespace aerotrack::rt
