// The MCAP writer: see mcap_writer.hpp. Record layouts follow https://mcap.dev/spec (version 0):
// little-endian integers, a record is opcode (1 byte) + content length (8 bytes) + content.
#include "aerotrack/hal/replay/mcap_writer.hpp"

#include <fcntl.h>
#include <lz4frame.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>
// The static-context API (exported by Debian's libzstd): a compressor over memory reserved once.
#define ZSTD_STATIC_LINKING_ONLY
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

namespace aerotrack::hal::replay {
namespace {

constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

/// Appends little-endian integers, strings and records to a byte buffer.
class Out {
 public:
  explicit Out(std::vector<std::uint8_t>& buffer) : b_(buffer) {}
  template <class T>
  void put(T value) {
    for (std::size_t i = 0; i < sizeof(T); ++i) b_.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
  }
  void bytes(std::span<const std::uint8_t> data) { b_.insert(b_.end(), data.begin(), data.end()); }
  void string(std::string_view s) {
    put(static_cast<std::uint32_t>(s.size()));
    b_.insert(b_.end(), s.begin(), s.end());
  }
  /// Starts a record: opcode and a length to be filled in by end().
  std::size_t begin(std::uint8_t opcode) {
    b_.push_back(opcode);
    const std::size_t at = b_.size();
    put(std::uint64_t{0});
    return at;
  }
  void end(std::size_t at) { patch64(at, b_.size() - at - 8); }
  /// A u32 byte length to be filled in by endLength() (maps and arrays).
  std::size_t beginLength() {
    const std::size_t at = b_.size();
    put(std::uint32_t{0});
    return at;
  }
  void endLength(std::size_t at) {
    const auto n = static_cast<std::uint32_t>(b_.size() - at - 4);
    for (std::size_t i = 0; i < 4; ++i) b_[at + i] = static_cast<std::uint8_t>(n >> (8 * i));
  }
  void patch64(std::size_t at, std::uint64_t v) {
    for (std::size_t i = 0; i < 8; ++i) b_[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
  }

 private:
  std::vector<std::uint8_t>& b_;
};

std::uint32_t crc32Of(std::uint32_t crc, std::span<const std::uint8_t> bytes) {
  // zlib's crc32 takes a uInt length: feed large spans in pieces.
  std::size_t done = 0;
  while (done < bytes.size()) {
    const std::size_t n = std::min<std::size_t>(bytes.size() - done, 1U << 30);
    crc = static_cast<std::uint32_t>(::crc32(crc, bytes.data() + done, static_cast<uInt>(n)));
    done += n;
  }
  return crc;
}

}  // namespace

const char* mcapCompressionName(McapCompression c) {
  switch (c) {
    case McapCompression::kZstd:
      return "zstd";
    case McapCompression::kLz4:
      return "lz4";
    case McapCompression::kNone:
      break;
  }
  return "";
}

rt::Expected<McapCompression> parseMcapCompression(std::string_view name) {
  if (name == "zstd") return McapCompression::kZstd;
  if (name == "lz4") return McapCompression::kLz4;
  if (name.empty() || name == "none") return McapCompression::kNone;
  return rt::Error{"unknown MCAP compression '" + std::string(name) + "' (zstd, lz4 or none)"};
}

struct McapWriter::ChunkIndex {
  std::uint64_t start_ns;
  std::uint64_t end_ns;
  std::uint64_t offset;
  std::uint64_t length;
  std::size_t first_offset;  ///< Its Message Index offsets: index_offsets_[first_offset, +offset_count).
  std::size_t offset_count;
  std::uint64_t index_length;
  std::uint64_t compressed_size;
  std::uint64_t uncompressed_size;
};

struct McapWriter::ChannelInfo {
  std::uint16_t id;
  std::vector<std::uint8_t> record;                            ///< The whole Channel record, repeated in the summary.
  std::uint64_t messages = 0;                                  ///< Accepted (the next message's sequence number).
  std::uint64_t in_file = 0;                                   ///< In chunks written to the file.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> index;  ///< (log time, offset in chunk) of the open chunk
};

/// The compressor, with its context kept from chunk to chunk.
/// zstd's context is a static one over a workspace reserved at open, with its parameters fixed for a whole
/// chunk: a dynamic context re-sizes its workspace as chunk sizes wander, an allocation now and then.
struct McapWriter::Codec {
  std::vector<std::uint64_t> zstd_workspace;  ///< 8-byte aligned, as zstd asks
  ZSTD_CCtx* zstd = nullptr;                  ///< lives in the workspace: nothing to free
  LZ4F_preferences_t lz4{};

  bool initZstd(int level, std::size_t max_source_bytes) {
    const ZSTD_compressionParameters p = ZSTD_getCParams(level, max_source_bytes, 0);
    const std::size_t bytes = ZSTD_estimateCCtxSize_usingCParams(p);
    zstd_workspace.assign((bytes + 7) / 8, 0);
    zstd = ZSTD_initStaticCCtx(zstd_workspace.data(), zstd_workspace.size() * 8);
    if (zstd == nullptr) return false;
    const std::pair<ZSTD_cParameter, int> fixed[] = {
        {ZSTD_c_windowLog, static_cast<int>(p.windowLog)}, {ZSTD_c_chainLog, static_cast<int>(p.chainLog)},
        {ZSTD_c_hashLog, static_cast<int>(p.hashLog)},     {ZSTD_c_searchLog, static_cast<int>(p.searchLog)},
        {ZSTD_c_minMatch, static_cast<int>(p.minMatch)},   {ZSTD_c_targetLength, static_cast<int>(p.targetLength)},
        {ZSTD_c_strategy, static_cast<int>(p.strategy)}};
    for (const auto& [parameter, value] : fixed) {
      if (ZSTD_isError(ZSTD_CCtx_setParameter(zstd, parameter, value)) != 0U) return false;
    }
    return true;
  }
};

McapWriter::McapWriter(std::string path, int fd, const McapWriterOptions& options)
    : path_(std::move(path)), fd_(fd), options_(options), codec_(std::make_unique<Codec>()) {
  // Room for a chunk and for what it becomes (compressed, with its header and message indexes), so that the
  // buffers do not grow chunk after chunk as their sizes wander (a message larger than a quarter chunk
  // still grows them, once).
  chunk_.reserve(options_.chunk_bytes + (options_.chunk_bytes >> 2));
  const std::size_t packed =
      std::max(ZSTD_compressBound(chunk_.capacity()), LZ4F_compressFrameBound(chunk_.capacity(), nullptr));
  packed_.reserve(packed);
  scratch_.reserve(packed + (options_.chunk_bytes >> 1));
  chunk_indexes_.reserve(1024);  // a GB of log at the default chunk size before the first growth
  index_offsets_.reserve(8192);
  if (options_.compression == McapCompression::kZstd && !codec_->initZstd(options_.zstd_level, chunk_.capacity())) {
    fail(rt::Error{"mcap: " + path_ + ": cannot set up the zstd compressor"});
  }
}

McapWriter::~McapWriter() {
  (void)close();
}

rt::Expected<std::unique_ptr<McapWriter>> McapWriter::open(const std::string& path, const McapWriterOptions& options) {
  if (options.chunk_bytes == 0) return rt::Error{"mcap: " + path + ": chunk size 0"};
  // O_NONBLOCK: a FIFO without a reader must not hang the start (it is refused below, as any file that
  // is not a regular one: the log seeks nothing, but a device or a pipe cannot hold a summary to read).
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | O_NONBLOCK, 0644);
  if (fd < 0) return rt::Error{"mcap: " + path + ": cannot create: " + std::strerror(errno)};
  struct stat info {};
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    ::close(fd);
    return rt::Error{"mcap: " + path + ": not a regular file"};
  }
  if (::ftruncate(fd, 0) != 0) {
    const int err = errno;
    ::close(fd);
    return rt::Error{"mcap: " + path + ": cannot truncate: " + std::strerror(err)};
  }
  std::unique_ptr<McapWriter> writer(new McapWriter(path, fd, options));
  std::vector<std::uint8_t> head(kMagic.begin(), kMagic.end());
  Out out(head);
  const std::size_t at = out.begin(kHeader);
  out.string(options.profile);
  out.string(options.library);
  out.end(at);
  if (rt::Status s = writer->writeFile(head); !s) return s.error();
  return writer;
}

void McapWriter::fail(rt::Error error) {
  if (failure_) failure_ = std::move(error);
}

rt::Status McapWriter::appendToFile(std::span<const std::uint8_t> bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : EIO;
      // Cut the partial record off, so that the file ends after its last whole one.
      if (::ftruncate(fd_, static_cast<off_t>(offset_)) == 0) (void)::lseek(fd_, static_cast<off_t>(offset_), SEEK_SET);
      return rt::Error{"mcap: " + path_ + ": write failed: " + std::strerror(err)};
    }
    done += static_cast<std::size_t>(n);
  }
  offset_ += bytes.size();
  data_crc_ = crc32Of(data_crc_, bytes);
  stats_.bytes_written += bytes.size();
  return rt::ok();
}

rt::Status McapWriter::writeFile(std::span<const std::uint8_t> bytes) {
  if (!failure_) return failure_;
  if (options_.max_file_bytes > 0 && offset_ + bytes.size() > options_.max_file_bytes) {
    fail(rt::Error{"mcap: " + path_ + ": the log reached its size limit of " + std::to_string(options_.max_file_bytes) +
                   " bytes; it stops here"});
    return failure_;
  }
  if (rt::Status s = appendToFile(bytes); !s) fail(s.error());
  return failure_;
}

rt::Expected<std::uint16_t> McapWriter::addSchema(std::string_view name, std::string_view encoding,
                                                  std::span<const std::uint8_t> data) {
  if (closed_) return rt::Error{"mcap: " + path_ + ": closed"};
  const auto id = static_cast<std::uint16_t>(schemas_.size() + 1);
  std::vector<std::uint8_t> record;
  Out out(record);
  const std::size_t at = out.begin(kSchema);
  out.put(id);
  out.string(name);
  out.string(encoding);
  out.put(static_cast<std::uint32_t>(data.size()));
  out.bytes(data);
  out.end(at);
  // Before any chunk that may use it: the open chunk is written later, so file order holds.
  if (rt::Status s = writeFile(record); !s) return s.error();
  schemas_.emplace_back(id, std::move(record));
  return id;
}

rt::Expected<std::uint16_t> McapWriter::addChannel(std::uint16_t schema_id, std::string_view topic,
                                                   std::string_view message_encoding,
                                                   const std::map<std::string, std::string>& metadata) {
  if (closed_) return rt::Error{"mcap: " + path_ + ": closed"};
  if (schema_id > schemas_.size()) {
    return rt::Error{"mcap: " + path_ + ": channel " + std::string(topic) + ": unknown schema " +
                     std::to_string(schema_id)};
  }
  ChannelInfo channel;
  channel.id = static_cast<std::uint16_t>(channels_.size() + 1);
  Out out(channel.record);
  const std::size_t at = out.begin(kChannel);
  out.put(channel.id);
  out.put(schema_id);
  out.string(topic);
  out.string(message_encoding);
  const std::size_t map_at = out.beginLength();
  for (const auto& [key, value] : metadata) {
    out.string(key);
    out.string(value);
  }
  out.endLength(map_at);
  out.end(at);
  if (rt::Status s = writeFile(channel.record); !s) return s.error();
  channel.index.reserve(256);
  channels_.push_back(std::move(channel));
  return channels_.back().id;
}

rt::Status McapWriter::write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
                             std::span<const std::uint8_t> data) {
  if (!failure_ || closed_) {
    ++stats_.dropped;
    return failure_ ? rt::Status(rt::Error{"mcap: " + path_ + ": closed"}) : failure_;
  }
  if (channel_id == 0 || channel_id > channels_.size()) {
    return rt::Error{"mcap: " + path_ + ": unknown channel " + std::to_string(channel_id)};
  }
  ChannelInfo& channel = channels_[channel_id - 1];
  if (chunk_.empty()) {
    chunk_start_ns_ = log_time_ns;
    chunk_end_ns_ = log_time_ns;
  }
  chunk_start_ns_ = std::min(chunk_start_ns_, log_time_ns);
  chunk_end_ns_ = std::max(chunk_end_ns_, log_time_ns);
  channel.index.emplace_back(log_time_ns, chunk_.size());
  Out out(chunk_);
  const std::size_t at = out.begin(kMessage);
  out.put(channel_id);
  out.put(static_cast<std::uint32_t>(channel.messages));
  out.put(log_time_ns);
  out.put(publish_time_ns);
  out.bytes(data);
  out.end(at);
  ++channel.messages;
  ++stats_.messages;
  if (chunk_.size() >= options_.chunk_bytes) return flushChunk();
  return rt::ok();
}

rt::Status McapWriter::flushChunk() {
  if (chunk_.empty()) return rt::ok();
  const std::uint32_t crc = crc32Of(0, chunk_);
  std::span<const std::uint8_t> records = chunk_;
  if (options_.compression == McapCompression::kZstd) {
    packed_.resize(ZSTD_compressBound(chunk_.size()));
    const std::size_t n = ZSTD_compress2(codec_->zstd, packed_.data(), packed_.size(), chunk_.data(), chunk_.size());
    if (ZSTD_isError(n) != 0U) {
      fail(rt::Error{"mcap: " + path_ + ": zstd: " + ZSTD_getErrorName(n)});
      return failure_;
    }
    records = std::span<const std::uint8_t>(packed_.data(), n);
  } else if (options_.compression == McapCompression::kLz4) {
    packed_.resize(LZ4F_compressFrameBound(chunk_.size(), &codec_->lz4));
    const std::size_t n =
        LZ4F_compressFrame(packed_.data(), packed_.size(), chunk_.data(), chunk_.size(), &codec_->lz4);
    if (LZ4F_isError(n) != 0U) {
      fail(rt::Error{"mcap: " + path_ + ": lz4: " + LZ4F_getErrorName(n)});
      return failure_;
    }
    records = std::span<const std::uint8_t>(packed_.data(), n);
  }
  // The chunk record and its Message Index records, handed to the file in one write: a failure
  // cuts the whole of it off.
  ChunkIndex index{chunk_start_ns_, chunk_end_ns_, offset_, 0, index_offsets_.size(), 0, 0,
                   records.size(),  chunk_.size()};
  scratch_.clear();
  Out out(scratch_);
  const char* compression = mcapCompressionName(options_.compression);
  out.put(kChunk);
  out.put(std::uint64_t{8 + 8 + 8 + 4 + 4 + std::strlen(compression) + 8 + records.size()});
  out.put(chunk_start_ns_);
  out.put(chunk_end_ns_);
  out.put(static_cast<std::uint64_t>(chunk_.size()));
  out.put(crc);
  out.string(compression);
  out.put(static_cast<std::uint64_t>(records.size()));
  out.bytes(records);
  index.length = scratch_.size();
  const std::size_t indexes_at = scratch_.size();
  for (ChannelInfo& channel : channels_) {
    if (channel.index.empty()) continue;
    index_offsets_.emplace_back(channel.id, offset_ + scratch_.size());
    ++index.offset_count;
    const std::size_t at = out.begin(kMessageIndex);
    out.put(channel.id);
    out.put(static_cast<std::uint32_t>(channel.index.size() * 16));
    for (const auto& [time_ns, offset] : channel.index) {
      out.put(time_ns);
      out.put(offset);
    }
    out.end(at);
  }
  index.index_length = scratch_.size() - indexes_at;
  if (rt::Status s = writeFile(scratch_); !s) {
    // The chunk's messages are lost with it.
    index_offsets_.resize(index.first_offset);
    for (ChannelInfo& channel : channels_) {
      stats_.dropped += channel.index.size();
      stats_.messages -= channel.index.size();
      channel.index.clear();
    }
    chunk_.clear();
    return s;
  }
  if (stats_.chunks == 0) message_start_ns_ = chunk_start_ns_, message_end_ns_ = chunk_end_ns_;
  message_start_ns_ = std::min(message_start_ns_, chunk_start_ns_);
  message_end_ns_ = std::max(message_end_ns_, chunk_end_ns_);
  for (ChannelInfo& channel : channels_) {
    channel.in_file += channel.index.size();
    channel.index.clear();
  }
  stats_.uncompressed_bytes += chunk_.size();
  ++stats_.chunks;
  chunk_indexes_.push_back(index);
  chunk_.clear();
  return rt::ok();
}

rt::Status McapWriter::close() {
  if (closed_) return failure_;
  (void)flushChunk();
  closed_ = true;
  // After a failure the summary is still tried (a size limit leaves room for it, a full disk may not);
  // if it cannot be written the file ends after its last whole chunk.
  std::vector<std::uint8_t> tail;
  Out out(tail);
  std::size_t at = out.begin(kDataEnd);
  const std::uint32_t data_crc = data_crc_;
  out.put(data_crc);
  out.end(at);
  const std::uint64_t summary_start = offset_ + tail.size();
  struct Group {
    std::uint8_t opcode;
    std::uint64_t start;
    std::uint64_t length;
  };
  std::vector<Group> groups;
  auto group = [&](std::uint8_t opcode, std::size_t from) {
    if (tail.size() > from) groups.push_back({opcode, offset_ + from, tail.size() - from});
  };
  std::size_t from = tail.size();
  for (const auto& [id, record] : schemas_) out.bytes(record);
  group(kSchema, from);
  from = tail.size();
  for (const ChannelInfo& channel : channels_) out.bytes(channel.record);
  group(kChannel, from);
  from = tail.size();
  at = out.begin(kStatistics);
  std::uint64_t in_file = 0;
  for (const ChannelInfo& channel : channels_) in_file += channel.in_file;
  out.put(in_file);
  out.put(static_cast<std::uint16_t>(schemas_.size()));
  out.put(static_cast<std::uint32_t>(channels_.size()));
  out.put(std::uint32_t{0});  // attachments
  out.put(std::uint32_t{0});  // metadata
  out.put(static_cast<std::uint32_t>(chunk_indexes_.size()));
  out.put(message_start_ns_);
  out.put(message_end_ns_);
  std::size_t map_at = out.beginLength();
  for (const ChannelInfo& channel : channels_) {
    out.put(channel.id);
    out.put(channel.in_file);
  }
  out.endLength(map_at);
  out.end(at);
  group(kStatistics, from);
  from = tail.size();
  for (const ChunkIndex& c : chunk_indexes_) {
    at = out.begin(kChunkIndex);
    out.put(c.start_ns);
    out.put(c.end_ns);
    out.put(c.offset);
    out.put(c.length);
    map_at = out.beginLength();
    for (std::size_t k = c.first_offset; k < c.first_offset + c.offset_count; ++k) {
      const auto& [id, offset] = index_offsets_[k];
      out.put(id);
      out.put(offset);
    }
    out.endLength(map_at);
    out.put(c.index_length);
    out.string(mcapCompressionName(options_.compression));
    out.put(c.compressed_size);
    out.put(c.uncompressed_size);
    out.end(at);
  }
  group(kChunkIndex, from);
  const std::uint64_t summary_offset_start = offset_ + tail.size();
  for (const Group& g : groups) {
    at = out.begin(kSummaryOffset);
    out.put(g.opcode);
    out.put(g.start);
    out.put(g.length);
    out.end(at);
  }
  const std::size_t summary_at = static_cast<std::size_t>(summary_start - offset_);
  out.put(kFooter);
  out.put(std::uint64_t{20});
  out.put(summary_start);
  out.put(summary_offset_start);
  const std::uint32_t summary_crc =
      crc32Of(0, std::span<const std::uint8_t>(tail.data() + summary_at, tail.size() - summary_at));
  out.put(summary_crc);
  out.bytes(kMagic);
  if (rt::Status s = appendToFile(tail); !s) fail(s.error());
  if (::close(fd_) != 0) fail(rt::Error{"mcap: " + path_ + ": close failed: " + std::strerror(errno)});
  fd_ = -1;
  return failure_;
}

}  // namespace aerotrack::hal::replay
