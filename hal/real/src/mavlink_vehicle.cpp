// MAVLink flight controller: see mavlink_vehicle.hpp.
#include "aerotrack/hal/real/mavlink_vehicle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "aerotrack/hal/real/ned_enu.hpp"

namespace aerotrack::hal::real {
namespace mav = protocol::mavlink;
namespace {

// MAV_AUTOPILOT, MAV_TYPE, MAV_STATE, MAV_FRAME values (common.xml / minimal.xml).
constexpr std::uint8_t kAutopilotArdupilot = 3;
constexpr std::uint8_t kAutopilotInvalid = 8;
constexpr std::uint8_t kAutopilotPx4 = 12;
constexpr std::uint8_t kTypeGcs = 6;
constexpr std::uint8_t kTypeOnboardController = 18;
constexpr std::uint8_t kStateActive = 4;
constexpr std::uint8_t kFrameLocalNed = 1;
constexpr std::uint8_t kFrameBodyNed = 8;  // deprecated MAV_FRAME_BODY_NED: axes parallel to local NED
constexpr std::uint8_t kFrameBodyFrd = 12;

// PX4 custom_mode (src/modules/commander/px4_custom_mode.h): main mode in bits 16..23, sub mode in
// 24..31. Main: 1 MANUAL, 2 ALTCTL, 3 POSCTL, 4 AUTO, 5 ACRO, 6 OFFBOARD, 7 STABILIZED. AUTO sub:
// 1 READY, 2 TAKEOFF, 3 LOITER, 4 MISSION, 5 RTL, 6 LAND.
FlightMode px4Mode(std::uint32_t custom_mode) {
  const unsigned main = (custom_mode >> 16) & 0xFFU;
  const unsigned sub = (custom_mode >> 24) & 0xFFU;
  switch (main) {
    case 1:
    case 2:
    case 3:
    case 5:
    case 7:
      return FlightMode::kManual;
    case 6:
      return FlightMode::kOffboard;
    case 4:
      if (sub == 3) return FlightMode::kHold;
      // RTL ends in a landing the autopilot flies by itself: for us it is "landing, not ours".
      if (sub == 5 || sub == 6) return FlightMode::kLand;
      return FlightMode::kUnknown;
    default:
      return FlightMode::kUnknown;
  }
}

// ArduCopter's mode numbers (ArduCopter/mode.h, Mode::Number): 0 STABILIZE, 1 ACRO, 2 ALT_HOLD, 4 GUIDED,
// 5 LOITER, 6 RTL, 9 LAND, 11 DRIFT, 13 SPORT, 16 POSHOLD, 17 BRAKE, 21 SMART_RTL.
FlightMode arducopterMode(std::uint32_t custom_mode) {
  switch (custom_mode) {
    case 0:
    case 1:
    case 2:
    case 11:
    case 13:
      return FlightMode::kManual;
    case 4:
      return FlightMode::kOffboard;
    case 5:
    case 16:
    case 17:
      return FlightMode::kHold;
    case 6:  // RTL (and SMART_RTL): the autopilot flies home and lands; reported as landing
    case 9:
    case 21:
      return FlightMode::kLand;
    default:
      return FlightMode::kUnknown;
  }
}

// The wire's floats, widened explicitly.
double d(float value) {
  return static_cast<double>(value);
}
Eigen::Vector3d vec(float x, float y, float z) {
  return {d(x), d(y), d(z)};
}

bool finite(const Eigen::Vector3d& v) {
  return v.allFinite();
}

std::string seconds(rt::TimeNs ns) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f s", static_cast<double>(ns) / static_cast<double>(rt::kNsPerSecond));
  return text;
}

}  // namespace

rt::TimeNs RemoteClock::toLocal(std::uint64_t remote_us, rt::TimeNs arrival_ns) {
  constexpr std::uint64_t kYear2100Us = 4'102'444'800'000'000ULL;
  if (remote_us == 0 || remote_us > kYear2100Us) return arrival_ns;
  const auto remote_ns = static_cast<std::int64_t>(remote_us) * 1000;
  const std::int64_t observed_ns = arrival_ns - remote_ns;
  if (valid_) {
    const rt::TimeNs elapsed_ns = arrival_ns > last_arrival_ns_ ? arrival_ns - last_arrival_ns_ : 0;
    const auto creep_ns = static_cast<std::int64_t>(static_cast<double>(elapsed_ns) * kDriftPpm * 1e-6);
    const std::int64_t allowed_ns = offset_ns_ + creep_ns;
    if (observed_ns - allowed_ns > rt::kNsPerSecond || allowed_ns - observed_ns > rt::kNsPerSecond) {
      offset_ns_ = observed_ns;  // a reboot or a clock step: start again
    } else {
      offset_ns_ = std::min(observed_ns, allowed_ns);
    }
  } else {
    offset_ns_ = observed_ns;
    valid_ = true;
  }
  last_arrival_ns_ = arrival_ns;
  return std::min(remote_ns + offset_ns_, arrival_ns);
}

FlightMode decodeFlightMode(const mav::Heartbeat& heartbeat) {
  if (heartbeat.autopilot == kAutopilotPx4) return px4Mode(heartbeat.custom_mode);
  if (heartbeat.autopilot == kAutopilotArdupilot) return arducopterMode(heartbeat.custom_mode);
  return FlightMode::kUnknown;
}

rt::Status validate(const MavlinkParams& p) {
  const auto bad = [](const std::string& field, const std::string& why) {
    return rt::Error{"mavlink: " + field + ": " + why};
  };
  if (p.url.empty()) return bad("url", "empty (expected udp://[bind_host]:port or udpout://host:port)");
  if (p.system_id < 1 || p.system_id > 255) return bad("system_id", "must be 1..255");
  if (p.component_id < 1 || p.component_id > 255) return bad("component_id", "must be 1..255");
  if (p.target_system < 1 || p.target_system > 255) return bad("target_system", "must be 1..255");
  if (p.target_component < 1 || p.target_component > 255) return bad("target_component", "must be 1..255");
  if (p.system_id == p.target_system && p.component_id == p.target_component)
    return bad("component_id", "equals the autopilot's (target_system, target_component)");
  if (!(p.heartbeat_period_s > 0.0 && p.heartbeat_period_s <= 1.0))
    return bad("heartbeat_period_s", "must be in (0, 1] (autopilots time a companion out after a few seconds)");
  if (!(p.setpoint_period_s > 0.0 && p.setpoint_period_s <= 0.05))
    return bad("setpoint_period_s", "must be in (0, 0.05] (>= 20 Hz)");
  if (!(p.setpoint_stale_s >= p.setpoint_period_s && p.setpoint_stale_s <= 0.5))
    return bad("setpoint_stale_s", "must be in [setpoint_period_s, 0.5] (PX4's COM_OF_LOSS_T default is 1 s)");
  if (!(p.link_timeout_s > p.heartbeat_period_s)) return bad("link_timeout_s", "must exceed heartbeat_period_s");
  if (!(p.odometry_timeout_s > 0.0)) return bad("odometry_timeout_s", "must be positive");
  return rt::ok();
}

rt::Expected<std::shared_ptr<MavlinkConnection>> MavlinkConnection::open(const MavlinkParams& params) {
  if (rt::Status s = validate(params); !s) return s.error();
  auto socket = UdpSocket::open(params.url);
  if (!socket) return socket.error();
  return std::make_shared<MavlinkConnection>(std::move(*socket), params);
}

MavlinkConnection::MavlinkConnection(UdpSocket socket, const MavlinkParams& params)
    : socket_(std::move(socket)), params_(params) {}

std::uint16_t MavlinkConnection::localPort() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return socket_.localPort();
}

std::uint32_t MavlinkConnection::bootMsLocked(rt::TimeNs now_ns) const {
  const rt::TimeNs since_ns = first_poll_ns_ >= 0 ? now_ns - first_poll_ns_ : 0;
  return static_cast<std::uint32_t>(since_ns / rt::kNsPerMillisecond);
}

void MavlinkConnection::poll(rt::TimeNs now_ns) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (first_poll_ns_ < 0) first_poll_ns_ = now_ns;
  receiveLocked(now_ns);
  sendDueLocked(now_ns);
}

void MavlinkConnection::send(const Setpoint& setpoint) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    setpoint_ = setpoint;
  }
  poll(setpoint.stamp_ns);
}

void MavlinkConnection::receiveLocked(rt::TimeNs now_ns) {
  // Bounded, so a flood cannot hold the mutex (and the other device's task) for long; what is left
  // waits for the next poll, 10 ms later.
  constexpr int kMaxDatagramsPerPoll = 256;
  for (int n = 0; n < kMaxDatagramsPerPoll; ++n) {
    auto received = socket_.receive(datagram_.data(), datagram_.size());
    if (!received) {
      noteLocked([&received] { return received.error().message; });
      return;
    }
    if (!received->has_value()) return;
    ++counters_.datagrams;
    const std::uint64_t bad_before =
        parser_.badCrc() + parser_.truncated() + parser_.unsupported() + parser_.skippedBytes();
    const std::uint64_t unknown_before = parser_.unknownMessages();
    // The lambda holds two words: std::function keeps it inline, no allocation.
    parser_.feedEach(datagram_.data(), **received,
                     [this, now_ns](const mav::FrameView& f) { handleLocked(f, now_ns); });
    parser_.endOfDatagram();  // a frame never spans two UDP datagrams
    counters_.unknown_messages += parser_.unknownMessages() - unknown_before;
    const std::uint64_t bad_after =
        parser_.badCrc() + parser_.truncated() + parser_.unsupported() + parser_.skippedBytes();
    if (bad_after != bad_before) {
      ++counters_.malformed;
      noteLocked([&] {
        return socket_.url() + ": a malformed datagram (" + std::to_string(**received) +
               " bytes: bad CRC, truncated, MAVLink 1, signed or not MAVLink)";
      });
    }
  }
}

void MavlinkConnection::handleLocked(const mav::FrameView& frame, rt::TimeNs now_ns) {
  ++counters_.frames;
  if (frame.system_id != params_.target_system || frame.component_id != params_.target_component) return;
  switch (frame.message_id) {
    case mav::kHeartbeat: {
      const mav::Heartbeat hb = mav::decodeHeartbeat(frame.payload, frame.payload_size);
      if (hb.type == kTypeGcs || hb.autopilot == kAutopilotInvalid) return;  // not the autopilot
      ++counters_.heartbeats;
      last_heartbeat_rx_ns_ = now_ns;
      armed_ = decodeArmed(hb);
      mode_ = decodeFlightMode(hb);
      return;
    }
    case mav::kOdometry: {
      const mav::Odometry m = mav::decodeOdometry(frame.payload, frame.payload_size);
      if (m.frame_id != kFrameLocalNed) {
        noteLocked([&] {
          return socket_.url() + ": ODOMETRY in MAV_FRAME " + std::to_string(m.frame_id) + ", not LOCAL_NED: ignored";
        });
        return;
      }
      const Eigen::Quaterniond q_NF(d(m.q[0]), d(m.q[1]), d(m.q[2]), d(m.q[3]));
      const Eigen::Vector3d p_N = vec(m.x, m.y, m.z);
      Eigen::Vector3d v = vec(m.vx, m.vy, m.vz);
      if (m.child_frame_id == kFrameBodyFrd) {
        v = q_NF.normalized() * v;  // expressed in the body (PX4 labels its ODOMETRY velocity so): into NED
      } else if (m.child_frame_id != kFrameLocalNed && m.child_frame_id != kFrameBodyNed) {
        noteLocked([&] {
          return socket_.url() + ": ODOMETRY velocity in MAV_FRAME " + std::to_string(m.child_frame_id) + ": ignored";
        });
        return;
      }
      const Eigen::Vector3d w_F = vec(m.rollspeed, m.pitchspeed, m.yawspeed);
      // An estimator without a solution sends NaN: no sample (the odometry times out), no error.
      if (!finite(p_N) || !q_NF.coeffs().allFinite() || q_NF.norm() < 0.5) return;
      last_odometry_msg_ns_ = now_ns;
      OdometrySample s;
      s.stamp_ns = odometry_clock_.toLocal(m.time_usec, now_ns);
      s.p_WB_m = ned_enu::nedToEnu(p_N);
      s.q_WB = ned_enu::nedFrdToEnuFlu(q_NF);
      s.v_WB_mps = finite(v) ? ned_enu::nedToEnu(v) : Eigen::Vector3d::Zero();
      s.w_WB_B_radps = finite(w_F) ? ned_enu::frdToFlu(w_F) : Eigen::Vector3d::Zero();
      publishLocked(s);
      return;
    }
    case mav::kLocalPositionNed:
    case mav::kAttitude: {
      if (frame.message_id == mav::kLocalPositionNed) {
        position_ = mav::decodeLocalPositionNed(frame.payload, frame.payload_size);
      } else {
        attitude_ = mav::decodeAttitude(frame.payload, frame.payload_size);
      }
      const bool odometry_fresh =
          last_odometry_msg_ns_ >= 0 && now_ns - last_odometry_msg_ns_ <= rt::secondsToNs(params_.odometry_timeout_s);
      if (odometry_fresh || !position_ || !attitude_) return;
      const Eigen::Vector3d p_N = vec(position_->x, position_->y, position_->z);
      const Eigen::Vector3d v_N = vec(position_->vx, position_->vy, position_->vz);
      const Eigen::Vector3d w_F = vec(attitude_->rollspeed, attitude_->pitchspeed, attitude_->yawspeed);
      if (!finite(p_N) || !std::isfinite(attitude_->roll) || !std::isfinite(attitude_->pitch) ||
          !std::isfinite(attitude_->yaw))
        return;
      OdometrySample s;
      const std::uint32_t newer_ms = std::max(position_->time_boot_ms, attitude_->time_boot_ms);
      s.stamp_ns = boot_clock_.toLocal(static_cast<std::uint64_t>(newer_ms) * 1000, now_ns);
      s.p_WB_m = ned_enu::nedToEnu(p_N);
      s.q_WB = ned_enu::nedFrdToEnuFlu(
          ned_enu::eulerNedToQuaternion(d(attitude_->roll), d(attitude_->pitch), d(attitude_->yaw)));
      s.v_WB_mps = finite(v_N) ? ned_enu::nedToEnu(v_N) : Eigen::Vector3d::Zero();
      s.w_WB_B_radps = finite(w_F) ? ned_enu::frdToFlu(w_F) : Eigen::Vector3d::Zero();
      publishLocked(s);
      return;
    }
    default:
      return;
  }
}

void MavlinkConnection::publishLocked(OdometrySample sample) {
  // Readers tell new samples by their stamps: never let them go backwards, which they could when the
  // clock offset's estimate drops by more than the time between two samples.
  if (state_ && sample.stamp_ns < state_->stamp_ns) sample.stamp_ns = state_->stamp_ns;
  state_ = sample;
  ++counters_.states;
}

void MavlinkConnection::transmitLocked(std::uint32_t message_id) {
  const mav::Sender sender{static_cast<std::uint8_t>(params_.system_id),
                           static_cast<std::uint8_t>(params_.component_id)};
  mav::frameInto(message_id, tx_payload_, sender, sequence_++, tx_frame_);
  if (rt::Status s = socket_.send(tx_frame_.bytes.data(), tx_frame_.size); !s) {
    ++counters_.send_failures;
    noteLocked([&s] { return s.error().message; });
    return;
  }
  if (message_id == mav::kHeartbeat) ++counters_.heartbeats_sent;
  if (message_id == mav::kSetPositionTargetLocalNed) ++counters_.setpoints_sent;
}

namespace {

/// Whether a periodic send is due; if so, moves the schedule on by one period (absolute deadlines,
/// resynchronised after a gap longer than a period, so a late poll does not cause a burst).
bool due(rt::TimeNs now_ns, rt::TimeNs period_ns, rt::TimeNs& next_ns) {
  if (next_ns >= 0 && now_ns < next_ns) return false;
  next_ns = (next_ns < 0 || now_ns - next_ns >= period_ns) ? now_ns + period_ns : next_ns + period_ns;
  return true;
}

}  // namespace

void MavlinkConnection::sendDueLocked(rt::TimeNs now_ns) {
  // A listening endpoint learns its peer from the first datagram; until then there is no one to send to.
  if (!socket_.hasRemote()) return;
  if (due(now_ns, rt::secondsToNs(params_.heartbeat_period_s), next_heartbeat_ns_)) {
    mav::Heartbeat hb;
    hb.type = kTypeOnboardController;
    hb.autopilot = kAutopilotInvalid;
    hb.system_status = kStateActive;
    mav::encodePayload(hb, tx_payload_);
    transmitLocked(mav::kHeartbeat);
  }
  // Nothing is streamed before the planner's first setpoint: a setpoint made up here (say, "hold where
  // you are") would let the pilot switch to offboard and fly the vehicle to a target nobody planned.
  // The trajectory server sends only once it has a trajectory, so offboard becomes possible then. Nor
  // is a setpoint re-sent once older than setpoint_stale_s: if the planner dies, the stream stops and
  // the autopilot's own offboard-loss failsafe takes over.
  if (!setpoint_ || now_ns - setpoint_->stamp_ns > rt::secondsToNs(params_.setpoint_stale_s)) return;
  if (!due(now_ns, rt::secondsToNs(params_.setpoint_period_s), next_setpoint_ns_)) return;
  const Setpoint& sp = *setpoint_;
  mav::SetPositionTargetLocalNed m;
  m.time_boot_ms = bootMsLocked(now_ns);
  const Eigen::Vector3d p_N = ned_enu::enuToNed(sp.p_W_m);
  const Eigen::Vector3d v_N = ned_enu::enuToNed(sp.v_W_mps);
  const Eigen::Vector3d a_N = ned_enu::enuToNed(sp.a_W_mps2);
  m.x = static_cast<float>(p_N.x());
  m.y = static_cast<float>(p_N.y());
  m.z = static_cast<float>(p_N.z());
  m.vx = static_cast<float>(v_N.x());
  m.vy = static_cast<float>(v_N.y());
  m.vz = static_cast<float>(v_N.z());
  m.afx = static_cast<float>(a_N.x());
  m.afy = static_cast<float>(a_N.y());
  m.afz = static_cast<float>(a_N.z());
  m.yaw = static_cast<float>(ned_enu::yawEnuToNed(sp.yaw_rad));
  m.yaw_rate = static_cast<float>(-sp.yaw_rate_radps);  // about z down instead of z up
  m.type_mask = 0;                                      // every field used: PX4 tracks p with v and a as feed-forward
  m.target_system = static_cast<std::uint8_t>(params_.target_system);
  m.target_component = static_cast<std::uint8_t>(params_.target_component);
  m.coordinate_frame = kFrameLocalNed;
  mav::encodePayload(m, tx_payload_);
  transmitLocked(mav::kSetPositionTargetLocalNed);
}

std::optional<OdometrySample> MavlinkConnection::odometry() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return state_;
}

VehicleStatus MavlinkConnection::status(rt::TimeNs now_ns) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  VehicleStatus s;
  s.stamp_ns = last_heartbeat_rx_ns_ >= 0 ? last_heartbeat_rx_ns_ : 0;
  s.link_ok = last_heartbeat_rx_ns_ >= 0 && now_ns - last_heartbeat_rx_ns_ <= rt::secondsToNs(params_.link_timeout_s);
  // After a loss, armed and mode are the last ones heard: link_ok says they are stale.
  s.armed = armed_;
  s.mode = mode_;
  return s;
}

MavlinkCounters MavlinkConnection::counters() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return counters_;
}

DeviceHealth MavlinkConnection::baseHealthLocked(rt::TimeNs now_ns) const {
  DeviceHealth h;
  h.error_count = problems_;
  const std::string system = "system " + std::to_string(params_.target_system);
  const rt::TimeNs silent_since_ns = last_heartbeat_rx_ns_ >= 0 ? last_heartbeat_rx_ns_ : first_poll_ns_;
  if (silent_since_ns >= 0 && now_ns - silent_since_ns > rt::secondsToNs(params_.link_timeout_s)) {
    h.state = DeviceHealth::State::kFailed;
    h.detail = socket_.url() + ": no heartbeat from " + system + " for " + seconds(now_ns - silent_since_ns) +
               (last_heartbeat_rx_ns_ < 0 ? " (never heard)" : "");
  } else if (problems_ > 0) {
    h.state = DeviceHealth::State::kDegraded;
    h.detail = socket_.url() + ": " + std::to_string(problems_) + " problems, the first: " + first_problem_;
  } else {
    h.state = DeviceHealth::State::kOk;
    h.detail = socket_.url() + ": " + system + " " + toString(mode_) + (armed_ ? ", armed" : ", disarmed");
  }
  return h;
}

DeviceHealth MavlinkConnection::linkHealth(rt::TimeNs now_ns) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  DeviceHealth h = baseHealthLocked(now_ns);
  h.last_sample_ns = last_heartbeat_rx_ns_ >= 0 ? last_heartbeat_rx_ns_ : 0;
  return h;
}

DeviceHealth MavlinkConnection::odometryHealth(rt::TimeNs now_ns) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  DeviceHealth h = baseHealthLocked(now_ns);
  h.last_sample_ns = state_ ? state_->stamp_ns : 0;
  if (h.state == DeviceHealth::State::kFailed) return h;
  const rt::TimeNs silent_since_ns = state_ ? state_->stamp_ns : first_poll_ns_;
  if (silent_since_ns >= 0 && now_ns - silent_since_ns > rt::secondsToNs(params_.odometry_timeout_s)) {
    h.state = DeviceHealth::State::kFailed;
    h.detail = socket_.url() + ": no ODOMETRY or LOCAL_POSITION_NED + ATTITUDE from system " +
               std::to_string(params_.target_system) + " for " +
               std::to_string((now_ns - silent_since_ns) / rt::kNsPerMillisecond) + " ms";
  }
  return h;
}

}  // namespace aerotrack::hal::real
