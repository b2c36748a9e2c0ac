// Hashed noise for the renderer's textures (ground, panels, bark). Private to hal/sim/render.
#pragma once

#include <cstdint>

namespace aerotrack::hal::sim {

/// Uniform in [0, 1) from two integer cell coordinates and a salt (splitmix64 finaliser).
inline double hash01(std::int64_t i, std::int64_t j, std::uint64_t salt) {
  std::uint64_t z = static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ULL ^
                    (static_cast<std::uint64_t>(j) + 0x632BE59BD9B4E019ULL) * 0xC2B2AE3D27D4EB4FULL ^ salt;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

}  // namespace aerotrack::hal::sim
