// The gimbal motor on the drone (issue 11 item 3): a MyActuator RMD-X on CAN, driven with the codec of
// hal/protocol/rmd.hpp over a CanSocket. Rate commands become speed frames (0xA2), angle commands
// absolute-position frames (0xA4); every read() asks for the multi-turn angle (0x92, 0.01 deg) and
// takes in what has arrived since: angles, the speed in the motors' feedback, and error frames. The
// first call arms the motor's communication watchdog (0xB3), so the motor stops by itself if this
// computer goes silent.
//
// Health: failed on bus-off, on a socket error, or when the motor has not answered for
// reply_timeout_s; degraded when stray or undecodable frames or CAN error frames arrived (counted, the
// first named), or a send was refused. Thread safety: command() and read() from the one owner task;
// health() from any thread.
#pragma once

#include <atomic>
#include <mutex>
#include <optional>
#include <string>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/real/can_socket.hpp"

namespace aerotrack::hal::real {

struct RmdGimbalParams {
  int motor_id = 1;                     ///< 1..32 (the motor's CAN id)
  double reply_timeout_s = 0.1;         ///< No answer this long: the device has failed.
  double watchdog_s = 0.2;              ///< The motor's own communication-loss stop; 0: off.
  double default_max_rate_radps = 6.0;  ///< Angle commands with max_rate_radps 0.
  double direction = 1.0;               ///< +1: motor positive turns the camera left (about body z); -1: right.
  double zero_offset_rad = 0.0;         ///< Camera angle = direction * motor angle - this (rad).
};

class RmdGimbal final : public Gimbal {
 public:
  RmdGimbal(CanSocket socket, const RmdGimbalParams& params) : socket_(std::move(socket)), params_(params) {}
  std::string_view backend() const override { return "real"; }
  DeviceHealth health(rt::TimeNs now_ns) const override;
  void command(const GimbalCommand& command) override;
  std::optional<GimbalState> read(rt::TimeNs now_ns) override;

 private:
  void note(const std::string& problem, bool failure);  // counts a problem; the first is kept
  void send(const rt::Expected<protocol::rmd::CanFrame>& frame);
  void drain(rt::TimeNs now_ns);

  CanSocket socket_;
  RmdGimbalParams params_;
  bool armed_ = false;
  rt::TimeNs first_request_ns_ = -1;
  std::optional<GimbalState> state_;
  double speed_radps_ = 0.0;
  std::atomic<rt::TimeNs> last_reply_ns_{-1};
  std::atomic<rt::TimeNs> first_request_seen_ns_{-1};
  mutable std::mutex mutex_;  // guards the fields below (health() reads them from other threads)
  bool failed_ = false;
  std::uint64_t problems_ = 0;
  std::string first_problem_;
  std::string failure_;
};

}  // namespace aerotrack::hal::real
