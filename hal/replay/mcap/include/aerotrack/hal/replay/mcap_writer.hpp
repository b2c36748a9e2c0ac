// An MCAP file writer (issue 24 item 1): the container format Foxglove, Lichtblick and the ROS 2
// tooling read (https://mcap.dev/spec, format version 0). Written here because neither Debian 12
// nor npm ships the C++ library; it is checked against an independent reader, @mcap/core from npm
// (tools/foxglove/check_mcap.js), and against the slow reader of its unit test.
//
// Layout of a file: magic, Header, then the data section: Schema and Channel records as they are
// added, and the messages in Chunks (zstd, lz4 or uncompressed), each chunk followed by one Message
// Index record per channel it holds; then Data End (the data section's CRC-32), the summary section
// (every Schema and Channel again, Statistics, one Chunk Index per chunk), the Summary Offset records,
// the Footer (with the summary's CRC-32) and the magic. A reader seeks through the summary; a file
// cut short (kill -9, a full disk) still holds every whole chunk before the cut, readable in order.
//
// Cost: a message is copied into the open chunk's buffer and its (time, offset) appended to its
// channel's index; both keep their capacity from chunk to chunk, so once the buffers have grown to a
// chunk's size, writing allocates nothing. What the summary needs of each chunk is appended to two flat
// lists reserved for a thousand chunks (a GB at the default size), which grow by doubling beyond.
// A full chunk is compressed with a reused context and handed to the file with write(2).
//
// Failures are values: a failed write (a full disk, EIO) or a file grown past max_file_bytes ends
// the log. write() then returns the first error, every later message is counted as dropped, and the
// file keeps every chunk written before it.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::replay {

enum class McapCompression : std::uint8_t { kNone, kZstd, kLz4 };

/// "zstd", "lz4" or "" (the spec's names); parse: an Error for anything else ("none" is accepted for "").
const char* mcapCompressionName(McapCompression c);
rt::Expected<McapCompression> parseMcapCompression(std::string_view name);

struct McapWriterOptions {
  std::string profile;  ///< Header profile ("" or e.g. "ros2"); Foxglove's schemas need none.
  std::string library = "aerotrack";
  McapCompression compression = McapCompression::kZstd;
  std::size_t chunk_bytes = 1U << 20;  ///< A chunk is closed once its records reach this size.
  int zstd_level = 1;                  ///< Fast: the log must keep up with the flight on one core.
  /// > 0: the log stops (a counted error) before its data section passes this; the summary is still added.
  std::uint64_t max_file_bytes = 0;
};

/// What a writer has done so far.
struct McapWriterStats {
  std::uint64_t messages = 0;            ///< Messages accepted (in the file, or in the open chunk).
  std::uint64_t dropped = 0;             ///< Messages refused after the log failed, or lost with the chunk that failed.
  std::uint64_t chunks = 0;              ///< Chunks written to the file.
  std::uint64_t bytes_written = 0;       ///< Bytes handed to the file.
  std::uint64_t uncompressed_bytes = 0;  ///< Records inside the chunks written, before compression.
};

class McapWriter {
 public:
  /// Creates (or truncates) path and writes the magic and the Header. Error: cannot create, a
  /// chunk_bytes of 0.
  static rt::Expected<std::unique_ptr<McapWriter>> open(const std::string& path, const McapWriterOptions& options);
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// Registers a schema (e.g. "foxglove.SceneUpdate", encoding "protobuf", a serialized FileDescriptorSet)
  /// and returns its id (1, 2, ...). Written to the data section at once.
  rt::Expected<std::uint16_t> addSchema(std::string_view name, std::string_view encoding,
                                        std::span<const std::uint8_t> data);
  /// Registers a topic; schema_id 0 means schemaless. Error: an unknown schema id.
  rt::Expected<std::uint16_t> addChannel(std::uint16_t schema_id, std::string_view topic,
                                         std::string_view message_encoding,
                                         const std::map<std::string, std::string>& metadata = {});
  /// Appends a message (log and publish time in nanoseconds; the log time orders it for readers).
  /// Error: an unknown channel, or the log has failed (the message is counted as dropped).
  rt::Status write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
                   std::span<const std::uint8_t> data);
  /// Writes the open chunk, Data End, the summary and the footer, and closes the file. The first
  /// error of the log, if any (then the file ends after its last whole chunk). Idempotent.
  rt::Status close();

  const McapWriterStats& stats() const { return stats_; }
  /// The first error of the log (ok while it is healthy).
  const rt::Status& failure() const { return failure_; }
  const std::string& path() const { return path_; }

 private:
  struct ChunkIndex;
  struct ChannelInfo;
  struct Codec;
  McapWriter(std::string path, int fd, const McapWriterOptions& options);
  /// Appends bytes to the file (a failed write is cut off again); the log's state is untouched.
  rt::Status appendToFile(std::span<const std::uint8_t> bytes);
  /// appendToFile, unless the log has failed or would pass its size limit; a failure ends the log.
  rt::Status writeFile(std::span<const std::uint8_t> bytes);
  rt::Status flushChunk();
  void fail(rt::Error error);

  std::string path_;
  int fd_ = -1;
  McapWriterOptions options_;
  std::uint64_t offset_ = 0;           ///< Bytes written so far: the next record's file offset.
  std::uint32_t data_crc_ = 0;         ///< CRC-32 of every byte written so far (the data section, then the summary).
  std::vector<std::uint8_t> scratch_;  ///< A record being assembled outside chunks.
  std::vector<std::uint8_t> chunk_;    ///< The open chunk's records, uncompressed.
  std::vector<std::uint8_t> packed_;   ///< A chunk's compressed records.
  std::uint64_t chunk_start_ns_ = 0;
  std::uint64_t chunk_end_ns_ = 0;
  std::uint64_t message_start_ns_ = 0;
  std::uint64_t message_end_ns_ = 0;
  std::vector<std::pair<std::uint16_t, std::vector<std::uint8_t>>> schemas_;  ///< id, whole record
  std::vector<ChannelInfo> channels_;
  std::vector<ChunkIndex> chunk_indexes_;
  std::vector<std::pair<std::uint16_t, std::uint64_t>>
      index_offsets_;  ///< Every chunk's (channel, Message Index offset)
  std::unique_ptr<Codec> codec_;
  McapWriterStats stats_;
  rt::Status failure_;
  bool closed_ = false;
};

}  // namespace aerotrack::hal::replay
