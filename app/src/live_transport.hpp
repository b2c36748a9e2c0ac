// The live view's WebSocket side (issue 24 item 2): a server of the Foxglove WebSocket protocol
// (subprotocol foxglove.websocket.v1: https://github.com/foxglove/ws-protocol) on Debian's websocketpp,
// in a thread of its own. It tells each client the channels (serverInfo, advertise), keeps track of
// their subscriptions, and sends each message handed to it to the clients subscribed to its channel
// (binary "message data": opcode 1, subscription id, timestamp, payload).
//
// This header is plain C++17 and includes nothing of the project: websocketpp 0.8.2 does not compile
// as C++20 (template-ids as constructor names), so live_transport.cpp is built as C++17 on its own,
// behind this interface (app/CMakeLists.txt). live_view.hpp is the C++20 side that feeds it.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace aerotrack::app::live {

struct Channel {
  std::uint32_t id = 0;
  std::string topic;
  std::string encoding;         ///< "protobuf" or "json"
  std::string schema_name;      ///< e.g. "foxglove.SceneUpdate"
  std::string schema;           ///< protobuf: the base64 of its FileDescriptorSet; json: the JSON schema
  std::string schema_encoding;  ///< "protobuf" or "jsonschema"
};

struct Outgoing {
  std::uint32_t channel = 0;
  std::uint64_t stamp_ns = 0;
  std::string data;
};

struct TransportCounters {
  std::uint64_t clients = 0;              ///< Connections accepted so far.
  std::uint64_t sent = 0;                 ///< Messages sent (one per subscribed client).
  std::uint64_t dropped_slow_client = 0;  ///< Not sent: the client's send buffer was full (a slow link).
};

class Transport {
 public:
  /// Binds host:port (numeric or a name) and starts serving. `next` is called on the server's thread to
  /// take the next message to send (false: none now; polled every poll_ms). On failure returns null and
  /// sets `error` to one line ("address already in use", ...).
  static std::unique_ptr<Transport> start(const std::string& host, std::uint16_t port, std::vector<Channel> channels,
                                          std::function<bool(Outgoing&)> next, std::string& error, int poll_ms = 5,
                                          std::size_t max_buffered_bytes = 8U << 20);
  ~Transport();
  Transport(const Transport&) = delete;
  Transport& operator=(const Transport&) = delete;

  /// Whether any client subscribes to `channel` now (any thread).
  bool subscribed(std::uint32_t channel) const;
  /// The port it listens on (the one bound when 0 was asked).
  std::uint16_t port() const;
  TransportCounters counters() const;
  /// Closes every connection and joins the thread. Idempotent.
  void stop();

 private:
  struct Impl;
  explicit Transport(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace aerotrack::app::live
