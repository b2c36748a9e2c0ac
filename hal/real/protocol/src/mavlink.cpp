// MAVLink v2 codec: see mavlink.hpp.
#include "aerotrack/hal/protocol/mavlink.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

namespace aerotrack::hal::protocol::mavlink {
namespace {

struct Known {
  std::uint32_t id;
  std::uint8_t crc_extra;
  std::size_t length;  // the full payload length, extensions included
};
// From common.xml (minimal.xml for HEARTBEAT); node-mavlink's MAGIC_NUMBER and PAYLOAD_LENGTH agree.
constexpr Known kKnown[] = {{kHeartbeat, 50, 9},
                            {kAttitude, 39, 28},
                            {kLocalPositionNed, 185, 28},
                            {kSetPositionTargetLocalNed, 143, 53},
                            {kOdometry, 91, 233}};

const Known* known(std::uint32_t id) {
  for (const Known& k : kKnown)
    if (k.id == id) return &k;
  return nullptr;
}

/// Little-endian writer into a fixed payload, and reader over bytes that reads zeros past their end
/// (MAVLink 2's truncated payloads): neither allocates.
class Writer {
 public:
  explicit Writer(Payload& out, std::size_t length) : out_(out) {
    out_.size = length;
    for (std::size_t i = 0; i < length; ++i) out_.bytes[i] = 0;
  }
  template <class T>
  Writer& put(T value) {
    if constexpr (std::is_same_v<T, float>) {
      put(std::bit_cast<std::uint32_t>(value));
    } else {
      using U = std::make_unsigned_t<T>;
      const auto u = static_cast<U>(value);
      for (std::size_t i = 0; i < sizeof(T); ++i) out_.bytes[at_++] = static_cast<std::uint8_t>(u >> (8 * i));
    }
    return *this;
  }

 private:
  Payload& out_;
  std::size_t at_ = 0;
};

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  template <class T>
  T get() {
    if constexpr (std::is_same_v<T, float>) {
      return std::bit_cast<float>(get<std::uint32_t>());
    } else {
      using U = std::make_unsigned_t<T>;
      U u = 0;
      for (std::size_t i = 0; i < sizeof(T); ++i, ++at_) {
        const std::uint8_t byte = at_ < size_ ? data_[at_] : 0;
        u = static_cast<U>(u | (static_cast<U>(byte) << (8 * i)));
      }
      return static_cast<T>(u);
    }
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

/// The allocating form of encodePayload(m, Payload&) (declared in the header), for callers that keep bytes.
template <class Message>
std::vector<std::uint8_t> encodeToVector(const Message& m) {
  Payload p;
  encodePayload(m, p);
  std::vector<std::uint8_t> out(p.size, 0);
  for (std::size_t i = 0; i < p.size; ++i) out[i] = p.bytes[i];
  return out;
}

}  // namespace

std::uint16_t crcAccumulate(std::uint8_t byte, std::uint16_t crc) {
  auto tmp = static_cast<std::uint8_t>(byte ^ static_cast<std::uint8_t>(crc & 0xFF));
  tmp = static_cast<std::uint8_t>(tmp ^ static_cast<std::uint8_t>(tmp << 4));
  return static_cast<std::uint16_t>((crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4));
}

std::uint16_t crc16(const std::uint8_t* data, std::size_t size, std::uint16_t crc) {
  for (std::size_t i = 0; i < size; ++i) crc = crcAccumulate(data[i], crc);
  return crc;
}

std::optional<std::uint8_t> crcExtra(std::uint32_t message_id) {
  const Known* k = known(message_id);
  if (k == nullptr) return std::nullopt;
  return k->crc_extra;
}

void encodePayload(const Heartbeat& m, Payload& out) {
  Writer w(out, 9);
  w.put(m.custom_mode).put(m.type).put(m.autopilot).put(m.base_mode).put(m.system_status).put(m.mavlink_version);
}

void encodePayload(const SetPositionTargetLocalNed& m, Payload& out) {
  Writer w(out, 53);
  w.put(m.time_boot_ms).put(m.x).put(m.y).put(m.z).put(m.vx).put(m.vy).put(m.vz).put(m.afx).put(m.afy).put(m.afz);
  w.put(m.yaw).put(m.yaw_rate).put(m.type_mask).put(m.target_system).put(m.target_component).put(m.coordinate_frame);
}

void encodePayload(const LocalPositionNed& m, Payload& out) {
  Writer w(out, 28);
  w.put(m.time_boot_ms).put(m.x).put(m.y).put(m.z).put(m.vx).put(m.vy).put(m.vz);
}

void encodePayload(const Attitude& m, Payload& out) {
  Writer w(out, 28);
  w.put(m.time_boot_ms).put(m.roll).put(m.pitch).put(m.yaw).put(m.rollspeed).put(m.pitchspeed).put(m.yawspeed);
}

void encodePayload(const Odometry& m, Payload& out) {
  Writer w(out, 233);
  w.put(m.time_usec).put(m.x).put(m.y).put(m.z);
  for (const float q : m.q) w.put(q);
  w.put(m.vx).put(m.vy).put(m.vz).put(m.rollspeed).put(m.pitchspeed).put(m.yawspeed);
  for (const float c : m.pose_covariance) w.put(c);
  for (const float c : m.velocity_covariance) w.put(c);
  w.put(m.frame_id).put(m.child_frame_id).put(m.reset_counter).put(m.estimator_type).put(m.quality);
}

std::vector<std::uint8_t> encodePayload(const Heartbeat& m) {
  return encodeToVector(m);
}

std::vector<std::uint8_t> encodePayload(const SetPositionTargetLocalNed& m) {
  return encodeToVector(m);
}

std::vector<std::uint8_t> encodePayload(const LocalPositionNed& m) {
  return encodeToVector(m);
}

std::vector<std::uint8_t> encodePayload(const Attitude& m) {
  return encodeToVector(m);
}

std::vector<std::uint8_t> encodePayload(const Odometry& m) {
  return encodeToVector(m);
}

Heartbeat decodeHeartbeat(const std::uint8_t* payload, std::size_t size) {
  Reader r(payload, size);
  Heartbeat m;
  m.custom_mode = r.get<std::uint32_t>();
  m.type = r.get<std::uint8_t>();
  m.autopilot = r.get<std::uint8_t>();
  m.base_mode = r.get<std::uint8_t>();
  m.system_status = r.get<std::uint8_t>();
  m.mavlink_version = r.get<std::uint8_t>();
  return m;
}

SetPositionTargetLocalNed decodeSetPositionTargetLocalNed(const std::uint8_t* payload, std::size_t size) {
  Reader r(payload, size);
  SetPositionTargetLocalNed m;
  m.time_boot_ms = r.get<std::uint32_t>();
  for (float* f : {&m.x, &m.y, &m.z, &m.vx, &m.vy, &m.vz, &m.afx, &m.afy, &m.afz, &m.yaw, &m.yaw_rate})
    *f = r.get<float>();
  m.type_mask = r.get<std::uint16_t>();
  m.target_system = r.get<std::uint8_t>();
  m.target_component = r.get<std::uint8_t>();
  m.coordinate_frame = r.get<std::uint8_t>();
  return m;
}

LocalPositionNed decodeLocalPositionNed(const std::uint8_t* payload, std::size_t size) {
  Reader r(payload, size);
  LocalPositionNed m;
  m.time_boot_ms = r.get<std::uint32_t>();
  for (float* f : {&m.x, &m.y, &m.z, &m.vx, &m.vy, &m.vz}) *f = r.get<float>();
  return m;
}

Attitude decodeAttitude(const std::uint8_t* payload, std::size_t size) {
  Reader r(payload, size);
  Attitude m;
  m.time_boot_ms = r.get<std::uint32_t>();
  for (float* f : {&m.roll, &m.pitch, &m.yaw, &m.rollspeed, &m.pitchspeed, &m.yawspeed}) *f = r.get<float>();
  return m;
}

Odometry decodeOdometry(const std::uint8_t* payload, std::size_t size) {
  Reader r(payload, size);
  Odometry m;
  m.time_usec = r.get<std::uint64_t>();
  for (float* f : {&m.x, &m.y, &m.z}) *f = r.get<float>();
  for (float& q : m.q) q = r.get<float>();
  for (float* f : {&m.vx, &m.vy, &m.vz, &m.rollspeed, &m.pitchspeed, &m.yawspeed}) *f = r.get<float>();
  for (float& c : m.pose_covariance) c = r.get<float>();
  for (float& c : m.velocity_covariance) c = r.get<float>();
  m.frame_id = r.get<std::uint8_t>();
  m.child_frame_id = r.get<std::uint8_t>();
  m.reset_counter = r.get<std::uint8_t>();
  m.estimator_type = r.get<std::uint8_t>();
  m.quality = r.get<std::int8_t>();
  return m;
}

Heartbeat decodeHeartbeat(const std::vector<std::uint8_t>& payload) {
  return decodeHeartbeat(payload.data(), payload.size());
}

SetPositionTargetLocalNed decodeSetPositionTargetLocalNed(const std::vector<std::uint8_t>& payload) {
  return decodeSetPositionTargetLocalNed(payload.data(), payload.size());
}

LocalPositionNed decodeLocalPositionNed(const std::vector<std::uint8_t>& payload) {
  return decodeLocalPositionNed(payload.data(), payload.size());
}

Attitude decodeAttitude(const std::vector<std::uint8_t>& payload) {
  return decodeAttitude(payload.data(), payload.size());
}

Odometry decodeOdometry(const std::vector<std::uint8_t>& payload) {
  return decodeOdometry(payload.data(), payload.size());
}

void frameInto(std::uint32_t message_id, const Payload& payload, const Sender& sender, std::uint8_t sequence,
               FrameBytes& out) {
  std::size_t length = std::min(payload.size, kMaxPayloadBytes);
  while (length > 1 && payload.bytes[length - 1] == 0) --length;  // v2 payload truncation (one byte stays)
  if (length == 0) length = 1;                                    // an empty payload is sent as one zero byte
  out.size = kHeaderBytes + length + 2;
  out.bytes[0] = kStxV2;
  out.bytes[1] = static_cast<std::uint8_t>(length);
  out.bytes[2] = 0;
  out.bytes[3] = 0;
  out.bytes[4] = sequence;
  out.bytes[5] = sender.system_id;
  out.bytes[6] = sender.component_id;
  out.bytes[7] = static_cast<std::uint8_t>(message_id);
  out.bytes[8] = static_cast<std::uint8_t>(message_id >> 8);
  out.bytes[9] = static_cast<std::uint8_t>(message_id >> 16);
  for (std::size_t i = 0; i < length; ++i) out.bytes[kHeaderBytes + i] = i < payload.size ? payload.bytes[i] : 0;
  std::uint16_t crc = crc16(out.bytes.data() + 1, kHeaderBytes - 1 + length);
  crc = crcAccumulate(crcExtra(message_id).value_or(0), crc);
  out.bytes[kHeaderBytes + length] = static_cast<std::uint8_t>(crc & 0xFF);
  out.bytes[kHeaderBytes + length + 1] = static_cast<std::uint8_t>(crc >> 8);
}

std::vector<std::uint8_t> frame(std::uint32_t message_id, std::vector<std::uint8_t> payload, const Sender& sender,
                                std::uint8_t sequence) {
  Payload p;
  p.size = std::min(payload.size(), kMaxPayloadBytes);
  for (std::size_t i = 0; i < p.size; ++i) p.bytes[i] = payload[i];
  FrameBytes f;
  frameInto(message_id, p, sender, sequence, f);
  std::vector<std::uint8_t> out(f.size, 0);
  for (std::size_t i = 0; i < f.size; ++i) out[i] = f.bytes[i];
  return out;
}

void Parser::feedEach(const std::uint8_t* data, std::size_t size,
                      const std::function<void(const FrameView&)>& on_frame) {
  buffer_.insert(buffer_.end(), data, data + size);
  std::size_t at = 0;
  while (at < buffer_.size()) {
    if (buffer_[at] != kStxV2) {
      if (buffer_[at] == kStxV1) ++unsupported_;
      ++skipped_bytes_;
      ++at;
      continue;
    }
    if (buffer_.size() - at < kHeaderBytes) break;  // wait for the header
    const std::size_t length = buffer_[at + 1];
    const std::uint8_t incompat = buffer_[at + 2];
    const std::size_t total = kHeaderBytes + length + 2 + ((incompat & 0x01) != 0 ? 13 : 0);
    if (buffer_.size() - at < total) break;  // wait for the rest
    const std::uint32_t id =
        buffer_[at + 7] | (buffer_[at + 8] << 8) | (static_cast<std::uint32_t>(buffer_[at + 9]) << 16);
    const Known* k = known(id);
    if ((incompat & ~0x01) != 0 || (incompat & 0x01) != 0) {  // signed, or flags this codec cannot honour
      ++unsupported_;
      at += total;
      continue;
    }
    if (k == nullptr) {
      ++unknown_;
      at += total;
      continue;
    }
    std::uint16_t crc = crc16(buffer_.data() + at + 1, kHeaderBytes - 1 + length);
    crc = crcAccumulate(k->crc_extra, crc);
    const std::uint16_t sent = buffer_[at + kHeaderBytes + length] | (buffer_[at + kHeaderBytes + length + 1] << 8);
    if (crc != sent || length > k->length) {
      // Not a frame after all (or corrupt): resynchronise on the next byte, not past a frame that may follow.
      ++bad_crc_;
      ++at;
      continue;
    }
    FrameView f;
    f.sequence = buffer_[at + 4];
    f.system_id = buffer_[at + 5];
    f.component_id = buffer_[at + 6];
    f.message_id = id;
    f.payload = buffer_.data() + at + kHeaderBytes;
    f.payload_size = length;
    f.full_size = k->length;
    on_frame(f);
    at += total;
  }
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(at));
  if (buffer_.size() > 4 * (kHeaderBytes + kMaxPayloadBytes + 15)) buffer_.clear();  // never grows without bound
}

std::vector<Frame> Parser::feed(const std::uint8_t* data, std::size_t size) {
  std::vector<Frame> out;
  feedEach(data, size, [&out](const FrameView& v) {
    Frame f;
    f.sequence = v.sequence;
    f.system_id = v.system_id;
    f.component_id = v.component_id;
    f.message_id = v.message_id;
    f.payload.assign(v.full_size, 0);
    for (std::size_t i = 0; i < v.payload_size; ++i) f.payload[i] = v.payload[i];
    out.push_back(std::move(f));
  });
  return out;
}

void Parser::endOfDatagram() {
  if (buffer_.empty()) return;
  ++truncated_;
  buffer_.clear();
}

}  // namespace aerotrack::hal::protocol::mavlink
