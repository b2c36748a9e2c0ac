// The flight controller over MAVLink v2 (issue 11 item 4): PX4 in offboard mode, ArduPilot copter in
// GUIDED (the same messages). One MavlinkConnection owns the UDP endpoint and the codec's parser; two
// devices share it: MavlinkOdometry (polled by the odometry task) and MavlinkVehicleLink (the
// trajectory server's setpoints and the vehicle's mode). Every call of either device polls the
// connection: it reads every datagram waiting, decodes the autopilot's messages, and sends what is due.
//
// On the wire (ned_enu.hpp converts; the project stays ENU/FLU):
//   out  HEARTBEAT at heartbeat_period_s as an onboard controller (MAV_TYPE_ONBOARD_CONTROLLER 18,
//        MAV_AUTOPILOT_INVALID 8, MAV_STATE_ACTIVE).
//   out  SET_POSITION_TARGET_LOCAL_NED in MAV_FRAME_LOCAL_NED with position, velocity, acceleration,
//        yaw and yaw rate all used (type_mask 0): the newest setpoint, at most once per
//        setpoint_period_s, and re-sent at that period when the caller is slower (for setpoint_stale_s
//        at most), so the stream is steady at 1 / setpoint_period_s (PX4 needs > 2 Hz, and a stream
//        before the switch to offboard). Nothing before the planner's first setpoint.
//   in   HEARTBEAT (mode, armed, link), ODOMETRY (preferred), else LOCAL_POSITION_NED + ATTITUDE.
//
// Time: a sample is stamped with the time the autopilot put in it (ODOMETRY time_usec; the newer
// time_boot_ms of LOCAL_POSITION_NED and ATTITUDE), mapped onto our clock by RemoteClock without
// TIMESYNC: the offset between the clocks is the minimum of (our poll time - the autopilot's time)
// over the messages. Read late (the odometry task runs every 10 ms, and may stall), a sample keeps
// its own time; the stamp is late only by the smallest delay seen, the autopilot's send path plus the
// network's (about a millisecond on a wire), and never later than the poll that read it. Messages
// without a time (0) are stamped with the poll's now_ns.
//
// Health: failed when no HEARTBEAT has come from the autopilot (target_system, target_component) for
// link_timeout_s (or, never heard, link_timeout_s after the first poll); the odometry also when no
// state has come for odometry_timeout_s. Degraded when malformed datagrams arrived (bad CRC, truncated
// frame, MAVLink 1 or signed frame, bytes that are no frame: counted, the first named) or sends
// failed. Frames of messages the codec does not know are counted but are no error: an autopilot
// streams dozens of messages this driver has no use for.
//
// Thread safety: every method may be called from any thread (one mutex; short critical sections).
// Allocation: none in steady state (fixed buffers, the codec's allocation-free calls); only the health
// details and the first problem's text are strings.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/protocol/mavlink.hpp"
#include "aerotrack/hal/real/udp_socket.hpp"

namespace aerotrack::hal::real {

struct MavlinkParams {
  std::string url = "udp://0.0.0.0:14540";  ///< udp://[bind_host]:port or udpout://host:port
  int system_id = 1;                        ///< Ours (1..255): usually the vehicle's, as a companion computer's.
  int component_id = 191;                   ///< Ours: MAV_COMP_ID_ONBOARD_COMPUTER.
  int target_system = 1;                    ///< The autopilot's system id.
  int target_component = 1;                 ///< The autopilot's component id (MAV_COMP_ID_AUTOPILOT1).
  double heartbeat_period_s = 1.0;          ///< Our HEARTBEAT period.
  double setpoint_period_s = 0.02;          ///< Setpoint stream period, and the cap on the wire rate (<= 0.05).
  double setpoint_stale_s = 0.5;            ///< The newest setpoint is re-sent only this long: a planner that
                                            ///< stops must let PX4's offboard-loss failsafe act (COM_OF_LOSS_T).
  double link_timeout_s = 1.5;              ///< No HEARTBEAT from the autopilot this long: the link is lost.
  double odometry_timeout_s = 0.2;          ///< No state this long: the odometry has failed.
};

/// Ok, or the first bad field named.
rt::Status validate(const MavlinkParams& params);

/// What the connection has counted since it opened.
struct MavlinkCounters {
  std::uint64_t datagrams = 0;   ///< received
  std::uint64_t frames = 0;      ///< decoded, from anyone
  std::uint64_t heartbeats = 0;  ///< from the autopilot
  std::uint64_t states = 0;      ///< ODOMETRY or LOCAL_POSITION_NED + ATTITUDE samples made
  std::uint64_t heartbeats_sent = 0;
  std::uint64_t setpoints_sent = 0;
  std::uint64_t malformed = 0;         ///< datagrams with a bad CRC, a truncated, v1 or signed frame, or noise
  std::uint64_t unknown_messages = 0;  ///< frames of messages the codec does not know (no error)
  std::uint64_t send_failures = 0;
};

/// The autopilot's clock (boot time or UNIX time, in microseconds) mapped onto ours, with no TIMESYNC
/// exchange: offset = arrival - remote time, and its running minimum is the true offset plus the
/// smallest delay seen. The minimum may rise by kDriftPpm of the elapsed time (two crystals differ by
/// tens of ppm, and a minimum alone would only ever follow one direction of drift); it starts again
/// when the offset jumps by more than a second (the autopilot rebooted, or set its clock). Not thread-
/// safe (the connection's mutex guards it); no allocation.
class RemoteClock {
 public:
  static constexpr double kDriftPpm = 100.0;
  /// One message's remote time and the time it was read on our clock: its time on our clock, never
  /// later than arrival_ns. A remote time of 0 (not filled in) or beyond year 2100 gives arrival_ns.
  rt::TimeNs toLocal(std::uint64_t remote_us, rt::TimeNs arrival_ns);

 private:
  bool valid_ = false;
  std::int64_t offset_ns_ = 0;
  rt::TimeNs last_arrival_ns_ = 0;
};

/// Mode and armed state from an autopilot's HEARTBEAT: PX4 (autopilot 12) and ArduPilot copter (3).
FlightMode decodeFlightMode(const protocol::mavlink::Heartbeat& heartbeat);
inline bool decodeArmed(const protocol::mavlink::Heartbeat& heartbeat) {
  return (heartbeat.base_mode & 128U) != 0;  // MAV_MODE_FLAG_SAFETY_ARMED
}

class MavlinkConnection {
 public:
  /// Opens the UDP endpoint (one-line error naming the URL) after validating the parameters.
  static rt::Expected<std::shared_ptr<MavlinkConnection>> open(const MavlinkParams& params);

  /// Reads everything waiting, updates the state, sends the heartbeat and the setpoint when due.
  void poll(rt::TimeNs now_ns);
  /// Takes the planner's newest setpoint (ENU) and polls at its stamp_ns; sent now unless the last
  /// setpoint went out less than setpoint_period_s ago (then at the next poll that is due).
  void send(const Setpoint& setpoint);
  /// The newest state, converted to ENU/FLU; nothing before the first.
  std::optional<OdometrySample> odometry() const;
  VehicleStatus status(rt::TimeNs now_ns) const;
  DeviceHealth linkHealth(rt::TimeNs now_ns) const;
  DeviceHealth odometryHealth(rt::TimeNs now_ns) const;
  MavlinkCounters counters() const;
  /// The local UDP port (tests open udp://127.0.0.1:0 and tell the peer this).
  std::uint16_t localPort() const;
  const MavlinkParams& params() const { return params_; }

  MavlinkConnection(UdpSocket socket, const MavlinkParams& params);

 private:
  // All below with mutex_ held.
  void receiveLocked(rt::TimeNs now_ns);
  void handleLocked(const protocol::mavlink::FrameView& frame, rt::TimeNs now_ns);
  void sendDueLocked(rt::TimeNs now_ns);
  void publishLocked(OdometrySample sample);
  void transmitLocked(std::uint32_t message_id);  // tx_payload_, framed
  /// Counts a problem; its text is made only for the first (kept for the health detail), so that a
  /// problem an autopilot repeats at 50 Hz (e.g. ODOMETRY in an unexpected frame) allocates nothing.
  template <class MakeText>
  void noteLocked(MakeText make_text) {
    ++problems_;
    if (first_problem_.empty()) first_problem_ = make_text();
  }
  std::uint32_t bootMsLocked(rt::TimeNs now_ns) const;
  DeviceHealth baseHealthLocked(rt::TimeNs now_ns) const;

  mutable std::mutex mutex_;
  UdpSocket socket_;
  MavlinkParams params_;
  protocol::mavlink::Parser parser_;
  std::array<std::uint8_t, 2048> datagram_{};
  protocol::mavlink::Payload tx_payload_;
  protocol::mavlink::FrameBytes tx_frame_;
  std::uint8_t sequence_ = 0;
  rt::TimeNs first_poll_ns_ = -1;
  rt::TimeNs last_heartbeat_rx_ns_ = -1;
  rt::TimeNs next_heartbeat_ns_ = -1;  // -1: at the first chance
  rt::TimeNs next_setpoint_ns_ = -1;
  std::optional<Setpoint> setpoint_;  // newest from the planner
  bool armed_ = false;
  FlightMode mode_ = FlightMode::kUnknown;
  // State: ODOMETRY when it comes; LOCAL_POSITION_NED and ATTITUDE combined otherwise.
  rt::TimeNs last_odometry_msg_ns_ = -1;
  std::optional<protocol::mavlink::LocalPositionNed> position_;
  std::optional<protocol::mavlink::Attitude> attitude_;
  std::optional<OdometrySample> state_;
  RemoteClock odometry_clock_;  // ODOMETRY time_usec
  RemoteClock boot_clock_;      // LOCAL_POSITION_NED / ATTITUDE time_boot_ms
  MavlinkCounters counters_;
  std::uint64_t problems_ = 0;
  std::string first_problem_;
};

class MavlinkOdometry final : public Odometry {
 public:
  explicit MavlinkOdometry(std::shared_ptr<MavlinkConnection> connection) : connection_(std::move(connection)) {}
  std::string_view backend() const override { return "real"; }
  DeviceHealth health(rt::TimeNs now_ns) const override { return connection_->odometryHealth(now_ns); }
  std::optional<OdometrySample> read(rt::TimeNs now_ns) override {
    connection_->poll(now_ns);
    return connection_->odometry();
  }

 private:
  std::shared_ptr<MavlinkConnection> connection_;
};

class MavlinkVehicleLink final : public VehicleLink {
 public:
  explicit MavlinkVehicleLink(std::shared_ptr<MavlinkConnection> connection) : connection_(std::move(connection)) {}
  std::string_view backend() const override { return "real"; }
  DeviceHealth health(rt::TimeNs now_ns) const override { return connection_->linkHealth(now_ns); }
  /// The setpoint's stamp_ns is taken as the time now (the trajectory server stamps with its step time).
  void send(const Setpoint& setpoint) override { connection_->send(setpoint); }
  VehicleStatus status(rt::TimeNs now_ns) override {
    connection_->poll(now_ns);
    return connection_->status(now_ns);
  }

 private:
  std::shared_ptr<MavlinkConnection> connection_;
};

}  // namespace aerotrack::hal::real
