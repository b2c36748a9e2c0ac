// The input policy's whole-file reader (rt/input_file.hpp): every refusal is one line naming the
// file, and nothing larger than the limit is ever held in memory.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/input_file.hpp"
#include "aerotrack/rt/input_limits.hpp"

namespace aerotrack::rt {
namespace {

class InputFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("aerotrack_input_file_" + std::to_string(::getpid()) + "_" +
                                                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) const {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  std::filesystem::path dir_;
};

TEST_F(InputFile, GivenAFileWithinTheLimitThenItsBytesAreRead) {
  const std::string path = write("a.txt", std::string("a\0b\n", 4));
  const auto bytes = readBoundedFile(path, 4);
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_EQ(bytes.value(), std::string("a\0b\n", 4));
}

TEST_F(InputFile, GivenAFileOverTheLimitThenOneLineNamesTheFileAndTheLimit) {
  const std::string path = write("big.yaml", std::string(2049, 'x'));
  const auto bytes = readBoundedFile(path, 2048);
  ASSERT_FALSE(bytes);
  EXPECT_EQ(bytes.error().message, path + ": larger than the limit of 2 KiB for this kind of file");
  EXPECT_FALSE(checkInputFile(path, 2048));
  EXPECT_TRUE(checkInputFile(path, 4096));
}

TEST_F(InputFile, GivenAnEndlessDeviceThenReadingStopsAtTheLimit) {
  const auto bytes = readBoundedFile("/dev/zero", 1 << 20);
  ASSERT_FALSE(bytes);
  EXPECT_EQ(bytes.error().message, "/dev/zero: larger than the limit of 1 MiB for this kind of file");
  // The YAML readers go through it: a config or scenario of /dev/zero is refused, not read for ever.
  const auto yaml = ConfigNode::loadFile("/dev/zero");
  ASSERT_FALSE(yaml);
  EXPECT_EQ(yaml.error().message,
            "/dev/zero: larger than the limit of " + formatBytes(limits::kMaxYamlBytes) + " for this kind of file");
}

TEST_F(InputFile, GivenADirectoryOrNothingThenTheErrorSaysWhich) {
  EXPECT_EQ(readBoundedFile(dir_.string(), 100).error().message, dir_.string() + ": is a directory, expected a file");
  EXPECT_EQ(checkInputFile(dir_.string()).error().message, dir_.string() + ": is a directory, expected a file");
  const std::string missing = (dir_ / "missing.yaml").string();
  EXPECT_EQ(readBoundedFile(missing, 100).error().message, missing + ": cannot open file: no such file or directory");
}

TEST_F(InputFile, GivenAFifoWithNoWriterThenOpeningDoesNotHang) {
  const std::string path = (dir_ / "fifo").string();
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  // Opened without waiting for a writer; with none, the read sees the end at once.
  const auto bytes = readBoundedFile(path, 100);
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_TRUE(bytes.value().empty());
}

TEST(QuoteForMessage, GivenBinaryOrLongTextThenOnePrintableQuotedLine) {
  EXPECT_EQ(quoteForMessage("stamp_ns,x"), "'stamp_ns,x'");
  EXPECT_EQ(quoteForMessage(std::string("a\nb\x01\xff\\", 6)), "'a\\x0ab\\x01\\xff\\x5c'");
  EXPECT_EQ(quoteForMessage(std::string(100, 'z'), 10), "'zzzzzzzzzz'...");
}

TEST(FormatBytes, GivenExactMultiplesThenTheUnitElseBytes) {
  EXPECT_EQ(formatBytes(4 * limits::kMiB), "4 MiB");
  EXPECT_EQ(formatBytes(256 * limits::kKiB), "256 KiB");
  EXPECT_EQ(formatBytes(1000), "1000 bytes");
}

TEST(ConfigNode, GivenAKeyTwiceThenTheErrorNamesBothLines) {
  const auto top = ConfigNode::fromString("max_speed_mps: 2\nrate_hz: 5\nmax_speed_mps: 9\n", "c.yaml");
  ASSERT_FALSE(top);
  EXPECT_EQ(top.error().message, "c.yaml:3: max_speed_mps: given twice (first on line 1)");
  const auto nested = ConfigNode::fromString("a:\n  - {b: 1, c: {d: 1, d: 2}}\n", "n.yaml");
  ASSERT_FALSE(nested);
  EXPECT_EQ(nested.error().message, "n.yaml:2: a[0].c.d: given twice (first on line 2)");
  EXPECT_TRUE(ConfigNode::fromString("a: {d: 1}\nb: {d: 2}\n", "ok.yaml"));  // the same key in two maps
}

TEST(ConfigNode, GivenAKeyThatIsAListThenAnErrorNotATerminate) {
  // Found by fuzz_scenario: finish() converted every key to a string, and a list threw past parseConfig.
  const auto root = ConfigNode::fromString("name: x\n[a, b]: 1\n", "k.yaml");
  ASSERT_TRUE(root);
  const auto finished = parseConfig<int>([&] {
    (void)root->getString("name");
    root->finish();
    return 0;
  });
  ASSERT_FALSE(finished);
  EXPECT_EQ(finished.error().message, "k.yaml:2: a key must be a plain word, got a list or map");
}

}  // namespace
}  // namespace aerotrack::rt
