// Replay devices: see replay_devices.hpp.
#include "aerotrack/hal/replay/replay_devices.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "aerotrack/hal/replay/stream_codecs.hpp"

namespace aerotrack::hal::replay {
namespace {

template <class Codec, class Sample>
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

template <class Sample>
void restamp(Sample& sample, rt::TimeNs stamp_ns) {
  sample.stamp_ns = stamp_ns;
}

}  // namespace

ReplayTimeline::ReplayTimeline(rt::TimeNs recording_start_ns, rt::TimeNs recording_end_ns, rt::TimeNs replay_start_ns,
                               const ReplayOptions& options)
    : first_ns_(recording_start_ns + rt::secondsToNs(options.offset_s)),
      end_ns_(std::max(recording_end_ns, recording_start_ns + rt::secondsToNs(options.offset_s))),
      replay_start_ns_(replay_start_ns),
      loop_(options.loop) {}

rt::TimeNs ReplayTimeline::toRecording(rt::TimeNs now_ns, std::int64_t& lap) const {
  const rt::TimeNs elapsed_ns = now_ns - replay_start_ns_;
  const rt::TimeNs period_ns = end_ns_ - first_ns_ + 1;  // the end instant is shown, then the start again
  lap = loop_ && elapsed_ns >= 0 ? elapsed_ns / period_ns : 0;
  return first_ns_ + elapsed_ns - lap * period_ns;
}

rt::TimeNs ReplayTimeline::toExecutor(rt::TimeNs rec_ns, std::int64_t lap) const {
  return replay_start_ns_ + (rec_ns - first_ns_) + lap * (end_ns_ - first_ns_ + 1);
}

bool ReplayTimeline::ended(rt::TimeNs now_ns) const {
  std::int64_t lap = 0;
  return !loop_ && toRecording(now_ns, lap) > end_ns_;
}

rt::Expected<std::shared_ptr<ReplayDataset>> ReplayDataset::open(const ReplayOptions& options,
                                                                 rt::TimeNs replay_start_ns) {
  if (!(options.offset_s >= 0.0)) return rt::Error{"replay: offset_s must be >= 0"};
  auto manifest = readManifest((std::filesystem::path(options.dir) / "manifest.yaml").string());
  if (!manifest) return manifest.error();
  std::optional<LoadedStream<OdometrySample>> odometry;
  std::optional<LoadedStream<GimbalState>> gimbal;
  std::optional<LoadedStream<Setpoint>> setpoints;
  std::optional<LoadedStream<GimbalCommand>> commands;
  rt::TimeNs end_ns = manifest->start_ns;
  const auto note_end = [&end_ns](const auto& stream) {
    if (!stream.samples.empty()) end_ns = std::max(end_ns, stream.samples.back().stamp_ns);
  };
  if (const StreamEntry* e = manifest->stream("odometry")) {
    auto s = load<OdometryCodec, OdometrySample>(options.dir, *e, options.bad_rows);
    if (!s) return s.error();
    note_end(*s);
    odometry = std::move(s.value());
  }
  if (const StreamEntry* e = manifest->stream("gimbal")) {
    auto s = load<GimbalStateCodec, GimbalState>(options.dir, *e, options.bad_rows);
    if (!s) return s.error();
    note_end(*s);
    gimbal = std::move(s.value());
  }
  if (const StreamEntry* e = manifest->stream("setpoints")) {
    auto s = load<SetpointCodec, Setpoint>(options.dir, *e, options.bad_rows);
    if (!s) return s.error();
    setpoints = std::move(s.value());
  }
  if (const StreamEntry* e = manifest->stream("gimbal_commands")) {
    auto s = load<GimbalCommandCodec, GimbalCommand>(options.dir, *e, options.bad_rows);
    if (!s) return s.error();
    commands = std::move(s.value());
  }
  const ReplayTimeline timeline(manifest->start_ns, end_ns, replay_start_ns, options);
  std::shared_ptr<ReplayDataset> dataset(new ReplayDataset(std::move(manifest.value()), timeline));
  dataset->odometry_ = std::move(odometry);
  dataset->gimbal_ = std::move(gimbal);
  dataset->setpoints_ = std::move(setpoints);
  dataset->gimbal_commands_ = std::move(commands);
  return dataset;
}

template <class Sample>
std::optional<Sample> StreamCursor<Sample>::newestAt(rt::TimeNs now_ns) {
  if (stream_ == nullptr || stream_->samples.empty()) return std::nullopt;
  const std::vector<Sample>& samples = stream_->samples;
  std::int64_t lap = 0;
  const rt::TimeNs rec_ns = dataset_->timeline().toRecording(now_ns, lap);
  if (lap != lap_) {  // a new lap: start the stream again
    lap_ = lap;
    next_ = 0;
  }
  // Samples before the offset are never shown: the first one shown is the newest at the start instant.
  while (next_ < samples.size() && samples[next_].stamp_ns <= rec_ns) ++next_;
  if (next_ == 0) return std::nullopt;
  Sample out = samples[next_ - 1];
  restamp(out, dataset_->timeline().toExecutor(out.stamp_ns, lap_));
  last_served_ns_ = out.stamp_ns;
  return out;
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
