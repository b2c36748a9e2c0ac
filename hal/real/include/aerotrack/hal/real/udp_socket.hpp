// A non-blocking UDP endpoint for MAVLink (issue 11 item 4), named by a URL as MAVSDK and
// mavlink-router name theirs:
//   udp://[bind_host]:port   listen on port (bind_host empty: every interface); the remote is learned
//                            from the first datagram. The peer must speak first: PX4 SITL's offboard
//                            link (it sends to 14540), a mavlink-router endpoint in Mode=Normal.
//   udpout://host:port       send to a fixed remote from an ephemeral local port; we speak first: a
//                            mavlink-router endpoint in Mode=Server, a flight controller's Ethernet
//                            MAVLink port.
// IPv4 only; host names are resolved once, at open. One owner at a time (the MAVLink connection
// serialises its two devices' calls with a mutex).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <netinet/in.h>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::real {

class UdpSocket {
 public:
  /// Opens the endpoint a URL names. Errors are one line starting with the URL: a malformed URL, an
  /// unknown host, a port in use, no permission.
  static rt::Expected<UdpSocket> open(const std::string& url);
  UdpSocket(UdpSocket&& other) noexcept;
  UdpSocket& operator=(UdpSocket&& other) noexcept;
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;
  ~UdpSocket();

  /// Sends one datagram to the remote. Error if there is no remote yet (a listening endpoint that has
  /// heard nothing) or the kernel refuses it. Does not allocate.
  rt::Status send(const std::uint8_t* data, std::size_t size);
  /// The next datagram waiting, copied into data (at most capacity bytes; a longer one is cut, as the
  /// kernel does): its size, nothing if none is waiting, or an error. Does not allocate on success.
  rt::Expected<std::optional<std::size_t>> receive(std::uint8_t* data, std::size_t capacity);
  /// Waits up to timeout_ms for a datagram (for tests and for callers that may block).
  bool waitReadable(int timeout_ms) const;

  bool hasRemote() const { return has_remote_; }
  /// The local port (the kernel's choice when the URL said port 0).
  std::uint16_t localPort() const;
  const std::string& url() const { return url_; }

 private:
  UdpSocket(int fd, std::string url) : fd_(fd), url_(std::move(url)) {}
  int fd_ = -1;
  std::string url_;
  bool listening_ = false;
  bool has_remote_ = false;
  sockaddr_in remote_{};
};

}  // namespace aerotrack::hal::real
