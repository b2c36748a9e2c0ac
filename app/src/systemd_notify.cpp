// systemd notification: see systemd_notify.hpp (protocol: sd_notify(3), "Notes").
#include "systemd_notify.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstddef>
#include <cstring>

namespace aerotrack::app {

SystemdNotifier SystemdNotifier::fromEnvironment(const char* notify_socket, const char* watchdog_usec,
                                                 const char* watchdog_pid, long own_pid) {
  if (notify_socket == nullptr || *notify_socket == '\0') return {};
  rt::DurationNs timeout_ns = 0;
  bool ours = true;
  if (watchdog_pid != nullptr && *watchdog_pid != '\0') {
    long pid = 0;
    const char* end = watchdog_pid + std::strlen(watchdog_pid);
    ours = std::from_chars(watchdog_pid, end, pid).ptr == end && pid == own_pid;
  }
  if (ours && watchdog_usec != nullptr && *watchdog_usec != '\0') {
    std::uint64_t usec = 0;
    const char* end = watchdog_usec + std::strlen(watchdog_usec);
    if (std::from_chars(watchdog_usec, end, usec).ptr == end && usec > 0 && usec < 3'600'000'000'000ULL)
      timeout_ns = static_cast<rt::DurationNs>(usec) * 1000;
  }
  return {notify_socket, timeout_ns};
}

rt::Status SystemdNotifier::notify(const std::string& state) const {
  if (!enabled()) return rt::ok();
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (address_.size() >= sizeof(address.sun_path)) return rt::Error{"NOTIFY_SOCKET " + address_ + ": path too long"};
  std::memcpy(address.sun_path, address_.data(), address_.size());
  if (address_[0] == '@') address.sun_path[0] = '\0';  // abstract namespace
  const auto length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + address_.size());
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return rt::Error{"NOTIFY_SOCKET " + address_ + ": socket: " + std::strerror(errno)};
  const ssize_t sent =
      ::sendto(fd, state.data(), state.size(), MSG_NOSIGNAL, reinterpret_cast<const sockaddr*>(&address), length);
  const int error = errno;
  ::close(fd);
  if (sent != static_cast<ssize_t>(state.size()))
    return rt::Error{"NOTIFY_SOCKET " + address_ + ": " + std::strerror(sent < 0 ? error : EMSGSIZE)};
  return rt::ok();
}

bool TaskLiveness::allAdvanced(const std::vector<std::uint64_t>& counts) {
  bool advanced = last_.size() == counts.size();
  for (std::size_t i = 0; advanced && i < counts.size(); ++i) advanced = counts[i] > last_[i];
  last_ = counts;
  return advanced;
}

}  // namespace aerotrack::app
