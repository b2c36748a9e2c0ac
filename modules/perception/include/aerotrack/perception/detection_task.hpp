// Task glue for the detector: takes the newest gimbal-camera image, runs the tracking loop
// (Detector::track) and publishes a DetectionFrame stamped with the image's exposure time, the
// followed person marked by target_index. Frames that arrive while the detector is busy are
// skipped, not queued: the newest image is the one worth detecting. Inference failures are
// counted, not printed (the app reports them).
//
// An rt::OverlappedTask: gather() takes the newest image, work() runs the network on it, publish()
// writes the frame. In lockstep with a latency (the task table's latency_ms: the detector's time on
// the drone's computer, the paper's 40 ms with the camera's own delay, Sect. VI-A), the network runs on
// the executor's second thread while the simulation renders the next frame, and its result appears
// that long after the image was taken, however fast this machine ran it: the run stays deterministic.
// Inline (latency 0, the real-time executor), the three run in a row.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "aerotrack/perception/detector.hpp"
#include "aerotrack/rt/clock.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/shared_slot.hpp"
#include "aerotrack/rt/spsc_queue.hpp"
#include "aerotrack/rt/task.hpp"
#include "aerotrack/rt/timing_stats.hpp"

namespace aerotrack::perception {

/// Reads the `perception:` config section (throws rt::ConfigError naming the key). model_dir is
/// taken as written; "default" is left for the app to resolve.
DetectorParams parseDetectorParams(const rt::ConfigNode& node);

/// The DetectionFrame for one detector output on an image. Pure.
hal::DetectionFrame toDetectionFrame(const DetectorOutput& output, const hal::ImageFrame& image, rt::TimeNs result_ns);

class DetectionTask final : public rt::OverlappedTask {
 public:
  DetectionTask(Detector detector, const rt::SharedSlot<hal::ImageFrame>& images,
                rt::SpscQueue<hal::DetectionFrame>& out, const rt::Clock& stats_clock)
      : detector_(std::move(detector)), images_(images), out_(out), stats_clock_(stats_clock) {}

  bool gather(rt::TimeNs now_ns) override;
  void work() override;
  void publish(rt::TimeNs publish_ns) override;
  /// Also publish every result on `newest` (for pictures and the recorder), besides the stream.
  void publishNewestTo(rt::LatestSlot<hal::DetectionFrame>& newest) { newest_ = &newest; }
  /// The target estimator's verdicts (the target task's frames with whom it took, TargetTask::publishFollowedTo):
  /// the newest at each release goes to Detector::judged before the network runs, so the crop follows the
  /// person the estimator follows.
  void judgedBy(const rt::LatestSlot<hal::DetectionFrame>& verdicts) { verdicts_ = &verdicts; }

  std::uint64_t framesDetected() const { return frames_detected_; }
  std::uint64_t framesWithTarget() const { return frames_with_target_; }
  std::uint64_t failures() const { return failures_; }
  /// Per detected frame: transform, inference, decoding, lock-on.
  const rt::TimingStats& detectStats() const { return detect_stats_; }
  /// How the network was run (crop or whole frame, and why), and the verdicts that moved the lock.
  const TrackCounts& trackCounts() const { return detector_.counts(); }

 private:
  Detector detector_;
  const rt::SharedSlot<hal::ImageFrame>& images_;
  rt::SpscQueue<hal::DetectionFrame>& out_;
  rt::LatestSlot<hal::DetectionFrame>* newest_ = nullptr;
  const rt::LatestSlot<hal::DetectionFrame>* verdicts_ = nullptr;
  std::optional<hal::DetectionFrame> verdict_;  ///< gathered, judged before the next track()
  const rt::Clock& stats_clock_;
  rt::TimingStats detect_stats_;
  std::uint64_t image_version_ = 0;
  std::shared_ptr<const hal::ImageFrame> image_;        ///< gathered, held until published
  std::optional<rt::Expected<DetectorOutput>> output_;  ///< work()'s result
  std::uint64_t frames_detected_ = 0;
  std::uint64_t frames_with_target_ = 0;
  std::uint64_t failures_ = 0;
};

}  // namespace aerotrack::perception
