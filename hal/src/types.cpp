// Names of HAL enumerations, for reports and logs.
#include "aerotrack/hal/types.hpp"

namespace aerotrack::hal {

const char* toString(DeviceHealth::State state) {
  switch (state) {
    case DeviceHealth::State::kOk:
      return "ok";
    case DeviceHealth::State::kDegraded:
      return "degraded";
    case DeviceHealth::State::kFailed:
      return "failed";
    case DeviceHealth::State::kAbsent:
      return "absent";
  }
  return "?";
}

const char* toString(FlightMode mode) {
  switch (mode) {
    case FlightMode::kUnknown:
      return "unknown";
    case FlightMode::kManual:
      return "manual";
    case FlightMode::kHold:
      return "hold";
    case FlightMode::kOffboard:
      return "offboard";
    case FlightMode::kLand:
      return "land";
  }
  return "?";
}

}  // namespace aerotrack::hal
