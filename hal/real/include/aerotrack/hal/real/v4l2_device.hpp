// V4L2 streaming capture (issue 11 items 1 and 2): the thin layer that does the ioctls, and nothing
// else, so that the camera logic above it (frame_source.hpp) can be tested without a camera. open()
// opens the node non-blocking, checks it is a capture device that streams (QUERYCAP), sets the pixel
// format (S_FMT: YUYV or MJPG for the gimbal camera, Z16 for the D435's depth node) and the frame
// rate (S_PARM), maps 4 buffers (REQBUFS, mmap), queues them and starts streaming. dequeue() never
// blocks: it drains the driver's filled buffers, keeps the newest, requeues the older ones and
// returns a view of the newest, valid until the next dequeue() (which requeues it).
//
// Timestamps: uvcvideo stamps buffers on CLOCK_MONOTONIC (V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC), the
// drone's rt::MonotonicClock; the view says whether the buffer's stamp is such a stamp. Errors are one
// line naming the device path; a vanished device (ENODEV, EIO) is "<path>: unplugged (...)".
// Thread safety: one owner thread.
#pragma once

#include <sys/time.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "aerotrack/rt/expected.hpp"
#include "aerotrack/rt/time.hpp"

namespace aerotrack::hal::real {

/// A V4L2 FourCC from its four characters ("YUYV", "MJPG", "Z16 "; "Z16" is padded with a space).
/// Error if the text is empty or longer than four characters.
rt::Expected<std::uint32_t> fourccFromString(std::string_view text);
/// The four characters of a FourCC ("Z16 ").
std::string fourccToString(std::uint32_t fourcc);

/// A kernel timeval (seconds, microseconds) in nanoseconds on the same clock.
inline constexpr rt::TimeNs timevalToNs(const timeval& tv) {
  return static_cast<rt::TimeNs>(tv.tv_sec) * rt::kNsPerSecond + static_cast<rt::TimeNs>(tv.tv_usec) * 1000;
}

struct V4l2Format {
  std::uint32_t fourcc = 0;
  int width_px = 640;
  int height_px = 480;
  double rate_hz = 30.0;
};

/// A filled buffer, valid until the next dequeue() or until the device is closed.
struct V4l2Frame {
  const std::uint8_t* data = nullptr;
  std::size_t bytes_used = 0;
  std::uint32_t sequence = 0;        ///< The driver's frame counter (gaps: frames it dropped).
  rt::TimeNs timestamp_ns = 0;       ///< The buffer's timestamp (see timestamp_monotonic).
  bool timestamp_monotonic = false;  ///< The driver says timestamp_ns is on CLOCK_MONOTONIC.
  std::uint32_t skipped = 0;         ///< Older filled buffers requeued unread to return this newest one.
};

class V4l2Device {
 public:
  /// Opens and starts streaming. Error: one line naming the path ("<path>: not a V4L2 capture
  /// device", "<path>: cannot open: No such file or directory", a refused format ...).
  static rt::Expected<V4l2Device> open(const std::string& path, const V4l2Format& format);

  V4l2Device(V4l2Device&& other) noexcept;
  V4l2Device& operator=(V4l2Device&& other) noexcept;
  V4l2Device(const V4l2Device&) = delete;
  V4l2Device& operator=(const V4l2Device&) = delete;
  ~V4l2Device();

  /// The newest filled buffer, or nothing if none is ready. Never blocks.
  rt::Expected<std::optional<V4l2Frame>> dequeue();

  const std::string& path() const { return path_; }
  /// What the driver accepted (it may adjust the size and rate it was asked for).
  const V4l2Format& format() const { return format_; }
  /// VIDIOC_QUERYCAP's card name and bus_info ("usb-0000:00:14.0-2").
  const std::string& card() const { return card_; }
  const std::string& busInfo() const { return bus_info_; }

 private:
  struct Mapping {
    void* start = nullptr;
    std::size_t length = 0;
  };
  V4l2Device(int fd, std::string path) : fd_(fd), path_(std::move(path)) {}
  void release();
  rt::Status requeue(std::uint32_t index);
  rt::Error ioctlError(const char* what, int error) const;

  int fd_ = -1;
  std::string path_;
  V4l2Format format_;
  std::string card_;
  std::string bus_info_;
  std::vector<Mapping> buffers_;
  std::optional<std::uint32_t> held_;  // index of the buffer last returned, requeued on the next dequeue
  bool streaming_ = false;
};

/// The pixel formats a capture node offers (VIDIOC_ENUM_FMT). Error: one line naming the path.
rt::Expected<std::vector<std::uint32_t>> listPixelFormats(const std::string& path);
/// The first /dev/videoN (N = 0..63, in order) whose formats include fourcc, e.g. the D435's depth
/// node among its depth, infrared, colour and metadata nodes. Error if none.
rt::Expected<std::string> findVideoNodeWithFormat(std::uint32_t fourcc, const std::string& dev_dir = "/dev");

}  // namespace aerotrack::hal::real
