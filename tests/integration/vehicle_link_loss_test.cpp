// The flight controller's link lost in flight (issue 11 item 4): the app's real MAVLink devices, built
// from config by the factory, with the odometry, trajectory-server and supervisor tasks on the real-time
// executor, against the fake PX4 (tests/support/fake_autopilot.hpp) on loopback UDP. The fake hovers at
// 1.5 m, so the supervisor leaves take-off for search; then it falls silent, and the vehicle link's
// health fails and the supervisor holds, with the link's loss as the reason.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "aerotrack/rt/realtime_executor.hpp"
#include "app_config.hpp"
#include "support/fake_autopilot.hpp"
#include "system.hpp"

namespace aerotrack::app {
namespace {

/// A UDP port free on loopback now (the kernel's choice, released for the driver to bind).
std::uint16_t freeUdpPort() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof(a);
  EXPECT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof(a)), 0);
  EXPECT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &length), 0);
  ::close(fd);
  return ntohs(a.sin_port);
}

std::string configFor(std::uint16_t port) {
  return R"(
vehicle: {radius_m: 0.25, max_speed_mps: 3.0, max_accel_mps2: 4.0}
hal:
  gimbal_camera: null
  depth_camera: null
  gimbal: null
  odometry: real
  vehicle_link: real
  real:
    flight_controller:
      url: udp://127.0.0.1:)" +
         std::to_string(port) + R"(
      system_id: 1
      component_id: 191
      target_system: 1
      target_component: 1
      heartbeat_period_s: 0.2
      setpoint_period_s: 0.02
      setpoint_stale_s: 0.5
      link_timeout_s: 0.5
      odometry_timeout_s: 0.2
trajectory_server: {yaw_min_speed_mps: 0.3, max_late_takeover_s: 0.1}
supervisor:
  takeoff_altitude_m: 1.5
  takeoff_tolerance_m: 0.3
  relocate_after_s: 0.4
  relocate_timeout_s: 5.0
  search_timeout_s: 20.0
  hold_then_land_s: 0.0
  odometry_timeout_s: 2.0   # longer than the link's timeout: the link's loss is seen first
  depth_timeout_s: 1.0
  camera_timeout_s: 1.0
  gimbal_timeout_s: 0.5
  max_planner_failures: 20
  overrun_storm: 50
  overrun_window_s: 1.0
  startup_grace_s: 60.0     # no cameras in this test: their silence is tolerated
realtime: {realtime_priority: false, affinity: false, lock_memory: false}
tasks:
  - {name: odometry,          rate_hz: 100, budget_ms: 1.0, priority: 0, cpu: -1}
  - {name: trajectory_server, rate_hz: 100, budget_ms: 1.0, priority: 0, cpu: -1}
  - {name: supervisor,        rate_hz: 50,  budget_ms: 1.0, priority: 0, cpu: -1}
)";
}

TEST(VehicleLinkLoss, TheSupervisorHoldsWhenTheAutopilotFallsSilent) {
  const std::uint16_t port = freeUdpPort();
  auto config = parseAppConfig(configFor(port), "link_loss.yaml");
  ASSERT_TRUE(config) << config.error().message;
  const rt::MonotonicClock clock;
  auto system = System::build(*config, nullptr, clock.now());
  ASSERT_TRUE(system) << system.error().message;
  hal::real::testing::FakeAutopilotParams fake;
  fake.heartbeat_period_s = 0.1;  // a link timeout of 0.5 s needs heartbeats more often than PX4's 1 Hz
  hal::real::testing::FakeAutopilot autopilot(port, fake);
  autopilot.truth.p_N_m = {2.0, 1.0, -1.5};  // hovering 1.5 m up: take-off is done

  rt::RealtimeExecutor executor(clock, (*system)->realtimeOptions());
  for (const rt::TaskBinding& b : (*system)->bindings()) ASSERT_TRUE(executor.add(b));
  ASSERT_TRUE(executor.start());
  const auto mode = [&] { return (*system)->channels().supervisor.read(); };
  // Runs the fake at 500 Hz until done() or timeout_s; the time it took.
  const auto runUntil = [&](auto done, double timeout_s) {
    const rt::TimeNs begin_ns = clock.now();
    while (!done() && clock.now() - begin_ns < rt::secondsToNs(timeout_s)) {
      autopilot.step(clock.now());
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return rt::nsToSeconds(clock.now() - begin_ns);
  };

  runUntil([&] { return mode() && mode()->mode == supervisor::Mode::kSearch; }, 10.0);
  ASSERT_TRUE(mode());
  EXPECT_EQ(mode()->mode, supervisor::Mode::kSearch) << supervisor::toString(mode()->reason);
  const hal::DeviceHealth up = (*system)->devices().vehicle_link->health(clock.now());
  EXPECT_EQ(up.state, hal::DeviceHealth::State::kOk) << up.detail;
  const auto odometry = (*system)->channels().odometry.read();
  ASSERT_TRUE(odometry);
  EXPECT_NEAR(odometry->p_WB_m.x(), 1.0, 1e-6);  // NED north 2, east 1, down -1.5 -> ENU (1, 2, 1.5)
  EXPECT_NEAR(odometry->p_WB_m.y(), 2.0, 1e-6);
  EXPECT_NEAR(odometry->p_WB_m.z(), 1.5, 1e-6);

  autopilot.setSilent(true);
  const double to_hold_s = runUntil([&] { return mode()->mode == supervisor::Mode::kHold; }, 10.0);
  executor.requestStop();
  executor.join();
  EXPECT_EQ(mode()->mode, supervisor::Mode::kHold);
  EXPECT_EQ(mode()->reason, supervisor::Reason::kVehicleLinkLost) << supervisor::toString(mode()->reason);
  // The link's timeout (0.5 s) plus a trajectory-server and a supervisor period, with slack for a
  // loaded machine: well before the odometry's 2 s.
  EXPECT_GE(to_hold_s, 0.4);
  EXPECT_LT(to_hold_s, 1.9);
  const hal::DeviceHealth lost = (*system)->devices().vehicle_link->health(clock.now());
  EXPECT_EQ(lost.state, hal::DeviceHealth::State::kFailed);
  EXPECT_NE(lost.detail.find("heartbeat"), std::string::npos) << lost.detail;
}

}  // namespace
}  // namespace aerotrack::app
