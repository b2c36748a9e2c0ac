// The recorder (issue 10 item 3): writes a dataset (hal/replay/README.md) from any backend while the
// system runs, without ever blocking a real-time task. Each stream has a bounded single-producer queue
// (the task that owns the device is its one producer); a writer thread drains them into the CSV files.
// A full queue drops the new record and counts it: a slow disk costs records, never a control period.
// The manifest is written first, so a recording killed at any moment (kill -9, power cut) is a valid
// dataset up to its last complete record (the streams are written one record per write(2)).
//
// The device decorators (RecordingOdometry, ...) wrap a backend's device: what it delivers (odometry,
// encoder) and what it is told (gimbal commands, setpoints) goes to the recorder, and everything else
// passes straight through.
#pragma once

#include <array>
#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/replay/csv_stream.hpp"
#include "aerotrack/hal/replay/manifest.hpp"
#include "aerotrack/rt/doorbell.hpp"
#include "aerotrack/rt/spsc_queue.hpp"

namespace aerotrack::hal::replay {

struct RecorderOptions {
  std::string dir;                    ///< Created if missing; must not hold a manifest.yaml already.
  std::string software_version;       ///< Written into the manifest.
  std::string source = "sim";         ///< "sim" or "real".
  std::size_t queue_capacity = 4096;  ///< Records per stream in flight to the writer thread.
};

/// The streams a recorder writes (index: RecordedStream).
enum class RecordedStream : std::uint8_t { kOdometry, kGimbal, kGimbalCommands, kSetpoints };
inline constexpr std::size_t kRecordedStreams = 4;

class DatasetRecorder {
 public:
  /// Creates the folder, writes manifest.yaml, opens every stream and starts the writer thread.
  static rt::Expected<std::unique_ptr<DatasetRecorder>> start(const RecorderOptions& options, rt::TimeNs start_ns);
  ~DatasetRecorder();
  DatasetRecorder(const DatasetRecorder&) = delete;
  DatasetRecorder& operator=(const DatasetRecorder&) = delete;

  // Producers, one thread per stream. Never block, never allocate; a full queue drops and counts.
  void record(const OdometrySample& sample) { push(odometry_, sample, RecordedStream::kOdometry); }
  void record(const GimbalState& sample) { push(gimbal_, sample, RecordedStream::kGimbal); }
  void record(const GimbalCommand& command) { push(commands_, command, RecordedStream::kGimbalCommands); }
  void record(const Setpoint& setpoint) { push(setpoints_, setpoint, RecordedStream::kSetpoints); }

  /// Drains the queues, stops the writer thread and closes the files. Idempotent. The first write
  /// error of the run, if any (the recording stopped growing there; the run went on).
  rt::Status stop();

  std::uint64_t written(RecordedStream s) const { return written_[index(s)].load(std::memory_order_relaxed); }
  std::uint64_t dropped(RecordedStream s) const;
  const std::string& dir() const { return options_.dir; }

 private:
  DatasetRecorder(RecorderOptions options, std::array<CsvStreamWriter, kRecordedStreams> writers);
  static std::size_t index(RecordedStream s) { return static_cast<std::size_t>(s); }
  template <class T>
  void push(rt::SpscQueue<T>& queue, const T& item, RecordedStream) {
    if (queue.try_push(item)) doorbell_.ring();
  }
  void run();
  /// Writes what is queued; true if anything was.
  bool drainOnce();

  RecorderOptions options_;
  std::array<CsvStreamWriter, kRecordedStreams> writers_;
  rt::SpscQueue<OdometrySample> odometry_;
  rt::SpscQueue<GimbalState> gimbal_;
  rt::SpscQueue<GimbalCommand> commands_;
  rt::SpscQueue<Setpoint> setpoints_;
  std::array<std::atomic<std::uint64_t>, kRecordedStreams> written_{};
  rt::Doorbell doorbell_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  bool stopped_ = false;
  rt::Status first_error_;  // writer thread only until joined
};

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
