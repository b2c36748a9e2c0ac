// The RMD-X CAN codec (hal/protocol/rmd.hpp) against the golden frames of MyActuator's servo motor
// control protocol V4.2 (the worked examples of its sections 2.12, 2.14, 2.20, 2.21 and 2.30):
// requests encode to those bytes, replies decode to those values; values that do not fit a field,
// motor ids outside 1..32, frames from another motor, short frames and unknown commands are errors.
#include "aerotrack/hal/protocol/rmd.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <initializer_list>

namespace aerotrack::hal::protocol::rmd {
namespace {

CanFrame frame(std::uint32_t id, std::initializer_list<int> bytes) {
  CanFrame f;
  f.id = id;
  f.length = static_cast<std::uint8_t>(bytes.size());
  std::size_t i = 0;
  for (const int b : bytes) f.data[i++] = static_cast<std::uint8_t>(b);
  return f;
}

TEST(RmdCodec, RequestsEncodeToTheProtocolsGoldenFrames) {
  // 2.20.4: 100 dps and -100 dps.
  EXPECT_EQ(*speedCommand(1, 100.0), frame(0x141, {0xA2, 0, 0, 0, 0x10, 0x27, 0, 0}));
  EXPECT_EQ(*speedCommand(1, -100.0), frame(0x141, {0xA2, 0, 0, 0, 0xF0, 0xD8, 0xFF, 0xFF}));
  // 2.21.4: 360 deg and -360 deg at most 500 dps.
  EXPECT_EQ(*absolutePositionCommand(1, 360.0, 500.0), frame(0x141, {0xA4, 0, 0xF4, 0x01, 0xA0, 0x8C, 0, 0}));
  EXPECT_EQ(*absolutePositionCommand(1, -360.0, 500.0), frame(0x141, {0xA4, 0, 0xF4, 0x01, 0x60, 0x73, 0xFF, 0xFF}));
  // 2.12.4, 2.14.4, 2.17, 2.18: reads and stops carry only the command.
  EXPECT_EQ(*readMultiTurnAngle(1), frame(0x141, {0x92, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(*readStatus1(1), frame(0x141, {0x9A, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(*stopCommand(3), frame(0x143, {0x81, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(*shutdownCommand(32), frame(0x160, {0x80, 0, 0, 0, 0, 0, 0, 0}));
  // 2.30.4: the communication watchdog at 1000 ms, and off.
  EXPECT_EQ(*watchdogCommand(1, 1.0), frame(0x141, {0xB3, 0, 0, 0, 0xE8, 0x03, 0, 0}));
  EXPECT_EQ(*watchdogCommand(1, 0.0), frame(0x141, {0xB3, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(watchdogCommand(1, 1e-4)->data[4], 1);  // positive: never rounded down to "off"
  // Rounding to the nearest count: 0.004 dps is 0; 0.005 dps is one count of 0.01.
  EXPECT_EQ(speedCommand(1, 0.004)->data[4], 0);
  EXPECT_EQ(speedCommand(1, 0.006)->data[4], 1);
}

TEST(RmdCodec, RepliesDecodeToTheProtocolsGoldenValues) {
  // 2.20.4: 50 C, 1.00 A, 500 dps, 45 deg; and the negative example.
  auto speed = decodeReply(1, frame(0x241, {0xA2, 0x32, 0x64, 0x00, 0xF4, 0x01, 0x2D, 0x00}));
  ASSERT_TRUE(speed) << speed.error().message;
  EXPECT_EQ(speed->command, Command::kSpeed);
  EXPECT_EQ(speed->feedback.temperature_c, 50);
  EXPECT_DOUBLE_EQ(speed->feedback.torque_current_a, 1.0);
  EXPECT_EQ(speed->feedback.speed_dps, 500.0);
  EXPECT_EQ(speed->feedback.angle_deg, 45.0);
  auto negative = decodeReply(1, frame(0x241, {0xA2, 0x32, 0x9C, 0xFF, 0x0C, 0xFE, 0xD3, 0xFF}));
  ASSERT_TRUE(negative);
  EXPECT_DOUBLE_EQ(negative->feedback.torque_current_a, -1.0);
  EXPECT_EQ(negative->feedback.speed_dps, -500.0);
  EXPECT_EQ(negative->feedback.angle_deg, -45.0);
  auto cold = decodeReply(1, frame(0x241, {0xA2, 0xF6, 0, 0, 0, 0, 0, 0}));  // int8 temperature
  EXPECT_EQ(cold->feedback.temperature_c, -10);
  // 2.21.4: the position command's reply has the same layout.
  auto position = decodeReply(1, frame(0x241, {0xA4, 0x32, 0x64, 0x00, 0xF4, 0x01, 0x2D, 0x00}));
  ASSERT_TRUE(position);
  EXPECT_EQ(position->command, Command::kAbsolutePosition);
  EXPECT_EQ(position->feedback.angle_deg, 45.0);
  // 2.12.4: +360.00 deg.
  auto angle = decodeReply(1, frame(0x241, {0x92, 0, 0, 0, 0xA0, 0x8C, 0, 0}));
  ASSERT_TRUE(angle);
  EXPECT_DOUBLE_EQ(angle->multi_turn_angle_deg, 360.0);
  auto below = decodeReply(1, frame(0x241, {0x92, 0, 0, 0, 0x60, 0x73, 0xFF, 0xFF}));
  EXPECT_DOUBLE_EQ(below->multi_turn_angle_deg, -360.0);
  // 2.14.4: 50 C, brake released, 48.5 V, low voltage.
  auto status = decodeReply(1, frame(0x241, {0x9A, 0x32, 0x00, 0x01, 0xE5, 0x01, 0x04, 0x00}));
  ASSERT_TRUE(status);
  EXPECT_EQ(status->status.temperature_c, 50);
  EXPECT_TRUE(status->status.brake_released);
  EXPECT_NEAR(status->status.voltage_v, 48.5, 1e-12);
  EXPECT_EQ(status->status.errors, kErrorLowVoltage);
  EXPECT_EQ(describeErrors(status->status.errors), "low voltage");
  EXPECT_EQ(describeErrors(0x0016), "stall, low voltage, over current");  // the protocol's own example
  EXPECT_EQ(describeErrors(0), "none");
  EXPECT_EQ(describeErrors(0x0301), "speeding, unknown bits 0x0201");
  // 2.30.4: the watchdog's reply (zeros after the command byte in the protocol's example).
  auto watchdog = decodeReply(1, frame(0x241, {0xB3, 0, 0, 0, 0, 0, 0, 0}));
  ASSERT_TRUE(watchdog);
  EXPECT_EQ(watchdog->command, Command::kWatchdog);
}

TEST(RmdCodec, ValuesThatDoNotFitAndStrayFramesAreErrors) {
  EXPECT_FALSE(speedCommand(0, 10.0));  // motor ids are 1..32
  EXPECT_FALSE(speedCommand(33, 10.0));
  EXPECT_FALSE(speedCommand(1, 3.0e7));  // beyond an int32 of 0.01 dps
  EXPECT_FALSE(speedCommand(1, std::nan("")));
  EXPECT_FALSE(absolutePositionCommand(1, 10.0, -1.0));     // a negative speed limit
  EXPECT_FALSE(absolutePositionCommand(1, 10.0, 70000.0));  // beyond a uint16 of dps
  EXPECT_FALSE(absolutePositionCommand(1, 2.2e7, 100.0));   // beyond an int32 of 0.01 deg
  EXPECT_FALSE(watchdogCommand(1, -1.0));
  const auto other = decodeReply(1, frame(0x242, {0xA2, 0, 0, 0, 0, 0, 0, 0}));
  ASSERT_FALSE(other);
  EXPECT_EQ(other.error().message, "rmd: frame 0x242 is not a reply from motor 1");
  const auto command_echo = decodeReply(1, frame(0x141, {0xA2, 0, 0, 0, 0, 0, 0, 0}));  // our own request
  EXPECT_FALSE(command_echo);
  const auto short_frame = decodeReply(1, frame(0x241, {0xA2, 0x32, 0x64}));
  ASSERT_FALSE(short_frame);
  EXPECT_EQ(short_frame.error().message, "rmd: reply 0x241 has 3 bytes, not 8");
  const auto unknown = decodeReply(1, frame(0x241, {0x3F, 0, 0, 0, 0, 0, 0, 0}));
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error().message, "rmd: reply 0x241 carries unknown command 0x3F");
}

}  // namespace
}  // namespace aerotrack::hal::protocol::rmd
