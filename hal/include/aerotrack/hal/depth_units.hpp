// Depth in the unit depth cameras deliver: Z16, an unsigned 16-bit count of millimetres, 0 meaning no
// return (the Intel RealSense D400 default depth unit, and the usual convention of 16-bit depth PNGs).
// The simulated depth camera quantises to it as the real one does, and a recording stores it; both
// convert with these two functions, so a recorded frame reads back bit for bit (issue 10's golden
// replay).
#pragma once

#include <cmath>
#include <cstdint>

namespace aerotrack::hal {

inline constexpr double kZ16UnitM = 0.001;  ///< One count.
inline constexpr double kMaxZ16DepthM = 65.535;

/// Metres to Z16 counts, rounded to the nearest. 0, negative, NaN, inf and depths beyond kMaxZ16DepthM
/// become 0 (no return).
inline std::uint16_t depthToZ16(double z_m) {
  // The comparisons are false for NaN: no return.
  return z_m > 0.0 && z_m <= kMaxZ16DepthM ? static_cast<std::uint16_t>(std::lround(z_m / kZ16UnitM)) : 0;
}

/// Z16 counts to metres as the float the depth frames hold.
inline float depthFromZ16(std::uint16_t counts) {
  return static_cast<float>(static_cast<double>(counts) * kZ16UnitM);
}

}  // namespace aerotrack::hal
