// The MAVLink flight-controller driver (hal/real/mavlink_vehicle.hpp, issue 11 item 4): the NED/FRD <->
// ENU/FLU conversions against explicit rotation matrices and worked cases; mode decoding for PX4 and
// ArduPilot; and the driver against a PX4-like fake autopilot (tests/support/fake_autopilot.hpp) on
// loopback UDP, stepped in fake time at 100 Hz: heartbeat at 1 Hz, setpoint stream >= 20 Hz and in
// NED on the wire, odometry back in ENU equal to the fake's truth, offboard accepted after streaming,
// HOLD when the stream stops, link loss and recovery, malformed datagrams counted and ignored, samples
// stamped with the autopilot's time mapped onto ours (RemoteClock), no allocation in steady state,
// and one-line open errors naming the URL.
#include "aerotrack/hal/real/mavlink_vehicle.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <new>
#include <numbers>
#include <random>

#include "aerotrack/hal/real/ned_enu.hpp"
#include "support/fake_autopilot.hpp"
#include "support/require.hpp"

// Counts the allocations made while a test says so (this thread only): the driver must make none in
// steady state.
namespace {
thread_local bool counting_allocations = false;
thread_local long allocations = 0;
}  // namespace

[[gnu::noinline]] void* operator new(std::size_t size) {
  if (counting_allocations) ++allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
// Not inlined: GCC 12 would then see free() meet operator new's result and warn (a false positive).
[[gnu::noinline]] void operator delete(void* p) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete(void* p, std::size_t /*size*/) noexcept {
  std::free(p);
}

namespace aerotrack::hal::real {
namespace {

using testing::FakeAutopilot;
using testing::FakeAutopilotParams;
using testing::Garbage;
constexpr rt::TimeNs kTick = 10 * rt::kNsPerMillisecond;  // the odometry task's 100 Hz
constexpr double kPi = std::numbers::pi;

// ---- Frame conversions ---------------------------------------------------------------------------

TEST(NedEnu, VectorsMatchTheRotationMatrixAndAWorkedCase) {
  // R_WN written out: ENU x (east) = NED y, ENU y (north) = NED x, ENU z (up) = -NED z.
  Eigen::Matrix3d r_WN;
  r_WN << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  EXPECT_TRUE(ned_enu::rotationEnuNed().isApprox(r_WN));
  EXPECT_NEAR(r_WN.determinant(), 1.0, 1e-12);  // a rotation, not a reflection
  // 1 m north, 2 m east, 3 m down is 2 m east, 1 m north, 3 m below: ENU (2, 1, -3).
  EXPECT_TRUE(ned_enu::nedToEnu({1, 2, 3}).isApprox(Eigen::Vector3d(2, 1, -3)));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-10, 10);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d v(u(rng), u(rng), u(rng));
    EXPECT_TRUE(ned_enu::nedToEnu(v).isApprox(r_WN * v));
    EXPECT_TRUE(ned_enu::enuToNed(ned_enu::nedToEnu(v)).isApprox(v));
    // FRD -> FLU: y right becomes y left, z down becomes z up.
    EXPECT_TRUE(ned_enu::frdToFlu(v).isApprox(Eigen::Vector3d(v.x(), -v.y(), -v.z())));
    EXPECT_TRUE(ned_enu::fluToFrd(ned_enu::frdToFlu(v)).isApprox(v));
  }
}

TEST(NedEnu, AttitudeFacingNorthEastAndPitchedUp) {
  const auto body_x_in_W = [](const Eigen::Quaterniond& q_NF) {
    return Eigen::Vector3d(ned_enu::nedFrdToEnuFlu(q_NF) * Eigen::Vector3d::UnitX());
  };
  const auto body_y_in_W = [](const Eigen::Quaterniond& q_NF) {
    return Eigen::Vector3d(ned_enu::nedFrdToEnuFlu(q_NF) * Eigen::Vector3d::UnitY());
  };
  // Level, facing north (NED yaw 0): forward is ENU +y, left is west (ENU -x).
  const Eigen::Quaterniond north = ned_enu::eulerNedToQuaternion(0, 0, 0);
  EXPECT_TRUE(body_x_in_W(north).isApprox(Eigen::Vector3d(0, 1, 0), 1e-12));
  EXPECT_TRUE(body_y_in_W(north).isApprox(Eigen::Vector3d(-1, 0, 0), 1e-12));
  // Facing east (NED yaw +90 deg): q_WB is the identity.
  const Eigen::Quaterniond east = ned_enu::eulerNedToQuaternion(0, 0, kPi / 2);
  EXPECT_TRUE(ned_enu::nedFrdToEnuFlu(east).toRotationMatrix().isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  // Facing north, nose up 10 deg (positive pitch in FRD): forward is north and up.
  const double pitch = 10.0 * kPi / 180.0;
  const Eigen::Quaterniond up = ned_enu::eulerNedToQuaternion(0, pitch, 0);
  EXPECT_TRUE(body_x_in_W(up).isApprox(Eigen::Vector3d(0, std::cos(pitch), std::sin(pitch)), 1e-12));
  // Rolled right 20 deg facing east: the left wing (FLU +y) rises: ENU (0, cos, sin).
  const double roll = 20.0 * kPi / 180.0;
  const Eigen::Quaterniond rolled = ned_enu::eulerNedToQuaternion(roll, 0, kPi / 2);
  EXPECT_TRUE(body_y_in_W(rolled).isApprox(Eigen::Vector3d(0, std::cos(roll), std::sin(roll)), 1e-12));
  // Against the matrices, for random attitudes, and back.
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-kPi, kPi);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Quaterniond q_NF = ned_enu::eulerNedToQuaternion(u(rng) / 2, u(rng) / 2, u(rng));
    const Eigen::Matrix3d expected = ned_enu::rotationEnuNed() * q_NF.toRotationMatrix() * ned_enu::rotationFrdFlu();
    EXPECT_TRUE(ned_enu::nedFrdToEnuFlu(q_NF).toRotationMatrix().isApprox(expected, 1e-12));
    EXPECT_TRUE(ned_enu::enuFluToNedFrd(ned_enu::nedFrdToEnuFlu(q_NF))
                    .toRotationMatrix()
                    .isApprox(q_NF.toRotationMatrix(), 1e-12));
  }
}

TEST(NedEnu, YawFromNorthClockwiseIsNinetyDegreesMinusYawFromEast) {
  EXPECT_NEAR(ned_enu::yawEnuToNed(0.0), kPi / 2, 1e-12);   // facing east
  EXPECT_NEAR(ned_enu::yawEnuToNed(kPi / 2), 0.0, 1e-12);   // facing north
  EXPECT_NEAR(ned_enu::yawEnuToNed(kPi), -kPi / 2, 1e-12);  // facing west
  EXPECT_NEAR(ned_enu::yawEnuToNed(-kPi / 2), kPi, 1e-12);  // facing south: wrapped to +pi
  EXPECT_NEAR(ned_enu::yawNedToEnu(ned_enu::yawEnuToNed(2.5)), 2.5, 1e-12);
  EXPECT_NEAR(ned_enu::yawEnuToNed(7.0), ned_enu::wrapPi(kPi / 2 - 7.0), 1e-12);
  // And the yaw agrees with the attitude conversion: NED yaw y, level, is ENU heading pi/2 - y.
  for (const double yaw_ned : {-2.0, -0.3, 0.0, 1.0, 3.0}) {
    const Eigen::Vector3d x_W =
        ned_enu::nedFrdToEnuFlu(ned_enu::eulerNedToQuaternion(0, 0, yaw_ned)) * Eigen::Vector3d::UnitX();
    EXPECT_NEAR(std::atan2(x_W.y(), x_W.x()), ned_enu::yawNedToEnu(yaw_ned), 1e-12);
  }
}

// ---- Modes and parameters ------------------------------------------------------------------------

protocol::mavlink::Heartbeat heartbeat(std::uint8_t autopilot, std::uint32_t custom_mode, std::uint8_t base_mode) {
  protocol::mavlink::Heartbeat hb;
  hb.autopilot = autopilot;
  hb.custom_mode = custom_mode;
  hb.base_mode = base_mode;
  return hb;
}

TEST(MavlinkModes, Px4AndArduCopterModesAndArmedDecode) {
  const auto px4 = [](unsigned main, unsigned sub) {
    return decodeFlightMode(heartbeat(12, (main << 16) | (sub << 24), 0));
  };
  EXPECT_EQ(px4(6, 0), FlightMode::kOffboard);
  EXPECT_EQ(px4(4, 3), FlightMode::kHold);     // AUTO.LOITER
  EXPECT_EQ(px4(4, 6), FlightMode::kLand);     // AUTO.LAND
  EXPECT_EQ(px4(4, 5), FlightMode::kLand);     // AUTO.RTL
  EXPECT_EQ(px4(4, 4), FlightMode::kUnknown);  // AUTO.MISSION: not ours, not a hold
  EXPECT_EQ(px4(1, 0), FlightMode::kManual);
  EXPECT_EQ(px4(2, 0), FlightMode::kManual);
  EXPECT_EQ(px4(3, 0), FlightMode::kManual);
  const auto copter = [](std::uint32_t mode) { return decodeFlightMode(heartbeat(3, mode, 0)); };
  EXPECT_EQ(copter(4), FlightMode::kOffboard);                            // GUIDED
  EXPECT_EQ(copter(5), FlightMode::kHold);                                // LOITER
  EXPECT_EQ(copter(16), FlightMode::kHold);                               // POSHOLD
  EXPECT_EQ(copter(17), FlightMode::kHold);                               // BRAKE
  EXPECT_EQ(copter(9), FlightMode::kLand);                                // LAND
  EXPECT_EQ(copter(6), FlightMode::kLand);                                // RTL
  EXPECT_EQ(copter(0), FlightMode::kManual);                              // STABILIZE
  EXPECT_EQ(copter(2), FlightMode::kManual);                              // ALT_HOLD
  EXPECT_EQ(decodeFlightMode(heartbeat(8, 4, 0)), FlightMode::kUnknown);  // not an autopilot
  EXPECT_TRUE(decodeArmed(heartbeat(12, 0, 128 | 1)));
  EXPECT_FALSE(decodeArmed(heartbeat(12, 0, 64 | 1)));
}

TEST(MavlinkParamsTest, ValidateNamesTheBadField) {
  EXPECT_TRUE(validate(MavlinkParams{}).has_value());
  MavlinkParams slow;
  slow.setpoint_period_s = 0.1;  // 10 Hz: below PX4's need and the 20 Hz
  ASSERT_FALSE(validate(slow).has_value());
  EXPECT_NE(validate(slow).error().message.find("setpoint_period_s"), std::string::npos);
  MavlinkParams same;
  same.component_id = 1;  // the autopilot's own id
  EXPECT_FALSE(validate(same).has_value());
}

TEST(UdpSocketTest, BadUrlsAndAPortInUseAreOneLineNamingTheUrl) {
  for (const std::string url : {"tcp://1.2.3.4:5", "udp://127.0.0.1", "udp://127.0.0.1:99999", "udpout://:14540"}) {
    const auto s = UdpSocket::open(url);
    ASSERT_FALSE(s.has_value()) << url;
    EXPECT_EQ(s.error().message.rfind(url, 0), 0U) << s.error().message;
    EXPECT_EQ(s.error().message.find('\n'), std::string::npos);
  }
  auto first = UdpSocket::open("udp://127.0.0.1:0");
  ASSERT_TRUE(first.has_value()) << first.error().message;
  const std::string taken = "udp://127.0.0.1:" + std::to_string(first->localPort());
  const auto second = MavlinkConnection::open(MavlinkParams{.url = taken});
  ASSERT_FALSE(second.has_value());
  EXPECT_EQ(second.error().message, taken + ": cannot bind: Address already in use");
}

// ---- The autopilot's clock on ours ----------------------------------------------------------------

TEST(RemoteClockTest, MinimumDelayOffsetGivesSampleTimesWithinTheSmallestDelay) {
  // Given an autopilot that booted 1234.5 s after our epoch, sending every 20 ms, read 1 to 11 ms later
  // (network plus a 100 Hz poll),
  RemoteClock clock;
  std::mt19937 rng(7);
  std::uniform_int_distribution<rt::TimeNs> delay_ns(rt::kNsPerMillisecond, 11 * rt::kNsPerMillisecond);
  const rt::TimeNs boot_ns = 1'234'500'000'000;
  double worst_after_1s_ms = 0.0, sum_after_1s_ms = 0.0, sum_delay_ms = 0.0;
  for (int i = 0; i < 500; ++i) {
    const rt::TimeNs sample_ns = boot_ns + 5 * rt::kNsPerSecond + i * 20 * rt::kNsPerMillisecond;
    const rt::TimeNs arrival_ns = sample_ns + delay_ns(rng);
    const rt::TimeNs stamp_ns = clock.toLocal(static_cast<std::uint64_t>((sample_ns - boot_ns) / 1000), arrival_ns);
    // then a stamp is never later than the arrival, nor earlier than the sample,
    EXPECT_LE(stamp_ns, arrival_ns);
    EXPECT_GE(stamp_ns, sample_ns);
    if (i >= 50) {
      const double error_ms = static_cast<double>(stamp_ns - sample_ns) * 1e-6;
      worst_after_1s_ms = std::max(worst_after_1s_ms, error_ms);
      sum_after_1s_ms += error_ms;
      sum_delay_ms += static_cast<double>(arrival_ns - sample_ns) * 1e-6;
    }
  }
  // and after a second it is late by the smallest delay (1 ms) plus the allowed drift since the last
  // fast message (100 ppm of a second or two: 0.1 to 0.2 ms), where stamping arrivals would be late by
  // the mean delay (6 ms) and up to 11 ms.
  const double mean_error_ms = sum_after_1s_ms / 450.0;
  EXPECT_LT(worst_after_1s_ms, 1.5);
  EXPECT_LT(mean_error_ms, 1.3);
  EXPECT_GT(sum_delay_ms / 450.0, 5.0);
  RecordProperty("remote_clock_worst_error_ms", std::to_string(worst_after_1s_ms));
  RecordProperty("remote_clock_mean_error_ms", std::to_string(mean_error_ms));
}

TEST(RemoteClockTest, FollowsADriftingClockAndStartsAgainAfterAReboot) {
  RemoteClock clock;
  // The autopilot's crystal runs 40 ppm slow: its microseconds are 1.00004 of ours.
  const auto remote_us = [](rt::TimeNs local_ns) {
    return static_cast<std::uint64_t>(static_cast<double>(local_ns - 7 * rt::kNsPerSecond) / 1000.0 / 1.00004);
  };
  double worst_ms = 0.0;
  rt::TimeNs t_ns = 10 * rt::kNsPerSecond;
  for (int i = 0; i < 6000; ++i, t_ns += 20 * rt::kNsPerMillisecond) {  // two minutes: 4.8 ms of drift
    const rt::TimeNs delay_ns = (i % 5 + 1) * rt::kNsPerMillisecond;
    const rt::TimeNs stamp_ns = clock.toLocal(remote_us(t_ns), t_ns + delay_ns);
    if (i > 100) worst_ms = std::max(worst_ms, std::abs(static_cast<double>(stamp_ns - t_ns)) * 1e-6);
  }
  EXPECT_LT(worst_ms, 1.5);
  // A reboot: the autopilot's time restarts near zero; the first message after it is mapped with its
  // own delay (3 ms here), not 2 minutes off.
  const rt::TimeNs stamp_ns = clock.toLocal(250'000, t_ns + 3 * rt::kNsPerMillisecond);
  EXPECT_EQ(stamp_ns, t_ns + 3 * rt::kNsPerMillisecond);
  // The next, 10 ms later on the autopilot's clock and read 5 ms after that, keeps the 3 ms offset, plus
  // the drift allowed over the 12 ms between the two reads (100 ppm: 1.2 us).
  EXPECT_EQ(clock.toLocal(260'000, t_ns + 15 * rt::kNsPerMillisecond), t_ns + 13 * rt::kNsPerMillisecond + 1'200);
  // No time in the message: the arrival.
  EXPECT_EQ(clock.toLocal(0, 42), 42);
}

// ---- The driver against the fake autopilot -------------------------------------------------------

/// The driver listening on an ephemeral loopback port, the two devices on it, and the fake autopilot.
struct Bench {
  explicit Bench(const FakeAutopilotParams& fake_params = {}, MavlinkParams params = {}) {
    params.url = "udp://127.0.0.1:0";
    connection = aerotrack::test::require(MavlinkConnection::open(params), "MavlinkConnection::open");
    odometry = std::make_unique<MavlinkOdometry>(connection);
    link = std::make_unique<MavlinkVehicleLink>(connection);
    fake = std::make_unique<FakeAutopilot>(connection->localPort(), fake_params);
  }
  /// One 100 Hz tick: the fake steps, then the odometry task reads; every send_every-th tick (0: none)
  /// the trajectory server sends `setpoint` stamped now and reads the status.
  void tick(int send_every = 0) {
    fake->step(now_ns);
    odometry->read(now_ns);
    if (send_every > 0 && tick_count % send_every == 0) {
      Setpoint sp = setpoint;
      sp.stamp_ns = now_ns;
      link->send(sp);
      status = link->status(now_ns);
    }
    ++tick_count;
    now_ns += kTick;
  }
  void run(double seconds, int send_every = 0) {
    const auto ticks = static_cast<int>(std::lround(seconds / 0.01));
    for (int i = 0; i < ticks; ++i) tick(send_every);
  }

  std::shared_ptr<MavlinkConnection> connection;
  std::unique_ptr<MavlinkOdometry> odometry;
  std::unique_ptr<MavlinkVehicleLink> link;
  std::unique_ptr<FakeAutopilot> fake;
  Setpoint setpoint;
  VehicleStatus status;
  rt::TimeNs now_ns = 1'000 * rt::kNsPerSecond;  // not zero: nothing may assume the clock starts at 0
  long tick_count = 0;
};

double rateHz(const std::vector<rt::TimeNs>& times) {
  if (times.size() < 2) return 0.0;
  return static_cast<double>(times.size() - 1) / (static_cast<double>(times.back() - times.front()) * 1e-9);
}

TEST(MavlinkVehicle, HeartbeatsAt1HzAndNoSetpointBeforeThePlannersFirst) {
  Bench b;
  b.run(5.0);  // the odometry task polls; the planner has sent nothing yet
  ASSERT_EQ(b.fake->heartbeat_rx_ns.size(), 5U);
  for (std::size_t i = 1; i < b.fake->heartbeat_rx_ns.size(); ++i)
    EXPECT_EQ(b.fake->heartbeat_rx_ns[i] - b.fake->heartbeat_rx_ns[i - 1], rt::kNsPerSecond);
  const auto& hb = b.fake->heartbeats.front();
  EXPECT_EQ(hb.type, 18);      // MAV_TYPE_ONBOARD_CONTROLLER
  EXPECT_EQ(hb.autopilot, 8);  // MAV_AUTOPILOT_INVALID
  EXPECT_EQ(hb.system_status, 4);
  EXPECT_EQ(b.fake->sender_components.front(), 191);
  EXPECT_TRUE(b.fake->setpoints.empty());  // nothing made up
}

TEST(MavlinkVehicle, SetpointsStreamAt50HzInNedEvenFromASlowCaller) {
  Bench b;
  b.setpoint.p_W_m = {1.0, 2.0, 3.0};  // 1 m east, 2 m north, 3 m up
  b.setpoint.v_W_mps = {0.5, -0.25, 0.125};
  b.setpoint.a_W_mps2 = {-1.0, 0.75, 0.5};
  b.setpoint.yaw_rad = 0.3;
  b.setpoint.yaw_rate_radps = 0.2;
  b.run(2.0, 1);  // the trajectory server at 100 Hz: the wire is capped at 1 / setpoint_period_s
  const double full_hz = rateHz(b.fake->setpoint_rx_ns);
  EXPECT_NEAR(full_hz, 50.0, 0.5);
  b.fake->setpoint_rx_ns.clear();
  b.run(2.0, 10);  // a caller at only 10 Hz: the newest setpoint is re-sent, still 50 Hz
  const double slow_hz = rateHz(b.fake->setpoint_rx_ns);
  EXPECT_NEAR(slow_hz, 50.0, 0.5);
  RecordProperty("setpoint_rate_hz_caller_100hz", std::to_string(full_hz));
  RecordProperty("setpoint_rate_hz_caller_10hz", std::to_string(slow_hz));
  const auto& m = b.fake->setpoints.back();
  EXPECT_EQ(m.coordinate_frame, 1);  // MAV_FRAME_LOCAL_NED
  EXPECT_EQ(m.type_mask, 0);
  EXPECT_EQ(m.target_system, 1);
  EXPECT_EQ(m.target_component, 1);
  EXPECT_FLOAT_EQ(m.x, 2.0F);   // north
  EXPECT_FLOAT_EQ(m.y, 1.0F);   // east
  EXPECT_FLOAT_EQ(m.z, -3.0F);  // down
  EXPECT_FLOAT_EQ(m.vx, -0.25F);
  EXPECT_FLOAT_EQ(m.vy, 0.5F);
  EXPECT_FLOAT_EQ(m.vz, -0.125F);
  EXPECT_FLOAT_EQ(m.afx, 0.75F);
  EXPECT_FLOAT_EQ(m.afy, -1.0F);
  EXPECT_FLOAT_EQ(m.afz, -0.5F);
  EXPECT_FLOAT_EQ(m.yaw, static_cast<float>(kPi / 2 - 0.3));
  EXPECT_FLOAT_EQ(m.yaw_rate, -0.2F);
  // time_boot_ms counts from the link's first use: monotonic, about 4 s now.
  EXPECT_NEAR(static_cast<double>(m.time_boot_ms), 4000.0, 20.0);
}

TEST(MavlinkVehicle, StaleSetpointsAreNotRepeatedForever) {
  Bench b;
  b.run(1.0, 1);
  const std::size_t streamed = b.fake->setpoints.size();
  b.run(2.0);  // the planner stops; the odometry task keeps polling
  // Re-sent for setpoint_stale_s (0.5 s, 25 more at 50 Hz), then nothing: PX4's failsafe may act.
  EXPECT_NEAR(static_cast<double>(b.fake->setpoints.size() - streamed), 25.0, 2.0);
  const std::size_t after = b.fake->setpoints.size();
  b.run(1.0);
  EXPECT_EQ(b.fake->setpoints.size(), after);
}

void expectStateMatchesTruth(const Bench& b, const OdometrySample& s) {
  const testing::FakeTruth& t = b.fake->truth;
  EXPECT_TRUE(s.p_WB_m.isApprox(Eigen::Vector3d(t.p_N_m.y(), t.p_N_m.x(), -t.p_N_m.z()), 1e-6));
  EXPECT_TRUE(s.v_WB_mps.isApprox(Eigen::Vector3d(t.v_N_mps.y(), t.v_N_mps.x(), -t.v_N_mps.z()), 1e-5));
  EXPECT_TRUE(s.w_WB_B_radps.isApprox(Eigen::Vector3d(t.w_F_radps.x(), -t.w_F_radps.y(), -t.w_F_radps.z()), 1e-5));
  // The body's forward axis and its left axis, independently: R_NF's first column, and minus its second.
  const Eigen::Matrix3d r_NF = ned_enu::eulerNedToQuaternion(t.roll_rad, t.pitch_rad, t.yaw_rad).toRotationMatrix();
  const Eigen::Vector3d fwd_N = r_NF.col(0);
  const Eigen::Vector3d right_N = r_NF.col(1);
  EXPECT_TRUE((s.q_WB * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d(fwd_N.y(), fwd_N.x(), -fwd_N.z()), 1e-6));
  EXPECT_TRUE(
      (s.q_WB * Eigen::Vector3d::UnitY()).isApprox(-Eigen::Vector3d(right_N.y(), right_N.x(), -right_N.z()), 1e-6));
}

void checkOdometry(bool odometry_message) {
  Bench b(FakeAutopilotParams{.odometry = odometry_message});
  b.fake->truth.p_N_m = {10.0, -4.0, -2.5};  // 2.5 m up
  b.fake->truth.v_N_mps = {1.0, 0.5, -0.2};
  b.fake->truth.roll_rad = 0.1;
  b.fake->truth.pitch_rad = -0.2;
  b.fake->truth.yaw_rad = 2.0;
  b.fake->truth.w_F_radps = {0.05, -0.1, 0.3};
  b.run(0.5);
  b.fake->step(b.now_ns);
  const auto s = b.odometry->read(b.now_ns);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->stamp_ns, b.now_ns);  // the fake sent at this tick: stamped when read
  expectStateMatchesTruth(b, *s);
  EXPECT_EQ(b.odometry->health(b.now_ns).state, DeviceHealth::State::kOk) << b.odometry->health(b.now_ns).detail;
  EXPECT_EQ(b.odometry->backend(), "real");
  // The fake sent 26 times at 50 Hz (0 to 0.5 s): one sample per ODOMETRY; with the pair, one per message
  // once both have arrived (51).
  EXPECT_EQ(b.connection->counters().states, odometry_message ? 26U : 51U);
}

TEST(MavlinkVehicle, OdometryMessageConvertsBackToTheTruthInEnuFlu) {
  checkOdometry(true);
}

TEST(MavlinkVehicle, LocalPositionAndAttitudeConvertBackToTheTruthInEnuFlu) {
  checkOdometry(false);
}

void checkLateRead(bool odometry_message) {
  Bench b(FakeAutopilotParams{.odometry = odometry_message});
  b.run(1.0);  // the offset is learnt
  // The odometry task stalls for 45 ms while the autopilot sends at 0, 20 and 40 ms.
  const rt::TimeNs stall_start_ns = b.now_ns;
  for (int i = 0; i < 5; ++i) {
    b.fake->step(b.now_ns);
    b.now_ns += kTick;
  }
  const auto s = b.odometry->read(b.now_ns - 5 * rt::kNsPerMillisecond);
  ASSERT_TRUE(s.has_value());
  // The newest sample keeps its own time (40 ms into the stall), not the read's (45 ms), give or take
  // the offset's allowed drift over the stall (100 ppm of 55 ms: 5.5 us) and the wire's 1 us resolution.
  EXPECT_NEAR(static_cast<double>(s->stamp_ns - stall_start_ns) * 1e-6, 40.0, 0.01);
}

TEST(MavlinkVehicle, ASampleReadLateKeepsTheAutopilotsTimeOnOurClock) {
  checkLateRead(true);
  checkLateRead(false);
}

TEST(MavlinkVehicle, NoAllocationInSteadyState) {
  for (const bool odometry_message : {true, false}) {
    Bench b(FakeAutopilotParams{.odometry = odometry_message});
    b.run(1.0, 1);  // warm up: the parser's buffer reaches its size
    long made = 0;
    std::size_t reads = 0;
    for (int i = 0; i < 200; ++i) {
      b.fake->step(b.now_ns);  // the fake allocates; it is not counted
      Setpoint sp;
      sp.stamp_ns = b.now_ns;
      counting_allocations = true;
      allocations = 0;
      const auto s = b.odometry->read(b.now_ns);
      b.link->send(sp);
      const VehicleStatus status = b.link->status(b.now_ns);
      made += allocations;
      counting_allocations = false;
      reads += (s.has_value() && status.link_ok) ? 1 : 0;
      b.now_ns += kTick;
    }
    EXPECT_EQ(reads, 200U);
    EXPECT_EQ(made, 0) << (odometry_message ? "ODOMETRY" : "LOCAL_POSITION_NED + ATTITUDE");
    EXPECT_GT(b.fake->setpoints.size(), 140U);  // it did send: 50 Hz over 3 s
  }
}

TEST(MavlinkVehicle, OffboardOnlyAfterStreamingThenFliesThereAndHoldsWhenTheStreamStops) {
  Bench b;
  b.run(0.5);
  EXPECT_EQ(b.link->status(b.now_ns).mode, FlightMode::kManual);  // POSCTL
  EXPECT_TRUE(b.link->status(b.now_ns).armed);
  EXPECT_FALSE(b.fake->requestOffboard(b.now_ns));  // nothing streamed: PX4 refuses
  b.setpoint.p_W_m = {3.0, 4.0, 2.0};
  b.setpoint.yaw_rad = kPi / 2;  // facing north
  b.run(0.5, 1);
  EXPECT_FALSE(b.fake->requestOffboard(b.now_ns));  // streaming, but not for 1 s yet
  b.run(0.6, 1);
  EXPECT_TRUE(b.fake->requestOffboard(b.now_ns));
  b.run(0.05, 1);
  EXPECT_EQ(b.status.mode, FlightMode::kOffboard);
  b.run(4.0, 1);  // 5.4 m at 2 m/s
  const auto s = b.odometry->read(b.now_ns);
  ASSERT_TRUE(s.has_value());
  EXPECT_TRUE(s->p_WB_m.isApprox(Eigen::Vector3d(3.0, 4.0, 2.0), 1e-5)) << s->p_WB_m.transpose();
  EXPECT_NEAR((s->q_WB * Eigen::Vector3d::UnitX()).y(), 1.0, 1e-6);  // facing north
  // The planner stops: re-sent for 0.5 s, then the fake's 0.5 s offboard loss: HOLD, seen at its
  // next heartbeat (1 Hz).
  b.run(1.2);
  EXPECT_EQ(b.fake->customMode(), FakeAutopilot::kLoiter);
  b.run(1.0);
  EXPECT_EQ(b.link->status(b.now_ns).mode, FlightMode::kHold);
}

TEST(MavlinkVehicle, ArduCopterGuidedIsOffboardAndDisarmedIsSeen) {
  Bench b(FakeAutopilotParams{.autopilot = 3});
  b.fake->setCustomMode(4);  // GUIDED
  b.fake->setArmed(false);
  b.run(0.1);
  const VehicleStatus s = b.link->status(b.now_ns);
  EXPECT_TRUE(s.link_ok);
  EXPECT_FALSE(s.armed);
  EXPECT_EQ(s.mode, FlightMode::kOffboard);
}

TEST(MavlinkVehicle, LinkLossFailsWithinTheTimeoutAndRecovers) {
  Bench b;
  b.run(2.0, 1);
  ASSERT_TRUE(b.status.link_ok);
  const rt::TimeNs last_heartbeat_ns = b.link->health(b.now_ns).last_sample_ns;
  b.fake->setSilent(true);
  rt::TimeNs lost_ns = -1;
  for (int i = 0; i < 300 && lost_ns < 0; ++i) {
    b.tick(1);
    if (!b.status.link_ok) lost_ns = b.now_ns - kTick;
  }
  ASSERT_GE(lost_ns, 0);
  // Lost once link_timeout_s (1.5 s) has passed since the last heartbeat, within one tick.
  EXPECT_GT(lost_ns - last_heartbeat_ns, rt::secondsToNs(1.5));
  EXPECT_LE(lost_ns - last_heartbeat_ns, rt::secondsToNs(1.5) + kTick);
  const DeviceHealth h = b.link->health(b.now_ns);
  EXPECT_EQ(h.state, DeviceHealth::State::kFailed);
  EXPECT_EQ(h.detail.rfind("udp://127.0.0.1:0: no heartbeat from system 1 for 1.", 0), 0U) << h.detail;
  EXPECT_EQ(b.odometry->health(b.now_ns).state, DeviceHealth::State::kFailed);
  b.fake->setSilent(false);
  b.run(0.05, 1);
  EXPECT_TRUE(b.status.link_ok);
  EXPECT_EQ(b.link->health(b.now_ns).state, DeviceHealth::State::kOk) << b.link->health(b.now_ns).detail;
  EXPECT_EQ(b.odometry->health(b.now_ns).state, DeviceHealth::State::kOk);
}

TEST(MavlinkVehicle, NeverHeardFailsAfterTheTimeoutFromFirstUse) {
  auto opened = MavlinkConnection::open(MavlinkParams{.url = "udp://127.0.0.1:0"});
  ASSERT_TRUE(opened.has_value());
  MavlinkVehicleLink link(*opened);
  const rt::TimeNs t0 = 5 * rt::kNsPerSecond;
  EXPECT_FALSE(link.status(t0).link_ok);
  EXPECT_NE(link.health(t0 + rt::secondsToNs(1.4)).state, DeviceHealth::State::kFailed);
  const DeviceHealth h = link.health(t0 + rt::secondsToNs(1.6));
  EXPECT_EQ(h.state, DeviceHealth::State::kFailed);
  EXPECT_EQ(h.detail, "udp://127.0.0.1:0: no heartbeat from system 1 for 1.6 s (never heard)");
}

TEST(MavlinkVehicle, MalformedDatagramsAreCountedAndIgnoredNeverACrash) {
  Bench b;
  b.run(0.5, 1);
  ASSERT_EQ(b.link->health(b.now_ns).state, DeviceHealth::State::kOk);
  for (const Garbage g : {Garbage::kBadCrc, Garbage::kTruncated, Garbage::kMavlink1, Garbage::kNoise})
    b.fake->sendGarbage(g);
  b.fake->sendGarbage(Garbage::kUnknownMessage);
  b.run(0.5, 1);
  const MavlinkCounters c = b.connection->counters();
  EXPECT_EQ(c.malformed, 4U);
  EXPECT_EQ(c.unknown_messages, 1U);  // counted, but no error: autopilots send many we do not read
  const DeviceHealth h = b.link->health(b.now_ns);
  EXPECT_EQ(h.state, DeviceHealth::State::kDegraded);
  EXPECT_EQ(h.error_count, 4U);
  EXPECT_NE(h.detail.find("the first: udp://127.0.0.1:0: a malformed datagram (21 bytes"), std::string::npos)
      << h.detail;
  // Everything else kept flowing: the state is fresh and the link up.
  EXPECT_TRUE(b.status.link_ok);
  const auto s = b.odometry->read(b.now_ns);
  ASSERT_TRUE(s.has_value());
  EXPECT_GE(s->stamp_ns, b.now_ns - 2 * kTick);
  // Random bytes in bulk: never a crash, never a frame.
  const std::uint64_t frames_before = b.connection->counters().frames;
  for (int i = 0; i < 200; ++i) b.fake->sendGarbage(Garbage::kNoise);
  b.odometry->read(b.now_ns);
  EXPECT_EQ(b.connection->counters().frames, frames_before);
  EXPECT_EQ(b.connection->counters().malformed, 204U);
}

}  // namespace
}  // namespace aerotrack::hal::real
