// A recorded dataset's timestamped CSV streams (issue 10; the format: hal/replay/README.md). A stream
// is one header line naming its columns, the first always `stamp_ns` (integer nanoseconds on the
// recording's one clock), then one record per line, in time order.
//
// Writing (the recorder): a record is formatted whole and handed to the file in one write(2), so a
// recording that ends abruptly (power cut, kill -9) holds complete lines and at most one partial last
// line. Numbers are written in their shortest round-trip form: reading them back gives the same doubles.
//
// Reading (the replay backend): record by record. A last line without its newline is what a killed
// recorder leaves: it is not a record, and truncatedTail() says so. Anything else wrong -- a missing
// or different header, a row with the wrong number of fields, a field that is not a number, a
// timestamp going backwards -- is an error naming the file and the line (strict), or (skip) the row
// is dropped, counted, and its message kept, so that a stream with a few bad rows can still be
// replayed.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::hal::replay {

/// Writes all of text to fd, retrying short writes and EINTR. The streams of a dataset append each
/// record with one call, so a record is whole in the file or (killed mid-call) a partial last line
/// the reader drops. Error naming path.
rt::Status writeAllFd(int fd, std::string_view text, const std::string& path);

struct CsvRecord {
  rt::TimeNs stamp_ns = 0;
  std::vector<double> values;  ///< The columns after stamp_ns, in header order.
  int line = 0;                ///< 1-based line in the file.
};

enum class BadRowPolicy : std::uint8_t { kStrict, kSkip };

class CsvStreamReader {
 public:
  /// Opens `path` and checks its header: exactly `stamp_ns` then `columns`, in that order.
  static rt::Expected<CsvStreamReader> open(const std::string& path, const std::vector<std::string>& columns,
                                            BadRowPolicy policy = BadRowPolicy::kStrict);

  /// The next record; nullopt at the end of the stream (after a truncated tail, too). Strict: a bad row
  /// is an Error "path:line: ..."; skip: it is counted and the next good row is returned.
  rt::Expected<std::optional<CsvRecord>> next();

  bool truncatedTail() const { return truncated_tail_; }
  std::uint64_t skippedRows() const { return skipped_rows_; }
  /// The first skipped row's message ("" if none).
  const std::string& firstSkipMessage() const { return first_skip_message_; }
  const std::string& path() const { return path_; }

 private:
  CsvStreamReader() = default;
  /// A parsed row, or the reason it is bad (without the "path:line: " prefix).
  rt::Expected<CsvRecord> parse(const std::string& text, int line) const;

  struct FileCloser {
    void operator()(std::FILE* f) const {
      if (f != nullptr) std::fclose(f);
    }
  };
  std::unique_ptr<std::FILE, FileCloser> file_;
  std::string path_;
  std::vector<std::string> columns_;
  BadRowPolicy policy_ = BadRowPolicy::kStrict;
  int line_ = 1;  // the header's
  rt::TimeNs last_stamp_ns_ = INT64_MIN;
  bool truncated_tail_ = false;
  std::uint64_t skipped_rows_ = 0;
  std::string first_skip_message_;
};

class CsvStreamWriter {
 public:
  /// Creates (truncates) `path` and writes the header `stamp_ns,columns...`.
  static rt::Expected<CsvStreamWriter> create(const std::string& path, const std::vector<std::string>& columns);
  CsvStreamWriter(CsvStreamWriter&& other) noexcept;
  CsvStreamWriter& operator=(CsvStreamWriter&& other) noexcept;
  CsvStreamWriter(const CsvStreamWriter&) = delete;
  CsvStreamWriter& operator=(const CsvStreamWriter&) = delete;
  ~CsvStreamWriter();

  /// Appends one record (values.size() must equal the number of columns) in one write(2).
  rt::Status write(rt::TimeNs stamp_ns, const std::vector<double>& values);
  /// Closes the file (also done by the destructor, without the error).
  rt::Status close();
  const std::string& path() const { return path_; }

 private:
  CsvStreamWriter() = default;

  int fd_ = -1;
  std::string path_;
  std::size_t columns_ = 0;
  std::string line_;  // reused formatting buffer
};

}  // namespace aerotrack::hal::replay
