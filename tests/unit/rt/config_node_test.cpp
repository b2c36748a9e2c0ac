// The strict YAML reader: every error class names the file, the line and the key.
#include <gtest/gtest.h>

#include "aerotrack/rt/config_node.hpp"

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
  EXPECT_EQ(root.error().message, "/nonexistent/aerotrack.yaml: cannot open file");
}

}  // namespace
}  // namespace aerotrack::rt
