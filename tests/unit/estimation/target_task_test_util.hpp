// Shared by the target task's tests: a level 640 x 480 gimbal camera of 87 deg horizontal field of view at
// the world's origin, looking along W x, and the pinhole localization of a 0.5 m torso seen by it.
#pragma once

#include "aerotrack/localization/localization_model.hpp"

namespace aerotrack::estimation::test {

inline constexpr double kFocalPx = 337.2;
inline constexpr double kTorsoM = 0.5;
inline constexpr int kWidthPx = 640;
inline constexpr int kHeightPx = 480;
inline constexpr double kFrameRateHz = 30.0;

inline localization::LocalizationParams pinholeLocalization() {
  localization::LocalizationParams p;
  p.model = localization::LocalizationModel::kPinhole;
  p.pinhole.fx_px = kFocalPx;
  p.pinhole.fy_px = kFocalPx;
  p.pinhole.cx_px = 0.5 * kWidthPx;
  p.pinhole.torso_m = kTorsoM;
  p.z_m = -0.4;
  return p;
}

}  // namespace aerotrack::estimation::test
