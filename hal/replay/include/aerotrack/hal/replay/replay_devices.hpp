// The replay backend for the numeric devices (issue 10 item 2): odometry, gimbal encoder and vehicle
// link served from a recorded dataset (hal/replay/README.md).
//
// Time: the recording is laid onto the executor's clock. Executor time `now` shows recording time
// start + offset + (now - replay_start); stamps of served samples are moved the other way, so the
// modules see a recording exactly as they would see the live devices, under either executor
// (lockstep: as fast as the tasks run, deterministic; real-time: at 1x). With `loop`, the recording
// starts again after its end, stamps still increasing.
//
// Actuators: commands sent to the replayed gimbal and setpoints sent to the replayed vehicle link are
// kept (for comparison with the recorded ones), not obeyed.
//
// Streams are read, decoded and checked whole when the dataset is opened: a strict error stops the
// start with one line naming the file and line; with the skip policy, bad rows are dropped and each
// device's health says how many. A recording ended by a kill -9 replays up to its last complete
// record.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/replay/csv_stream.hpp"
#include "aerotrack/hal/replay/manifest.hpp"

namespace aerotrack::hal::replay {

/// Commands kept per actuator before the buffer first grows (a minute at 200 Hz; growth doubles it, so
/// it allocates about log2(n / this) times in a run).
inline constexpr std::size_t kKeptCommands = 12'000;

struct ReplayOptions {
  std::string dir;        ///< The recording's folder (holding manifest.yaml).
  double offset_s = 0.0;  ///< Start this far into the recording; >= 0.
  bool loop = false;      ///< After the end, start again from the offset.
  BadRowPolicy bad_rows = BadRowPolicy::kSkip;
};

/// Recording time <-> executor time.
class ReplayTimeline {
 public:
  ReplayTimeline(rt::TimeNs recording_start_ns, rt::TimeNs recording_end_ns, rt::TimeNs replay_start_ns,
                 const ReplayOptions& options);
  /// The recording instant shown at executor time now_ns; `lap` counts loops (0: first pass).
  rt::TimeNs toRecording(rt::TimeNs now_ns, std::int64_t& lap) const;
  /// The executor time at which recording instant rec_ns is shown in lap `lap`.
  rt::TimeNs toExecutor(rt::TimeNs rec_ns, std::int64_t lap) const;
  /// True once a non-looping replay has shown its last instant.
  bool ended(rt::TimeNs now_ns) const;

 private:
  rt::TimeNs first_ns_;  // recording start + offset
  rt::TimeNs end_ns_;    // recording end
  rt::TimeNs replay_start_ns_;
  bool loop_;
};

/// A decoded stream: its samples in time order, and what reading it found.
template <class Sample>
struct LoadedStream {
  std::vector<Sample> samples;
  std::string path;
  std::uint64_t skipped_rows = 0;
  std::string first_skip_message;
  bool truncated_tail = false;
};

/// One recording, opened and checked. Devices made from it share it (and its timeline).
class ReplayDataset {
 public:
  static rt::Expected<std::shared_ptr<ReplayDataset>> open(const ReplayOptions& options, rt::TimeNs replay_start_ns);

  const DatasetManifest& manifest() const { return manifest_; }
  const ReplayTimeline& timeline() const { return timeline_; }
  const LoadedStream<OdometrySample>* odometry() const { return odometry_ ? &*odometry_ : nullptr; }
  const LoadedStream<GimbalState>* gimbal() const { return gimbal_ ? &*gimbal_ : nullptr; }
  const LoadedStream<Setpoint>* setpoints() const { return setpoints_ ? &*setpoints_ : nullptr; }
  const LoadedStream<GimbalCommand>* gimbalCommands() const { return gimbal_commands_ ? &*gimbal_commands_ : nullptr; }

 private:
  ReplayDataset(DatasetManifest manifest, ReplayTimeline timeline)
      : manifest_(std::move(manifest)), timeline_(timeline) {}
  DatasetManifest manifest_;
  ReplayTimeline timeline_;
  std::optional<LoadedStream<OdometrySample>> odometry_;
  std::optional<LoadedStream<GimbalState>> gimbal_;
  std::optional<LoadedStream<Setpoint>> setpoints_;
  std::optional<LoadedStream<GimbalCommand>> gimbal_commands_;
};

/// Serves a loaded stream by executor time: the newest sample at or before now, restamped.
template <class Sample>
class StreamCursor {
 public:
  StreamCursor(std::shared_ptr<const ReplayDataset> dataset, const LoadedStream<Sample>* stream)
      : dataset_(std::move(dataset)), stream_(stream) {}
  std::optional<Sample> newestAt(rt::TimeNs now_ns);
  DeviceHealth health(rt::TimeNs now_ns) const;

 private:
  std::shared_ptr<const ReplayDataset> dataset_;
  const LoadedStream<Sample>* stream_;
  std::size_t next_ = 0;  // first sample not yet shown in this lap
  std::int64_t lap_ = 0;
  rt::TimeNs last_served_ns_ = 0;
};

class ReplayOdometry final : public Odometry {
 public:
  explicit ReplayOdometry(const std::shared_ptr<const ReplayDataset>& dataset)
      : cursor_(dataset, dataset->odometry()) {}
  std::string_view backend() const override { return "replay"; }
  DeviceHealth health(rt::TimeNs now_ns) const override { return cursor_.health(now_ns); }
  std::optional<OdometrySample> read(rt::TimeNs now_ns) override { return cursor_.newestAt(now_ns); }

 private:
  StreamCursor<OdometrySample> cursor_;
};

class ReplayGimbal final : public Gimbal {
 public:
  explicit ReplayGimbal(const std::shared_ptr<const ReplayDataset>& dataset) : cursor_(dataset, dataset->gimbal()) {
    commands_.reserve(kKeptCommands);
  }
  std::string_view backend() const override { return "replay"; }
  DeviceHealth health(rt::TimeNs now_ns) const override { return cursor_.health(now_ns); }
  /// Kept, not obeyed: the recorded encoder readings are what the gimbal did.
  void command(const GimbalCommand& command) override { commands_.push_back(command); }  // reserved: see ctor
  std::optional<GimbalState> read(rt::TimeNs now_ns) override { return cursor_.newestAt(now_ns); }
  const std::vector<GimbalCommand>& commands() const { return commands_; }

 private:
  StreamCursor<GimbalState> cursor_;
  std::vector<GimbalCommand> commands_;
};

class ReplayVehicleLink final : public VehicleLink {
 public:
  explicit ReplayVehicleLink(std::shared_ptr<const ReplayDataset> dataset) : dataset_(std::move(dataset)) {
    sent_.reserve(kKeptCommands);
  }
  std::string_view backend() const override { return "replay"; }
  DeviceHealth health(rt::TimeNs now_ns) const override;
  /// Kept, not obeyed: the recorded odometry is what the vehicle did.
  void send(const Setpoint& setpoint) override { sent_.push_back(setpoint); }
  VehicleStatus status(rt::TimeNs now_ns) override;
  const std::vector<Setpoint>& sent() const { return sent_; }

 private:
  std::shared_ptr<const ReplayDataset> dataset_;
  std::vector<Setpoint> sent_;
};

}  // namespace aerotrack::hal::replay
