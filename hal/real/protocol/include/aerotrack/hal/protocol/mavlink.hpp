// MAVLink v2 for the flight controller (issue 11 item 4), for the few messages the drone uses: pure
// code, no sockets. No MAVLink library is packaged in Debian 12; this codec is checked against frames
// from an independent implementation, the npm package node-mavlink (tests/unit/hal/protocol/).
//
// Framing (mavlink.io, "Packet Serialization"): 0xFD, payload length, incompatibility flags (0: no
// signing), compatibility flags, sequence, system id, component id, 24-bit message id, the payload
// with its trailing zero bytes cut off (receivers pad them back), and CRC-16/MCRF4XX over everything
// after the 0xFD followed by the message's CRC_EXTRA. Payload fields are little-endian, ordered by
// size (largest first), extensions last, as in each message's definition (common.xml).
//
// Frames here use the wire's frames: positions NED (x north, y east, z down), body FRD. The project
// converts to and from ENU/FLU in frames.hpp of the driver, not here.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::protocol::mavlink {

inline constexpr std::uint8_t kStxV2 = 0xFD;
inline constexpr std::uint8_t kStxV1 = 0xFE;
inline constexpr std::size_t kHeaderBytes = 10;  // STX .. message id
inline constexpr std::size_t kMaxPayloadBytes = 255;

/// CRC-16/MCRF4XX (MAVLink's X.25 variant): initial 0xFFFF, no final XOR.
std::uint16_t crcAccumulate(std::uint8_t byte, std::uint16_t crc);
std::uint16_t crc16(const std::uint8_t* data, std::size_t size, std::uint16_t crc = 0xFFFF);

enum MessageId : std::uint32_t {
  kHeartbeat = 0,
  kAttitude = 30,
  kLocalPositionNed = 32,
  kSetPositionTargetLocalNed = 84,
  kOdometry = 331,
};

/// CRC_EXTRA of a message this codec knows; nothing for another id.
std::optional<std::uint8_t> crcExtra(std::uint32_t message_id);

struct Heartbeat {
  std::uint32_t custom_mode = 0;
  std::uint8_t type = 0;       ///< MAV_TYPE (18: onboard controller; 2: quadrotor)
  std::uint8_t autopilot = 0;  ///< MAV_AUTOPILOT (12: PX4, 3: ArduPilot, 8: none)
  std::uint8_t base_mode = 0;  ///< MAV_MODE_FLAG bits (128: armed)
  std::uint8_t system_status = 0;
  std::uint8_t mavlink_version = 3;
};

/// Bits of SET_POSITION_TARGET_LOCAL_NED's type_mask: a set bit means "ignore this field".
enum PositionTargetMask : std::uint16_t {
  kIgnorePosition = 0x0007,
  kIgnoreVelocity = 0x0038,
  kIgnoreAcceleration = 0x01C0,
  kForceSetpoint = 0x0200,
  kIgnoreYaw = 0x0400,
  kIgnoreYawRate = 0x0800,
};
inline constexpr std::uint8_t kFrameLocalNed = 1;  ///< MAV_FRAME_LOCAL_NED

struct SetPositionTargetLocalNed {
  std::uint32_t time_boot_ms = 0;
  float x = 0, y = 0, z = 0;        ///< m, NED
  float vx = 0, vy = 0, vz = 0;     ///< m/s, NED
  float afx = 0, afy = 0, afz = 0;  ///< m/s^2, NED
  float yaw = 0, yaw_rate = 0;      ///< rad, rad/s (yaw from north, clockwise)
  std::uint16_t type_mask = 0;
  std::uint8_t target_system = 1, target_component = 1;
  std::uint8_t coordinate_frame = kFrameLocalNed;
};

struct LocalPositionNed {
  std::uint32_t time_boot_ms = 0;
  float x = 0, y = 0, z = 0, vx = 0, vy = 0, vz = 0;
};

struct Attitude {
  std::uint32_t time_boot_ms = 0;
  float roll = 0, pitch = 0, yaw = 0, rollspeed = 0, pitchspeed = 0, yawspeed = 0;  ///< rad, rad/s (FRD)
};

struct Odometry {
  std::uint64_t time_usec = 0;
  float x = 0, y = 0, z = 0;
  std::array<float, 4> q{1, 0, 0, 0};  ///< w x y z, FRD body to the local frame
  float vx = 0, vy = 0, vz = 0;        ///< in child_frame_id's frame
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;
  std::array<float, 21> pose_covariance{};
  std::array<float, 21> velocity_covariance{};
  std::uint8_t frame_id = 0, child_frame_id = 0;  ///< MAV_FRAME
  std::uint8_t reset_counter = 0;                 ///< extensions
  std::uint8_t estimator_type = 0;
  std::int8_t quality = 0;
};

/// A payload in fixed storage (full length, before truncation), for callers that must not allocate.
struct Payload {
  std::array<std::uint8_t, kMaxPayloadBytes> bytes{};
  std::size_t size = 0;
};
inline constexpr std::size_t kMaxFrameBytes = kHeaderBytes + kMaxPayloadBytes + 2;  // unsigned
/// A whole frame in fixed storage.
struct FrameBytes {
  std::array<std::uint8_t, kMaxFrameBytes> bytes{};
  std::size_t size = 0;
};
void encodePayload(const Heartbeat& m, Payload& out);
void encodePayload(const SetPositionTargetLocalNed& m, Payload& out);
void encodePayload(const LocalPositionNed& m, Payload& out);
void encodePayload(const Attitude& m, Payload& out);
void encodePayload(const Odometry& m, Payload& out);
/// Decoding from bytes that may be truncated (missing bytes read as zeros). No allocation.
Heartbeat decodeHeartbeat(const std::uint8_t* payload, std::size_t size);
SetPositionTargetLocalNed decodeSetPositionTargetLocalNed(const std::uint8_t* payload, std::size_t size);
LocalPositionNed decodeLocalPositionNed(const std::uint8_t* payload, std::size_t size);
Attitude decodeAttitude(const std::uint8_t* payload, std::size_t size);
Odometry decodeOdometry(const std::uint8_t* payload, std::size_t size);

// Payloads (full length, before truncation) and their decoding (the payload zero-padded to full length).
std::vector<std::uint8_t> encodePayload(const Heartbeat& m);
std::vector<std::uint8_t> encodePayload(const SetPositionTargetLocalNed& m);
std::vector<std::uint8_t> encodePayload(const LocalPositionNed& m);
std::vector<std::uint8_t> encodePayload(const Attitude& m);
std::vector<std::uint8_t> encodePayload(const Odometry& m);
Heartbeat decodeHeartbeat(const std::vector<std::uint8_t>& payload);
SetPositionTargetLocalNed decodeSetPositionTargetLocalNed(const std::vector<std::uint8_t>& payload);
LocalPositionNed decodeLocalPositionNed(const std::vector<std::uint8_t>& payload);
Attitude decodeAttitude(const std::vector<std::uint8_t>& payload);
Odometry decodeOdometry(const std::vector<std::uint8_t>& payload);

/// Who sends a frame.
struct Sender {
  std::uint8_t system_id = 1;
  std::uint8_t component_id = 191;  ///< MAV_COMP_ID_ONBOARD_COMPUTER
};

/// A whole v2 frame around a payload of message_id (trailing zeros cut, at least one byte kept).
std::vector<std::uint8_t> frame(std::uint32_t message_id, std::vector<std::uint8_t> payload, const Sender& sender,
                                std::uint8_t sequence);

/// As frame(), into fixed storage: no allocation.
void frameInto(std::uint32_t message_id, const Payload& payload, const Sender& sender, std::uint8_t sequence,
               FrameBytes& out);

/// A frame that arrived: whose, which message, and its payload padded back to the message's length.
struct Frame {
  std::uint8_t sequence = 0;
  std::uint8_t system_id = 0;
  std::uint8_t component_id = 0;
  std::uint32_t message_id = 0;
  std::vector<std::uint8_t> payload;
};

/// A frame that arrived, seen in the parser's buffer (valid during the callback only): the payload as
/// sent (payload_size bytes, possibly truncated), full_size its message's length.
struct FrameView {
  std::uint8_t sequence = 0;
  std::uint8_t system_id = 0;
  std::uint8_t component_id = 0;
  std::uint32_t message_id = 0;
  const std::uint8_t* payload = nullptr;
  std::size_t payload_size = 0;
  std::size_t full_size = 0;
};

/// Finds frames in a byte stream (UDP datagrams or a serial line), whatever is in between. A frame with
/// a bad CRC, a message this codec does not know (its CRC cannot be checked), a signed frame, or bytes
/// that are not a frame are counted and skipped, never returned.
class Parser {
 public:
  /// Appends bytes; the frames completed by them are returned in order.
  std::vector<Frame> feed(const std::uint8_t* data, std::size_t size);
  /// As feed(), handing each frame to on_frame in order; allocates nothing once its buffer has grown
  /// to the largest frame (on_frame should not either: a lambda holding a few pointers stays inline).
  void feedEach(const std::uint8_t* data, std::size_t size, const std::function<void(const FrameView&)>& on_frame);
  std::uint64_t badCrc() const { return bad_crc_; }
  std::uint64_t unknownMessages() const { return unknown_; }
  std::uint64_t skippedBytes() const { return skipped_bytes_; }
  std::uint64_t unsupported() const { return unsupported_; }  ///< signed frames, MAVLink 1 frames
  std::uint64_t truncated() const { return truncated_; }
  /// For datagram transports (UDP), where a frame never spans two datagrams: the bytes left waiting
  /// after a datagram are a truncated frame, counted and dropped rather than joined with the next one.
  void endOfDatagram();

 private:
  std::vector<std::uint8_t> buffer_;
  std::uint64_t bad_crc_ = 0, unknown_ = 0, skipped_bytes_ = 0, unsupported_ = 0, truncated_ = 0;
};

}  // namespace aerotrack::hal::protocol::mavlink
