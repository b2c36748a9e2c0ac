// The RMD-X gimbal driver (hal/real/rmd_gimbal.hpp; issue 11 item 3) against the simulated motor of
// tests/support/rmd_motor_sim.hpp on the other end of a socketpair carrying Linux's struct can_frame,
// as a SocketCAN socket does: the watchdog is armed first, rate and angle commands become the
// protocol's frames, the multi-turn angle comes back in radians; a silent motor, stray and garbage
// frames, and a bus-off error frame show in the health. Opening a CAN interface that does not exist
// is a one-line error naming it. tests/vcan/ runs the same driver over real SocketCAN (vcan0).
#include "aerotrack/hal/real/rmd_gimbal.hpp"

#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <vector>

#include "support/rmd_motor_sim.hpp"

namespace aerotrack::hal::real {
namespace {

constexpr rt::TimeNs kMs = rt::kNsPerMillisecond;

struct Bench {
  Bench() {
    int fds[2];
    EXPECT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK, 0, fds), 0);
    gimbal = std::make_unique<RmdGimbal>(CanSocket::adopt(fds[0], "pair0"), RmdGimbalParams{});
    motor = std::make_unique<test::RmdMotorSim>(fds[1]);
  }
  std::unique_ptr<RmdGimbal> gimbal;
  std::unique_ptr<test::RmdMotorSim> motor;
};

TEST(RmdGimbal, ArmsTheWatchdogCommandsTheMotorAndReadsItsAngle) {
  Bench b;
  EXPECT_FALSE(b.gimbal->read(0).has_value());  // nothing has answered yet
  b.motor->serve(0.0);
  ASSERT_GE(b.motor->received().size(), 2U);
  EXPECT_EQ(b.motor->received()[0].can_id, 0x141U);
  EXPECT_EQ(b.motor->received()[0].data[0], 0xB3);  // the watchdog first: 200 ms
  EXPECT_EQ(b.motor->received()[0].data[4] | (b.motor->received()[0].data[5] << 8), 200);
  EXPECT_EQ(b.motor->received()[1].data[0], 0x92);
  const auto first = b.gimbal->read(5 * kMs);
  ASSERT_TRUE(first.has_value());
  EXPECT_NEAR(first->angle_rad, std::numbers::pi / 2.0, 1e-9);
  EXPECT_EQ(first->stamp_ns, 5 * kMs);
  EXPECT_EQ(b.gimbal->health(5 * kMs).state, DeviceHealth::State::kOk);

  GimbalCommand rate;
  rate.mode = GimbalCommand::Mode::kRate;
  rate.rate_radps = 1.0;  // 57.2958 deg/s: 5730 counts of 0.01
  b.gimbal->command(rate);
  b.motor->serve(0.0);
  const can_frame& sent = b.motor->received().back();
  EXPECT_EQ(sent.data[0], 0xA2);
  std::int32_t counts = 0;
  std::memcpy(&counts, sent.data + 4, 4);
  EXPECT_EQ(counts, 5730);
  for (int i = 1; i <= 20; ++i) {  // 100 ms at 200 Hz
    b.gimbal->read((5 + 5 * i) * kMs);
    b.motor->serve(0.005);
  }
  const auto moved = b.gimbal->read(110 * kMs);
  ASSERT_TRUE(moved.has_value());
  EXPECT_NEAR(moved->angle_rad, std::numbers::pi / 2.0 + 0.1, 0.006);  // one 5 ms step of lag
  EXPECT_NEAR(moved->rate_radps, 1.0, 0.01);                           // the feedback's whole deg/s

  GimbalCommand angle;
  angle.mode = GimbalCommand::Mode::kAngle;
  angle.angle_rad = -2.0 * std::numbers::pi;  // unlimited rotation: a full turn back
  angle.max_rate_radps = 0.0;                 // the default limit, 6 rad/s = 343.77 -> 344 deg/s
  b.gimbal->command(angle);
  b.motor->serve(0.0);
  const can_frame& position = b.motor->received().back();
  EXPECT_EQ(position.data[0], 0xA4);
  EXPECT_EQ(position.data[2] | (position.data[3] << 8), 344);
  std::memcpy(&counts, position.data + 4, 4);
  EXPECT_EQ(counts, -36000);
}

TEST(RmdGimbal, ASilentMotorFailsAfterTheReplyTimeout) {
  Bench b;
  b.motor->setSilent(true);
  b.gimbal->read(0);
  b.motor->serve(0.0);
  EXPECT_EQ(b.gimbal->health(50 * kMs).state, DeviceHealth::State::kOk);
  const DeviceHealth h = b.gimbal->health(150 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kFailed);
  EXPECT_EQ(h.detail, "pair0 motor 1: no reply for 150 ms");
}

TEST(RmdGimbal, StrayAndGarbageFramesAreCountedAndIgnoredAndBusOffFails) {
  Bench b;
  b.gimbal->read(0);
  b.motor->serve(0.0);
  b.motor->inject(0x242, {0x92, 0, 0, 0, 0, 0, 0, 0});  // another motor's reply
  b.motor->inject(0x241, {0x3F, 1, 2, 3, 4, 5, 6, 7});  // an unknown command
  b.motor->inject(0x241, {0x92, 0});                    // too short
  const auto state = b.gimbal->read(5 * kMs);
  ASSERT_TRUE(state.has_value());
  EXPECT_NEAR(state->angle_rad, std::numbers::pi / 2.0, 1e-9);  // the good reply still counts
  DeviceHealth h = b.gimbal->health(5 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kDegraded);
  EXPECT_EQ(h.error_count, 3U);
  EXPECT_NE(h.detail.find("rmd: frame 0x242 is not a reply from motor 1"), std::string::npos) << h.detail;

  b.motor->inject(CAN_ERR_FLAG | CAN_ERR_BUSOFF, {0, 0, 0, 0, 0, 0, 0, 0});
  b.gimbal->read(10 * kMs);
  h = b.gimbal->health(10 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kFailed);
  EXPECT_EQ(h.detail, "pair0: bus-off");
}

// The motor speaks with standard identifiers only: an extended frame whose 29-bit identifier is
// 0x241 is another node's, and a remote frame asks for data rather than carrying it; neither is an
// angle, whatever its bytes say.
TEST(RmdGimbal, ExtendedAndRemoteFramesWithTheReplyIdentifierAreNotReplies) {
  Bench b;
  b.gimbal->read(0);
  b.motor->serve(0.0);
  ASSERT_TRUE(b.gimbal->read(5 * kMs).has_value());
  b.motor->inject(CAN_EFF_FLAG | 0x241, {0x92, 0, 0, 0, 0x10, 0x27, 0, 0});  // "100.00 deg"
  b.motor->inject(CAN_RTR_FLAG | 0x241, {0x92, 0, 0, 0, 0x10, 0x27, 0, 0});
  const auto state = b.gimbal->read(10 * kMs);
  ASSERT_TRUE(state.has_value());
  EXPECT_NEAR(state->angle_rad, std::numbers::pi / 2.0, 1e-9);
  EXPECT_EQ(state->stamp_ns, 5 * kMs);  // still the motor's reply to the first request
  const DeviceHealth h = b.gimbal->health(10 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kDegraded);
  EXPECT_EQ(h.error_count, 2U);
  EXPECT_EQ(h.detail, "pair0 motor 1: 2 problems, the first: rmd: frame 0x80000241 is not a reply from motor 1");
}

TEST(CanSocket, OpeningAnInterfaceThatIsNotThereNamesIt) {
  const auto socket = CanSocket::open("nosuchcan7");
  ASSERT_FALSE(socket);
  EXPECT_EQ(socket.error().message.rfind("nosuchcan7: ", 0), 0U) << socket.error().message;
}

}  // namespace
}  // namespace aerotrack::hal::real
