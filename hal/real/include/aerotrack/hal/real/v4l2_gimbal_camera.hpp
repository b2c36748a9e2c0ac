// The gimbal camera on the drone (issue 11 item 1): a UVC camera read through V4L2, MJPG decoded with
// cv::imdecode or YUYV converted with cv::cvtColor, delivered as 8-bit BGR with the intrinsics of its
// calibration file (loaded by the caller, camera_calibration.hpp). Stamps, sequence gaps, the frame
// timeout, reconnect on unplug and health are ReconnectingSource's (frame_source.hpp); a frame that
// cannot be decoded is dropped and counted (degraded), never a crash.
//
// Thread safety: grab() from the one capture task (never blocks; it allocates the frame it
// returns); health() from any thread.
#pragma once

#include <memory>
#include <string>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/real/frame_source.hpp"

namespace aerotrack::hal::real {

struct V4l2GimbalCameraParams {
  std::string device = "/dev/video0";  ///< V4L2 node (or a udev symlink to it).
  int width_px = 640;
  int height_px = 480;
  double rate_hz = 30.0;
  std::string pixel_format = "MJPG";  ///< "MJPG" or "YUYV".
  CameraIntrinsics intrinsics;        ///< From the calibration file; its size must be width_px x height_px.
  double frame_timeout_s = 0.5;       ///< No frame this long: failed.
  double reconnect_period_s = 1.0;    ///< Reopen attempts while unplugged.
};

/// Checks the parameters; error: one line naming the parameter.
rt::Status validate(const V4l2GimbalCameraParams& params);

enum class RawImageFormat : std::uint8_t { kMjpg, kYuyv };

/// Decodes one raw frame to 8-bit BGR of the given size. Error (one line) if the bytes are not a
/// frame of that size: truncated or corrupt JPEG, short YUYV buffer.
rt::Expected<cv::Mat> decodeToBgr(const std::uint8_t* data, std::size_t size_bytes, RawImageFormat format, int width_px,
                                  int height_px);

class V4l2GimbalCamera final : public GimbalCamera {
 public:
  /// Opens the V4L2 device and starts streaming. Error: one line naming the device (a camera that
  /// is not there at start-up is an error, not a silent start).
  static rt::Expected<std::unique_ptr<V4l2GimbalCamera>> open(const V4l2GimbalCameraParams& params, rt::TimeNs now_ns);
  /// The same over any FrameSource (tests use a fake): opens it, with the same errors.
  static rt::Expected<std::unique_ptr<V4l2GimbalCamera>> open(std::unique_ptr<FrameSource> source,
                                                              const V4l2GimbalCameraParams& params, rt::TimeNs now_ns);

  std::string_view backend() const override { return "real"; }
  DeviceHealth health(rt::TimeNs now_ns) const override { return source_.health(now_ns); }
  ImageFrameHandle grab(rt::TimeNs now_ns) override;

 private:
  V4l2GimbalCamera(std::unique_ptr<FrameSource> source, const V4l2GimbalCameraParams& params, RawImageFormat format,
                   rt::TimeNs now_ns);

  V4l2GimbalCameraParams params_;
  RawImageFormat format_;
  ReconnectingSource source_;
};

}  // namespace aerotrack::hal::real
