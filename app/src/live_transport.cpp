// The live view's WebSocket side: see live_transport.hpp. Built as C++17 (websocketpp 0.8.2).
#include "live_transport.hpp"

#define ASIO_STANDALONE
#include <nlohmann/json.hpp>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include <atomic>
#include <map>
#include <mutex>
#include <thread>

namespace aerotrack::app::live {
namespace {

using Server = websocketpp::server<websocketpp::config::asio>;
using Handle = websocketpp::connection_hdl;

constexpr const char* kSubprotocol = "foxglove.websocket.v1";

std::string base64(const std::string& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16U) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8U) | static_cast<unsigned char>(bytes[i + 2]);
    for (int k = 3; k >= 0; --k) out.push_back(kAlphabet[(v >> (6U * static_cast<unsigned>(k))) & 63U]);
  }
  if (i < bytes.size()) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16U;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8U;
    out.push_back(kAlphabet[(v >> 18U) & 63U]);
    out.push_back(kAlphabet[(v >> 12U) & 63U]);
    out.push_back(i + 1 < bytes.size() ? kAlphabet[(v >> 6U) & 63U] : '=');
    out.push_back('=');
  }
  return out;
}

void putLe(std::string& s, std::size_t at, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) s[at + static_cast<std::size_t>(i)] = static_cast<char>((v >> (8 * i)) & 0xFFU);
}

}  // namespace

struct Transport::Impl {
  Server server;
  std::vector<Channel> channels;
  std::function<bool(Outgoing&)> next;
  int poll_ms = 5;
  std::size_t max_buffered_bytes = 0;
  std::thread thread;
  std::uint16_t port = 0;
  // Subscriptions: per connection, subscription id -> channel id (the server thread only), and per
  // channel how many there are (read by any thread).
  std::map<Handle, std::map<std::uint32_t, std::uint32_t>, std::owner_less<Handle>> subscriptions;
  std::vector<std::atomic<int>> subscribers;
  std::atomic<std::uint64_t> clients{0};
  std::atomic<std::uint64_t> sent{0};
  std::atomic<std::uint64_t> dropped_slow_client{0};
  std::atomic<bool> stopping{false};
  std::string hello;  ///< serverInfo and advertise, sent to each new client
  std::string advertise;

  void countSubscription(std::uint32_t channel, int delta) {
    if (channel < subscribers.size()) subscribers[channel].fetch_add(delta, std::memory_order_relaxed);
  }

  void onMessage(const Handle& hdl, const Server::message_ptr& msg) {
    if (msg->get_opcode() != websocketpp::frame::opcode::text) return;  // client publishing: not offered
    const nlohmann::json request = nlohmann::json::parse(msg->get_payload(), nullptr, /*allow_exceptions=*/false);
    if (!request.is_object() || !request.contains("op")) return;
    auto& mine = subscriptions[hdl];
    const std::string op = request.value("op", "");
    if (op == "subscribe" && request.contains("subscriptions") && request["subscriptions"].is_array()) {
      for (const auto& s : request["subscriptions"]) {
        if (!s.is_object() || !s.contains("id") || !s.contains("channelId")) continue;
        if (!s["id"].is_number_unsigned() || !s["channelId"].is_number_unsigned()) continue;
        const auto id = s["id"].get<std::uint32_t>();
        const auto channel = s["channelId"].get<std::uint32_t>();
        if (channel >= subscribers.size() || mine.count(id) != 0) continue;
        mine[id] = channel;
        countSubscription(channel, +1);
      }
    } else if (op == "unsubscribe" && request.contains("subscriptionIds") && request["subscriptionIds"].is_array()) {
      for (const auto& id : request["subscriptionIds"]) {
        if (!id.is_number_unsigned()) continue;
        const auto it = mine.find(id.get<std::uint32_t>());
        if (it == mine.end()) continue;
        countSubscription(it->second, -1);
        mine.erase(it);
      }
    }
  }

  void onClose(const Handle& hdl) {
    const auto it = subscriptions.find(hdl);
    if (it == subscriptions.end()) return;
    for (const auto& [id, channel] : it->second) countSubscription(channel, -1);
    subscriptions.erase(it);
  }

  /// Sends what is waiting, then polls again in poll_ms.
  void pump() {
    if (stopping.load()) return;
    Outgoing m;
    std::string frame;
    for (int n = 0; n < 1024 && next(m); ++n) {
      for (auto& [hdl, mine] : subscriptions) {
        for (const auto& [id, channel] : mine) {
          if (channel != m.channel) continue;
          websocketpp::lib::error_code ec;
          const Server::connection_ptr con = server.get_con_from_hdl(hdl, ec);
          if (ec || !con) continue;
          if (con->get_buffered_amount() > max_buffered_bytes) {
            dropped_slow_client.fetch_add(1, std::memory_order_relaxed);
            continue;
          }
          frame.assign(1 + 4 + 8 + m.data.size(), '\0');
          frame[0] = 1;  // message data
          putLe(frame, 1, id, 4);
          putLe(frame, 5, m.stamp_ns, 8);
          std::copy(m.data.begin(), m.data.end(), frame.begin() + 13);
          ec = con->send(frame.data(), frame.size(), websocketpp::frame::opcode::binary);
          if (!ec) sent.fetch_add(1, std::memory_order_relaxed);
        }
      }
    }
    server.set_timer(poll_ms, [this](const websocketpp::lib::error_code& ec) {
      if (!ec) pump();
    });
  }
};

std::unique_ptr<Transport> Transport::start(const std::string& host, std::uint16_t port, std::vector<Channel> channels,
                                            std::function<bool(Outgoing&)> next, std::string& error, int poll_ms,
                                            std::size_t max_buffered_bytes) {
  auto impl = std::make_unique<Impl>();
  Impl& s = *impl;
  s.next = std::move(next);
  s.poll_ms = poll_ms;
  s.max_buffered_bytes = max_buffered_bytes;
  std::uint32_t max_id = 0;
  for (const Channel& c : channels) max_id = std::max(max_id, c.id);
  s.subscribers = std::vector<std::atomic<int>>(max_id + 1);
  nlohmann::json advertised = nlohmann::json::array();
  for (const Channel& c : channels) {
    advertised.push_back({{"id", c.id},
                          {"topic", c.topic},
                          {"encoding", c.encoding},
                          {"schemaName", c.schema_name},
                          {"schema", c.schema_encoding == "protobuf" ? base64(c.schema) : c.schema},
                          {"schemaEncoding", c.schema_encoding}});
  }
  s.channels = std::move(channels);
  s.hello = nlohmann::json{{"op", "serverInfo"},
                           {"name", "aerotrack"},
                           {"capabilities", nlohmann::json::array()},
                           {"supportedEncodings", nlohmann::json::array()},
                           {"metadata", nlohmann::json::object()}}
                .dump();
  s.advertise = nlohmann::json{{"op", "advertise"}, {"channels", advertised}}.dump();

  // The library's own logging off: failures are values here, not prints (DESIGN.md rule 6).
  s.server.clear_access_channels(websocketpp::log::alevel::all);
  s.server.clear_error_channels(websocketpp::log::elevel::all);
  websocketpp::lib::error_code ec;
  s.server.init_asio(ec);
  if (ec) {
    error = "cannot start the server: " + ec.message();
    return nullptr;
  }
  s.server.set_reuse_addr(true);
  Impl* self = &s;
  s.server.set_validate_handler([self](Handle hdl) {
    websocketpp::lib::error_code e;
    const Server::connection_ptr con = self->server.get_con_from_hdl(std::move(hdl), e);
    if (e) return false;
    for (const std::string& p : con->get_requested_subprotocols()) {
      if (p == kSubprotocol) {
        con->select_subprotocol(kSubprotocol, e);
        return !e;
      }
    }
    return false;  // not a Foxglove client
  });
  s.server.set_open_handler([self](const Handle& hdl) {
    self->clients.fetch_add(1, std::memory_order_relaxed);
    self->subscriptions[hdl];
    websocketpp::lib::error_code e;
    self->server.send(hdl, self->hello, websocketpp::frame::opcode::text, e);
    if (!e) self->server.send(hdl, self->advertise, websocketpp::frame::opcode::text, e);
  });
  s.server.set_message_handler(
      [self](const Handle& hdl, const Server::message_ptr& msg) { self->onMessage(hdl, msg); });
  s.server.set_close_handler([self](const Handle& hdl) { self->onClose(hdl); });
  s.server.set_fail_handler([self](const Handle& hdl) { self->onClose(hdl); });
  s.server.listen(host, std::to_string(port), ec);
  if (ec) {
    error = host + ":" + std::to_string(port) + ": cannot listen: " + ec.message();
    return nullptr;
  }
  const auto endpoint = s.server.get_local_endpoint(ec);
  s.port = ec ? port : endpoint.port();
  s.server.start_accept(ec);
  if (ec) {
    error = host + ":" + std::to_string(port) + ": cannot accept: " + ec.message();
    return nullptr;
  }
  s.pump();
  s.thread = std::thread([self] {
    try {
      self->server.run();
    } catch (...) {  // a handler's exception ends the live view, never the flight
    }
  });
  return std::unique_ptr<Transport>(new Transport(std::move(impl)));
}

Transport::Transport(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Transport::~Transport() {
  stop();
}

bool Transport::subscribed(std::uint32_t channel) const {
  return channel < impl_->subscribers.size() && impl_->subscribers[channel].load(std::memory_order_relaxed) > 0;
}

std::uint16_t Transport::port() const {
  return impl_->port;
}

TransportCounters Transport::counters() const {
  return {impl_->clients.load(), impl_->sent.load(), impl_->dropped_slow_client.load()};
}

void Transport::stop() {
  if (!impl_ || !impl_->thread.joinable()) return;
  Impl* self = impl_.get();
  self->stopping.store(true);
  // On the server's thread: stop accepting, close every connection, then let run() return.
  self->server.get_io_service().post([self] {
    websocketpp::lib::error_code ec;
    self->server.stop_listening(ec);
    for (auto& [hdl, subscriptions] : self->subscriptions)
      self->server.close(hdl, websocketpp::close::status::going_away, "", ec);
    self->server.stop();
  });
  impl_->thread.join();
}

}  // namespace aerotrack::app::live
