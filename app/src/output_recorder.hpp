// What the modules decide, recorded beside what the devices delivered (issue 10): the detections
// (the detector's, or a keypoint-mode camera's), the target estimates and the planned trajectories, so that `aerotrack
// replay --compare` can check a replay against the run that was recorded (hal/replay/README.md, "Outputs"). The device
// streams are written by hal::replay::DatasetRecorder; these two are module types, so they live here.
//
// OutputRecorderTask is a background task (priority 0, not in the task table: System adds it with
// --record). It polls the newest-detection, estimate and trajectory channels and appends each new
// detection (by sequence), estimate (by stamp) and trajectory (by handle) to its CSV file, one
// write(2) per record, like the device streams. Polling sees the newest value: a detector at 30 Hz
// loses nothing at the task's 100 Hz, a keypoint camera delivering two results between polls shows
// the second.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "aerotrack/estimation/target_estimator.hpp"
#include "aerotrack/hal/replay/csv_stream.hpp"
#include "aerotrack/hal/types.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/task.hpp"
#include "aerotrack/trajectory_server/trajectory.hpp"

namespace aerotrack::app {

/// outputs/estimates.csv: every field of a TargetEstimate (the covariance's upper triangle, row by row) but the
/// other people it carries for the planner (`others`, the bystander tracks' states).
struct EstimateCodec {
  static const std::vector<std::string>& columns();
  static std::vector<double> encode(const estimation::TargetEstimate& estimate);
  /// A row of estimates.csv back (the bystander tracks it does not carry stay empty). Error naming the
  /// file and line for a value out of range.
  static rt::Expected<estimation::TargetEstimate> decode(const hal::replay::CsvRecord& record, const std::string& path);
};

/// outputs/trajectories.csv, stamped when this task saw it published: its start, its duration, the capture time of
/// the image it answered (-1: none), a 64-bit digest of its p, v and a at kTrajectoryDigestSamples
/// instants (two whole-number halves), and its position at the start, the middle and the end. Two
/// trajectories with the same row are, to that sampling, the same bits.
inline constexpr int kTrajectoryDigestSamples = 64;
struct TrajectoryCodec {
  static const std::vector<std::string>& columns();
  static std::vector<double> encode(const trajectory_server::TimedTrajectory& trajectory);
};

class OutputRecorderTask final : public rt::Task {
 public:
  /// Creates dir/outputs/ and both files (with their headers).
  static rt::Expected<std::unique_ptr<OutputRecorderTask>> create(
      const std::string& dir, const rt::LatestSlot<hal::DetectionFrame>& detections,
      const rt::LatestSlot<estimation::TargetEstimate>& estimates,
      const rt::SharedSlot<trajectory_server::TimedTrajectory>& trajectories);
  void step(rt::TimeNs now_ns) override;
  /// Closes the files; the first write error of the run, if any.
  rt::Status finish();
  std::uint64_t detectionsWritten() const { return detections_written_; }
  std::uint64_t estimatesWritten() const { return estimates_written_; }
  std::uint64_t trajectoriesWritten() const { return trajectories_written_; }

 private:
  OutputRecorderTask(const rt::LatestSlot<hal::DetectionFrame>& detections,
                     const rt::LatestSlot<estimation::TargetEstimate>& estimates,
                     const rt::SharedSlot<trajectory_server::TimedTrajectory>& trajectories,
                     std::vector<hal::replay::CsvStreamWriter> writers)
      : detections_(detections), estimates_(estimates), trajectories_(trajectories), writers_(std::move(writers)) {}
  rt::Status write(std::size_t stream, rt::TimeNs stamp_ns, const std::vector<double>& values, std::uint64_t& written);

  const rt::LatestSlot<hal::DetectionFrame>& detections_;
  const rt::LatestSlot<estimation::TargetEstimate>& estimates_;
  const rt::SharedSlot<trajectory_server::TimedTrajectory>& trajectories_;
  std::vector<hal::replay::CsvStreamWriter> writers_;  // detections, estimates, trajectories
  std::uint64_t last_detection_sequence_ = 0;
  rt::TimeNs last_detection_ns_ = INT64_MIN;
  rt::TimeNs last_estimate_ns_ = INT64_MIN;
  std::shared_ptr<const trajectory_server::TimedTrajectory> last_trajectory_;  // held: its address stays unique
  std::uint64_t detections_written_ = 0;
  std::uint64_t estimates_written_ = 0;
  std::uint64_t trajectories_written_ = 0;
  rt::Status first_error_;
};

}  // namespace aerotrack::app
