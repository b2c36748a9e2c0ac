// Time in aerotrack: integer nanoseconds on one clock's epoch (DESIGN.md rule 2). Every message
// carries the time its data was sampled as a TimeNs; durations are DurationNs. Conversions to and
// from floating-point seconds live here so that rounding is done one way everywhere.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

namespace aerotrack::rt {

using TimeNs = std::int64_t;      ///< A point in time, nanoseconds since the clock's epoch.
using DurationNs = std::int64_t;  ///< A span of time in nanoseconds (may be negative).

inline constexpr DurationNs kNsPerSecond = 1'000'000'000;
inline constexpr DurationNs kNsPerMillisecond = 1'000'000;
/// No time: a release never scheduled, a task never run (the executors' sentinel).
inline constexpr TimeNs kNeverNs = std::numeric_limits<TimeNs>::max();

/// Seconds to nanoseconds, rounded to the nearest nanosecond.
inline DurationNs secondsToNs(double seconds) {
  return std::llround(seconds * 1e9);
}

/// Milliseconds to nanoseconds, rounded to the nearest nanosecond.
inline DurationNs millisecondsToNs(double milliseconds) {
  return std::llround(milliseconds * 1e6);
}

inline constexpr double nsToSeconds(DurationNs ns) {
  return static_cast<double>(ns) * 1e-9;
}
inline constexpr double nsToMilliseconds(DurationNs ns) {
  return static_cast<double>(ns) * 1e-6;
}

/// The period of a task that runs at rate_hz, rounded to whole nanoseconds. rate_hz must be > 0.
inline DurationNs periodFromRateHz(double rate_hz) {
  return std::llround(1e9 / rate_hz);
}

}  // namespace aerotrack::rt
