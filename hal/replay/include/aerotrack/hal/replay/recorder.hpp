// The recorder (issue 10 item 3): writes a dataset (hal/replay/README.md) from any backend while the
// system runs, without ever blocking a real-time task. Each stream has a bounded single-producer queue
// (the task that owns the device is its one producer); a writer thread drains them into the CSV files.
// A full queue drops the new record and counts it: a slow disk costs records, never a control period.
// The manifest is written first, so a recording killed at any moment (kill -9, power cut) is a valid
// dataset up to its last complete record (the streams are written one record per write(2)).
//
// The device decorators (RecordingOdometry, ...) wrap a backend's device: what it delivers (odometry,
// encoder, detections, depth frames, images) and what it is told (gimbal commands, setpoints) goes to
// the recorder, and everything else passes straight through. Camera frames are written by the writer
// thread (PNG or JPEG), each before its index row.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/replay/csv_stream.hpp"
#include "aerotrack/hal/replay/manifest.hpp"
#include "aerotrack/hal/replay/stream_codecs.hpp"
#include "aerotrack/rt/doorbell.hpp"
#include "aerotrack/rt/spsc_queue.hpp"

namespace aerotrack::hal::replay {

struct RecorderOptions {
  std::string dir;                        ///< Created if missing; must not hold a manifest.yaml already.
  std::string software_version;           ///< Written into the manifest.
  std::string source = "sim";             ///< "sim" or "real".
  std::size_t queue_capacity = 4096;      ///< Records per numeric stream in flight to the writer thread.
  std::size_t frame_queue_capacity = 16;  ///< Camera frames in flight (each is held, not copied).
  /// Wait for room instead of dropping: for the lockstep executor, whose time does not run while a
  /// task waits, so that a recording of a simulated run is complete and deterministic. Never on a
  /// real-time run.
  bool lossless = false;
};

/// The streams a recorder writes (index: RecordedStream).
enum class RecordedStream : std::uint8_t {
  kOdometry,
  kGimbal,
  kGimbalCommands,
  kSetpoints,
  kDetections,
  kDepthFrames,
  kImages
};
inline constexpr std::size_t kRecordedStreams = 7;
const char* toString(RecordedStream stream);

/// A camera frame on its way to the disk, with its delivery delay.
template <class Frame>
struct FrameRecord {
  std::shared_ptr<const Frame> frame;
  rt::DurationNs delay_ns = 0;
};

class DatasetRecorder {
 public:
  /// Creates the folder, writes manifest.yaml, opens every stream and starts the writer thread.
  static rt::Expected<std::unique_ptr<DatasetRecorder>> start(const RecorderOptions& options, rt::TimeNs start_ns);
  ~DatasetRecorder();
  DatasetRecorder(const DatasetRecorder&) = delete;
  DatasetRecorder& operator=(const DatasetRecorder&) = delete;

  // Producers, one thread per stream. Never block, never allocate; a full queue drops and counts.
  // Delivered samples carry the delay between their stamp and their delivery (replay shows them then).
  void record(const Delivered<OdometrySample>& sample) { push(odometry_, sample); }
  void record(const Delivered<GimbalState>& sample) { push(gimbal_, sample); }
  void record(const GimbalCommand& command) { push(commands_, command); }
  void record(const Setpoint& setpoint) { push(setpoints_, setpoint); }
  void record(const Delivered<DetectionFrame>& frame) { push(detections_, frame); }
  /// The frame is held (not copied) until written: its producer must not modify it once published.
  void record(const FrameRecord<DepthFrame>& frame) { push(depth_, frame); }
  void record(const FrameRecord<ImageFrame>& frame) { push(images_, frame); }

  /// Drains the queues, stops the writer thread and closes the files; with end_ns (the run's last
  /// instant), writes it into the manifest. Idempotent. The first write error of the run, if any (the
  /// recording stopped growing there; the run went on).
  rt::Status stop(std::optional<rt::TimeNs> end_ns = std::nullopt);

  std::uint64_t written(RecordedStream s) const { return written_[index(s)].load(std::memory_order_relaxed); }
  std::uint64_t dropped(RecordedStream s) const;
  const std::string& dir() const { return options_.dir; }
  /// "odometry N, gimbal N, ...": the records written per stream, for the streams that got any.
  std::string summary() const;
  std::uint64_t droppedTotal() const;

 private:
  DatasetRecorder(RecorderOptions options, DatasetManifest manifest, std::vector<CsvStreamWriter> writers);
  static std::size_t index(RecordedStream s) { return static_cast<std::size_t>(s); }
  template <class T>
  void push(rt::SpscQueue<T>& queue, const T& item) {
    if (options_.lossless) {
      while (!queue.canPush()) {
        doorbell_.ring();
        std::this_thread::sleep_for(std::chrono::microseconds(100));
      }
    }
    if (queue.try_push(item)) doorbell_.ring();
  }
  void run();
  /// Writes what is queued; true if anything was.
  bool drainOnce();
  template <class Frame>
  bool drainFrames(rt::SpscQueue<FrameRecord<Frame>>& queue, RecordedStream stream);
  rt::Status writeFrame(const FrameRecord<DepthFrame>& record, std::uint64_t file_index);
  rt::Status writeFrame(const FrameRecord<ImageFrame>& record, std::uint64_t file_index);

  RecorderOptions options_;
  DatasetManifest manifest_;              // writer thread: rewritten when a camera's first frame tells its intrinsics
  std::vector<CsvStreamWriter> writers_;  // by RecordedStream
  rt::SpscQueue<Delivered<OdometrySample>> odometry_;
  rt::SpscQueue<Delivered<GimbalState>> gimbal_;
  rt::SpscQueue<GimbalCommand> commands_;
  rt::SpscQueue<Setpoint> setpoints_;
  rt::SpscQueue<Delivered<DetectionFrame>> detections_;
  rt::SpscQueue<FrameRecord<DepthFrame>> depth_;
  rt::SpscQueue<FrameRecord<ImageFrame>> images_;
  std::array<std::atomic<std::uint64_t>, kRecordedStreams> written_{};
  rt::Doorbell doorbell_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  bool stopped_ = false;
  rt::Status first_error_;  // writer thread only until joined
};

/// Delivered samples: a device decorator records what it delivers with the delay from its stamp to the
/// `now` it was delivered at.
class RecordingOdometry final : public Odometry {
 public:
  RecordingOdometry(std::unique_ptr<Odometry> inner, DatasetRecorder& recorder)
      : inner_(std::move(inner)), recorder_(recorder) {}
  std::string_view backend() const override { return inner_->backend(); }
  DeviceHealth health(rt::TimeNs now_ns) const override { return inner_->health(now_ns); }
  std::optional<OdometrySample> read(rt::TimeNs now_ns) override;

 private:
  std::unique_ptr<Odometry> inner_;
  DatasetRecorder& recorder_;
  rt::TimeNs last_stamp_ns_ = INT64_MIN;
};

class RecordingGimbalCamera final : public GimbalCamera {
 public:
  RecordingGimbalCamera(std::unique_ptr<GimbalCamera> inner, DatasetRecorder& recorder)
      : inner_(std::move(inner)), recorder_(recorder) {}
  std::string_view backend() const override { return inner_->backend(); }
  DeviceHealth health(rt::TimeNs now_ns) const override { return inner_->health(now_ns); }
  ImageFrameHandle grab(rt::TimeNs now_ns) override;
  std::optional<DetectionFrame> grabDetections(rt::TimeNs now_ns) override;

 private:
  std::unique_ptr<GimbalCamera> inner_;
  DatasetRecorder& recorder_;
};

class RecordingDepthCamera final : public DepthCamera {
 public:
  RecordingDepthCamera(std::unique_ptr<DepthCamera> inner, DatasetRecorder& recorder)
      : inner_(std::move(inner)), recorder_(recorder) {}
  std::string_view backend() const override { return inner_->backend(); }
  DeviceHealth health(rt::TimeNs now_ns) const override { return inner_->health(now_ns); }
  DepthFrameHandle grab(rt::TimeNs now_ns) override;

 private:
  std::unique_ptr<DepthCamera> inner_;
  DatasetRecorder& recorder_;
};

class RecordingGimbal final : public Gimbal {
 public:
  RecordingGimbal(std::unique_ptr<Gimbal> inner, DatasetRecorder& recorder)
      : inner_(std::move(inner)), recorder_(recorder) {}
  std::string_view backend() const override { return inner_->backend(); }
  DeviceHealth health(rt::TimeNs now_ns) const override { return inner_->health(now_ns); }
  void command(const GimbalCommand& command) override;
  std::optional<GimbalState> read(rt::TimeNs now_ns) override;

 private:
  std::unique_ptr<Gimbal> inner_;
  DatasetRecorder& recorder_;
  rt::TimeNs last_stamp_ns_ = INT64_MIN;
};

class RecordingVehicleLink final : public VehicleLink {
 public:
  RecordingVehicleLink(std::unique_ptr<VehicleLink> inner, DatasetRecorder& recorder)
      : inner_(std::move(inner)), recorder_(recorder) {}
  std::string_view backend() const override { return inner_->backend(); }
  DeviceHealth health(rt::TimeNs now_ns) const override { return inner_->health(now_ns); }
  void send(const Setpoint& setpoint) override;
  VehicleStatus status(rt::TimeNs now_ns) override { return inner_->status(now_ns); }

 private:
  std::unique_ptr<VehicleLink> inner_;
  DatasetRecorder& recorder_;
};

}  // namespace aerotrack::hal::replay
