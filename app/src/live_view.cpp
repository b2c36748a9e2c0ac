// The live view: see live_view.hpp.
#include "live_view.hpp"

#include <charconv>
#include <cstdio>

namespace aerotrack::app {

rt::Expected<std::pair<std::string, std::uint16_t>> parseLiveAddress(const std::string& address) {
  std::string host = "127.0.0.1";
  std::string port_text = address;
  if (const std::size_t colon = address.rfind(':'); colon != std::string::npos) {
    host = address.substr(0, colon);
    port_text = address.substr(colon + 1);
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
    if (host.empty()) return rt::Error{"--live: '" + address + "': no host before ':'"};
  }
  unsigned port = 0;
  const auto [end, ec] = std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (ec != std::errc() || end != port_text.data() + port_text.size() || port == 0 || port > 65535) {
    return rt::Error{"--live: '" + address + "': expected PORT or HOST:PORT with a port in 1..65535"};
  }
  return std::make_pair(host, static_cast<std::uint16_t>(port));
}

LiveView::LiveView(const LiveViewOptions& options, std::string where, std::size_t channels)
    : options_(options),
      where_(std::move(where)),
      queue_(options.queue_capacity, rt::OverflowPolicy::kDropNewest),
      last_offered_ns_(channels, INT64_MIN) {}

LiveView::~LiveView() {
  stop();
}

rt::Expected<std::unique_ptr<LiveView>> LiveView::start(const LiveViewOptions& options,
                                                        std::vector<live::Channel> channels) {
  const auto address = parseLiveAddress(options.address);
  if (!address) return address.error();
  std::uint32_t max_id = 0;
  for (const live::Channel& c : channels) max_id = std::max(max_id, c.id);
  std::unique_ptr<LiveView> view(
      new LiveView(options, address->first + ":" + std::to_string(address->second), max_id + 1));
  LiveView* self = view.get();
  std::string error;
  view->transport_ = live::Transport::start(
      address->first, address->second, std::move(channels),
      [self](live::Outgoing& out) { return self->queue_.try_pop(out); }, error);
  if (!view->transport_) return rt::Error{"--live: " + error};
  return view;
}

void LiveView::offer(std::uint32_t channel, rt::TimeNs stamp_ns, std::span<const std::uint8_t> data) {
  if (!transport_ || channel >= last_offered_ns_.size() || !transport_->subscribed(channel)) return;
  // The rate bound, by the messages' own stamps (so a lockstep replay would be bounded the same way).
  const auto min_gap_ns = static_cast<rt::TimeNs>(1e9 / options_.max_rate_hz);
  if (last_offered_ns_[channel] != INT64_MIN && stamp_ns - last_offered_ns_[channel] < min_gap_ns &&
      stamp_ns >= last_offered_ns_[channel]) {
    return;
  }
  last_offered_ns_[channel] = stamp_ns;
  live::Outgoing m;
  m.channel = channel;
  m.stamp_ns = static_cast<std::uint64_t>(std::max<rt::TimeNs>(stamp_ns, 0));
  m.data.assign(reinterpret_cast<const char*>(data.data()), data.size());
  (void)queue_.try_push(std::move(m));  // full: dropped and counted
}

std::string LiveView::summary() const {
  const live::TransportCounters c = transport_ ? transport_->counters() : live::TransportCounters{};
  char line[256];
  std::snprintf(
      line, sizeof(line),
      "live view on ws://%s: %llu clients, %llu messages sent, %llu dropped (%llu queue full, %llu slow client)",
      where_.c_str(), static_cast<unsigned long long>(c.clients), static_cast<unsigned long long>(c.sent),
      static_cast<unsigned long long>(queue_.dropped()) + static_cast<unsigned long long>(c.dropped_slow_client),
      static_cast<unsigned long long>(queue_.dropped()), static_cast<unsigned long long>(c.dropped_slow_client));
  return line;
}

void LiveView::stop() {
  if (transport_) transport_->stop();
}

}  // namespace aerotrack::app
