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

FlightLogWriter::~FlightLogWriter() = default;

rt::Expected<std::unique_ptr<FlightLogWriter>> FlightLogWriter::open(const FlightLogTargets& targets, bool simulation) {
  std::unique_ptr<FlightLogWriter> log(new FlightLogWriter());
  log->buffer_.reserve(1U << 16);
  log->compression_ = targets.mcap.compression;
  if (!targets.mcap_path.empty()) {
    auto mcap = hal::replay::McapWriter::open(targets.mcap_path, targets.mcap);
    if (!mcap) return mcap.error();
    log->mcap_ = std::move(mcap.value());
  }
  std::map<std::string, std::uint16_t> schemas;  // one schema per type in the file, shared by its topics
  std::vector<live::Channel> live_channels;
  for (const TopicSpec& spec : kTopics) {
    if (spec.simulation_only && !simulation) continue;
    const bool proto = spec.proto != nullptr;
    const std::string schema_name = proto ? spec.proto()->full_name() : spec.json_schema;
    const std::string data = proto ? foxglove_log::fileDescriptorSet(*spec.proto()) : std::string(kAnyObject);
    const auto index = static_cast<std::size_t>(spec.topic);
    if (log->mcap_) {
      hal::replay::McapWriter& w = *log->mcap_;
      auto it = schemas.find(schema_name);
      if (it == schemas.end()) {
        auto id = w.addSchema(schema_name, proto ? "protobuf" : "jsonschema", bytesOf(data));
        if (!id) return id.error();
        it = schemas.emplace(schema_name, *id).first;
      }
      auto channel = w.addChannel(it->second, spec.name, proto ? "protobuf" : "json");
      if (!channel) return channel.error();
      log->channels_[index] = *channel;
    }
    // The live view's channel ids are the topics' indices.
    live_channels.push_back({static_cast<std::uint32_t>(index), spec.name, proto ? "protobuf" : "json", schema_name,
                             data, proto ? "protobuf" : "jsonschema"});
  }
  if (!targets.live.address.empty()) {
    auto live = LiveView::start(targets.live, std::move(live_channels));
    if (!live) return live.error();
    log->live_ = std::move(live.value());
  }
  return log;
}

void FlightLogWriter::put(Topic topic, rt::TimeNs stamp_ns, std::span<const std::uint8_t> bytes) {
  const auto index = static_cast<std::size_t>(topic);
  if (mcap_ && channels_[index] != 0) {
    const auto t = static_cast<std::uint64_t>(std::max<rt::TimeNs>(stamp_ns, 0));
    (void)mcap_->write(channels_[index], t, t, bytes);  // after a failure: counted as dropped
  }
  if (live_) live_->offer(static_cast<std::uint32_t>(index), stamp_ns, bytes);
}

void FlightLogWriter::write(Topic topic, rt::TimeNs stamp_ns, const google::protobuf::Message& message) {
  if (!active()) return;
  const std::size_t size = message.ByteSizeLong();
  if (buffer_.size() < size) buffer_.resize(size);
  if (!message.SerializeToArray(buffer_.data(), static_cast<int>(size))) return;
  put(topic, stamp_ns, std::span<const std::uint8_t>(buffer_.data(), size));
}

void FlightLogWriter::writeJson(Topic topic, rt::TimeNs stamp_ns, std::string_view json) {
  if (!active()) return;
  put(topic, stamp_ns, bytesOf(json));
}

rt::Status FlightLogWriter::close() {
  if (live_) live_->stop();
  return mcap_ ? mcap_->close() : rt::ok();
}

hal::replay::McapWriterStats FlightLogWriter::stats() const {
  return mcap_ ? mcap_->stats() : hal::replay::McapWriterStats{};
}

std::string FlightLogWriter::summary() const {
  std::string out;
  if (mcap_) {
    const hal::replay::McapWriterStats& s = mcap_->stats();
    const char* compression = hal::replay::mcapCompressionName(compression_);
    char line[512];
    std::snprintf(line, sizeof(line), "flight log %s: %llu messages, %.1f MB in %llu chunks (%s)",
                  mcap_->path().c_str(), static_cast<unsigned long long>(s.messages),
                  static_cast<double>(s.bytes_written) / 1e6, static_cast<unsigned long long>(s.chunks),
                  compression[0] != '\0' ? compression : "uncompressed");
    out = line;
    if (!mcap_->failure()) {
      out += "; stopped early, " + std::to_string(s.dropped) +
             " messages not written: " + mcap_->failure().error().message;
    }
  }
  if (live_) out += (out.empty() ? "" : "\n") + live_->summary();
  return out;
}

}  // namespace aerotrack::app
