// The V4L2 cameras' shared capture logic: see frame_source.hpp.
#include "aerotrack/hal/real/frame_source.hpp"

#include <algorithm>
#include <cstdio>

namespace aerotrack::hal::real {

rt::Status V4l2FrameSource::open() {
  device_.reset();
  auto device = V4l2Device::open(path_, format_);
  if (!device) return device.error();
  device_.emplace(std::move(*device));
  return rt::ok();
}

rt::Expected<std::optional<RawFrame>> V4l2FrameSource::dequeue() {
  if (!device_) return rt::Error{path_ + ": not open"};
  auto frame = device_->dequeue();
  if (!frame) return frame.error();
  if (!frame->has_value()) return std::optional<RawFrame>{};
  const V4l2Frame& f = **frame;
  RawFrame raw;
  raw.data = f.data;
  raw.size_bytes = f.bytes_used;
  raw.sequence = f.sequence;
  if (f.timestamp_monotonic) raw.monotonic_ns = f.timestamp_ns;
  raw.skipped = f.skipped;
  return std::optional<RawFrame>{raw};
}

ReconnectingSource::ReconnectingSource(std::unique_ptr<FrameSource> source, const ReconnectParams& params,
                                       rt::TimeNs now_ns)
    : source_(std::move(source)), name_(source_->name()), params_(params), last_frame_ns_(now_ns) {}

rt::DurationNs ReconnectingSource::timeoutNs() const {
  const double timeout_s =
      awaiting_first_frame_ ? std::max(params_.frame_timeout_s, kFirstFrameGraceS) : params_.frame_timeout_s;
  return rt::secondsToNs(timeout_s);
}

void ReconnectingSource::lose(const std::string& reason, rt::TimeNs now_ns) {
  source_->close();
  open_ = false;
  next_attempt_ns_ = now_ns + rt::secondsToNs(params_.reconnect_period_s);
  last_device_sequence_.reset();
  const std::lock_guard<std::mutex> lock(mutex_);
  ++disconnects_;
  lost_reason_ = reason;
  reopen_error_.clear();
}

std::optional<CapturedFrame> ReconnectingSource::poll(rt::TimeNs now_ns) {
  if (!open_) {
    if (now_ns < next_attempt_ns_) return std::nullopt;
    next_attempt_ns_ = now_ns + rt::secondsToNs(params_.reconnect_period_s);
    if (rt::Status s = source_->open(); !s) {
      const std::lock_guard<std::mutex> lock(mutex_);
      reopen_error_ = s.error().message;
      return std::nullopt;
    }
    open_ = true;
    const std::lock_guard<std::mutex> lock(mutex_);
    lost_reason_.clear();
    reopen_error_.clear();
    last_frame_ns_ = now_ns;  // the timeout restarts with the stream
    awaiting_first_frame_ = true;
  }
  auto frame = source_->dequeue();
  if (!frame) {
    lose(frame.error().message, now_ns);
    return std::nullopt;
  }
  if (!frame->has_value()) {
    rt::TimeNs last_ns = 0;
    rt::DurationNs timeout_ns = 0;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      last_ns = last_frame_ns_;
      timeout_ns = timeoutNs();
    }
    if (now_ns - last_ns > timeout_ns) {
      lose(name_ + ": no frame for " + std::to_string((now_ns - last_ns) / rt::kNsPerMillisecond) + " ms", now_ns);
    }
    return std::nullopt;
  }
  CapturedFrame out;
  out.raw = **frame;
  // Frames the device dropped: the gap in its counter less the frames skipped here on purpose.
  std::uint64_t lost = 0;
  if (last_device_sequence_ && out.raw.sequence > *last_device_sequence_) {
    const std::uint64_t gap = out.raw.sequence - *last_device_sequence_ - 1;
    lost = gap > out.raw.skipped ? gap - out.raw.skipped : 0;
  }
  if (!last_device_sequence_ || out.raw.sequence <= *last_device_sequence_) {
    // First frame since a reopen, or the counter restarted: continue the output numbering. The very
    // first frame keeps the device's number (sequence_base_ stays 0).
    if (next_sequence_) sequence_base_ = *next_sequence_ - out.raw.sequence;  // unsigned wrap-around intended
  }
  last_device_sequence_ = out.raw.sequence;
  out.sequence = sequence_base_ + out.raw.sequence;
  next_sequence_ = out.sequence + 1;
  out.stamp_ns = out.raw.monotonic_ns.value_or(now_ns);

  const std::lock_guard<std::mutex> lock(mutex_);
  last_frame_ns_ = now_ns;
  awaiting_first_frame_ = false;
  if (!out.raw.monotonic_ns) stamps_from_poll_ = true;
  if (lost > 0) {
    dropped_ += lost;
    last_problem_ns_ = now_ns;
    any_problem_ = true;
  }
  return out;
}

void ReconnectingSource::noteCorrupt(const std::string& problem, rt::TimeNs now_ns) {
  const std::lock_guard<std::mutex> lock(mutex_);
  ++corrupt_;
  last_corrupt_ = problem;
  last_problem_ns_ = now_ns;
  any_problem_ = true;
}

void ReconnectingSource::noteDelivered(rt::TimeNs stamp_ns) {
  const std::lock_guard<std::mutex> lock(mutex_);
  last_stamp_ns_ = stamp_ns;
}

DeviceHealth ReconnectingSource::health(rt::TimeNs now_ns) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  DeviceHealth h;
  h.last_sample_ns = last_stamp_ns_;
  h.error_count = dropped_ + corrupt_ + disconnects_;
  const std::string& name = name_;
  const std::string stamps =
      stamps_from_poll_ ? "; stamps are poll times (the driver gives no monotonic buffer timestamps)" : "";
  const rt::DurationNs silent_ns = now_ns - last_frame_ns_;
  if (!lost_reason_.empty()) {
    h.state = DeviceHealth::State::kFailed;
    char period[32];
    std::snprintf(period, sizeof(period), "%.1f", params_.reconnect_period_s);
    h.detail = lost_reason_ + "; reopening every " + period + " s";
    if (!reopen_error_.empty()) h.detail += " (last: " + reopen_error_ + ")";
  } else if (silent_ns > timeoutNs()) {
    h.state = DeviceHealth::State::kFailed;
    h.detail = name + ": no frame for " + std::to_string(silent_ns / rt::kNsPerMillisecond) + " ms";
  } else if (any_problem_ && now_ns - last_problem_ns_ <= rt::secondsToNs(kDegradedHoldS)) {
    h.state = DeviceHealth::State::kDegraded;
    h.detail = name + ": " + std::to_string(dropped_) + " frames dropped by the device, " + std::to_string(corrupt_) +
               " undecodable" + (last_corrupt_.empty() ? "" : " (last: " + last_corrupt_ + ")") + stamps;
  } else {
    h.state = DeviceHealth::State::kOk;
    h.detail = name + ": streaming" + stamps;
  }
  return h;
}

}  // namespace aerotrack::hal::real
