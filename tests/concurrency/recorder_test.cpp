// The recorder (hal/replay/recorder.hpp), its producer queues and writer thread (these run under
// ThreadSanitizer too): what devices deliver and are told, recorded through the decorators and
// replayed, comes back bit for bit; a full queue drops and counts instead of blocking; it refuses to
// write over a recording. (A recorder killed with SIGKILL: tests/unit/hal/replay/recorder_kill_test.cpp.)
#include "aerotrack/hal/replay/recorder.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "aerotrack/hal/replay/replay_devices.hpp"

namespace aerotrack::hal::replay {
namespace {

std::string freshDir(const std::string& tag) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("aerotrack-recorder-" + tag + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return dir.string();
}

// Backends that produce a known sequence (what the simulator or the drone would deliver).
class ScriptedOdometry final : public Odometry {
 public:
  std::string_view backend() const override { return "scripted"; }
  DeviceHealth health(rt::TimeNs) const override { return {}; }
  std::optional<OdometrySample> read(rt::TimeNs now_ns) override {
    OdometrySample s;
    s.stamp_ns = now_ns - now_ns % (10 * rt::kNsPerMillisecond);  // a new sample every 10 ms, repeated between
    s.p_WB_m = {1.0 / 3.0 * static_cast<double>(s.stamp_ns) * 1e-9, 2.0, 1.5};
    s.q_WB =
        Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * static_cast<double>(s.stamp_ns) * 1e-9, Eigen::Vector3d::UnitZ()));
    return s;
  }
};

class ScriptedGimbal final : public Gimbal {
 public:
  std::string_view backend() const override { return "scripted"; }
  DeviceHealth health(rt::TimeNs) const override { return {}; }
  void command(const GimbalCommand& c) override { last_ = c; }
  std::optional<GimbalState> read(rt::TimeNs now_ns) override {
    return GimbalState{now_ns, 1e-3 * static_cast<double>(now_ns % 977), 0.5};
  }
  GimbalCommand last_;
};

class ScriptedLink final : public VehicleLink {
 public:
  std::string_view backend() const override { return "scripted"; }
  DeviceHealth health(rt::TimeNs) const override { return {}; }
  void send(const Setpoint& s) override {
    ++sent_;
    last_ = s;
  }
  VehicleStatus status(rt::TimeNs now_ns) override { return {now_ns, true, true, FlightMode::kOffboard}; }
  int sent_ = 0;
  Setpoint last_;
};

TEST(Recorder, WhatDevicesDeliverAndAreToldReplaysBitForBit) {
  RecorderOptions options;
  options.dir = freshDir("roundtrip");
  options.software_version = "test";
  auto recorder = DatasetRecorder::start(options, 0);
  ASSERT_TRUE(recorder) << recorder.error().message;
  auto link_inner = std::make_unique<ScriptedLink>();
  ScriptedLink* link_seen = link_inner.get();
  RecordingOdometry odometry(std::make_unique<ScriptedOdometry>(), **recorder);
  RecordingGimbal gimbal(std::make_unique<ScriptedGimbal>(), **recorder);
  RecordingVehicleLink link(std::move(link_inner), **recorder);
  std::vector<OdometrySample> delivered;
  std::vector<Setpoint> sent;
  for (rt::TimeNs t = 0; t <= rt::secondsToNs(2.0); t += 5 * rt::kNsPerMillisecond) {  // a 200 Hz task
    const auto o = odometry.read(t);
    if (delivered.empty() || o->stamp_ns != delivered.back().stamp_ns) delivered.push_back(*o);
    (void)gimbal.read(t);
    GimbalCommand c;
    c.stamp_ns = t;
    c.rate_radps = std::sin(static_cast<double>(t) * 1e-9);
    gimbal.command(c);
    Setpoint sp;
    sp.stamp_ns = t;
    sp.p_W_m = {static_cast<double>(t) * 1e-9 / 7.0, 0.0, 1.5};
    link.send(sp);
    sent.push_back(sp);
    if (t % (50 * rt::kNsPerMillisecond) == 0) std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  EXPECT_EQ(link_seen->sent_, static_cast<int>(sent.size()));  // passed through
  ASSERT_TRUE((*recorder)->stop());
  EXPECT_EQ((*recorder)->written(RecordedStream::kOdometry), delivered.size());
  EXPECT_EQ((*recorder)->dropped(RecordedStream::kSetpoints), 0U);

  ReplayOptions replay;
  replay.dir = options.dir;
  replay.bad_rows = BadRowPolicy::kStrict;
  auto dataset = ReplayDataset::open(replay, 0);
  ASSERT_TRUE(dataset) << dataset.error().message;
  const auto* recorded = (*dataset)->odometry();
  ASSERT_NE(recorded, nullptr);
  ASSERT_EQ(recorded->samples.size(), delivered.size());
  for (std::size_t i = 0; i < delivered.size(); ++i) {
    EXPECT_EQ(recorded->samples[i].stamp_ns, delivered[i].stamp_ns);
    EXPECT_EQ(recorded->samples[i].p_WB_m, delivered[i].p_WB_m) << i;
    EXPECT_EQ(recorded->samples[i].q_WB.coeffs(), delivered[i].q_WB.coeffs()) << i;
  }
  const auto* setpoints = (*dataset)->setpoints();
  ASSERT_NE(setpoints, nullptr);
  ASSERT_EQ(setpoints->samples.size(), sent.size());
  EXPECT_EQ(setpoints->samples.back().p_W_m, sent.back().p_W_m);
  std::filesystem::remove_all(options.dir);
}

TEST(Recorder, AFullQueueDropsAndCountsInsteadOfBlocking) {
  RecorderOptions options;
  options.dir = freshDir("full");
  options.queue_capacity = 2;
  auto recorder = DatasetRecorder::start(options, 0);
  ASSERT_TRUE(recorder);
  constexpr int kRecords = 20000;
  const auto begin = std::chrono::steady_clock::now();
  for (int i = 0; i < kRecords; ++i) (*recorder)->record(GimbalState{i, 0.0, 0.0});
  const auto producer_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  ASSERT_TRUE((*recorder)->stop());
  const std::uint64_t written = (*recorder)->written(RecordedStream::kGimbal);
  const std::uint64_t dropped = (*recorder)->dropped(RecordedStream::kGimbal);
  EXPECT_EQ(written + dropped, static_cast<std::uint64_t>(kRecords));
  EXPECT_GT(dropped, 0U);  // a 2-record queue cannot keep up with a tight loop
  std::printf("20000 pushes in %.2f ms: %llu written, %llu dropped\n", producer_s * 1e3,
              static_cast<unsigned long long>(written), static_cast<unsigned long long>(dropped));
  std::filesystem::remove_all(options.dir);
}

TEST(Recorder, RefusesToWriteOverARecordingOrIntoAnUnwritablePlace) {
  RecorderOptions options;
  options.dir = freshDir("twice");
  {
    auto first = DatasetRecorder::start(options, 0);
    ASSERT_TRUE(first);
  }
  auto second = DatasetRecorder::start(options, 0);
  ASSERT_FALSE(second);
  EXPECT_NE(second.error().message.find("already holds a recording"), std::string::npos);
  options.dir = "/proc/aerotrack-cannot-be-here";
  auto nowhere = DatasetRecorder::start(options, 0);
  ASSERT_FALSE(nowhere);
  EXPECT_NE(nowhere.error().message.find("record: /proc/aerotrack-cannot-be-here"), std::string::npos);
  std::filesystem::remove_all(freshDir("twice"));
}

}  // namespace
}  // namespace aerotrack::hal::replay
