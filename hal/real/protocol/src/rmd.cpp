// RMD-X CAN protocol codec: see rmd.hpp.
#include "aerotrack/hal/protocol/rmd.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

namespace aerotrack::hal::protocol::rmd {
namespace {

rt::Status checkMotor(int motor_id) {
  if (motor_id < kMinMotorId || motor_id > kMaxMotorId)
    return rt::Error{"rmd: motor id " + std::to_string(motor_id) + " is outside 1..32"};
  return rt::ok();
}

CanFrame request(int motor_id, Command command) {
  CanFrame f;
  f.id = kCommandBaseId + static_cast<std::uint32_t>(motor_id);
  f.length = 8;
  f.data[0] = static_cast<std::uint8_t>(command);
  return f;
}

/// value / unit rounded to a count that must lie in [lo, hi].
rt::Expected<std::int64_t> counts(double value, double unit, std::int64_t lo, std::int64_t hi, const char* what) {
  const double scaled = std::round(value / unit);
  if (!std::isfinite(scaled) || scaled < static_cast<double>(lo) || scaled > static_cast<double>(hi))
    return rt::Error{std::string("rmd: ") + what + " " + std::to_string(value) + " does not fit the frame"};
  return static_cast<std::int64_t>(scaled);
}

void putLe(CanFrame& f, std::size_t at, std::uint64_t value, std::size_t bytes) {
  for (std::size_t i = 0; i < bytes; ++i) f.data[at + i] = static_cast<std::uint8_t>(value >> (8 * i));
}

std::uint32_t getLe(const CanFrame& f, std::size_t at, std::size_t bytes) {
  std::uint32_t value = 0;
  for (std::size_t i = 0; i < bytes; ++i) value |= static_cast<std::uint32_t>(f.data[at + i]) << (8 * i);
  return value;
}

/// A two's-complement byte (the protocol's int8 temperature).
int signedByte(std::uint8_t b) {
  return b < 0x80 ? b : b - 0x100;
}

std::int16_t getI16(const CanFrame& f, std::size_t at) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(getLe(f, at, 2)));
}

}  // namespace

rt::Expected<CanFrame> speedCommand(int motor_id, double speed_dps) {
  if (rt::Status s = checkMotor(motor_id); !s) return s.error();
  const auto v = counts(speed_dps, 0.01, std::numeric_limits<std::int32_t>::min(),
                        std::numeric_limits<std::int32_t>::max(), "speed (deg/s)");
  if (!v) return v.error();
  CanFrame f = request(motor_id, Command::kSpeed);
  putLe(f, 4, static_cast<std::uint32_t>(static_cast<std::int32_t>(*v)), 4);
  return f;
}

rt::Expected<CanFrame> absolutePositionCommand(int motor_id, double angle_deg, double max_speed_dps) {
  if (rt::Status s = checkMotor(motor_id); !s) return s.error();
  const auto angle = counts(angle_deg, 0.01, std::numeric_limits<std::int32_t>::min(),
                            std::numeric_limits<std::int32_t>::max(), "angle (deg)");
  if (!angle) return angle.error();
  const auto speed = counts(max_speed_dps, 1.0, 0, 0xFFFF, "speed limit (deg/s)");
  if (!speed) return speed.error();
  CanFrame f = request(motor_id, Command::kAbsolutePosition);
  putLe(f, 2, static_cast<std::uint64_t>(*speed), 2);
  putLe(f, 4, static_cast<std::uint32_t>(static_cast<std::int32_t>(*angle)), 4);
  return f;
}

rt::Expected<CanFrame> readMultiTurnAngle(int motor_id) {
  if (rt::Status s = checkMotor(motor_id); !s) return s.error();
  return request(motor_id, Command::kReadMultiTurnAngle);
}

rt::Expected<CanFrame> readStatus1(int motor_id) {
  if (rt::Status s = checkMotor(motor_id); !s) return s.error();
  return request(motor_id, Command::kReadStatus1);
}

rt::Expected<CanFrame> stopCommand(int motor_id) {
  if (rt::Status s = checkMotor(motor_id); !s) return s.error();
  return request(motor_id, Command::kStop);
}

rt::Expected<CanFrame> shutdownCommand(int motor_id) {
  if (rt::Status s = checkMotor(motor_id); !s) return s.error();
  return request(motor_id, Command::kShutdown);
}

rt::Expected<CanFrame> watchdogCommand(int motor_id, double timeout_s) {
  if (rt::Status s = checkMotor(motor_id); !s) return s.error();
  auto ms = counts(timeout_s, 1e-3, 0, std::numeric_limits<std::uint32_t>::max(), "watchdog time (s)");
  if (!ms) return ms.error();
  if (*ms == 0 && timeout_s > 0.0) ms = 1;  // a positive time below half a millisecond is not "off"
  CanFrame f = request(motor_id, Command::kWatchdog);
  putLe(f, 4, static_cast<std::uint64_t>(*ms), 4);
  return f;
}

rt::Expected<Reply> decodeReply(int motor_id, const CanFrame& frame) {
  if (rt::Status s = checkMotor(motor_id); !s) return s.error();
  char id[16];
  std::snprintf(id, sizeof(id), "0x%03X", static_cast<unsigned>(frame.id));
  if (frame.id != kReplyBaseId + static_cast<std::uint32_t>(motor_id))
    return rt::Error{std::string("rmd: frame ") + id + " is not a reply from motor " + std::to_string(motor_id)};
  if (frame.length != 8)
    return rt::Error{std::string("rmd: reply ") + id + " has " + std::to_string(frame.length) + " bytes, not 8"};
  Reply r;
  switch (frame.data[0]) {
    case static_cast<std::uint8_t>(Command::kSpeed):
    case static_cast<std::uint8_t>(Command::kAbsolutePosition):
      r.command = static_cast<Command>(frame.data[0]);
      r.feedback.temperature_c = signedByte(frame.data[1]);
      r.feedback.torque_current_a = 0.01 * getI16(frame, 2);
      r.feedback.speed_dps = getI16(frame, 4);
      r.feedback.angle_deg = getI16(frame, 6);
      return r;
    case static_cast<std::uint8_t>(Command::kReadMultiTurnAngle):
      r.command = Command::kReadMultiTurnAngle;
      r.multi_turn_angle_deg = 0.01 * static_cast<std::int32_t>(getLe(frame, 4, 4));
      return r;
    case static_cast<std::uint8_t>(Command::kReadStatus1):
      r.command = Command::kReadStatus1;
      r.status.temperature_c = signedByte(frame.data[1]);
      r.status.brake_released = frame.data[3] == 1;
      r.status.voltage_v = 0.1 * getLe(frame, 4, 2);
      r.status.errors = static_cast<std::uint16_t>(getLe(frame, 6, 2));
      return r;
    case static_cast<std::uint8_t>(Command::kStop):
    case static_cast<std::uint8_t>(Command::kShutdown):
    case static_cast<std::uint8_t>(Command::kWatchdog):  // V4.2's own example replies zeros, not an echo
      r.command = static_cast<Command>(frame.data[0]);
      return r;
    default: {
      char command[8];
      std::snprintf(command, sizeof(command), "0x%02X", frame.data[0]);
      return rt::Error{std::string("rmd: reply ") + id + " carries unknown command " + command};
    }
  }
}

std::string describeErrors(std::uint16_t errors) {
  if (errors == 0) return "none";
  static constexpr std::pair<std::uint16_t, const char*> kNames[] = {
      {kErrorStall, "stall"},
      {kErrorLowVoltage, "low voltage"},
      {kErrorOverVoltage, "over voltage"},
      {kErrorOverCurrent, "over current"},
      {kErrorPowerOverrun, "power overrun"},
      {kErrorCalibrationWrite, "calibration write error"},
      {kErrorSpeeding, "speeding"},
      {kErrorOverTemperature, "over temperature"},
      {kErrorEncoderCalibration, "encoder calibration error"}};
  std::string out;
  std::uint16_t known = 0;
  for (const auto& [bit, name] : kNames) {
    known = static_cast<std::uint16_t>(known | bit);
    if ((errors & bit) != 0) out += (out.empty() ? "" : ", ") + std::string(name);
  }
  if (const auto unknown = static_cast<std::uint16_t>(errors & ~known); unknown != 0) {
    char hex[16];
    std::snprintf(hex, sizeof(hex), "0x%04X", unknown);
    out += (out.empty() ? "unknown bits " : ", unknown bits ") + std::string(hex);
  }
  return out;
}

}  // namespace aerotrack::hal::protocol::rmd
