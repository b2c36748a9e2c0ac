// Gimbal control (issue 9 item 1; paper Sect. III-B, active vision): a 1-DOF yaw gimbal that can spin
// forever keeps the followed person at the centre of the image horizontally.
//  - Error: the person's horizontal image error, as an angle: between the camera's optical axis and the
//    ray to the person, both projected on the horizontal plane. The person's position is the target
//    estimate (localized detections, carried to now by its velocity), so the error is the one the image
//    would show now: the detector's latency and the drone's motion since the capture are compensated.
//  - Control: a rate command u = kp e + ki int e + feed-forward. The feed-forward cancels the body's own
//    yaw rate (the gimbal turns with the body) and adds the rate at which the bearing to the person
//    turns (from the person's and the drone's velocities), so the PI only corrects what neither predicts.
//  - Anti-windup: the integral is clamped, runs only for small errors (integral separation: a large
//    step is closed by the proportional part without overshoot), and stops while the command saturates
//    in the error's direction (conditional integration).
//  - Unlimited rotation: angles are unwrapped; the error is wrapped to (-pi, pi], so the gimbal always
//    turns the short way and never unwinds.
//  - Search: when the person is lost (or the supervisor asks), the gimbal first keeps looking where the
//    estimate predicts them, as long as that prediction is good enough to put them in the image: its
//    bearing uncertainty (the estimate's position covariance across the line of sight, over the range)
//    stays below max_bearing_sigma_rad, and for at most look_at_prediction_s. A person hidden for a
//    moment -- a missed detection, a corner between them and the drone -- reappears there, and
//    sweeping away at once would lose them for a whole turn (measured on sharp_turn at 1.5 m/s, 20
//    seeds: 1.5 s a run out of the image when sweeping after 1 s, 0.01 s with this rule). Then it
//    sweeps at a constant rate, turning first towards where the person was last seen, so the camera
//    looks all around.
// Pure: time and every input come in; no clock, no device.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include <Eigen/Core>

#include "aerotrack/estimation/camera_to_world.hpp"
#include "aerotrack/estimation/target_estimator.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::gimbal_control {

struct GimbalControlParams {
  double kp_per_s = 6.0;                ///< Proportional gain (rad/s per rad); > 0.
  double ki_per_s2 = 9.0;               ///< Integral gain (rad/s per rad s); >= 0. kp^2 / 4: critically damped.
  double integral_limit_rad_s = 0.2;    ///< Clamp on the integral of the error; >= 0.
  double integral_zone_rad = 0.3;       ///< The integral runs only for errors smaller than this (no overshoot on
                                        ///< large steps: the proportional part brings the person in); > 0.
  double max_rate_radps = 4.0;          ///< Command limit (the motor's); > 0.
  double sweep_rate_radps = 2.0;        ///< Search sweep speed; > 0, <= max_rate_radps.
  bool feed_forward = true;             ///< Body yaw rate and bearing rate feed-forward.
  double max_estimate_age_s = 0.5;      ///< An estimate older than this is not used (search instead); > 0.
  double look_at_prediction_s = 5.0;    ///< After the last accepted detection, point at the predicted person at
                                        ///< most this long before sweeping; >= 0 (0: sweep at once).
  double max_bearing_sigma_rad = 0.38;  ///< ... and only while the prediction's bearing sigma stays below this
                                        ///< (0.38: 2 sigma = the 87 degree camera's half field of view); > 0.
};

rt::Status validate(const GimbalControlParams& params);
/// Every field by its name, all required; throws rt::ConfigError naming the key.
GimbalControlParams parseGimbalControlParams(const rt::ConfigNode& node);

enum class GimbalMode : std::uint8_t { kIdle, kTrack, kSearch };
std::string_view toString(GimbalMode mode);

struct GimbalInputs {
  rt::TimeNs now_ns = 0;
  const hal::GimbalState* gimbal = nullptr;            ///< Newest encoder reading (required).
  const hal::OdometrySample* odometry = nullptr;       ///< Newest vehicle state (required).
  const estimation::TargetEstimate* target = nullptr;  ///< Newest person estimate; may be null.
  bool search_requested = false;                       ///< The supervisor wants a sweep (relocation).
};

struct GimbalOutput {
  hal::GimbalCommand command;  ///< Rate mode.
  GimbalMode mode = GimbalMode::kIdle;
  double error_rad = 0.0;  ///< The horizontal image error (kTrack).
};

/// The horizontal angle from the camera's optical axis to the point p_W (positive: to the left, the
/// direction the gimbal turns for a positive rate), in (-pi, pi]. Pure.
/// One standard deviation of the bearing to the person (rad): the estimate's horizontal position
/// covariance across the line of sight from the camera, over the horizontal range.
double bearingSigmaRad(const Eigen::Isometry3d& T_WC, const estimation::TargetEstimate& target);

double horizontalBearingError(const Eigen::Isometry3d& T_WC, const Eigen::Vector3d& p_W_m);

/// Not thread-safe (one task). No allocation.
class GimbalController {
 public:
  GimbalController(const GimbalControlParams& params, const estimation::GimbalCameraExtrinsics& extrinsics)
      : params_(params), extrinsics_(extrinsics) {}

  /// One control step. Without gimbal or odometry: a zero-rate command, kIdle.
  GimbalOutput update(const GimbalInputs& inputs);

  const GimbalControlParams& params() const { return params_; }
  double integralRadS() const { return integral_rad_s_; }

 private:
  GimbalControlParams params_;
  estimation::GimbalCameraExtrinsics extrinsics_;
  double integral_rad_s_ = 0.0;
  rt::TimeNs last_ns_ = -1;
  double sweep_direction_ = 1.0;  ///< +1 left, -1 right: towards the side the person was last seen on.
};

}  // namespace aerotrack::gimbal_control
