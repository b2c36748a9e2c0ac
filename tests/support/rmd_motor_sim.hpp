// A simulated MyActuator RMD-X gimbal motor (protocol V4.2) for the driver's tests (issue 11 item 3):
// it sits on any socket that carries Linux's `struct can_frame` one per message -- one end of a
// socketpair, or a raw SocketCAN socket on vcan0 -- and answers the requests addressed to its
// identifier (0x140 + id) from 0x240 + id, as the motor does. Speed (0xA2) and absolute-position
// (0xA4) commands move its shaft when the test advances its time with serve(dt_s); 0x92 reads the
// multi-turn angle back in 0.01 deg; the watchdog (0xB3) and stop commands are answered. Frames for
// other identifiers are ignored (a bus carries other nodes), but kept for the test to inspect.
// Time is the test's: nothing here reads a clock, and awaitRequests() only bounds a wait.
// Header-only; one thread.
#pragma once

#include <gtest/gtest.h>
#include <linux/can.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <vector>

namespace aerotrack::test {

class RmdMotorSim {
 public:
  /// Takes ownership of fd. The motor starts at start_angle_cdeg (0.01 deg), standing still.
  explicit RmdMotorSim(int fd, int motor_id = 1, double start_angle_cdeg = 9000.0)
      : fd_(fd), motor_id_(motor_id), angle_cdeg_(start_angle_cdeg) {}
  ~RmdMotorSim() { ::close(fd_); }
  RmdMotorSim(const RmdMotorSim&) = delete;
  RmdMotorSim& operator=(const RmdMotorSim&) = delete;
  RmdMotorSim(RmdMotorSim&&) = delete;
  RmdMotorSim& operator=(RmdMotorSim&&) = delete;

  /// Waits until `count` requests to this motor are waiting to be served (a real bus delivers
  /// asynchronously); false if they have not arrived within timeout_ms.
  bool awaitRequests(std::size_t count, int timeout_ms) {
    take();
    for (int waited_ms = 0; pending_.size() < count && waited_ms < timeout_ms; waited_ms += kPollStepMs) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, kPollStepMs) > 0) take();
    }
    return pending_.size() >= count;
  }

  /// Moves for dt_s under the current command, then answers every request that has arrived.
  void serve(double dt_s) {
    move(dt_s);
    take();
    for (const can_frame& in : pending_) {
      if (!silent_) answer(in);
    }
    pending_.clear();
  }

  /// Writes one frame onto the bus as this motor's socket (any identifier, flags included).
  void inject(canid_t id, std::initializer_list<int> bytes) {
    can_frame f{};
    f.can_id = id;
    f.can_dlc = static_cast<std::uint8_t>(bytes.size());
    std::size_t i = 0;
    for (const int b : bytes) f.data[i++] = static_cast<std::uint8_t>(b);
    ASSERT_EQ(::write(fd_, &f, sizeof(f)), static_cast<ssize_t>(sizeof(f)));
  }

  /// Every request to this motor so far, in order of arrival.
  const std::vector<can_frame>& received() const { return received_; }
  /// Frames on the bus for other identifiers.
  const std::vector<can_frame>& others() const { return others_; }
  void setSilent(bool silent) { silent_ = silent; }
  double angleCdeg() const { return angle_cdeg_; }
  double speedCdps() const { return speed_cdps_; }

 private:
  static constexpr int kPollStepMs = 10;

  static std::int32_t getI32(const can_frame& f, int at) {
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | f.data[at + i];
    return static_cast<std::int32_t>(v);
  }
  static void putLe(can_frame& f, int at, int bytes, std::int64_t value) {
    for (int i = 0; i < bytes; ++i) f.data[at + i] = static_cast<std::uint8_t>((value >> (8 * i)) & 0xFF);
  }

  void take() {
    can_frame in{};
    while (::recv(fd_, &in, sizeof(in), MSG_DONTWAIT) == static_cast<ssize_t>(sizeof(in))) {
      if (in.can_id == 0x140U + static_cast<canid_t>(motor_id_)) {
        received_.push_back(in);
        pending_.push_back(in);
      } else {
        others_.push_back(in);
      }
    }
  }

  void move(double dt_s) {
    if (!positioning_) {
      angle_cdeg_ += speed_cdps_ * dt_s;
      return;
    }
    // Position mode: towards the target at the limit (0: no limit), standing still once there.
    const double error_cdeg = target_cdeg_ - angle_cdeg_;
    const double step_cdeg = max_speed_cdps_ > 0.0 ? max_speed_cdps_ * dt_s : std::abs(error_cdeg);
    if (std::abs(error_cdeg) <= step_cdeg) {
      angle_cdeg_ = target_cdeg_;
      speed_cdps_ = 0.0;
    } else {
      angle_cdeg_ += std::copysign(step_cdeg, error_cdeg);
      speed_cdps_ = std::copysign(max_speed_cdps_, error_cdeg);
    }
  }

  void answer(const can_frame& in) {
    can_frame out{};
    out.can_id = 0x240U + static_cast<canid_t>(motor_id_);
    out.can_dlc = 8;
    out.data[0] = in.data[0];
    switch (in.data[0]) {
      case 0xA2:  // speed, int32 0.01 deg/s
        positioning_ = false;
        speed_cdps_ = getI32(in, 4);
        feedback(out);
        break;
      case 0xA4:  // position: uint16 deg/s limit, int32 0.01 deg
        positioning_ = true;
        max_speed_cdps_ = 100.0 * (in.data[2] | (in.data[3] << 8));
        target_cdeg_ = getI32(in, 4);
        feedback(out);
        break;
      case 0x92:
        putLe(out, 4, 4, std::lround(angle_cdeg_));
        break;
      case 0x81:  // stop
        positioning_ = false;
        speed_cdps_ = 0.0;
        break;
      default:  // 0xB3 and the rest: the command echoed, zeros
        break;
    }
    ASSERT_EQ(::write(fd_, &out, sizeof(out)), static_cast<ssize_t>(sizeof(out)));
  }

  /// The reply to a motion command: temperature, iq, speed in whole deg/s, angle in whole degrees.
  void feedback(can_frame& out) const {
    out.data[1] = 30;
    putLe(out, 4, 2, std::lround(speed_cdps_ / 100.0));
    putLe(out, 6, 2, std::lround(angle_cdeg_ / 100.0));
  }

  int fd_;
  int motor_id_;
  double angle_cdeg_;
  double speed_cdps_ = 0.0;
  bool positioning_ = false;
  double target_cdeg_ = 0.0;
  double max_speed_cdps_ = 0.0;
  bool silent_ = false;
  std::vector<can_frame> received_;
  std::vector<can_frame> pending_;
  std::vector<can_frame> others_;
};

}  // namespace aerotrack::test
