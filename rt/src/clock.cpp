// MonotonicClock: CLOCK_MONOTONIC in integer nanoseconds.
#include "aerotrack/rt/clock.hpp"

#include <ctime>

namespace aerotrack::rt {

TimeNs MonotonicClock::now() const {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<TimeNs>(ts.tv_sec) * kNsPerSecond + ts.tv_nsec;
}

}  // namespace aerotrack::rt
