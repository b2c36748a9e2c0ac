// Raw CAN traffic as candump -l logs (hal/replay/candump.hpp): golden lines in can-utils' format (as
// its README and candump -l write them) parse to the frames they mean and format back to the same
// text; standard, extended, remote, empty and error frames; a log written and read back keeps every
// frame; a killed writer's partial last line ends the log; bad lines name the file and line (strict)
// or are skipped and counted.
#include "aerotrack/hal/replay/candump.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "support/temp_dir.hpp"

namespace aerotrack::hal::replay {
namespace {

TEST(Candump, GoldenLinesParseToTheirFramesAndFormatBackToTheSameText) {
  // A speed command to an RMD-X motor with id 1 (0x141: 0xA2, then int32 0.01 deg/s little-endian).
  const std::string speed = "(1700000000.123456) can0 141#A200000010270000";
  auto f = parseCandumpLine(speed);
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_EQ(f->stamp_ns, 1700000000123456000LL);
  EXPECT_EQ(f->interface, "can0");
  EXPECT_EQ(f->id, 0x141U);
  EXPECT_FALSE(f->extended);
  EXPECT_EQ(f->length, 8);
  EXPECT_EQ(f->data[0], 0xA2);
  EXPECT_EQ(f->data[4] | (f->data[5] << 8), 10000);  // 100 deg/s
  EXPECT_EQ(formatCandumpLine(*f), speed);

  const std::pair<std::string, CanLogRecord> golden[] = {
      {"(1436509052.249713) vcan0 044#2A366C2BBA",
       {1436509052249713000, "vcan0", 0x44, false, false, false, 5, {0x2A, 0x36, 0x6C, 0x2B, 0xBA}}},
      {"(0.000001) can1 12345678#", {1000, "can1", 0x12345678, true, false, false, 0, {}}},
      {"(12.500000) can0 7FF#R", {12'500'000'000, "can0", 0x7FF, false, true, false, 0, {}}},
      {"(12.500001) can0 123#R8", {12'500'001'000, "can0", 0x123, false, true, false, 8, {}}},
      {"(13.000000) can0 20000040#0000000000000000",  // an error frame: bus-off (CAN_ERR_BUSOFF, 0x40)
       {13'000'000'000, "can0", 0x40, false, false, true, 8, {}}}};
  for (const auto& [line, expected] : golden) {
    auto parsed = parseCandumpLine(line);
    ASSERT_TRUE(parsed) << line << ": " << parsed.error().message;
    EXPECT_EQ(*parsed, expected) << line;
    EXPECT_EQ(formatCandumpLine(expected), line);
  }
}

TEST(Candump, BadLinesAreRejectedWithAReason) {
  for (const char* line : {"", "1.000000 can0 141#00", "(1.0) can0 141#00", "(1.000000) can0", "(1.000000) can0 141",
                           "(1.000000) can0 1411#00", "(1.000000) can0 800#00", "(1.000000) can0 141#0",
                           "(1.000000) can0 141#000102030405060708", "(1.000000) can0 141#GG",
                           "(1.000000) can0 141##100", "(1.000000) can0 141#R9", "(x.000000) can0 141#00"}) {
    EXPECT_FALSE(parseCandumpLine(line)) << "'" << line << "'";
  }
}

TEST(Candump, ALogWrittenAndReadBackKeepsEveryFrameAndAKilledWritersLastLineEndsIt) {
  test::TempDir dir;
  const std::string path = dir.file("can.log");
  std::vector<CanLogRecord> frames;
  {
    auto writer = CandumpWriter::create(path);
    ASSERT_TRUE(writer);
    for (int i = 0; i < 300; ++i) {
      CanLogRecord f;
      f.stamp_ns = 5'000'000'000 + i * 1'000'000LL;  // whole microseconds: exact through the format
      f.interface = "can0";
      f.id = i % 3 == 0 ? 0x241U : 0x141U;
      f.extended = i % 7 == 0;
      f.length = static_cast<std::uint8_t>(i % 9);
      for (std::uint8_t k = 0; k < f.length; ++k) f.data[k] = static_cast<std::uint8_t>(i * 31 + k);
      ASSERT_TRUE(writer->write(f));
      frames.push_back(f);
    }
  }
  std::ofstream(path, std::ios::app) << "(5.300000) can0 141#A2";  // cut mid-line
  const auto log = loadCandump(path, BadRowPolicy::kStrict);
  ASSERT_TRUE(log) << log.error().message;
  EXPECT_TRUE(log->truncated_tail);
  ASSERT_EQ(log->frames.size(), frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) EXPECT_EQ(log->frames[i], frames[i]) << i;
}

TEST(Candump, StrictStopsAtTheFirstBadLineNamingItAndSkipCountsThem) {
  test::TempDir dir;
  const std::string path = dir.file("can.log");
  std::ofstream(path) << "(1.000000) can0 141#A2\n"
                         "(1.000100) can0 141#ZZ\n"  // line 2: not hex
                         "(0.500000) can0 241#A2\n"  // line 3: back in time
                         "(1.000300) can0 241#A200\n";
  const auto strict = loadCandump(path, BadRowPolicy::kStrict);
  ASSERT_FALSE(strict);
  EXPECT_NE(strict.error().message.find("can.log:2: data 'ZZ' is not hex"), std::string::npos)
      << strict.error().message;
  const auto skip = loadCandump(path, BadRowPolicy::kSkip);
  ASSERT_TRUE(skip);
  EXPECT_EQ(skip->frames.size(), 2U);
  EXPECT_EQ(skip->skipped_lines, 2U);
  EXPECT_NE(skip->first_skip_message.find("can.log:2:"), std::string::npos);
  const auto missing = loadCandump(dir.file("none.log"), BadRowPolicy::kSkip);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("none.log: cannot open"), std::string::npos);
}

}  // namespace
}  // namespace aerotrack::hal::replay
