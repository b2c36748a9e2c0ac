// The D435 through librealsense2 (issue 11 item 2), for a drone that has the SDK; built only when
// CMake finds realsense2 (-DAEROTRACK_REALSENSE=AUTO|ON|OFF, see hal/real/CMakeLists.txt), and the
// factory offers it only when AEROTRACK_HAVE_REALSENSE is ON. Without the SDK, V4l2DepthCamera reads
// the same depth stream through uvcvideo.
//
// An rs2::pipeline streams depth only (Z16, 640x480 at 30 Hz by default); intrinsics and the depth
// scale come from the SDK (the camera's own calibration), not from a file. Frames are converted with
// z16ToMetres and go through ReconnectingSource like the V4L2 cameras (timeout, reopen every
// reconnect_period_s, health).
//
// Timestamps: the sensor's RS2_OPTION_GLOBAL_TIME_ENABLED is switched on where supported; a frame in
// RS2_TIMESTAMP_DOMAIN_GLOBAL_TIME carries the camera's hardware stamp mapped by the SDK onto the
// host's system clock (CLOCK_REALTIME, ms). It is moved onto CLOCK_MONOTONIC with the offset between
// the two clocks read back to back when the frame is taken (the wall clock is read here because the
// SDK's stamp is on it; an NTP step between exposure and poll shifts that one frame). Frames in any
// other domain (the SDK fell back to the hardware clock or to an unspecified host stamp) get the
// poll time, which the health detail reports. Thread safety: grab() from one task; health() from any.
#pragma once

#include <memory>
#include <string>

#include <Eigen/Geometry>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/real/frame_source.hpp"

namespace aerotrack::hal::real {

struct RealsenseDepthCameraParams {
  std::string serial;  ///< The camera's serial number; empty: the first RealSense found.
  int width_px = 640;
  int height_px = 480;
  int rate_hz = 30;  ///< The SDK takes integer frame rates (6, 15, 30, 60, 90 for the D435).
  Eigen::Isometry3d T_BC = Eigen::Isometry3d::Identity();  ///< Depth camera C (z forward) in body B.
  double min_range_m = 0.1;
  double max_range_m = 10.0;
  double frame_timeout_s = 0.5;
  double reconnect_period_s = 1.0;
};

rt::Status validate(const RealsenseDepthCameraParams& params);

class RealsenseDepthCamera final : public DepthCamera {
 public:
  /// Starts the pipeline. Error: one line naming the camera ("RealSense 841512070123: ...").
  static rt::Expected<std::unique_ptr<RealsenseDepthCamera>> open(const RealsenseDepthCameraParams& params,
                                                                  rt::TimeNs now_ns);

  std::string_view backend() const override { return "real"; }
  DeviceHealth health(rt::TimeNs now_ns) const override { return source_.health(now_ns); }
  DepthFrameHandle grab(rt::TimeNs now_ns) override;

 private:
  RealsenseDepthCamera(std::unique_ptr<FrameSource> source, const RealsenseDepthCameraParams& params,
                       const CameraIntrinsics& intrinsics, double depth_scale_m, rt::TimeNs now_ns);

  RealsenseDepthCameraParams params_;
  CameraIntrinsics intrinsics_;
  double depth_scale_m_;
  ReconnectingSource source_;
};

}  // namespace aerotrack::hal::real
