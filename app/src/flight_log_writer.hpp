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

class FlightLogWriter {
 public:
  /// Creates the file and registers every topic (the simulation's only with `simulation`). Error: one
  /// line (the path cannot be created, is not a regular file, ...).
  static rt::Expected<std::unique_ptr<FlightLogWriter>> open(const std::string& path,
                                                             const hal::replay::McapWriterOptions& options,
                                                             bool simulation);

  /// Serializes and appends a message, log time = stamp. Failures are counted, never thrown.
  void write(Topic topic, rt::TimeNs stamp_ns, const google::protobuf::Message& message);
  void writeJson(Topic topic, rt::TimeNs stamp_ns, std::string_view json);
  /// False once the log has failed (a full disk): writing is then pointless.
  bool healthy() const { return static_cast<bool>(writer_->failure()); }
  /// Writes the summary and closes the file; the log's first error, if any.
  rt::Status close() { return writer_->close(); }
  /// One line: the file, its messages, size, chunks, and any early stop with its cause.
  std::string summary() const;
  const hal::replay::McapWriterStats& stats() const { return writer_->stats(); }

 private:
  FlightLogWriter(std::unique_ptr<hal::replay::McapWriter> writer, hal::replay::McapCompression compression)
      : writer_(std::move(writer)), compression_(compression) {}

  std::unique_ptr<hal::replay::McapWriter> writer_;
  hal::replay::McapCompression compression_;
  std::array<std::uint16_t, static_cast<std::size_t>(Topic::kCount)> channels_{};  ///< 0: not registered
  std::vector<std::uint8_t> buffer_;  ///< One serialized message (keeps its capacity).
};

}  // namespace aerotrack::app
