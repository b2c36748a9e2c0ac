// The D435 through librealsense2: see realsense_depth_camera.hpp. Built only with the SDK.
#include "aerotrack/hal/real/realsense_depth_camera.hpp"

#include <librealsense2/rs.hpp>

#include <cmath>
#include <ctime>
#include <exception>

#include "aerotrack/hal/real/v4l2_depth_camera.hpp"

namespace aerotrack::hal::real {
namespace {

rt::TimeNs clockNs(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<rt::TimeNs>(ts.tv_sec) * rt::kNsPerSecond + ts.tv_nsec;
}

/// An SDK stamp on the system clock (ms since the epoch) moved onto CLOCK_MONOTONIC.
rt::TimeNs systemMsToMonotonicNs(double system_ms) {
  const rt::TimeNs realtime_ns = clockNs(CLOCK_REALTIME);
  const rt::TimeNs monotonic_ns = clockNs(CLOCK_MONOTONIC);
  return std::llround(system_ms * 1e6) + (monotonic_ns - realtime_ns);
}

/// FrameSource over an rs2::pipeline streaming depth only. The frame last returned is held, so the
/// RawFrame's bytes stay valid until the next dequeue() or close().
class RealsenseFrameSource final : public FrameSource {
 public:
  explicit RealsenseFrameSource(const RealsenseDepthCameraParams& params)
      : name_("RealSense " + (params.serial.empty() ? std::string("(first found)") : params.serial)) {
    if (!params.serial.empty()) config_.enable_device(params.serial);
    config_.enable_stream(RS2_STREAM_DEPTH, params.width_px, params.height_px, RS2_FORMAT_Z16, params.rate_hz);
  }
  ~RealsenseFrameSource() override { close(); }
  RealsenseFrameSource(const RealsenseFrameSource&) = delete;
  RealsenseFrameSource& operator=(const RealsenseFrameSource&) = delete;

  rt::Status open() override {
    close();
    try {
      const rs2::pipeline_profile profile = pipeline_.start(config_);
      started_ = true;
      const rs2::device device = profile.get_device();
      if (device.supports(RS2_CAMERA_INFO_SERIAL_NUMBER))
        name_ = std::string("RealSense ") + device.get_info(RS2_CAMERA_INFO_SERIAL_NUMBER);
      rs2::depth_sensor sensor = device.first<rs2::depth_sensor>();
      if (sensor.supports(RS2_OPTION_GLOBAL_TIME_ENABLED)) sensor.set_option(RS2_OPTION_GLOBAL_TIME_ENABLED, 1.0F);
      depth_scale_m_ = sensor.get_depth_scale();
      const rs2_intrinsics k = profile.get_stream(RS2_STREAM_DEPTH).as<rs2::video_stream_profile>().get_intrinsics();
      intrinsics_.width_px = k.width;
      intrinsics_.height_px = k.height;
      intrinsics_.fx_px = k.fx;
      intrinsics_.fy_px = k.fy;
      intrinsics_.cx_px = k.ppx;
      intrinsics_.cy_px = k.ppy;
      // The depth stream is rectified: its model is "none" or Brown-Conrady with zero coefficients.
      for (std::size_t i = 0; i < 5; ++i) intrinsics_.distortion.at(i) = k.coeffs[i];
    } catch (const std::exception& e) {
      close();
      return rt::Error{name_ + ": cannot start the depth stream: " + e.what()};
    }
    return rt::ok();
  }

  rt::Expected<std::optional<RawFrame>> dequeue() override {
    if (!started_) return rt::Error{name_ + ": not started"};
    try {
      rs2::frameset frames;
      if (!pipeline_.poll_for_frames(&frames)) return std::optional<RawFrame>{};
      rs2::depth_frame depth = frames.get_depth_frame();
      if (!depth) return std::optional<RawFrame>{};
      held_ = depth;
      RawFrame raw;
      raw.data = static_cast<const std::uint8_t*>(depth.get_data());
      raw.size_bytes = static_cast<std::size_t>(depth.get_data_size());
      raw.sequence = depth.get_frame_number();
      if (depth.get_frame_timestamp_domain() == RS2_TIMESTAMP_DOMAIN_GLOBAL_TIME)
        raw.monotonic_ns = systemMsToMonotonicNs(depth.get_timestamp());
      return std::optional<RawFrame>{raw};
    } catch (const std::exception& e) {
      return rt::Error{name_ + ": unplugged or failed (" + e.what() + ")"};
    }
  }

  void close() override {
    held_ = rs2::frame();
    if (!started_) return;
    started_ = false;
    try {
      pipeline_.stop();
    } catch (const std::exception&) {
      // stopping a pipeline whose camera is gone may throw; it is stopped either way
    }
  }

  const std::string& name() const override { return name_; }
  const CameraIntrinsics& intrinsics() const { return intrinsics_; }
  double depthScaleM() const { return depth_scale_m_; }

 private:
  std::string name_;
  rs2::config config_;
  rs2::pipeline pipeline_;
  rs2::frame held_;
  bool started_ = false;
  CameraIntrinsics intrinsics_;
  double depth_scale_m_ = 0.001;
};

}  // namespace

rt::Status validate(const RealsenseDepthCameraParams& params) {
  const std::string where = "RealSense " + params.serial + ": ";
  if (params.width_px < 1 || params.height_px < 1) return rt::Error{where + "width_px and height_px must be positive"};
  if (params.rate_hz < 1 || params.rate_hz > 300) return rt::Error{where + "rate_hz must be in [1, 300]"};
  if (!(params.min_range_m >= 0.0 && params.max_range_m > params.min_range_m && std::isfinite(params.max_range_m)))
    return rt::Error{where + "need 0 <= min_range_m < max_range_m"};
  if (!(params.frame_timeout_s > 0.0) || !(params.reconnect_period_s > 0.0))
    return rt::Error{where + "frame_timeout_s and reconnect_period_s must be positive"};
  return rt::ok();
}

RealsenseDepthCamera::RealsenseDepthCamera(std::unique_ptr<FrameSource> source,
                                           const RealsenseDepthCameraParams& params, const CameraIntrinsics& intrinsics,
                                           double depth_scale_m, rt::TimeNs now_ns)
    : params_(params),
      intrinsics_(intrinsics),
      depth_scale_m_(depth_scale_m),
      source_(std::move(source), ReconnectParams{params.frame_timeout_s, params.reconnect_period_s}, now_ns) {}

rt::Expected<std::unique_ptr<RealsenseDepthCamera>> RealsenseDepthCamera::open(const RealsenseDepthCameraParams& params,
                                                                               rt::TimeNs now_ns) {
  if (rt::Status s = validate(params); !s) return s.error();
  auto source = std::make_unique<RealsenseFrameSource>(params);
  if (rt::Status s = source->open(); !s) return s.error();
  const CameraIntrinsics intrinsics = source->intrinsics();
  const double depth_scale_m = source->depthScaleM();
  return std::unique_ptr<RealsenseDepthCamera>(
      new RealsenseDepthCamera(std::move(source), params, intrinsics, depth_scale_m, now_ns));
}

DepthFrameHandle RealsenseDepthCamera::grab(rt::TimeNs now_ns) {
  const std::optional<CapturedFrame> frame = source_.poll(now_ns);
  if (!frame) return {};
  return depthFrameFromZ16(source_, *frame, intrinsics_, depth_scale_m_, params_.min_range_m, params_.max_range_m,
                           params_.T_BC, now_ns);
}

}  // namespace aerotrack::hal::real
