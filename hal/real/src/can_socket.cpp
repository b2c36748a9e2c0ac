// CAN socket: see can_socket.hpp.
#include "aerotrack/hal/real/can_socket.hpp"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace aerotrack::hal::real {

rt::Expected<CanSocket> CanSocket::open(const std::string& interface) {
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0)
    return rt::Error{interface + ": cannot open a CAN socket (no SocketCAN in this kernel?): " + std::strerror(errno)};
  CanSocket socket(fd, interface);
  const can_err_mask_t errors = CAN_ERR_MASK;  // every error class: bus-off, controller, no ack ...
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof(errors)) != 0)
    return rt::Error{interface + ": cannot enable CAN error frames: " + std::strerror(errno)};
  const unsigned index = ::if_nametoindex(interface.c_str());
  if (index == 0) return rt::Error{interface + ": no such CAN interface"};
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = static_cast<int>(index);
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0)
    return rt::Error{interface + ": cannot bind the CAN socket: " + std::strerror(errno)};
  return socket;
}

CanSocket CanSocket::adopt(int fd, std::string name) {
  const int flags = ::fcntl(fd, F_GETFL, 0);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags | O_NONBLOCK);
  return CanSocket(fd, std::move(name));
}

CanSocket::CanSocket(CanSocket&& other) noexcept : fd_(std::exchange(other.fd_, -1)), name_(std::move(other.name_)) {}

CanSocket& CanSocket::operator=(CanSocket&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    name_ = std::move(other.name_);
  }
  return *this;
}

CanSocket::~CanSocket() {
  if (fd_ >= 0) ::close(fd_);
}

rt::Status CanSocket::send(const protocol::rmd::CanFrame& frame) {
  can_frame raw{};
  raw.can_id = frame.id & CAN_SFF_MASK;
  raw.can_dlc = frame.length;
  std::memcpy(raw.data, frame.data.data(), sizeof(raw.data));
  const ssize_t n = ::write(fd_, &raw, sizeof(raw));
  if (n == static_cast<ssize_t>(sizeof(raw))) return rt::ok();
  if (n < 0) return rt::Error{name_ + ": CAN send failed: " + std::strerror(errno)};
  return rt::Error{name_ + ": CAN send wrote a partial frame"};
}

rt::Expected<std::optional<CanReceived>> CanSocket::receive() {
  can_frame raw{};
  const ssize_t n = ::read(fd_, &raw, sizeof(raw));
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return std::optional<CanReceived>{};
    return rt::Error{name_ + ": CAN receive failed: " + std::strerror(errno)};
  }
  if (n == 0) return rt::Error{name_ + ": the CAN endpoint closed"};
  if (n != static_cast<ssize_t>(sizeof(raw))) return rt::Error{name_ + ": a truncated CAN frame arrived"};
  CanReceived r;
  r.error = (raw.can_id & CAN_ERR_FLAG) != 0;
  r.remote = (raw.can_id & CAN_RTR_FLAG) != 0;
  // An extended identifier keeps its flag: 0x241 in 29 bits is another node's frame, not the standard
  // 0x241, and a decoder of standard identifiers must not take one for the other.
  const canid_t id_mask =
      r.error ? CAN_ERR_MASK : ((raw.can_id & CAN_EFF_FLAG) != 0 ? (CAN_EFF_FLAG | CAN_EFF_MASK) : CAN_SFF_MASK);
  r.frame.id = raw.can_id & id_mask;
  r.frame.length = raw.can_dlc > 8 ? 8 : raw.can_dlc;
  std::memcpy(r.frame.data.data(), raw.data, sizeof(raw.data));
  return std::optional<CanReceived>{r};
}

}  // namespace aerotrack::hal::real
