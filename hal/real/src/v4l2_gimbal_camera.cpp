// The gimbal camera over V4L2: see v4l2_gimbal_camera.hpp.
#include "aerotrack/hal/real/v4l2_gimbal_camera.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <limits>
#include <span>

#include "aerotrack/hal/image_decode.hpp"

namespace aerotrack::hal::real {
namespace {

rt::Expected<RawImageFormat> rawFormat(const std::string& name) {
  if (name == "MJPG") return RawImageFormat::kMjpg;
  if (name == "YUYV") return RawImageFormat::kYuyv;
  return rt::Error{"gimbal camera: pixel_format '" + name + "': expected MJPG or YUYV"};
}

}  // namespace

rt::Status validate(const V4l2GimbalCameraParams& params) {
  const std::string where = "gimbal camera " + params.device + ": ";
  if (params.device.empty()) return rt::Error{"gimbal camera: device is empty"};
  if (params.width_px < 1 || params.width_px > 16384 || params.height_px < 1 || params.height_px > 16384)
    return rt::Error{where + "width_px and height_px must be in [1, 16384]"};
  if (params.width_px % 2 != 0) return rt::Error{where + "width_px must be even (YUYV packs pixel pairs)"};
  if (!(params.rate_hz > 0.0 && params.rate_hz <= 1000.0)) return rt::Error{where + "rate_hz must be in (0, 1000]"};
  if (auto f = rawFormat(params.pixel_format); !f) return rt::Error{where + "pixel_format must be MJPG or YUYV"};
  if (params.intrinsics.width_px != params.width_px || params.intrinsics.height_px != params.height_px)
    return rt::Error{where + "the calibration is for " + std::to_string(params.intrinsics.width_px) + "x" +
                     std::to_string(params.intrinsics.height_px) + ", the camera is set to " +
                     std::to_string(params.width_px) + "x" + std::to_string(params.height_px)};
  if (!(params.intrinsics.fx_px > 0.0 && params.intrinsics.fy_px > 0.0))
    return rt::Error{where + "the calibration's fx_px and fy_px must be positive"};
  if (!(params.frame_timeout_s > 0.0 && std::isfinite(params.frame_timeout_s)))
    return rt::Error{where + "frame_timeout_s must be positive"};
  if (!(params.reconnect_period_s > 0.0 && std::isfinite(params.reconnect_period_s)))
    return rt::Error{where + "reconnect_period_s must be positive"};
  return rt::ok();
}

rt::Expected<cv::Mat> decodeToBgr(const std::uint8_t* data, std::size_t size_bytes, RawImageFormat format, int width_px,
                                  int height_px) {
  if (format == RawImageFormat::kYuyv) {
    const std::size_t expected = static_cast<std::size_t>(width_px) * static_cast<std::size_t>(height_px) * 2;
    if (size_bytes < expected)
      return rt::Error{"YUYV frame of " + std::to_string(size_bytes) + " bytes, expected " + std::to_string(expected)};
    // cvtColor reads the driver's buffer through this header without copying it.
    const cv::Mat yuyv(height_px, width_px, CV_8UC2, const_cast<std::uint8_t*>(data));  // NOLINT: read only
    cv::Mat bgr;
    cv::cvtColor(yuyv, bgr, cv::COLOR_YUV2BGR_YUYV);
    return bgr;
  }
  if (size_bytes < 4 || size_bytes > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    return rt::Error{"MJPG frame of " + std::to_string(size_bytes) + " bytes"};
  // A frame cut short by the USB transfer, or garbled, is refused: libjpeg would fill the missing
  // rows with grey and only warn (image_decode.hpp). uvcvideo's padding after EOI is tolerated.
  auto decoded = decodeImage(std::span<const std::uint8_t>(data, size_bytes), cv::IMREAD_COLOR);
  if (!decoded) return rt::Error{"MJPG frame of " + std::to_string(size_bytes) + " bytes: " + decoded.error().message};
  const cv::Mat bgr = std::move(decoded.value());
  if (bgr.cols != width_px || bgr.rows != height_px)
    return rt::Error{"MJPG frame is " + std::to_string(bgr.cols) + "x" + std::to_string(bgr.rows) + ", expected " +
                     std::to_string(width_px) + "x" + std::to_string(height_px)};
  return bgr;
}

V4l2GimbalCamera::V4l2GimbalCamera(std::unique_ptr<FrameSource> source, const V4l2GimbalCameraParams& params,
                                   RawImageFormat format, rt::TimeNs now_ns)
    : params_(params),
      format_(format),
      source_(std::move(source), ReconnectParams{params.frame_timeout_s, params.reconnect_period_s}, now_ns) {}

rt::Expected<std::unique_ptr<V4l2GimbalCamera>> V4l2GimbalCamera::open(const V4l2GimbalCameraParams& params,
                                                                       rt::TimeNs now_ns) {
  if (rt::Status s = validate(params); !s) return s.error();
  V4l2Format format;
  format.fourcc = *fourccFromString(params.pixel_format);
  format.width_px = params.width_px;
  format.height_px = params.height_px;
  format.rate_hz = params.rate_hz;
  return open(std::make_unique<V4l2FrameSource>(params.device, format), params, now_ns);
}

rt::Expected<std::unique_ptr<V4l2GimbalCamera>> V4l2GimbalCamera::open(std::unique_ptr<FrameSource> source,
                                                                       const V4l2GimbalCameraParams& params,
                                                                       rt::TimeNs now_ns) {
  if (rt::Status s = validate(params); !s) return s.error();
  if (rt::Status s = source->open(); !s) return rt::Error{"gimbal camera: " + s.error().message};
  const RawImageFormat format = *rawFormat(params.pixel_format);
  return std::unique_ptr<V4l2GimbalCamera>(new V4l2GimbalCamera(std::move(source), params, format, now_ns));
}

ImageFrameHandle V4l2GimbalCamera::grab(rt::TimeNs now_ns) {
  const std::optional<CapturedFrame> frame = source_.poll(now_ns);
  if (!frame) return {};
  auto bgr = decodeToBgr(frame->raw.data, frame->raw.size_bytes, format_, params_.width_px, params_.height_px);
  if (!bgr) {
    source_.noteCorrupt(bgr.error().message, now_ns);
    return {};
  }
  auto out = std::make_shared<ImageFrame>();
  out->stamp_ns = frame->stamp_ns;
  out->sequence = frame->sequence;
  out->bgr = std::move(*bgr);
  out->intrinsics = params_.intrinsics;
  source_.noteDelivered(out->stamp_ns);
  return out;
}

}  // namespace aerotrack::hal::real
