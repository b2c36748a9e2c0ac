// The flight log's file: see flight_log_writer.hpp.
#include "flight_log_writer.hpp"

#include <foxglove/CameraCalibration.pb.h>
#include <foxglove/CompressedImage.pb.h>
#include <foxglove/FrameTransforms.pb.h>
#include <foxglove/ImageAnnotations.pb.h>
#include <foxglove/PointCloud.pb.h>
#include <foxglove/SceneUpdate.pb.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "foxglove_messages.hpp"

namespace aerotrack::app {
namespace {

/// A topic: its name, and either its protobuf type or (null) the name of its JSON schema.
struct TopicSpec {
  Topic topic;
  const char* name;
  const google::protobuf::Descriptor* (*proto)();
  const char* json_schema;
  bool simulation_only;
};

template <class T>
const google::protobuf::Descriptor* descriptorOf() {
  return T::descriptor();
}

constexpr TopicSpec kTopics[] = {
    {Topic::kTf, "/tf", descriptorOf<foxglove::FrameTransforms>, nullptr, false},
    {Topic::kImage, "/gimbal_camera/image", descriptorOf<foxglove::CompressedImage>, nullptr, false},
    {Topic::kCalibration, "/gimbal_camera/calibration", descriptorOf<foxglove::CameraCalibration>, nullptr, false},
    {Topic::kDetections, "/gimbal_camera/detections", descriptorOf<foxglove::ImageAnnotations>, nullptr, false},
    {Topic::kDepth, "/depth_camera/points", descriptorOf<foxglove::PointCloud>, nullptr, false},
    {Topic::kEstimate, "/person/estimate", descriptorOf<foxglove::SceneUpdate>, nullptr, false},
    {Topic::kEstimateValues, "/person/estimate/values", nullptr, "aerotrack.TargetEstimate", false},
    {Topic::kTrajectory, "/planning/trajectory", descriptorOf<foxglove::SceneUpdate>, nullptr, false},
    {Topic::kPlan, "/planning/plan", descriptorOf<foxglove::SceneUpdate>, nullptr, false},
    {Topic::kPlanValues, "/planning/cycle", nullptr, "aerotrack.PlanCycle", false},
    {Topic::kPath, "/drone/path", descriptorOf<foxglove::SceneUpdate>, nullptr, false},
    {Topic::kMap, "/map/occupied", descriptorOf<foxglove::SceneUpdate>, nullptr, false},
    {Topic::kSupervisor, "/supervisor", nullptr, "aerotrack.SupervisorState", false},
    {Topic::kSetpoint, "/setpoint", nullptr, "aerotrack.Setpoint", false},
    {Topic::kGimbalCommand, "/gimbal/command", nullptr, "aerotrack.GimbalCommand", false},
    {Topic::kTiming, "/timing", nullptr, "aerotrack.TaskTimings", false},
    {Topic::kHealth, "/health", nullptr, "aerotrack.DeviceHealth", false},
    {Topic::kObstacles, "/sim/obstacles", descriptorOf<foxglove::SceneUpdate>, nullptr, true},
    {Topic::kTruth, "/sim/truth", descriptorOf<foxglove::SceneUpdate>, nullptr, true},
    {Topic::kTruthValues, "/sim/truth/values", nullptr, "aerotrack.SimTruth", true},
};
static_assert(std::size(kTopics) == static_cast<std::size_t>(Topic::kCount));

/// A JSON schema that accepts any object: what Foxglove needs to plot a JSON topic's fields.
constexpr std::string_view kAnyObject = R"({"type":"object"})";

std::span<const std::uint8_t> bytesOf(std::string_view s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

}  // namespace

const char* topicName(Topic topic) {
  return kTopics[static_cast<std::size_t>(topic)].name;
}

rt::Expected<std::unique_ptr<FlightLogWriter>> FlightLogWriter::open(const std::string& path,
                                                                     const hal::replay::McapWriterOptions& options,
                                                                     bool simulation) {
  auto mcap = hal::replay::McapWriter::open(path, options);
  if (!mcap) return mcap.error();
  std::unique_ptr<FlightLogWriter> log(new FlightLogWriter(std::move(mcap.value()), options.compression));
  log->buffer_.reserve(1U << 16);
  hal::replay::McapWriter& w = *log->writer_;
  std::map<std::string, std::uint16_t> schemas;  // one schema per type, shared by its topics
  for (const TopicSpec& spec : kTopics) {
    if (spec.simulation_only && !simulation) continue;
    const std::string schema_name = spec.proto != nullptr ? spec.proto()->full_name() : spec.json_schema;
    auto it = schemas.find(schema_name);
    if (it == schemas.end()) {
      const std::string data =
          spec.proto != nullptr ? foxglove_log::fileDescriptorSet(*spec.proto()) : std::string(kAnyObject);
      auto id = w.addSchema(schema_name, spec.proto != nullptr ? "protobuf" : "jsonschema", bytesOf(data));
      if (!id) return id.error();
      it = schemas.emplace(schema_name, *id).first;
    }
    auto channel = w.addChannel(it->second, spec.name, spec.proto != nullptr ? "protobuf" : "json");
    if (!channel) return channel.error();
    log->channels_[static_cast<std::size_t>(spec.topic)] = *channel;
  }
  return log;
}

void FlightLogWriter::write(Topic topic, rt::TimeNs stamp_ns, const google::protobuf::Message& message) {
  const std::uint16_t channel = channels_[static_cast<std::size_t>(topic)];
  if (channel == 0) return;
  if (!healthy()) {
    (void)writer_->write(channel, 0, 0, {});  // counted as dropped
    return;
  }
  const std::size_t size = message.ByteSizeLong();
  if (buffer_.size() < size) buffer_.resize(size);
  if (!message.SerializeToArray(buffer_.data(), static_cast<int>(size))) return;
  const auto t = static_cast<std::uint64_t>(std::max<rt::TimeNs>(stamp_ns, 0));
  (void)writer_->write(channel, t, t, std::span<const std::uint8_t>(buffer_.data(), size));
}

void FlightLogWriter::writeJson(Topic topic, rt::TimeNs stamp_ns, std::string_view json) {
  const std::uint16_t channel = channels_[static_cast<std::size_t>(topic)];
  if (channel == 0) return;
  const auto t = static_cast<std::uint64_t>(std::max<rt::TimeNs>(stamp_ns, 0));
  (void)writer_->write(channel, t, t, bytesOf(json));
}

std::string FlightLogWriter::summary() const {
  const hal::replay::McapWriterStats& s = writer_->stats();
  const char* compression = hal::replay::mcapCompressionName(compression_);
  char line[512];
  std::snprintf(line, sizeof(line), "flight log %s: %llu messages, %.1f MB in %llu chunks (%s)",
                writer_->path().c_str(), static_cast<unsigned long long>(s.messages),
                static_cast<double>(s.bytes_written) / 1e6, static_cast<unsigned long long>(s.chunks),
                compression[0] != '\0' ? compression : "uncompressed");
  std::string out = line;
  if (!writer_->failure()) {
    out += "; stopped early, " + std::to_string(s.dropped) +
           " messages not written: " + writer_->failure().error().message;
  }
  return out;
}

}  // namespace aerotrack::app
