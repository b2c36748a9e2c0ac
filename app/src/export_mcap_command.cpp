// `aerotrack export-mcap DIR` (issue 24 item 1): a recording (hal/replay/README.md) as a flight log for
// Foxglove and Lichtblick, with the topics of `--mcap` (flight_log_writer.hpp) that a recording holds:
//   /tf                         odometry, with the gimbal's newest encoder angle and the cameras' mounting
//   /gimbal_camera/image        the frame files as they are (PNG or JPEG bytes, not re-encoded)
//   /gimbal_camera/detections   and /calibration: the modules' detections (outputs/), else the camera's
//   /depth_camera/points        the depth frames, decimated (5 Hz, one pixel in 8)
//   /person/estimate(/values)   outputs/estimates.csv
//   /planning/trajectory        outputs/trajectories.csv: a recording keeps three points of each (start,
//                               middle, end), so the line has three points
//   /drone/path, /setpoint, /gimbal/command
// Messages are written in time order. Bad rows are skipped and counted (the replay's policy) unless
// --strict; a frame file that cannot be read is skipped and counted.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "aerotrack/hal/replay/frame_files.hpp"
#include "aerotrack/hal/replay/replay_devices.hpp"
#include "aerotrack/rt/input_file.hpp"
#include "aerotrack/rt/input_limits.hpp"
#include "app_config.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "flight_log_writer.hpp"
#include "foxglove_messages.hpp"
#include "output_recorder.hpp"

namespace aerotrack::app {
namespace {

namespace fs = std::filesystem;

/// What one message of the export is made from: a kind and an index into its stream.
enum class Source : std::uint8_t {
  kOdometry,
  kImage,
  kDetection,
  kDepth,
  kEstimate,
  kTrajectory,
  kSetpoint,
  kGimbalCommand
};
struct ExportEvent {
  rt::TimeNs stamp_ns;
  Source source;
  std::size_t index;
};

struct RecordedTrajectory {
  rt::TimeNs stamp_ns;
  std::array<Eigen::Vector3d, 3> points_W_m;
};

/// outputs/<name>: every good row decoded by `decode`; a missing file is no stream (an import has none).
template <class T, class Decode>
rt::Expected<std::vector<T>> readOutputs(const fs::path& file, const std::vector<std::string>& columns,
                                         hal::replay::BadRowPolicy policy, Decode decode, std::uint64_t& skipped) {
  std::vector<T> out;
  if (!fs::exists(file)) return out;
  auto reader = hal::replay::CsvStreamReader::open(file.string(), columns, policy);
  if (!reader) return reader.error();
  while (true) {
    auto record = reader->next();
    if (!record) return record.error();
    if (!*record) break;
    auto value = decode(**record, file.string());
    if (!value) {
      if (policy == hal::replay::BadRowPolicy::kStrict) return value.error();
      ++skipped;
      continue;
    }
    out.push_back(std::move(*value));
  }
  skipped += reader->skippedRows();
  return out;
}

}  // namespace

int exportMcapCommand(const ParsedArgs& args) {
  const std::string dir = *args.positional;
  const std::string out = args.valueOr("out", "out/" + fs::path(dir).filename().string() + ".mcap");
  const auto policy =
      args.flags.count("strict") != 0 ? hal::replay::BadRowPolicy::kStrict : hal::replay::BadRowPolicy::kSkip;
  hal::replay::ReplayOptions replay;
  replay.dir = dir;
  replay.bad_rows = policy;
  auto dataset = hal::replay::ReplayDataset::open(replay, 0);  // the timeline is unused: records keep their stamps
  if (!dataset) return failCommand("export-mcap", dataset.error().message);
  const hal::replay::ReplayDataset& d = **dataset;
  const hal::replay::DatasetManifest& manifest = d.manifest();

  // The gimbal camera's mounting: the recorded run's configuration, else the manifest's mount.
  std::optional<estimation::GimbalCameraExtrinsics> extrinsics;
  if (const fs::path config = fs::path(dir) / "config.yaml"; fs::exists(config)) {
    if (auto recorded = loadAppConfig(config.string()); recorded && recorded->estimation)
      extrinsics = recorded->estimation->task.extrinsics;
  }
  if (!extrinsics && manifest.gimbal_camera) {
    extrinsics.emplace();
    extrinsics->p_BG_m = manifest.gimbal_camera->mount_B_m;
  }
  std::optional<Eigen::Isometry3d> T_BD;
  if (manifest.depth_camera) {
    T_BD = Eigen::Isometry3d::Identity();
    T_BD->linear() = manifest.depth_camera->R_BC;
    T_BD->translation() = manifest.depth_camera->mount_B_m;
  }

  std::uint64_t skipped = 0;
  const fs::path outputs = fs::path(dir) / "outputs";
  auto estimates = readOutputs<estimation::TargetEstimate>(outputs / "estimates.csv", EstimateCodec::columns(), policy,
                                                           EstimateCodec::decode, skipped);
  if (!estimates) return failCommand("export-mcap", estimates.error().message);
  auto detections = readOutputs<hal::DetectionFrame>(outputs / "detections.csv", hal::replay::DetectionCodec::columns(),
                                                     policy, hal::replay::DetectionCodec::decode, skipped);
  if (!detections) return failCommand("export-mcap", detections.error().message);
  auto trajectories = readOutputs<RecordedTrajectory>(
      outputs / "trajectories.csv", TrajectoryCodec::columns(), policy,
      [](const hal::replay::CsvRecord& r, const std::string& path) -> rt::Expected<RecordedTrajectory> {
        const std::vector<double>& v = r.values;
        if (v.size() != 14) return rt::Error{path + ":" + std::to_string(r.line) + ": wrong field count"};
        return RecordedTrajectory{r.stamp_ns,
                                  {Eigen::Vector3d(v[5], v[6], v[7]), Eigen::Vector3d(v[8], v[9], v[10]),
                                   Eigen::Vector3d(v[11], v[12], v[13])}};
      },
      skipped);
  if (!trajectories) return failCommand("export-mcap", trajectories.error().message);
  // The modules' detections if they were recorded (they carry the lock-on's choice), else the camera's own.
  std::vector<hal::DetectionFrame> camera_detections;
  if (detections->empty() && d.detections() != nullptr) {
    for (const auto& delivered : d.detections()->samples) camera_detections.push_back(delivered.sample);
  }
  const std::vector<hal::DetectionFrame>& frames = detections->empty() ? camera_detections : *detections;

  std::vector<ExportEvent> events;
  auto add = [&](Source source, std::size_t n, auto stamp_of) {
    for (std::size_t i = 0; i < n; ++i) events.push_back({stamp_of(i), source, i});
  };
  const auto* odometry = d.odometry();
  if (odometry != nullptr)
    add(Source::kOdometry, odometry->samples.size(),
        [&](std::size_t i) { return odometry->samples[i].sample.stamp_ns; });
  if (d.images() != nullptr)
    add(Source::kImage, d.images()->samples.size(),
        [&](std::size_t i) { return d.images()->samples[i].sample.stamp_ns; });
  add(Source::kDetection, frames.size(), [&](std::size_t i) { return frames[i].stamp_ns; });
  if (d.depthFrames() != nullptr) {
    // 5 Hz of the depth stream, as the live log writes.
    rt::TimeNs next_ns = INT64_MIN;
    const auto& depth = d.depthFrames()->samples;
    for (std::size_t i = 0; i < depth.size(); ++i) {
      if (depth[i].sample.stamp_ns < next_ns) continue;
      next_ns = depth[i].sample.stamp_ns + rt::secondsToNs(0.2);
      events.push_back({depth[i].sample.stamp_ns, Source::kDepth, i});
    }
  }
  add(Source::kEstimate, estimates->size(), [&](std::size_t i) { return (*estimates)[i].stamp_ns; });
  add(Source::kTrajectory, trajectories->size(), [&](std::size_t i) { return (*trajectories)[i].stamp_ns; });
  if (d.setpoints() != nullptr)
    add(Source::kSetpoint, d.setpoints()->samples.size(),
        [&](std::size_t i) { return d.setpoints()->samples[i].stamp_ns; });
  if (d.gimbalCommands() != nullptr) {
    add(Source::kGimbalCommand, d.gimbalCommands()->samples.size(),
        [&](std::size_t i) { return d.gimbalCommands()->samples[i].stamp_ns; });
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const ExportEvent& a, const ExportEvent& b) { return a.stamp_ns < b.stamp_ns; });

  FlightLogTargets targets;
  targets.mcap_path = out;
  auto compression = hal::replay::parseMcapCompression(args.valueOr("mcap-compression", "zstd"));
  if (!compression) return failCommand("export-mcap", "--mcap-compression: " + compression.error().message);
  targets.mcap.compression = *compression;
  auto log = FlightLogWriter::open(targets, /*simulation=*/false);
  if (!log) return failCommand("export-mcap", log.error().message);
  FlightLogWriter& w = **log;

  foxglove::FrameTransforms transforms;
  foxglove::CompressedImage image;
  foxglove::ImageAnnotations annotations;
  foxglove::CameraCalibration calibration;
  foxglove::PointCloud points;
  foxglove::SceneUpdate scene;
  foxglove_log::FlownPath flown_path(1.0);  // seconds a stretch, as the live log's default
  std::size_t gimbal_next = 0;
  double gimbal_angle_rad = 0.0;
  std::uint64_t unreadable_frames = 0;
  const auto* gimbal = d.gimbal();
  const auto* images = d.images();
  const auto* depth_frames = d.depthFrames();
  const auto* setpoints = d.setpoints();
  const auto* gimbal_commands = d.gimbalCommands();
  for (const ExportEvent& e : events) {
    if (!w.active()) break;
    JsonLine json;
    switch (e.source) {
      case Source::kOdometry: {
        if (odometry == nullptr) break;
        const hal::OdometrySample& o = odometry->samples[e.index].sample;
        // The newest encoder reading at the odometry's time.
        while (gimbal != nullptr && gimbal_next < gimbal->samples.size() &&
               gimbal->samples[gimbal_next].sample.stamp_ns <= o.stamp_ns) {
          gimbal_angle_rad = gimbal->samples[gimbal_next++].sample.angle_rad;
        }
        foxglove_log::fillTransforms(transforms, o, gimbal_angle_rad, extrinsics ? &*extrinsics : nullptr,
                                     T_BD ? &*T_BD : nullptr);
        w.write(Topic::kTf, o.stamp_ns, transforms);
        if (flown_path.add(o.stamp_ns, o.p_WB_m, scene)) w.write(Topic::kPath, o.stamp_ns, scene);
        break;
      }
      case Source::kImage: {
        if (images == nullptr) break;
        const hal::replay::FrameIndexRow& row = images->samples[e.index].sample;
        const std::string format = manifest.gimbal_camera ? manifest.gimbal_camera->image_format : "png";
        const fs::path file = fs::path(images->path).parent_path() / hal::replay::frameFileName(row.file_index, format);
        const rt::Expected<std::string> bytes = rt::readBoundedFile(file.string(), rt::limits::kMaxImageFileBytes);
        if (!bytes) {
          ++unreadable_frames;
          break;
        }
        image.Clear();
        foxglove_log::setTime(*image.mutable_timestamp(), row.stamp_ns);
        image.set_frame_id("camera_optical");
        image.set_format(format == "jpg" ? "jpeg" : format);
        image.set_data(*bytes);
        w.write(Topic::kImage, row.stamp_ns, image);
        break;
      }
      case Source::kDetection: {
        const hal::DetectionFrame& frame = frames[e.index];
        foxglove_log::fillAnnotations(annotations, frame, 0.2);
        w.write(Topic::kDetections, frame.stamp_ns, annotations);
        foxglove_log::fillCalibration(calibration, frame.stamp_ns, frame.intrinsics);
        w.write(Topic::kCalibration, frame.stamp_ns, calibration);
        break;
      }
      case Source::kDepth: {
        if (depth_frames == nullptr) break;
        const hal::replay::FrameIndexRow& row = depth_frames->samples[e.index].sample;
        const fs::path file =
            fs::path(depth_frames->path).parent_path() / hal::replay::frameFileName(row.file_index, "png");
        auto depth = hal::replay::readDepthPng(file.string());
        if (!depth || !manifest.depth_camera) {
          ++unreadable_frames;
          break;
        }
        hal::DepthFrame frame;
        frame.stamp_ns = row.stamp_ns;
        frame.depth_m = *depth;
        frame.intrinsics = manifest.depth_camera->intrinsics;
        foxglove_log::fillDepthPoints(points, frame, 8);
        w.write(Topic::kDepth, row.stamp_ns, points);
        break;
      }
      case Source::kEstimate: {
        const estimation::TargetEstimate& estimate = (*estimates)[e.index];
        foxglove_log::fillEstimate(scene, estimate);
        w.write(Topic::kEstimate, estimate.stamp_ns, scene);
        w.writeJson(Topic::kEstimateValues, estimate.stamp_ns, foxglove_log::estimateJson(estimate, json));
        break;
      }
      case Source::kTrajectory: {
        const RecordedTrajectory& t = (*trajectories)[e.index];
        foxglove_log::fillTrajectoryPoints(scene, t.stamp_ns, t.points_W_m);  // the newest replaces the last
        w.write(Topic::kTrajectory, t.stamp_ns, scene);
        break;
      }
      case Source::kSetpoint: {
        if (setpoints == nullptr) break;
        const hal::Setpoint& s = setpoints->samples[e.index];
        w.writeJson(Topic::kSetpoint, s.stamp_ns, foxglove_log::setpointJson(s, json));
        break;
      }
      case Source::kGimbalCommand: {
        if (gimbal_commands == nullptr) break;
        const hal::GimbalCommand& c = gimbal_commands->samples[e.index];
        w.writeJson(Topic::kGimbalCommand, c.stamp_ns, foxglove_log::gimbalCommandJson(c, json));
        break;
      }
    }
  }
  if (flown_path.flush(scene)) w.write(Topic::kPath, flown_path.lastStampNs(), scene);  // the last stretch
  const rt::Status closed = w.close();
  std::printf("%s; %zu records of %s", w.summary().c_str(), events.size(), dir.c_str());
  if (skipped > 0 || unreadable_frames > 0) {
    std::printf(" (%llu bad rows and %llu unreadable frames skipped)", static_cast<unsigned long long>(skipped),
                static_cast<unsigned long long>(unreadable_frames));
  }
  std::printf("\n");
  return closed ? 0 : 1;
}

}  // namespace aerotrack::app
