// The MyActuator RMD-X gimbal motor's CAN protocol (servo motor control protocol V4.2, driver V3;
// issue 11 item 3): the frames the driver sends and the replies it reads, as pure code -- no sockets,
// no clocks. Classic CAN at 1 Mbit/s, standard identifiers: commands to 0x140 + motor id, replies from
// 0x240 + motor id (ids 1..32); always 8 data bytes, byte 0 the command (echoed by the reply),
// multi-byte fields little-endian, unused bytes 0.
//
// Units are the protocol's (degrees, degrees per second, amperes, volts) and named so; the driver
// converts to the project's radians. Encoding checks that a value fits its field (an int32 of
// 0.01 deg/s, a uint16 of deg/s, ...) and rounds to the nearest count; decoding checks the
// identifier, the length and the command, so a stray or corrupt frame is an error, never a reading.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::protocol::rmd {

/// One classic CAN data frame (the shape of linux/can.h's can_frame without the flags).
struct CanFrame {
  std::uint32_t id = 0;  ///< 11-bit standard identifier.
  std::uint8_t length = 0;
  std::array<std::uint8_t, 8> data{};
  bool operator==(const CanFrame&) const = default;
};

inline constexpr int kMinMotorId = 1;
inline constexpr int kMaxMotorId = 32;
inline constexpr std::uint32_t kCommandBaseId = 0x140;
inline constexpr std::uint32_t kReplyBaseId = 0x240;

enum class Command : std::uint8_t {
  kShutdown = 0x80,            ///< Output off, closed loop left.
  kStop = 0x81,                ///< Speed to zero, closed loop kept.
  kReadMultiTurnAngle = 0x92,  ///< Reply: output-shaft angle, int32 0.01 deg.
  kReadStatus1 = 0x9A,         ///< Reply: temperature, brake, voltage, error bits.
  kSpeed = 0xA2,               ///< int32 0.01 deg/s; reply: Feedback.
  kAbsolutePosition = 0xA4,    ///< uint16 deg/s limit, int32 0.01 deg; reply: Feedback.
  kWatchdog = 0xB3,            ///< Communication-loss protection: uint32 ms (0: off); motor stops on expiry.
};

/// The error bits of status 1 (several may be set at once).
enum ErrorBits : std::uint16_t {
  kErrorStall = 0x0002,
  kErrorLowVoltage = 0x0004,
  kErrorOverVoltage = 0x0008,
  kErrorOverCurrent = 0x0010,
  kErrorPowerOverrun = 0x0040,
  kErrorCalibrationWrite = 0x0080,
  kErrorSpeeding = 0x0100,
  kErrorOverTemperature = 0x1000,
  kErrorEncoderCalibration = 0x2000,
};

// --- Requests. Error: a motor id outside 1..32 or a value that does not fit its field. ---

rt::Expected<CanFrame> speedCommand(int motor_id, double speed_dps);
/// max_speed_dps: the motor's speed limit for the move, 0..65535 (0: no limit).
rt::Expected<CanFrame> absolutePositionCommand(int motor_id, double angle_deg, double max_speed_dps);
rt::Expected<CanFrame> readMultiTurnAngle(int motor_id);
rt::Expected<CanFrame> readStatus1(int motor_id);
rt::Expected<CanFrame> stopCommand(int motor_id);
rt::Expected<CanFrame> shutdownCommand(int motor_id);
/// timeout_s: 0 turns the protection off; else rounded to whole milliseconds, at least 1.
rt::Expected<CanFrame> watchdogCommand(int motor_id, double timeout_s);

// --- Replies. ---

/// The reply to a speed or position command (and the motor's regular feedback).
struct Feedback {
  int temperature_c = 0;
  double torque_current_a = 0.0;  ///< iq, 0.01 A counts
  double speed_dps = 0.0;         ///< output shaft, whole deg/s
  double angle_deg = 0.0;         ///< output shaft, whole degrees, +-32767 (multi-turn; use 0x92 for 0.01 deg)
};

struct Status1 {
  int temperature_c = 0;
  bool brake_released = false;
  double voltage_v = 0.0;  ///< 0.1 V counts
  std::uint16_t errors = 0;
};

struct Reply {
  Command command = Command::kStop;
  Feedback feedback;                  ///< kSpeed, kAbsolutePosition
  double multi_turn_angle_deg = 0.0;  ///< kReadMultiTurnAngle
  Status1 status;                     ///< kReadStatus1
};

/// Decodes a frame from motor_id. Error (one line): not from this motor's reply identifier, not 8
/// bytes, or a command this codec does not know.
rt::Expected<Reply> decodeReply(int motor_id, const CanFrame& frame);

/// "stall, low voltage" for the set bits (unknown bits in hex); "none" for 0.
std::string describeErrors(std::uint16_t errors);

}  // namespace aerotrack::hal::protocol::rmd
