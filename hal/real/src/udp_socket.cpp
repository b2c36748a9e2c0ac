// UDP endpoint: see udp_socket.hpp.
#include "aerotrack/hal/real/udp_socket.hpp"

#include <arpa/inet.h>
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <utility>

namespace aerotrack::hal::real {
namespace {

constexpr const char* kForms = " (expected udp://[bind_host]:port or udpout://host:port)";

struct ParsedUrl {
  bool listen = false;
  std::string host;
  std::uint16_t port = 0;
};

rt::Expected<ParsedUrl> parseUrl(const std::string& url) {
  ParsedUrl p;
  std::string rest;
  if (url.rfind("udp://", 0) == 0) {
    p.listen = true;
    rest = url.substr(6);
  } else if (url.rfind("udpout://", 0) == 0) {
    rest = url.substr(9);
  } else {
    return rt::Error{url + ": not a UDP URL" + kForms};
  }
  const std::size_t colon = rest.rfind(':');
  if (colon == std::string::npos) return rt::Error{url + ": no port" + kForms};
  p.host = rest.substr(0, colon);
  const std::string port = rest.substr(colon + 1);
  unsigned value = 0;
  const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (port.empty() || ec != std::errc() || end != port.data() + port.size() || value > 65535)
    return rt::Error{url + ": bad port '" + port + "'" + kForms};
  p.port = static_cast<std::uint16_t>(value);
  if (!p.listen && (p.host.empty() || p.port == 0)) return rt::Error{url + ": udpout needs a host and a port" + kForms};
  return p;
}

rt::Expected<in_addr> resolve(const std::string& url, const std::string& host) {
  in_addr address{};
  if (host.empty()) {
    address.s_addr = htonl(INADDR_ANY);
    return address;
  }
  if (::inet_pton(AF_INET, host.c_str(), &address) == 1) return address;
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* found = nullptr;
  const int rc = ::getaddrinfo(host.c_str(), nullptr, &hints, &found);
  if (rc != 0 || found == nullptr)
    return rt::Error{url + ": cannot resolve host '" + host + "': " + ::gai_strerror(rc)};
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API
  address = reinterpret_cast<const sockaddr_in*>(found->ai_addr)->sin_addr;
  ::freeaddrinfo(found);
  return address;
}

}  // namespace

rt::Expected<UdpSocket> UdpSocket::open(const std::string& url) {
  const auto parsed = parseUrl(url);
  if (!parsed) return parsed.error();
  const auto address = resolve(url, parsed->host);
  if (!address) return address.error();
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return rt::Error{url + ": cannot open a UDP socket: " + std::strerror(errno)};
  UdpSocket socket(fd, url);
  socket.listening_ = parsed->listen;
  sockaddr_in local{};
  local.sin_family = AF_INET;
  if (parsed->listen) {
    local.sin_addr = *address;
    local.sin_port = htons(parsed->port);
  } else {
    local.sin_addr.s_addr = htonl(INADDR_ANY);  // an ephemeral port
    socket.remote_.sin_family = AF_INET;
    socket.remote_.sin_addr = *address;
    socket.remote_.sin_port = htons(parsed->port);
    socket.has_remote_ = true;
  }
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&local), sizeof(local)) != 0)
    return rt::Error{url + ": cannot bind: " + std::strerror(errno)};
  return socket;
}

UdpSocket::UdpSocket(UdpSocket&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      url_(std::move(other.url_)),
      listening_(other.listening_),
      has_remote_(other.has_remote_),
      remote_(other.remote_) {}

UdpSocket& UdpSocket::operator=(UdpSocket&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    url_ = std::move(other.url_);
    listening_ = other.listening_;
    has_remote_ = other.has_remote_;
    remote_ = other.remote_;
  }
  return *this;
}

UdpSocket::~UdpSocket() {
  if (fd_ >= 0) ::close(fd_);
}

rt::Status UdpSocket::send(const std::uint8_t* data, std::size_t size) {
  if (!has_remote_) return rt::Error{url_ + ": no remote yet (nothing has been received)"};
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API
  const ssize_t n =
      ::sendto(fd_, data, size, MSG_NOSIGNAL, reinterpret_cast<const sockaddr*>(&remote_), sizeof(remote_));
  if (n == static_cast<ssize_t>(size)) return rt::ok();
  if (n < 0) return rt::Error{url_ + ": send failed: " + std::strerror(errno)};
  return rt::Error{url_ + ": send wrote a partial datagram"};
}

rt::Expected<std::optional<std::size_t>> UdpSocket::receive(std::uint8_t* data, std::size_t capacity) {
  sockaddr_in from{};
  socklen_t from_size = sizeof(from);
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API
  const ssize_t n = ::recvfrom(fd_, data, capacity, 0, reinterpret_cast<sockaddr*>(&from), &from_size);
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return std::optional<std::size_t>{};
    return rt::Error{url_ + ": receive failed: " + std::strerror(errno)};
  }
  if (listening_ && !has_remote_) {
    // The first peer heard is the one answered; later senders are still read (a router may relay
    // several) but replies keep going to the first.
    remote_ = from;
    has_remote_ = true;
  }
  return std::optional<std::size_t>{static_cast<std::size_t>(n)};
}

bool UdpSocket::waitReadable(int timeout_ms) const {
  pollfd p{fd_, POLLIN, 0};
  return ::poll(&p, 1, timeout_ms) > 0 && (p.revents & POLLIN) != 0;
}

std::uint16_t UdpSocket::localPort() const {
  sockaddr_in local{};
  socklen_t size = sizeof(local);
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&local), &size) != 0) return 0;
  return ntohs(local.sin_port);
}

}  // namespace aerotrack::hal::real
