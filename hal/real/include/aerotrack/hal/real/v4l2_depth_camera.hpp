// The depth camera on the drone (issue 11 item 2): an Intel RealSense D435 read without its SDK. The
// stock uvcvideo driver exposes the D435's depth stream as a V4L2 node with pixel format Z16 (16-bit
// depth units, 1 mm each unless the camera was told otherwise); this converts it to CV_32FC1 metres
// (0: no data, also for ranges outside [min_range_m, max_range_m]). Intrinsics come from a per-camera
// calibration file, calibration_dir/d435_<serial>.yaml, the serial read from sysfs, or from an
// explicit calibration_file. The D435 shows several nodes (depth, infrared, colour, metadata);
// device "auto" takes the first that offers Z16. Stamps, sequence gaps, frame timeout, reconnect
// and health are ReconnectingSource's (frame_source.hpp), shared with the gimbal camera.
//
// Thread safety: grab() from the one capture task (never blocks; allocates the frame it returns);
// health() from any thread.
#pragma once

#include <memory>
#include <string>

#include <Eigen/Geometry>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/real/camera_calibration.hpp"
#include "aerotrack/hal/real/frame_source.hpp"

namespace aerotrack::hal::real {

struct V4l2DepthCameraParams {
  std::string device = "auto";  ///< V4L2 node, or "auto": the first /dev/videoN offering Z16.
  int width_px = 640;
  int height_px = 480;
  double rate_hz = 30.0;
  /// Calibration: calibration_file if set, else calibration_dir/d435_<USB serial>.yaml. Its
  /// depth_scale_m (default 0.001) is the metres per Z16 unit.
  std::string calibration_dir;
  std::string calibration_file;
  Eigen::Isometry3d T_BC = Eigen::Isometry3d::Identity();  ///< Depth camera C (z forward) in body B.
  double min_range_m = 0.1;                                ///< Nearer: no data (the D435 reads ~0.2 m at its closest).
  double max_range_m = 10.0;                               ///< Farther: no data (noise grows with the square of range).
  double frame_timeout_s = 0.5;
  double reconnect_period_s = 1.0;
};

/// Checks the parameters; error: one line naming the parameter.
rt::Status validate(const V4l2DepthCameraParams& params);

/// Z16 (little-endian 16-bit units) to CV_32FC1 metres: unit * depth_scale_m, and 0 where the unit
/// is 0 (no data) or the range is outside [min_range_m, max_range_m]. Error if the buffer is short.
rt::Expected<cv::Mat> z16ToMetres(const std::uint8_t* data, std::size_t size_bytes, int width_px, int height_px,
                                  double depth_scale_m, double min_range_m, double max_range_m);

/// The depth frame of one captured Z16 frame (both D435 drivers: V4L2 and librealsense2): converted
/// with z16ToMetres, or nothing if it is short (counted in source as corrupt); delivered frames are
/// noted in source.
DepthFrameHandle depthFrameFromZ16(ReconnectingSource& source, const CapturedFrame& frame,
                                   const CameraIntrinsics& intrinsics, double depth_scale_m, double min_range_m,
                                   double max_range_m, const Eigen::Isometry3d& T_BC, rt::TimeNs now_ns);

class V4l2DepthCamera final : public DepthCamera {
 public:
  /// Finds the node ("auto"), loads the calibration (per serial) and starts streaming Z16. Error:
  /// one line naming the device or the calibration file.
  static rt::Expected<std::unique_ptr<V4l2DepthCamera>> open(const V4l2DepthCameraParams& params, rt::TimeNs now_ns);
  /// The same over any FrameSource with a calibration already loaded (tests use a fake).
  static rt::Expected<std::unique_ptr<V4l2DepthCamera>> open(std::unique_ptr<FrameSource> source,
                                                             const V4l2DepthCameraParams& params,
                                                             const CameraCalibration& calibration, rt::TimeNs now_ns);

  std::string_view backend() const override { return "real"; }
  DeviceHealth health(rt::TimeNs now_ns) const override { return source_.health(now_ns); }
  DepthFrameHandle grab(rt::TimeNs now_ns) override;

 private:
  V4l2DepthCamera(std::unique_ptr<FrameSource> source, const V4l2DepthCameraParams& params,
                  const CameraCalibration& calibration, rt::TimeNs now_ns);

  V4l2DepthCameraParams params_;
  CameraCalibration calibration_;
  ReconnectingSource source_;
};

}  // namespace aerotrack::hal::real
