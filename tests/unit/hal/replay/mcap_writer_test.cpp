// The MCAP writer against the slow reference reader (tests/support/mcap_reference_reader.hpp): every
// message back, in order, bit for bit, with every CRC and index checked, for each compression; the
// failure paths (an unwritable path, a size limit, a disk that fills mid-log) end with a counted error
// and a file that still reads.
#include "aerotrack/hal/replay/mcap_writer.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <random>

#include "support/mcap_reference_reader.hpp"
#include "support/temp_dir.hpp"

namespace aerotrack::hal::replay {
namespace {

using test::TempDir;

std::vector<std::uint8_t> payload(std::mt19937& rng, std::size_t max_bytes) {
  std::uniform_int_distribution<std::size_t> size(0, max_bytes);
  std::uniform_int_distribution<int> byte(0, 15);  // compressible, as real messages are
  std::vector<std::uint8_t> p(size(rng));
  for (auto& b : p) b = static_cast<std::uint8_t>(byte(rng));
  return p;
}

struct Written {
  std::vector<aerotrack::test::McapReadMessage> messages;
  McapWriterStats stats;
  bool close_ok;
};

/// Two schemas, three channels (one schemaless), n messages of up to max_bytes each.
Written writeSome(const std::string& path, const McapWriterOptions& options, int n, std::size_t max_bytes) {
  auto writer = McapWriter::open(path, options);
  EXPECT_TRUE(writer) << writer.error().message;
  McapWriter& w = **writer;
  const std::vector<std::uint8_t> fds = {1, 2, 3};
  const auto pose = w.addSchema("foxglove.Pose", "protobuf", fds);
  const auto mode = w.addSchema("mode", "jsonschema", std::vector<std::uint8_t>{'{', '}'});
  EXPECT_TRUE(pose && mode);
  const auto a = w.addChannel(*pose, "/drone/pose", "protobuf", {{"frame", "world"}});
  const auto b = w.addChannel(*mode, "/supervisor", "json");
  const auto c = w.addChannel(0, "/raw", "");
  EXPECT_TRUE(a && b && c);
  std::mt19937 rng(7);
  Written out;
  const std::uint16_t ids[] = {*a, *b, *c};
  std::uint32_t sequence[4] = {};
  for (int i = 0; i < n; ++i) {
    const std::uint16_t id = ids[static_cast<std::size_t>(i) % 3];
    const auto t = static_cast<std::uint64_t>(1'000'000'000LL + 1'000'000LL * i);
    std::vector<std::uint8_t> data = payload(rng, max_bytes);
    if (w.write(id, t, t + 5, data)) out.messages.push_back({id, sequence[id]++, t, t + 5, std::move(data)});
  }
  out.close_ok = static_cast<bool>(w.close());
  out.stats = w.stats();
  return out;
}

void expectSameMessages(const std::vector<aerotrack::test::McapReadMessage>& read,
                        const std::vector<aerotrack::test::McapReadMessage>& written, std::size_t count) {
  ASSERT_EQ(read.size(), count);
  for (std::size_t i = 0; i < count; ++i) {
    EXPECT_EQ(read[i].channel_id, written[i].channel_id) << i;
    EXPECT_EQ(read[i].sequence, written[i].sequence) << i;
    EXPECT_EQ(read[i].log_time_ns, written[i].log_time_ns) << i;
    EXPECT_EQ(read[i].publish_time_ns, written[i].publish_time_ns) << i;
    EXPECT_EQ(read[i].data, written[i].data) << i;
  }
}

TEST(McapWriter, EveryMessageReadsBackWithItsIndexesForEachCompression) {
  const TempDir dir;
  for (const McapCompression compression : {McapCompression::kZstd, McapCompression::kLz4, McapCompression::kNone}) {
    SCOPED_TRACE(mcapCompressionName(compression));
    McapWriterOptions options;
    options.compression = compression;
    options.chunk_bytes = 4096;  // many chunks
    const std::string path = dir.file("log.mcap");
    const Written w = writeSome(path, options, 3000, 300);
    ASSERT_TRUE(w.close_ok);
    const aerotrack::test::McapReadResult r = aerotrack::test::readMcapReference(path);
    EXPECT_TRUE(r.has_summary);
    EXPECT_EQ(r.schemas.size(), 2U);
    EXPECT_EQ(r.channels.size(), 3U);
    EXPECT_EQ(r.channels.at(1).first, "/drone/pose");
    EXPECT_GT(r.chunks, 50U);
    EXPECT_EQ(r.chunks, w.stats.chunks);
    EXPECT_EQ(w.stats.messages, 3000U);
    expectSameMessages(r.messages, w.messages, 3000);
    EXPECT_EQ(r.statistics_channel_counts.at(3), 1000U);
  }
}

TEST(McapWriter, AnEmptyLogIsAValidFile) {
  const TempDir dir;
  const std::string path = dir.file("empty.mcap");
  const Written w = writeSome(path, McapWriterOptions{}, 0, 10);
  ASSERT_TRUE(w.close_ok);
  const aerotrack::test::McapReadResult r = aerotrack::test::readMcapReference(path);
  EXPECT_TRUE(r.has_summary);
  EXPECT_EQ(r.messages.size(), 0U);
  EXPECT_EQ(r.chunks, 0U);
}

TEST(McapWriter, AnUnwritablePathIsOneLineAtOpen) {
  const auto writer = McapWriter::open("/nonexistent/dir/log.mcap", McapWriterOptions{});
  ASSERT_FALSE(writer);
  EXPECT_EQ(writer.error().message, "mcap: /nonexistent/dir/log.mcap: cannot create: No such file or directory");
  const auto device = McapWriter::open("/dev/full", McapWriterOptions{});
  ASSERT_FALSE(device);
  EXPECT_EQ(device.error().message, "mcap: /dev/full: not a regular file");
  const TempDir dir;
  ASSERT_EQ(::mkfifo(dir.file("fifo").c_str(), 0600), 0);
  const auto fifo = McapWriter::open(dir.file("fifo"), McapWriterOptions{});  // no reader: must not hang
  ASSERT_FALSE(fifo);
  EXPECT_EQ(fifo.error().message, "mcap: " + dir.file("fifo") + ": cannot create: No such device or address");
  EXPECT_FALSE(parseMcapCompression("gzip"));
}

TEST(McapWriter, ASizeLimitStopsTheLogWithACountedErrorAndTheFileStillReads) {
  const TempDir dir;
  McapWriterOptions options;
  options.compression = McapCompression::kNone;
  options.chunk_bytes = 2048;
  options.max_file_bytes = 20000;
  const std::string path = dir.file("limited.mcap");
  const Written w = writeSome(path, options, 3000, 100);
  EXPECT_FALSE(w.close_ok);
  EXPECT_GT(w.stats.dropped, 2000U);
  const aerotrack::test::McapReadResult r = aerotrack::test::readMcapReference(path);
  EXPECT_TRUE(r.has_summary);  // the summary is still added after the limit
  EXPECT_GT(r.chunks, 3U);
  // Everything in the file is what was written first, in order; the open chunk at the failure is lost.
  ASSERT_LE(r.messages.size(), w.messages.size());
  expectSameMessages(r.messages, w.messages, r.messages.size());
  EXPECT_EQ(w.stats.messages + w.stats.dropped, 3000U);
}

TEST(McapWriter, ADiskThatFillsMidLogLeavesEveryWholeChunkReadable) {
  // A child process with a file size limit (EFBIG past it, as ENOSPC on a full disk): the writer
  // fails mid-log, cuts the partial chunk off, and the summary cannot be written either.
  const TempDir dir;
  const std::string path = dir.file("full.mcap");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{30000, 30000};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    McapWriterOptions options;
    options.compression = McapCompression::kNone;
    options.chunk_bytes = 4000;
    const Written w = writeSome(path, options, 3000, 100);
    ::_exit(!w.close_ok && w.stats.dropped > 0 ? 0 : 1);
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  const aerotrack::test::McapReadResult r = aerotrack::test::readMcapReference(path);  // throws on a cut record
  EXPECT_GT(r.chunks, 4U);
  EXPECT_GT(r.messages.size(), 200U);
  for (std::size_t i = 0; i < r.messages.size(); ++i)
    EXPECT_EQ(r.messages[i].log_time_ns, 1'000'000'000ULL + 1'000'000ULL * i);
}

}  // namespace
}  // namespace aerotrack::hal::replay
