// Random views of the person for calibration: see calibration_views.hpp.
#include "aerotrack/hal/sim/calibration_views.hpp"

#include <cmath>
#include <numbers>

#include "aerotrack/hal/sim/keypoint_camera.hpp"

namespace aerotrack::hal::sim {

rt::Status validate(const CalibrationViewParams& p) {
  if (!(p.min_distance_m > 0.3 && p.max_distance_m >= p.min_distance_m))
    return rt::Error{"distance: need 0.3 < min_distance_m <= max_distance_m"};
  if (!(p.min_height_m > 0.0 && p.max_height_m >= p.min_height_m))
    return rt::Error{"height: need 0 < min_height_m <= max_height_m"};
  if (!(p.horizontal_fov_rad > 0.0 && p.horizontal_fov_rad < std::numbers::pi))
    return rt::Error{"horizontal_fov_rad: must be in (0, pi)"};
  if (!(p.fov_margin > 0.0 && p.fov_margin <= 1.0)) return rt::Error{"fov_margin: must be in (0, 1]"};
  return rt::ok();
}

CalibrationView sampleCalibrationView(const WalkingPerson& person, double walk_duration_s,
                                      const CalibrationViewParams& params, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto between = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  CalibrationView view;
  view.person = person.state(between(0.0, walk_duration_s));
  const double distance_m = between(params.min_distance_m, params.max_distance_m);
  const double around_rad = between(-std::numbers::pi, std::numbers::pi);  // where the camera stands
  const double height_m = between(params.min_height_m, params.max_height_m);
  const double half_fov_rad = 0.5 * params.horizontal_fov_rad * params.fov_margin;
  const double bearing_rad = between(-half_fov_rad, half_fov_rad);  // the person's bearing in the image

  const Eigen::Vector3d& p_WT = view.person.p_W_m;
  const Eigen::Vector3d camera_W(p_WT.x() + distance_m * std::cos(around_rad),
                                 p_WT.y() + distance_m * std::sin(around_rad), height_m);
  const double to_person_rad = std::atan2(p_WT.y() - camera_W.y(), p_WT.x() - camera_W.x());
  // A level camera whose forward axis is turned from the person by the bearing (left positive).
  const Eigen::Matrix3d R_W_flu =
      Eigen::AngleAxisd(to_person_rad - bearing_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  view.T_WC.linear() = R_W_flu * opticalAxesInFlu();
  view.T_WC.translation() = camera_W;
  view.p_C_flu_m = R_W_flu.transpose() * (p_WT - camera_W);
  return view;
}

}  // namespace aerotrack::hal::sim
