// Bounded whole-file reads: see input_file.hpp. POSIX calls rather than iostreams so that the size
// and the kind of file are known before the first byte is read.
#include "aerotrack/rt/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cctype>
#include <cerrno>
#include <cstring>

namespace aerotrack::rt {
namespace {

class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const { return fd_; }

 private:
  int fd_;
};

/// "cannot open file: no such file or directory" (strerror's words, as a clause).
Error openError(const std::string& path, int error_number) {
  if (error_number == EISDIR) return Error{path + ": is a directory, expected a file"};
  std::string reason = std::strerror(error_number);
  if (!reason.empty()) reason[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(reason[0])));
  return Error{path + ": cannot open file: " + reason};
}

Error tooLarge(const std::string& path, std::uint64_t max_bytes) {
  return Error{path + ": larger than the limit of " + formatBytes(max_bytes) + " for this kind of file"};
}

/// The error for a path that stat() refused or that is not a file.
Status checkStat(const std::string& path, const struct stat& st, std::uint64_t max_bytes) {
  if (S_ISDIR(st.st_mode)) return Error{path + ": is a directory, expected a file"};
  if (S_ISREG(st.st_mode) && max_bytes > 0 && static_cast<std::uint64_t>(st.st_size) > max_bytes)
    return tooLarge(path, max_bytes);
  return ok();
}

}  // namespace

std::string quoteForMessage(std::string_view text, std::size_t max_chars) {
  std::string out = "'";
  for (std::size_t i = 0; i < text.size() && i < max_chars; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7F && c != '\\') {
      out.push_back(static_cast<char>(c));
    } else {
      constexpr std::array<char, 16> kHex = {'0', '1', '2', '3', '4', '5', '6', '7',
                                             '8', '9', 'a', 'b', 'c', 'd', 'e', 'f'};
      out += "\\x";
      out.push_back(kHex[c >> 4U]);
      out.push_back(kHex[c & 0xFU]);
    }
  }
  out += text.size() > max_chars ? "'..." : "'";
  return out;
}

std::string formatBytes(std::uint64_t bytes) {
  constexpr std::uint64_t kKiB = 1024;
  if (bytes >= kKiB * kKiB && bytes % (kKiB * kKiB) == 0) return std::to_string(bytes / (kKiB * kKiB)) + " MiB";
  if (bytes >= kKiB && bytes % kKiB == 0) return std::to_string(bytes / kKiB) + " KiB";
  return std::to_string(bytes) + " bytes";
}

Status checkInputFile(const std::string& path, std::uint64_t max_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return openError(path, errno);
  return checkStat(path, st, max_bytes);
}

Expected<std::string> readBoundedFile(const std::string& path, std::uint64_t max_bytes) {
  const Fd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK));
  if (fd.get() < 0) return openError(path, errno);
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) return Error{path + ": cannot read: " + std::strerror(errno)};
  if (auto status = checkStat(path, st, max_bytes); !status) return status.error();
  // O_NONBLOCK only keeps open() from waiting on a FIFO with no writer; reads block again.
  ::fcntl(fd.get(), F_SETFL, ::fcntl(fd.get(), F_GETFL) & ~O_NONBLOCK);
  std::string bytes;
  if (S_ISREG(st.st_mode)) bytes.reserve(static_cast<std::size_t>(st.st_size));
  std::array<char, 65536> chunk{};
  for (;;) {
    const ssize_t n = ::read(fd.get(), chunk.data(), chunk.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      return Error{path + ": cannot read: " + std::strerror(errno)};
    }
    if (n == 0) break;
    if (bytes.size() + static_cast<std::size_t>(n) > max_bytes) return tooLarge(path, max_bytes);
    bytes.append(chunk.data(), static_cast<std::size_t>(n));
  }
  return bytes;
}

}  // namespace aerotrack::rt
