// Replay devices: see replay_devices.hpp.
#include "aerotrack/hal/replay/replay_devices.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <system_error>
#include <utility>

#include "aerotrack/hal/replay/frame_files.hpp"
#include "aerotrack/hal/replay/stream_codecs.hpp"
#include "aerotrack/rt/input_limits.hpp"

namespace aerotrack::hal::replay {
namespace {

std::string formatSeconds(rt::DurationNs ns) {
  std::array<char, 32> text{};
  std::snprintf(text.data(), text.size(), "%.1f s", rt::nsToSeconds(ns));
  return text.data();
}

/// A codec's decoded record: Delivered<Sample> for delivered streams.
template <class Codec>
struct Record {
  using Type = typename Codec::Sample;
};
template <class Codec>
struct Record<DeliveredCodec<Codec>> {
  using Type = Delivered<typename Codec::Sample>;
};

template <class Codec, class Sample = typename Record<Codec>::Type>
rt::Expected<LoadedStream<Sample>> load(const std::string& dir, const StreamEntry& entry, BadRowPolicy policy) {
  LoadedStream<Sample> out;
  out.path = (std::filesystem::path(dir) / entry.file).string();
  auto reader = CsvStreamReader::open(out.path, Codec::columns(), policy);
  if (!reader) return reader.error();
  for (;;) {
    auto record = reader->next();
    if (!record) return record.error();
    if (!record->has_value()) break;
    auto sample = Codec::decode(**record, out.path);
    if (!sample) {
      if (policy == BadRowPolicy::kStrict) return sample.error();
      if (out.skipped_rows++ == 0) out.first_skip_message = sample.error().message;
      continue;
    }
    out.samples.push_back(*sample);
  }
  out.skipped_rows += reader->skippedRows();
  if (out.first_skip_message.empty()) out.first_skip_message = reader->firstSkipMessage();
  out.truncated_tail = reader->truncatedTail();
  return out;
}

/// Drops (skip) or refuses (strict) the index rows whose frame file is missing.
rt::Status checkFrameFiles(LoadedStream<Delivered<FrameIndexRow>>& stream, const std::string& extension,
                           BadRowPolicy policy) {
  const std::filesystem::path folder = std::filesystem::path(stream.path).parent_path();
  std::vector<Delivered<FrameIndexRow>> kept;
  kept.reserve(stream.samples.size());
  for (const Delivered<FrameIndexRow>& row : stream.samples) {
    const std::string file = (folder / frameFileName(row.sample.file_index, extension)).string();
    std::error_code ec;
    if (std::filesystem::is_regular_file(file, ec)) {
      kept.push_back(row);
      continue;
    }
    const std::string message =
        stream.path + ": frame " + std::to_string(row.sample.sequence) + ": " + file + " is missing";
    if (policy == BadRowPolicy::kStrict) return rt::Error{message};
    if (stream.skipped_rows++ == 0 && stream.first_skip_message.empty()) stream.first_skip_message = message;
  }
  stream.samples = std::move(kept);
  return rt::ok();
}

template <class Sample>
void restamp(Sample& sample, rt::DurationNs shift_ns) {
  sample.stamp_ns += shift_ns;
}

void restamp(DetectionFrame& frame, rt::DurationNs shift_ns) {
  frame.stamp_ns += shift_ns;
  frame.result_ns += shift_ns;
}

template <class Sample>
rt::TimeNs deliveredNs(const Delivered<Sample>& d) {
  return d.sample.stamp_ns + d.delay_ns;
}

DeviceHealth unreadableHealth(DeviceHealth h, std::uint64_t unreadable, const std::string& first) {
  if (unreadable == 0 || h.state == DeviceHealth::State::kFailed) return h;
  h.state = DeviceHealth::State::kDegraded;
  h.error_count += unreadable;
  h.detail = "replay: " + std::to_string(unreadable) + " unreadable frames skipped, the first: " + first;
  return h;
}

/// Reads the frame file of one index row of a camera stream (beside the stream's CSV) with read, and
/// checks its size against the manifest's camera. A frame that does not read or does not fit gives
/// nothing: it is counted in unreadable, the first problem kept, and the device goes on.
template <class Read>
std::optional<cv::Mat> readFrameFile(const std::string& stream_path, std::uint64_t file_index,
                                     const std::string& extension, const CameraIntrinsics& intrinsics,
                                     const char* camera, Read read, std::uint64_t& unreadable,
                                     std::string& first_unreadable) {
  const std::string file =
      (std::filesystem::path(stream_path).parent_path() / frameFileName(file_index, extension)).string();
  rt::Expected<cv::Mat> frame = read(file);
  std::string problem = frame ? std::string() : frame.error().message;
  if (frame && (frame->cols != intrinsics.width_px || frame->rows != intrinsics.height_px))
    problem = file + ": the frame's size differs from the manifest's " + camera;
  if (problem.empty()) return std::move(*frame);
  if (unreadable++ == 0) first_unreadable = problem;
  return std::nullopt;
}

}  // namespace

ReplayTimeline::ReplayTimeline(rt::TimeNs recording_start_ns, rt::TimeNs recording_end_ns, rt::TimeNs replay_start_ns,
                               const ReplayOptions& options)
    : first_ns_(recording_start_ns + rt::secondsToNs(options.offset_s)),
      end_ns_(std::max(recording_end_ns, recording_start_ns + rt::secondsToNs(options.offset_s))),
      replay_start_ns_(options.start_at_first_use ? kUnanchored : replay_start_ns),
      loop_(options.loop) {}

ReplayTimeline::ReplayTimeline(const ReplayTimeline& other)
    : first_ns_(other.first_ns_),
      end_ns_(other.end_ns_),
      replay_start_ns_(other.replay_start_ns_.load(std::memory_order_acquire)),
      loop_(other.loop_) {}

ReplayTimeline& ReplayTimeline::operator=(const ReplayTimeline& other) {
  first_ns_ = other.first_ns_;
  end_ns_ = other.end_ns_;
  replay_start_ns_.store(other.replay_start_ns_.load(std::memory_order_acquire), std::memory_order_release);
  loop_ = other.loop_;
  return *this;
}

rt::TimeNs ReplayTimeline::replayStart(rt::TimeNs now_ns) const {
  rt::TimeNs start_ns = replay_start_ns_.load(std::memory_order_acquire);
  if (start_ns != kUnanchored) return start_ns;
  // The first device asked anchors the replay; a concurrent first ask from another thread loses the
  // exchange and takes the winner's instant.
  if (replay_start_ns_.compare_exchange_strong(start_ns, now_ns, std::memory_order_acq_rel)) return now_ns;
  return start_ns;
}

rt::TimeNs ReplayTimeline::toRecording(rt::TimeNs now_ns, std::int64_t& lap) const {
  const rt::TimeNs elapsed_ns = now_ns - replayStart(now_ns);
  const rt::TimeNs period_ns = end_ns_ - first_ns_ + 1;  // the end instant is shown, then the start again
  lap = loop_ && elapsed_ns >= 0 ? elapsed_ns / period_ns : 0;
  return first_ns_ + elapsed_ns - lap * period_ns;
}

rt::TimeNs ReplayTimeline::toExecutor(rt::TimeNs rec_ns, std::int64_t lap) const {
  const rt::TimeNs start_ns = replay_start_ns_.load(std::memory_order_acquire);
  // Unanchored (nothing asked yet): as if the replay started now-ish; only toRecording's callers ask.
  return (start_ns == kUnanchored ? 0 : start_ns) + (rec_ns - first_ns_) + lap * (end_ns_ - first_ns_ + 1);
}

bool ReplayTimeline::ended(rt::TimeNs now_ns) const {
  std::int64_t lap = 0;
  return !loop_ && toRecording(now_ns, lap) > end_ns_;
}

rt::Expected<std::shared_ptr<ReplayDataset>> ReplayDataset::open(const ReplayOptions& options,
                                                                 rt::TimeNs replay_start_ns) {
  if (!(options.offset_s >= 0.0 && options.offset_s <= rt::limits::kMaxRunS))
    return rt::Error{"replay: offset_s must be in [0, " + formatSeconds(rt::limits::kMaxRunNs) + "]"};
  auto manifest = readManifest((std::filesystem::path(options.dir) / "manifest.yaml").string());
  if (!manifest) return manifest.error();
  // Built with a provisional timeline; the real one needs the streams' end.
  std::shared_ptr<ReplayDataset> d(new ReplayDataset(
      *manifest, options.dir, ReplayTimeline(manifest->start_ns, manifest->start_ns, replay_start_ns, options),
      options.bad_rows));
  rt::TimeNs end_ns = manifest->start_ns;
  const auto note_end = [&end_ns](const auto& stream) {
    for (const auto& record : stream.samples) end_ns = std::max(end_ns, deliveredNs(record));
  };
  const auto read = [&](const char* device, auto codec, auto& into) -> rt::Status {
    const StreamEntry* e = manifest->stream(device);
    if (e == nullptr) return rt::ok();
    auto s = load<decltype(codec)>(options.dir, *e, options.bad_rows);
    if (!s) return s.error();
    into = std::move(s.value());
    return rt::ok();
  };
  if (rt::Status s = read("odometry", DeliveredOdometryCodec{}, d->odometry_); !s) return s.error();
  if (rt::Status s = read("gimbal", DeliveredGimbalStateCodec{}, d->gimbal_); !s) return s.error();
  if (rt::Status s = read("detections", DeliveredDetectionCodec{}, d->detections_); !s) return s.error();
  if (rt::Status s = read("depth_camera", DeliveredFrameIndexCodec{}, d->depth_frames_); !s) return s.error();
  if (rt::Status s = read("gimbal_camera", DeliveredFrameIndexCodec{}, d->images_); !s) return s.error();
  if (rt::Status s = read("setpoints", SetpointCodec{}, d->setpoints_); !s) return s.error();
  if (rt::Status s = read("gimbal_commands", GimbalCommandCodec{}, d->gimbal_commands_); !s) return s.error();
  if (const StreamEntry* e = manifest->stream("can")) {
    auto log = loadCandump((std::filesystem::path(options.dir) / e->file).string(), options.bad_rows);
    if (!log) return log.error();
    d->can_log_ = std::move(log.value());
  }
  if (d->depth_frames_) {
    if (!manifest->depth_camera) return rt::Error{options.dir + "/manifest.yaml: a depth stream needs depth_camera:"};
    if (rt::Status s = checkFrameFiles(*d->depth_frames_, "png", options.bad_rows); !s) return s.error();
  }
  if (d->images_) {
    if (!manifest->gimbal_camera)
      return rt::Error{options.dir + "/manifest.yaml: a gimbal camera stream needs gimbal_camera:"};
    if (rt::Status s = checkFrameFiles(*d->images_, manifest->gimbal_camera->image_format, options.bad_rows); !s)
      return s.error();
  }
  if (d->odometry_) note_end(*d->odometry_);
  if (d->gimbal_) note_end(*d->gimbal_);
  if (d->detections_) note_end(*d->detections_);
  if (d->depth_frames_) note_end(*d->depth_frames_);
  if (d->images_) note_end(*d->images_);
  // What the actuators were told counts too: a replay runs until the recorded run's last command.
  if (d->setpoints_ && !d->setpoints_->samples.empty())
    end_ns = std::max(end_ns, d->setpoints_->samples.back().stamp_ns);
  if (d->gimbal_commands_ && !d->gimbal_commands_->samples.empty())
    end_ns = std::max(end_ns, d->gimbal_commands_->samples.back().stamp_ns);
  // The input policy: a recording spans at most kMaxRunNs, and an offset must land inside it.
  if (end_ns - manifest->start_ns > rt::limits::kMaxRunNs)
    return rt::Error{options.dir + ": a record lies " + formatSeconds(end_ns - manifest->start_ns) +
                     " after start_ns, past the limit of " + formatSeconds(rt::limits::kMaxRunNs) + " for a recording"};
  if (options.offset_s > 0.0 && rt::secondsToNs(options.offset_s) > end_ns - manifest->start_ns)
    return rt::Error{"offset_s " + formatSeconds(rt::secondsToNs(options.offset_s)) +
                     " is past the recording's last record at " + formatSeconds(end_ns - manifest->start_ns)};
  d->timeline_ = ReplayTimeline(manifest->start_ns, end_ns, replay_start_ns, options);
  return d;
}

template <class Sample>
rt::TimeNs StreamCursor<Sample>::sync(rt::TimeNs now_ns) {
  std::int64_t lap = 0;
  const rt::TimeNs rec_ns = dataset_->timeline().toRecording(now_ns, lap);
  if (lap != lap_ || !lap_started_) {  // a new lap: start the stream again
    lap_ = lap;
    lap_started_ = true;
    next_ = 0;
    // A queue shows nothing delivered before the lap's first instant (the offset).
    const auto& records = stream_->samples;
    served_ = 0;
    while (served_ < records.size() && deliveredNs(records[served_]) < dataset_->timeline().firstNs()) ++served_;
  }
  // Records delivered before the offset are never shown: the first one shown is the newest at the start.
  const auto& records = stream_->samples;
  while (next_ < records.size() && deliveredNs(records[next_]) <= rec_ns) ++next_;
  return rec_ns;
}

template <class Sample>
Sample StreamCursor<Sample>::shown(std::size_t i) {
  Sample out = stream_->samples[i].sample;
  restamp(out, dataset_->timeline().toExecutor(out.stamp_ns, lap_) - out.stamp_ns);
  last_served_ns_ = out.stamp_ns;
  return out;
}

template <class Sample>
std::optional<Sample> StreamCursor<Sample>::newestAt(rt::TimeNs now_ns) {
  if (stream_ == nullptr || stream_->samples.empty()) return std::nullopt;
  sync(now_ns);
  if (next_ == 0) return std::nullopt;
  return shown(next_ - 1);
}

template <class Sample>
std::optional<Sample> StreamCursor<Sample>::newestUnseenAt(rt::TimeNs now_ns) {
  if (stream_ == nullptr || stream_->samples.empty()) return std::nullopt;
  sync(now_ns);
  if (next_ == served_) return std::nullopt;
  served_ = next_;
  return shown(next_ - 1);
}

template <class Sample>
std::optional<Sample> StreamCursor<Sample>::nextAt(rt::TimeNs now_ns) {
  if (stream_ == nullptr || stream_->samples.empty()) return std::nullopt;
  sync(now_ns);
  if (served_ >= next_) return std::nullopt;
  return shown(served_++);
}

template <class Sample>
DeviceHealth StreamCursor<Sample>::health(rt::TimeNs now_ns) const {
  DeviceHealth h;
  h.last_sample_ns = last_served_ns_;
  if (stream_ == nullptr) {
    h.state = DeviceHealth::State::kFailed;
    h.detail = "replay: the recording has no such stream";
    return h;
  }
  h.error_count = stream_->skipped_rows;
  if (dataset_->timeline().ended(now_ns)) {
    h.state = DeviceHealth::State::kFailed;
    h.detail = "replay: the recording has ended";
  } else if (stream_->skipped_rows > 0) {
    h.state = DeviceHealth::State::kDegraded;
    h.detail = "replay: " + std::to_string(stream_->skipped_rows) +
               " bad rows skipped, the first: " + stream_->first_skip_message;
  } else {
    h.state = DeviceHealth::State::kOk;
    h.detail = stream_->truncated_tail ? "replay: " + stream_->path + " ends in a partial record (ignored)"
                                       : "replay: " + stream_->path;
  }
  return h;
}

template class StreamCursor<OdometrySample>;
template class StreamCursor<GimbalState>;
template class StreamCursor<DetectionFrame>;
template class StreamCursor<FrameIndexRow>;

DeviceHealth ReplayGimbalCamera::health(rt::TimeNs now_ns) const {
  const bool images = images_.dataset().images() != nullptr;
  return unreadableHealth(images ? images_.health(now_ns) : detections_.health(now_ns), unreadable_, first_unreadable_);
}

ImageFrameHandle ReplayGimbalCamera::grab(rt::TimeNs now_ns) {
  const ReplayDataset& dataset = images_.dataset();
  if (dataset.images() == nullptr) return {};
  const auto row = images_.newestUnseenAt(now_ns);
  if (!row) return {};
  const RecordedCamera& camera = *dataset.manifest().gimbal_camera;
  auto bgr = readFrameFile(dataset.images()->path, row->file_index, camera.image_format, camera.intrinsics,
                           "gimbal_camera", readImage, unreadable_, first_unreadable_);
  if (!bgr) return {};
  auto frame = std::make_shared<ImageFrame>();
  frame->stamp_ns = row->stamp_ns;
  frame->sequence = row->sequence;
  frame->bgr = std::move(*bgr);
  frame->intrinsics = camera.intrinsics;
  return frame;
}

ReplayDepthCamera::ReplayDepthCamera(const std::shared_ptr<const ReplayDataset>& dataset)
    : cursor_(dataset, dataset->depthFrames()) {
  if (const auto& camera = dataset->manifest().depth_camera) {
    intrinsics_ = camera->intrinsics;
    T_BC_.linear() = camera->R_BC;
    T_BC_.translation() = camera->mount_B_m;
  }
}

DeviceHealth ReplayDepthCamera::health(rt::TimeNs now_ns) const {
  return unreadableHealth(cursor_.health(now_ns), unreadable_, first_unreadable_);
}

DepthFrameHandle ReplayDepthCamera::grab(rt::TimeNs now_ns) {
  const ReplayDataset& dataset = cursor_.dataset();
  if (dataset.depthFrames() == nullptr) return {};
  const auto row = cursor_.newestUnseenAt(now_ns);
  if (!row) return {};
  auto depth = readFrameFile(dataset.depthFrames()->path, row->file_index, "png", intrinsics_, "depth_camera",
                             readDepthPng, unreadable_, first_unreadable_);
  if (!depth) return {};
  auto frame = std::make_shared<DepthFrame>();
  frame->stamp_ns = row->stamp_ns;
  frame->sequence = row->sequence;
  frame->depth_m = std::move(*depth);
  frame->intrinsics = intrinsics_;
  frame->T_BC = T_BC_;
  return frame;
}

DeviceHealth ReplayVehicleLink::health(rt::TimeNs now_ns) const {
  DeviceHealth h;
  h.state = dataset_->timeline().ended(now_ns) ? DeviceHealth::State::kFailed : DeviceHealth::State::kOk;
  h.detail = "replay: setpoints kept for comparison, not flown";
  return h;
}

VehicleStatus ReplayVehicleLink::status(rt::TimeNs now_ns) {
  // The recorded flight was flown under the planner's control: offboard and armed while it lasts.
  const bool live = !dataset_->timeline().ended(now_ns);
  return {now_ns, live, live, live ? FlightMode::kOffboard : FlightMode::kUnknown};
}

}  // namespace aerotrack::hal::replay
