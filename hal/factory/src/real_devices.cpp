// Real devices: see real_devices.hpp.
#include "real_devices.hpp"

#include <utility>

#include "aerotrack/hal/real/camera_calibration.hpp"
#include "aerotrack/hal/real/can_socket.hpp"
#include "aerotrack/hal/real/mavlink_vehicle.hpp"
#include "aerotrack/hal/real/rmd_gimbal.hpp"
#include "aerotrack/hal/real/v4l2_depth_camera.hpp"
#include "aerotrack/hal/real/v4l2_gimbal_camera.hpp"
#if AEROTRACK_HAVE_REALSENSE
#include "aerotrack/hal/real/realsense_depth_camera.hpp"
#endif

namespace aerotrack::hal {
namespace {

rt::Status makeGimbalCamera(const RealConfig& c, TimeNs start_ns, Devices& d) {
  auto calibration = real::loadCameraCalibration(c.gimbal_camera_calibration);
  if (!calibration) return rt::Error{"gimbal camera: " + calibration.error().message};
  real::V4l2GimbalCameraParams params = c.gimbal_camera;
  params.intrinsics = calibration->intrinsics;
  if (rt::Status s = real::validate(params); !s)
    return rt::Error{"gimbal camera " + params.device + ": " + s.error().message};
  auto camera = real::V4l2GimbalCamera::open(params, start_ns);
  if (!camera) return camera.error();
  d.gimbal_camera = std::move(camera.value());
  return rt::ok();
}

rt::Status makeDepthCamera(const RealConfig& c, TimeNs start_ns, Devices& d) {
  if (c.depth_driver == "realsense") {
#if AEROTRACK_HAVE_REALSENSE
    real::RealsenseDepthCameraParams params;
    params.serial = c.depth_camera.device == "auto" ? std::string() : c.depth_camera.device;
    params.width_px = c.depth_camera.width_px;
    params.height_px = c.depth_camera.height_px;
    params.rate_hz = static_cast<int>(c.depth_camera.rate_hz);
    params.T_BC = c.depth_camera.T_BC;
    params.min_range_m = c.depth_camera.min_range_m;
    params.max_range_m = c.depth_camera.max_range_m;
    params.frame_timeout_s = c.depth_camera.frame_timeout_s;
    params.reconnect_period_s = c.depth_camera.reconnect_period_s;
    auto camera = real::RealsenseDepthCamera::open(params, start_ns);
    if (!camera) return camera.error();
    d.depth_camera = std::move(camera.value());
    return rt::ok();
#else
    return rt::Error{
        "depth camera: driver realsense: this build has no librealsense2 (build with "
        "-DAEROTRACK_REALSENSE=ON where the SDK is installed, or use driver v4l2)"};
#endif
  }
  auto camera = real::V4l2DepthCamera::open(c.depth_camera, start_ns);
  if (!camera) return camera.error();
  d.depth_camera = std::move(camera.value());
  return rt::ok();
}

rt::Status makeGimbal(const RealConfig& c, Devices& d) {
  auto socket = real::CanSocket::open(c.can_interface);
  if (!socket) return rt::Error{"gimbal motor: " + socket.error().message};
  d.gimbal = std::make_unique<real::RmdGimbal>(std::move(socket.value()), c.gimbal);
  return rt::ok();
}

rt::Status makeFlightController(const HalConfig& config, Devices& d) {
  auto connection = real::MavlinkConnection::open(config.real.flight_controller);
  if (!connection) return rt::Error{"flight controller: " + connection.error().message};
  if (config.odometry == "real") d.odometry = std::make_unique<real::MavlinkOdometry>(*connection);
  if (config.vehicle_link == "real") d.vehicle_link = std::make_unique<real::MavlinkVehicleLink>(*connection);
  return rt::ok();
}

}  // namespace

rt::Status makeRealDevices(const HalConfig& config, TimeNs start_ns, Devices& d) {
  const RealDevices real = config.realDevices();
  if (real.gimbal_camera) {
    if (rt::Status s = makeGimbalCamera(config.real, start_ns, d); !s) return s;
  }
  if (real.depth_camera) {
    if (rt::Status s = makeDepthCamera(config.real, start_ns, d); !s) return s;
  }
  if (real.gimbal) {
    if (rt::Status s = makeGimbal(config.real, d); !s) return s;
  }
  if (real.flight_controller) {
    if (rt::Status s = makeFlightController(config, d); !s) return s;
  }
  return rt::ok();
}

}  // namespace aerotrack::hal
