// Views of the simulated person for calibrating the localization regression (issue 6; the paper's
// Sect. IV-B fits it on motion-capture data, the simulator knows the truth). Each view puts a level
// gimbal camera at a random distance, height and bearing from the walking person at a random moment
// of their walk, turned so that the person lands anywhere across the image, and reports the true
// position of the person in the camera's forward-left-up frame. What the camera then sees -- the
// keypoint model's detection, or a rendered image for the real detector -- is the caller's choice.
#pragma once

#include <random>

#include <Eigen/Geometry>

#include "aerotrack/hal/sim/walking_person.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::sim {

struct CalibrationViewParams {
  double min_distance_m = 1.5;  ///< Horizontal camera-to-person distance, uniform in [min, max].
  double max_distance_m = 9.0;
  double min_height_m = 1.0;  ///< Camera height above the ground (the drone's flight height).
  double max_height_m = 2.5;
  double horizontal_fov_rad = 0.0;  ///< The camera's; the person's bearing stays within
  double fov_margin = 0.85;         ///< +- margin x half of it.
};
rt::Status validate(const CalibrationViewParams& params);

struct CalibrationView {
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();  ///< Camera, OpenCV axes, in the world.
  PersonState person;                                      ///< The person at the view's moment.
  /// The person's reference point (the ground point under the pelvis, PersonState::p_W_m) in the
  /// camera's forward-left-up frame (x forward, y left, z up), metres: what the localization predicts.
  Eigen::Vector3d p_C_flu_m = Eigen::Vector3d::Zero();
};

/// One random view of the person walking their path for walk_duration_s. Draws from rng only;
/// pure otherwise. Expects validated params.
CalibrationView sampleCalibrationView(const WalkingPerson& person, double walk_duration_s,
                                      const CalibrationViewParams& params, std::mt19937_64& rng);

}  // namespace aerotrack::hal::sim
