// A slow, obvious MCAP reader for the tests (https://mcap.dev/spec, version 0), independent of the
// writer's code: it walks the file record by record, decompresses every chunk, and checks every
// CRC, every message index against the chunk it follows, the statistics, the chunk indexes and the
// summary offsets against what it walked. The second independent check is @mcap/core from npm
// (tools/foxglove/check_mcap.js).
#pragma once

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace aerotrack::test {

struct McapReadMessage {
  std::uint16_t channel_id;
  std::uint32_t sequence;
  std::uint64_t log_time_ns;
  std::uint64_t publish_time_ns;
  std::vector<std::uint8_t> data;
};

struct McapReadResult {
  std::map<std::uint16_t, std::pair<std::string, std::string>> schemas;     ///< id -> (name, encoding)
  std::map<std::uint16_t, std::pair<std::string, std::uint16_t>> channels;  ///< id -> (topic, schema id)
  std::vector<McapReadMessage> messages;                                    ///< In file order.
  std::size_t chunks = 0;
  bool has_summary = false;  ///< A complete file: Data End, summary, footer, magic, all checked.
  std::uint64_t statistics_messages = 0;
  std::map<std::uint16_t, std::uint64_t> statistics_channel_counts;
};

/// Reads path; throws std::runtime_error naming what is wrong. A file cut after a whole record
/// (no Data End) is accepted with has_summary = false; a file cut inside a record is an error.
inline McapReadResult readMcapReference(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<std::uint8_t> f((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto fail = [&](const std::string& what) { throw std::runtime_error(path + ": " + what); };
  struct Cursor {
    const std::vector<std::uint8_t>& b;
    std::size_t at;
    std::size_t end;
    std::function<void(const std::string&)> fail;
    std::uint64_t u(int bytes) {
      if (at + static_cast<std::size_t>(bytes) > end) fail("read past the end of a record");
      std::uint64_t v = 0;
      for (int i = 0; i < bytes; ++i) v |= static_cast<std::uint64_t>(b[at + static_cast<std::size_t>(i)]) << (8 * i);
      at += static_cast<std::size_t>(bytes);
      return v;
    }
    std::string str() {
      const std::size_t n = u(4);
      if (at + n > end) fail("string past the end of a record");
      std::string s(b.begin() + static_cast<std::ptrdiff_t>(at), b.begin() + static_cast<std::ptrdiff_t>(at + n));
      at += n;
      return s;
    }
  };
  static const std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
  if (f.size() < 8 || std::memcmp(f.data(), kMagic, 8) != 0) fail("no MCAP magic");
  McapReadResult result;
  std::map<std::uint16_t, std::uint64_t> counts;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> chunk_spans;  // offset, length
  std::size_t at = 8;
  bool header = false;
  while (at < f.size()) {
    if (at + 9 > f.size()) fail("a record cut inside its opcode and length");
    const std::uint8_t op = f[at];
    Cursor c{f, at + 1, at + 9, fail};
    const std::uint64_t length = c.u(8);
    const std::size_t begin = at + 9;
    if (begin + length > f.size()) fail("a record cut short at offset " + std::to_string(at));
    Cursor r{f, begin, static_cast<std::size_t>(begin + length), fail};
    if (!header && op != 0x01) fail("first record is not a Header");
    if (op == 0x01) {
      header = true;
    } else if (op == 0x03) {
      const auto id = static_cast<std::uint16_t>(r.u(2));
      const std::string name = r.str();
      result.schemas[id] = {name, r.str()};
    } else if (op == 0x04) {
      const auto id = static_cast<std::uint16_t>(r.u(2));
      const auto schema = static_cast<std::uint16_t>(r.u(2));
      if (schema != 0 && result.schemas.count(schema) == 0) fail("channel before its schema");
      result.channels[id] = {r.str(), schema};
    } else if (op == 0x06) {
      chunk_spans.emplace_back(at, 9 + length);
      r.u(8);
      r.u(8);
      const std::uint64_t size = r.u(8);
      const auto crc = static_cast<std::uint32_t>(r.u(4));
      const std::string compression = r.str();
      const std::uint64_t packed = r.u(8);
      if (r.at + packed != r.end) fail("chunk records length disagrees with the record");
      std::vector<std::uint8_t> records(size);
      if (compression == "zstd") {
        if (ZSTD_decompress(records.data(), size, f.data() + r.at, packed) != size) fail("zstd chunk");
      } else if (compression == "lz4") {
        LZ4F_dctx* d = nullptr;
        LZ4F_createDecompressionContext(&d, LZ4F_VERSION);
        std::size_t out = size;
        std::size_t src = packed;
        const std::size_t rc = LZ4F_decompress(d, records.data(), &out, f.data() + r.at, &src, nullptr);
        LZ4F_freeDecompressionContext(d);
        if (LZ4F_isError(rc) != 0U || out != size) fail("lz4 chunk");
      } else if (compression.empty()) {
        if (packed != size) fail("uncompressed chunk of the wrong size");
        std::memcpy(records.data(), f.data() + r.at, size);
      } else {
        fail("unknown compression " + compression);
      }
      if (crc32(0, records.data(), static_cast<uInt>(records.size())) != crc) fail("chunk CRC");
      // The chunk's messages, then the Message Index records that follow it.
      std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> offsets;
      std::size_t in_at = 0;
      while (in_at < records.size()) {
        Cursor h{records, in_at + 1, in_at + 9, fail};
        const std::uint64_t n = h.u(8);
        Cursor m{records, in_at + 9, static_cast<std::size_t>(in_at + 9 + n), fail};
        if (m.end > records.size()) fail("a record inside a chunk cut short");
        if (records[in_at] == 0x05) {
          McapReadMessage msg;
          msg.channel_id = static_cast<std::uint16_t>(m.u(2));
          msg.sequence = static_cast<std::uint32_t>(m.u(4));
          msg.log_time_ns = m.u(8);
          msg.publish_time_ns = m.u(8);
          msg.data.assign(records.begin() + static_cast<std::ptrdiff_t>(m.at),
                          records.begin() + static_cast<std::ptrdiff_t>(m.end));
          if (result.channels.count(msg.channel_id) == 0) fail("message before its channel");
          offsets[msg.channel_id].emplace_back(msg.log_time_ns, in_at);
          ++counts[msg.channel_id];
          result.messages.push_back(std::move(msg));
        }
        in_at = m.end;
      }
      ++result.chunks;
      std::size_t next = static_cast<std::size_t>(begin + length);
      std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> indexed;
      while (next + 9 <= f.size() && f[next] == 0x07) {
        Cursor h{f, next + 1, next + 9, fail};
        const std::uint64_t n = h.u(8);
        Cursor m{f, next + 9, static_cast<std::size_t>(next + 9 + n), fail};
        if (m.end > f.size()) fail("message index cut short");
        const auto id = static_cast<std::uint16_t>(m.u(2));
        const std::uint64_t bytes = m.u(4);
        for (std::uint64_t k = 0; k < bytes / 16; ++k) {
          const std::uint64_t t = m.u(8);
          indexed[id].emplace_back(t, m.u(8));
        }
        next = m.end;
      }
      if (indexed != offsets) fail("message indexes disagree with the chunk at offset " + std::to_string(at));
      at = next;
      continue;
    } else if (op == 0x0F) {
      const auto crc = static_cast<std::uint32_t>(r.u(4));
      if (crc != 0 && crc32(0, f.data(), static_cast<uInt>(at)) != crc) fail("data section CRC");
      // The summary: checked against the footer and what the data section held.
      if (f.size() < 8 + 29 || std::memcmp(f.data() + f.size() - 8, kMagic, 8) != 0) fail("no closing magic");
      const std::size_t footer = f.size() - 8 - 29;
      if (f[footer] != 0x02) fail("no footer");
      Cursor ft{f, footer + 9, footer + 29, fail};
      const std::uint64_t summary_start = ft.u(8);
      const std::uint64_t offsets_start = ft.u(8);
      const auto summary_crc = static_cast<std::uint32_t>(ft.u(4));
      if (summary_start != begin + length) fail("summary does not start after Data End");
      if (crc32(0, f.data() + summary_start, static_cast<uInt>(footer + 9 + 16 - summary_start)) != summary_crc) {
        fail("summary CRC");
      }
      std::size_t s = static_cast<std::size_t>(summary_start);
      std::vector<std::pair<std::uint64_t, std::uint64_t>> indexed_chunks;
      std::map<std::uint8_t, std::pair<std::uint64_t, std::uint64_t>> groups;
      while (s < footer) {
        Cursor h{f, s + 1, s + 9, fail};
        const std::uint64_t n = h.u(8);
        Cursor m{f, s + 9, static_cast<std::size_t>(s + 9 + n), fail};
        const std::uint8_t sop = f[s];
        if (sop == 0x0B) {
          result.statistics_messages = m.u(8);
          m.u(2);
          m.u(4);
          m.u(4);
          m.u(4);
          if (m.u(4) != result.chunks) fail("statistics chunk count");
          m.u(8);
          m.u(8);
          const std::uint64_t bytes = m.u(4);
          for (std::uint64_t k = 0; k < bytes / 10; ++k) {
            const auto id = static_cast<std::uint16_t>(m.u(2));
            result.statistics_channel_counts[id] = m.u(8);
          }
        } else if (sop == 0x08) {
          m.u(8);
          m.u(8);
          const std::uint64_t offset = m.u(8);
          indexed_chunks.emplace_back(offset, m.u(8));
        } else if (sop == 0x0E) {
          const auto g = static_cast<std::uint8_t>(m.u(1));
          const std::uint64_t start = m.u(8);
          groups[g] = {start, m.u(8)};
          if (s < offsets_start) fail("summary offset before the summary offset section");
        }
        s = m.end;
      }
      if (indexed_chunks != chunk_spans) fail("chunk indexes disagree with the chunks");
      if (result.statistics_messages != result.messages.size()) fail("statistics message count");
      for (const auto& [id, n] : counts) {
        if (result.statistics_channel_counts[id] != n) fail("statistics count of channel " + std::to_string(id));
      }
      for (const auto& [g, span] : groups) {
        if (f[span.first] != g) fail("summary offset of group " + std::to_string(g) + " points elsewhere");
      }
      result.has_summary = true;
      return result;
    }
    at = static_cast<std::size_t>(begin + length);
  }
  return result;
}

}  // namespace aerotrack::test
