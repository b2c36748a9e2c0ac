// A PX4-like autopilot on loopback UDP for the MAVLink driver's tests (issue 11 item 4), speaking through
// the project's own codec: HEARTBEAT at 1 Hz (autopilot PX4 12, or ArduPilot 3 when told; type
// quadrotor 2), ODOMETRY (or LOCAL_POSITION_NED + ATTITUDE) at 50 Hz from a kinematic vehicle that, in
// OFFBOARD, moves towards the newest SET_POSITION_TARGET_LOCAL_NED at a bounded speed. Like PX4 it
// accepts the switch to OFFBOARD (requestOffboard, the pilot's switch) only after setpoints have
// streamed at >= 2 Hz for >= 1 s, and falls back to HOLD (AUTO.LOITER) when the stream stops for 0.5 s
// (COM_OF_LOSS_T). It can go silent (link loss) or send malformed datagrams. Time is the test's: step()
// with explicit now_ns; no threads. Everything here is NED/FRD, as on the wire.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "aerotrack/hal/protocol/mavlink.hpp"
#include "aerotrack/hal/real/udp_socket.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::hal::real::testing {

namespace mav = protocol::mavlink;

struct FakeAutopilotParams {
  std::uint8_t autopilot = 12;  ///< MAV_AUTOPILOT_PX4
  std::uint8_t system_id = 1;
  std::uint8_t component_id = 1;
  bool odometry = true;  ///< ODOMETRY; false: LOCAL_POSITION_NED + ATTITUDE
  double heartbeat_period_s = 1.0;
  double state_period_s = 0.02;
  double max_speed_mps = 2.0;
  double offboard_loss_s = 0.5;      ///< PX4's COM_OF_LOSS_T in the test's setting
  rt::TimeNs boot_ns = 123'456'789;  ///< when the autopilot booted, on the test's clock: its time is since then
};

/// The vehicle's true state (NED, FRD), as the fake's estimator would report it.
struct FakeTruth {
  Eigen::Vector3d p_N_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_N_mps = Eigen::Vector3d::Zero();
  double roll_rad = 0.0, pitch_rad = 0.0, yaw_rad = 0.0;
  Eigen::Vector3d w_F_radps = Eigen::Vector3d::Zero();
};

enum class Garbage { kBadCrc, kTruncated, kUnknownMessage, kMavlink1, kNoise };

class FakeAutopilot {
 public:
  // PX4 custom_mode: main mode << 16 | sub mode << 24 (px4_custom_mode.h).
  static constexpr std::uint32_t kPosctl = 3U << 16;
  static constexpr std::uint32_t kOffboard = 6U << 16;
  static constexpr std::uint32_t kLoiter = (4U << 16) | (3U << 24);

  /// Sends to the driver listening on 127.0.0.1:port.
  FakeAutopilot(std::uint16_t port, const FakeAutopilotParams& params)
      : socket_(std::move(UdpSocket::open("udpout://127.0.0.1:" + std::to_string(port)).value())), params_(params) {}

  /// Reads what the driver sent, moves the vehicle, sends what is due.
  void step(rt::TimeNs now_ns) {
    receive(now_ns);
    const double dt_s = last_step_ns_ >= 0 ? static_cast<double>(now_ns - last_step_ns_) * 1e-9 : 0.0;
    last_step_ns_ = now_ns;
    if (custom_mode_ == kOffboard && params_.autopilot == 12) {
      if (now_ns - last_setpoint_ns_ > rt::secondsToNs(params_.offboard_loss_s)) {
        custom_mode_ = kLoiter;  // offboard loss: PX4's failsafe holds position
        truth.v_N_mps.setZero();
      } else if (dt_s > 0.0) {
        const Eigen::Vector3d to_go = Eigen::Vector3f(setpoint_.x, setpoint_.y, setpoint_.z).cast<double>();
        Eigen::Vector3d step_m = to_go - truth.p_N_m;
        const double max_m = params_.max_speed_mps * dt_s;
        if (step_m.norm() > max_m) step_m *= max_m / step_m.norm();
        truth.p_N_m += step_m;
        truth.v_N_mps = step_m / dt_s;
        truth.yaw_rad = static_cast<double>(setpoint_.yaw);
      }
    }
    if (silent_) return;
    if (due(now_ns, rt::secondsToNs(params_.heartbeat_period_s), next_heartbeat_ns_)) sendHeartbeat();
    if (due(now_ns, rt::secondsToNs(params_.state_period_s), next_state_ns_)) sendState(now_ns);
  }

  /// The pilot's switch to OFFBOARD: accepted (true) only while setpoints stream at >= 2 Hz and have
  /// for >= 1 s, as PX4 requires.
  bool requestOffboard(rt::TimeNs now_ns) {
    const bool streaming = last_setpoint_ns_ >= 0 && now_ns - last_setpoint_ns_ <= rt::secondsToNs(0.5) &&
                           now_ns - stream_start_ns_ >= rt::kNsPerSecond;
    if (streaming) {
      custom_mode_ = kOffboard;
      sendHeartbeat();  // PX4 announces a mode change at once
    }
    return streaming;
  }

  void setSilent(bool silent) { silent_ = silent; }
  void setArmed(bool armed) { armed_ = armed; }
  void setCustomMode(std::uint32_t custom_mode) { custom_mode_ = custom_mode; }
  std::uint32_t customMode() const { return custom_mode_; }

  void sendGarbage(Garbage kind) {
    std::vector<std::uint8_t> bytes = frameOf(mav::kHeartbeat, mav::encodePayload(heartbeat()));
    switch (kind) {
      case Garbage::kBadCrc:
        bytes.back() ^= 0x5A;
        break;
      case Garbage::kTruncated:
        // pop_back, not resize: GCC 12 with ASan warns of a huge memset in resize's (dead) growth path.
        for (int i = 0; i < 4; ++i) bytes.pop_back();
        break;
      case Garbage::kUnknownMessage:
        bytes = frameOf(12345, {1, 2, 3, 4});
        break;
      case Garbage::kMavlink1:
        bytes = {0xFE, 9, 0, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
        break;
      case Garbage::kNoise:
        bytes.assign(40, 0);
        for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(i * 37 + 11);
        break;
    }
    sendBytes(bytes);
  }

  FakeTruth truth;
  std::vector<rt::TimeNs> heartbeat_rx_ns;  ///< when the driver's heartbeats arrived (fake's time)
  std::vector<mav::Heartbeat> heartbeats;
  std::vector<rt::TimeNs> setpoint_rx_ns;
  std::vector<mav::SetPositionTargetLocalNed> setpoints;
  std::vector<std::uint8_t> sender_components;

 private:
  static bool due(rt::TimeNs now_ns, rt::TimeNs period_ns, rt::TimeNs& next_ns) {
    if (next_ns >= 0 && now_ns < next_ns) return false;
    next_ns = (next_ns < 0 || now_ns - next_ns >= period_ns) ? now_ns + period_ns : next_ns + period_ns;
    return true;
  }

  mav::Heartbeat heartbeat() const {
    mav::Heartbeat hb;
    hb.type = 2;  // MAV_TYPE_QUADROTOR
    hb.autopilot = params_.autopilot;
    hb.base_mode = static_cast<std::uint8_t>((armed_ ? 128U : 0U) | 1U);  // armed | custom mode enabled
    hb.custom_mode = custom_mode_;
    hb.system_status = 4;
    return hb;
  }

  std::vector<std::uint8_t> frameOf(std::uint32_t id, std::vector<std::uint8_t> payload) {
    return mav::frame(id, std::move(payload), mav::Sender{params_.system_id, params_.component_id}, sequence_++);
  }

  void sendBytes(const std::vector<std::uint8_t>& bytes) { (void)socket_.send(bytes.data(), bytes.size()); }

  void sendHeartbeat() { sendBytes(frameOf(mav::kHeartbeat, mav::encodePayload(heartbeat()))); }

  void sendState(rt::TimeNs now_ns) {
    const Eigen::Quaterniond q_NF = Eigen::AngleAxisd(truth.yaw_rad, Eigen::Vector3d::UnitZ()) *
                                    Eigen::AngleAxisd(truth.pitch_rad, Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(truth.roll_rad, Eigen::Vector3d::UnitX());
    const rt::TimeNs since_boot_ns = now_ns - params_.boot_ns;
    const auto ms = static_cast<std::uint32_t>(since_boot_ns / rt::kNsPerMillisecond);
    if (params_.odometry) {
      mav::Odometry m;  // as PX4 sends it: pose in LOCAL_NED, velocity in BODY_FRD
      m.time_usec = static_cast<std::uint64_t>(since_boot_ns / 1000);
      m.frame_id = 1;
      m.child_frame_id = 12;
      m.x = static_cast<float>(truth.p_N_m.x());
      m.y = static_cast<float>(truth.p_N_m.y());
      m.z = static_cast<float>(truth.p_N_m.z());
      m.q = {static_cast<float>(q_NF.w()), static_cast<float>(q_NF.x()), static_cast<float>(q_NF.y()),
             static_cast<float>(q_NF.z())};
      const Eigen::Vector3d v_F = q_NF.conjugate() * truth.v_N_mps;
      m.vx = static_cast<float>(v_F.x());
      m.vy = static_cast<float>(v_F.y());
      m.vz = static_cast<float>(v_F.z());
      m.rollspeed = static_cast<float>(truth.w_F_radps.x());
      m.pitchspeed = static_cast<float>(truth.w_F_radps.y());
      m.yawspeed = static_cast<float>(truth.w_F_radps.z());
      sendBytes(frameOf(mav::kOdometry, mav::encodePayload(m)));
      return;
    }
    mav::LocalPositionNed lp;
    lp.time_boot_ms = ms;
    lp.x = static_cast<float>(truth.p_N_m.x());
    lp.y = static_cast<float>(truth.p_N_m.y());
    lp.z = static_cast<float>(truth.p_N_m.z());
    lp.vx = static_cast<float>(truth.v_N_mps.x());
    lp.vy = static_cast<float>(truth.v_N_mps.y());
    lp.vz = static_cast<float>(truth.v_N_mps.z());
    sendBytes(frameOf(mav::kLocalPositionNed, mav::encodePayload(lp)));
    mav::Attitude at;
    at.time_boot_ms = ms;
    at.roll = static_cast<float>(truth.roll_rad);
    at.pitch = static_cast<float>(truth.pitch_rad);
    at.yaw = static_cast<float>(truth.yaw_rad);
    at.rollspeed = static_cast<float>(truth.w_F_radps.x());
    at.pitchspeed = static_cast<float>(truth.w_F_radps.y());
    at.yawspeed = static_cast<float>(truth.w_F_radps.z());
    sendBytes(frameOf(mav::kAttitude, mav::encodePayload(at)));
  }

  void receive(rt::TimeNs now_ns) {
    std::uint8_t buffer[2048];
    for (;;) {
      auto n = socket_.receive(buffer, sizeof(buffer));
      if (!n || !n->has_value()) return;
      for (const mav::Frame& f : parser_.feed(buffer, **n)) {
        sender_components.push_back(f.component_id);
        if (f.message_id == mav::kHeartbeat) {
          heartbeat_rx_ns.push_back(now_ns);
          heartbeats.push_back(mav::decodeHeartbeat(f.payload));
        } else if (f.message_id == mav::kSetPositionTargetLocalNed) {
          const auto sp = mav::decodeSetPositionTargetLocalNed(f.payload);
          if (sp.target_system != params_.system_id) continue;
          if (last_setpoint_ns_ < 0 || now_ns - last_setpoint_ns_ > rt::secondsToNs(0.5)) stream_start_ns_ = now_ns;
          last_setpoint_ns_ = now_ns;
          setpoint_ = sp;
          setpoint_rx_ns.push_back(now_ns);
          setpoints.push_back(sp);
        }
      }
      parser_.endOfDatagram();
    }
  }

  UdpSocket socket_;
  FakeAutopilotParams params_;
  mav::Parser parser_;
  std::uint8_t sequence_ = 0;
  bool silent_ = false;
  bool armed_ = true;
  std::uint32_t custom_mode_ = kPosctl;
  rt::TimeNs last_step_ns_ = -1;
  rt::TimeNs next_heartbeat_ns_ = -1;
  rt::TimeNs next_state_ns_ = -1;
  rt::TimeNs last_setpoint_ns_ = -1;
  rt::TimeNs stream_start_ns_ = -1;
  mav::SetPositionTargetLocalNed setpoint_;
};

}  // namespace aerotrack::hal::real::testing
