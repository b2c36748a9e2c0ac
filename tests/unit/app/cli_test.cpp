// Command-line parsing: strict options, required values, numbers with ranges.
#include <gtest/gtest.h>

#include "cli.hpp"
#include "commands.hpp"

namespace aerotrack::app {
namespace {

rt::Expected<ParsedArgs> parse(std::vector<std::string> args) {
  return parseArgs(args, commandTable());
}

TEST(Cli, GivenNoArgumentsThenErrorSuggestsHelp) {
  const auto a = parse({});
  ASSERT_FALSE(a);
  EXPECT_EQ(a.error().message, "no command given; try 'aerotrack --help'");
}

TEST(Cli, GivenTopLevelHelpThenHelpWithoutCommand) {
  const auto a = parse({"--help"});
  ASSERT_TRUE(a);
  EXPECT_TRUE(a->help);
  EXPECT_TRUE(a->command.empty());
}

TEST(Cli, GivenUnknownCommandThenError) {
  const auto a = parse({"fly"});
  ASSERT_FALSE(a);
  EXPECT_EQ(a.error().message, "unknown command 'fly'; try 'aerotrack --help'");
}

TEST(Cli, GivenSimOptionsThenParsed) {
  const auto a = parse({"sim", "--scenario", "open", "--seed=7", "--realtime"});
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ(a->command, "sim");
  EXPECT_EQ(a->values.at("scenario"), "open");
  EXPECT_EQ(a->values.at("seed"), "7");
  EXPECT_TRUE(a->flags.count("realtime"));
  EXPECT_EQ(a->valueOr("out", "x"), "x");
}

TEST(Cli, GivenBadOptionsThenOneLineErrors) {
  EXPECT_EQ(parse({"sim", "--scenario", "open", "--sead", "1"}).error().message, "sim: unknown option '--sead'");
  EXPECT_EQ(parse({"sim", "--scenario"}).error().message, "sim: option '--scenario' needs a value NAME|FILE");
  EXPECT_EQ(parse({"sim"}).error().message, "sim: missing required option --scenario NAME|FILE");
  EXPECT_EQ(parse({"sim", "--scenario", "a", "--scenario", "b"}).error().message,
            "sim: option '--scenario' given twice");
  EXPECT_EQ(parse({"sim", "--scenario", "a", "--realtime=yes"}).error().message,
            "sim: option '--realtime' takes no value");
  EXPECT_EQ(parse({"run", "--config", "a", "extra"}).error().message, "run: unexpected argument 'extra'");
  EXPECT_EQ(parse({"detect"}).error().message, "detect: missing argument IMAGE|VIDEO");
}

TEST(Cli, GivenARepeatableOptionThenEveryValueIsKeptInOrder) {
  const auto a = parse({"sim", "--scenario", "open", "--set", "a.b=1", "--set=c=2,3", "--set", "a.b=4"});
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ(a->listOf("set"), (std::vector<std::string>{"a.b=1", "c=2,3", "a.b=4"}));
  EXPECT_TRUE(a->has("set"));
  EXPECT_TRUE(a->listOf("slurm-option").empty());
  const auto overrides = configOverrides(*a);
  ASSERT_TRUE(overrides);
  ASSERT_EQ(overrides->size(), 3U);
  EXPECT_EQ((*overrides)[1].key, "c");
  EXPECT_EQ((*overrides)[1].value, "2,3");
  EXPECT_EQ(configOverrides(*parse({"sim", "--scenario", "o", "--set", "novalue"})).error().message,
            "--set: expected KEY=VALUE, got 'novalue'");
}

TEST(Cli, GivenASubCommandThenItsOwnOptionsAndArgumentAreParsed) {
  const auto merge = parse({"bench", "merge", "out/x", "--resubmit-missing"});
  ASSERT_TRUE(merge) << merge.error().message;
  EXPECT_EQ(merge->command, "bench merge");
  EXPECT_EQ(*merge->positional, "out/x");
  EXPECT_TRUE(merge->flags.count("resubmit-missing"));
  EXPECT_EQ(parse({"bench", "merge"}).error().message, "bench merge: missing argument DIR");
  EXPECT_EQ(parse({"bench", "merge", "d", "--trials", "3"}).error().message, "bench merge: unknown option '--trials'");
  const auto bench = parse({"bench", "--suite", "s.yaml"});  // the command itself is still there
  ASSERT_TRUE(bench);
  EXPECT_EQ(bench->command, "bench");
}

TEST(Cli, NumbersAreCheckedAndNamed) {
  EXPECT_EQ(*parseInt("seed", "42", 0, 100), 42);
  EXPECT_EQ(parseInt("seed", "4x", 0, 100).error().message, "--seed: expected an integer, got '4x'");
  EXPECT_EQ(parseInt("seed", "-1", 0, 100).error().message, "--seed: -1 is out of range [0, 100]");
  EXPECT_EQ(parseInt("seed", "99999999999999999999", 0, 100).error().message,
            "--seed: expected an integer, got '99999999999999999999'");
  EXPECT_EQ(*parseDouble("duration-s", "2.5", 0, 10), 2.5);
  EXPECT_EQ(parseDouble("duration-s", "nan", 0, 10).error().message, "--duration-s: expected a number, got 'nan'");
  EXPECT_EQ(parseDouble("duration-s", "", 0, 10).error().message, "--duration-s: expected a number, got ''");
}

TEST(Cli, EveryDesignCommandIsListedInUsage) {
  const std::string text = usage(commandTable());
  for (const char* c : {"run", "sim", "bench", "detect", "calibrate", "eval-localization"})
    EXPECT_NE(text.find(std::string("  ") + c + " "), std::string::npos) << c;
}

}  // namespace
}  // namespace aerotrack::app
