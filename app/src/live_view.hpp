// The live view (issue 24 item 2): `aerotrack run --live ADDRESS:PORT` and `sim --realtime --live ...`
// serve the flight log's topics over the Foxglove WebSocket protocol, so Foxglove or Lichtblick can
// watch a flight as it happens ("Open connection", ws://ADDRESS:PORT). Off by default: no listening
// socket without --live; `--live PORT` listens on the loopback only, an address must be given to listen
// beyond it.
//
// It never blocks a flight task: the flight log task (an observer, priority 0) offers each message
// it writes; a message is copied into a bounded single-producer queue only if a client subscribes to
// its topic and the topic's rate bound (live_rate_hz) lets it through, and is dropped, counted, when
// the queue is full. The WebSocket server (live_transport.hpp) empties the queue on its own thread
// and skips, counted, a client whose send buffer is full.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/spsc_queue.hpp"
#include "aerotrack/rt/time.hpp"
#include "live_transport.hpp"

namespace aerotrack::app {

struct LiveViewOptions {
  std::string address;        ///< "PORT" (loopback) or "HOST:PORT".
  double max_rate_hz = 30.0;  ///< Per topic: messages offered at most this often (by their stamps).
  std::size_t queue_capacity = 512;
};

class LiveView {
 public:
  /// Parses the address and starts listening. Error (one line): a bad address, a port in use.
  static rt::Expected<std::unique_ptr<LiveView>> start(const LiveViewOptions& options,
                                                       std::vector<live::Channel> channels);
  ~LiveView();
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  /// Producer (one thread): hands a copy of the message to the server, if a client subscribes to the
  /// channel and its rate bound allows.
  void offer(std::uint32_t channel, rt::TimeNs stamp_ns, std::span<const std::uint8_t> data);
  /// One line: where it listened, clients, messages sent and dropped.
  std::string summary() const;
  std::uint16_t port() const { return transport_->port(); }
  std::uint64_t droppedQueueFull() const { return queue_.dropped(); }
  void stop();

 private:
  LiveView(const LiveViewOptions& options, std::string where, std::size_t channels);
  LiveViewOptions options_;
  std::string where_;
  rt::SpscQueue<live::Outgoing> queue_;
  std::vector<rt::TimeNs> last_offered_ns_;  ///< Per channel id.
  std::unique_ptr<live::Transport> transport_;
};

/// "PORT" -> ("127.0.0.1", PORT); "HOST:PORT" -> (HOST, PORT); "[v6]:PORT" -> (v6, PORT). Error for
/// anything else, or a port outside 1..65535.
rt::Expected<std::pair<std::string, std::uint16_t>> parseLiveAddress(const std::string& address);

}  // namespace aerotrack::app
