// The RMD-X gimbal driver over real SocketCAN (issue 11 item 3): CanSocket::open("vcan0") and the
// RmdGimbal driver against the simulated motor of tests/support/rmd_motor_sim.hpp on a second raw
// socket on vcan0 (a raw socket does not receive its own frames; the other sockets on the interface
// do). Rate and angle commands move the motor and its angle reads back; a silent motor fails the
// health after the reply timeout; stray and garbage frames, extended and remote frames are counted;
// a bus-off error frame fails it; the interface going down fails it; a missing interface is one
// line naming it.
//
// Needs vcan0 up, so it is not a ctest test: scripts/vcan_test.sh boots a kernel with CAN in QEMU and
// runs it there (the build machines' kernels have no CAN). Each test opens its own sockets, so frames
// of one test never reach the next.
#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <numbers>
#include <string>

#include "aerotrack/hal/real/rmd_gimbal.hpp"
#include "support/rmd_motor_sim.hpp"

namespace aerotrack::hal::real {
namespace {

constexpr rt::TimeNs kMs = rt::kNsPerMillisecond;
constexpr char kInterface[] = "vcan0";
constexpr int kWaitMs = 1000;  // bounds a wait for a frame; vcan delivers within the write

/// A raw socket on vcan0, as another node on the bus; -1 if that fails (the failure is reported).
int openNode(bool error_frames) {
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    ADD_FAILURE() << "socket(PF_CAN): " << std::strerror(errno);
    return -1;
  }
  if (error_frames) {
    const can_err_mask_t errors = CAN_ERR_MASK;
    EXPECT_EQ(::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof(errors)), 0);
  }
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = static_cast<int>(::if_nametoindex(kInterface));
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API
  if (address.can_ifindex == 0 || ::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) {
    ADD_FAILURE() << kInterface << ": cannot bind: " << std::strerror(errno);
    ::close(fd);
    return -1;
  }
  return fd;
}

/// `ip link set vcan0 up|down`, through the interface-flags ioctl.
bool setInterfaceUp(bool up) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  ifreq request{};
  std::strncpy(request.ifr_name, kInterface, IFNAMSIZ - 1);
  bool done = ::ioctl(fd, SIOCGIFFLAGS, &request) == 0;
  if (done) {
    request.ifr_flags = static_cast<short>(up ? (request.ifr_flags | IFF_UP) : (request.ifr_flags & ~IFF_UP));
    done = ::ioctl(fd, SIOCSIFFLAGS, &request) == 0;
  }
  ::close(fd);
  return done;
}

std::int32_t i32At(const can_frame& f, int at) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | f.data[at + i];
  return static_cast<std::int32_t>(v);
}

/// The driver on one socket of vcan0, the motor (id 1, at 90 degrees) on another.
struct VcanBench {
  VcanBench() {
    auto socket = CanSocket::open(kInterface);
    if (!socket) {
      ADD_FAILURE() << socket.error().message;
      return;
    }
    gimbal = std::make_unique<RmdGimbal>(std::move(*socket), RmdGimbalParams{});
    if (const int fd = openNode(false); fd >= 0) motor = std::make_unique<test::RmdMotorSim>(fd);
  }
  bool ready() const { return gimbal && motor; }
  /// One control step: the driver reads at now_ns (and asks for the angle), the motor moves dt_s and answers.
  std::optional<GimbalState> step(rt::TimeNs now_ns, double dt_s) {
    auto state = gimbal->read(now_ns);
    EXPECT_TRUE(motor->awaitRequests(1, kWaitMs));
    motor->serve(dt_s);
    return state;
  }
  std::unique_ptr<RmdGimbal> gimbal;
  std::unique_ptr<test::RmdMotorSim> motor;
};

TEST(RmdGimbalOnVcan, RateAndAngleCommandsMoveTheMotorAndItsAngleReadsBack) {
  VcanBench b;
  ASSERT_TRUE(b.ready());
  EXPECT_FALSE(b.gimbal->read(0).has_value());
  ASSERT_TRUE(b.motor->awaitRequests(2, kWaitMs));
  b.motor->serve(0.0);
  EXPECT_EQ(b.motor->received()[0].can_id, 0x141U);
  EXPECT_EQ(b.motor->received()[0].data[0], 0xB3);  // the watchdog first
  EXPECT_EQ(b.motor->received()[1].data[0], 0x92);
  const auto first = b.gimbal->read(5 * kMs);
  ASSERT_TRUE(first.has_value());
  EXPECT_NEAR(first->angle_rad, std::numbers::pi / 2.0, 1e-9);
  const DeviceHealth ok = b.gimbal->health(5 * kMs);
  EXPECT_EQ(ok.state, DeviceHealth::State::kOk);
  EXPECT_EQ(ok.detail, "vcan0 motor 1");

  // Given 1 rad/s (5730 counts of 0.01 deg/s) for 20 steps of 5 ms, the shaft turns 5.73 degrees.
  GimbalCommand rate;
  rate.mode = GimbalCommand::Mode::kRate;
  rate.rate_radps = 1.0;
  b.gimbal->command(rate);
  ASSERT_TRUE(b.motor->awaitRequests(2, kWaitMs));  // the angle request of read(5 ms), then the speed
  b.motor->serve(0.0);
  EXPECT_EQ(b.motor->received().back().data[0], 0xA2);
  EXPECT_EQ(i32At(b.motor->received().back(), 4), 5730);
  for (int i = 1; i <= 20; ++i) b.step((5 + 5 * i) * kMs, 0.005);
  const auto turned = b.gimbal->read(110 * kMs);
  ASSERT_TRUE(turned.has_value());
  EXPECT_NEAR(turned->angle_rad, 95.73 * std::numbers::pi / 180.0, 1e-9);
  EXPECT_NEAR(turned->rate_radps, 57.0 * std::numbers::pi / 180.0, 1e-9);  // the feedback's whole deg/s
  EXPECT_EQ(turned->stamp_ns, 110 * kMs);

  // Then an angle command to -90 degrees at the default limit (6 rad/s: 344 deg/s, 1.72 deg a step).
  GimbalCommand angle;
  angle.mode = GimbalCommand::Mode::kAngle;
  angle.angle_rad = -std::numbers::pi / 2.0;
  b.gimbal->command(angle);
  ASSERT_TRUE(b.motor->awaitRequests(2, kWaitMs));
  b.motor->serve(0.0);
  const can_frame& position = b.motor->received().back();
  EXPECT_EQ(position.data[0], 0xA4);
  EXPECT_EQ(position.data[2] | (position.data[3] << 8), 344);
  EXPECT_EQ(i32At(position, 4), -9000);
  rt::TimeNs now_ns = 110 * kMs;
  for (int i = 0; i < 50; ++i) b.step(now_ns += 5 * kMs, 0.005);
  const auto moving = b.step(now_ns += 5 * kMs, 0.005);  // reads what 50 steps made of it
  ASSERT_TRUE(moving.has_value());
  EXPECT_NEAR(moving->angle_rad, (95.73 - 50 * 1.72) * std::numbers::pi / 180.0, 1e-9);
  for (int i = 0; i < 60; ++i) b.step(now_ns += 5 * kMs, 0.005);  // 111 steps in all; 108 reach -90
  const auto there = b.gimbal->read(now_ns += 5 * kMs);
  ASSERT_TRUE(there.has_value());
  EXPECT_NEAR(there->angle_rad, -std::numbers::pi / 2.0, 1e-9);
  EXPECT_EQ(b.gimbal->health(now_ns).state, DeviceHealth::State::kOk);
}

TEST(RmdGimbalOnVcan, ASilentMotorFailsAfterTheReplyTimeout) {
  VcanBench b;
  ASSERT_TRUE(b.ready());
  b.motor->setSilent(true);
  b.gimbal->read(0);
  ASSERT_TRUE(b.motor->awaitRequests(2, kWaitMs));  // the requests are on the bus; nobody answers
  b.motor->serve(0.0);
  EXPECT_FALSE(b.gimbal->read(50 * kMs).has_value());
  EXPECT_EQ(b.gimbal->health(50 * kMs).state, DeviceHealth::State::kOk);
  const DeviceHealth h = b.gimbal->health(150 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kFailed);
  EXPECT_EQ(h.detail, "vcan0 motor 1: no reply for 150 ms");
}

TEST(RmdGimbalOnVcan, StrayAndGarbageFramesAreCountedAndIgnored) {
  VcanBench b;
  ASSERT_TRUE(b.ready());
  b.gimbal->read(0);
  ASSERT_TRUE(b.motor->awaitRequests(2, kWaitMs));
  b.motor->serve(0.0);
  b.motor->inject(0x242, {0x92, 0, 0, 0, 0, 0, 0, 0});  // another motor's reply
  b.motor->inject(0x241, {0x3F, 1, 2, 3, 4, 5, 6, 7});  // an unknown command
  b.motor->inject(0x241, {0x92, 0});                    // too short
  const auto state = b.gimbal->read(5 * kMs);
  ASSERT_TRUE(state.has_value());
  EXPECT_NEAR(state->angle_rad, std::numbers::pi / 2.0, 1e-9);  // the good reply still counts
  const DeviceHealth h = b.gimbal->health(5 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kDegraded);
  EXPECT_EQ(h.error_count, 3U);
  EXPECT_EQ(h.detail, "vcan0 motor 1: 3 problems, the first: rmd: frame 0x242 is not a reply from motor 1");
}

// Over the real stack too: the motor uses standard identifiers only, so an extended frame with the
// 29-bit identifier 0x241 is another node's, and a remote frame carries no reading.
TEST(RmdGimbalOnVcan, ExtendedAndRemoteFramesWithTheReplyIdentifierAreNotReplies) {
  VcanBench b;
  ASSERT_TRUE(b.ready());
  b.gimbal->read(0);
  ASSERT_TRUE(b.motor->awaitRequests(2, kWaitMs));
  b.motor->serve(0.0);
  ASSERT_TRUE(b.gimbal->read(5 * kMs).has_value());
  b.motor->inject(CAN_EFF_FLAG | 0x241, {0x92, 0, 0, 0, 0x10, 0x27, 0, 0});  // "100.00 deg"
  b.motor->inject(CAN_RTR_FLAG | 0x241, {0x92, 0, 0, 0, 0x10, 0x27, 0, 0});
  const auto state = b.gimbal->read(10 * kMs);
  ASSERT_TRUE(state.has_value());
  EXPECT_NEAR(state->angle_rad, std::numbers::pi / 2.0, 1e-9);
  EXPECT_EQ(state->stamp_ns, 5 * kMs);
  const DeviceHealth h = b.gimbal->health(10 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kDegraded);
  EXPECT_EQ(h.error_count, 2U);
  EXPECT_EQ(h.detail, "vcan0 motor 1: 2 problems, the first: rmd: frame 0x80000241 is not a reply from motor 1");
}

// An error frame written by a raw socket on vcan0 (Linux 6.1 lets a raw socket send a frame with
// CAN_ERR_FLAG set) is delivered to the sockets whose error mask matches its class bits -- the
// driver's, which takes every class -- as a controller's would be; a socket without the error
// mask, like the motor's, never sees it.
TEST(RmdGimbalOnVcan, ABusOffErrorFrameOnTheBusFailsTheHealth) {
  VcanBench b;
  ASSERT_TRUE(b.ready());
  const int reporter = openNode(false);
  ASSERT_GE(reporter, 0);
  b.gimbal->read(0);
  ASSERT_TRUE(b.motor->awaitRequests(2, kWaitMs));
  b.motor->serve(0.0);
  can_frame bus_off{};
  bus_off.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  bus_off.can_dlc = CAN_ERR_DLC;
  EXPECT_EQ(::write(reporter, &bus_off, sizeof(bus_off)), static_cast<ssize_t>(sizeof(bus_off)))
      << std::strerror(errno);
  ::close(reporter);
  b.gimbal->read(5 * kMs);
  const DeviceHealth h = b.gimbal->health(5 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kFailed);
  EXPECT_EQ(h.detail, "vcan0: bus-off");
  ASSERT_TRUE(b.motor->awaitRequests(1, kWaitMs));  // the motor has read what the bus carried since
  EXPECT_TRUE(b.motor->others().empty());           // no error mask: no error frames
}

// `ip link set vcan0 down` under a running driver: the kernel reports ENETDOWN on the bound socket
// (its next receive fails) and refuses sends, so the health fails at once, naming the interface.
TEST(RmdGimbalOnVcan, TheInterfaceGoingDownFailsTheHealth) {
  VcanBench b;
  ASSERT_TRUE(b.ready());
  b.gimbal->read(0);
  ASSERT_TRUE(b.motor->awaitRequests(2, kWaitMs));
  b.motor->serve(0.0);
  ASSERT_TRUE(b.gimbal->read(5 * kMs).has_value());
  ASSERT_TRUE(setInterfaceUp(false));
  b.gimbal->read(10 * kMs);
  const bool restored = setInterfaceUp(true);  // before any assertion can end the test
  const DeviceHealth h = b.gimbal->health(10 * kMs);
  EXPECT_EQ(h.state, DeviceHealth::State::kFailed);
  EXPECT_EQ(h.detail, "vcan0: CAN receive failed: Network is down");
  EXPECT_EQ(h.error_count, 2U) << "the receive error and the refused angle request";
  EXPECT_TRUE(restored);
}

TEST(CanSocketOnVcan, OpeningAnInterfaceThatIsNotThereNamesIt) {
  const auto socket = CanSocket::open("nosuchcan7");
  ASSERT_FALSE(socket);
  EXPECT_EQ(socket.error().message, "nosuchcan7: no such CAN interface");
}

}  // namespace
}  // namespace aerotrack::hal::real
