// Raw CAN traffic in a recorded dataset (issue 10; hal/replay/README.md): `can.log` in the format
// of can-utils' `candump -l`, so that candump, canplayer and log2asc read it unchanged:
//
//   (1700000000.123456) can0 141#A200000010270000
//
// one frame per line: the time in seconds with six decimals (the format's microseconds; on the
// dataset's one clock, rounded down from its nanoseconds), the interface, and the frame: a standard
// identifier as 3 hex digits or an extended one as 8, '#', then the data bytes in hex (none to eight;
// classic CAN), or 'R' and an optional length digit for a remote frame. Error frames carry
// CAN_ERR_FLAG in an 8-digit identifier (linux/can.h). Pure code and files; no sockets.
//
// Like the CSV streams, the writer hands each line to the kernel in one write(2) and the reader
// treats a last line without its newline as the end (a recorder killed mid-write); a malformed line is
// an error naming the file and line (strict) or skipped and counted (skip); so is a time going back.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "aerotrack/hal/replay/csv_stream.hpp"
#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::hal::replay {

/// linux/can.h's identifier flags, as candump writes them into an 8-digit identifier.
inline constexpr std::uint32_t kCanEffFlag = 0x80000000U;  ///< extended frame format
inline constexpr std::uint32_t kCanRtrFlag = 0x40000000U;  ///< remote transmission request
inline constexpr std::uint32_t kCanErrFlag = 0x20000000U;  ///< error frame
inline constexpr std::uint32_t kCanSffMask = 0x000007FFU;
inline constexpr std::uint32_t kCanEffMask = 0x1FFFFFFFU;

/// One classic CAN frame as logged.
struct CanLogRecord {
  rt::TimeNs stamp_ns = 0;  ///< Microsecond resolution once written (the format's).
  std::string interface;    ///< e.g. "can0"
  std::uint32_t id = 0;     ///< Without flags: 11 bits (standard) or 29 bits (extended); error class bits.
  bool extended = false;
  bool remote = false;
  bool error = false;
  std::uint8_t length = 0;  ///< 0..8 data bytes (a remote frame: the requested length)
  std::array<std::uint8_t, 8> data{};

  bool operator==(const CanLogRecord&) const = default;
};

/// The candump -l line of a frame, without the newline.
std::string formatCandumpLine(const CanLogRecord& frame);

/// Parses one line (without its newline). Error: what is wrong with it (no file or line).
rt::Expected<CanLogRecord> parseCandumpLine(std::string_view line);

/// A can.log read whole.
struct LoadedCanLog {
  std::vector<CanLogRecord> frames;
  std::uint64_t skipped_lines = 0;
  std::string first_skip_message;
  bool truncated_tail = false;  ///< The last line had no newline (not read).
};

/// Reads path. Strict: the first bad line is an error "path:line: ..."; skip: bad lines are counted.
/// Error (both): the file cannot be opened.
rt::Expected<LoadedCanLog> loadCandump(const std::string& path, BadRowPolicy policy);

/// Appends frames to a can.log, each line in one write(2).
class CandumpWriter {
 public:
  /// Creates (truncates) path.
  static rt::Expected<CandumpWriter> create(const std::string& path);
  CandumpWriter(CandumpWriter&& other) noexcept;
  CandumpWriter& operator=(CandumpWriter&& other) noexcept;
  CandumpWriter(const CandumpWriter&) = delete;
  CandumpWriter& operator=(const CandumpWriter&) = delete;
  ~CandumpWriter();
  rt::Status write(const CanLogRecord& frame);
  rt::Status close();

 private:
  CandumpWriter() = default;
  int fd_ = -1;
  std::string path_;
};

}  // namespace aerotrack::hal::replay
