// A CAN endpoint carrying Linux's `struct can_frame` (issue 11 item 3): a SocketCAN raw socket bound to
// an interface (can0, vcan0) with error frames enabled, or -- for tests -- any file descriptor that
// carries the same structs, such as one end of a socketpair. Non-blocking; one owner thread.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "aerotrack/hal/protocol/rmd.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::real {

/// What arrived: a data frame, or an error frame (the controller's report: bus-off, error passive ...).
struct CanReceived {
  /// A data frame's id; an extended frame's keeps CAN_EFF_FLAG (0x80000000), so it never equals a standard id.
  protocol::rmd::CanFrame frame;
  bool error = false;   ///< An error frame: frame.id holds the error class bits (linux/can/error.h).
  bool remote = false;  ///< A remote (request) frame: it carries no data.
};

class CanSocket {
 public:
  /// A SocketCAN raw socket on `interface`, receiving every frame and every error class. Error naming
  /// the interface: no such interface, no CAN support in the kernel, no permission.
  static rt::Expected<CanSocket> open(const std::string& interface);
  /// Takes ownership of fd (e.g. a socketpair end), made non-blocking.
  static CanSocket adopt(int fd, std::string name);
  CanSocket(CanSocket&& other) noexcept;
  CanSocket& operator=(CanSocket&& other) noexcept;
  CanSocket(const CanSocket&) = delete;
  CanSocket& operator=(const CanSocket&) = delete;
  ~CanSocket();

  /// Queues one frame; error if the socket refuses it (full transmit queue, bus-off, closed).
  rt::Status send(const protocol::rmd::CanFrame& frame);
  /// The next frame waiting, nothing if none; error if the socket failed (closed, unplugged).
  rt::Expected<std::optional<CanReceived>> receive();
  const std::string& name() const { return name_; }

 private:
  CanSocket(int fd, std::string name) : fd_(fd), name_(std::move(name)) {}
  int fd_ = -1;
  std::string name_;
};

}  // namespace aerotrack::hal::real
