// The recorder (hal/replay/recorder.hpp), its producer queues and writer thread (these run under
// ThreadSanitizer too): what devices deliver and are told, recorded through the decorators and
// replayed, comes back bit for bit and at the instants it was delivered (depth frames and detections
// too); a full queue drops and counts instead of blocking; it refuses to
// write over a recording. (A recorder killed with SIGKILL: tests/unit/hal/replay/recorder_kill_test.cpp.)
#include "aerotrack/hal/replay/recorder.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <thread>

#include <opencv2/core.hpp>

#include "aerotrack/hal/depth_units.hpp"
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
    EXPECT_EQ(recorded->samples[i].sample.stamp_ns, delivered[i].stamp_ns);
    EXPECT_EQ(recorded->samples[i].sample.p_WB_m, delivered[i].p_WB_m) << i;
    EXPECT_EQ(recorded->samples[i].sample.q_WB.coeffs(), delivered[i].q_WB.coeffs()) << i;
  }
  const auto* setpoints = (*dataset)->setpoints();
  ASSERT_NE(setpoints, nullptr);
  ASSERT_EQ(setpoints->samples.size(), sent.size());
  EXPECT_EQ(setpoints->samples.back().p_W_m, sent.back().p_W_m);
  std::filesystem::remove_all(options.dir);
}

// A depth camera whose frames arrive 4 ms after they were taken, every 33 ms, each a fresh pattern; and
// a keypoint-mode camera delivering a detection result every 20 ms, 35 ms after its exposure.
class ScriptedDepthCamera final : public DepthCamera {
 public:
  std::string_view backend() const override { return "scripted"; }
  DeviceHealth health(rt::TimeNs) const override { return {}; }
  DepthFrameHandle grab(rt::TimeNs now_ns) override {
    const rt::TimeNs stamp_ns = (now_ns - 4 * kMs) - (now_ns - 4 * kMs) % (33 * kMs);
    if (stamp_ns < 0 || stamp_ns <= last_ns_) return {};
    last_ns_ = stamp_ns;
    auto frame = std::make_shared<DepthFrame>();
    frame->stamp_ns = stamp_ns;
    frame->sequence = ++sequence_;
    frame->depth_m.create(12, 16, CV_32FC1);
    for (int v = 0; v < 12; ++v)
      for (int u = 0; u < 16; ++u)
        frame->depth_m.at<float>(v, u) = depthFromZ16(static_cast<std::uint16_t>(300 + 17 * u + 101 * v + sequence_));
    frame->intrinsics.width_px = 16;
    frame->intrinsics.height_px = 12;
    frame->intrinsics.fx_px = frame->intrinsics.fy_px = 1.0 / 3.0 * 40.0;
    frame->intrinsics.cx_px = 8.0;
    frame->intrinsics.cy_px = 6.0;
    frame->T_BC.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
    frame->T_BC.translation() = Eigen::Vector3d(0.1, 0.02, -0.03);
    return frame;
  }
  static constexpr rt::TimeNs kMs = rt::kNsPerMillisecond;

 private:
  rt::TimeNs last_ns_ = -1;
  std::uint64_t sequence_ = 0;
};

class ScriptedKeypointCamera final : public GimbalCamera {
 public:
  std::string_view backend() const override { return "scripted"; }
  DeviceHealth health(rt::TimeNs) const override { return {}; }
  ImageFrameHandle grab(rt::TimeNs) override { return {}; }
  std::optional<DetectionFrame> grabDetections(rt::TimeNs now_ns) override {
    const rt::TimeNs next_stamp_ns = static_cast<rt::TimeNs>(sequence_) * 20 * rt::kNsPerMillisecond;
    if (next_stamp_ns + 35 * rt::kNsPerMillisecond > now_ns) return std::nullopt;
    DetectionFrame f;
    f.stamp_ns = next_stamp_ns;
    f.result_ns = next_stamp_ns + 35 * rt::kNsPerMillisecond;
    f.sequence = ++sequence_;
    f.person_count = 2;
    f.target_index = 1;
    f.persons[1].score = 1.0 / static_cast<double>(f.sequence);
    f.persons[1].keypoints[11] = {100.0 / 7.0, 200.0 / 3.0, 0.9};
    return f;
  }

 private:
  std::uint64_t sequence_ = 0;
};

TEST(Recorder, CameraFramesAndDetectionsReplayBitForBitAtTheInstantsTheyWereDelivered) {
  RecorderOptions options;
  options.dir = freshDir("cameras");
  options.lossless = true;  // the loop below runs far faster than real time: wait for the disk, as lockstep does
  auto recorder = DatasetRecorder::start(options, 0);
  ASSERT_TRUE(recorder) << recorder.error().message;
  RecordingDepthCamera depth(std::make_unique<ScriptedDepthCamera>(), **recorder);
  RecordingGimbalCamera camera(std::make_unique<ScriptedKeypointCamera>(), **recorder);
  struct Seen {
    rt::TimeNs at_ns;
    DepthFrameHandle frame;
  };
  std::vector<Seen> frames;
  std::vector<std::pair<rt::TimeNs, DetectionFrame>> detections;
  const rt::DurationNs step_ns = 5 * rt::kNsPerMillisecond;
  const rt::TimeNs end_ns = rt::secondsToNs(1.0);
  for (rt::TimeNs t = 0; t <= end_ns; t += step_ns) {
    if (auto f = depth.grab(t)) frames.push_back({t, f});
    while (auto d = camera.grabDetections(t)) detections.emplace_back(t, *d);
  }
  ASSERT_TRUE((*recorder)->stop());
  EXPECT_EQ((*recorder)->written(RecordedStream::kDepthFrames), frames.size());
  EXPECT_EQ((*recorder)->written(RecordedStream::kDetections), detections.size());

  ReplayOptions replay;
  replay.dir = options.dir;
  replay.bad_rows = BadRowPolicy::kStrict;
  auto dataset = ReplayDataset::open(replay, 0);
  ASSERT_TRUE(dataset) << dataset.error().message;
  ReplayDepthCamera depth_replay(*dataset);
  ReplayGimbalCamera camera_replay(*dataset);
  std::size_t f = 0, d = 0;
  for (rt::TimeNs t = 0; t <= end_ns; t += step_ns) {
    if (auto frame = depth_replay.grab(t)) {
      ASSERT_LT(f, frames.size());
      EXPECT_EQ(frames[f].at_ns, t);
      const DepthFrame& a = *frames[f++].frame;
      EXPECT_EQ(frame->stamp_ns, a.stamp_ns);
      EXPECT_EQ(frame->sequence, a.sequence);
      EXPECT_EQ(cv::norm(frame->depth_m, a.depth_m, cv::NORM_INF), 0.0);
      EXPECT_EQ(std::memcmp(&frame->intrinsics, &a.intrinsics, sizeof(CameraIntrinsics)), 0);
      EXPECT_TRUE(frame->T_BC.matrix() == a.T_BC.matrix());
    }
    while (auto det = camera_replay.grabDetections(t)) {
      ASSERT_LT(d, detections.size());
      EXPECT_EQ(detections[d].first, t);
      const DetectionFrame& a = detections[d++].second;
      EXPECT_EQ(det->stamp_ns, a.stamp_ns);
      EXPECT_EQ(det->result_ns, a.result_ns);
      EXPECT_EQ(std::memcmp(det->persons.data(), a.persons.data(), sizeof(a.persons)), 0);
    }
  }
  EXPECT_EQ(f, frames.size());
  EXPECT_EQ(d, detections.size());
  std::filesystem::remove_all(options.dir);
}

TEST(Recorder, ALosslessRecorderWaitsForRoomAndKeepsEveryRecord) {
  RecorderOptions options;
  options.dir = freshDir("lossless");
  options.queue_capacity = 2;
  options.lossless = true;
  auto recorder = DatasetRecorder::start(options, 0);
  ASSERT_TRUE(recorder);
  constexpr int kRecords = 5000;
  for (int i = 0; i < kRecords; ++i) (*recorder)->record(Delivered<GimbalState>{{i, 0.0, 0.0}, 0});
  ASSERT_TRUE((*recorder)->stop());
  EXPECT_EQ((*recorder)->written(RecordedStream::kGimbal), static_cast<std::uint64_t>(kRecords));
  EXPECT_EQ((*recorder)->dropped(RecordedStream::kGimbal), 0U);
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
  for (int i = 0; i < kRecords; ++i) (*recorder)->record(Delivered<GimbalState>{{i, 0.0, 0.0}, 0});
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
