// Scalar helpers for the renderer's vectorised passes. Private to hal/sim/render.
#pragma once

#include <cstdint>

namespace aerotrack::hal::sim {

/// Value (not reference) forms of min and max: GCC 12 vectorises these, not std::min's.
inline float minF(float a, float b) {
  return b < a ? b : a;
}
inline float maxF(float a, float b) {
  return a < b ? b : a;
}
inline int minI(int a, int b) {
  return b < a ? b : a;
}

/// Rounds a colour channel; every colour drawn is a non-negative blend, so only the top needs a clamp.
inline std::uint8_t toByte(float c) {
  return static_cast<std::uint8_t>(minF(c, 255.0F) + 0.5F);  // NOLINT(bugprone-incorrect-roundings): c >= 0
}

/// floor(x) as an int (x within +-2^30), branch-free.
inline int floorToInt(float x) {
  const int i = static_cast<int>(x);
  return i - static_cast<int>(static_cast<float>(i) > x);
}

}  // namespace aerotrack::hal::sim
