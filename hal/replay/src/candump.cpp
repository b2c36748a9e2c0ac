// candump -l logs: see candump.hpp.
#include "aerotrack/hal/replay/candump.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <utility>

namespace aerotrack::hal::replay {
namespace {

int hexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool parseHex(std::string_view text, std::uint32_t& out) {
  if (text.empty() || text.size() > 8) return false;
  out = 0;
  for (const char c : text) {
    const int d = hexDigit(c);
    if (d < 0) return false;
    out = (out << 4) | static_cast<std::uint32_t>(d);
  }
  return true;
}

/// "(sec.usec)" to nanoseconds.
bool parseTime(std::string_view text, rt::TimeNs& out) {
  if (text.size() < 3 || text.front() != '(' || text.back() != ')') return false;
  text = text.substr(1, text.size() - 2);
  const auto dot = text.find('.');
  if (dot == std::string_view::npos || dot == 0 || text.size() - dot - 1 != 6 || dot > 12) return false;
  rt::TimeNs seconds = 0;
  rt::TimeNs micros = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (i == dot) continue;
    if (text[i] < '0' || text[i] > '9') return false;
    rt::TimeNs& into = i < dot ? seconds : micros;
    into = into * 10 + (text[i] - '0');
  }
  out = seconds * rt::kNsPerSecond + micros * 1000;
  return true;
}

}  // namespace

std::string formatCandumpLine(const CanLogRecord& f) {
  const rt::TimeNs stamp_ns = f.stamp_ns < 0 ? 0 : f.stamp_ns;
  char head[64];
  std::snprintf(head, sizeof(head), "(%lld.%06lld) ", static_cast<long long>(stamp_ns / rt::kNsPerSecond),
                static_cast<long long>((stamp_ns % rt::kNsPerSecond) / 1000));
  std::string line = head;
  line += f.interface;
  line += ' ';
  char id[16];
  if (f.extended || f.error) {
    const std::uint32_t flags = (f.extended ? kCanEffFlag : 0U) | (f.error ? kCanErrFlag : 0U);
    // candump writes the extended flag implicitly (8 digits); the error flag explicitly.
    std::snprintf(id, sizeof(id), "%08X", (f.id & kCanEffMask) | (flags & kCanErrFlag));
  } else {
    std::snprintf(id, sizeof(id), "%03X", f.id & kCanSffMask);
  }
  line += id;
  line += '#';
  if (f.remote) {
    line += 'R';
    if (f.length > 0) line += static_cast<char>('0' + f.length);
    return line;
  }
  static constexpr char kHex[] = "0123456789ABCDEF";
  for (std::size_t i = 0; i < f.length && i < f.data.size(); ++i) {
    line += kHex[f.data[i] >> 4];
    line += kHex[f.data[i] & 0xF];
  }
  return line;
}

rt::Expected<CanLogRecord> parseCandumpLine(std::string_view line) {
  CanLogRecord f;
  const auto space1 = line.find(' ');
  if (space1 == std::string_view::npos || !parseTime(line.substr(0, space1), f.stamp_ns))
    return rt::Error{"expected '(seconds.microseconds)' first"};
  const auto space2 = line.find(' ', space1 + 1);
  if (space2 == std::string_view::npos || space2 == space1 + 1) return rt::Error{"expected an interface name"};
  f.interface = std::string(line.substr(space1 + 1, space2 - space1 - 1));
  const std::string_view frame = line.substr(space2 + 1);
  const auto hash = frame.find('#');
  if (hash == std::string_view::npos) return rt::Error{"expected ID#DATA"};
  const std::string_view id_text = frame.substr(0, hash);
  std::uint32_t id = 0;
  if ((id_text.size() != 3 && id_text.size() != 8) || !parseHex(id_text, id))
    return rt::Error{"identifier '" + std::string(id_text) + "' is not 3 or 8 hex digits"};
  if (id_text.size() == 8) {
    f.error = (id & kCanErrFlag) != 0;
    f.extended = !f.error;
    f.id = id & kCanEffMask;
  } else {
    if (id > kCanSffMask) return rt::Error{"standard identifier " + std::string(id_text) + " exceeds 7FF"};
    f.id = id;
  }
  std::string_view data = frame.substr(hash + 1);
  if (!data.empty() && data.front() == '#') return rt::Error{"CAN FD frames (ID##...) are not supported"};
  if (!data.empty() && (data.front() == 'R' || data.front() == 'r')) {
    f.remote = true;
    if (data.size() == 2 && data[1] >= '0' && data[1] <= '8') {
      f.length = static_cast<std::uint8_t>(data[1] - '0');
    } else if (data.size() != 1) {
      return rt::Error{"a remote frame is R or R and a length digit 0-8"};
    }
    return f;
  }
  if (data.size() % 2 != 0 || data.size() > 16) return rt::Error{"data must be 0 to 8 bytes in hex pairs"};
  for (std::size_t i = 0; i < data.size(); i += 2) {
    const int hi = hexDigit(data[i]);
    const int lo = hexDigit(data[i + 1]);
    if (hi < 0 || lo < 0) return rt::Error{"data '" + std::string(data) + "' is not hex"};
    f.data[i / 2] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  f.length = static_cast<std::uint8_t>(data.size() / 2);
  return f;
}

rt::Expected<LoadedCanLog> loadCandump(const std::string& path, BadRowPolicy policy) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return rt::Error{path + ": cannot open: " + std::strerror(errno)};
  std::string text;
  char buffer[65536];
  for (std::size_t n = 0; (n = std::fread(buffer, 1, sizeof(buffer), file)) > 0;) text.append(buffer, n);
  const bool read_error = std::ferror(file) != 0;
  std::fclose(file);
  if (read_error) return rt::Error{path + ": read failed"};
  LoadedCanLog out;
  std::size_t begin = 0;
  int line_number = 0;
  rt::TimeNs last_ns = INT64_MIN;
  while (begin < text.size()) {
    const std::size_t end = text.find('\n', begin);
    ++line_number;
    if (end == std::string::npos) {  // a last line cut short by a kill: the end of the log
      out.truncated_tail = true;
      break;
    }
    const std::string_view line(text.data() + begin, end - begin);
    begin = end + 1;
    auto frame = parseCandumpLine(line);
    std::string problem;
    if (!frame) {
      problem = frame.error().message;
    } else if (frame->stamp_ns < last_ns) {
      problem = "time goes back";
    }
    if (!problem.empty()) {
      std::string message = path;
      message += ":" + std::to_string(line_number) + ": ";
      message += problem;
      if (policy == BadRowPolicy::kStrict) return rt::Error{message};
      if (out.skipped_lines++ == 0) out.first_skip_message = message;
      continue;
    }
    last_ns = frame->stamp_ns;
    out.frames.push_back(std::move(*frame));
  }
  return out;
}

rt::Expected<CandumpWriter> CandumpWriter::create(const std::string& path) {
  CandumpWriter writer;
  writer.fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (writer.fd_ < 0) return rt::Error{path + ": cannot create: " + std::strerror(errno)};
  writer.path_ = path;
  return writer;
}

CandumpWriter::CandumpWriter(CandumpWriter&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), path_(std::move(other.path_)) {}

CandumpWriter& CandumpWriter::operator=(CandumpWriter&& other) noexcept {
  if (this != &other) {
    (void)close();
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
  }
  return *this;
}

CandumpWriter::~CandumpWriter() {
  (void)close();
}

rt::Status CandumpWriter::write(const CanLogRecord& frame) {
  if (fd_ < 0) return rt::Error{path_ + ": closed"};
  return writeAllFd(fd_, formatCandumpLine(frame) + "\n", path_);
}

rt::Status CandumpWriter::close() {
  if (fd_ < 0) return rt::ok();
  const int fd = std::exchange(fd_, -1);
  if (::close(fd) != 0) return rt::Error{path_ + ": close failed: " + std::strerror(errno)};
  return rt::ok();
}

}  // namespace aerotrack::hal::replay
