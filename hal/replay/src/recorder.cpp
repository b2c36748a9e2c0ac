// The recorder: see recorder.hpp.
#include "aerotrack/hal/replay/recorder.hpp"

#include <algorithm>
#include <filesystem>
#include <system_error>
#include <utility>

#include "aerotrack/hal/replay/frame_files.hpp"

namespace aerotrack::hal::replay {
namespace {

constexpr rt::DurationNs kIdleWaitNs = 20 * rt::kNsPerMillisecond;

struct StreamFile {
  RecordedStream stream;
  const char* device;
  const char* file;
  const std::vector<std::string>& columns;
};

std::array<StreamFile, kRecordedStreams> streamFiles() {
  return {StreamFile{RecordedStream::kOdometry, "odometry", "odometry.csv", DeliveredOdometryCodec::columns()},
          StreamFile{RecordedStream::kGimbal, "gimbal", "gimbal.csv", DeliveredGimbalStateCodec::columns()},
          StreamFile{RecordedStream::kGimbalCommands, "gimbal_commands", "gimbal_commands.csv",
                     GimbalCommandCodec::columns()},
          StreamFile{RecordedStream::kSetpoints, "setpoints", "setpoints.csv", SetpointCodec::columns()},
          StreamFile{RecordedStream::kDetections, "detections", "gimbal_camera/detections.csv",
                     DeliveredDetectionCodec::columns()},
          StreamFile{RecordedStream::kDepthFrames, "depth_camera", "depth_camera/frames.csv",
                     DeliveredFrameIndexCodec::columns()},
          StreamFile{RecordedStream::kImages, "gimbal_camera", "gimbal_camera/frames.csv",
                     DeliveredFrameIndexCodec::columns()}};
}

template <class T>
rt::TimeNs stampOf(const T& item) {
  return item.stamp_ns;
}
template <class T>
rt::TimeNs stampOf(const Delivered<T>& item) {
  return item.sample.stamp_ns;
}

template <class T, class Codec>
bool drain(rt::SpscQueue<T>& queue, CsvStreamWriter& writer, std::atomic<std::uint64_t>& written,
           rt::Status& first_error) {
  bool any = false;
  T item;
  while (queue.try_pop(item)) {
    any = true;
    if (!first_error) continue;  // the disk failed: keep draining, stop writing
    if (rt::Status s = writer.write(stampOf(item), Codec::encode(item)); !s) {
      first_error = s;
      continue;
    }
    written.fetch_add(1, std::memory_order_relaxed);
  }
  return any;
}

}  // namespace

const char* toString(RecordedStream stream) {
  switch (stream) {
    case RecordedStream::kOdometry:
      return "odometry";
    case RecordedStream::kGimbal:
      return "gimbal";
    case RecordedStream::kGimbalCommands:
      return "gimbal commands";
    case RecordedStream::kSetpoints:
      return "setpoints";
    case RecordedStream::kDetections:
      return "detections";
    case RecordedStream::kDepthFrames:
      return "depth frames";
    case RecordedStream::kImages:
      return "images";
  }
  return "?";
}

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
  for (const char* folder : {"gimbal_camera", "depth_camera"}) {
    fs::create_directories(fs::path(options.dir) / folder, ec);
    if (ec) return rt::Error{"record: " + options.dir + "/" + folder + ": cannot create: " + ec.message()};
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
    // The camera streams are listed once their first frame has given the camera's intrinsics.
    if (f.stream != RecordedStream::kDepthFrames && f.stream != RecordedStream::kImages)
      manifest.streams.push_back({f.device, f.file});
  }
  if (rt::Status s = writeManifest(manifest, manifest_path.string()); !s)
    return rt::Error{"record: " + s.error().message};
  std::unique_ptr<DatasetRecorder> recorder(new DatasetRecorder(options, std::move(manifest), std::move(opened)));
  recorder->thread_ = std::thread([r = recorder.get()] { r->run(); });
  return recorder;
}

DatasetRecorder::DatasetRecorder(RecorderOptions options, DatasetManifest manifest,
                                 std::vector<CsvStreamWriter> writers)
    : options_(std::move(options)),
      manifest_(std::move(manifest)),
      writers_(std::move(writers)),
      odometry_(options_.queue_capacity, rt::OverflowPolicy::kDropNewest),
      gimbal_(options_.queue_capacity, rt::OverflowPolicy::kDropNewest),
      commands_(options_.queue_capacity, rt::OverflowPolicy::kDropNewest),
      setpoints_(options_.queue_capacity, rt::OverflowPolicy::kDropNewest),
      detections_(options_.queue_capacity, rt::OverflowPolicy::kDropNewest),
      depth_(options_.frame_queue_capacity, rt::OverflowPolicy::kDropNewest),
      images_(options_.frame_queue_capacity, rt::OverflowPolicy::kDropNewest) {}

DatasetRecorder::~DatasetRecorder() {
  (void)stop();
}

rt::Status DatasetRecorder::writeFrame(const FrameRecord<DepthFrame>& record, std::uint64_t file_index) {
  const DepthFrame& f = *record.frame;
  if (!manifest_.depth_camera) {
    RecordedCamera camera;
    camera.intrinsics = f.intrinsics;
    camera.mount_B_m = f.T_BC.translation();
    camera.R_BC = f.T_BC.linear();
    manifest_.depth_camera = camera;
    manifest_.streams.push_back({"depth_camera", "depth_camera/frames.csv"});
    const std::string path = (std::filesystem::path(options_.dir) / "manifest.yaml").string();
    if (rt::Status s = writeManifest(manifest_, path); !s) return s;
  }
  const std::string file = (std::filesystem::path(options_.dir) / "depth_camera" / frameFileName(file_index, "png"));
  return writeDepthPng(file, f.depth_m);
}

rt::Status DatasetRecorder::writeFrame(const FrameRecord<ImageFrame>& record, std::uint64_t file_index) {
  const ImageFrame& f = *record.frame;
  if (!manifest_.gimbal_camera) {
    RecordedCamera camera;  // the mount is the estimator's configuration, not the camera's: left at 0
    camera.intrinsics = f.intrinsics;
    camera.image_format = "png";  // lossless: a replay detects on the very pixels the run did
    manifest_.gimbal_camera = camera;
    manifest_.streams.push_back({"gimbal_camera", "gimbal_camera/frames.csv"});
    const std::string path = (std::filesystem::path(options_.dir) / "manifest.yaml").string();
    if (rt::Status s = writeManifest(manifest_, path); !s) return s;
  }
  const std::string file = (std::filesystem::path(options_.dir) / "gimbal_camera" / frameFileName(file_index, "png"));
  return writeImage(file, f.bgr);
}

template <class Frame>
bool DatasetRecorder::drainFrames(rt::SpscQueue<FrameRecord<Frame>>& queue, RecordedStream stream) {
  bool any = false;
  FrameRecord<Frame> record;
  while (queue.try_pop(record)) {
    any = true;
    if (!first_error_) continue;
    const std::uint64_t file_index = written_[index(stream)].load(std::memory_order_relaxed) + 1;
    // The image first, then its index row: a recording cut in between lists only whole frames.
    rt::Status s = writeFrame(record, file_index);
    if (s) {
      const FrameIndexRow row{record.frame->sequence, file_index, record.frame->stamp_ns};
      s = writers_[index(stream)].write(row.stamp_ns, DeliveredFrameIndexCodec::encode({row, record.delay_ns}));
    }
    record.frame.reset();  // the producer's pool may reuse it
    if (!s) {
      first_error_ = s;
      continue;
    }
    written_[index(stream)].fetch_add(1, std::memory_order_relaxed);
  }
  return any;
}

bool DatasetRecorder::drainOnce() {
  bool any = false;
  const auto writer = [this](RecordedStream s) -> CsvStreamWriter& { return writers_[index(s)]; };
  const auto count = [this](RecordedStream s) -> std::atomic<std::uint64_t>& { return written_[index(s)]; };
  using S = RecordedStream;
  any |= drain<Delivered<OdometrySample>, DeliveredOdometryCodec>(odometry_, writer(S::kOdometry), count(S::kOdometry),
                                                                  first_error_);
  any |= drain<Delivered<GimbalState>, DeliveredGimbalStateCodec>(gimbal_, writer(S::kGimbal), count(S::kGimbal),
                                                                  first_error_);
  any |= drain<GimbalCommand, GimbalCommandCodec>(commands_, writer(S::kGimbalCommands), count(S::kGimbalCommands),
                                                  first_error_);
  any |= drain<Setpoint, SetpointCodec>(setpoints_, writer(S::kSetpoints), count(S::kSetpoints), first_error_);
  any |= drain<Delivered<DetectionFrame>, DeliveredDetectionCodec>(detections_, writer(S::kDetections),
                                                                   count(S::kDetections), first_error_);
  any |= drainFrames(depth_, S::kDepthFrames);
  any |= drainFrames(images_, S::kImages);
  return any;
}

void DatasetRecorder::run() {
  while (!stop_.load(std::memory_order_acquire)) {
    doorbell_.consume();
    if (!drainOnce()) doorbell_.waitFor(kIdleWaitNs);
  }
  drainOnce();  // what the producers pushed before stop()
}

rt::Status DatasetRecorder::stop(std::optional<rt::TimeNs> end_ns) {
  if (stopped_) return first_error_;
  stopped_ = true;
  stop_.store(true, std::memory_order_release);
  doorbell_.ring();
  if (thread_.joinable()) thread_.join();
  for (CsvStreamWriter& w : writers_) {
    if (rt::Status s = w.close(); !s && first_error_) first_error_ = s;
  }
  if (end_ns && first_error_) {  // the writer thread has stopped: the manifest is this thread's now
    manifest_.end_ns = std::max(*end_ns, manifest_.start_ns);
    first_error_ = writeManifest(manifest_, (std::filesystem::path(options_.dir) / "manifest.yaml").string());
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
    case RecordedStream::kDetections:
      return detections_.dropped();
    case RecordedStream::kDepthFrames:
      return depth_.dropped();
    case RecordedStream::kImages:
      return images_.dropped();
  }
  return 0;
}

std::string DatasetRecorder::summary() const {
  std::string out;
  for (std::size_t i = 0; i < kRecordedStreams; ++i) {
    const auto s = static_cast<RecordedStream>(i);
    if (written(s) == 0 && dropped(s) == 0) continue;
    out += (out.empty() ? "" : ", ") + std::string(toString(s)) + " " + std::to_string(written(s));
  }
  return out;
}

std::uint64_t DatasetRecorder::droppedTotal() const {
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < kRecordedStreams; ++i) total += dropped(static_cast<RecordedStream>(i));
  return total;
}

std::optional<OdometrySample> RecordingOdometry::read(rt::TimeNs now_ns) {
  std::optional<OdometrySample> sample = inner_->read(now_ns);
  if (sample && sample->stamp_ns > last_stamp_ns_) {  // devices may repeat their newest sample
    last_stamp_ns_ = sample->stamp_ns;
    recorder_.record(Delivered<OdometrySample>{*sample, now_ns - sample->stamp_ns});
  }
  return sample;
}

ImageFrameHandle RecordingGimbalCamera::grab(rt::TimeNs now_ns) {
  ImageFrameHandle frame = inner_->grab(now_ns);
  if (frame) recorder_.record(FrameRecord<ImageFrame>{frame, now_ns - frame->stamp_ns});
  return frame;
}

std::optional<DetectionFrame> RecordingGimbalCamera::grabDetections(rt::TimeNs now_ns) {
  std::optional<DetectionFrame> frame = inner_->grabDetections(now_ns);
  if (frame) recorder_.record(Delivered<DetectionFrame>{*frame, now_ns - frame->stamp_ns});
  return frame;
}

DepthFrameHandle RecordingDepthCamera::grab(rt::TimeNs now_ns) {
  DepthFrameHandle frame = inner_->grab(now_ns);
  if (frame) recorder_.record(FrameRecord<DepthFrame>{frame, now_ns - frame->stamp_ns});
  return frame;
}

void RecordingGimbal::command(const GimbalCommand& command) {
  recorder_.record(command);
  inner_->command(command);
}

std::optional<GimbalState> RecordingGimbal::read(rt::TimeNs now_ns) {
  std::optional<GimbalState> state = inner_->read(now_ns);
  if (state && state->stamp_ns > last_stamp_ns_) {
    last_stamp_ns_ = state->stamp_ns;
    recorder_.record(Delivered<GimbalState>{*state, now_ns - state->stamp_ns});
  }
  return state;
}

void RecordingVehicleLink::send(const Setpoint& setpoint) {
  recorder_.record(setpoint);
  inner_->send(setpoint);
}

}  // namespace aerotrack::hal::replay
