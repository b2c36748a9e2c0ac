// The flight log's file (issue 24): an MCAP file whose topics are fixed here, once, for both writers
// of flight logs -- the live flight (flight_log.hpp, `--mcap`) and a recording turned into one
// (`aerotrack export-mcap`). Protobuf topics carry Foxglove's schemas (their FileDescriptorSets in the
// file); JSON topics carry a permissive JSON schema, so that Foxglove's plot panel can chart any field.
// docs/flight-log.md lists the topics.
#pragma once

#include <google/protobuf/message.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "aerotrack/hal/replay/mcap_writer.hpp"
#include "aerotrack/rt/time.hpp"
#include "live_view.hpp"

namespace aerotrack::app {

enum class Topic : std::uint8_t {
  kTf,              ///< /tf: foxglove.FrameTransforms
  kImage,           ///< /gimbal_camera/image: foxglove.CompressedImage
  kCalibration,     ///< /gimbal_camera/calibration: foxglove.CameraCalibration
  kDetections,      ///< /gimbal_camera/detections: foxglove.ImageAnnotations
  kDepth,           ///< /depth_camera/points: foxglove.PointCloud
  kEstimate,        ///< /person/estimate: foxglove.SceneUpdate
  kEstimateValues,  ///< /person/estimate/values: JSON
  kTrajectory,      ///< /planning/trajectory: foxglove.SceneUpdate
  kPlan,            ///< /planning/plan: foxglove.SceneUpdate (corridor, search, prediction)
  kPlanValues,      ///< /planning/cycle: JSON
  kPath,            ///< /drone/path: foxglove.SceneUpdate
  kMap,             ///< /map/occupied: foxglove.SceneUpdate
  kSupervisor,      ///< /supervisor: JSON
  kSetpoint,        ///< /setpoint: JSON
  kGimbalCommand,   ///< /gimbal/command: JSON
  kTiming,          ///< /timing: JSON
  kHealth,          ///< /health: JSON
  kObstacles,       ///< /sim/obstacles: foxglove.SceneUpdate (simulation only)
  kTruth,           ///< /sim/truth: foxglove.SceneUpdate (simulation only)
  kTruthValues,     ///< /sim/truth/values: JSON (simulation only)
  kCount,
};

/// The topic's name in the file ("/tf", ...).
const char* topicName(Topic topic);

/// Where a flight log goes: an MCAP file, a live view, or both.
struct FlightLogTargets {
  std::string mcap_path;  ///< "": no file.
  hal::replay::McapWriterOptions mcap;
  LiveViewOptions live;  ///< live.address "": no live view.
};

class FlightLogWriter {
 public:
  /// Creates the file and starts the live view (each if asked) and registers every topic (the
  /// simulation's only with `simulation`). Error: one line (the path cannot be created, is not a regular
  /// file, the port is in use, ...).
  static rt::Expected<std::unique_ptr<FlightLogWriter>> open(const FlightLogTargets& targets, bool simulation);
  ~FlightLogWriter();

  /// Serializes a message once and appends it to the file (log time = stamp) and offers it to the live
  /// view. Failures are counted, never thrown.
  void write(Topic topic, rt::TimeNs stamp_ns, const google::protobuf::Message& message);
  void writeJson(Topic topic, rt::TimeNs stamp_ns, std::string_view json);
  /// False once nothing is left to write to: the file has failed (a full disk) and there is no live view.
  bool active() const { return live_ != nullptr || (mcap_ != nullptr && static_cast<bool>(mcap_->failure())); }
  /// Writes the file's summary and closes it, stops the live view; the file's first error, if any.
  rt::Status close();
  /// One line per target: the file (messages, size, chunks, any early stop and its cause), the live view.
  std::string summary() const;
  /// The file's statistics (all zero without a file).
  hal::replay::McapWriterStats stats() const;
  /// The live view, if any (for its port and counters).
  const LiveView* live() const { return live_.get(); }

 private:
  FlightLogWriter() = default;
  void put(Topic topic, rt::TimeNs stamp_ns, std::span<const std::uint8_t> bytes);

  std::unique_ptr<hal::replay::McapWriter> mcap_;
  hal::replay::McapCompression compression_ = hal::replay::McapCompression::kZstd;
  std::unique_ptr<LiveView> live_;
  std::array<std::uint16_t, static_cast<std::size_t>(Topic::kCount)> channels_{};  ///< 0: not in the file
  std::vector<std::uint8_t> buffer_;  ///< One serialized message (keeps its capacity).
};

}  // namespace aerotrack::app
