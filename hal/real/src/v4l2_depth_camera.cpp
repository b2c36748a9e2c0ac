// The D435's depth stream over V4L2: see v4l2_depth_camera.hpp.
#include "aerotrack/hal/real/v4l2_depth_camera.hpp"

#include <linux/videodev2.h>

#include <cmath>
#include <cstring>

namespace aerotrack::hal::real {

rt::Status validate(const V4l2DepthCameraParams& params) {
  const std::string where = "depth camera " + params.device + ": ";
  if (params.device.empty()) return rt::Error{"depth camera: device is empty (a path or auto)"};
  if (params.width_px < 1 || params.width_px > 16384 || params.height_px < 1 || params.height_px > 16384)
    return rt::Error{where + "width_px and height_px must be in [1, 16384]"};
  if (!(params.rate_hz > 0.0 && params.rate_hz <= 1000.0)) return rt::Error{where + "rate_hz must be in (0, 1000]"};
  if (params.calibration_dir.empty() && params.calibration_file.empty())
    return rt::Error{where + "set calibration_dir or calibration_file"};
  if (!(params.min_range_m >= 0.0 && params.max_range_m > params.min_range_m && std::isfinite(params.max_range_m)))
    return rt::Error{where + "need 0 <= min_range_m < max_range_m"};
  if (!(params.frame_timeout_s > 0.0 && std::isfinite(params.frame_timeout_s)))
    return rt::Error{where + "frame_timeout_s must be positive"};
  if (!(params.reconnect_period_s > 0.0 && std::isfinite(params.reconnect_period_s)))
    return rt::Error{where + "reconnect_period_s must be positive"};
  return rt::ok();
}

rt::Expected<cv::Mat> z16ToMetres(const std::uint8_t* data, std::size_t size_bytes, int width_px, int height_px,
                                  double depth_scale_m, double min_range_m, double max_range_m) {
  const std::size_t pixels = static_cast<std::size_t>(width_px) * static_cast<std::size_t>(height_px);
  if (size_bytes < pixels * 2)
    return rt::Error{"Z16 frame of " + std::to_string(size_bytes) + " bytes, expected " + std::to_string(pixels * 2)};
  cv::Mat depth_m(height_px, width_px, CV_32FC1);
  auto* out = depth_m.ptr<float>(0);  // a freshly allocated Mat is continuous
  for (std::size_t i = 0; i < pixels; ++i) {
    const auto unit = static_cast<std::uint16_t>(data[2 * i] | (data[2 * i + 1] << 8U));  // little-endian
    const double range_m = unit * depth_scale_m;
    out[i] = (unit == 0 || range_m < min_range_m || range_m > max_range_m) ? 0.0F : static_cast<float>(range_m);
  }
  return depth_m;
}

V4l2DepthCamera::V4l2DepthCamera(std::unique_ptr<FrameSource> source, const V4l2DepthCameraParams& params,
                                 const CameraCalibration& calibration, rt::TimeNs now_ns)
    : params_(params),
      calibration_(calibration),
      source_(std::move(source), ReconnectParams{params.frame_timeout_s, params.reconnect_period_s}, now_ns) {}

rt::Expected<std::unique_ptr<V4l2DepthCamera>> V4l2DepthCamera::open(const V4l2DepthCameraParams& params,
                                                                     rt::TimeNs now_ns) {
  if (rt::Status s = validate(params); !s) return s.error();
  std::string path = params.device;
  if (path == "auto") {
    auto found = findVideoNodeWithFormat(V4L2_PIX_FMT_Z16);
    if (!found) return rt::Error{"depth camera: " + found.error().message};
    path = *found;
  }
  std::string calibration_path = params.calibration_file;
  if (calibration_path.empty()) {
    auto serial = usbSerialOfVideoNode(path);
    if (!serial) return rt::Error{"depth camera: " + serial.error().message};
    calibration_path = depthCalibrationPath(params.calibration_dir, *serial);
  }
  auto calibration = loadCameraCalibration(calibration_path);
  if (!calibration) return rt::Error{"depth camera " + path + ": " + calibration.error().message};
  V4l2Format format;
  format.fourcc = V4L2_PIX_FMT_Z16;
  format.width_px = params.width_px;
  format.height_px = params.height_px;
  format.rate_hz = params.rate_hz;
  V4l2DepthCameraParams resolved = params;
  resolved.device = path;
  return open(std::make_unique<V4l2FrameSource>(path, format), resolved, *calibration, now_ns);
}

rt::Expected<std::unique_ptr<V4l2DepthCamera>> V4l2DepthCamera::open(std::unique_ptr<FrameSource> source,
                                                                     const V4l2DepthCameraParams& params,
                                                                     const CameraCalibration& calibration,
                                                                     rt::TimeNs now_ns) {
  if (rt::Status s = validate(params); !s) return s.error();
  const CameraIntrinsics& k = calibration.intrinsics;
  if (k.width_px != params.width_px || k.height_px != params.height_px)
    return rt::Error{"depth camera " + source->name() + ": the calibration is for " + std::to_string(k.width_px) + "x" +
                     std::to_string(k.height_px) + ", the camera is set to " + std::to_string(params.width_px) + "x" +
                     std::to_string(params.height_px)};
  if (rt::Status s = source->open(); !s) return rt::Error{"depth camera: " + s.error().message};
  return std::unique_ptr<V4l2DepthCamera>(new V4l2DepthCamera(std::move(source), params, calibration, now_ns));
}

DepthFrameHandle depthFrameFromZ16(ReconnectingSource& source, const CapturedFrame& frame,
                                   const CameraIntrinsics& intrinsics, double depth_scale_m, double min_range_m,
                                   double max_range_m, const Eigen::Isometry3d& T_BC, rt::TimeNs now_ns) {
  auto depth_m = z16ToMetres(frame.raw.data, frame.raw.size_bytes, intrinsics.width_px, intrinsics.height_px,
                             depth_scale_m, min_range_m, max_range_m);
  if (!depth_m) {
    source.noteCorrupt(depth_m.error().message, now_ns);
    return {};
  }
  auto out = std::make_shared<DepthFrame>();
  out->stamp_ns = frame.stamp_ns;
  out->sequence = frame.sequence;
  out->depth_m = std::move(*depth_m);
  out->intrinsics = intrinsics;
  out->T_BC = T_BC;
  source.noteDelivered(out->stamp_ns);
  return out;
}

DepthFrameHandle V4l2DepthCamera::grab(rt::TimeNs now_ns) {
  const std::optional<CapturedFrame> frame = source_.poll(now_ns);
  if (!frame) return {};
  return depthFrameFromZ16(source_, *frame, calibration_.intrinsics, calibration_.depth_scale_m, params_.min_range_m,
                           params_.max_range_m, params_.T_BC, now_ns);
}

}  // namespace aerotrack::hal::real
