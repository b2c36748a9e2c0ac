// The MCAP writer's hot path (issue 24 item 5): once its buffers have grown to a chunk, writing a
// message -- chunks closed, compressed and written included -- allocates nothing, for each compression.
#include <gtest/gtest.h>

#include "aerotrack/hal/replay/mcap_writer.hpp"
#include "support/temp_dir.hpp"
#include "unit/malloc_counter.hpp"

namespace aerotrack::hal::replay {
namespace {

TEST(McapWriterAllocation, OnceWarmWritingAllocatesNothing) {
  if (!aerotrack::test::kMallocCounted) GTEST_SKIP() << "malloc is the sanitizer's";
  ASSERT_GE(aerotrack::test::mallocsOfAHeapBuffer(), 1);
  const test::TempDir dir;
  for (const McapCompression compression : {McapCompression::kZstd, McapCompression::kLz4, McapCompression::kNone}) {
    McapWriterOptions options;
    options.compression = compression;
    options.chunk_bytes = 64 * 1024;
    auto writer = McapWriter::open(dir.file("log.mcap"), options);
    ASSERT_TRUE(writer);
    const auto schema = (*writer)->addSchema("s", "jsonschema", std::vector<std::uint8_t>{'{', '}'});
    ASSERT_TRUE(schema);
    std::vector<std::uint16_t> channels;
    for (const char* topic : {"/a", "/b", "/c"}) channels.push_back(*(*writer)->addChannel(*schema, topic, "json"));
    std::vector<std::uint8_t> data(700, 7);
    std::uint64_t t = 0;
    // Warm-up: several chunks, so every buffer and per-channel index has grown to its size.
    for (int i = 0; i < 2000; ++i, t += 1000) ASSERT_TRUE((*writer)->write(channels[i % 3], t, t, data));
    const std::uint64_t chunks_before = (*writer)->stats().chunks;
    long mallocs = 0;
    {
      const aerotrack::test::MallocCount count;
      for (int i = 0; i < 2000; ++i, t += 1000) (void)(*writer)->write(channels[i % 3], t, t, data);
      mallocs = count.count();
    }
    const std::uint64_t chunks = (*writer)->stats().chunks - chunks_before;
    EXPECT_GE(chunks, 15U) << mcapCompressionName(compression);
    EXPECT_EQ(mallocs, 0) << mcapCompressionName(compression);
    ASSERT_TRUE((*writer)->close());
  }
}

}  // namespace
}  // namespace aerotrack::hal::replay
