// The record layouts of a dataset's CSV streams (hal/replay/README.md), one codec per device stream:
// its columns (after stamp_ns) and the conversion to and from a record. Encoding then decoding gives
// back the same sample bit for bit (the streams write doubles in round-trip form). A decoded value
// that is out of its domain (a non-unit quaternion, an unknown gimbal mode) is an error naming the
// file and line. Pure; no I/O.
#pragma once

#include <string>
#include <vector>

#include "aerotrack/hal/replay/csv_stream.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::replay {

/// odometry.csv: position, orientation (unit quaternion w x y z), velocity in W, body rates in B.
struct OdometryCodec {
  static const std::vector<std::string>& columns();
  static std::vector<double> encode(const OdometrySample& sample);
  static rt::Expected<OdometrySample> decode(const CsvRecord& record, const std::string& path);
};

/// gimbal.csv: the encoder (unwrapped angle and rate).
struct GimbalStateCodec {
  static const std::vector<std::string>& columns();
  static std::vector<double> encode(const GimbalState& sample);
  static rt::Expected<GimbalState> decode(const CsvRecord& record, const std::string& path);
};

/// gimbal_commands.csv: mode 0 = rate, 1 = angle, then the command's three numbers.
struct GimbalCommandCodec {
  static const std::vector<std::string>& columns();
  static std::vector<double> encode(const GimbalCommand& command);
  static rt::Expected<GimbalCommand> decode(const CsvRecord& record, const std::string& path);
};

/// setpoints.csv: the setpoints sent to the flight controller.
struct SetpointCodec {
  static const std::vector<std::string>& columns();
  static std::vector<double> encode(const Setpoint& setpoint);
  static rt::Expected<Setpoint> decode(const CsvRecord& record, const std::string& path);
};

}  // namespace aerotrack::hal::replay
