// The flight log's writer on one core (issue 24 item 5; docs/benchmarks.md):
//   BM_McapWrite      the MCAP writer alone: messages of a given size (200 B: a transform or a JSON value;
//                     30 kB: a JPEG frame, incompressible) into a file, per compression (0: none, 1: zstd,
//                     2: lz4) -- messages/s and MB/s.
//   BM_FlightLogMix   what one second of a flight costs the log task: the message mix of `sim --mcap`
//                     (100 transforms, 30 detections and calibrations, 30 estimates, 30 plans, 100
//                     setpoints, ...) filled from our types in an arena, serialized and written, as the
//                     flight log task does it; with the mallocs each message makes.
// Files go to $TMPDIR (default /tmp): the disk is part of what is measured.
#include <benchmark/benchmark.h>
#include <google/protobuf/arena.h>

#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "aerotrack/hal/replay/mcap_writer.hpp"
#include "flight_log_writer.hpp"
#include "foxglove_messages.hpp"
#include "unit/malloc_counter.hpp"

namespace aerotrack {
namespace {

std::string tempPath(const char* name) {
  const char* dir = std::getenv("TMPDIR");
  return (std::filesystem::path(dir != nullptr ? dir : "/tmp") / name).string();
}

void BM_McapWrite(benchmark::State& state) {
  hal::replay::McapWriterOptions options;
  options.compression = static_cast<hal::replay::McapCompression>(state.range(0));
  const auto size = static_cast<std::size_t>(state.range(1));
  auto writer = hal::replay::McapWriter::open(tempPath("bench_flight_log.mcap"), options);
  if (!writer) {
    state.SkipWithError(writer.error().message.c_str());
    return;
  }
  const auto schema = (*writer)->addSchema("s", "jsonschema", std::vector<std::uint8_t>{'{', '}'});
  const std::uint16_t channel = *(*writer)->addChannel(*schema, "/t", "json");
  // A small message is structured (fields, repeated keys: it compresses); a large one is a JPEG frame, which
  // does not: random bytes, 64 different frames (more than a chunk holds, so none repeats inside one).
  std::vector<std::vector<std::uint8_t>> payloads(size > 1000 ? 64 : 1, std::vector<std::uint8_t>(size));
  std::mt19937 rng(1);
  for (auto& data : payloads) {
    for (std::size_t i = 0; i < size; ++i) {
      data[i] = size > 1000 ? static_cast<std::uint8_t>(rng())
                            : static_cast<std::uint8_t>("{\"p_W_m\":[1.25,-0.5,2.0]}"[i % 25]);
    }
  }
  std::uint64_t t = 0;
  std::size_t next = 0;
  for (auto _ : state) {
    (void)(*writer)->write(channel, t, t, payloads[next]);
    next = (next + 1) % payloads.size();
    t += 1000;
  }
  (void)(*writer)->close();
  state.SetItemsProcessed(state.iterations());
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(size));
  state.counters["file_MB"] = static_cast<double>((*writer)->stats().bytes_written) / 1e6;
  std::filesystem::remove(tempPath("bench_flight_log.mcap"));
}
BENCHMARK(BM_McapWrite)
    ->ArgNames({"compression", "bytes"})
    ->ArgsProduct({{0, 1, 2}, {200, 30000}})
    ->Unit(benchmark::kMicrosecond);

void BM_FlightLogMix(benchmark::State& state) {
  app::FlightLogTargets targets;
  targets.mcap_path = tempPath("bench_flight_log_mix.mcap");
  auto log = app::FlightLogWriter::open(targets, true);
  if (!log) {
    state.SkipWithError(log.error().message.c_str());
    return;
  }
  app::FlightLogWriter& w = **log;
  hal::OdometrySample odometry;
  odometry.p_WB_m = {1.0, 2.0, 1.5};
  estimation::GimbalCameraExtrinsics extrinsics;
  hal::DetectionFrame detections;
  detections.person_count = 2;
  detections.target_index = 0;
  for (auto& person : detections.persons) {
    for (std::size_t i = 0; i < hal::kNumKeypoints; ++i) person.keypoints[i] = {300.0 + 3.0 * i, 200.0 + 5.0 * i, 0.8};
  }
  detections.intrinsics = {640, 480, 500.0, 500.0, 320.0, 240.0, {}};
  estimation::TargetEstimate estimate;
  estimate.initialised = true;
  estimate.lost = false;
  estimate.covariance = estimation::Matrix6d::Identity() * 0.01;
  estimate.v_WT_mps = {1.0, 0.2, 0.0};
  planning::PlanSnapshot plan;
  plan.box_count = 6;
  plan.search_count = planning::kSnapshotPathSamples;
  plan.prediction_count = planning::kSnapshotPredictionSamples;
  hal::Setpoint setpoint;
  // As the flight log task does it (flight_log.hpp): each 10 ms step's messages made in an arena over a
  // block reserved once, reset after the step; JSON values written into a fixed buffer.
  std::vector<char> block(8U << 20);
  google::protobuf::ArenaOptions arena_options;
  arena_options.initial_block = block.data();
  arena_options.initial_block_size = block.size();
  google::protobuf::Arena arena(arena_options);
  rt::TimeNs t = 0;
  std::int64_t messages = 0;
  long mallocs = 0;
  for (auto _ : state) {  // one simulated second: 100 Hz odometry, 30 Hz camera, estimates and plans
    const aerotrack::test::MallocCount count;
    for (int k = 0; k < 100; ++k, t += 10'000'000) {
      odometry.stamp_ns = t;
      auto& transforms = *google::protobuf::Arena::CreateMessage<foxglove::FrameTransforms>(&arena);
      app::foxglove_log::fillTransforms(transforms, odometry, 0.1 * k, &extrinsics, nullptr);
      w.write(app::Topic::kTf, t, transforms);
      setpoint.stamp_ns = t;
      app::JsonLine json;
      w.writeJson(app::Topic::kSetpoint, t, app::foxglove_log::setpointJson(setpoint, json));
      messages += 2;
      if (k % 3 == 0) {
        detections.stamp_ns = t;
        auto& annotations = *google::protobuf::Arena::CreateMessage<foxglove::ImageAnnotations>(&arena);
        app::foxglove_log::fillAnnotations(annotations, detections, 0.2);
        w.write(app::Topic::kDetections, t, annotations);
        auto& calibration = *google::protobuf::Arena::CreateMessage<foxglove::CameraCalibration>(&arena);
        app::foxglove_log::fillCalibration(calibration, t, detections.intrinsics);
        w.write(app::Topic::kCalibration, t, calibration);
        estimate.stamp_ns = t;
        auto& scene = *google::protobuf::Arena::CreateMessage<foxglove::SceneUpdate>(&arena);
        app::foxglove_log::fillEstimate(scene, estimate);
        w.write(app::Topic::kEstimate, t, scene);
        app::JsonLine json2;
        w.writeJson(app::Topic::kEstimateValues, t, app::foxglove_log::estimateJson(estimate, json2));
        plan.stamp_ns = t;
        auto& plan_scene = *google::protobuf::Arena::CreateMessage<foxglove::SceneUpdate>(&arena);
        app::foxglove_log::fillPlan(plan_scene, plan);
        w.write(app::Topic::kPlan, t, plan_scene);
        messages += 5;
      }
      arena.Reset();
    }
    mallocs += count.count();
  }
  (void)w.close();
  state.SetItemsProcessed(messages);
  state.counters["mallocs_per_message"] = static_cast<double>(mallocs) / static_cast<double>(messages);
  std::filesystem::remove(tempPath("bench_flight_log_mix.mcap"));
}
BENCHMARK(BM_FlightLogMix)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace aerotrack
