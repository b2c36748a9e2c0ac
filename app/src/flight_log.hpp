// The flight log (issue 24 item 1): `--mcap FILE` on run, sim and replay writes an MCAP file that
// Foxglove and Lichtblick open (docs/flight-log.md lists the topics; tools/foxglove/layout.json is a
// ready layout). Protobuf messages with Foxglove's own schemas, JSON for what plots chart.
//
// How it costs the flight nothing: FlightLogTask is an observer (rt::TaskSpec::observer), a
// priority-0 task the flight's tasks never see. It reads the same latest-value slots and shared
// handles the other tasks read (lock-free copies, or a handle taken under the slot's brief
// priority-inheriting lock), converts what is new, and hands it to the MCAP writer on its own thread
// (the real-time executor) or between the flight's steps (lockstep, where its steps stay out of the
// trace hash: a run logs the same flight, bit for bit, as without --mcap). Nothing is queued for it,
// so it can never block a producer; a value it polls too slowly to see is skipped (counted per topic
// as the samples it did write, against the producers' own counts in summary.json).
//
// A failed write (a full disk, the size limit) ends the log with one counted error; the flight goes on
// and the file keeps every chunk written before it.
#pragma once

#include <foxglove/CameraCalibration.pb.h>
#include <foxglove/CompressedImage.pb.h>
#include <foxglove/FrameTransforms.pb.h>
#include <foxglove/ImageAnnotations.pb.h>
#include <foxglove/PointCloud.pb.h>
#include <foxglove/SceneUpdate.pb.h>
#include <google/protobuf/arena.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "aerotrack/estimation/camera_to_world.hpp"
#include "aerotrack/hal/factory.hpp"
#include "aerotrack/hal/replay/mcap_writer.hpp"
#include "aerotrack/hal/sim/simulation.hpp"
#include "aerotrack/rt/task.hpp"
#include "aerotrack/rt/task_set.hpp"
#include "flight_log_writer.hpp"
#include "foxglove_messages.hpp"

namespace aerotrack::app {

struct Channels;

struct FlightLogOptions {
  FlightLogTargets targets;         ///< The file (--mcap), the live view (--live), or both.
  double map_rate_hz = 1.0;         ///< The occupied cells (a whole window each time).
  double truth_rate_hz = 20.0;      ///< The simulator's truth.
  double depth_rate_hz = 5.0;       ///< Depth images as point clouds.
  int depth_step_px = 8;            ///< One depth pixel in this many along each axis.
  double path_segment_s = 1.0;      ///< The flown path is written in stretches this long.
  int jpeg_quality = 80;            ///< Gimbal-camera images (image mode, or a real camera).
  double keypoint_min_score = 0.2;  ///< Keypoints drawn in the image annotations.
};

/// What the log reads besides the channels (each optional).
struct FlightLogSources {
  const Channels& channels;
  const estimation::GimbalCameraExtrinsics* extrinsics = nullptr;  ///< The gimbal camera's mounting.
  std::shared_ptr<const hal::sim::Simulation> simulation;          ///< Truth and obstacles (sim only).
  const hal::Devices* devices = nullptr;                           ///< Their health (health() is thread-safe).
};

class FlightLogTask final : public rt::Task {
 public:
  /// Opens the file and registers every topic. Error: the path cannot be created (one line).
  static rt::Expected<std::unique_ptr<FlightLogTask>> create(const FlightLogOptions& options,
                                                             const FlightLogSources& sources);
  ~FlightLogTask() override;
  void step(rt::TimeNs now_ns) override;
  /// The executor's per-task statistics, to log as /timing (their snapshots may be taken from any thread).
  void watchTimings(std::vector<rt::TaskSet::NamedStats> timings) { timings_ = std::move(timings); }
  /// Closes the file (summary and index); the log's first error, if any.
  rt::Status finish();
  /// One line: the file, its messages, size, chunks, and any error.
  std::string summary() const;
  hal::replay::McapWriterStats stats() const { return log_->stats(); }
  const FlightLogWriter& log() const { return *log_; }

 private:
  FlightLogTask(const FlightLogOptions& options, const FlightLogSources& sources, std::unique_ptr<FlightLogWriter> log);
  void logOdometry();
  void logSetpoint();
  void logCamera();
  void logDepth(rt::TimeNs now_ns);
  void logEstimate();
  void logPlanning(rt::TimeNs now_ns);
  void logSim(rt::TimeNs now_ns);
  void logStatus(rt::TimeNs now_ns);

  FlightLogOptions options_;
  FlightLogSources sources_;
  std::unique_ptr<FlightLogWriter> log_;
  std::vector<std::uint8_t> jpeg_;
  /// The messages of one step are made in an arena over a block reserved once, reset after the step: no
  /// allocation per message (protobuf's Clear() would free a reused message's sub-messages). The frames'
  /// messages are kept instead, so that their data keeps its capacity.
  static constexpr std::size_t kArenaBytes = 8U << 20;
  std::vector<char> arena_block_;
  google::protobuf::Arena arena_;
  template <class T>
  T& fresh() {
    return *google::protobuf::Arena::CreateMessage<T>(&arena_);
  }
  foxglove::CompressedImage image_;
  foxglove::PointCloud points_;
  foxglove_log::FlownPath flown_path_;
  rt::TimeNs last_odometry_ns_ = INT64_MIN;
  rt::TimeNs last_estimate_ns_ = INT64_MIN;
  rt::TimeNs last_detection_ns_ = INT64_MIN;
  std::uint64_t last_detection_sequence_ = 0;
  const void* last_image_ = nullptr;
  rt::TimeNs last_image_ns_ = INT64_MIN;
  const void* last_trajectory_ = nullptr;
  rt::TimeNs last_trajectory_ns_ = INT64_MIN;
  rt::TimeNs last_plan_ns_ = INT64_MIN;
  rt::TimeNs last_setpoint_ns_ = INT64_MIN;
  rt::TimeNs next_map_ns_ = INT64_MIN;
  rt::TimeNs next_depth_ns_ = INT64_MIN;
  rt::TimeNs last_depth_ns_ = INT64_MIN;
  rt::TimeNs next_truth_ns_ = INT64_MIN;
  std::uint64_t last_transitions_ = UINT64_MAX;
  bool obstacles_written_ = false;
  std::vector<rt::TaskSet::NamedStats> timings_;
  rt::TimeNs next_status_ns_ = INT64_MIN;
  rt::TimeNs next_supervisor_ns_ = INT64_MIN;
};

}  // namespace aerotrack::app
