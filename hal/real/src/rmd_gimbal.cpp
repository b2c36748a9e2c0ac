// RMD-X gimbal driver: see rmd_gimbal.hpp.
#include "aerotrack/hal/real/rmd_gimbal.hpp"

#include <linux/can/error.h>

#include <cmath>
#include <cstdio>
#include <numbers>

namespace aerotrack::hal::real {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

}  // namespace

void RmdGimbal::note(const std::string& problem, bool failure) {
  const std::lock_guard<std::mutex> lock(mutex_);
  ++problems_;
  if (first_problem_.empty()) first_problem_ = problem;
  if (failure) {
    failed_ = true;
    failure_ = problem;
  }
}

void RmdGimbal::send(const rt::Expected<protocol::rmd::CanFrame>& frame) {
  if (!frame) {
    note(frame.error().message, false);
    return;
  }
  if (rt::Status s = socket_.send(*frame); !s) note(s.error().message, false);
}

void RmdGimbal::command(const GimbalCommand& command) {
  const int id = params_.motor_id;
  if (command.mode == GimbalCommand::Mode::kRate) {
    send(protocol::rmd::speedCommand(id, params_.direction * command.rate_radps * kDegPerRad));
  } else {
    const double max_rate_radps =
        command.max_rate_radps > 0.0 ? command.max_rate_radps : params_.default_max_rate_radps;
    send(protocol::rmd::absolutePositionCommand(
        id, params_.direction * (command.angle_rad + params_.zero_offset_rad) * kDegPerRad,
        max_rate_radps * kDegPerRad));
  }
}

void RmdGimbal::drain(rt::TimeNs now_ns) {
  for (;;) {
    auto received = socket_.receive();
    if (!received) {
      note(received.error().message, true);
      return;
    }
    if (!received->has_value()) return;
    const CanReceived& r = **received;
    if (r.error) {
      const bool bus_off = (r.frame.id & CAN_ERR_BUSOFF) != 0;
      char bits[16];
      std::snprintf(bits, sizeof(bits), "0x%08X", static_cast<unsigned>(r.frame.id));
      note(socket_.name() + (bus_off ? ": bus-off" : std::string(": CAN error frame, class ") + bits), bus_off);
      continue;
    }
    if (r.remote) {  // a request for data, not data: whatever its bytes hold is no reading
      char id[16];
      std::snprintf(id, sizeof(id), "0x%03X", static_cast<unsigned>(r.frame.id));
      note(socket_.name() + ": remote frame " + id + " ignored", false);
      continue;
    }
    const auto reply = protocol::rmd::decodeReply(params_.motor_id, r.frame);
    if (!reply) {
      note(reply.error().message, false);  // another node's frame, or garbage: ignored
      continue;
    }
    last_reply_ns_.store(now_ns, std::memory_order_release);
    switch (reply->command) {
      case protocol::rmd::Command::kReadMultiTurnAngle: {
        const double motor_rad = reply->multi_turn_angle_deg / kDegPerRad;
        GimbalState s;
        s.stamp_ns = now_ns;  // the arrival: the motor's replies carry no time
        s.angle_rad = params_.direction * motor_rad - params_.zero_offset_rad;
        s.rate_radps = speed_radps_;
        state_ = s;
        break;
      }
      case protocol::rmd::Command::kSpeed:
      case protocol::rmd::Command::kAbsolutePosition:
        speed_radps_ = params_.direction * reply->feedback.speed_dps / kDegPerRad;
        break;
      default:
        break;
    }
  }
}

std::optional<GimbalState> RmdGimbal::read(rt::TimeNs now_ns) {
  if (!armed_) {
    armed_ = true;
    send(protocol::rmd::watchdogCommand(params_.motor_id, params_.watchdog_s));
  }
  drain(now_ns);
  send(protocol::rmd::readMultiTurnAngle(params_.motor_id));
  if (first_request_ns_ < 0) {
    first_request_ns_ = now_ns;
    first_request_seen_ns_.store(now_ns, std::memory_order_release);
  }
  return state_;
}

DeviceHealth RmdGimbal::health(rt::TimeNs now_ns) const {
  DeviceHealth h;
  const rt::TimeNs last_ns = last_reply_ns_.load(std::memory_order_acquire);
  const rt::TimeNs asked_ns = first_request_seen_ns_.load(std::memory_order_acquire);
  h.last_sample_ns = last_ns < 0 ? 0 : last_ns;
  const std::lock_guard<std::mutex> lock(mutex_);
  h.error_count = problems_;
  const std::string motor = socket_.name() + " motor " + std::to_string(params_.motor_id);
  const rt::TimeNs silent_since_ns = last_ns >= 0 ? last_ns : asked_ns;
  if (failed_) {
    h.state = DeviceHealth::State::kFailed;
    h.detail = failure_;
  } else if (silent_since_ns >= 0 && now_ns - silent_since_ns > rt::secondsToNs(params_.reply_timeout_s)) {
    h.state = DeviceHealth::State::kFailed;
    h.detail = motor + ": no reply for " + std::to_string((now_ns - silent_since_ns) / rt::kNsPerMillisecond) + " ms";
  } else if (problems_ > 0) {
    h.state = DeviceHealth::State::kDegraded;
    h.detail = motor + ": " + std::to_string(problems_) + " problems, the first: " + first_problem_;
  } else {
    h.state = DeviceHealth::State::kOk;
    h.detail = motor;
  }
  return h;
}

}  // namespace aerotrack::hal::real
