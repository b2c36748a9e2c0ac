// Builds the devices whose backend is "real" (issue 11): the one place that knows the drivers, and
// the only `#if` for an optional one (librealsense2, DESIGN.md rule 5).
#pragma once

#include "aerotrack/hal/factory.hpp"

namespace aerotrack::hal {

/// Fills the slots of d whose backend is "real", opening each device. Error: one line naming the
/// device (a camera that is not there, a CAN interface that does not exist, a port in use).
rt::Status makeRealDevices(const HalConfig& config, TimeNs start_ns, Devices& d);

}  // namespace aerotrack::hal
