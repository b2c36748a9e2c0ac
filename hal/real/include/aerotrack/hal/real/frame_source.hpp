// What the V4L2 cameras share (issue 11 items 1 and 2): a FrameSource interface (open, non-blocking
// dequeue of the newest raw frame, close) that the V4L2 layer implements and tests fake, and
// ReconnectingSource, the one piece of logic both the gimbal camera and the depth camera run on top
// of it: timestamps, sequence gaps, frame timeout, reconnect on unplug, and health.
//
// Timestamps: a frame's stamp is the driver's buffer timestamp when the driver says it is on
// CLOCK_MONOTONIC (uvcvideo does; rt::MonotonicClock is that clock); otherwise the poll time now_ns
// is used, and the health detail says so. Reconnect: a dequeue error (the camera was unplugged) or
// no frame for frame_timeout_s closes the source, the health turns failed, and open() is retried
// every reconnect_period_s (time passed in) until it succeeds. Degraded: frames the device dropped
// (sequence gaps not explained by older frames skipped on purpose to return the newest) or frames
// that could not be decoded, within the last kDegradedHoldS seconds.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "aerotrack/hal/real/v4l2_device.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::real {

/// A raw frame as the device delivered it; data stays valid until the source's next dequeue() or close().
struct RawFrame {
  const std::uint8_t* data = nullptr;
  std::size_t size_bytes = 0;
  std::uint64_t sequence = 0;              ///< The device's counter; restarts on reopen.
  std::optional<rt::TimeNs> monotonic_ns;  ///< The device's CLOCK_MONOTONIC stamp, if it has one.
  std::uint32_t skipped = 0;               ///< Older frames passed over to return this newest one.
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// Opens the device and starts streaming. Error: one line naming the device.
  virtual rt::Status open() = 0;
  /// The newest frame not returned before, or nothing. Never blocks. Error: the device is gone.
  virtual rt::Expected<std::optional<RawFrame>> dequeue() = 0;
  virtual void close() = 0;
  /// The device, for messages ("/dev/video0").
  virtual const std::string& name() const = 0;
};

/// FrameSource over a V4L2 node (v4l2_device.hpp).
class V4l2FrameSource final : public FrameSource {
 public:
  V4l2FrameSource(std::string path, const V4l2Format& format) : path_(std::move(path)), format_(format) {}
  rt::Status open() override;
  rt::Expected<std::optional<RawFrame>> dequeue() override;
  void close() override { device_.reset(); }
  const std::string& name() const override { return path_; }
  /// The open device (nothing while closed), e.g. for its bus_info.
  const V4l2Device* device() const { return device_ ? &*device_ : nullptr; }

 private:
  std::string path_;
  V4l2Format format_;
  std::optional<V4l2Device> device_;
};

struct ReconnectParams {
  double frame_timeout_s = 0.5;     ///< No frame this long: failed (and the device is reopened).
  double reconnect_period_s = 1.0;  ///< Time between attempts to reopen a lost device.
};

/// A frame ready for decoding, with its stamp on the monotonic clock and a gap-free output sequence.
struct CapturedFrame {
  RawFrame raw;
  rt::TimeNs stamp_ns = 0;
  std::uint64_t sequence = 0;  ///< Continues across reconnects, so downstream sees no reset.
};

/// Reconnect, timeout and health logic shared by the V4L2 cameras. poll() and noteCorrupt() from the
/// owner task; health() from any thread. Allocates only when a problem's text is recorded.
class ReconnectingSource {
 public:
  /// How long a dropped or corrupt frame keeps the health degraded: long enough for a supervisor
  /// polling at 1 Hz to see it, short enough that one hiccup does not mark a whole flight.
  static constexpr double kDegradedHoldS = 2.0;
  /// The frame timeout before the first frame after a (re)open is at least this: some UVC cameras
  /// take a second after STREAMON while their auto exposure settles, and must not be reopened forever.
  static constexpr double kFirstFrameGraceS = 2.0;

  /// source must be open already (a camera missing at start-up is the caller's error); now_ns starts
  /// the frame timeout.
  ReconnectingSource(std::unique_ptr<FrameSource> source, const ReconnectParams& params, rt::TimeNs now_ns);

  /// Reopens when due, dequeues the newest frame, stamps and numbers it. Nothing if no new frame.
  std::optional<CapturedFrame> poll(rt::TimeNs now_ns);
  /// The frame poll() returned could not be decoded: counted, degraded, not delivered.
  void noteCorrupt(const std::string& problem, rt::TimeNs now_ns);
  /// The frame poll() returned was delivered with this stamp.
  void noteDelivered(rt::TimeNs stamp_ns);

  DeviceHealth health(rt::TimeNs now_ns) const;
  const FrameSource& source() const { return *source_; }

 private:
  void lose(const std::string& reason, rt::TimeNs now_ns);  // closes and schedules a reopen
  rt::DurationNs timeoutNs() const;                         // call with mutex_ held

  std::unique_ptr<FrameSource> source_;
  std::string name_;  // the source's, copied once: health() must not call into the source
  ReconnectParams params_;
  bool open_ = true;
  rt::TimeNs next_attempt_ns_ = 0;
  std::optional<std::uint64_t> last_device_sequence_;  // since the last (re)open
  std::optional<std::uint64_t> next_sequence_;         // output sequence of the next frame (none yet)
  std::uint64_t sequence_base_ = 0;                    // output = base + device sequence

  mutable std::mutex mutex_;        // guards the fields below (health() reads them from other threads)
  rt::TimeNs last_frame_ns_ = 0;    // poll time of the newest frame, or of the (re)open
  rt::TimeNs last_problem_ns_ = 0;  // newest drop or corrupt frame
  bool any_problem_ = false;
  rt::TimeNs last_stamp_ns_ = 0;  // stamp of the newest frame delivered
  std::uint64_t dropped_ = 0;
  std::uint64_t corrupt_ = 0;
  std::uint64_t disconnects_ = 0;
  std::string last_corrupt_;
  std::string lost_reason_;   // why the source is closed (empty while open)
  std::string reopen_error_;  // the last failed reopen
  bool stamps_from_poll_ = false;
  bool awaiting_first_frame_ = true;  // since the last (re)open
};

}  // namespace aerotrack::hal::real
