// Timestamped CSV streams: see csv_stream.hpp.
#include "aerotrack/hal/replay/csv_stream.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <utility>

#include "aerotrack/rt/input_file.hpp"
#include "aerotrack/rt/input_limits.hpp"

namespace aerotrack::hal::replay {
namespace {

std::vector<std::string> splitFields(const std::string& text) {
  std::vector<std::string> fields;
  std::size_t begin = 0;
  for (;;) {
    const std::size_t comma = text.find(',', begin);
    fields.push_back(text.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin));
    if (comma == std::string::npos) return fields;
    begin = comma + 1;
  }
}

std::string joinHeader(const std::vector<std::string>& columns) {
  std::string header = "stamp_ns";
  for (const std::string& c : columns) header += "," + c;
  return header;
}

/// Reads one line without its newline; false at the end of the file. `complete`: it ended in '\n'.
/// `too_long`: it passed the limit on a line (input_limits.hpp) and was not read further -- a file
/// with no newline, such as /dev/zero, would otherwise be read into memory whole.
bool readLine(std::FILE* file, std::string& line, bool& complete, bool& too_long) {
  line.clear();
  complete = false;
  too_long = false;
  int c = 0;
  while ((c = std::fgetc(file)) != EOF) {
    if (c == '\n') {
      complete = true;
      return true;
    }
    if (line.size() >= rt::limits::kMaxCsvLineBytes) {
      too_long = true;
      return true;
    }
    line.push_back(static_cast<char>(c));
  }
  return !line.empty();
}

std::string lineTooLong(const std::string& path, int line) {
  return path + ":" + std::to_string(line) + ": line longer than the limit of " +
         rt::formatBytes(rt::limits::kMaxCsvLineBytes);
}

}  // namespace

rt::Expected<CsvStreamReader> CsvStreamReader::open(const std::string& path, const std::vector<std::string>& columns,
                                                    BadRowPolicy policy) {
  if (auto status = rt::checkInputFile(path); !status) return status.error();  // fopen opens a directory
  CsvStreamReader reader;
  reader.file_.reset(std::fopen(path.c_str(), "rb"));
  if (!reader.file_) return rt::Error{path + ": cannot open: " + std::strerror(errno)};
  reader.path_ = path;
  reader.columns_ = columns;
  reader.policy_ = policy;
  std::string header;
  bool complete = false;
  bool too_long = false;
  const bool read = readLine(reader.file_.get(), header, complete, too_long);
  if (too_long) return rt::Error{lineTooLong(path, 1)};
  if (!read || !complete) return rt::Error{path + ":1: missing header (expected '" + joinHeader(columns) + "')"};
  if (!header.empty() && header.back() == '\r') header.pop_back();
  if (header != joinHeader(columns)) {
    return rt::Error{path + ":1: header " + rt::quoteForMessage(header) + " is not '" + joinHeader(columns) + "'"};
  }
  return reader;
}

rt::Expected<CsvRecord> CsvStreamReader::parse(const std::string& text, int line) const {
  const std::vector<std::string> fields = splitFields(text);
  if (fields.size() != columns_.size() + 1) {
    return rt::Error{std::to_string(fields.size()) + " fields, expected " + std::to_string(columns_.size() + 1)};
  }
  CsvRecord record;
  record.line = line;
  const std::string& stamp = fields[0];
  const auto [end, ec] = std::from_chars(stamp.data(), stamp.data() + stamp.size(), record.stamp_ns);
  if (ec != std::errc() || end != stamp.data() + stamp.size()) {
    return rt::Error{"stamp_ns: expected integer nanoseconds, got '" + stamp + "'"};
  }
  record.values.assign(columns_.size(), 0.0);
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    const std::string& field = fields[i + 1];
    const char* first = field.data();
    const char* last = field.data() + field.size();
    const auto [ptr, error] = std::from_chars(first, last, record.values[i]);
    if (error != std::errc() || ptr != last || field.empty()) {
      return rt::Error{columns_[i] + ": expected a number, got '" + field + "'"};
    }
  }
  return record;
}

rt::Expected<std::optional<CsvRecord>> CsvStreamReader::next() {
  std::string text;
  bool complete = false;
  bool too_long = false;
  while (readLine(file_.get(), text, complete, too_long)) {
    ++line_;
    if (too_long) return rt::Error{lineTooLong(path_, line_)};
    if (!complete) {  // what a killed recorder leaves: not a record
      truncated_tail_ = true;
      return std::optional<CsvRecord>{};
    }
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (text.empty()) continue;
    auto record = parse(text, line_);
    std::string problem;
    if (!record) {
      problem = record.error().message;
    } else if (record->stamp_ns < 0 || record->stamp_ns > rt::limits::kMaxStampNs) {
      problem = "stamp_ns " + std::to_string(record->stamp_ns) + " is outside [0, " +
                std::to_string(rt::limits::kMaxStampNs) + "]";
    } else if (record->stamp_ns < last_stamp_ns_) {
      problem = "stamp_ns " + std::to_string(record->stamp_ns) + " goes back from " + std::to_string(last_stamp_ns_);
    }
    if (problem.empty()) {
      last_stamp_ns_ = record->stamp_ns;
      return std::optional<CsvRecord>{std::move(record.value())};
    }
    const std::string message = path_ + ":" + std::to_string(line_) + ": " + problem;
    if (policy_ == BadRowPolicy::kStrict) return rt::Error{message};
    if (skipped_rows_++ == 0) first_skip_message_ = message;
  }
  if (std::ferror(file_.get()) != 0) return rt::Error{path_ + ":" + std::to_string(line_) + ": read error"};
  return std::optional<CsvRecord>{};
}

rt::Expected<CsvStreamWriter> CsvStreamWriter::create(const std::string& path,
                                                      const std::vector<std::string>& columns) {
  CsvStreamWriter writer;
  writer.fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (writer.fd_ < 0) return rt::Error{path + ": cannot create: " + std::strerror(errno)};
  writer.path_ = path;
  writer.columns_ = columns.size();
  if (rt::Status s = writeAllFd(writer.fd_, joinHeader(columns) + "\n", writer.path_); !s) return s.error();
  return writer;
}

CsvStreamWriter::CsvStreamWriter(CsvStreamWriter&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      path_(std::move(other.path_)),
      columns_(other.columns_),
      line_(std::move(other.line_)) {}

CsvStreamWriter& CsvStreamWriter::operator=(CsvStreamWriter&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
    columns_ = other.columns_;
    line_ = std::move(other.line_);
  }
  return *this;
}

CsvStreamWriter::~CsvStreamWriter() {
  if (fd_ >= 0) ::close(fd_);
}

rt::Status writeAllFd(int fd, std::string_view text, const std::string& path) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return rt::Error{path + ": write failed: " + std::strerror(errno)};
    done += static_cast<std::size_t>(n);
  }
  return rt::ok();
}

rt::Status CsvStreamWriter::write(rt::TimeNs stamp_ns, const std::vector<double>& values) {
  if (fd_ < 0) return rt::Error{path_ + ": write after close"};
  if (values.size() != columns_) {
    return rt::Error{path_ + ": a record of " + std::to_string(values.size()) + " values, expected " +
                     std::to_string(columns_)};
  }
  line_ = std::to_string(stamp_ns);
  char number[32];
  for (const double v : values) {
    // Shortest form that reads back to the same double (std::to_chars round-trips exactly).
    const auto [end, ec] = std::to_chars(number, number + sizeof(number), v);
    line_.push_back(',');
    line_.append(number, ec == std::errc() ? end : number);
  }
  line_.push_back('\n');
  return writeAllFd(fd_, line_, path_);
}

rt::Status CsvStreamWriter::close() {
  if (fd_ < 0) return rt::ok();
  const int fd = std::exchange(fd_, -1);
  if (::close(fd) != 0) return rt::Error{path_ + ": close failed: " + std::strerror(errno)};
  return rt::ok();
}

}  // namespace aerotrack::hal::replay
