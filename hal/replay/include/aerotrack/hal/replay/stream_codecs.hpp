// The record layouts of a dataset's CSV streams (hal/replay/README.md), one codec per device stream:
// its columns (after stamp_ns) and the conversion to and from a record. Encoding then decoding gives
// back the same sample bit for bit (the streams write doubles in round-trip form). A decoded value
// that is out of its domain (a non-unit quaternion, an unknown gimbal mode) is an error naming the
// file and line. Pure; no I/O.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "aerotrack/hal/replay/csv_stream.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::replay {

/// record.values[at] as a whole number in [0, 2^53] (exact in a double), or an error naming the file,
/// line and column.
rt::Expected<std::int64_t> wholeNumber(const CsvRecord& record, std::size_t at, const std::string& path,
                                       const char* column);

/// A sample as a device delivered it: delay_ns after its stamp (transport, processing, the
/// simulator's modelled latency). Replay serves it at stamp + delay, so the modules see each sample
/// at the instant they saw it live, which is what makes a lockstep replay bit-identical.
template <class Sample>
struct Delivered {
  Sample sample;
  rt::DurationNs delay_ns = 0;
};

/// The stream of Codec's samples as delivered: a `delay_ns` column (a whole number >= 0) before
/// Codec's columns.
template <class Codec>
struct DeliveredCodec {
  using Sample = typename Codec::Sample;
  static const std::vector<std::string>& columns() {
    static const std::vector<std::string> kColumns = [] {
      std::vector<std::string> c{"delay_ns"};
      c.insert(c.end(), Codec::columns().begin(), Codec::columns().end());
      return c;
    }();
    return kColumns;
  }
  static std::vector<double> encode(const Delivered<Sample>& d) {
    std::vector<double> out{static_cast<double>(d.delay_ns)};
    const std::vector<double> values = Codec::encode(d.sample);
    out.insert(out.end(), values.begin(), values.end());
    return out;
  }
  static rt::Expected<Delivered<Sample>> decode(const CsvRecord& record, const std::string& path) {
    auto delay_ns = wholeNumber(record, 0, path, "delay_ns");
    if (!delay_ns) return delay_ns.error();
    CsvRecord rest{record.stamp_ns, std::vector<double>(record.values.begin() + 1, record.values.end()), record.line};
    auto sample = Codec::decode(rest, path);
    if (!sample) return sample.error();
    return Delivered<Sample>{*sample, *delay_ns};
  }
};

/// odometry.csv: position, orientation (unit quaternion w x y z), velocity in W, body rates in B.
struct OdometryCodec {
  using Sample = OdometrySample;
  static const std::vector<std::string>& columns();
  static std::vector<double> encode(const OdometrySample& sample);
  static rt::Expected<OdometrySample> decode(const CsvRecord& record, const std::string& path);
};

/// gimbal.csv: the encoder (unwrapped angle and rate).
struct GimbalStateCodec {
  using Sample = GimbalState;
  static const std::vector<std::string>& columns();
  static std::vector<double> encode(const GimbalState& sample);
  static rt::Expected<GimbalState> decode(const CsvRecord& record, const std::string& path);
};

/// gimbal_commands.csv: mode 0 = rate, 1 = angle, then the command's three numbers.
struct GimbalCommandCodec {
  using Sample = GimbalCommand;
  static const std::vector<std::string>& columns();
  static std::vector<double> encode(const GimbalCommand& command);
  static rt::Expected<GimbalCommand> decode(const CsvRecord& record, const std::string& path);
};

/// setpoints.csv: the setpoints sent to the flight controller.
struct SetpointCodec {
  using Sample = Setpoint;
  static const std::vector<std::string>& columns();
  static std::vector<double> encode(const Setpoint& setpoint);
  static rt::Expected<Setpoint> decode(const CsvRecord& record, const std::string& path);
};

/// gimbal_camera/detections.csv: what a keypoint-mode camera (the simulator's) delivers, every field of
/// the DetectionFrame: result_delay_ns (result_ns - stamp_ns), sequence, the intrinsics, person_count,
/// target_index, then all kMaxPersons persons (score, box, 17 keypoints u v score), used or not, then
/// each person's appearance signature (has_appearance, 37 bins).
/// Recordings made before the signatures (issue 20) lack those columns and are refused by the header check.
struct DetectionCodec {
  using Sample = DetectionFrame;
  static const std::vector<std::string>& columns();
  static std::vector<double> encode(const DetectionFrame& frame);
  static rt::Expected<DetectionFrame> decode(const CsvRecord& record, const std::string& path);
};

/// A camera frame index (depth_camera/frames.csv, gimbal_camera/frames.csv): the device's frame
/// sequence number and the number of the frame's image file (<file_index, 6 digits at least>.png).
/// The recorder numbers files itself, so a camera whose counter restarts cannot overwrite a frame.
struct FrameIndexRow {
  std::uint64_t sequence = 0;
  std::uint64_t file_index = 0;
  rt::TimeNs stamp_ns = 0;
};
struct FrameIndexCodec {
  using Sample = FrameIndexRow;
  static const std::vector<std::string>& columns();
  static std::vector<double> encode(const FrameIndexRow& row);
  static rt::Expected<FrameIndexRow> decode(const CsvRecord& record, const std::string& path);
};

using DeliveredOdometryCodec = DeliveredCodec<OdometryCodec>;
using DeliveredGimbalStateCodec = DeliveredCodec<GimbalStateCodec>;
using DeliveredDetectionCodec = DeliveredCodec<DetectionCodec>;
using DeliveredFrameIndexCodec = DeliveredCodec<FrameIndexCodec>;

}  // namespace aerotrack::hal::replay
