// The recorder: see recorder.hpp.
#include "aerotrack/hal/replay/recorder.hpp"

#include <filesystem>
#include <system_error>
#include <utility>

#include "aerotrack/hal/replay/stream_codecs.hpp"

namespace aerotrack::hal::replay {
namespace {

constexpr rt::DurationNs kIdleWaitNs = 20 * rt::kNsPerMillisecond;

struct StreamFile {
  const char* device;
  const char* file;
  const std::vector<std::string>& columns;
};

std::array<StreamFile, kRecordedStreams> streamFiles() {
  return {StreamFile{"odometry", "odometry.csv", OdometryCodec::columns()},
          StreamFile{"gimbal", "gimbal.csv", GimbalStateCodec::columns()},
          StreamFile{"gimbal_commands", "gimbal_commands.csv", GimbalCommandCodec::columns()},
          StreamFile{"setpoints", "setpoints.csv", SetpointCodec::columns()}};
}

template <class T, class Codec>
bool drain(rt::SpscQueue<T>& queue, CsvStreamWriter& writer, std::atomic<std::uint64_t>& written,
           rt::Status& first_error) {
  bool any = false;
  T item;
  while (queue.try_pop(item)) {
    any = true;
    if (!first_error) continue;  // the disk failed: keep draining, stop writing
    if (rt::Status s = writer.write(item.stamp_ns, Codec::encode(item)); !s) {
      first_error = s;
      continue;
    }
    written.fetch_add(1, std::memory_order_relaxed);
  }
  return any;
}

}  // namespace

rt::Expected<std::unique_ptr<DatasetRecorder>> DatasetRecorder::start(const RecorderOptions& options,
                                                                      rt::TimeNs start_ns) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(options.dir, ec);
  if (ec) return rt::Error{"record: " + options.dir + ": cannot create: " + ec.message()};
  const fs::path manifest_path = fs::path(options.dir) / "manifest.yaml";
  if (fs::exists(manifest_path)) {
    return rt::Error{"record: " + options.dir + " already holds a recording (manifest.yaml); choose a new folder"};
  }
  DatasetManifest manifest;
  manifest.software_version = options.software_version;
  manifest.start_ns = start_ns;
  manifest.source = options.source;
  std::vector<CsvStreamWriter> opened;
  for (const StreamFile& f : streamFiles()) {
    auto writer = CsvStreamWriter::create((fs::path(options.dir) / f.file).string(), f.columns);
    if (!writer) return rt::Error{"record: " + writer.error().message};
    opened.push_back(std::move(writer.value()));
    manifest.streams.push_back({f.device, f.file});
  }
  if (rt::Status s = writeManifest(manifest, manifest_path.string()); !s)
    return rt::Error{"record: " + s.error().message};
  std::unique_ptr<DatasetRecorder> recorder(new DatasetRecorder(
      options, {std::move(opened[0]), std::move(opened[1]), std::move(opened[2]), std::move(opened[3])}));
  recorder->thread_ = std::thread([r = recorder.get()] { r->run(); });
  return recorder;
}

DatasetRecorder::DatasetRecorder(RecorderOptions options, std::array<CsvStreamWriter, kRecordedStreams> writers)
    : options_(std::move(options)),
      writers_(std::move(writers)),
      odometry_(options_.queue_capacity, rt::OverflowPolicy::kDropNewest),
      gimbal_(options_.queue_capacity, rt::OverflowPolicy::kDropNewest),
      commands_(options_.queue_capacity, rt::OverflowPolicy::kDropNewest),
      setpoints_(options_.queue_capacity, rt::OverflowPolicy::kDropNewest) {}

DatasetRecorder::~DatasetRecorder() {
  (void)stop();
}

bool DatasetRecorder::drainOnce() {
  bool any = false;
  any |= drain<OdometrySample, OdometryCodec>(odometry_, writers_[index(RecordedStream::kOdometry)],
                                              written_[index(RecordedStream::kOdometry)], first_error_);
  any |= drain<GimbalState, GimbalStateCodec>(gimbal_, writers_[index(RecordedStream::kGimbal)],
                                              written_[index(RecordedStream::kGimbal)], first_error_);
  any |= drain<GimbalCommand, GimbalCommandCodec>(commands_, writers_[index(RecordedStream::kGimbalCommands)],
                                                  written_[index(RecordedStream::kGimbalCommands)], first_error_);
  any |= drain<Setpoint, SetpointCodec>(setpoints_, writers_[index(RecordedStream::kSetpoints)],
                                        written_[index(RecordedStream::kSetpoints)], first_error_);
  return any;
}

void DatasetRecorder::run() {
  while (!stop_.load(std::memory_order_acquire)) {
    doorbell_.consume();
    if (!drainOnce()) doorbell_.waitFor(kIdleWaitNs);
  }
  drainOnce();  // what the producers pushed before stop()
}

rt::Status DatasetRecorder::stop() {
  if (stopped_) return first_error_;
  stopped_ = true;
  stop_.store(true, std::memory_order_release);
  doorbell_.ring();
  if (thread_.joinable()) thread_.join();
  for (CsvStreamWriter& w : writers_) {
    if (rt::Status s = w.close(); !s && first_error_) first_error_ = s;
  }
  return first_error_;
}

std::uint64_t DatasetRecorder::dropped(RecordedStream s) const {
  switch (s) {
    case RecordedStream::kOdometry:
      return odometry_.dropped();
    case RecordedStream::kGimbal:
      return gimbal_.dropped();
    case RecordedStream::kGimbalCommands:
      return commands_.dropped();
    case RecordedStream::kSetpoints:
      return setpoints_.dropped();
  }
  return 0;
}

std::optional<OdometrySample> RecordingOdometry::read(rt::TimeNs now_ns) {
  std::optional<OdometrySample> sample = inner_->read(now_ns);
  if (sample && sample->stamp_ns > last_stamp_ns_) {  // devices may repeat their newest sample
    last_stamp_ns_ = sample->stamp_ns;
    recorder_.record(*sample);
  }
  return sample;
}

void RecordingGimbal::command(const GimbalCommand& command) {
  recorder_.record(command);
  inner_->command(command);
}

std::optional<GimbalState> RecordingGimbal::read(rt::TimeNs now_ns) {
  std::optional<GimbalState> state = inner_->read(now_ns);
  if (state && state->stamp_ns > last_stamp_ns_) {
    last_stamp_ns_ = state->stamp_ns;
    recorder_.record(*state);
  }
  return state;
}

void RecordingVehicleLink::send(const Setpoint& setpoint) {
  recorder_.record(setpoint);
  inner_->send(setpoint);
}

}  // namespace aerotrack::hal::replay
