// The strict YAML reader: every error class names the file, the line and the key. And the field tables
// built on it (field_table.hpp): one list per struct drives parse, validate and emit.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/field_table.hpp"

namespace aerotrack::rt {
namespace {

/// Parses `yaml` as file "test.yaml" and runs `read` on the root; returns the error message or "".
std::string errorOf(const std::string& yaml, const std::function<void(const ConfigNode&)>& read) {
  const auto root = ConfigNode::fromString(yaml, "test.yaml");
  if (!root) return root.error().message;
  const auto result = parseConfig<int>([&] {
    read(*root);
    return 0;
  });
  return result ? "" : result.error().message;
}

TEST(ConfigNode, GivenValidKeysThenValuesRead) {
  const auto root = ConfigNode::fromString("a: 1.5\nb: 3\nc: true\nd: text\ne: [1, 2, 3]\nf: {g: 2}\n", "t");
  ASSERT_TRUE(root);
  EXPECT_EQ(root->getDouble("a", 0, 2), 1.5);
  EXPECT_EQ(root->getInt("b", 0, 5), 3);
  EXPECT_TRUE(root->getBool("c"));
  EXPECT_EQ(root->getString("d"), "text");
  EXPECT_EQ(root->getDoubleList("e", 3, 0, 10), (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(root->child("f").getInt("g", 0, 9), 2);
  EXPECT_EQ(root->getDoubleOr("missing", 4.0, 0, 10), 4.0);
}

/// Parses `yaml` as "test.yaml" with `--set` assignments; the root or the error message.
Expected<ConfigNode> withSets(const std::string& yaml, const std::vector<std::string>& sets) {
  std::vector<ConfigOverride> overrides;
  for (const std::string& s : sets) {
    auto o = parseConfigOverride(s);
    if (!o) return o.error();
    overrides.push_back(*o);
  }
  return ConfigNode::fromString(yaml, "test.yaml", overrides);
}

TEST(ConfigOverride, GivenSetsThenTheyReplaceValuesInMapsAndListsInOrder) {
  const auto root = withSets("a: 1\nf: {g: 2, h: [1, 2]}\ntasks:\n  - {rate_hz: 10}\n  - {rate_hz: 20}\n",
                             {"a=3.5", "f.g=4", "f.h=[7, 8, 9]", "tasks[1].rate_hz=50", "a=4.5", "f.new=true"});
  ASSERT_TRUE(root) << root.error().message;
  EXPECT_EQ(root->getDouble("a", 0, 9), 4.5);  // the last --set of a key wins
  EXPECT_EQ(root->child("f").getInt("g", 0, 9), 4);
  EXPECT_EQ(root->child("f").getDoubleList("h", 0, 0, 10), (std::vector<double>{7, 8, 9}));
  EXPECT_TRUE(root->child("f").getBool("new"));
  EXPECT_EQ(root->childList("tasks")[1].getDouble("rate_hz", 0, 100), 50.0);
  EXPECT_EQ(root->childList("tasks")[0].getDouble("rate_hz", 0, 100), 10.0);
}

TEST(ConfigOverride, GivenABadSetValueOrKeyThenTheParsersErrorNamesTheSetNotAFileLine) {
  const auto bad_value = withSets("f: {g: 2}\n", {"f.g=fast"});
  ASSERT_TRUE(bad_value);
  const auto read = parseConfig<double>([&] { return bad_value->child("f").getDouble("g", 0, 9); });
  ASSERT_FALSE(read);
  EXPECT_EQ(read.error().message.rfind("--set f.g: expected a number", 0), 0U) << read.error().message;

  const auto typo = withSets("f: {g: 2}\n", {"f.typo=1"});
  ASSERT_TRUE(typo);
  const auto unknown = parseConfig<int>([&] {
    const ConfigNode f = typo->child("f");
    f.getDouble("g", 0, 9);
    f.finish();
    return 0;
  });
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error().message, "--set f.typo: unknown key");
}

TEST(ConfigOverride, GivenAPathThatDoesNotLeadIntoTheFileThenOneLineNamesIt) {
  EXPECT_EQ(withSets("a: 1\n", {"b.c=1"}).error().message, "--set b.c: test.yaml has no key b");
  EXPECT_EQ(withSets("a: 1\n", {"a.c=1"}).error().message, "--set a.c: a is not a map of keys in test.yaml");
  EXPECT_EQ(withSets("l: [1]\n", {"l[3]=1"}).error().message, "--set l[3]: l has no item [3] in test.yaml");
  EXPECT_EQ(withSets("a: 1\n", {"a"}).error().message, "--set: expected KEY=VALUE, got 'a'");
  EXPECT_EQ(withSets("a: 1\n", {"=1"}).error().message.rfind("--set: '' is not a key path", 0), 0U);
  EXPECT_EQ(withSets("a: 1\n", {"a..b=1"}).error().message.rfind("--set: 'a..b' is not a key path", 0), 0U);
  EXPECT_EQ(withSets("a: 1\n", {"a=[1, 2"}).error().message.rfind("--set a: invalid YAML value '[1, 2'", 0), 0U);
}

TEST(ConfigNode, GivenMissingKeyThenErrorNamesFileAndKey) {
  EXPECT_EQ(errorOf("a: 1\n", [](const ConfigNode& n) { n.getDouble("rate_hz", 0, 1); }),
            "test.yaml:1: rate_hz: missing required key");
}

TEST(ConfigNode, GivenNestedMissingKeyThenErrorNamesFullPath) {
  const std::string e = errorOf("vehicle:\n  radius_m: 1\n",
                                [](const ConfigNode& n) { n.child("vehicle").getDouble("max_speed_mps", 0, 9); });
  EXPECT_EQ(e, "test.yaml:2: vehicle.max_speed_mps: missing required key");
}

TEST(ConfigNode, GivenUnknownKeyThenErrorNamesItsLineAndPath) {
  const std::string e = errorOf("vehicle:\n  radius_m: 1\n  radious_m: 2\n", [](const ConfigNode& n) {
    const ConfigNode v = n.child("vehicle");
    v.getDouble("radius_m", 0, 9);
    v.finish();
  });
  EXPECT_EQ(e, "test.yaml:3: vehicle.radious_m: unknown key");
}

TEST(ConfigNode, GivenWrongTypeThenErrorSaysWhatWasExpected) {
  EXPECT_EQ(errorOf("rate_hz: fast\n", [](const ConfigNode& n) { n.getDouble("rate_hz", 0, 1); }),
            "test.yaml:1: rate_hz: expected a number, got 'fast'");
  EXPECT_EQ(errorOf("n: 2.5\n", [](const ConfigNode& n) { n.getInt("n", 0, 9); }),
            "test.yaml:1: n: expected an integer, got '2.5'");
  EXPECT_EQ(errorOf("m: [1]\n", [](const ConfigNode& n) { n.child("m"); }),
            "test.yaml:1: m: expected a map of keys, got a list");
  EXPECT_EQ(errorOf("b: maybe\n", [](const ConfigNode& n) { n.getBool("b"); }),
            "test.yaml:1: b: expected true or false, got 'maybe'");
}

TEST(ConfigNode, GivenOutOfRangeThenErrorGivesValueAndRange) {
  EXPECT_EQ(errorOf("x: 1\ny: 500\n", [](const ConfigNode& n) { n.getDouble("y", 0, 100); }),
            "test.yaml:2: y: 500 is out of range [0, 100]");
  EXPECT_EQ(errorOf("x: .nan\n", [](const ConfigNode& n) { n.getDouble("x", 0, 100); }),
            "test.yaml:1: x: nan is out of range [0, 100]");
}

TEST(ConfigNode, GivenBadEnumThenErrorListsAllowedNames) {
  EXPECT_EQ(errorOf("backend: real\n",
                    [](const ConfigNode& n) {
                      n.getEnum("backend", {"null", "sim"});
                    }),
            "test.yaml:1: backend: 'real' is not one of: null, sim");
}

TEST(ConfigNode, GivenYamlNullWhereNullIsAllowedThenReadsAsTheNameNull) {
  const auto root = ConfigNode::fromString("backend: null\nother: ~\n", "t");
  ASSERT_TRUE(root);
  EXPECT_EQ(root->getEnum("backend", {"null", "sim"}), "null");
  EXPECT_EQ(errorOf("x: ~\n", [](const ConfigNode& n) { n.getString("x"); }), "test.yaml:1: x: has no value");
}

TEST(ConfigNode, GivenListOfMapsThenItemsCarryTheirIndex) {
  const std::string e = errorOf("tasks:\n  - {name: a}\n  - {name: b, rate: x}\n", [](const ConfigNode& n) {
    for (const ConfigNode& t : n.childList("tasks")) {
      t.getString("name");
      t.finish();
    }
  });
  EXPECT_EQ(e, "test.yaml:3: tasks[1].rate: unknown key");
}

TEST(ConfigNode, GivenBadRowsThenErrorNamesTheRow) {
  EXPECT_EQ(errorOf("w: [[0, 0, 1], [1, 2]]\n", [](const ConfigNode& n) { n.getDoubleRows("w", 3, -9, 9); }),
            "test.yaml:1: w: row 1: expected a list of 3 numbers, got a list");
}

TEST(ConfigNode, GivenInvalidYamlThenErrorWithLine) {
  const auto root = ConfigNode::fromString("a: 1\nb: [1, 2\n", "bad.yaml");
  ASSERT_FALSE(root);
  EXPECT_EQ(root.error().message.rfind("bad.yaml:", 0), 0U);
  EXPECT_NE(root.error().message.find("invalid YAML"), std::string::npos);
}

TEST(ConfigNode, GivenTopLevelNotAMapThenError) {
  const auto root = ConfigNode::fromString("- 1\n- 2\n", "list.yaml");
  ASSERT_FALSE(root);
  EXPECT_EQ(root.error().message, "list.yaml: the top level must be a map of keys");
}

TEST(ConfigNode, GivenMissingFileThenErrorNamesIt) {
  const auto root = ConfigNode::loadFile("/nonexistent/aerotrack.yaml");
  ASSERT_FALSE(root);
  EXPECT_EQ(root.error().message, "/nonexistent/aerotrack.yaml: cannot open file: no such file or directory");
}

// ---- ranges ----

TEST(Range, GivenOpenAndClosedEndsThenContainsAndPrintsThem) {
  const Range budget = Range::closedOpen(0.0, 1.0);
  EXPECT_TRUE(budget.contains(0.0));
  EXPECT_TRUE(budget.contains(std::nextafter(1.0, 0.0)));
  EXPECT_FALSE(budget.contains(1.0));
  EXPECT_FALSE(budget.contains(std::nextafter(0.0, -1.0)));
  EXPECT_EQ(budget.toString(), "[0, 1)");
  EXPECT_EQ(Range::closed(0.05, 2.0).toString(), "[0.05, 2]");
  EXPECT_EQ(Range::openClosed(0.0, 30.0).toString(), "(0, 30]");
  EXPECT_EQ(Range::greaterThan(0.0).toString(), "(0, inf)");
  EXPECT_EQ(Range::atLeast(0.0).toString(), "[0, inf)");
  EXPECT_EQ(Range::finite().toString(), "(-inf, inf)");
  // Only finite numbers are inside, even where an infinite end was written closed.
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(Range::finite().contains(std::numeric_limits<double>::max()));
  EXPECT_FALSE(Range::finite().contains(inf));
  EXPECT_FALSE(Range::finite().contains(std::nan("")));
  EXPECT_FALSE(Range::closed(0.0, inf).contains(inf));
  EXPECT_EQ(Range::closed(0.0, inf).toString(), "[0, inf)");
}

TEST(Range, GivenNumbersThenPrintedShortWhereExactElseInFull) {
  EXPECT_EQ(formatConfigNumber(0.05), "0.05");
  EXPECT_EQ(formatConfigNumber(100000.0), "100000");
  EXPECT_EQ(formatConfigNumber(1e6), "1e+06");
  EXPECT_EQ(formatConfigNumber(-5.0), "-5");
  EXPECT_EQ(formatConfigNumber(std::nextafter(1.0, 0.0)), "0.9999999999999999");
  EXPECT_EQ(formatConfigNumber(0.1 + 0.2), "0.30000000000000004");
  EXPECT_EQ(formatConfigNumber(std::nan("")), "nan");
  EXPECT_EQ(formatYamlNumber(std::nan("")), ".nan");
  EXPECT_EQ(formatYamlNumber(-std::numeric_limits<double>::infinity()), "-.inf");
}

TEST(ConfigNode, GivenAnOpenEndThenTheBoundItselfIsOutOfRange) {
  const auto read = [](const std::string& yaml) {
    return errorOf(yaml, [](const ConfigNode& n) { n.getDouble("budget_s", Range::closedOpen(0.0, 1.0)); });
  };
  EXPECT_EQ(read("budget_s: 0.9999999999999999\n"), "");
  EXPECT_EQ(read("budget_s: 0\n"), "");
  EXPECT_EQ(read("budget_s: 1\n"), "test.yaml:1: budget_s: 1 is out of range [0, 1)");
  EXPECT_EQ(errorOf("v: [1, 0]\n", [](const ConfigNode& n) { n.getDoubleList("v", 2, Range::greaterThan(0.0)); }),
            "test.yaml:1: v: item 1: 0 is out of range (0, inf)");
  EXPECT_EQ(errorOf("m: c\n",
                    [](const ConfigNode& n) {
                      n.getEnum("m", std::vector<std::string>{"a", "b"});
                    }),
            "test.yaml:1: m: 'c' is not one of: a, b");
}

// ---- field tables ----

enum class Shape : std::uint8_t { kBox, kBall };

struct BoxParams {
  double width_m = 1.0;
  int cells = 4;
};

struct BallParams {
  double radius_m = 0.5;
};

struct ToyParams {
  double budget_s = 0.05;
  double low_m = 0.5;
  double high_m = 1.5;
  bool enabled = true;
  std::array<double, 3> size_m{3.0, 3.0, 2.0};
  std::uint64_t samples = 7;
  Shape shape = Shape::kBox;
  BoxParams box;
  BallParams ball;
};

FieldTable<BoxParams> boxFields() {
  return FieldTable<BoxParams>(
      {number("width_m", &BoxParams::width_m, Range::greaterThan(0.0)), integer("cells", &BoxParams::cells, 1, 64)},
      {{"cells", "must be even", [](const BoxParams& b) { return b.cells % 2 == 0; }}});
}

const FieldTable<ToyParams>& toyFields() {
  using P = ToyParams;
  static const FieldTable<P> kTable(
      {
          number("budget_s", &P::budget_s, Range::closedOpen(0.0, 1.0)),
          number("low_m", &P::low_m, Range::closed(0.0, 10.0)),
          number("high_m", &P::high_m, Range::closed(0.0, 10.0)),
          flag("enabled", &P::enabled),
          numberList("size_m", &P::size_m, 3, Range::closed(0.01, 100.0)),
          count("samples", &P::samples),
          choice("shape", &P::shape, {{"box", Shape::kBox}, {"ball", Shape::kBall}}),
          section("box", &P::box, boxFields()).when([](const P& p) { return p.shape == Shape::kBox; }),
          section("ball", &P::ball,
                  FieldTable<BallParams>({number("radius_m", &BallParams::radius_m, Range::openClosed(0.0, 5.0))}))
              .when([](const P& p) { return p.shape == Shape::kBall; })
              .withComment("the ball\ntwo lines"),
      },
      {{"high_m", "must be > low_m", [](const P& p) { return p.high_m > p.low_m; }}});
  return kTable;
}

/// Parses `yaml` with the toy table; the error message, or "" (and the result in `out`).
std::string toyError(const std::string& yaml, ToyParams* out = nullptr) {
  const auto root = ConfigNode::fromString(yaml, "toy.yaml");
  if (!root) return root.error().message;
  const auto parsed = parseConfig<ToyParams>([&root] { return toyFields().parse(*root); });
  if (!parsed) return parsed.error().message;
  if (out != nullptr) *out = *parsed;
  return "";
}

TEST(FieldTable, GivenAStructThenEmitPrintsEveryActiveKeyInTableOrder) {
  ToyParams p;
  p.budget_s = std::nextafter(1.0, 0.0);
  EXPECT_EQ(toyFields().toYaml(p),
            "budget_s: 0.9999999999999999\nlow_m: 0.5\nhigh_m: 1.5\nenabled: true\nsize_m: [3, 3, 2]\n"
            "samples: 7\nshape: box\nbox:\n  width_m: 1\n  cells: 4");
  p.shape = Shape::kBall;
  const std::string ball = toyFields().toYaml(p);
  EXPECT_NE(ball.find("shape: ball\n# the ball\n# two lines\nball:\n  radius_m: 0.5"), std::string::npos) << ball;
  EXPECT_EQ(ball.find("box:"), std::string::npos) << ball;
  EXPECT_EQ(toyFields().keyPaths(p), (std::vector<std::string>{"budget_s", "low_m", "high_m", "enabled", "size_m",
                                                               "samples", "shape", "ball", "ball.radius_m"}));
}

TEST(FieldTable, GivenEmittedYamlThenParseGivesTheSameStruct) {
  ToyParams p;
  p.budget_s = std::nextafter(1.0, 0.0);
  p.low_m = 0.1 + 0.2;
  p.enabled = false;
  p.size_m = {0.01, 1.0 / 3.0, 100.0};
  p.samples = std::numeric_limits<std::uint64_t>::max();
  p.box = {2.5, 64};
  for (const Shape shape : {Shape::kBox, Shape::kBall}) {
    p.shape = shape;
    ToyParams back;
    back.low_m = 9.0;
    back.enabled = true;
    ASSERT_EQ(toyError(toyFields().toYaml(p), &back), "");
    for (const FieldLeaf<ToyParams>& leaf : toyFields().leaves()) {
      if (!leaf.active(p)) continue;
      EXPECT_EQ(leaf.text(back), leaf.text(p)) << leaf.path;
      for (std::size_t i = 0; i < leaf.items; ++i) EXPECT_EQ(leaf.get(back, i), leaf.get(p, i)) << leaf.path;
    }
  }
}

TEST(FieldTable, GivenBadValuesThenParseAndValidateNameTheKeyPath) {
  const std::string good = toyFields().toYaml(ToyParams{});
  const auto with = [&good](const std::string& from, const std::string& to) {
    std::string text = good;
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  EXPECT_EQ(toyError(with("budget_s: 0.05", "budget_s: 1")), "toy.yaml:1: budget_s: 1 is out of range [0, 1)");
  EXPECT_EQ(toyError(with("  cells: 4", "  cells: 65")), "toy.yaml:10: box.cells: 65 is out of range [1, 64]");
  EXPECT_EQ(toyError(with("  cells: 4", "  cells: 3")), "toy.yaml:10: box.cells: must be even");
  EXPECT_EQ(toyError(with("high_m: 1.5", "high_m: 0.5")), "toy.yaml:3: high_m: must be > low_m");
  EXPECT_EQ(toyError(with("size_m: [3, 3, 2]", "size_m: [3, 0, 2]")),
            "toy.yaml:5: size_m: item 1: 0 is out of range [0.01, 100]");
  EXPECT_EQ(toyError(with("shape: box", "shape: cone")), "toy.yaml:7: shape: 'cone' is not one of: box, ball");
  EXPECT_EQ(toyError(with("samples: 7\n", "")), "toy.yaml:1: samples: missing required key");
  // The inactive section is not read: its key is an unknown key.
  EXPECT_EQ(toyError(good + "\nball: {radius_m: 1}"), "toy.yaml:11: ball: unknown key");

  ToyParams p;
  EXPECT_TRUE(toyFields().validate(p));
  p.budget_s = 1.0;
  EXPECT_EQ(toyFields().validate(p).error().message, "budget_s must be in [0, 1), got 1");
  p = ToyParams{};
  p.box.cells = 3;
  EXPECT_EQ(toyFields().validate(p).error().message, "box.cells must be even");
  p.shape = Shape::kBall;  // the box section is inactive now: not checked
  EXPECT_TRUE(toyFields().validate(p));
  p.ball.radius_m = 0.0;
  EXPECT_EQ(toyFields().validate(p).error().message, "ball.radius_m must be in (0, 5], got 0");
  p = ToyParams{};
  p.size_m[2] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(toyFields().validate(p).error().message, "size_m[2] must be in [0.01, 100], got inf");
  p = ToyParams{};
  p.high_m = 0.5;
  EXPECT_EQ(toyFields().validate(p).error().message, "high_m must be > low_m");
  p = ToyParams{};
  p.shape = static_cast<Shape>(7);
  EXPECT_EQ(toyFields().validate(p).error().message, "shape must be one of: box, ball");
}

TEST(FieldTable, GivenNestedSectionsThenLeavesCarryFullPathsAndAccessTheirMember) {
  const std::vector<FieldLeaf<ToyParams>> leaves = toyFields().leaves();
  std::vector<std::string> paths;
  for (const auto& leaf : leaves) paths.push_back(leaf.path);
  EXPECT_EQ(paths, (std::vector<std::string>{"budget_s", "low_m", "high_m", "enabled", "size_m", "samples", "shape",
                                             "box.width_m", "box.cells", "ball.radius_m"}));
  ToyParams p;
  leaves[8].set(p, 0, 12.0);
  EXPECT_EQ(p.box.cells, 12);
  leaves[4].set(p, 1, 7.5);
  EXPECT_EQ(p.size_m[1], 7.5);
  EXPECT_EQ(leaves[4].items, 3U);
  EXPECT_TRUE(leaves[7].active(p));
  EXPECT_FALSE(leaves[9].active(p));
  leaves[6].set(p, 0, 1.0);
  EXPECT_EQ(p.shape, Shape::kBall);
  EXPECT_TRUE(leaves[9].active(p));
  EXPECT_EQ(leaves[6].choices, (std::vector<std::string>{"box", "ball"}));
}

}  // namespace
}  // namespace aerotrack::rt
