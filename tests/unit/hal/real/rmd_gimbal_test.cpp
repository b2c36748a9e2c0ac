// The RMD-X gimbal driver (hal/real/rmd_gimbal.hpp) against a simulated motor on the other end of a
// socketpair carrying Linux's struct can_frame, as a SocketCAN socket does: the watchdog is armed
// first, rate and angle commands become the protocol's frames, the multi-turn angle comes back in
// radians; a silent motor, stray and garbage frames, and a bus-off error frame show in the health.
// Opening a CAN interface that does not exist is a one-line error naming it.
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

namespace aerotrack::hal::real {
namespace {

constexpr rt::TimeNs kMs = rt::kNsPerMillisecond;

/// A motor with id 1 at the far end: answers every request the way protocol V4.2 says.
class FakeMotor {
 public:
  explicit FakeMotor(int fd) : fd_(fd) {}
  ~FakeMotor() { ::close(fd_); }
  FakeMotor(const FakeMotor&) = delete;
  FakeMotor& operator=(const FakeMotor&) = delete;

  /// Moves for dt_s at the commanded speed, then answers what arrived.
  void serve(double dt_s) {
    angle_cdeg_ += speed_cdps_ * dt_s;
    can_frame in{};
    while (::read(fd_, &in, sizeof(in)) == static_cast<ssize_t>(sizeof(in))) {
      received_.push_back(in);
      if (silent_) continue;
      can_frame out{};
      out.can_id = 0x241;
      out.can_dlc = 8;
      out.data[0] = in.data[0];
      std::int32_t value = 0;
      std::memcpy(&value, in.data + 4, 4);  // little-endian host, as the motor
      if (in.data[0] == 0xA2) {
        speed_cdps_ = value;
        const auto dps = static_cast<std::int16_t>(std::lround(speed_cdps_ / 100.0));
        std::memcpy(out.data + 4, &dps, 2);
      } else if (in.data[0] == 0x92) {
        const auto cdeg = static_cast<std::int32_t>(std::lround(angle_cdeg_));
        std::memcpy(out.data + 4, &cdeg, 4);
      }
      ASSERT_EQ(::write(fd_, &out, sizeof(out)), static_cast<ssize_t>(sizeof(out)));
    }
  }
  void inject(canid_t id, std::initializer_list<int> bytes) {
    can_frame f{};
    f.can_id = id;
    f.can_dlc = static_cast<std::uint8_t>(bytes.size());
    std::size_t i = 0;
    for (const int b : bytes) f.data[i++] = static_cast<std::uint8_t>(b);
    ASSERT_EQ(::write(fd_, &f, sizeof(f)), static_cast<ssize_t>(sizeof(f)));
  }
  const std::vector<can_frame>& received() const { return received_; }
  void setSilent(bool silent) { silent_ = silent; }

 private:
  int fd_;
  double angle_cdeg_ = 9000.0;  // starts at 90 degrees
  double speed_cdps_ = 0.0;
  bool silent_ = false;
  std::vector<can_frame> received_;
};

struct Bench {
  Bench() {
    int fds[2];
    EXPECT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK, 0, fds), 0);
    gimbal = std::make_unique<RmdGimbal>(CanSocket::adopt(fds[0], "pair0"), RmdGimbalParams{});
    motor = std::make_unique<FakeMotor>(fds[1]);
  }
  std::unique_ptr<RmdGimbal> gimbal;
  std::unique_ptr<FakeMotor> motor;
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

TEST(CanSocket, OpeningAnInterfaceThatIsNotThereNamesIt) {
  const auto socket = CanSocket::open("nosuchcan7");
  ASSERT_FALSE(socket);
  EXPECT_EQ(socket.error().message.rfind("nosuchcan7: ", 0), 0U) << socket.error().message;
}

}  // namespace
}  // namespace aerotrack::hal::real
