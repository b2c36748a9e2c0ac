// The replay backend (issue 10 item 2): every device served from a recorded dataset
// (hal/replay/README.md): odometry, gimbal encoder, vehicle link, the gimbal camera (images or a
// keypoint-mode camera's detections) and the depth camera.
//
// Time: the recording is laid onto the executor's clock. Executor time `now` shows recording time
// start + offset + (now - replay_start); stamps of served samples are moved the other way, so the
// modules see a recording exactly as they would see the live devices, under either executor
// (lockstep: as fast as the tasks run, deterministic; real-time: at 1x). A record is shown from the
// instant its device delivered it (its stamp plus the recorded delay), so a lockstep replay of a
// lockstep recording feeds the modules exactly what they saw. With `loop`, the recording starts again
// after its end, stamps still increasing.
//
// Actuators: commands sent to the replayed gimbal and setpoints sent to the replayed vehicle link are
// kept (for comparison with the recorded ones), not obeyed.
//
// Streams are read, decoded and checked whole when the dataset is opened (camera frame files are
// checked to exist then, and decoded when served): a strict error stops the start with one line naming
// the file and line; with the skip policy, bad rows are dropped and each device's health says how many. A recording
// ended by a kill -9 replays up to its last complete record.
#pragma once

#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "aerotrack/hal/devices.hpp"
#include "aerotrack/hal/replay/candump.hpp"
#include "aerotrack/hal/replay/csv_stream.hpp"
#include "aerotrack/hal/replay/manifest.hpp"
#include "aerotrack/hal/replay/stream_codecs.hpp"

namespace aerotrack::hal::replay {

/// Commands kept per actuator before the buffer first grows (a minute at 200 Hz; growth doubles it, so
/// it allocates about log2(n / this) times in a run).
inline constexpr std::size_t kKeptCommands = 12'000;

struct ReplayOptions {
  std::string dir;        ///< The recording's folder (holding manifest.yaml).
  double offset_s = 0.0;  ///< Start this far into the recording; >= 0.
  bool loop = false;      ///< After the end, start again from the offset.
  BadRowPolicy bad_rows = BadRowPolicy::kSkip;
  /// Real-time executor: the replay starts at the first instant any device is asked (when the tasks
  /// start), not at the replay start given to open() -- building the system takes time, and the
  /// recording's first moments would go by unseen. Not a config key: the commands set it.
  bool start_at_first_use = false;
};

/// Recording time <-> executor time. Thread-safe: devices polled from several task threads share it.
class ReplayTimeline {
 public:
  ReplayTimeline(rt::TimeNs recording_start_ns, rt::TimeNs recording_end_ns, rt::TimeNs replay_start_ns,
                 const ReplayOptions& options);
  ReplayTimeline(const ReplayTimeline& other);
  ReplayTimeline& operator=(const ReplayTimeline& other);
  /// The recording instant shown at executor time now_ns; `lap` counts loops (0: first pass).
  rt::TimeNs toRecording(rt::TimeNs now_ns, std::int64_t& lap) const;
  /// The executor time at which recording instant rec_ns is shown in lap `lap`.
  rt::TimeNs toExecutor(rt::TimeNs rec_ns, std::int64_t lap) const;
  /// True once a non-looping replay has shown its last instant.
  bool ended(rt::TimeNs now_ns) const;
  /// The first recording instant shown (start + offset).
  rt::TimeNs firstNs() const { return first_ns_; }
  /// The recording's last instant: its last record of any stream.
  rt::TimeNs endNs() const { return end_ns_; }

 private:
  static constexpr rt::TimeNs kUnanchored = INT64_MIN;
  /// The executor time the replay started at (anchoring it at now_ns if it starts at first use).
  rt::TimeNs replayStart(rt::TimeNs now_ns) const;

  rt::TimeNs first_ns_;  // recording start + offset
  rt::TimeNs end_ns_;    // recording end
  mutable std::atomic<rt::TimeNs> replay_start_ns_;
  bool loop_;
};

/// A decoded stream: its records in time order, and what reading it found.
template <class Item>
struct LoadedStream {
  std::vector<Item> samples;
  std::string path;
  std::uint64_t skipped_rows = 0;  ///< Bad rows, and index rows whose frame file is missing.
  std::string first_skip_message;
  bool truncated_tail = false;
};

/// One recording, opened and checked. Devices made from it share it (and its timeline).
class ReplayDataset {
 public:
  static rt::Expected<std::shared_ptr<ReplayDataset>> open(const ReplayOptions& options, rt::TimeNs replay_start_ns);

  const DatasetManifest& manifest() const { return manifest_; }
  const std::string& dir() const { return dir_; }
  const ReplayTimeline& timeline() const { return timeline_; }
  BadRowPolicy badRowPolicy() const { return policy_; }
  const LoadedStream<Delivered<OdometrySample>>* odometry() const { return get(odometry_); }
  const LoadedStream<Delivered<GimbalState>>* gimbal() const { return get(gimbal_); }
  const LoadedStream<Delivered<DetectionFrame>>* detections() const { return get(detections_); }
  const LoadedStream<Delivered<FrameIndexRow>>* depthFrames() const { return get(depth_frames_); }
  const LoadedStream<Delivered<FrameIndexRow>>* images() const { return get(images_); }
  const LoadedStream<Setpoint>* setpoints() const { return get(setpoints_); }
  const LoadedStream<GimbalCommand>* gimbalCommands() const { return get(gimbal_commands_); }
  /// The raw CAN traffic (can.log), when recorded: checked on open, for diagnosis; the gimbal is
  /// replayed from its encoder stream, not by re-parsing the motor's frames.
  const LoadedCanLog* canLog() const { return get(can_log_); }

 private:
  ReplayDataset(DatasetManifest manifest, std::string dir, const ReplayTimeline& timeline, BadRowPolicy policy)
      : manifest_(std::move(manifest)), dir_(std::move(dir)), timeline_(timeline), policy_(policy) {}
  template <class T>
  static const T* get(const std::optional<T>& stream) {
    return stream ? &*stream : nullptr;
  }
  DatasetManifest manifest_;
  std::string dir_;
  ReplayTimeline timeline_;
  BadRowPolicy policy_;
  std::optional<LoadedStream<Delivered<OdometrySample>>> odometry_;
  std::optional<LoadedStream<Delivered<GimbalState>>> gimbal_;
  std::optional<LoadedStream<Delivered<DetectionFrame>>> detections_;
  std::optional<LoadedStream<Delivered<FrameIndexRow>>> depth_frames_;
  std::optional<LoadedStream<Delivered<FrameIndexRow>>> images_;
  std::optional<LoadedStream<Setpoint>> setpoints_;
  std::optional<LoadedStream<GimbalCommand>> gimbal_commands_;
  std::optional<LoadedCanLog> can_log_;
};

/// Serves a loaded stream by executor time. A record is shown from the instant the device delivered
/// it (stamp + delay) and restamped onto the executor's clock.
template <class Sample>
class StreamCursor {
 public:
  StreamCursor(std::shared_ptr<const ReplayDataset> dataset, const LoadedStream<Delivered<Sample>>* stream)
      : dataset_(std::move(dataset)), stream_(stream) {}
  /// The newest sample delivered at or before now (repeated until a newer one is delivered).
  std::optional<Sample> newestAt(rt::TimeNs now_ns);
  /// The newest sample delivered at or before now if not returned before; older ones are skipped (a
  /// camera's newest-frame grab).
  std::optional<Sample> newestUnseenAt(rt::TimeNs now_ns);
  /// The oldest sample delivered at or before now and not returned before (a queue).
  std::optional<Sample> nextAt(rt::TimeNs now_ns);
  DeviceHealth health(rt::TimeNs now_ns) const;
  const ReplayDataset& dataset() const { return *dataset_; }

 private:
  /// Moves to now's lap; returns the recording instant shown at now.
  rt::TimeNs sync(rt::TimeNs now_ns);
  Sample shown(std::size_t i);

  std::shared_ptr<const ReplayDataset> dataset_;
  const LoadedStream<Delivered<Sample>>* stream_;
  std::size_t next_ = 0;    // first record not yet delivered in this lap
  std::size_t served_ = 0;  // first record not yet returned in this lap (newestUnseenAt, nextAt)
  std::int64_t lap_ = 0;
  bool lap_started_ = false;
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

/// The gimbal camera from a recording: its images (gimbal_camera/frames.csv and the image files, read
/// when served), and a keypoint-mode camera's detections (gimbal_camera/detections.csv), each in the
/// order and at the instants they were delivered. A frame file that cannot be read when its turn
/// comes is skipped and counted in the health.
class ReplayGimbalCamera final : public GimbalCamera {
 public:
  explicit ReplayGimbalCamera(const std::shared_ptr<const ReplayDataset>& dataset)
      : images_(dataset, dataset->images()), detections_(dataset, dataset->detections()) {}
  std::string_view backend() const override { return "replay"; }
  DeviceHealth health(rt::TimeNs now_ns) const override;
  ImageFrameHandle grab(rt::TimeNs now_ns) override;
  std::optional<DetectionFrame> grabDetections(rt::TimeNs now_ns) override { return detections_.nextAt(now_ns); }

 private:
  StreamCursor<FrameIndexRow> images_;
  StreamCursor<DetectionFrame> detections_;
  std::uint64_t unreadable_ = 0;
  std::string first_unreadable_;
};

/// The depth camera from a recording (depth_camera/frames.csv and its 16-bit PNGs, read when served),
/// with the manifest's intrinsics and mount. Unreadable frames are skipped and counted in the health.
class ReplayDepthCamera final : public DepthCamera {
 public:
  explicit ReplayDepthCamera(const std::shared_ptr<const ReplayDataset>& dataset);
  std::string_view backend() const override { return "replay"; }
  DeviceHealth health(rt::TimeNs now_ns) const override;
  DepthFrameHandle grab(rt::TimeNs now_ns) override;

 private:
  StreamCursor<FrameIndexRow> cursor_;
  CameraIntrinsics intrinsics_;
  Eigen::Isometry3d T_BC_ = Eigen::Isometry3d::Identity();
  std::uint64_t unreadable_ = 0;
  std::string first_unreadable_;
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
